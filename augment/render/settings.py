"""The render stage's tuning values, one section per module, each with its reason.

Code reads them at call time (``RENDER.staged.margin_px`` inside a function), so a
caller, or a test with ``monkeypatch.setattr(RENDER.erase, "covered_warn", 0.05)``, can
change one. Lengths are meters unless the name says otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class GlSettings:
    """The GL context (:mod:`augment.render.gl`)."""

    znear_m: float = 0.05  # near clipping plane of every render
    zfar_m: float = 40.0  # far clipping plane: rooms are at most about 12 m across
    shadow_offset: tuple[float, float] = (2.0, 8.0)  # shadow pass glPolygonOffset (factor, units): against acne


@dataclass
class FurnitureSettings:
    """The procedural furniture (:mod:`augment.render.furniture`)."""

    fit_slack_m: float = 0.02  # parts may miss the item's box by this per side before the final fit; more is a bug
    bevel_min_m: float = 0.004  # smaller bevels are left out: they cost triangles and show only from up close


@dataclass
class StagedSettings:
    """Light, shadows, occlusion and resolution of a staged photo (:mod:`augment.render.staged`)."""

    paper_albedo: float = 0.85  # the board's white squares are office paper: they give the photo's exposure
    sky_share: float = 0.55  # share of the non-key light that comes from above rather than from all round
    front_fill: float = 0.18  # light from the room behind the camera, relative to the irradiance
    bounce: float = 0.5  # light off the floor onto the furniture, relative to the floor's brightness
    metal_env: float = 0.5  # what a metal mirrors of the room, relative to the irradiance
    occlusion_m: float = 0.06  # furniture this much behind an occluder still shows
    occlusion_rel: float = 0.03  # ... plus this fraction of the occluder's distance
    floor_level_m: float = 0.02  # furniture pixels this low take the floor's shadows
    caster_min_height_m: float = 0.03  # parts lower than this cast no shadow (rugs)
    shadow_samples: int = 10  # key-light directions averaged for a soft shadow
    window_clipped: float = 245.0  # luminance (0-255, at 320 px) a blown-out window reaches
    window_edge_ratio: float = 0.9  # a window's outline: the light 2 px outside at most this x 2 px inside
    # (windows 0.3-0.7, 0.87 in a cream frame on bright walls; a lamp's glow on a wall 0.97-0.99, at 320 px)
    window_min_sill_m: float = 0.45  # a bright blob on a wall reaching lower is sun on the wall or a door
    ao_strength: float = 1.0  # share of the ambient light occlusion removes at most
    ao_directions: int = 96  # sky directions sampled for the floor's occlusion (cosine-weighted) ...
    ao_blur_rel: float = 0.5  # ... their shadows' copies blurred by this x their spacing at a typical height
    ao_reach_rel: float = 1.75  # the occlusion beside a thing is worked out this x its height away ...
    ao_reach_max_m: float = 1.75  # ... at most (a wall of height h hides 7 % of the sky 1.75 h away)
    ao_cell_m: float = 0.02  # the occlusion's raster: about this fine (a whole number of the floor's cells)
    lamp_diffuse_share: float = 0.35  # share of a ceiling lamp's light reaching the floor off its shade,
    # the ceiling and the walls near it: occluded like the sky's, the rest shadowed from the lamp
    contact_height_m: float = 0.015  # parts whose underside is this close to the floor stand on it
    contact_band_m: float = 0.02  # their foot: the part of them this close to their underside
    contact_sigma_m: float = 0.012  # the contact shadow's spread beyond the foot's edge
    contact_strength: float = 0.7  # share of all light the floor loses right at the foot's edge, at most
    floor_cell_max_px: int = 900  # floor raster: at most this many cells a side
    wall_samples: int = 150_000  # walls' shadows: worked out on at most this many pixels of the region
    wall_ambient_share: float = 0.6  # a wall's light but the key, relative to the floor's: half the sky, the bounce
    wall_ao_directions: int = 48  # directions sampled for a wall's occlusion (cosine-weighted about its normal) ...
    wall_ao_cell_m: float = 0.02  # ... on a raster in the wall's plane this fine, or coarser on a long wall ...
    wall_ao_above: float = 0.5  # ... reaching this x the occlusion's reach above a piece (a few % is left there)
    wall_ao_min: float = 0.015  # ... less is left out (under a level of 255 in the photo), twice it kept
    wall_run_on_m: float = 3.0  # a wall the floor in view leaves at the photo's edge goes on this far past it
    wall_smooth_px: float = 8.0  # walls' shadows smoothed by this (Gaussian sigma, photo pixels)
    floor_cell_min_m: float = 0.004  # ... and cells no finer than this
    occlusion_long_px: int = 800  # the floor mask is read at most this large
    render_budget_px: float = 1.4e6  # rendered pixels (after supersampling) per image
    max_supersample: float = 2.0  # rendered pixels per photo pixel along each axis, at most
    min_render_scale: float = 0.6  # large photos are rendered at this scale at least, then upsampled ...
    # ... or lower, to 0.35, where the photo's own edge spread is wider than the render's
    # would be (its share below): the look's blur then hides what a finer render adds.
    blurred_render_scale: float = 0.35
    render_blur_share: float = 0.7
    margin_px: int = 6  # around the region furniture and shadows can reach
    sun_from_floor: bool = True  # the key light from sunlit patches on the floor when they show (else a window's)
    sun_elevation_deg: float = 35.0  # the sun's height where its patches do not tell it (SunSettings.glass_m)
    # A window in view and no sun on the floor: daylight through it is a broad source, so its
    # key is soft, modest and high (its shadows fall short and blurred, away from the window).
    window_elevation_deg: float = 65.0
    window_key: float = 0.25
    window_softness_rad: float = 0.5
    sun_key_range: tuple[float, float] = (0.3, 0.9)  # the sun's share of the light in the sun, at least and most
    sun_softness_rad: float = 0.01  # the sun's shadows: its disc, and a window's edge blur
    # The sun through a window in view, its patches' edges too soft to read: its share and disc
    window_sun_key: float = 0.6
    window_sun_softness_rad: float = 0.03
    # A window in view casts the sun's patches when, slid down along the sun (at some height of
    # it) onto the floor in view (this share of it, at least), it lands mostly in them, and the
    # floor between them and its wall is this much less often in the sun (else they climb it).
    cast_min_in_view: float = 0.3
    cast_min_lit: float = 0.6
    cast_min_margin: float = 0.3
    # The sun read off a bright floor with no edges, a window in view: the way and height at which
    # the window's outline slid down covers it best, when that covers it this well (intersection over union).
    window_sun_min_iou: float = 0.4
    # ... unless the bright floor is the window mirrored by a glossy floor: its mirror image
    # lands on bright floor (this share of it, at least) and the sun fitted comes from the
    # window straight at the camera (within this), as a reflection always does.
    reflection_min_lit: float = 0.8
    reflection_max_gap_deg: float = 10.0
    # A glossy floor: the share of the light it mirrors, read off the window in view's
    # reflection on a view this many pixels wide (the window, its reflection and the floor
    # around that this many pixels each, at least), at most this.
    gloss_view_px: int = 800
    gloss_min_px: int = 20
    max_floor_gloss: float = 0.3
    # The furniture mirrored by a floor that glossy at least: rendered at this scale of the
    # photo at most, coarser while its blur still spans this many rendered pixels, what
    # stands this high (m) at most, fading over this height (m) and blurred by this (m at
    # the furniture's distance): wood's gloss is soft.
    min_reflection_gloss: float = 0.03
    reflection_scale: float = 0.5
    reflection_blur_px: float = 2.0
    reflection_reach_m: float = 1.2
    reflection_fade_m: float = 0.35
    reflection_blur_m: float = 0.015
    # A window in view and the patches not cast by it: it casts them when the line from it to
    # them is this close to the sun's axis (cosine).
    sun_window_alignment: float = 0.5
    # Heights every window's glass covers (sills up to 1.0 m, heads from 1.4 m): a wall in view
    # that is plain over them has no window there, whatever the photo cuts off above.
    window_band_m: tuple[float, float] = (1.0, 1.4)
    light_cell_m: float = 0.04  # the floor's light map: cell size ...
    light_sigma_m: float = 0.3  # ... its blur (planks and tiles average out) ...
    light_gain_range: tuple[float, float] = (0.3, 2.5)  # ... and how far the light there may differ from the median
    render_edge_px: float = 0.55  # a render's edge spread (Gaussian sigma) at one rendered pixel per photo pixel
    highlight_knee: float = 0.8  # linear light above this rolls off toward white, as a camera's tone curve does
    # The floor mask is right to about a working pixel of its segmentation (400 px a side):
    # the floor's shadows meet what stands on it along the photo's own edges, found by a
    # guided filter of the mask this share of the photo's long side wide (colour, eps in 8-bit units squared).
    matte_radius_share: float = 0.005
    matte_eps: float = 50.0
    matte_long_px: int = 1600  # ... worked out at this long side at most (12 MP: 0.4 s a photo at full size)


@dataclass
class EraseSettings:
    """The board erased from the photo (:mod:`augment.render.erase`)."""

    context_share: float = 1.5  # floor shown around the sheet on each side, of its longer side: texture sources
    max_px_per_m: int = 6000  # the top-down view is as sharp as the photo at the sheet, up to this
    source_sharpness: float = 0.8  # texture comes from floor the photo shows at least this sharp (area) as the sheet
    search_sheet_px: int = 96  # the sheet's shorter side on the small view that finds light and texture source
    light_sigma_share: float = 0.5  # light: what varies slower than this share of the shorter side (blotches: texture)
    rim_share: float = 0.07  # the rim matched when choosing the texture's source, of the sheet's shorter side
    rim_fix_levels: float = 6.0  # what the copy misses of the floor's light at the rim is carried in, up to this
    paper_growth_squares: float = 1.0  # the paper may reach this many squares beyond the print (larger paper)
    edge_margin_m: float = 0.004  # always erased beyond the sheet: the paper's edge, its shadow and blur
    paper_line_share: float = 0.5  # a line beyond the sheet is paper while this share of it has the paper's colour
    edge_grow_px: int = 2  # photo pixels added around the sheet for the print's blurred edge
    feather_px: float = 1.0  # the blend's soft edge (Gaussian sigma)
    max_splits: int = 2  # where no place beside the sheet is all floor, its halves look for one, and theirs
    map_step_px: int = 4  # the view's pixel maps are computed on this coarse grid, then interpolated
    shadow_max_edges: int = 2  # straight shadow edges looked for, one after the other (a band has two)
    shadow_strip_share: float = 0.125  # a shadow's edge: the strips compared on its sides, of the sheet's shorter side
    shadow_piece_share: float = 0.33  # ... the pieces along it that must agree, of the sheet's shorter side
    shadow_agree: float = 0.8  # ... this share of them darken the same side ...
    shadow_min_step: float = 0.1  # ... by at least this (log of the photo's levels, about 20 % of the light) ...
    shadow_fit: float = 0.9  # ... and a soft step explains this share of the median profile across it
    covered_warn: float = 0.02  # the user is warned when something stands on more of the sheet than this


@dataclass
class SunSettings:
    """The sun's direction from sunlit patches on the floor (:mod:`augment.render.sun`)."""

    reach_m: float = 6.0  # the floor read, around the camera's foot
    cell_m: float = 0.01  # the top-down view's cell ...
    rim_m: float = 0.3  # ... covering the floor in view and this much around it ...
    max_cells: int = 600  # ... grown so the view has at most this many cells a side
    # Scales tried in turn until one finds the sun: the light smoothed this much (m; a seam
    # or grout line fades, a step stays), and sun over shade this much across the edges
    # (medians); the coarser scale, which sees soft edges, and more of the planks, asks more.
    edge_scales: tuple = ((0.015, 1.65), (0.03, 1.75))
    min_contrast: float = 1.5  # a sun's edge: light this many times brighter on one side (planks differ less)
    lit_level: float = 0.6  # in the sun: floor this far from the shade's light to the sun's (log)
    min_edge_m: float = 1.0  # sun's edges this long in all, at least ...
    min_edge_directed_m: float = 0.5  # ... or this long where the patches' far end runs into a wall
    board_margin_m: float = 0.08  # the board's sheet, grown by this, is left out (its edges are steps too)
    min_peak_share: float = 0.12  # an edge family this strong against the strongest
    wall_tol_deg: float = 4.0  # edges this close to a wall's direction run along it
    # The lit floor's rim steps (median) by at least this share of the sun's contrast per
    # share of the floor lit: the more floor reads as sun, the more its rim must be the
    # sun's edges and not a level crossed by grain, planks or daylight falling off (real
    # wood floors without sun: 0.1-0.4 of the contrast at 0.6-0.87 of the floor).
    rim_step_per_lit: float = 0.6
    # ... and is taken as sure from this on: below it, its light is softer and weaker, down
    # to a window's at rim_step_per_lit (a real floor's grain may come close).
    rim_step_per_lit_sure: float = 0.8
    min_touch_cells: int = 20  # a patch in the sun: its edges along the sun touch it on this many cells
    family_deg: float = 5.0  # the sun's edges past the planks: this near their peak, this much farther off a wall
    colour_spread: float = 1.2  # no edges in the light: the most varied channel, this many times the light's spread ...
    min_tint: float = 1.2  # ... and its patch's channels this far apart (the sun's colour against the shade's)
    colour_gap_m: float = 0.05  # the sun's colour: sunlit floor and shade this far from the edges ...
    colour_ring_m: float = 0.3  # ... the shade within this of the patches ...
    max_tint: float = 2.5  # ... each channel within this factor of the luminance (a few pixels are noisy)
    # Sun with no edge read, a window in view giving its azimuth: floor this many times its median light ...
    bright_ratio: float = 2.2
    bright_share: float = 0.03  # ... on this share of the floor seen, at least
    bright_smooth_m: float = 0.03  # the light smoothed this much first (grain, seams)
    # The sun's height: a window's glass this tall casts patches that run this over the
    # sun's slope; an end this much on the rim of the floor seen is out of view.
    glass_m: float = 1.2
    max_cut_share: float = 0.2
    elevation_deg: tuple = (12.0, 60.0)


