"""Floor-plane geometry shared by the solver, the metrics and the plots.

Conventions (used everywhere in :mod:`layout`):

* The floor frame is right-handed: x and y span the floor, z points up, meters.
* An item's ``yaw_rad`` is the direction its *front* faces: ``(cos yaw, sin yaw)``.
* Item sizes are ``(width, depth, height)``: depth runs along the facing direction,
  width across it. In the item's local frame +x is front, +y is left.
* Sides are numbered as in Weiss et al. (accessibility centers): 0 back, 1 left,
  2 front, 3 right.
* Polygons are ``(m, 2)`` arrays of vertices in meters, counter-clockwise, not closed
  (the last vertex is not a copy of the first).
"""
from __future__ import annotations

import mapbox_earcut
import numpy as np

SIDE_NAMES = ("back", "left", "front", "right")
# Outward unit normal of each side in the item's local frame (x front, y left).
SIDE_NORMALS = np.array([[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0], [0.0, -1.0]])
# (along the facing, across it) of the footprint corners, in box_corners' order.
_CORNER_SIGNS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


def box_corners(center_m, yaw_rad, width_m, depth_m):
    """Corners of oriented footprint rectangles.

    Parameters
    ----------
    center_m : (n, 2) float64
        Footprint centers in meters.
    yaw_rad : (n,) float64
        Facing direction of each item.
    width_m, depth_m : (n,) float64
        Extent across and along the facing direction.

    Returns
    -------
    corners_m : (n, 4, 2) float64
        Counter-clockwise corners: back-right, front-right, front-left, back-left.
    """
    center_m = np.asarray(center_m, dtype=np.float64).reshape(-1, 2)
    yaw_rad = np.asarray(yaw_rad, dtype=np.float64).reshape(-1)
    along = _CORNER_SIGNS[:, 0] * (0.5 * np.asarray(depth_m, dtype=np.float64).reshape(-1, 1))
    across = _CORNER_SIGNS[:, 1] * (0.5 * np.asarray(width_m, dtype=np.float64).reshape(-1, 1))
    c, s = np.cos(yaw_rad)[:, None], np.sin(yaw_rad)[:, None]
    out = np.empty((len(yaw_rad), 4, 2))
    out[..., 0] = c * along - s * across + center_m[:, :1]
    out[..., 1] = s * along + c * across + center_m[:, 1:]
    return out


def access_box_corners(center_m, yaw_rad, width_m, depth_m, access_depth_m):
    """Corners of the accessibility boxes in front of each side of each item.

    Parameters
    ----------
    center_m : (n, 2) float64
    yaw_rad, width_m, depth_m : (n,) float64
    access_depth_m : (n, 4) float64
        Clearance depth in front of the back, left, front and right side; 0 = none.

    Returns
    -------
    corners_m : (n, 4, 4, 2) float64
        ``corners_m[i, k]`` is the rectangle of side ``k`` of item ``i`` (degenerate, of
        zero depth, where ``access_depth_m[i, k] == 0``).
    """
    center_m = np.asarray(center_m, dtype=np.float64).reshape(-1, 2)
    yaw_rad = np.asarray(yaw_rad, dtype=np.float64).reshape(-1)
    w = np.asarray(width_m, dtype=np.float64).reshape(-1)
    d = np.asarray(depth_m, dtype=np.float64).reshape(-1)
    a = np.asarray(access_depth_m, dtype=np.float64).reshape(-1, 4)
    c, s = np.cos(yaw_rad)[:, None], np.sin(yaw_rad)[:, None]
    nx, ny = SIDE_NORMALS[:, 0], SIDE_NORMALS[:, 1]
    # Along the normal each box spans from the face outwards by the access depth.
    half_along_normal = 0.5 * np.where(nx != 0, d[:, None], w[:, None])
    half_across = 0.5 * np.where(nx != 0, w[:, None], d[:, None])
    offset = half_along_normal + 0.5 * a
    lx, ly = nx * offset, ny * offset
    cx = center_m[:, :1] + c * lx - s * ly
    cy = center_m[:, 1:] + s * lx + c * ly
    # The box's local "depth" axis is the side normal.
    box_yaw = yaw_rad[:, None] + np.arctan2(ny, nx)
    return box_corners(np.stack([cx, cy], -1).reshape(-1, 2), box_yaw.ravel(), 2 * half_across.ravel(),
                       a.ravel()).reshape(len(w), 4, 4, 2)


