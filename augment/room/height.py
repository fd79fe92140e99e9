"""Room (wall) height from a calibrated photo: single-view metrology on vertical edges.

The thesis (Appendix C.3.2, step 5) runs HED over the photo, keeps edges whose cosine with
the floor normal exceeds 0.9 and takes the longest as the height of the space. Stager
keeps the idea and makes each step a measurement:

1. **Line segments** (:func:`detect_segments`): OpenCV's FastLineDetector (Canny edges,
   then line fitting) on a lightly blurred gray copy shrunk by a whole factor to about
   ``CAMERA.lines.side_px`` across, so a 12 MP photo costs about what a 1 MP one does. Not HED:
   it needs trained weights Stager does not ship, and its edge map would still have to be
   cut into straight segments. LSD (``method="lsd"``) is the alternative; slower, and it
   breaks lines into more short pieces.
2. **The vertical direction** comes from the calibration, not the image: the image of the
   floor normal, the vertical vanishing point ``v = K R [0, 0, 1]``
   (:func:`vertical_vanishing_point`).
3. **Vertical edges** (:func:`vertical_alignment`): the paper's cosine test done in 3D. A
   segment and the camera center span its interpretation plane; every 3D line that could
   have made the segment lies in it, so the largest cosine any of them can have with the
   floor normal is the cosine of the angle between the normal and that plane. Real
   vertical edges have it within a fraction of a degree of 1; 0.9 admits 26 degrees, far
   too loose once the normal is known, so ``CAMERA.lines.min_vertical_cos`` is much
   stricter. The segment must also pass through ``v`` (its endpoints within
   ``CAMERA.lines.vp_distance_fraction`` of the line from its midpoint to ``v``). Pieces
   of one edge are merged (across longer gaps only where the image shows the edge in the
   gap) and followed in the image beyond their detected ends (past a baseboard, through a
   light pool).
4. **Metrology** (:func:`segment_heights`): the lower end of an edge standing on the floor
   maps to floor meters through the floor homography; the vertical through that foot
   images to the line from the foot to ``v``, and the top's height ``h`` solves
   ``pi(foot + h up) = top`` exactly along that line (the top projected onto it: least
   squares along the line, in closed form).
5. **Candidates**: vertical edges (room corners, door frames, window frames, boxes), and,
   given a floor mask, wall--ceiling lines: long lines above the horizon whose points,
   dropped vertically to where the floor begins, all give one height, whose feet lie on
   one floor line, and which span their wall (a window or door head stops while its wall
   goes on).
6. **Checks**: the foot is on the floor (with a mask: the mask turns to floor there and
   the foot moves to that boundary; without one, the image just below looks like the
   floor around the board, a weak test); both ends are in the frame; no long line crosses
   the vertical above the top (a window head has its wall, and the ceiling line, above
   it); the height is plausible (``ROOM.height.min_m`` excludes door frames).
7. **Estimate** (:func:`measure_height`, :func:`height_from_segments`): the weighted
   median of the highest well-supported cluster of heights (anything that stands on the
   floor but stops short of the ceiling measures lower), weights from the image length
   and whether a long line (the ceiling's) meets the top; a confidence from the cluster's
   weight and share. Without a trustworthy candidate: ``ROOM.height.fallback_m`` with
   ``fallback=True`` and the reason.

Conventions: images are (row, col) arrays; points are (x, y) pixels with pixel centers at
integers (OpenCV). Segments are ``(n, 4)`` rows ``x1, y1, x2, y2`` in full-resolution,
undistorted pixels. The floor frame is the calibration's (meters, z up, origin at the
board's center); camera axes are OpenCV's. Public functions never modify their inputs.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from layout.geometry import point_segment_distances

from ..camera.calibration import Calibration
from ..camera.lines import (as_camera, as_segments, detect_raw, floor_share, is_vertical, prepare_lines, sample_image,
                            shrink_factor, to_full, to_gray, to_small, toward_vanishing_point)
from ..camera.settings import CAMERA
from .settings import ROOM


@dataclass(frozen=True)
class HeightResult:
    """A measured wall height and the evidence behind it.

    Attributes
    ----------
    height_m : float
        The wall height in meters (``ROOM.height.fallback_m`` when ``fallback``).
    confidence : float
        0 to 1: how much and how consistent the evidence is (0 for the fallback).
    fallback : bool
        True when no trustworthy edge was found and ``height_m`` is the default.
    reason : str
        One sentence: what the estimate rests on, or why it fell back.
    bases_px, tops_px : (k, 2) float64
        Lower (on the floor) and upper ends of the measured vertical edges, pixels.
    heights_m : (k,) float64
        Height of each edge's top above the floor.
    feet_m : (k, 2) float64
        Where each edge stands on the floor, floor meters.
    kinds : (k,) str
        ``"edge"`` for a vertical edge, ``"ceiling"`` for a wall--ceiling junction line (then
        base and top are its point of median height, the base where the floor mask ends).
    weights : (k,) float64
        Each edge's weight in the estimate (length and junction support).
    inliers : (k,) bool
        The edges the estimate was taken from.
    given : bool
        True when ``height_m`` is the user's, taken because the photo does not show it.
    at_least_m : float or None
        When not measured: the top of the tallest whole vertical edge standing on the
        floor (a door's or window's frame), which the walls reach at least.
    """

    height_m: float
    confidence: float
    fallback: bool
    reason: str
    bases_px: np.ndarray = field(repr=False)
    tops_px: np.ndarray = field(repr=False)
    heights_m: np.ndarray = field(repr=False)
    feet_m: np.ndarray = field(repr=False)
    kinds: np.ndarray = field(repr=False)
    weights: np.ndarray = field(repr=False)
    inliers: np.ndarray = field(repr=False)
    given: bool = False
    at_least_m: float | None = None

    def to_json(self) -> dict:
        return {"height_m": self.height_m, "confidence": self.confidence, "fallback": self.fallback,
                "given": self.given, "at_least_m": self.at_least_m, "reason": self.reason,
                "segments": [{"kind": str(k), "base_px": b.round(2).tolist(), "top_px": t.round(2).tolist(),
                              "height_m": None if not np.isfinite(h) else round(float(h), 4),
                              "foot_m": None if not np.all(np.isfinite(f)) else f.round(4).tolist(),
                              "weight": round(float(w), 4), "inlier": bool(i)}
                             for b, t, h, f, k, w, i in zip(self.bases_px, self.tops_px, self.heights_m,
                                                            self.feet_m, self.kinds, self.weights, self.inliers)]}


# ---------------------------------------------------------------------------------------
# Validation helpers


def _as_points(points, name: str) -> np.ndarray:
    p = np.ascontiguousarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"{name} of shape {p.shape}: expected (n, 2) pixels")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} holds non-finite values")
    return p


def _as_mask(floor_mask, size_px: tuple[int, int]) -> np.ndarray | None:
    if floor_mask is None:
        return None
    mask = np.asarray(floor_mask)
    width, height = size_px
    if mask.shape != (height, width):
        raise ValueError(f"floor_mask of shape {mask.shape}: expected {(height, width)} like the photo")
    return mask if mask.dtype == bool else mask != 0


# ---------------------------------------------------------------------------------------
# 1. Line segments


# ---------------------------------------------------------------------------------------
# 2. The vertical direction and 3. vertical segments


# ---------------------------------------------------------------------------------------
# 4. Metrology


def segment_heights(bases_px: np.ndarray, tops_px: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Heights of vertical edges standing on the floor, by single-view metrology.

    Each base is taken to lie on the floor: the floor homography ``K [r1 r2 t]`` maps it
    to floor meters (the foot). The vertical through the foot images to the line from the
    base to the vertical vanishing point; the top is projected onto that line (least
    squares along the line) and ``h`` solves ``pi(foot + h up) = top`` exactly on it.

    Parameters
    ----------
    bases_px : (n, 2) float64
        Lower ends, on the floor, undistorted pixels.
    tops_px : (n, 2) float64
        Upper ends, undistorted pixels.
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64

    Returns
    -------
    heights_m : (n,) float64
        Height of each top above the floor, meters; NaN where the base is not in front
        of the camera on the floor or the top lies at or beyond the vanishing point.
    feet_m : (n, 2) float64
        The feet in floor meters (NaN where the base does not see the floor).
    """
    bases = _as_points(bases_px, "bases_px")
    tops = _as_points(tops_px, "tops_px")
    if bases.shape != tops.shape:
        raise ValueError(f"bases_px {bases.shape} and tops_px {tops.shape} differ in shape")
    K, pose = as_camera(K, camera_from_floor)
    R, t = pose[:3, :3], pose[:3, 3]
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    floor = np.column_stack([bases, np.ones(len(bases))]) @ np.linalg.inv(H).T
    with np.errstate(divide="ignore", invalid="ignore"):
        feet = floor[:, :2] / floor[:, 2:3]
    feet_3d = np.column_stack([feet, np.zeros(len(feet))])
    a = (feet_3d @ R.T + t) @ K.T                  # homogeneous image of the foot; a_w = its depth
    b = K @ R[:, 2]                                # the vertical vanishing point, unscaled
    foot_px = a[:, :2] / a[:, 2:3]
    d = b[:2] - foot_px * b[2]                     # image direction of the vertical at the foot
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    s_top = np.sum((tops - foot_px) * d, axis=1)
    # Along d: ((a + h b)_xy / (a + h b)_w - foot) . d = s_top, linear in h.
    denom = b[:2] @ d.T - (np.sum(foot_px * d, axis=1) + s_top) * b[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        heights = s_top * a[:, 2] / denom
    bad = ~(a[:, 2] > 0) | ~np.isfinite(heights)
    # A top past the vanishing point would have a depth of the wrong sign.
    w_top = a[:, 2] + np.where(bad, 0.0, heights) * b[2]
    bad |= ~(w_top > 0)
    heights[bad] = np.nan
    feet[~(a[:, 2] > 0)] = np.nan
    return heights, feet


# ---------------------------------------------------------------------------------------
# 5. Which edges to trust


def _elevation(points: np.ndarray, K: np.ndarray, up_camera: np.ndarray) -> np.ndarray:
    """Sine of each pixel's ray elevation above the horizontal (negative: sees the floor)."""
    rays = np.column_stack([points, np.ones(len(points))]) @ np.linalg.inv(K).T
    return rays @ up_camera / np.linalg.norm(rays, axis=1)


def _merge_vertical(seg: np.ndarray, vp: np.ndarray, tol_px: float, gap_px: float,
                    bridge=None, bridge_px: float = 0.0) -> list[np.ndarray]:
    """Group vertical segments lying on one line through ``vp`` with gaps up to ``gap_px``,
    or up to ``bridge_px`` where ``bridge(p, q)`` says the edge runs on across the gap."""
    n = len(seg)
    mid = (seg[:, :2] + seg[:, 2:]) / 2
    u = toward_vanishing_point(mid, vp)
    parent = np.arange(n)

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        ends = np.vstack([seg[:, :2], seg[:, 2:]]) - mid[i]            # all endpoints, relative to i
        off = np.abs(ends[:, 0] * u[i, 1] - ends[:, 1] * u[i, 0])      # distance from i's line
        along = ends @ u[i]
        near = (off[:n] <= tol_px) & (off[n:] <= tol_px)
        lo_j, hi_j = np.minimum(along[:n], along[n:]), np.maximum(along[:n], along[n:])
        lo_i, hi_i = min(along[i], along[i + n]), max(along[i], along[i + n])
        gap = np.maximum(lo_j - hi_i, lo_i - hi_j)
        for j in np.flatnonzero(near & (gap <= max(gap_px, bridge_px))):
            if j <= i or root(j) == root(i):
                continue
            if gap[j] > gap_px:
                span = (hi_i, lo_j[j]) if lo_j[j] > hi_i else (hi_j[j], lo_i)
                if bridge is None or not bridge(mid[i] + span[0] * u[i], mid[i] + span[1] * u[i]):
                    continue
            parent[root(j)] = root(i)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return [np.array(g) for g in groups.values()]


def _gradients(small: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return cv2.Sobel(small, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(small, cv2.CV_32F, 0, 1, ksize=3)


def _across(gx: np.ndarray, gy: np.ndarray, p: np.ndarray, q: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """|gradient across the line p->q| sampled every pixel along it, at lateral ``offsets``:
    (len(offsets), m)."""
    length = max(np.linalg.norm(q - p), 1.0)
    along = (q - p) / length
    normal = np.array([-along[1], along[0]])
    ks = np.arange(0.0, length + 1)
    pts = p + ks[None, :, None] * along + offsets[:, None, None] * normal
    return np.abs(sample_image(gx, pts) * normal[0] + sample_image(gy, pts) * normal[1])


def _bridge_test(grads: tuple[np.ndarray, np.ndarray], k: int):
    """A ``bridge(p, q)`` for :func:`_merge_vertical`: does the edge run on between full-size
    points p and q? Yes when the gradient across the line (best of three neighboring lines)
    is ``ROOM.height.bridge_contrast`` times the gradient a few pixels to either side, in median.
    ``grads`` are the shrunk photo's (x, y) gradients, ``k`` its factor."""
    gx, gy = grads

    def bridge(p, q):
        p, q = to_small(p, k), to_small(q, k)
        on = np.median(_across(gx, gy, p, q, np.array([-1.0, 0.0, 1.0])).max(axis=0))
        beside = np.median(_across(gx, gy, p, q, np.array([-6.0, -5.0, 5.0, 6.0])))
        return on >= ROOM.height.bridge_contrast * max(beside, 1.0)

    return bridge


def _trace(grads: tuple[np.ndarray, np.ndarray], starts: np.ndarray, ends: np.ndarray, max_px: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """Follow each segment ``starts -> ends`` (points in the shrunk photo) beyond both ends.

    Detectors end a segment early where the edge fades (a baseboard, a light pool). Along
    the segment's line the gradient across it is compared with its median over the
    detected part; an end moves on while ``ROOM.height.trace_ratio`` of that holds, across
    gaps up to ``ROOM.height.trace_gap_px``, for at most ``max_px``. ``grads`` are the
    shrunk photo's (x, y) gradients. Returns new starts and ends.
    """
    settings = ROOM.height
    starts, ends = starts.copy(), ends.copy()
    lateral = np.array([-1.0, 0.0, 1.0])
    for i in range(len(starts)):
        p, q = starts[i], ends[i]
        length = np.linalg.norm(q - p)
        if length < 2:
            continue
        ref = np.median(_across(*grads, p, q, lateral).max(axis=0))
        if ref <= 0:
            continue
        u = (q - p) / length
        for end, sign in ((q, 1.0), (p, -1.0)):
            hits = _across(*grads, end, end + sign * max_px * u, lateral).max(axis=0)[1:] >= settings.trace_ratio * ref
            misses = np.cumsum(~hits) - np.maximum.accumulate(np.where(hits, np.cumsum(~hits), 0))  # current gap
            stop = np.flatnonzero(misses > settings.trace_gap_px)
            hits = hits[: stop[0]] if len(stop) else hits
            reach = np.flatnonzero(hits)[-1] + 1 if hits.any() else 0
            if sign > 0:
                ends[i] = q + reach * u
            else:
                starts[i] = p - reach * u
    return starts, ends


def _merge_edges(vseg: np.ndarray, K: np.ndarray, pose: np.ndarray, side: int, bridge=None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Vertical segments merged into edges: lower ends (n, 2) and upper ends (n, 2), both on
    the edge's line through the vanishing point."""
    settings = ROOM.height
    up = pose[:3, 2]
    vp = K @ up
    bases, tops = [], []
    for g in _merge_vertical(vseg, vp, 2 * CAMERA.lines.vp_distance_fraction * side, settings.merge_gap_fraction * side,
                             bridge, settings.bridge_gap_fraction * side):
        s = vseg[g]
        lengths = np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])
        c = np.sum((s[:, :2] + s[:, 2:]) / 2 * lengths[:, None], axis=0) / max(lengths.sum(), 1e-12)
        u = toward_vanishing_point(c[None], vp)[0]
        ends = np.vstack([s[:, :2], s[:, 2:]])
        ends = c + np.outer((ends - c) @ u, u)     # onto the line through c and the vanishing point
        e = _elevation(ends, K, up)
        bases.append(ends[np.argmin(e)])
        tops.append(ends[np.argmax(e)])
    return np.array(bases).reshape(-1, 2), np.array(tops).reshape(-1, 2)


def _snap_to_floor(bases: np.ndarray, tops: np.ndarray, floor_mask: np.ndarray, band_px: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Move each base along its edge to where the floor mask begins, within ``band_px`` (n,).

    Returns the new bases and whether a floor boundary was found there: going down the
    edge, the mask turns from mostly not-floor to mostly floor.
    """
    share = CAMERA.lines.floor_share
    snapped = bases.copy()
    found = np.zeros(len(bases), bool)
    for i in range(len(bases)):
        down = bases[i] - tops[i]
        down /= max(np.linalg.norm(down), 1e-12)
        reach = int(np.ceil(band_px[i]))
        run = max(3, reach // 4)
        ks = np.arange(-reach - run, reach + run + 1)
        floor = sample_image(floor_mask, bases[i] + ks[:, None] * down).astype(float)
        csum = np.concatenate([[0.0], np.cumsum(floor)])
        j = np.arange(run, len(ks) - run)                        # candidate boundary positions
        below = (csum[j + run] - csum[j]) / run                  # mean over [k, k + run)
        above = (csum[j] - csum[j - run]) / run                  # mean over [k - run, k)
        ok = (below >= share) & (above <= 1 - share)
        if ok.any():
            k = ks[j[ok]][np.argmin(np.abs(ks[j[ok]]))]
            snapped[i] = bases[i] + k * down
            found[i] = True
    return snapped, found


def _drop_to_floor(tops: np.ndarray, K: np.ndarray, pose: np.ndarray, floor_mask: np.ndarray, step: int = 1
                   ) -> np.ndarray:
    """For each point (k, 2), where the vertical through it meets the floor in the mask.

    Walks down the point's vertical (its line away from the vanishing point) to the first
    pixel that starts a run of ``ROOM.height.floor_run_px`` floor pixels, after at least
    one that is not floor; in strides of ``step`` pixels, then pixel by pixel over the
    last stride. Returns (k, 2) pixels, NaN where the walk leaves the frame first.
    """
    floor_run_px = ROOM.height.floor_run_px
    h, w = floor_mask.shape
    b = K @ pose[:3, 2]
    down = -(b[:2] - tops * b[2])
    down /= np.linalg.norm(down, axis=1, keepdims=True)
    run = max(2, floor_run_px // step)
    first = _first_floor(tops, down, floor_mask, np.arange(0.0, float(np.hypot(h, w)), step), run)
    out = np.full((len(tops), 2), np.nan)
    found = np.isfinite(first)
    if step > 1 and found.any():
        starts = tops[found] + (first[found, None] - step) * down[found]
        refined = _first_floor(starts, down[found], floor_mask, np.arange(0.0, step + floor_run_px + 1.0),
                               floor_run_px, need_other=False)
        first[found] = np.where(np.isfinite(refined), first[found] - step + refined, first[found])
    out[found] = tops[found] + first[found, None] * down[found]
    return out


def _first_floor(starts: np.ndarray, down: np.ndarray, floor_mask: np.ndarray, ks: np.ndarray, run: int,
                 need_other: bool = True) -> np.ndarray:
    """Distance along ``down`` (from ``ks``) to the first run of ``run`` floor samples, after a
    sample that is not floor when ``need_other``; NaN where there is none. (n,)"""
    h, w = floor_mask.shape
    pts = starts[:, None, :] + ks[None, :, None] * down[:, None, :]
    inside = (pts[..., 0] >= 0) & (pts[..., 0] <= w - 1) & (pts[..., 1] >= 0) & (pts[..., 1] <= h - 1)
    floor = sample_image(floor_mask, pts) & inside
    n = len(ks) - run + 1
    if n <= 0:
        return np.full(len(starts), np.nan)
    csum = np.concatenate([np.zeros((len(starts), 1)), np.cumsum(floor, axis=1)], axis=1)
    hit = (csum[:, run:run + n] - csum[:, :n]) == run
    if need_other:
        seen_other = np.maximum.accumulate(~floor[:, :n] & inside[:, :n], axis=1)
        hit &= np.concatenate([np.zeros((len(starts), 1), bool), seen_other[:, :-1]], axis=1)
    out = np.full(len(starts), np.nan)
    rows = np.flatnonzero(hit.any(axis=1))
    out[rows] = ks[np.argmax(hit[rows], axis=1)]
    return out


def _floor_points(pixels: np.ndarray, K: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Floor meters (k, 2) of undistorted pixels (k, 2) on the floor."""
    R, t = pose[:3, :3], pose[:3, 3]
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    f = np.column_stack([pixels, np.ones(len(pixels))]) @ np.linalg.inv(H).T
    return f[:, :2] / f[:, 2:3]


def _wall_line(feet: np.ndarray, tol_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A line through floor points (n, 2), the worst dropped until all lie within ``tol_m``:
    its center, unit normal and which points it keeps."""
    keep = np.ones(len(feet), bool)
    while True:
        center = feet[keep].mean(axis=0)
        normal = np.linalg.svd(feet[keep] - center)[2][1]
        off = np.abs((feet - center) @ normal)
        worst = np.argmax(np.where(keep, off, -1.0))
        if off[worst] <= tol_m or keep.sum() <= 3:
            return center, normal, keep & (off <= tol_m)
        keep[worst] = False


def _ceiling_candidates(lines: np.ndarray, K: np.ndarray, pose: np.ndarray, floor_mask: np.ndarray,
                        size_px: tuple[int, int], k: int = 1, grads=None
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Wall--ceiling junctions: long lines above the horizon measured against the floor mask.

    Points along each line are dropped vertically to where the floor mask begins (walked in
    strides of ``k`` pixels); for the top of a wall their heights agree (within
    ``ROOM.height.cluster_width``, at least half of them) and their feet lie on one floor line, the
    wall's. The line must also span its wall: where the wall goes on beyond an end of the
    line (feet beyond it continue along the same floor line) while the line does not (with
    ``grads``, the shrunk photo's gradients: no edge along its extension), it is a window
    or door head or a ceiling fixture, not the junction. Returns, per accepted line, a
    representative base and top (the point of median height), the height and the
    agreeing length, pixels.
    """
    settings = ROOM.height
    side = max(size_px)
    up = pose[:3, 2]
    above = lines[(_elevation(lines[:, :2], K, up) > 0) & (_elevation(lines[:, 2:], K, up) > 0)]
    out_b, out_t, out_h, out_len = [], [], [], []
    for line in above:
        length = np.hypot(line[2] - line[0], line[3] - line[1])
        m = int(np.clip(length / (0.02 * side), 4, 16))
        f = (np.arange(m) + 0.5) / m
        tops = line[:2] + f[:, None] * (line[2:] - line[:2])
        bases = _drop_to_floor(tops, K, pose, floor_mask, k)
        heights = np.full(m, np.nan)
        ok = np.all(np.isfinite(bases), axis=1)
        if ok.sum() < 3:
            continue
        heights[ok] = segment_heights(bases[ok], tops[ok], K, pose)[0]
        good = np.isfinite(heights)
        if good.sum() < 3:
            continue
        med = np.median(heights[good])
        agree = good & (np.abs(np.log(np.where(good, heights, 1.0) / med)) <= settings.cluster_width)
        if agree.sum() < max(3, 0.5 * m):
            continue
        # The wall's foot: a line through the agreeing feet, in floor meters.
        feet = _floor_points(bases[agree], K, pose)
        tol = settings.wall_straightness * np.linalg.norm(feet - _camera_xy(pose), axis=1).mean()
        center, normal, on_wall = _wall_line(feet, tol)
        agree[np.flatnonzero(agree)[~on_wall]] = False
        if agree.sum() < max(3, 0.5 * m):
            continue
        if _stops_mid_wall(line, K, pose, floor_mask, size_px, k, grads, center, normal, tol):
            continue
        i = np.flatnonzero(agree)[np.argsort(heights[agree])[agree.sum() // 2]]
        out_b.append(bases[i])
        out_t.append(tops[i])
        out_h.append(heights[i])
        out_len.append(length * agree.sum() / m)
    return (np.array(out_b).reshape(-1, 2), np.array(out_t).reshape(-1, 2), np.array(out_h),
            np.array(out_len))


def _stops_mid_wall(line, K, pose, floor_mask, size_px, k, grads, center, normal, tol) -> bool:
    """Does the wall under ``line`` go on beyond one of its ends while the line does not?"""
    settings = ROOM.height
    width, height = size_px
    length = np.hypot(line[2] - line[0], line[3] - line[1])
    direction = (line[2:] - line[:2]) / length
    ref = None
    if grads is not None:
        ref = np.median(_across(*grads, to_small(line[:2], k), to_small(line[2:], k), np.array([-1.0, 0.0, 1.0]))
                        .max(axis=0))
    for end, sign in ((line[:2], -1.0), (line[2:], 1.0)):
        beyond = end + sign * np.outer(settings.span_probe_fraction * max(size_px), direction)
        inside = (beyond[:, 0] >= 0) & (beyond[:, 0] <= width - 1) & (beyond[:, 1] >= 0) & \
            (beyond[:, 1] <= height - 1)
        if inside.sum() < 2:
            continue
        dropped = _drop_to_floor(beyond[inside], K, pose, floor_mask, k)
        hit = np.all(np.isfinite(dropped), axis=1)
        if hit.sum() < 2:
            continue
        off = np.abs((_floor_points(dropped[hit], K, pose) - center) @ normal)
        # Things against the wall (radiators, baseboards) stand a little in front of it.
        if np.sum(off <= max(tol, settings.against_wall_m)) < 2:
            continue
        if ref is not None and ref > 0:
            far = beyond[inside][hit][-1]
            edge = _across(*grads, to_small(end, k), to_small(far, k), np.array([-1.0, 0.0, 1.0])).max(axis=0)
            if np.mean(edge >= settings.trace_ratio * ref) >= 0.6:
                continue                # the line itself goes on: a piece of a longer junction
        return True
    return False


def _camera_xy(pose: np.ndarray) -> np.ndarray:
    """The camera's position on the floor plane, floor meters (2,)."""
    return (-pose[:3, :3].T @ pose[:3, 3])[:2]


def _crossed(starts: np.ndarray, ends: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """(k,) bool: does any of ``lines`` (m, 4) cross the segment ``starts[i] -> ends[i]``?"""
    if len(lines) == 0 or len(starts) == 0:
        return np.zeros(len(starts), bool)
    p, r = starts, ends - starts                               # (k, 2)
    q, sv = lines[:, :2], lines[:, 2:] - lines[:, :2]          # (m, 2)

    def cross(a, c):
        return a[..., 0] * c[..., 1] - a[..., 1] * c[..., 0]

    denom = cross(r[:, None, :], sv[None, :, :])               # (k, m)
    qp = q[None, :, :] - p[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_seg = cross(qp, sv[None]) / denom
        u_line = cross(qp, r[:, None, :]) / denom
    hits = (np.abs(denom) > 1e-9) & (t_seg > 0) & (t_seg <= 1) & (u_line >= 0) & (u_line <= 1)
    return np.any(hits, axis=1)


def _blocked_above(tops: np.ndarray, K: np.ndarray, pose: np.ndarray, lines: np.ndarray, size_px: tuple[int, int],
                   clear_px: float) -> np.ndarray:
    """(k,) bool: does a line cross the vertical above each top, within the frame?

    The wall--ceiling junction is the highest horizontal line of its wall: above it there
    is only ceiling. A window or door head has wall above it, and where the ceiling is in
    view, the junction line crosses that wall's verticals higher up. Lines passing within
    ``clear_px`` of the top itself (the junction the top ends at) do not count.
    """
    width, height = size_px
    if len(lines) == 0 or len(tops) == 0:
        return np.zeros(len(tops), bool)
    b = K @ pose[:3, 2]
    up = b[:2] - tops * b[2]
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    # Distance to the frame along ``up``.
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(up[:, 0] > 0, (width - 1 - tops[:, 0]) / up[:, 0], -tops[:, 0] / up[:, 0])
        ty = np.where(up[:, 1] > 0, (height - 1 - tops[:, 1]) / up[:, 1], -tops[:, 1] / up[:, 1])
    reach = np.nan_to_num(np.minimum(np.where(np.isfinite(tx), tx, np.inf), np.where(np.isfinite(ty), ty, np.inf)),
                          posinf=0.0)
    starts = tops + clear_px * up
    ends = tops + np.maximum(reach, clear_px)[:, None] * up
    # (k, m): the top's own junction does not count.
    far = point_segment_distances(tops, lines[:, :2], lines[:, 2:]) > clear_px
    return np.array([_crossed(starts[i:i + 1], ends[i:i + 1], lines[far[i]])[0] for i in range(len(tops))])


def _floor_like_below(color: np.ndarray, k: int, shape: tuple[int, int], bases: np.ndarray, tops: np.ndarray,
                      K: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Without a floor mask: does the image just below each base look like the floor around
    the board? Read ``ROOM.height.floor_color_below`` of the edge's length below it (past a baseboard).
    No floor reference in view: no verdict (all True). (n,) bool."""
    down = bases - tops
    length = np.linalg.norm(down, axis=1, keepdims=True)
    down /= np.maximum(length, 1e-12)
    ks = np.linspace(*ROOM.height.floor_color_below, 12)
    pts = bases[:, None, :] + (ks[None, :, None] * length[:, :, None]) * down[:, None, :]
    share = floor_share(color, k, shape, pts, K, pose)
    return np.ones(len(bases), bool) if share is None else share >= CAMERA.lines.floor_share


def _edge_candidates(seg: np.ndarray, vertical: np.ndarray, K: np.ndarray, pose: np.ndarray,
                     size_px: tuple[int, int], floor_mask: np.ndarray | None, small: np.ndarray | None,
                     color: np.ndarray | None, grads) -> dict:
    """Vertical edges: merged, followed in the image, their feet checked against the floor."""
    settings = ROOM.height
    width, height = size_px
    side = max(size_px)
    k = shrink_factor((height, width))
    bridge = None if grads is None else _bridge_test(grads, k)
    bases, tops = _merge_edges(seg[vertical], K, pose, side, bridge)
    if grads is not None and len(bases):
        # Follow each edge beyond its detected ends, then merge edges that now meet.
        b, t = _trace(grads, to_small(bases, k), to_small(tops, k), settings.trace_fraction * max(small.shape))
        bases, tops = _merge_edges(np.hstack([to_full(b, k), to_full(t, k)]), K, pose, side)
    on_floor = np.ones(len(bases), bool)
    if floor_mask is not None and len(bases):
        band = np.maximum(settings.floor_band_fraction * side,
                          settings.floor_band_edge * np.linalg.norm(tops - bases, axis=1))
        bases, on_floor = _snap_to_floor(bases, tops, floor_mask, band)
    elif color is not None and len(bases):
        on_floor = _floor_like_below(color, k, (height, width), bases, tops, K, pose)
    length = np.linalg.norm(tops - bases, axis=1)
    return dict(bases=bases, tops=tops, length=length, weight_length=length, on_floor=on_floor,
                kind=np.zeros(len(bases), int))


def _candidates(seg: np.ndarray, K: np.ndarray, pose: np.ndarray, size_px: tuple[int, int],
                floor_mask: np.ndarray | None, small: np.ndarray | None = None,
                color: np.ndarray | None = None) -> dict:
    """Every candidate measurement and the evidence about it, as arrays of one length:
    vertical edges, then (with a floor mask) wall--ceiling lines."""
    settings = ROOM.height
    width, height = size_px
    side = max(size_px)
    k = shrink_factor((height, width))
    grads = None if small is None else _gradients(small)
    vertical = is_vertical(seg, K, pose, side)
    c = _edge_candidates(seg, vertical, K, pose, size_px, floor_mask, small, color, grads)

    # Long non-vertical lines: where tops end (the ceiling line), what blocks them, and
    # with a floor mask, candidates of their own.
    lines = seg[~vertical]
    lines = lines[np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
                  >= settings.min_junction_fraction * side]
    if grads is not None and len(lines):
        b, t = _trace(grads, to_small(lines[:, 2:], k), to_small(lines[:, :2], k),
                      settings.trace_fraction * max(small.shape))
        lines = np.hstack([to_full(t, k), to_full(b, k)])
    if floor_mask is not None and len(lines):
        cb, ct, _, clen = _ceiling_candidates(lines, K, pose, floor_mask, size_px, k, grads)
        c = {key: np.concatenate([c[key], extra]) for key, extra in (
            ("bases", cb), ("tops", ct), ("length", np.linalg.norm(ct - cb, axis=1)), ("weight_length", clen),
            ("on_floor", np.ones(len(cb), bool)), ("kind", np.ones(len(cb), int)))}

    bases, tops = c["bases"], c["tops"]
    c["heights"], c["feet"] = segment_heights(bases, tops, K, pose)
    hz = -(np.linalg.inv(K).T @ pose[:3, 2])
    hz /= np.hypot(hz[0], hz[1])
    c["below"] = np.column_stack([bases, np.ones(len(bases))]) @ hz       # px on the floor side of the horizon
    border = settings.border_fraction * side
    for key, p in (("base_in", bases), ("top_in", tops)):
        c[key] = (p[:, 0] >= border) & (p[:, 0] <= width - 1 - border) & (p[:, 1] >= border) & \
            (p[:, 1] <= height - 1 - border)
    r = settings.junction_fraction * side
    olen = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    if len(lines) and len(bases):
        capped = np.max(np.where(point_segment_distances(tops, lines[:, :2], lines[:, 2:]) <= r, olen, 0), axis=1) > 0
    else:
        capped = np.zeros(len(bases), bool)
    c["capped"] = capped | (c["kind"] == 1)          # a long line meets the top
    c["blocked"] = _blocked_above(tops, K, pose, lines, size_px, r)
    return c


KINDS = np.array(["edge", "ceiling"])       # HeightResult.kinds: a vertical edge, a wall--ceiling junction


def _result(c: dict | None, height_m: float, confidence: float, fallback: bool, reason: str,
            weights: np.ndarray | None = None, inliers: np.ndarray | None = None, given: bool = False,
            at_least_m: float | None = None) -> HeightResult:
    if c is None:
        c = dict(bases=np.zeros((0, 2)), tops=np.zeros((0, 2)), heights=np.zeros(0), feet=np.zeros((0, 2)),
                 kind=np.zeros(0, int))
    n = len(c["bases"])
    arrays = [np.array(a, copy=True) for a in (c["bases"], c["tops"], c["heights"], c["feet"], KINDS[c["kind"]],
                                               np.zeros(n) if weights is None else weights,
                                               np.zeros(n, bool) if inliers is None else inliers)]
    for a in arrays:
        a.flags.writeable = False
    return HeightResult(float(height_m), float(confidence), fallback, reason, *arrays, given=given,
                        at_least_m=at_least_m)


def _fallback(reason: str, c: dict | None = None, given_m: float | None = None,
              at_least_m: float | None = None) -> HeightResult:
    """The height not measured: the user's ``given_m``, else ``ROOM.height.fallback_m`` raised
    to ``at_least_m`` (the top of something standing on the floor in view: walls reach higher)."""
    if at_least_m is not None:
        reason += f"; the tallest vertical edge standing on the floor in view (a door's or window's frame) " \
                  f"reaches {at_least_m:.2f} m, so the walls are at least that high"
    if given_m is not None:
        return _result(c, given_m, 0.0, True, f"{reason}: using the given {given_m:g} m", given=True,
                       at_least_m=at_least_m)
    fallback_m = max(ROOM.height.fallback_m, at_least_m or 0.0)
    return _result(c, fallback_m, 0.0, True, f"{reason}: assuming {fallback_m:g} m", at_least_m=at_least_m)


def _lower_bound_m(c: dict, side: int) -> float | None:
    """The top of the tallest whole vertical edge that stands on the floor (a door's
    casing, a window's frame, a corner cut by the photo's top): the walls reach at least
    that high. None when there is none of ``ROOM.height.bound_min_m`` or more."""
    settings = ROOM.height
    with np.errstate(invalid="ignore"):
        whole = (c["kind"] == 0) & c["on_floor"] & c["base_in"] & c["top_in"] & np.isfinite(c["heights"]) \
            & (c["heights"] >= settings.bound_min_m) & (c["heights"] <= settings.max_m) \
            & (c["below"] >= settings.horizon_margin_fraction * side)
    return float(c["heights"][whole].max()) if whole.any() else None


def _combine(c: dict, valid: np.ndarray, side: int, verified: bool) -> HeightResult:
    """The weighted median of the highest well-supported cluster of heights.

    Weights: image length over the longer side, doubled when a long line meets the top.
    Clusters: heights within ``ROOM.height.cluster_width`` of each candidate; a cluster is
    well supported with at least half the weight of the best one, and the highest of those
    wins (door frames, window heads and edges cut short all end below the ceiling).
    Confidence: the support ``1 - exp(-W / ROOM.height.confidence_weight)`` of the
    cluster's weight W, times its share of all the weight, times
    ``ROOM.height.unverified_confidence`` when no floor mask verified the feet.
    """
    settings = ROOM.height
    weights = np.where(valid, c["weight_length"] / side * (1.0 + c["capped"]), 0.0)
    idx = np.flatnonzero(valid)
    logh = np.log(np.where(valid, c["heights"], 1.0))
    near = np.abs(logh[idx, None] - logh[None, idx]) <= settings.cluster_width
    support = near.astype(float) @ weights[idx]
    strong = support >= 0.5 * support.max()
    pick = idx[strong][np.argmax(c["heights"][idx[strong]])]
    inliers = np.zeros(len(valid), bool)
    inliers[idx] = np.abs(logh[idx] - logh[pick]) <= settings.cluster_width
    h, w = c["heights"][inliers], weights[inliers]
    order = np.argsort(h)
    cum = np.cumsum(w[order])
    estimate = float(h[order][np.searchsorted(cum, cum[-1] / 2)])
    confidence = (1 - np.exp(-cum[-1] / settings.confidence_weight)) * cum[-1] / weights.sum()
    if not verified:
        confidence *= settings.unverified_confidence
    edges = int(np.sum(inliers & (c["kind"] == 0)))
    lines = int(np.sum(inliers & (c["kind"] == 1)))
    what = " and ".join(part for part in (f"{edges} vertical edge{'s' * (edges != 1)}" if edges else "",
                                          f"{lines} wall-ceiling line{'s' * (lines != 1)}" if lines else "") if part)
    others = len(idx) - edges - lines
    reason = f"{what} agree{'s' * (edges + lines == 1)} on {estimate:.2f} m"
    if others:
        reason += f"; {others} other candidate{'s' * (others != 1)} lower or weaker"
    if not verified:
        reason += "; no floor mask, so feet were checked by color only (a window frame can pass for a wall's edge)"
    return _result(c, estimate, confidence, False, reason, weights, inliers)


def height_from_segments(segments_px: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray,
                         size_px: tuple[int, int], floor_mask: np.ndarray | None = None,
                         image: np.ndarray | None = None, given_m: float | None = None) -> HeightResult:
    """Wall height from line segments of a calibrated photo.

    Parameters
    ----------
    segments_px : (n, 4) float64
        Rows ``x1, y1, x2, y2``, undistorted full-resolution pixels (from
        :func:`detect_segments`, or built by hand). Not modified.
    K : (3, 3) float64
        Camera matrix, pixels.
    camera_from_floor : (4, 4) float64
        Floor frame (meters, z up) to camera frame (OpenCV axes).
    size_px : (width, height)
        The photo's size: ends near its border count as cut off.
    floor_mask : (height, width) bool, optional
        Floor pixels (the floor segmentation). Not modified. When given, an edge counts
        only if the mask turns from not-floor to floor near its lower end (and its foot
        moves there), and wall--ceiling lines become candidates too.
    image : (height, width) or (height, width, 3) uint8, optional
        The photo, without lens distortion. Not modified. When given, edges are followed
        beyond their detected ends, a wall--ceiling line that stops mid-wall is told from a
        piece of a longer one, and without a mask the feet are checked by color (RGB only).
    given_m : float, optional
        The height the user knows, taken when the segments do not show it (:func:`measure_height`).

    Returns
    -------
    HeightResult
    """
    seg = as_segments(segments_px)
    K, pose = as_camera(K, camera_from_floor)
    width, height = (int(v) for v in size_px)
    if width < 16 or height < 16:
        raise ValueError(f"size_px {size_px}: expected (width, height) of a photo")
    floor_mask = _as_mask(floor_mask, (width, height))
    small = color = None
    if image is not None:
        if np.asarray(image).shape[:2] != (height, width):
            raise ValueError(f"image of shape {np.asarray(image).shape}: expected {(height, width)} like size_px")
        small, color, _ = prepare_lines(image)
    return _measure(seg, K, pose, (width, height), floor_mask, small, color, given_m)


def _measure(seg, K, pose, size_px, floor_mask, small, color=None, given_m=None) -> HeightResult:
    """Candidates, the checks each must pass, and the estimate (or the fallback)."""
    settings = ROOM.height
    width, height = size_px
    side = max(width, height)
    if len(seg) == 0:
        return _fallback("no line segments found", given_m=given_m)
    c = _candidates(seg, K, pose, (width, height), floor_mask, small, color)
    if len(c["bases"]) == 0:
        return _fallback("no vertical edges found", c, given_m)
    with np.errstate(invalid="ignore"):
        plausible = (c["heights"] >= settings.min_m) & (c["heights"] <= settings.max_m)
    valid = (plausible & c["on_floor"] & ~c["blocked"] & c["base_in"] & c["top_in"]
             & (c["below"] >= settings.horizon_margin_fraction * side)
             & (c["length"] >= settings.min_edge_fraction * min(width, height)))
    if not valid.any():
        return _fallback(f"none of {len(c['bases'])} candidate edges stands on the floor and reaches the ceiling "
                         f"in view at a plausible height ({settings.min_m}-{settings.max_m} m); the ceiling may be "
                         "out of the photo", c, given_m, _lower_bound_m(c, side) if floor_mask is not None else None)
    return _combine(c, valid, side, verified=floor_mask is not None)


def measure_height(image: np.ndarray, calibration: Calibration, floor_mask: np.ndarray | None = None,
                   given_m: float | None = None) -> HeightResult:
    """Wall height of the room in a calibrated photo, from its vertical edges.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        The photo (gray or RGB) the calibration was made from. Not modified.
    calibration : Calibration
        From :func:`augment.camera.calibrate.calibrate_photo`; ``size_px`` must match the image.
    floor_mask : (h, w) bool, optional
        The floor segmentation. Not modified. When given, only edges whose foot lies where
        the floor begins count (window frames, which end at their sill, do not), and
        wall--ceiling lines are measured too. Without it the feet are checked by color
        only and the confidence is at most ``ROOM.height.unverified_confidence``.
    given_m : float, optional
        The height the user knows, taken when the photo does not show it (the ceiling out
        of view); a height the photo shows is measured all the same.

    Returns
    -------
    HeightResult
        ``height_m`` with a confidence; or, when nothing trustworthy is in view,
        ``fallback=True``, the reason, and ``given_m``, else ``ROOM.height.fallback_m``
        raised to the top of the tallest vertical edge standing on the floor (with a mask).

    Notes
    -----
    Lines are found in the photo as taken and their ends undistorted; with a lens
    distortion the steps that read the photo along a line (following edges, the color
    check) are skipped, since its lines are not straight there.
    """
    gray = to_gray(image)
    width, height = calibration.size_px
    if gray.shape != (height, width):
        raise ValueError(f"image of {gray.shape[1]}x{gray.shape[0]} px but the calibration is for "
                         f"{width}x{height} px")
    floor_mask = _as_mask(floor_mask, (width, height))
    small, color, k = prepare_lines(image, gray)
    seg = to_full(detect_raw(small, "fld"), k)
    intr = calibration.intrinsics
    K, pose = as_camera(intr.K, calibration.camera_from_floor)
    if np.any(intr.distortion):
        if len(seg):
            seg = cv2.undistortPoints(seg.reshape(-1, 1, 2), intr.K, intr.distortion, P=intr.K).reshape(-1, 4)
        small = color = None
    return _measure(seg, K, pose, (width, height), floor_mask, small, color, given_m)
