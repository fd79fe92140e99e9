"""Procedural, seamlessly tiling textures for synthetic empty-room renders.

The renderer samples these images with REPEAT wrap, so every image here is periodic in
both axes: its left edge continues its right edge and its top edge continues its bottom
edge. Periodicity comes from construction, never from blending seams afterwards: noise is
white noise smoothed with wrap-around filtering, and plank and tile layouts place their
joints so that the pattern wraps consistently.

Each generator also returns ``tile_m``, the physical width in meters that one repeat of
the image covers, so that planks and tiles come out at believable real sizes. Feature
sizes are drawn in meters or millimeters and converted to pixels with
``px_per_m = size_px / tile_m``.

Images are ``(size_px, size_px, 3)`` uint8 in sRGB, channel order RGB (convert before
``cv2.imwrite``). Randomness comes only from the ``rng`` passed in: the same generator
state gives the same image.

The textures are made per rendered image, so they are written for speed: the noise is
:mod:`augment.render.noise`'s, per-plank and per-tile values are looked up with
``cv2.LUT`` on uint8 id maps, color is kept as three planes because NumPy broadcasting
over a trailing axis of length 3 is an order of magnitude slower than plane-wise
arithmetic, and image-sized temporaries live in the noise module's per-thread scratch
buffers. The functions are thread-safe.
"""
from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..render.noise import SCRATCH, WOOD_SHADE_GAIN_RGB, fine_scale, noise_mix, octave_layers, wood_grain

FLOOR_KINDS = ("wood", "tiles", "carpet", "concrete", "laminate")

# Plank and tile layouts need a few pixels per plank or tile to mean anything.
_MIN_SIZE_PX = 16

# name, base sRGB, plank-to-plank tone sd (log), figure contrast, streak contrast,
# probability of knots.
_WOOD_SPECIES = (
    ("oak", (182, 138, 92), 0.08, 0.30, 0.20, 0.5),
    ("light oak", (206, 172, 128), 0.07, 0.25, 0.16, 0.4),
    ("walnut", (108, 72, 48), 0.12, 0.30, 0.22, 0.3),
    ("maple", (222, 194, 150), 0.05, 0.12, 0.10, 0.1),
    ("cherry", (160, 94, 60), 0.08, 0.18, 0.15, 0.2),
    ("ash", (204, 184, 150), 0.07, 0.32, 0.18, 0.3),
    ("hickory", (188, 146, 104), 0.16, 0.28, 0.20, 0.6),
    ("grey-washed", (150, 144, 136), 0.08, 0.30, 0.20, 0.5),
    ("white-washed", (214, 205, 190), 0.05, 0.22, 0.12, 0.4),
    ("dark stained", (82, 56, 40), 0.10, 0.25, 0.20, 0.3),
    ("honey pine", (198, 150, 88), 0.09, 0.35, 0.18, 0.8),
    ("smoked oak", (126, 96, 70), 0.10, 0.28, 0.20, 0.5),
)

# name, tile sRGB choices, veined (marble), per-tile tone sd (log), mottle, speckle.
_TILE_STYLES = (
    ("ceramic", ((238, 236, 231), (232, 226, 214), (226, 214, 190), (214, 198, 170),
                 (198, 198, 194), (150, 150, 148), (92, 92, 94), (40, 40, 42)),
     False, 0.02, 0.03, 0.015),
    ("marble", ((234, 232, 228), (222, 208, 184), (38, 38, 40), (176, 176, 178)),
     True, 0.02, 0.04, 0.01),
    ("terracotta", ((178, 94, 58), (160, 80, 50), (192, 112, 72), (150, 92, 66)),
     False, 0.07, 0.10, 0.04),
    ("stone", ((124, 122, 118), (88, 88, 90), (162, 156, 146), (186, 178, 162)),
     False, 0.04, 0.10, 0.05),
)

_CARPET_COLORS = (
    (128, 126, 122), (160, 156, 148), (96, 96, 98), (188, 176, 156), (168, 150, 124),
    (120, 104, 86), (78, 92, 120), (104, 118, 140), (92, 108, 88), (126, 130, 104),
    (112, 84, 70), (70, 66, 64),
)


def _check_size(size_px):
    if isinstance(size_px, bool) or not isinstance(size_px, (int, np.integer)):
        raise TypeError(f"size_px must be an int, got {type(size_px).__name__}")
    if size_px < _MIN_SIZE_PX:
        raise ValueError(f"size_px must be >= {_MIN_SIZE_PX}, got {size_px}")
    return int(size_px)


