"""Ceiling lamps from the pools of light they cast on the photo's floor.

A lamp on the ceiling lights the floor under it most, and less with distance: seen from
above (the floor rectified by the calibration), a smooth round pool. The floor's light in
view, smoothed past planks and grain, is fitted with a plane (light from windows and the
room at large) plus up to two pools ``peak / (1 + r^2 / w^2)^(3/2)``: a bare bulb's at ``w``
= its height, a spot's narrower cone at less. A pool clearly brighter than the floor at
large, whose centre the fit puts in view or just beyond it, is a lamp on the ceiling above
that centre: it lights the furniture from there and casts shadows away from it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numba import njit, prange

from .settings import RENDER, LampSettings
from .sun import REC709, linear_rgb


@dataclass(frozen=True)
class Lamp:
    """A ceiling lamp found from its pool of light.

    Attributes
    ----------
    position_m : (3,) tuple of float
        Where it hangs, floor frame (meters; z its height above the floor).
    width_m : float
        The pool's width ``w`` (meters): how fast its light on the floor falls off.
    peak : float
        Its light on the floor right under it, over the floor at large's (the
        irradiance the board gives, :class:`augment.render.staged.Lighting`).
    """

    position_m: tuple
    width_m: float
    peak: float

    def on_floor(self, xy) -> np.ndarray:
        """Its light (n,) on floor points (n, 2+), over the floor at large's."""
        return self.peak * _pool(np.asarray(xy, dtype=np.float64)[..., :2], np.asarray(self.position_m[:2]),
                                 self.width_m)

    def on(self, points_m, normals) -> np.ndarray:
        """Its light (n,) on surfaces at points (n, 3) facing unit normals (n, 3), over
        the floor at large's: the pool's law toward each direction, the inverse square
        of the distance and the cosine of incidence (on the floor: :meth:`on_floor`)."""
        u = np.asarray(self.position_m, dtype=np.float64) - np.asarray(points_m, dtype=np.float64)
        d2 = np.maximum((u * u).sum(axis=1), 1e-4)
        below = u[:, 2] > 1e-3
        tan2 = (u[:, 0] ** 2 + u[:, 1] ** 2) / np.maximum(u[:, 2], 1e-3) ** 2
        height = float(self.position_m[2])
        # The lamp's intensity toward a direction, relative to a bare bulb's: the pool's
        # law over a point light's own, where that direction meets the floor.
        cone = ((1.0 + height ** 2 * tan2 / self.width_m ** 2) / (1.0 + tan2)) ** -1.5
        facing = np.maximum((np.asarray(normals, dtype=np.float64) * u).sum(axis=1) / np.sqrt(d2), 0.0)
        return np.where(below, self.peak * height ** 2 * cone * facing / d2, 0.0)

    def to_json(self) -> dict:
        return {"position_m": [round(float(v), 3) for v in self.position_m], "width_m": round(self.width_m, 3),
                "peak": round(self.peak, 3)}


