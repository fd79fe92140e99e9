"""The floor stage's tuning: one section per module (the floor model, segmentation, the
skirting trim, the wall's foot, the polygon), each setting with its reason.

Code reads the values at call time (``FLOOR.segment.grabcut_long_px``), so a caller, or a
test with ``monkeypatch.setattr(FLOOR.segment, "sure_other", 0.03)``, can change one.
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class ModelSettings:
    """The floor model (:mod:`augment.floor.model`)."""

    preshrink_long_px: int = 2048  # larger photos are shrunk to this once, by a whole factor (12 MP: 2016 px)


@dataclass
class SegmentSettings:
    """The floor mask (:mod:`augment.floor.segment`); sizes in pixels are at GrabCut's working size."""

    grabcut_long_px: int = 400  # GrabCut's cost grows with the pixels; the edges it fixes are a few pixels here
    grabcut_iterations: int = 3  # GrabCut's iterations refining the model's mask
    sure_floor: float = 0.97  # model probabilities above this are floor as given; GrabCut decides the rest
    sure_other: float = 0.01  # below this not floor as given: higher loses floor in shade, lower leaks into walls
    max_floor_distance_m: float = 15.0  # farther floor is not believed: rooms rarely show more; a pixel spans meters
    min_part_m2: float = 0.05  # a part cut off from the board's floor with less floor than this is a leak or a sliver
    min_part_share: float = 0.005  # so is one of fewer pixels than this share of the main region's (a far sliver)
    disputed_share_warn: float = 0.10  # above this share of the floor disputed by model and mask, floor is uncertain
    restore_min_m2: float = 0.3  # a region the model calls floor and GrabCut dropped whole, this large, is floor
    restore_edge_px: int = 2  # ... when thicker than this either side: GrabCut's edge corrections are thinner
    restore_below_share: float = 0.8  # ... and, if fewer pixels than min_part_share, the floor kept below this
    # share of its lower edge (a far strip, not a carton's top) ...
    restore_gap_m: float = 0.3  # ... this near on the floor (a threshold bar; a carton's face spans more) ...
    restore_gap_px: int = 40  # ... looked for this far down
    veto_p: float = 0.05  # floor GrabCut added past the model, thicker than an edge, where the model gives below this
    spur_width_px: int = 5  # mask lines thinner than this and farther than spur_reach_px from the model's floor go
    spur_reach_px: int = 25  # GrabCut's spurs up walls reach farther; a sliver of floor behind a far carton, less
    bridge_px: int = 5  # floor either side of a not-floor line thinner than this (a threshold bar) is one region
    board_margin: float = 1.3  # the board grown this much about its center is floor for sure: it lies on open floor
    click_tolerance: int = 12  # a click's region holds the pixels within this Lab distance of the clicked colour
    click_region_reach_m: float = 0.5  # below the horizon, within this of the clicked floor point, on the floor
    click_region_max_reach: float = 0.10  # and this share of the long side: far away, along a far wall, not up it
    click_region_reach: float = 0.05  # above the horizon or uncalibrated, within this share of the long side
    click_reach: float = 0.15  # share of the long side around a click where the model's sure labels become probable
    click_canny: tuple[int, int] = (10, 30)  # edges stopping a click's region: low, to catch a faint wall-floor line
    mask_aspect_tolerance: float = 0.01  # a user's mask of the photo's shape to within this is scaled to the photo
    max_mask_grey: float = 0.25  # a mask with more mid-grey pixels than this share is a photo: a soft edge is a few %
    mask_sky_warn: float = 0.005  # a mask's white above the horizon past this share is left out with a word
    max_mask_sky: float = 0.10  # past this share the mask marks walls or the ceiling as floor, and is refused


