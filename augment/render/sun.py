"""The sun's direction from the sunlit patches on the photo's floor.

Sunlight through a window lands on the floor as a bright patch whose straight edges are the
shadows of the window's frame: its jambs and mullions (vertical) cast edges that run along
the sun's direction on the floor, its sill, head and transoms (horizontal, along the wall)
cast edges parallel to that wall. Seen from above (the floor rectified by the calibration),
the patch's edges therefore come in two families. The one not parallel to a wall of the
room gives the sun's azimuth; the other family tells which wall the window is on, and so
which way the light travels. How high the sun stands is not read here.
"""
from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from numba import njit, prange

from .settings import RENDER, SunSettings


@dataclass(frozen=True)
class SunOnFloor:
    """Sunlit patches found on the floor.

    Attributes
    ----------
    axes_xy : tuple of (2,) float
        Unit vectors on the floor (floor frame) along which the patches' edges run, the
        likeliest azimuth of the sun (up to its sign) first: one or two.
    along_wall : bool
        Of two edge families, exactly one runs along a wall of the room: the other is
        the sun's (what makes the first axis certain).
    edge_m : float
        Length of the sun's edges found, meters (about).
    contrast : float
        The sunlit floor's light over the shaded floor's (linear; medians on the two
        sides of the edges): the sun's share of the light in the sun is ``1 - 1 / contrast``.
    center_m : (2,) float
        Where they are: their mean point on the floor, meters.
    downstream : int
        +1 when the light travels along ``axes_xy[0]``, -1 against it, 0 when the floor
        does not tell (the patches' far end runs into a wall; their near end never does).
    lit_share : float
        Share of the floor seen that is in the sun.
    lo_m, cell_m, lit, seen
        The top-down view: its corner (2,) and cell (meters), and rasters (rows, cols) of
        the floor in the sun and of the floor seen.
    edge_sigma_m : float
        The scale the sun's edges were found at: :meth:`sunlit` is as soft (0: sharp).
    ratio_rgb : (3,) float
        ``contrast`` per channel (linear RGB): the sun's colour against the shade's; all
        1 where not read (the key light is then white).
    sheet : (rows, cols) bool or None
        The board's sheet in the top-down view, left out of ``seen``: floor all the same.
    rim_sharpness : float
        How sharply the light steps across the lit floor's rim (median, log) over the
        share of the floor lit times the sun's contrast (log): a sun's edges give 1 and
        more, a level crossed by grain or falling daylight less (inf: not read).
    """

    axes_xy: tuple
    along_wall: bool
    edge_m: float
    contrast: float
    center_m: tuple
    downstream: int
    lit_share: float
    lo_m: tuple
    cell_m: float
    lit: np.ndarray = field(compare=False, repr=False)
    seen: np.ndarray = field(compare=False, repr=False)
    edge_sigma_m: float = 0.0
    ratio_rgb: tuple = (1.0, 1.0, 1.0)
    sheet: np.ndarray | None = field(default=None, compare=False, repr=False)
    rim_sharpness: float = math.inf

    @functools.cached_property
    def _soft(self) -> tuple[np.ndarray, np.ndarray]:
        """``lit`` with the photo's own edge: blurred over the seen floor by the scale its
        edges were found at (thresholded noisy light has a ragged edge); and the floor
        known: the floor seen and the board's sheet, whose light is the floor's either side
        of it along the sun (a patch's side crossing the sheet goes on straight)."""
        lit = self.lit.astype(np.float32) * self.seen
        if self.edge_sigma_m > 0:
            sigma = self.edge_sigma_m / self.cell_m
            seen = cv2.GaussianBlur(self.seen.astype(np.float32), (0, 0), sigma)
            lit = cv2.GaussianBlur(lit, (0, 0), sigma) / np.maximum(seen, 1e-3)
        if self.sheet is None or not self.sheet.any():
            return lit, self.seen
        return _fill_along(lit, self.seen, self.sheet, self.axes_xy[0]), self.seen | self.sheet

    def run_along_sun(self) -> tuple[float, float]:
        """(run_m, cut_share): how far the patches run along the sun (their cells' 1st to
        99th percentile along ``axes_xy[0]``), and the larger share of an end's cells on the
        rim of the floor seen (a wall, the photo's edge, the sheet: the run may go on there)."""
        rows, cols = np.nonzero(self.lit)
        if len(rows) == 0:
            return 0.0, 1.0
        along = cols * self.axes_xy[0][0] + rows * self.axes_xy[0][1]
        lo, hi = np.quantile(along, [0.01, 0.99])
        rim = cv2.dilate((~self.seen).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        cut = max(rim[rows[along <= lo], cols[along <= lo]].mean(), rim[rows[along >= hi], cols[along >= hi]].mean())
        return float((hi - lo) * self.cell_m), float(cut)

    def sunlit(self, xy) -> np.ndarray:
        """How much floor points (n, 2+) lie in the sun: 1.0 in it, 0.0 in shade, between
        over the width of the photo's sun edges, and the share in the sun where the photo
        does not show the floor."""
        xy = np.asarray(xy, dtype=np.float64)
        flat = np.ascontiguousarray(xy.reshape(-1, xy.shape[-1])[:, :2])
        out = np.empty(len(flat))
        soft, known = self._soft
        _sunlit_kernel(flat, self.lo_m[0], self.lo_m[1], self.cell_m, soft, known, self.lit_share, out)
        return out.reshape(xy.shape[:-1])


@njit(cache=True, parallel=True)
def _sunlit_kernel(xy, x0, y0, cell, soft, seen, share, out):
    """Per point, ``soft`` read bilinearly where the nearest cell is seen, else ``share``
    (also outside the raster's inner cells)."""
    rows, cols = soft.shape
    for i in prange(xy.shape[0]):
        fx = (xy[i, 0] - x0) / cell - 0.5
        fy = (xy[i, 1] - y0) / cell - 0.5
        c, r = math.floor(fx), math.floor(fy)
        out[i] = share
        if 0 <= c < cols - 1 and 0 <= r < rows - 1:
            nc = min(max(int(round(fx)), 0), cols - 1)
            nr = min(max(int(round(fy)), 0), rows - 1)
            if seen[nr, nc]:
                u, v = fx - c, fy - r
                out[i] = ((1 - v) * ((1 - u) * soft[r, c] + u * soft[r, c + 1])
                          + v * ((1 - u) * soft[r + 1, c] + u * soft[r + 1, c + 1]))


def _fill_along(values, known, holes, axis_xy) -> np.ndarray:
    """``values`` (rows, cols) with each ``holes`` cell the mean of the first ``known``
    cells either way along ``axis_xy`` (the one met where only one is)."""
    rows, cols = np.nonzero(holes)
    h, w = holes.shape
    found = np.zeros((2, len(rows)), np.float32)
    have = np.zeros((2, len(rows)), bool)
    for side, sign in enumerate((1.0, -1.0)):
        for k in range(1, h + w):
            r = np.rint(rows + sign * k * axis_xy[1]).astype(int)
            c = np.rint(cols + sign * k * axis_xy[0]).astype(int)
            inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
            r, c = np.clip(r, 0, h - 1), np.clip(c, 0, w - 1)
            hit = inside & ~have[side] & known[r, c]
            found[side, hit], have[side, hit] = values[r[hit], c[hit]], True
            if have[side].all() or not inside.any():
                break
    out = values.copy()
    out[rows, cols] = np.where(have.all(axis=0), found.mean(axis=0), found.sum(axis=0))
    return out


REC709 = np.array([0.2126, 0.7152, 0.0722])  # luminance of linear RGB (Rec. 709 primaries)


def sun_elevation_rad(found: SunOnFloor, default_rad: float, settings: SunSettings | None = None) -> float:
    """The sun's height over the floor from its patches: a window's glass
    (``settings.glass_m``, sill to head) casts a patch that long over the sun's slope.
    Where an end of the patches is out of view their run is a lower bound: the height it
    gives can then only lower ``default_rad``. Within ``settings.elevation_deg``."""
    settings = RENDER.sun if settings is None else settings
    run_m, cut = found.run_along_sun()
    if run_m <= 0:
        return default_rad
    elevation = math.atan(settings.glass_m / run_m)
    if cut > settings.max_cut_share:
        elevation = min(elevation, default_rad)
    return float(np.clip(elevation, *np.radians(settings.elevation_deg)))


def linear_rgb(rgb_uint8) -> np.ndarray:
    """Linear light (..., 3) float32 of sRGB-ish pixels (..., 3) uint8 (the renderer's 2.2 power)."""
    return (np.asarray(rgb_uint8, dtype=np.float32) / 255.0) ** 2.2


def linear_luminance(rgb_uint8) -> np.ndarray:
    """Luminance (...,) float32 in linear light of sRGB-ish pixels (..., 3) uint8 (Rec. 709
    weights)."""
    return linear_rgb(rgb_uint8) @ REC709.astype(np.float32)


def wall_angles_rad(polygon_m: np.ndarray, edge_kinds=None) -> np.ndarray:
    """The room's wall directions (k,), radians in [0, pi): the peaks of the boundary edges'
    angles weighted by their length (a rectangular room gives two, 90 degrees apart)."""
    poly = np.asarray(polygon_m, dtype=np.float64)
    d = np.roll(poly, -1, axis=0) - poly
    keep = np.ones(len(poly), bool) if edge_kinds is None else np.asarray(edge_kinds) == "boundary"
    length = np.hypot(d[:, 0], d[:, 1])[keep]
    if length.sum() <= 0:
        return np.zeros(0)
    hist = np.bincount((np.degrees(np.arctan2(d[keep, 1], d[keep, 0])) % 180).astype(int) % 180,
                       weights=length, minlength=180)
    hist = _circular_smooth(hist, 2.0)
    return np.radians(_peaks(hist, 0.25, 20))


def _circular_smooth(hist: np.ndarray, sigma_bins: float) -> np.ndarray:
    k = np.arange(-int(4 * sigma_bins), int(4 * sigma_bins) + 1)
    kernel = np.exp(-0.5 * (k / sigma_bins) ** 2)
    padded = np.concatenate([hist[-len(k):], hist, hist[:len(k)]])
    return np.convolve(padded, kernel / kernel.sum(), mode="same")[len(k):len(k) + len(hist)]


def _peaks(hist: np.ndarray, min_share: float, min_apart_deg: float) -> np.ndarray:
    """Angles (degrees, bin centres refined) of a 180-bin circular histogram's peaks, the
    strongest first: at least ``min_share`` of the top one and ``min_apart_deg`` apart."""
    n = len(hist)
    is_peak = (hist >= np.roll(hist, 1)) & (hist > np.roll(hist, -1)) & (hist > 0)
    order = [i for i in np.argsort(-hist) if is_peak[i]]
    found = []
    for i in order:
        if hist[i] < min_share * hist[order[0]]:
            break
        if all(min(abs(i - j), n - abs(i - j)) >= min_apart_deg for j in found):
            found.append(i)
    out = []
    for i in found:  # parabolic refinement
        a, b, c = hist[(i - 1) % n], hist[i], hist[(i + 1) % n]
        den = a - 2 * b + c
        out.append((i + (0.5 * (a - c) / den if den != 0 else 0.0)) % n)
    return np.array(out)


def _axis_gap_deg(a_deg, b_deg):
    """Angle between undirected directions (degrees, arrays broadcast), degrees in [0, 90]."""
    return np.abs((np.asarray(a_deg) - b_deg + 90.0) % 180.0 - 90.0)


def find_sun(image: np.ndarray, floor_mask: np.ndarray, floor_from_image: np.ndarray, camera_xy_m,
             walls_rad=None, exclude_m=None, settings: SunSettings | None = None,
             colour: bool = True) -> SunOnFloor | None:
    """Sunlit patches on the floor and the direction their edges give, or None when the
    floor shows none.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo, RGB. Not modified.
    floor_mask : (h, w) bool
        The floor in view.
    floor_from_image : (3, 3) float
        Homography from pixels (x, y, 1) to floor points (x, y, 1), meters (lens
        distortion already removed, or small).
    camera_xy_m : (2,) float
        The camera's foot on the floor: only the floor within ``settings.reach_m`` of it is read.
    walls_rad : (k,) float, optional
        The room's wall directions (:func:`wall_angles_rad`).
    exclude_m : (k, 2) float, optional
        A convex region of the floor to leave out (the board's sheet), meters.
    settings : SunSettings, optional
        Default ``RENDER.sun``.
    colour : bool
        Where the light shows no sun's edges, read them in colour (:func:`_sun_in_colour`).

    Returns
    -------
    SunOnFloor or None
    """
    settings = RENDER.sun if settings is None else settings
    view = _top_view(image, floor_mask, floor_from_image, camera_xy_m, exclude_m, settings)
    if view is None:
        return None
    top_rgb, top, valid, standing, lo, cell, sheet = view
    walls_rad = np.zeros(0) if walls_rad is None else np.asarray(walls_rad, dtype=np.float64)
    if len(walls_rad) == 1:  # one wall in view: rooms have square corners, the others run across it
        walls_rad = np.append(walls_rad, (walls_rad[0] + math.pi / 2) % math.pi)
    for sigma_m, min_contrast in settings.edge_scales:  # sharp edges first, then soft ones (a blurred photo)
        found = _patches_at(top, valid, standing, lo, cell, sigma_m, min_contrast, walls_rad, settings)
        if found is not None:
            return dataclasses.replace(found, ratio_rgb=_ratio_rgb(top_rgb, found, settings), sheet=sheet)
    found = _sun_in_colour(top_rgb, top, valid, standing, lo, cell, walls_rad, settings) if colour else None
    return None if found is None else dataclasses.replace(found, sheet=sheet)


def _sun_in_colour(top_rgb, top, valid, standing, lo, cell, walls_rad, settings: SunSettings) -> SunOnFloor | None:
    """Sun and shade may differ more in colour than in light (a white sun in a room lit warm
    by lamps, a low sun's orange beside the sky's blue): the sun's edges read in the channel
    whose bright floor stands furthest above its median, when that is
    ``settings.colour_spread`` times the luminance's, and kept only when the patch found is
    tinted (channels' contrasts ``settings.min_tint`` apart: a lamp's pool or a lighter tile
    is about grey); its contrast is the luminance's."""
    linear = linear_rgb(top_rgb)
    logs = np.log(np.maximum(np.column_stack([linear[valid], top[valid]]), 1e-4))
    median, bright = np.percentile(logs, [50, 95], axis=0)
    spread = bright - median
    c = int(np.argmax(spread[:3]))
    if not spread[c] >= settings.colour_spread * spread[3]:
        return None
    channel = np.ascontiguousarray(linear[..., c])
    for sigma_m, min_contrast in settings.edge_scales:
        found = _patches_at(channel, valid, standing, lo, cell, sigma_m, min_contrast, walls_rad, settings)
        if found is None:
            continue
        sides = _sun_and_shade(top_rgb, found, settings)
        if sides is None:
            return None
        ratio = sides[0] / np.maximum(sides[1], 1e-4)
        contrast = float(sides[0] @ REC709) / max(float(sides[1] @ REC709), 1e-6)
        if contrast <= 1.0 or ratio.max() < settings.min_tint * ratio.min():
            return None
        return dataclasses.replace(found, contrast=contrast, ratio_rgb=tuple(float(v) for v in ratio))
    return None



def bright_floor(image: np.ndarray, floor_mask: np.ndarray, floor_from_image: np.ndarray, camera_xy_m, axis_xy,
                 exclude_m=None, settings: SunSettings | None = None) -> SunOnFloor | None:
    """Sunlit floor whose edges :func:`find_sun` does not read (soft, or blurred by the
    photo), the sun's azimuth known from elsewhere (a window in view): the floor over
    ``settings.bright_ratio`` times its median light, when that is at least
    ``settings.bright_share`` of the floor seen. So only that floor loses the sun under
    the furniture, not all of it.

    Parameters are :func:`find_sun`'s, and ``axis_xy`` (2,): the way the light travels on
    the floor. Returns a :class:`SunOnFloor` (its ``downstream`` 0, no edges), or None.
    """
    settings = RENDER.sun if settings is None else settings
    view = _top_view(image, floor_mask, floor_from_image, camera_xy_m, exclude_m, settings)
    if view is None:
        return None
    top_rgb, top, valid, _, lo, cell, sheet = view
    log = cv2.GaussianBlur(np.log(np.maximum(top, 1e-4)), (0, 0), max(1.0, settings.bright_smooth_m / cell))
    shade = float(np.median(log[valid]))
    lit = valid & (log > shade + math.log(settings.bright_ratio))
    lit = cv2.morphologyEx(lit.astype(np.uint8), cv2.MORPH_OPEN, np.ones((5, 5), np.uint8)) > 0
    if lit.sum() < settings.bright_share * valid.sum():
        return None
    rc = np.argwhere(lit).mean(axis=0)
    axis = np.asarray(axis_xy, dtype=np.float64)[:2]
    found = SunOnFloor((tuple(float(v) for v in axis / np.linalg.norm(axis)),), False, 0.0,
                       float(math.exp(np.median(log[lit]) - np.median(log[valid & ~lit]))),
                       (float(lo[0] + rc[1] * cell), float(lo[1] + rc[0] * cell)), 0, float(lit.sum() / valid.sum()),
                       (float(lo[0]), float(lo[1])), float(cell), lit, valid, float(settings.bright_smooth_m))
    return dataclasses.replace(found, ratio_rgb=_ratio_rgb(top_rgb, found, settings), sheet=sheet)


def _top_view(image, floor_mask, floor_from_image, camera_xy_m, exclude_m, settings: SunSettings):
    """The floor in view from above, within ``settings.reach_m`` of the camera's foot:
    its colour (rows, cols, 3) uint8 and linear light, the floor seen (bool), the walls and
    things standing in view (bool), the view's corner (2,) and cell, meters; None when
    too little floor shows."""
    h, w = floor_mask.shape
    image_from_floor = np.linalg.inv(floor_from_image)
    # The floor in view, from above: its box from a coarse sample of the mask's pixels.
    ys, xs = np.nonzero(floor_mask[::8, ::8])
    if len(xs) < 20:
        return None
    pts = np.column_stack([xs * 8.0, ys * 8.0, np.ones(len(xs))]) @ floor_from_image.T
    ok = pts[:, 2] > 0
    xy = pts[ok, :2] / pts[ok, 2:]
    xy = xy[np.hypot(*(xy - np.asarray(camera_xy_m)[:2]).T) < settings.reach_m]
    if len(xy) < 20:
        return None
    # A rim beyond the floor: the walls and things it runs into (see _downstream).
    lo, hi = xy.min(axis=0) - settings.rim_m, xy.max(axis=0) + settings.rim_m
    cell = max(settings.cell_m, float(np.max(hi - lo)) / settings.max_cells)
    cols, rows = (np.ceil((hi - lo) / cell).astype(int) + 1)
    gx, gy = np.meshgrid(lo[0] + np.arange(cols) * cell, lo[1] + np.arange(rows) * cell)
    p = np.stack([gx, gy, np.ones_like(gx)], axis=-1) @ image_from_floor.T
    front = p[..., 2] > 1e-9
    map_x = np.where(front, p[..., 0] / np.where(front, p[..., 2], 1), -1).astype(np.float32)
    map_y = np.where(front, p[..., 1] / np.where(front, p[..., 2], 1), -1).astype(np.float32)
    # Only the view from above is linearized: a 12 MP photo costs no more than a small one.
    top_rgb = cv2.remap(np.ascontiguousarray(image), map_x, map_y, cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    top = linear_luminance(top_rgb)
    valid = cv2.remap(floor_mask.astype(np.uint8), map_x, map_y, cv2.INTER_NEAREST,
                      borderMode=cv2.BORDER_CONSTANT, borderValue=0) > 0
    valid &= top > 1e-4
    in_view = front & (map_x >= 0) & (map_x <= w - 1) & (map_y >= 0) & (map_y <= h - 1)
    standing = in_view & ~valid  # walls and things in view (not the photo's edge)
    if valid.sum() < 400:
        return None
    sheet = None
    if exclude_m is not None:  # the board: its paper's edges are the sharpest steps on the floor
        corners = (np.asarray(exclude_m, dtype=np.float64) - lo) / cell
        sheet = np.zeros(valid.shape, np.uint8)
        cv2.fillConvexPoly(sheet, np.round(corners).astype(np.int32), 1)
        sheet = (sheet > 0) & valid
        valid &= ~sheet
    return top_rgb, top, valid, standing, lo, cell, sheet


def unit_colour(ratio, limit: float | None = None) -> tuple:
    """A light's colour from ``ratio`` (3,), linear RGB over another light's: scaled to
    luminance 1, each channel within ``1 / limit`` and ``limit`` of it (default
    ``RENDER.sun.max_tint``); white where a channel is not positive."""
    limit = RENDER.sun.max_tint if limit is None else limit
    ratio = np.asarray(ratio, dtype=np.float64)
    lum = float(ratio @ REC709)
    if not lum > 0 or np.any(ratio <= 0):
        return (1.0, 1.0, 1.0)
    tint = np.clip(ratio / lum, 1.0 / limit, limit)
    return tuple(float(v) for v in tint / (tint @ REC709))


def _ratio_rgb(top_rgb, found: SunOnFloor, settings: SunSettings) -> tuple:
    """The sunlit floor's light over the shade's beside it, per channel (medians; the
    floor's own colour cancels): the sun's colour against the rest of the light. Floor
    within ``settings.colour_gap_m`` of a sun edge (the penumbra) is left out, the shade
    is read within ``settings.colour_ring_m`` of the patches, and clipped pixels not at
    all; grey (the contrast in each channel) when either side shows too little."""
    sides = _sun_and_shade(top_rgb, found, settings)
    if sides is None:
        return (found.contrast,) * 3
    ratio = sides[0] / np.maximum(sides[1], 1e-4)
    return tuple(float(v) for v in ratio) if np.all(ratio > 1.0) else (found.contrast,) * 3


def _sun_and_shade(top_rgb, found: SunOnFloor, settings: SunSettings):
    """The linear light (3,) of the sunlit floor and of the shade beside it (medians, as
    :func:`_ratio_rgb` reads them), or None when either side shows too little."""
    lit = found.lit.astype(np.uint8)
    gap = max(1, round(settings.colour_gap_m / found.cell_m))
    ring = max(gap + 1, round(settings.colour_ring_m / found.cell_m))
    clear = np.ones((2 * gap + 1,) * 2, np.uint8)
    unclipped = found.seen & (top_rgb.max(axis=2) < 250)
    sun = unclipped & (cv2.erode(lit, clear) > 0)
    near = cv2.dilate(lit, np.ones((2 * ring + 1,) * 2, np.uint8)) > 0
    shade = unclipped & near & ~(cv2.dilate(lit, clear) > 0)
    if sun.sum() < 50 or shade.sum() < 50:
        return None
    return tuple(np.median(linear_rgb(top_rgb[side]), axis=0) for side in (sun, shade))


def _patches_at(top, valid, standing, lo, cell, sigma_m, min_median_contrast, walls_rad,
                settings: SunSettings) -> SunOnFloor | None:
    """:func:`find_sun` on the top-down view ``top`` of the floor's light, its edges read at
    the scale ``sigma_m``, the sun at least ``min_median_contrast`` times the shade."""
    # Steps of light (the sun's edges), not lines (seams, grout): the slope of the log
    # light smoothed over a few centimetres; an ideal step of height A seen through a
    # Gaussian of sigma s has slope A / (s sqrt(2 pi)) at its centre.
    sigma = max(1.0, sigma_m / cell)
    log = cv2.GaussianBlur(np.log(np.maximum(top, 1e-4)), (0, 0), sigma)
    dx = cv2.Sobel(log, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    dy = cv2.Sobel(log, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    step = np.hypot(dx, dy) * sigma * math.sqrt(2 * math.pi)
    margin = int(math.ceil(3 * sigma)) + 2
    inner = cv2.erode(valid.astype(np.uint8), np.ones((2 * margin + 1, 2 * margin + 1), np.uint8)) > 0
    edges = inner & (step >= math.log(settings.min_contrast))
    length_m = float(edges.sum()) * cell / (2.5 * sigma)  # an edge is about 2.5 sigma wide
    if length_m < settings.min_edge_directed_m:
        return None
    weight = step[edges]
    edge_deg = (np.degrees(np.arctan2(dy[edges], dx[edges])) + 90.0) % 180.0
    hist = np.bincount(edge_deg.astype(int) % 180, weights=weight, minlength=180)
    smooth = _circular_smooth(hist, 2.0)
    peaks = _peaks(smooth, settings.min_peak_share, 20)
    if len(peaks) == 0:
        return None
    walls_deg = np.degrees(walls_rad)

    def on_wall(a_deg, tol_deg=settings.wall_tol_deg):
        return bool(np.any(_axis_gap_deg(a_deg, walls_deg) <= tol_deg))

    two = list(peaks[:2])
    free = [a for a in two if not on_wall(a)]
    if len(walls_deg) and not free:
        # The strongest steps run along the walls (planks, tiles, a wall's shade); the sun's
        # edges may still show off the walls, fainter: then they alone are read.
        peaks = [a for a in _peaks(smooth, 0.0, 2 * settings.family_deg)
                 if not on_wall(a, settings.wall_tol_deg + settings.family_deg)]
        if not peaks:
            return None
        family = _axis_gap_deg(edge_deg, peaks[0]) <= settings.family_deg
        length_m = float(family.sum()) * cell / (2.5 * sigma)
        if length_m < settings.min_edge_m:
            return None
        edges[edges] = family
        edge_deg = edge_deg[family]
        two = [peaks[0]]
    along_wall = len(two) == 2 and len(free) == 1
    rc = np.argwhere(edges).mean(axis=0)
    center = (float(lo[0] + rc[1] * cell), float(lo[1] + rc[0] * cell))
    if along_wall:
        two = free + [a for a in two if a != free[0]]
    axes = tuple((math.cos(math.radians(a)), math.sin(math.radians(a))) for a in two)
    # The light on either side of the edges, 3 sigma off along their slope: sun and shade.
    r, c = np.nonzero(edges)
    g = np.hypot(dx[r, c], dy[r, c])
    k = 3.0 * sigma
    rows, cols = valid.shape
    sides = []
    for sgn in (1.0, -1.0):
        rr = np.clip(np.round(r + sgn * k * dy[r, c] / g).astype(int), 0, rows - 1)
        cc = np.clip(np.round(c + sgn * k * dx[r, c] / g).astype(int), 0, cols - 1)
        keep = valid[rr, cc]
        sides.append(float(np.median(log[rr[keep], cc[keep]])) if keep.any() else math.nan)
    sun_log, shade_log = sides
    if not sun_log - shade_log > math.log(min_median_contrast):
        return None
    contrast = float(math.exp(sun_log - shade_log))
    # In the sun: floor nearly as bright as the sunny side of the edges, in patches that
    # edges along the sun bound (a bright stretch of floor without a sharp edge is
    # lamplight; a light plank's edges run along the walls).
    lit = valid & (log > shade_log + settings.lit_level * (sun_log - shade_log))
    lit = cv2.morphologyEx(lit.astype(np.uint8), cv2.MORPH_OPEN, np.ones((5, 5), np.uint8))
    n_labels, labels = cv2.connectedComponents(lit, connectivity=8)
    sun_edges = np.zeros(edges.shape, np.uint8)
    sun_edges[edges] = _axis_gap_deg(edge_deg, two[0]) <= settings.family_deg
    along_sun = cv2.dilate(sun_edges, np.ones((5, 5), np.uint8)) > 0
    touch = np.bincount(labels[along_sun], minlength=n_labels)
    touch[0] = 0
    lit = (touch >= settings.min_touch_cells)[labels]
    if lit.sum() < 100:
        return None
    lit_share = float(lit.sum() / valid.sum())
    rim_sharpness = _rim_step(lit, inner, step) / max(lit_share * (sun_log - shade_log), 1e-9)
    if rim_sharpness < settings.rim_step_per_lit:
        return None
    downstream = _downstream(lit, standing, axes[0], margin)
    if length_m < settings.min_edge_m and not downstream:
        return None  # a small patch is trusted only when its far end says which way the light goes
    return SunOnFloor(axes, bool(along_wall), length_m, contrast, center, downstream,
                      lit_share, (float(lo[0]), float(lo[1])), float(cell), lit, valid, float(sigma_m),
                      rim_sharpness=float(rim_sharpness))


def _rim_step(lit, inner, step) -> float:
    """The step of log light (median) on the rim of the floor ``lit`` inside ``inner``:
    the full sun's contrast where the sun's edges bound it, little where the light
    merely crosses a level (grain, planks, daylight falling off)."""
    rim = (cv2.morphologyEx(lit.astype(np.uint8), cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0) & inner
    return float(np.median(step[rim])) if rim.any() else 0.0


def _downstream(lit, standing, axis_xy, margin) -> int:
    """Which way along ``axis_xy`` the light travels, +1 or -1, or 0 when the floor does
    not tell: a window's sill stands above the floor, so its patch never reaches the
    window's wall, while the far end of a patch runs into the wall it climbs."""
    rows, cols = np.nonzero(lit)
    along = cols * axis_xy[0] + rows * axis_xy[1]
    lo_s, hi_s = np.quantile(along, [0.1, 0.9])
    near_wall = cv2.dilate(standing.astype(np.uint8), np.ones((2 * margin + 3, 2 * margin + 3), np.uint8)) > 0
    touch = near_wall[rows, cols]
    ends = (along >= hi_s).sum(), (along <= lo_s).sum()
    plus, minus = touch[along >= hi_s].sum() / max(ends[0], 1), touch[along <= lo_s].sum() / max(ends[1], 1)
    if max(plus, minus) < 0.1 or abs(plus - minus) < 0.1:
        return 0
    return 1 if plus > minus else -1