def _lut(values):
    """256-entry float32 table for ``cv2.LUT`` on uint8 id maps."""
    table = np.zeros(256, np.float32)
    table[:len(values)] = values
    return table


def _shade_to_rgb8(shade, rgb):
    """uint8 RGB image ``rgb * shade``, rounded and saturated; ``shade`` must be >= 0.

    ``convertScaleAbs`` scales, rounds and saturates in one pass per channel; it takes
    absolute values, hence the sign requirement.
    """
    return cv2.merge([cv2.convertScaleAbs(shade, alpha=float(c),
                                          dst=SCRATCH.array(f"rgb{i}", shade.shape, np.uint8))
                      for i, c in enumerate(rgb)])


# Direction in log-RGB along which natural materials vary in warmth: redder and less
# blue, or the reverse. Independent per-channel jitter would instead turn wood and stone
# green or pink.
_WARMTH_LOG_RGB = np.array([1.0, 0.15, -1.2])


def _jitter_rgb(rng, rgb, sd):
    """Random brightness (log sd ``sd``) and warmth (about ``sd / 2``) of an sRGB color."""
    log_gain = rng.normal(0.0, sd) + rng.normal(0.0, 0.5 * sd) * _WARMTH_LOG_RGB
    return np.asarray(rgb, np.float64) * np.exp(log_gain)


def _tones(rng, n, sd):
    """(n, 3) per-item RGB gains: brightness with log sd ``sd`` and a smaller warmth shift."""
    log_gain = rng.normal(0.0, sd, (n, 1)) + rng.normal(0.0, 0.3 * sd, (n, 1)) * _WARMTH_LOG_RGB
    return np.exp(log_gain)


def _luma(rgb):
    return 0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]


# --------------------------------------------------------------------------- planks


def _cyclic_gap(a, b, period):
    d = abs(a - b) % period
    return min(d, period - d)


def _plank_joints(rng, size_px, n_rows, *, min_stagger_px, laminate):
    """x positions (px) of the end joints in each plank row.

    A row's planks are the cyclic intervals between its joints, so whatever the joint
    positions, the row wraps onto itself and the layout is periodic in x.
    """
    # Keep the stagger rule satisfiable even for short repeats.
    min_stagger_px = min(min_stagger_px, size_px / 6.0)
    # Laminate planks all have the same length: one or two per repeat on every row.
    count = 1 if rng.random() < 0.7 else 2
    joints = []
    for r in range(n_rows):
        neighbours = [joints[r - 1]] if r > 0 else []
        if r == n_rows - 1 and r > 0:
            # The last row also touches the first one across the top/bottom wrap.
            neighbours.append(joints[0])
        if not laminate:
            count = 1 if rng.random() < 0.55 else 2
        for _ in range(30):
            first = float(rng.uniform(0.0, size_px))
            if count == 1:
                xs = [first]
            elif laminate:
                xs = [first, (first + size_px / 2.0) % size_px]
            else:
                xs = [first, (first + size_px * float(rng.uniform(0.35, 0.65))) % size_px]
            if all(_cyclic_gap(a, b, size_px) >= min_stagger_px
                   for n in neighbours for a in xs for b in n):
                break
        joints.append(sorted(int(x) for x in xs))
    return joints