def access_zones(size_m, access_depth_m):
    """(n, 3): center (x front, y left, in the item's frame) and radius of a circle
    around each item's access boxes, from the bounding box of the boxes it has; radius
    -1 for items without any. (The access pass rejects most pairs by this circle.)"""
    size = np.asarray(size_m, dtype=np.float64)
    a = np.asarray(access_depth_m, dtype=np.float64)
    hd, hw = 0.5 * size[:, 1], 0.5 * size[:, 0]
    back, left, front, right = (a[:, k] > 0.0 for k in range(4))
    # Behind and ahead span the width; left and right span the depth.
    x0 = np.where(back, -hd - a[:, 0], np.where(left | right, -hd, hd))
    x1 = np.where(front, hd + a[:, 2], np.where(left | right, hd, -hd))
    y0 = np.where(right, -hw - a[:, 3], np.where(back | front, -hw, hw))
    y1 = np.where(left, hw + a[:, 1], np.where(back | front, hw, -hw))
    zone = np.stack([0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * np.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2)], axis=1)
    zone[a.max(axis=1) <= 0.0] = [0.0, 0.0, -1.0]
    return zone


def polygon_area(polygon_m):
    """Signed area (m²) of a polygon: positive when counter-clockwise."""
    p = np.asarray(polygon_m, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def triangulate_polygon(polygon_m):
    """Triangles covering a simple polygon exactly.

    Parameters
    ----------
    polygon_m : (n, 2) array
        Vertices in either winding, not closed.

    Returns
    -------
    (k, 3) int64 array
        Vertex indices of each triangle, counter-clockwise; ``k = n - 2`` unless
        collinear or repeated vertices are skipped.
    """
    p = np.ascontiguousarray(polygon_m, dtype=np.float64)
    tris = mapbox_earcut.triangulate_float64(p, np.array([len(p)], dtype=np.uint32))
    tris = tris.reshape(-1, 3).astype(np.int64)
    a, b, c = p[tris[:, 0]], p[tris[:, 1]], p[tris[:, 2]]
    cw = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    tris[cw] = tris[cw][:, ::-1]
    return tris


def point_segment_distances(points, starts, ends):
    """(k, m) distances from points (k, 2) to the segments from ``starts`` (m, 2) to
    ``ends`` (m, 2), in the points' unit."""
    p = np.asarray(points, dtype=np.float64)
    a = np.asarray(starts, dtype=np.float64)
    ab = np.asarray(ends, dtype=np.float64) - a
    t = np.clip(np.einsum("kmi,mi->km", p[:, None, :] - a[None], ab) / np.maximum(np.sum(ab * ab, 1), 1e-12), 0, 1)
    return np.linalg.norm(p[:, None, :] - (a[None] + t[..., None] * ab[None]), axis=2)


def edge_distances(points, polygon_m):
    """(k, m) distances from points (k, 2) to each edge (k -> k + 1) of a polygon."""
    poly = np.asarray(polygon_m, dtype=np.float64)
    return point_segment_distances(points, poly, np.roll(poly, -1, axis=0))


def stepped_wall(polygon_m, point_m, width_m, depth_m, step_m=0.02):
    """The straight wall an outline draws in steps near ``point_m``: a line fit to the
    outline on both sides of its nearest point, grown until it spans ``width_m``.

    A floor found in a photo has a door's threshold or a skirting board's shadow as short
    steps along its wall; an opening wider than the step it is nearest still stands on
    that wall.

    Parameters
    ----------
    polygon_m : (m, 2) float
        Counter-clockwise outline, meters.
    point_m : (2,) float
        Near the opening's middle, meters.
    width_m : float
        The opening's width.
    depth_m : float
        How far the outline may stray from the line (either side) and still be that wall.
    step_m : float
        The outline is sampled this finely.

    Returns
    -------
    (2, 2) float or None
        The opening's two ends on the line, in the outline's direction (so that the floor
        is on their left), centred as near ``point_m`` as the run allows; None where the
        outline turns away (a corner) before it spans ``width_m``.
    """
    poly = np.asarray(polygon_m, dtype=np.float64)
    point = np.asarray(point_m, dtype=np.float64)
    ends = np.roll(poly, -1, axis=0)
    lengths = np.linalg.norm(ends - poly, axis=1)
    starts_s = np.concatenate([[0.0], np.cumsum(lengths)])
    perimeter = starts_s[-1]
    s = np.arange(0.0, perimeter, step_m)
    k = np.minimum(np.searchsorted(starts_s, s, side="right") - 1, len(poly) - 1)
    t = (s - starts_s[k]) / np.maximum(lengths[k], 1e-12)
    samples = poly[k] + t[:, None] * (ends[k] - poly[k])
    s0 = s[int(np.argmin(np.linalg.norm(samples - point, axis=1)))]
    along = (s - s0 + perimeter / 2) % perimeter - perimeter / 2  # signed, round the outline

    def fit(behind, ahead):
        """The line through the outline from ``behind`` to ``ahead`` of the nearest point,
        and how far it spans; None where the outline strays from it."""
        near = (along >= -behind) & (along <= ahead)
        pts = samples[near][np.argsort(along[near])]
        centre = pts.mean(axis=0)
        u = np.linalg.svd(pts - centre, full_matrices=False)[2][0]
        u = u if np.dot(u, pts[-1] - pts[0]) >= 0 else -u
        if np.abs((pts - centre) @ np.array([-u[1], u[0]])).max() > depth_m:
            return None
        proj = (pts - centre) @ u
        return centre, u, proj.min(), proj.max()

    # Grown a tenth of the width at a time on each side, as long as that side stays straight.
    reach, grow, growing = [0.25 * width_m] * 2, 0.1 * width_m, [True, True]
    line = fit(*reach)
    while line is not None and line[3] - line[2] < width_m:
        for side in (0, 1):
            if growing[side]:
                trial = list(reach)
                trial[side] += grow
                bigger = fit(*trial) if sum(trial) < perimeter else None
                growing[side] = bigger is not None
                if bigger is not None:
                    reach, line = trial, bigger
                else:  # a corner: what it let in of the next wall (depth_m at most) goes again
                    reach[side] = max(reach[side] - depth_m, 0.25 * width_m)
                    line = fit(*reach)
        if not any(growing):
            return None
    if line is None:
        return None
    centre, u, lo, hi = line
    middle = np.clip(np.dot(point - centre, u), lo + 0.5 * width_m, hi - 0.5 * width_m)
    foot = centre + middle * u
    return np.stack([foot - 0.5 * width_m * u, foot + 0.5 * width_m * u])


def polygon_centroid(polygon_m):
    """Area centroid (2,) of a simple polygon in meters."""
    p = np.asarray(polygon_m, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = 0.5 * cross.sum()
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * a)


def segments_intersect(p1, p2, q1, q2) -> bool:
    """Whether closed segments p1p2 and q1q2 touch or cross."""

    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return 0 if abs(v) < 1e-12 else (1 if v > 0 else -1)

    def on_segment(a, b, c):
        return min(a[0], b[0]) - 1e-12 <= c[0] <= max(a[0], b[0]) + 1e-12 and min(
            a[1], b[1]
        ) - 1e-12 <= c[1] <= max(a[1], b[1]) + 1e-12

    o1, o2 = orient(p1, p2, q1), orient(p1, p2, q2)
    o3, o4 = orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 != o2 and o3 != o4:
        return True
    return (
        (o1 == 0 and on_segment(p1, p2, q1))
        or (o2 == 0 and on_segment(p1, p2, q2))
        or (o3 == 0 and on_segment(q1, q2, p1))
        or (o4 == 0 and on_segment(q1, q2, p2))
    )


def self_intersection(polygon_m):
    """First pair of non-adjacent edges ``(a, b)``, ``a < b``, that touch, or ``None`` if
    the polygon is simple.

    Edge k runs from corner k to k + 1. Only edges that share a cell of a grid about as
    fine as the edges are tested, all at once: near-linear in the corners (a 10,000-corner
    outline in a fraction of a second), with the answer of testing every pair in order
    (:func:`segments_intersect`, the same tolerances).
    """
    p = np.asarray(polygon_m, dtype=np.float64)
    m = len(p)
    if m < 4:
        return None
    start, end = p, np.roll(p, -1, axis=0)
    eps = 1e-9
    lo, hi = np.minimum(start, end) - eps, np.maximum(start, end) + eps
    origin = lo.min(axis=0)
    extent = float((hi.max(axis=0) - origin).max())
    cell = max(extent / max(1.0, np.sqrt(m)), float(np.median(np.linalg.norm(end - start, axis=1))), 1e-6)
    first = np.floor((lo - origin) / cell).astype(np.int64)
    last = np.floor((hi - origin) / cell).astype(np.int64)
    counts = (last - first + 1).prod(axis=1)
    if counts.sum() > 64 * m + 4096:  # a few edges long across a fine grid: a coarser one
        return self_intersection_coarse(p, start, end, lo, hi)
    edge = np.repeat(np.arange(m), counts)
    offset = np.arange(len(edge)) - np.repeat(np.cumsum(counts) - counts, counts)
    width = last[:, 0] - first[:, 0] + 1
    cx = first[edge, 0] + offset % width[edge]
    cy = first[edge, 1] + offset // width[edge]
    key = cx * (int(last[:, 1].max()) + 2) + cy
    order = np.lexsort((edge, key))
    key, edge = key[order], edge[order]
    bounds = np.flatnonzero(np.diff(key)) + 1
    groups = np.split(edge, bounds)
    pairs = [np.stack(np.triu_indices(len(g), 1)) for g in groups if len(g) > 1]
    if not pairs:
        return None
    a = np.concatenate([g[t[0]] for g, t in zip((g for g in groups if len(g) > 1), pairs)])
    b = np.concatenate([g[t[1]] for g, t in zip((g for g in groups if len(g) > 1), pairs)])
    a, b = np.minimum(a, b), np.maximum(a, b)
    return _first_touching(start, end, a, b, m)


def self_intersection_coarse(p, start, end, lo, hi):
    """:func:`self_intersection` for outlines whose edge lengths differ by orders of
    magnitude: the pairs whose bounding boxes overlap, by a sweep along x."""
    m = len(p)
    order = np.argsort(lo[:, 0], kind="stable")
    reach = np.searchsorted(lo[order, 0], hi[order, 0], side="right")
    a = np.repeat(order, reach - np.arange(m) - 1)
    b = order[np.concatenate([np.arange(k + 1, r) for k, r in enumerate(reach)])] if m else np.zeros(0, int)
    overlap = (lo[a, 1] <= hi[b, 1]) & (lo[b, 1] <= hi[a, 1])
    a, b = np.minimum(a, b)[overlap], np.maximum(a, b)[overlap]
    return _first_touching(start, end, a, b, m)


def _first_touching(start, end, a, b, m):
    """The first pair in (a, b) order of the candidates that touch and are not adjacent."""
    pair = np.unique(a * m + b)
    a, b = pair // m, pair % m
    keep = (b != a + 1) & ~((a == 0) & (b == m - 1))
    a, b = a[keep], b[keep]
    if not len(a):
        return None
    hit = _segments_touch(start[a], end[a], start[b], end[b])
    if not hit.any():
        return None
    k = int(np.flatnonzero(hit)[0])  # pairs are sorted by a * m + b: the first is the smallest
    return int(a[k]), int(b[k])


def _segments_touch(p1, p2, q1, q2) -> np.ndarray:
    """:func:`segments_intersect` for arrays of segments (k, 2) each."""
    def orient(u, v, w):
        cross = (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])
        return np.where(np.abs(cross) < 1e-12, 0, np.sign(cross))

    def on_segment(u, v, w):
        return ((np.minimum(u[:, 0], v[:, 0]) - 1e-12 <= w[:, 0]) & (w[:, 0] <= np.maximum(u[:, 0], v[:, 0]) + 1e-12)
                & (np.minimum(u[:, 1], v[:, 1]) - 1e-12 <= w[:, 1]) & (w[:, 1] <= np.maximum(u[:, 1], v[:, 1]) + 1e-12))

    o1, o2, o3, o4 = orient(p1, p2, q1), orient(p1, p2, q2), orient(q1, q2, p1), orient(q1, q2, p2)
    return (((o1 != o2) & (o3 != o4)) | ((o1 == 0) & on_segment(p1, p2, q1)) | ((o2 == 0) & on_segment(p1, p2, q2))
            | ((o3 == 0) & on_segment(q1, q2, p1)) | ((o4 == 0) & on_segment(q1, q2, p2)))