@dataclass
class LampSettings:
    """Ceiling lamps from their pools of light on the floor (:mod:`augment.render.lamps`)."""

    ceiling_m: float = 2.5  # the room's height when the caller does not know it
    below_ceiling_m: float = 0.08  # a lamp hangs this far below the ceiling
    reach_m: float = 7.0  # the floor read, around the camera's foot
    cell_m: float = 0.1  # the fit's cell (the light is read at half of it, then averaged)
    smooth_m: float = 0.1  # the light is smoothed this much first: planks and grain fade, a pool stays
    board_margin_m: float = 0.1  # the board's sheet, grown by this, is left out
    min_cells: int = 40  # fewer cells of floor in view than this: no lamp is looked for
    min_extent_m: float = 1.0  # ... nor when the floor in view spans less than this
    width_shares: tuple = (0.45, 0.6, 0.8, 1.0)  # pool widths tried, of the lamp's height (1: a bare bulb)
    max_width_share: float = 0.8  # ... and the widest a lamp keeps (its peak fitted again)
    beyond_view_m: float = 0.8  # a pool's centre may lie this far past the floor in view
    max_lamps: int = 2
    search_cells: int = 600  # the search for a pool's centre reads about this many cells
    min_explained: float = 0.3  # a pool explains this share of the light the plane leaves, at least ...
    min_core_cells: int = 20  # ... its core (light over half its peak) shows on this many cells ...
    max_misfit: float = 0.15  # ... where the light departs from it by this share of its peak at most (rms)
    min_peak: float = 0.25  # ... and is this much brighter than the floor at large, right under it
    side_reach_share: float = 0.5  # its peak is seen: floor in view within this x its width of its centre ...
    max_gap_deg: float = 200.0  # ... all around it but for a gap this wide (180: the centre on the view's edge);
    min_flank_warmth: float = 1.0  # else its red over blue is this x the floor's at large, at least (not daylight)
    max_peak: float = 3.0  # brighter is a sun patch or a reflection, not a lamp's pool
    shade_radius_m: float = 0.1  # a lamp's shade: its shadows' penumbra
    shadow_top_share: float = 0.75  # shadows are cast from at most this share of a lamp's height up