def _add_knots(rng, shade, row_edges, px_per_mm, count):
    """Darken ``shade`` in place with ``count`` small elliptic knots, each inside a row."""
    size_px = shade.shape[0]
    for _ in range(count):
        r = int(rng.integers(len(row_edges) - 1))
        y0, y1 = row_edges[r], row_edges[r + 1]
        sy = min(rng.uniform(3.0, 7.0) * px_per_mm, (y1 - y0) / 6.0)
        if sy < 0.7:
            continue
        sx = sy * rng.uniform(1.3, 2.5)
        yc = rng.uniform(y0 + 2.5 * sy, y1 - 2.5 * sy)
        xc = rng.uniform(0.0, size_px)
        half_x = min(int(3 * sx) + 1, size_px // 2 - 1)
        ys = np.arange(max(y0, int(yc - 3 * sy)), min(y1, int(yc + 3 * sy) + 2))
        xs = np.arange(int(xc) - half_x, int(xc) + half_x + 1)
        dy = ((ys + 0.5 - yc) / sy)[:, None]
        dx = ((xs + 0.5 - xc) / sx)[None, :]
        d2 = dx * dx + dy * dy
        # A dark core with a slightly darker rim, like the ring around a real knot.
        knot = -0.45 * np.exp(-d2) - 0.15 * np.exp(-4.0 * (np.sqrt(d2) - 1.3) ** 2)
        shade[np.ix_(ys % size_px, xs % size_px)] += knot.astype(np.float32)


def _planks(rng, size_px, *, laminate):
    """Wood or laminate floor: staggered plank rows along x, see :func:`floor_texture`."""
    if laminate:
        width_m = rng.uniform(0.15, 0.25)
        n_rows = max(3, round(rng.uniform(1.1, 1.45) / width_m))
    else:
        width_m = rng.uniform(0.12, 0.22)
        n_rows = max(3, round(rng.uniform(0.9, 1.7) / width_m))
    tile_m = n_rows * width_m
    px_per_m = size_px / tile_m
    px_per_mm = px_per_m / 1000.0

    _, base_rgb, tone_sd, figure, streak, knot_p = _WOOD_SPECIES[
        rng.integers(len(_WOOD_SPECIES))]
    base = _jitter_rgb(rng, base_rgb, 0.05)
    if laminate:
        # Printed decor: planks differ little in tone and the grain is flatter.
        tone_sd, figure, streak = tone_sd * 0.35, figure * 0.8, streak * 0.7

    # Rows start a little below the top edge so that the seam falls inside a plank row;
    # on a row boundary it would show the same plank gap in every repeat. Row r covers
    # pixel rows row_edges[r] .. row_edges[r + 1] - 1, modulo size_px.
    shift = int(rng.integers(1, max(2, size_px // n_rows)))
    row_edges = shift + np.round(np.arange(n_rows + 1) * size_px / n_rows).astype(np.int64)
    joints = _plank_joints(rng, size_px, n_rows, laminate=laminate,
                           min_stagger_px=(0.3 if laminate else 0.15) * px_per_m)

    # Plank ids: one per cyclic interval between a row's joints.
    x = np.arange(size_px)
    id_rows = np.empty((n_rows, size_px), np.uint8)
    origin_x, origin_y = [], []
    n_planks = 0
    for r, xs in enumerate(joints):
        k = len(xs)
        seg = (np.searchsorted(xs, x, side="right") - 1) % k
        id_rows[r] = n_planks + seg
        origin_x.extend(xs)
        origin_y.extend([row_edges[r] % size_px] * k)
        n_planks += k
    ids = np.roll(np.repeat(id_rows, np.diff(row_edges), axis=0), shift, axis=0)
    origin_x, origin_y = np.array(origin_x), np.array(origin_y)

    # Every plank shows its own patch of one periodic grain field, so grain breaks at
    # the joints as it does between real boards. Laminate repeats a few printed decors,
    # each anchored at the plank's own corner, so equal prints look identical.
    if laminate:
        n_prints = int(rng.integers(3, 7))
        prints = rng.integers(0, size_px, (n_prints, 2))[rng.integers(n_prints, size=n_planks)]
        off_y = (prints[:, 0] - origin_y) % size_px
        off_x = (prints[:, 1] - origin_x) % size_px
    else:
        off_y = rng.integers(0, size_px, n_planks)
        off_x = rng.integers(0, size_px, n_planks)
    grain = wood_grain(rng, size_px, px_per_mm, figure, streak)
    shape = (size_px, size_px)
    grid = np.arange(size_px, dtype=np.float32)
    map_x = cv2.LUT(ids, _lut(off_x), dst=SCRATCH.array("plane0", shape))
    map_x += grid[None, :]
    map_y = cv2.LUT(ids, _lut(off_y), dst=SCRATCH.array("plane1", shape))
    map_y += grid[:, None]
    shade = cv2.remap(grain, map_x, map_y, cv2.INTER_NEAREST, borderMode=cv2.BORDER_WRAP,
                      dst=SCRATCH.array("plane2", shape))

    if not laminate and rng.random() < knot_p:
        _add_knots(rng, shade, row_edges, px_per_mm, int(rng.integers(1, 4)))

    # Gaps and bevels are sub-pixel at these resolutions: their strength is the share of
    # a pixel they darken.
    gap = float(np.clip(rng.uniform(0.8, 1.6) * px_per_mm, 0.12, 0.6))
    bevel = laminate or rng.random() < 0.4
    edges = map_x  # reuse the buffer
    edges.fill(1.0)
    for r in range(n_rows):
        y0, y1 = row_edges[r], row_edges[r + 1]
        edges[y0 % size_px, :] *= 1.0 - gap
        if bevel:
            # Light from one side: one bevel face catches it, the other is in shadow.
            edges[(y0 + 1) % size_px, :] *= 1.0 + 0.25 * gap
            edges[(y0 - 1) % size_px, :] *= 1.0 - 0.45 * gap
        inside = np.arange(y0 + 1, y1) % size_px
        for xj in joints[r]:
            edges[inside, xj] *= 1.0 - 0.8 * gap
            if bevel:
                edges[inside, xj - 1] *= 1.0 - 0.3 * gap

    # Per-plank tone and warmth: boards are cut from different trees. Each channel is
    # tone[id] * edges * (1 + gain_c * shade) = tone[id] * (edges + gain_c * shade * edges).
    gains = _tones(rng, n_planks, tone_sd)
    shade *= edges
    tone = map_y  # reuse the buffer
    factor = SCRATCH.array("plane3", shape)
    channels = []
    for c in range(3):
        tone = cv2.LUT(ids, _lut(base[c] * gains[:, c]), dst=tone)
        factor = cv2.scaleAdd(shade, WOOD_SHADE_GAIN_RGB[c], edges, dst=factor)
        factor = cv2.multiply(tone, factor, dst=factor)
        np.maximum(factor, 0.0, out=factor)
        channels.append(cv2.convertScaleAbs(
            factor, dst=SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(tile_m)


# --------------------------------------------------------------------------- tiles


@dataclass(frozen=True)
class _TileLayout:
    """Grid of one repeat: ``nx`` tiles along x, ``ny`` rows, pitches include grout."""

    nx: int
    ny: int
    pitch_x_m: float
    pitch_y_m: float
    grout_m: float
    # Horizontal shift of row r is (r * row_shift mod 1) * pitch: 0, 1/2 or 1/3 bond.
    row_shift: float

    @property
    def tile_m(self):
        return self.nx * self.pitch_x_m


def _sample_tile_layout(rng):
    """Random tile grid whose repeat is square and holds a whole number of tiles."""
    grout_m = rng.uniform(0.002, 0.005)
    if rng.random() < 0.6:
        aspect = 1
        width_m = rng.choice([0.2, 0.25, 0.3, 0.33, 0.4, 0.45, 0.5, 0.6]) * rng.uniform(0.98, 1.02)
        width_m = min(width_m, 0.6)
        row_shift = 0.5 if rng.random() < 0.2 else 0.0
    else:
        aspect = int(rng.choice([2, 2, 3]))
        width_m = rng.uniform(0.15, 0.3) if aspect == 2 else rng.uniform(0.15, 0.2)
        row_shift = float(rng.choice([0.0, 0.5, 1.0 / 3.0] if aspect == 3 else [0.0, 0.5, 0.5]))
    pitch_y_m = width_m + grout_m
    # Long side L = aspect * W + (aspect - 1) * grout, as with rectified tiles sold for
    # mixing sizes; then `aspect` rows of pitch_y fill one tile pitch_x exactly, and a
    # repeat of nx tiles by aspect * nx rows is square.
    pitch_x_m = aspect * pitch_y_m
    nx = int(np.clip(round(rng.uniform(0.9, 1.8) / pitch_x_m), 1, 8))
    ny = aspect * nx
    if row_shift == 0.5 and ny % 2:
        # Half-bond rows alternate, so the repeat needs an even number of them.
        nx, ny = nx + 1, ny + aspect
    return _TileLayout(nx=nx, ny=ny, pitch_x_m=float(pitch_x_m), pitch_y_m=float(pitch_y_m),
                       grout_m=float(grout_m), row_shift=float(row_shift))


def _line_coverage(coord_px, pitch_px, width_px):
    """Share of each pixel covered by lines of ``width_px`` centred on multiples of pitch.

    ``coord_px`` holds pixel indices; the lines sit on pixel centres, and the coverage is
    the exact overlap of the unit pixel with the line (a box-filtered, anti-aliased line).
    Also returns the index of the cell (between lines) that each pixel falls in.
    """
    t = coord_px / pitch_px
    cell = np.floor(t)
    frac = t - cell
    d = np.minimum(frac, 1.0 - frac) * pitch_px
    half = 0.5 * width_px
    cov = np.clip(np.minimum(d + 0.5, half) - np.maximum(d - 0.5, -half), 0.0, 1.0)
    return cov.astype(np.float32), cell.astype(np.int64)


def _tile_grid(size_px, layout):
    """Tile ids, grout coverage and edge-band coverage of one repeat, all (size_px,)*2.

    Rows of a running bond differ only by their shift, and there are at most three
    shifts, so every profile along x is computed once per shift and rows copy theirs.
    The arrays are scratch buffers, valid until the next call.
    """
    px_per_m = size_px / layout.tile_m
    pitch_x_px, pitch_y_px = size_px / layout.nx, size_px / layout.ny
    grout_px = layout.grout_m * px_per_m
    # The rounded tile edge shades a band about a millimetre wider than the grout.
    edge_px = grout_px + 2.0 * max(0.7, px_per_m / 1000.0)

    y = np.arange(size_px, dtype=np.float64)
    cov_y, row = _line_coverage(y, pitch_y_px, grout_px)
    wide_y, _ = _line_coverage(y, pitch_y_px, edge_px)
    shifts = np.round((row * layout.row_shift) % 1.0 * 6.0).astype(np.int64)  # sixths
    kinds, kind_of_row = np.unique(shifts, return_inverse=True)
    cov_x = np.empty((len(kinds), size_px), np.float32)
    wide_x = np.empty_like(cov_x)
    col = np.empty((len(kinds), size_px), np.int64)
    for k, sixths in enumerate(kinds):
        x = y + sixths / 6.0 * pitch_x_px
        cov_x[k], col[k] = _line_coverage(x, pitch_x_px, grout_px)
        wide_x[k], _ = _line_coverage(x, pitch_x_px, edge_px)
    shape = (size_px, size_px)
    grout = np.take(cov_x, kind_of_row, axis=0, out=SCRATCH.array("plane0", shape))
    np.maximum(grout, cov_y[:, None], out=grout)
    edge = np.take(wide_x, kind_of_row, axis=0, out=SCRATCH.array("plane1", shape))
    np.maximum(edge, wide_y[:, None], out=edge)
    edge -= grout
    # uint8 arithmetic wraps at 256, which is the id space of cv2.LUT anyway.
    ids = np.take((col % layout.nx).astype(np.uint8), kind_of_row, axis=0,
                  out=SCRATCH.array("ids", shape, np.uint8))
    ids += ((row % layout.ny) * layout.nx % 256).astype(np.uint8)[:, None]
    return ids, grout, edge


def _marble_veins(rng, size_px, px_per_mm, level, *, strength, thin, tag):
    """Opacity (size_px, size_px) float32 of one family of marble veins.

    Perlin's marble: veins are the lines where ``k . x / size_px + turbulence`` is an
    integer. With an integer wave vector ``k`` the phase wraps exactly at the image
    edges, so the veins stay periodic while running diagonally. ``level`` (a per-tile
    phase offset) gives every tile its own veins, as cut from different slabs.

    The result lives in the scratch buffer ``tag``; the noise scratch buffers
    ``noise1`` and ``noise2`` are overwritten.
    """
    spacing_m = rng.uniform(0.12, 0.3) if thin else rng.uniform(0.25, 0.6)
    waves = size_px / (spacing_m * 1000.0 * px_per_mm)
    angle = rng.uniform(0.0, math.pi)
    kx, ky = round(waves * math.cos(angle)), round(waves * math.sin(angle))
    if kx == 0 and ky == 0:
        kx = 1
    # Smooth turbulence: a rough one breaks the veins into specks. Its slope stays
    # below that of the linear term, or the level sets close into rings that look like
    # contour lines on a map.
    sigma_px = rng.uniform(50.0, 120.0) * px_per_mm
    slope = math.hypot(kx, ky) / size_px
    phase = noise_mix(rng, size_px, octave_layers(
        sigma_px, rng.uniform(0.3, 0.6) * sigma_px * slope, 3, persistence=0.4),
        "noise1")
    phase += (np.arange(size_px, dtype=np.float32) * np.float32(ky / size_px))[:, None]
    phase += (np.arange(size_px, dtype=np.float32) * np.float32(kx / size_px))[None, :]
    phase += level
    # Distance in pixels to the nearest vein centre line, over the local vein width,
    # which swells and thins along the vein.
    dist = np.round(phase, out=SCRATCH.array(tag, phase.shape))
    np.subtract(phase, dist, out=dist)
    np.abs(dist, out=dist)
    width_px = max(1.5, (rng.uniform(0.5, 1.2) if thin else rng.uniform(1.0, 3.0)) * px_per_mm)
    width = noise_mix(rng, size_px, [((0.5 * sigma_px,) * 2, 0.5 * width_px)], "noise2")
    width += np.float32(width_px)
    np.maximum(width, 0.6 * width_px, out=width)
    width *= np.float32(slope)
    dist /= width
    # A core (1 - d)^2 plus a faint halo 0.3 * (1 - d / 6), each clipped at zero.
    halo = np.multiply(dist, np.float32(-0.3 / 6.0), out=width)
    halo += np.float32(0.3)
    np.maximum(halo, 0.0, out=halo)
    core = np.subtract(np.float32(1.0), dist, out=dist)
    np.maximum(core, 0.0, out=core)
    core *= core
    core += halo
    core *= np.float32(strength)
    return core


def _render_tiles(rng, size_px, layout):
    """Tile floor on the grid ``layout``, in a random style, see :func:`floor_texture`."""
    px_per_mm = size_px / layout.tile_m / 1000.0
    ids, grout, edge = _tile_grid(size_px, layout)
    n_tiles = min(layout.nx * layout.ny, 256)

    _, colors, veins, tone_sd, mottle_amp, speckle_amp = _TILE_STYLES[
        rng.integers(len(_TILE_STYLES))]
    base = _jitter_rgb(rng, colors[rng.integers(len(colors))], 0.03)
    tile_luma = _luma(base)
    if rng.random() < 0.5:
        # Contrasting grout: a darker grey on light tiles, a lighter one on dark tiles.
        g = (tile_luma * rng.uniform(0.55, 0.75) if tile_luma > 140
             else min(225.0, tile_luma + rng.uniform(60.0, 110.0)))
        grout_rgb = _jitter_rgb(rng, (g, g * 0.99, g * 0.96), 0.02)
    elif tile_luma > 90:
        # "Matching" grout is still visibly darker: it is recessed and picks up dirt.
        grout_rgb = base * rng.uniform(0.68, 0.85)
    else:
        grout_rgb = base * rng.uniform(1.5, 1.9) + 8.0
    # Recessed joints receive less light than the tile faces.
    grout_rgb = grout_rgb * 0.92

    layers = octave_layers(rng.uniform(8.0, 25.0) * px_per_mm, mottle_amp / 3.0, 3)
    layers.append(((fine_scale(0.6 * px_per_mm),) * 2, speckle_amp / 3.0))
    shade = noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    edge *= np.float32(-0.12)
    shade += edge

    # Every channel is tile[id] * k_tile + vein_c * k_vein + grout_c * k_grout, with the
    # weights shared by the channels; the grout takes the tile's noise too, as sand.
    shape = (size_px, size_px)
    k_grout = cv2.multiply(grout, shade, dst=SCRATCH.array("plane2", shape))
    inside = np.subtract(np.float32(1.0), grout, out=grout)
    k_tile = cv2.multiply(inside, shade, dst=edge)
    k_vein = None
    if veins:
        level = cv2.LUT(ids, _lut(rng.uniform(0.0, 1.0, n_tiles)),
                        dst=SCRATCH.array("plane3", shape))
        vein = _marble_veins(rng, size_px, px_per_mm, level, strength=rng.uniform(0.5, 0.85),
                             thin=False, tag="plane4")
        vein += _marble_veins(rng, size_px, px_per_mm, level, strength=rng.uniform(0.12, 0.3),
                              thin=True, tag="plane5")
        np.minimum(vein, 1.0, out=vein)
        k_vein = cv2.multiply(vein, k_tile, dst=vein)
        k_tile = cv2.subtract(k_tile, k_vein, dst=k_tile)
        vein_rgb = (np.array([206.0, 204.0, 198.0]) if tile_luma < 90
                    else base * np.array([0.55, 0.57, 0.63]))

    gains = _tones(rng, n_tiles, tone_sd)
    tone = SCRATCH.array("plane6", shape)
    out = SCRATCH.array("plane7", shape)
    channels = []
    for c in range(3):
        tone = cv2.LUT(ids, _lut(base[c] * gains[:, c]), dst=tone)
        out = cv2.multiply(tone, k_tile, dst=out)
        out = cv2.scaleAdd(k_grout, float(grout_rgb[c]), out, dst=out)
        if k_vein is not None:
            out = cv2.scaleAdd(k_vein, float(vein_rgb[c]), out, dst=out)
        np.maximum(out, 0.0, out=out)
        channels.append(cv2.convertScaleAbs(out, dst=SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(layout.tile_m)


# --------------------------------------------------------------------------- soft floors


def _carpet(rng, size_px):
    """Carpet: pixel-level pile noise, faint mottling, heathered flecks."""
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    base = _jitter_rgb(rng, _CARPET_COLORS[rng.integers(len(_CARPET_COLORS))], 0.06)
    # Tufts are 2-4 mm, about one pixel: the pile is near-white noise, tufts clump a
    # little, and wear and pile direction show as large faint blotches.
    layers = [((fine_scale(rng.uniform(0.5, 1.0) * px_per_mm),) * 2, rng.uniform(0.18, 0.32) / 3.0),
              ((rng.uniform(3.0, 6.0) * px_per_mm,) * 2, rng.uniform(0.08, 0.15) / 3.0)]
    layers += octave_layers(rng.uniform(60.0, 150.0) * px_per_mm, rng.uniform(0.05, 0.12) / 3.0, 2)
    if rng.random() < 0.3:
        # Looped (berber) pile: short rows along x.
        layers.append(((fine_scale(px_per_mm), 5.0 * px_per_mm), rng.uniform(0.1, 0.2) / 3.0))
    shade = noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    np.maximum(shade, 0.0, out=shade)

    # Heathered yarn: a share of fibres in a second color. Each channel is
    # base_c * shade + (fleck_c - base_c) * flecks * shade.
    fleck_rgb = base * np.exp(rng.normal(0.0, 0.1, 3)) * rng.choice([0.8, 1.2])
    flecks = noise_mix(rng, size_px, [((fine_scale(0.7 * px_per_mm),) * 2, 4.0 / 3.0)],
                        "noise1")
    flecks -= np.float32(4.0 * rng.uniform(0.25, 0.5))
    np.clip(flecks, 0.0, 1.0, out=flecks)
    flecks *= shade
    flecks *= np.float32(rng.uniform(0.4, 0.9))
    shape = (size_px, size_px)
    out = SCRATCH.array("plane0", shape)
    channels = []
    for c in range(3):
        out = cv2.addWeighted(shade, float(base[c]), flecks, float(fleck_rgb[c] - base[c]),
                              0.0, dst=out)
        channels.append(cv2.convertScaleAbs(out, dst=SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(tile_m)


def _concrete(rng, size_px):
    """Concrete: grey fractal mottling, stains, pores and aggregate; sometimes polished."""
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    grey = rng.uniform(105.0, 195.0)
    tint = rng.normal(0.0, 0.025)
    base = np.array([grey * (1 + tint), grey, grey * (1 - 1.2 * tint)])
    polished = rng.random() < 0.35
    contrast = rng.uniform(0.07, 0.13) if polished else rng.uniform(0.1, 0.2)

    # Cement paste: fractal mottling with plenty of mid-scale detail (a flat spectrum
    # would read as clouds), plus a sandy grain.
    layers = octave_layers(rng.uniform(20.0, 60.0) * px_per_mm, contrast / 3.0, 5, persistence=0.75)
    layers.append(((max(0.7, rng.uniform(1.0, 2.0) * px_per_mm),) * 2, rng.uniform(0.01, 0.025)))
    shade = noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    # Stains: soft-edged patches where the large-scale noise is high.
    stains = noise_mix(rng, size_px, octave_layers(rng.uniform(80.0, 200.0) * px_per_mm,
                                               4.0 / 3.0, 2), "noise1")
    stains -= np.float32(4.0 * rng.uniform(0.1, 0.35))
    np.clip(stains, 0.0, 1.0, out=stains)
    stains *= np.float32(rng.uniform(0.04, 0.12))
    shade -= stains
    # Pores (dark) and exposed aggregate (light and dark) are the finest detail;
    # polishing exposes more aggregate.
    fine = noise_mix(rng, size_px, [((fine_scale(rng.uniform(0.5, 1.0) * px_per_mm),) * 2,
                                      1.0 / 3.0)], "noise2")
    fine_amp = np.float32(rng.uniform(0.03, 0.07))
    spots = np.abs(fine, out=stains)
    spots -= np.float32(rng.uniform(0.55, 0.75))
    np.maximum(spots, 0.0, out=spots)
    spots *= np.float32(0.3 if polished else rng.uniform(0.4, 1.0))
    shade -= spots
    fine *= fine_amp
    shade += fine
    np.maximum(shade, 0.0, out=shade)
    return _shade_to_rgb8(shade, base), float(tile_m)


def floor_texture(kind, rng, size_px=512):
    """Seamless floor texture of the given kind.

    Parameters
    ----------
    kind : str
        One of :data:`FLOOR_KINDS`: ``"wood"``, ``"tiles"``, ``"carpet"``,
        ``"concrete"``, ``"laminate"``.
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters covered by one repeat of the image (both axes). Plank
        rows and tile grids fit a whole number of times into it: wood planks are
        0.12-0.22 m wide, laminate 0.15-0.25 m, tiles 0.15-0.6 m with 2-5 mm grout;
        carpet and concrete repeat every 1-2 m.

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`FLOOR_KINDS` or ``size_px`` is too small.
    """
    if kind not in FLOOR_KINDS:
        raise ValueError(f"unknown floor kind {kind!r}; valid kinds: {', '.join(FLOOR_KINDS)}")
    size_px = _check_size(size_px)
    if kind == "wood":
        return _planks(rng, size_px, laminate=False)
    if kind == "laminate":
        return _planks(rng, size_px, laminate=True)
    if kind == "tiles":
        return _render_tiles(rng, size_px, _sample_tile_layout(rng))
    if kind == "carpet":
        return _carpet(rng, size_px)
    return _concrete(rng, size_px)


# --------------------------------------------------------------------------- walls


def _hsv_rgb(h, s, v):
    return np.array(colorsys.hsv_to_rgb(h % 1.0, s, v)) * 255.0


def _wall_color(rng):
    u = rng.random()
    warm_or_cool = rng.uniform(0.07, 0.15) if rng.random() < 0.7 else rng.uniform(0.52, 0.62)
    if u < 0.32:  # white
        return _hsv_rgb(warm_or_cool, rng.uniform(0.0, 0.035), rng.uniform(0.93, 0.985))
    if u < 0.57:  # off-white, cream, greige
        return _hsv_rgb(warm_or_cool, rng.uniform(0.04, 0.11), rng.uniform(0.86, 0.95))
    if u < 0.72:  # light grey
        return _hsv_rgb(rng.random(), rng.uniform(0.0, 0.05), rng.uniform(0.70, 0.88))
    if u < 0.88:  # pastel tint
        return _hsv_rgb(rng.random(), rng.uniform(0.08, 0.22), rng.uniform(0.82, 0.95))
    # Accent walls: sage, navy, terracotta, mustard, teal, dusty pink, forest, charcoal.
    h, s, v = [(0.25, 0.25, 0.62), (0.61, 0.5, 0.38), (0.04, 0.5, 0.68), (0.12, 0.55, 0.78),
               (0.50, 0.45, 0.50), (0.97, 0.25, 0.78), (0.33, 0.4, 0.38),
               (0.58, 0.06, 0.32)][rng.integers(8)]
    return _hsv_rgb(h + rng.normal(0, 0.02), s * rng.uniform(0.8, 1.2), v * rng.uniform(0.9, 1.1))


def _paint(rng, size_px, rgb, fine_amp, low_amp, px_per_mm):
    """Flat color with fine stipple and soft mottling, relative amplitudes as given."""
    layers = [((fine_scale(rng.uniform(0.5, 1.5) * px_per_mm),) * 2, fine_amp / 3.0)]
    layers += octave_layers(rng.uniform(40.0, 120.0) * px_per_mm, low_amp / 3.0, 4, persistence=0.6)
    shade = noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    np.maximum(shade, 0.0, out=shade)
    return _shade_to_rgb8(shade, rgb)


def wall_texture(rng, size_px=256):
    """Seamless painted-wall texture.

    Mostly whites, off-whites, light greys and pastel tints, sometimes a stronger
    accent color; the surface is flat, orange-peel (fine roller stipple) or plaster
    (soft large-scale mottling), always subtle.

    Parameters
    ----------
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters of one repeat, 1-2 m.
    """
    size_px = _check_size(size_px)
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    rgb = _wall_color(rng)
    u = rng.random()
    if u < 0.3:  # flat: barely more than dither
        fine_amp, low_amp = rng.uniform(0.004, 0.01), rng.uniform(0.003, 0.008)
    elif u < 0.7:  # orange peel
        fine_amp, low_amp = rng.uniform(0.02, 0.05), rng.uniform(0.004, 0.012)
    else:  # plaster
        fine_amp, low_amp = rng.uniform(0.008, 0.02), rng.uniform(0.02, 0.06)
    return _paint(rng, size_px, rgb, fine_amp, low_amp, px_per_mm), float(tile_m)


def ceiling_texture(rng, size_px=128):
    """Seamless near-white ceiling texture with very subtle noise.

    Parameters
    ----------
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters of one repeat, 1-2 m.
    """
    size_px = _check_size(size_px)
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    hue = rng.uniform(0.07, 0.15) if rng.random() < 0.7 else rng.uniform(0.52, 0.62)
    rgb = _hsv_rgb(hue, rng.uniform(0.0, 0.03), rng.uniform(0.93, 0.985))
    image = _paint(rng, size_px, rgb, rng.uniform(0.006, 0.015), rng.uniform(0.004, 0.012),
                   px_per_mm)
    return image, float(tile_m)