@dataclass
class SkirtingSettings:
    """The skirting trim (:mod:`augment.floor.skirting`); sizes in pixels are at its working size."""

    work_long_px: int = 1280  # the trim works at this long side at most: a board is 10 px or more there at 4 m
    min_height_m: float = 0.02  # a strip lower than this is no board: anti-aliasing at the mask's edge
    max_height_m: float = 0.20  # a strip taller than this is no board
    search_m: float = 0.25  # each column is searched for the board's lower edge up to this height above the floor
    mode_bin_m: float = 0.01  # heights are binned this wide to find the most common one, the board's
    near_px: int = 2  # a column looks again for its board's lower edge within this of the most common height
    min_contrast: float = 15.0  # a board's strip differs from the floor below it by this at least (RGB distance)
    sharpness: float = 0.6  # and this share of the change happens in one 3-pixel step: a shadow fades out instead
    shadow_ratio: float = 0.8  # a strip darker than the floor below it by this ratio and ...
    shadow_deg: float = 8.0  # ... within this angle of its colour (RGB direction) is the walls' shadow, not a board
    min_agreeing: float = 0.3  # the photo agrees on a board when this share of the wall columns shows one and ...
    max_spread: float = 0.3  # ... their heights' interquartile range is below this share of the median: boards are even
    gap_px: int = 16  # columns between two that show the board, no farther apart than this, are cut too
    stretch_agreeing: float = 0.5  # a stretch of wall where this share of columns shows the board is cut all along
    step_px: int = 6  # neighbouring top floor rows farther apart are on different walls (or either side of a thing)
    profile_from_m: float = -0.10  # the skirting models read each column from this far below the edge (< 0: above)
    profile_to_m: float = 0.30  # to this far below the mask's edge: the window the models were trained on
    profile_step_m: float = 0.005  # in steps of this, as the models were trained
    profile_floor_m: float = 0.22  # against the floor's colour from this far below, as the models were trained
    profile_context: int = 8  # with the mean of this many columns either side, as the models were trained
    no_board_p: float = 0.15  # below this mean board probability the photo shows no board; to board_p, rules decide
    board_p: float = 0.5  # from this mean the photo (or a wall) shows a board, whatever the rules say
    no_wall_board_p: float = 0.05  # where the photo shows a board, runs of wall averaging below this hold none
    alone_p: float = 0.3  # below this mean over the photo, a wall only the board model is sure of needs the rules' step
    rules_near_m: float = 0.04  # a wall's rules' height within this of the depth model's is kept
    learned_near_m: float = 0.02  # else the board's lower edge is looked for this far either side of the model's height
    board_click_reach: float = 0.10  # a "not floor" click this near a wall's column (of the long side) marks its board
    doubt_p: float = 0.3  # an uncut wall with this mean board probability may hold a board: the trim says where
    seen_p: float = 0.5  # a column where the board probability reaches this shows the board
    gap_p: float = 0.5  # a column whose gap probability reaches this sees the floor line above the mask's edge
    gap_agreeing: float = 0.7  # a wall where this share of columns sees it has its mask edge moved up to the floor line
    gap_smooth_columns: int = 9  # that reach is smoothed over this many columns: a lone column's is a spike
    above_min_m: float = 0.05  # a strip this tall or more above the mask's edge, ending at a step, is a board ...
    above_agreeing: float = 0.5  # ... on the floor line: a wall where this share of columns shows one is not cut
    corner_px: float = 3.0  # the mask's top edge bending by more than this is a corner between walls
    min_wall_columns: int = 24  # a wall judged on its own needs this many columns


@dataclass
class WallFootSettings:
    """Far strips given back up to the wall's foot (:mod:`augment.floor.wall_foot`); pixels at
    the skirting trim's working size."""

    reach_m: float = 1.5  # the wall's foot is looked for this far beyond the mask's edge on the floor at most
    floor_step: float = 15.0  # the floor line: a step of this much colour (RGB distance, 3 rows' means) or more
    board_step: float = 8.0  # the board's top: this much (a white board on a pale wall differs little)
    board_m: tuple[float, float] = (0.045, 0.22)  # a board's height upright; a lit bevel on its top is thinner
    bevel_share: float = 0.25  # a lit bevel along a board's top is this share of its height at most
    board_spread: float = 0.3  # a board's height differs by this share at most from one end of a wall to the other
    wall_m: float = 0.15  # the wall is plain this far above the board
    plain: float = 7.0  # a band is plain when its colour spread (RGB standard deviation) is below this
    sharpness: float = 0.6  # the board's top step holds this share of the change from board to wall ...
    noise_factor: float = 3.0  # ... and is this many times the wall's median step: not the wall's noise or shading
    line_px: float = 1.5  # a column's floor line within this of a line is on it
    line_trials: int = 400  # RANSAC's tries per line
    most_lines: int = 8  # lines looked for: a wall each, and the threshold's edges
    lined_up: float = 0.6  # this share of a line's columns have their boards' tops on one line too
    min_width_share: float = 0.1  # a strip is given back along this share of the photo's width or more
    gap_px: int = 48  # columns that saw a line, this far apart or nearer, are one stretch of wall
    strip_m: tuple[float, float] = (0.05, 0.35)  # the strip as tall as this upright (taller: a thing before the wall)
    clash_px: float = 4.0  # a foot or board beside the strip farther off its line than this: a thing stands there
    rise_m: float = 0.03  # a mask edge this far above a wall's foot seen beside it (upright) is a thing on it ...
    thing_m: float = 1.0  # ... when it comes back to the foot within this many meters along the wall


@dataclass
class PolygonSettings:
    """The floor polygon (:mod:`augment.floor.polygon`)."""

    long_px: int = 1024  # contours are traced at this long side at most: walls within centimeters, and fast
    simplify_share: float = 0.0035  # the outline is first straightened this far in the photo, of its long side
    simplify_m: float = 0.05  # how far the straightened outline may stray from the mask's
    notch_area_m2: float = 0.02  # vertices cutting off less than this are noise, not corners
    corner_min_deg: float = 10.0  # edges meeting at less than this are one wall, not a corner
    border_px: int = 2  # a contour point this near the photo's edge is the photo's edge
    bridge_m: float = 0.001  # width of the corridor joining a part of the floor on
    bridge_tries: int = 50  # nearest corner pairs tried for a corridor


@dataclass
class FloorSettings:
    """The floor stage's settings, a section per module."""

    model: ModelSettings = field(default_factory=ModelSettings)
    segment: SegmentSettings = field(default_factory=SegmentSettings)
    skirting: SkirtingSettings = field(default_factory=SkirtingSettings)
    wall_foot: WallFootSettings = field(default_factory=WallFootSettings)
    polygon: PolygonSettings = field(default_factory=PolygonSettings)


FLOOR = FloorSettings()