def find_lamps(image: np.ndarray, floor_mask: np.ndarray, calibration, ceiling_m: float, reference: float,
               left_out=None, settings: LampSettings | None = None, inside=None) -> tuple:
    """The ceiling lamps whose pools of light the photo's floor shows.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo, RGB. Not modified.
    floor_mask : (rows, cols) bool
        Visible floor (scaled to the photo when of another size).
    calibration : Calibration
        Of this photo: the floor's pixels seen from above.
    ceiling_m : float
        The room's height: the lamps hang just below it.
    reference : float
        Linear luminance of the floor at large (the lamps' peaks are relative to it).
    left_out : callable, optional
        Floor points (n, 2) -> (n,) bool: floor not to read (sunlit patches).
    settings : LampSettings, optional
        Default ``RENDER.lamps``.
    inside : callable, optional
        Floor points (n, 2) -> (n,) bool: in the room, where a lamp can hang (not behind
        a wall in view). A pool is looked for there only.

    Returns
    -------
    tuple of Lamp
        Brightest first; empty when the floor shows no pool.
    """
    settings = RENDER.lamps if settings is None else settings
    cells = _floor_light(image, floor_mask, calibration, reference, left_out, settings)
    if cells is None:
        return ()
    xy, light, rgb = cells
    height = ceiling_m - settings.below_ceiling_m
    widths = [f * height for f in settings.width_shares]
    base = np.column_stack([np.ones(len(xy)), xy - xy.mean(axis=0)])
    columns, found = [base], []
    # The search reads a subset of the cells when the floor in view is large.
    every = max(1, len(xy) // settings.search_cells)
    candidates = _candidates(xy, settings.cell_m * 2, settings)
    if inside is not None:
        candidates = candidates[np.asarray(inside(candidates), dtype=bool)]
    for _ in range(settings.max_lamps):
        basis, _ = np.linalg.qr(np.column_stack(columns))
        rest = light - basis @ (basis.T @ light)
        best = _best_pool(xy[::every], rest[::every], basis[::every], widths, candidates, settings)
        if best is None:
            break
        # Refined on a finer grid around the coarse best, with every cell.
        offsets = np.arange(-2, 3) * (settings.cell_m / 2)
        near = best[0] + np.stack(np.meshgrid(offsets, offsets), axis=-1).reshape(-1, 2)
        if inside is not None:
            near = near[np.asarray(inside(near), dtype=bool)]
        best = _best_pool(xy, rest, basis, [best[1]], near, settings)
        if best is None:
            break
        centre, width = best
        pool = _pool(xy, centre, width)
        alone = pool - basis @ (basis.T @ pool)
        amplitude = float(alone @ rest) / max(float(alone @ alone), 1e-12)
        # A pool explains much of the light the plane leaves, its centre is seen, and it
        # fits there: a sun patch's straight, sharp edges leave much of it unexplained.
        explained = amplitude * float(alone @ rest) / max(float(rest @ rest), 1e-12)
        core = pool > 0.5
        misfit = float(np.sqrt(np.mean((rest - amplitude * alone)[core] ** 2))) / amplitude if core.any() else np.inf
        if (explained < settings.min_explained or core.sum() < settings.min_core_cells
                or misfit > settings.max_misfit):
            break
        columns.append(pool[:, None])
        found.append((centre, width, _peak_seen(xy, centre, width, settings)))
    if not found:
        return ()
    # A pool as wide as a bare bulb's carries the room's broad light with it (the bounce, a
    # fill at the ceiling's middle): it places the lamp, which then lights as a narrower one.
    found = [(centre, min(width, settings.max_width_share * height), seen) for centre, width, seen in found]
    columns = [base] + [_pool(xy, centre, width)[:, None] for centre, width, _ in found]
    # All peaks at once: two pools share the floor between them; and in red and blue.
    design = np.column_stack(columns)
    fitted = np.linalg.lstsq(design, np.column_stack([light, rgb[:, 0], rgb[:, 2]]), rcond=None)[0][base.shape[1]:]
    # A pool whose peak the photo does not show falls off one way only, as a window's
    # light does: a lamp only when its light is no bluer than the floor's at large.
    red, blue = np.median(rgb[:, 0]), np.median(rgb[:, 2])
    lamps = [Lamp((float(c[0]), float(c[1]), float(height)), float(w), float(a))
             for (c, w, seen), (a, a_red, a_blue) in zip(found, fitted)
             if settings.min_peak <= a <= settings.max_peak
             and (seen or (a_red > 0 and a_red * blue >= settings.min_flank_warmth * a_blue * red))]
    return tuple(sorted(lamps, key=lambda lamp: -lamp.peak))


def _floor_light(image, floor_mask, calibration, reference, left_out, settings: LampSettings):
    """The floor's light in view seen from above: cell centres (n, 2) and their light (n,)
    and linear colour (n, 3) over ``reference``, smoothed past texture; None with too
    little floor in view."""
    pose = np.asarray(calibration.camera_from_floor, dtype=np.float64)
    R, t = pose[:3, :3], pose[:3, 3]
    foot = (-R.T @ t)[:2]
    fine = settings.cell_m / 2
    n = int(math.ceil(2 * settings.reach_m / settings.cell_m)) * 2
    lo = foot - n * fine / 2
    g = (np.arange(n) + 0.5) * fine
    X, Y = np.meshgrid(lo[0] + g, lo[1] + g)
    points = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    ahead = points @ R[2] + t[2] > 0.1
    px = np.full((len(points), 2), -1.0)
    px[ahead] = calibration.pixels_from_floor(points[ahead])
    h, w = image.shape[:2]
    if floor_mask.shape != (h, w):
        floor_mask = cv2.resize(floor_mask.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST) > 0
    ij = np.round(px).astype(np.int64)
    ok = ahead & (ij[:, 0] >= 0) & (ij[:, 0] < w) & (ij[:, 1] >= 0) & (ij[:, 1] < h)
    ok[ok] = floor_mask[ij[ok, 1], ij[ok, 0]]
    sheet = np.asarray(calibration.board.outline_m(), dtype=np.float64)[:, :2]
    lo_s, hi_s = sheet.min(axis=0) - settings.board_margin_m, sheet.max(axis=0) + settings.board_margin_m
    ok &= ~np.all((points[:, :2] > lo_s) & (points[:, :2] < hi_s), axis=1)
    if left_out is not None and ok.any():
        ok[ok] = ~np.asarray(left_out(points[ok, :2]), dtype=bool)
    if ok.sum() < 4 * settings.min_cells:
        return None
    rgb = np.zeros((len(points), 3), np.float32)
    rgb[ok] = linear_rgb(image[ij[ok, 1], ij[ok, 0]]) / max(reference, 1e-6)
    sigma = settings.smooth_m / fine
    weight = ok.reshape(n, n).astype(np.float32)
    num = cv2.GaussianBlur(rgb.reshape(n, n, 3), (0, 0), sigma)
    den = cv2.GaussianBlur(weight, (0, 0), sigma)
    # Cells whose fine points are all floor: the edges of the floor in view, smoothed with
    # what is not floor, are left out.
    whole = cv2.resize(weight, (n // 2, n // 2), interpolation=cv2.INTER_AREA) > 0.99
    light = cv2.resize(num / np.maximum(den, 1e-6)[..., None], (n // 2, n // 2), interpolation=cv2.INTER_AREA)
    if whole.sum() < settings.min_cells:
        return None
    centres = (np.arange(n // 2) + 0.5) * settings.cell_m
    cx, cy = np.meshgrid(lo[0] + centres, lo[1] + centres)
    xy = np.column_stack([cx[whole], cy[whole]])
    if np.ptp(xy, axis=0).max() < settings.min_extent_m:
        return None
    rgb = light[whole].astype(np.float64)
    return xy, rgb @ REC709, rgb  # smoothing is linear: the luminance of the smoothed colour


def _peak_seen(xy, centre, width, settings: LampSettings) -> bool:
    """Whether the floor in view (cells (n, 2)) shows the pool's peak: floor near its
    centre all around it but for a gap of at most ``settings.max_gap_deg`` (180: a centre
    on the edge of the view). A pool's flank alone falls off one way, as a window's light
    on the floor does: it tells no lamp."""
    d = xy - centre
    near = (d * d).sum(axis=1) <= (settings.side_reach_share * width) ** 2
    if near.sum() < 2:
        return False
    angles = np.sort(np.arctan2(d[near, 1], d[near, 0]))
    gaps = np.diff(np.append(angles, angles[0] + 2 * np.pi))
    return math.degrees(float(gaps.max())) <= settings.max_gap_deg


def _pool(xy, centre, width):
    """The pool's shape at floor points (..., 2): 1 at ``centre``."""
    return (1.0 + ((xy - centre) ** 2).sum(axis=-1) / width ** 2) ** -1.5


def _candidates(xy, step, settings: LampSettings):
    """Pool centres to try: a grid over the floor in view and up to ``beyond_view_m`` past it."""
    margin = settings.beyond_view_m
    lo, hi = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    gx, gy = np.meshgrid(np.arange(lo[0], hi[0] + 1e-9, step), np.arange(lo[1], hi[1] + 1e-9, step))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    # Distance to the floor in view, on a raster of the grid's step.
    seen = np.full(gx.shape, 255, np.uint8)
    ij = np.clip(np.round((xy - lo) / step).astype(np.int64), 0, np.array(gx.shape[::-1]) - 1)
    seen[ij[:, 1], ij[:, 0]] = 0
    far_m = cv2.distanceTransform(seen, cv2.DIST_L2, 5) * step
    return grid[far_m.ravel() <= margin]


def _best_pool(xy, rest, basis, widths, candidates, settings: LampSettings):
    """The pool (centre (2,), width) that explains most of ``rest`` (the light the model so
    far leaves, (n,)) beside ``basis`` (n, k, orthonormal), brighter than the floor around
    it and not implausibly so; None when none is."""
    if len(candidates) == 0:
        return None
    gain, amplitude = _pool_fits(np.ascontiguousarray(xy, np.float64), np.ascontiguousarray(rest, np.float64),
                                 np.ascontiguousarray(basis, np.float64), np.asarray(widths, np.float64),
                                 np.ascontiguousarray(candidates, np.float64))
    gain[(amplitude <= 0) | (amplitude > settings.max_peak)] = 0.0
    w, j = np.unravel_index(int(np.argmax(gain)), gain.shape)
    return None if gain[w, j] <= 0 else (candidates[j].copy(), float(widths[w]))


@njit(cache=True, parallel=True)
def _pool_fits(xy, rest, basis, widths, centres):
    """Per width and centre (w, m): how much of ``rest`` a pool there explains beside the
    basis (the squared length of its projection), and the pool's amplitude."""
    gain = np.zeros((len(widths), len(centres)))
    amplitude = np.zeros((len(widths), len(centres)))
    n, k = basis.shape
    for w in range(len(widths)):
        inv_w2 = 1.0 / widths[w] ** 2
        for j in prange(len(centres)):
            pool = np.empty(n)
            for i in range(n):
                t = 1.0 + ((xy[i, 0] - centres[j, 0]) ** 2 + (xy[i, 1] - centres[j, 1]) ** 2) * inv_w2
                pool[i] = 1.0 / (t * np.sqrt(t))
            for c in range(k):  # the part of the pool the basis already explains goes
                dot = 0.0
                for i in range(n):
                    dot += pool[i] * basis[i, c]
                for i in range(n):
                    pool[i] -= dot * basis[i, c]
            along, norm = 0.0, 0.0
            for i in range(n):
                along += pool[i] * rest[i]
                norm += pool[i] * pool[i]
            if norm > 1e-12:
                gain[w, j] = along * along / norm
                amplitude[w, j] = along / norm
    return gain, amplitude