@dataclass
class LookSettings:
    """The photo's noise and sharpness given to the furniture (:mod:`augment.render.look`)."""

    noise_block_px: int = 16  # the photo is measured in blocks this large
    noise_flat_share: float = 0.1  # the share of blocks with the least structure: where noise shows alone
    unclipped_levels: tuple[int, int] = (5, 250)  # a block with a pixel outside these is clipped: no noise shows
    noise_tile_px: int = 512  # noise drawn as a tile this large and repeated: no visible period at a few levels
    min_noise_levels: float = 0.05  # below this std the layer gets no noise
    edge_step_px: float = 0.25  # the board's edge profiles are sampled this finely
    edge_min_contrast: float = 30.0  # a profile is a step when its ends differ by this many levels ...
    edge_max_residual: float = 0.08  # ... and a blurred step fits it within this share of that difference
    edge_min_span_px: float = 8.0  # profiles shorter than this in the photo are not read: squares too small
    edge_min_count: int = 3  # fewer clean profiles than this: the sharpness is unknown
    min_extra_blur_px: float = 0.1  # the layer is not blurred for less than this


@dataclass
class GltfSettings:
    """The suggestion's 3-D scene (:mod:`augment.render.gltf`)."""

    floor_rgba: tuple[int, int, int, int] = (196, 170, 132, 255)  # the scene's floor: a mid wood
    wall_rgba: tuple[int, int, int, int] = (232, 229, 222, 255)  # its walls: off-white paint


@dataclass
class RenderSettings:
    """Every tuning value of the render stage, by module."""

    gl: GlSettings = field(default_factory=GlSettings)
    furniture: FurnitureSettings = field(default_factory=FurnitureSettings)
    staged: StagedSettings = field(default_factory=StagedSettings)
    erase: EraseSettings = field(default_factory=EraseSettings)
    look: LookSettings = field(default_factory=LookSettings)
    sun: SunSettings = field(default_factory=SunSettings)
    lamps: LampSettings = field(default_factory=LampSettings)
    gltf: GltfSettings = field(default_factory=GltfSettings)


RENDER = RenderSettings()
