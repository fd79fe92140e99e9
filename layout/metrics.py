"""Exact quality metrics of a furniture layout: overlaps, containment, clearances, paths.

All functions follow the conventions of :mod:`layout.geometry` (floor frame in meters,
polygons ``(m, 2)`` counter-clockwise and not closed, footprints ``(n, 4, 2)`` as
returned by :func:`layout.geometry.box_corners`). Inputs are never modified.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numba
import numpy as np

from .geometry import access_box_corners, box_corners

# Vertical intervals must overlap by more than this to count as a 3-D collision, so
# that an item standing exactly on top of another does not collide with it.
_Z_OVERLAP_TOL_M = 1e-6


def _as_polygon(polygon_m, name, min_vertices=3):
    p = np.asarray(polygon_m, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < min_vertices:
        raise ValueError(f"{name} must have shape (m, 2) with m >= {min_vertices}, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} must be finite")
    return p


def _as_boxes(corners_m, name="corners_m"):
    c = np.asarray(corners_m, dtype=np.float64)
    if c.ndim != 3 or c.shape[1:] != (4, 2):
        raise ValueError(f"{name} must have shape (n, 4, 2), got {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError(f"{name} must be finite")
    return c


def _as_flags(flags, n, name):
    f = np.asarray(flags)
    if f.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {f.shape}")
    return f.astype(bool)


def _signed_areas(poly):
    """Shoelace signed areas (P,) of polygons (P, M, 2)."""
    x, y = poly[..., 0], poly[..., 1]
    xn, yn = np.roll(x, -1, axis=1), np.roll(y, -1, axis=1)
    return 0.5 * (x * yn - xn * y).sum(axis=1)


@numba.njit(cache=True)
def _clipped_areas(subject, clip):
    """Areas (P,) of ``subject[p] ∩ clip[p]``: Sutherland–Hodgman by each edge of the
    convex ``clip[p]`` (either winding), then the shoelace. A non-convex subject may
    leave zero-area bridge edges, which keep the area exact."""
    n_pairs, m = subject.shape[0], subject.shape[1]
    k = clip.shape[1]
    areas = np.zeros(n_pairs)
    for p in range(n_pairs):
        c = clip[p]
        turn = 0.0
        for a in range(k):
            b = (a + 1) % k
            turn += c[a, 0] * c[b, 1] - c[b, 0] * c[a, 1]
        sign = 1.0 if turn >= 0.0 else -1.0  # inside: left of a counter-clockwise edge
        poly = subject[p].copy()
        count = m
        for a in range(k):
            if count == 0:
                break
            ax, ay = c[a, 0], c[a, 1]
            ex, ey = c[(a + 1) % k, 0] - ax, c[(a + 1) % k, 1] - ay
            out = np.empty((2 * count, 2))
            n_out = 0
            px, py = poly[count - 1, 0], poly[count - 1, 1]
            dp = sign * (ex * (py - ay) - ey * (px - ax))
            for i in range(count):
                qx, qy = poly[i, 0], poly[i, 1]
                dq = sign * (ex * (qy - ay) - ey * (qx - ax))
                if (dq >= 0.0) != (dp >= 0.0):
                    t = dp / (dp - dq)
                    out[n_out, 0] = px + t * (qx - px)
                    out[n_out, 1] = py + t * (qy - py)
                    n_out += 1
                if dq >= 0.0:
                    out[n_out, 0] = qx
                    out[n_out, 1] = qy
                    n_out += 1
                px, py, dp = qx, qy, dq
            poly, count = out, n_out
        twice = 0.0
        for i in range(count):
            j = (i + 1) % count
            twice += poly[i, 0] * poly[j, 1] - poly[j, 0] * poly[i, 1]
        areas[p] = abs(0.5 * twice)
    return areas


def pairwise_intersection_area(subject, clip):
    """Areas (P,) in m² of ``subject[p] ∩ clip[p]`` (one compiled loop over the pairs).

    Parameters
    ----------
    subject : (P, M, 2) float64
        Simple polygons (any winding).
    clip : (P, K, 2) float64
        Convex polygons (any winding).
    """
    if len(subject) == 0:
        return np.zeros(0)
    return _clipped_areas(np.ascontiguousarray(subject, dtype=np.float64),
                          np.ascontiguousarray(clip, dtype=np.float64))


def convex_intersection_area(a_m, b_m):
    """Area of the intersection of two convex polygons.

    Parameters
    ----------
    a_m, b_m : (k, 2) array_like
        Convex polygons in meters, any orientation (e.g. footprints, shape (4, 2)).

    Returns
    -------
    area_m2 : float
        Intersection area in m²; 0 when they are disjoint or only touch.
    """
    a = _as_polygon(a_m, "a_m")
    b = _as_polygon(b_m, "b_m")
    return float(pairwise_intersection_area(a[None], b[None])[0])


def box_overlaps(corners_m, z_range_m, collides, min_area_m2=1e-6):
    """All pairs of colliding items whose boxes interpenetrate.

    A sort-and-sweep over the footprints' x extents (then y and z interval tests) finds
    candidates; their footprints are intersected exactly.

    Parameters
    ----------
    corners_m : (n, 4, 2) array_like
        Footprint corners in meters.
    z_range_m : (n, 2) array_like
        Bottom and top height of each item in meters.
    collides : (n,) array_like of bool
        Items taking part in collisions (rugs and lamps on tables may not).
    min_area_m2 : float
        Footprint intersections of at most this area (m²) are contacts, not overlaps.

    Returns
    -------
    pairs : (k, 2) int64
        Item indices ``i < j``, sorted lexicographically.
    area_m2 : (k,) float64
        Footprint intersection area of each pair in m².
    """
    corners = _as_boxes(corners_m)
    n = len(corners)
    z = np.asarray(z_range_m, dtype=np.float64)
    if z.shape != (n, 2):
        raise ValueError(f"z_range_m must have shape ({n}, 2), got {z.shape}")
    active = np.flatnonzero(_as_flags(collides, n, "collides"))
    lo = corners[active].min(axis=1)
    hi = corners[active].max(axis=1)
    order = np.argsort(lo[:, 0], kind="stable")
    lo, hi, ids = lo[order], hi[order], active[order]
    # Sorted by x-min, box i can only meet the boxes after it that start before it ends.
    end = np.searchsorted(lo[:, 0], hi[:, 0], side="left")
    n_cand = np.maximum(end - np.arange(len(ids)) - 1, 0)
    first = np.repeat(np.arange(len(ids)), n_cand)
    start = np.cumsum(n_cand) - n_cand
    second = first + 1 + np.arange(n_cand.sum()) - np.repeat(start, n_cand)
    keep = (lo[first, 1] < hi[second, 1]) & (lo[second, 1] < hi[first, 1])
    first, second = ids[first[keep]], ids[second[keep]]
    z_overlap = np.minimum(z[first, 1], z[second, 1]) - np.maximum(z[first, 0], z[second, 0])
    keep = z_overlap > _Z_OVERLAP_TOL_M
    first, second = first[keep], second[keep]

    area = pairwise_intersection_area(corners[first], corners[second])
    keep = area > min_area_m2
    pairs = np.sort(np.stack([first[keep], second[keep]], axis=1), axis=1).astype(np.int64)
    area = area[keep]
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    return pairs[order], area[order]


def area_outside(polygon_m, corners_m):
    """Area of each footprint lying outside the floor.

    Parameters
    ----------
    polygon_m : (m, 2) array_like
        Floor polygon in meters, possibly non-convex.
    corners_m : (n, 4, 2) array_like
        Footprint corners in meters.

    Returns
    -------
    area_m2 : (n,) float64
        ``area(box) - area(floor ∩ box)`` in m², exact up to rounding.
    """
    floor = _as_polygon(polygon_m, "polygon_m")
    corners = _as_boxes(corners_m)
    n = len(corners)
    box_area = np.abs(_signed_areas(corners))
    inside = pairwise_intersection_area(np.broadcast_to(floor, (n,) + floor.shape), corners)
    return np.maximum(box_area - inside, 0.0)


def door_clearance(door_zones_m, corners_m, blocks):
    """How much blocking furniture covers each door's clearance zone.

    Parameters
    ----------
    door_zones_m : (d, 4, 2) array_like
        Convex clearance zone of each door in meters.
    corners_m : (n, 4, 2) array_like
        Footprint corners in meters.
    blocks : (n,) array_like of bool
        Items that obstruct walking (a rug does not).

    Returns
    -------
    area_m2 : (d,) float64
        Summed overlap area in m² of blocking footprints with each zone; 0 means clear.
    """
    zones = _as_boxes(door_zones_m, "door_zones_m")
    corners = _as_boxes(corners_m)
    blocking = corners[_as_flags(blocks, len(corners), "blocks")]
    d, b = len(zones), len(blocking)
    area = pairwise_intersection_area(
        np.repeat(blocking[None], d, axis=0).reshape(d * b, 4, 2),
        np.repeat(zones, b, axis=0),
    )
    return area.reshape(d, b).sum(axis=1)


@dataclass(frozen=True, eq=False)
class Traversability:
    """Result of :func:`traversability`.

    Attributes
    ----------
    ok : bool
        Every door and every access side touch one common passable component.
    n_components : int
        Number of 8-connected components of ``passable``.
    unreachable : tuple of (int, int)
        ``(item, side)`` access sides not touching the main component (the one touched
        by the most doors, ties broken by the most access sides).
    blocked_doors : tuple of int
        Doors not touching the main component.
    passable : (H, W) bool
        Where a person can stand; row ``r``, column ``c`` covers
        ``x in origin_m[0] + resolution_m * [c, c + 1]`` and
        ``y in origin_m[1] + resolution_m * [r, r + 1]`` (draw with ``origin="lower"``).
    origin_m : (2,) float64
        World (x, y) in meters of the outer corner of pixel (0, 0).
    resolution_m : float
        Pixel side in meters.
    """

    ok: bool
    n_components: int
    unreachable: tuple
    blocked_doors: tuple
    passable: np.ndarray
    origin_m: np.ndarray
    resolution_m: float


# Fixed-point vertices for cv2.fillPoly: 8 fractional bits.
_SHIFT = 8
_SUBPIXEL = 1 << _SHIFT


class _Raster:
    """Fills world polygons into a pixel grid whose row axis is y and column axis is x."""

    def __init__(self, origin_m, resolution_m, shape):
        self.origin_m = origin_m
        self.resolution_m = resolution_m
        self.shape = shape

    def _fill(self, polygons_m):
        """fillPoly of polygons (each (k, 2) meters) with sub-pixel vertices, as bool."""
        m = np.zeros(self.shape, dtype=np.uint8)
        pts = [np.round(np.stack([(p[:, 0] - self.origin_m[0]) / self.resolution_m - 0.5,
                                  (p[:, 1] - self.origin_m[1]) / self.resolution_m - 0.5], axis=1)
                        * _SUBPIXEL).astype(np.int32) for p in polygons_m]
        if pts:
            cv2.fillPoly(m, pts, 1, lineType=cv2.LINE_8, shift=_SHIFT)
        return m.astype(bool)

    def _mark(self, mask, points_m):
        """Set the pixels that contain ``points_m`` (k, 2), those inside the image."""
        rc = np.floor((points_m[:, ::-1] - self.origin_m[::-1]) / self.resolution_m).astype(int)
        inside = np.all((rc >= 0) & (rc < self.shape), axis=1)
        mask[rc[inside, 0], rc[inside, 1]] = True

    def mask_all(self, polygons_m):
        """Union of the masks of many small convex polygons (one OpenCV call); fillPoly
        with LINE_8 marks the pixels their edges pass through, which may differ from
        pixel-center filling, so each centroid's pixel is added too (slivers)."""
        mask = self._fill(list(polygons_m))
        if len(polygons_m):
            self._mark(mask, polygons_m.mean(axis=1))
        return mask

    def mask(self, polygon_m):
        """Pixels whose centers lie in ``polygon_m`` (any simple polygon); a sliver
        thinner than a pixel that covers no center keeps the pixels of its vertices
        and centroid."""
        mask = self._fill([polygon_m])
        if not mask.any():
            self._mark(mask, np.vstack([polygon_m, polygon_m.mean(axis=0, keepdims=True)]))
        return mask


@numba.njit(cache=True)
def _labels_in_quads(labels, n_labels, quads_px):
    """For each convex quad (pixel-center coordinates), which labels its pixels carry.

    A pixel belongs to a quad when its center is inside; a quad thinner than a pixel
    that covers no center takes the pixels holding its corners and its centroid
    (as :meth:`_Raster.mask` does). Returns (q, n_labels + 1) bool.
    """
    h, w = labels.shape
    out = np.zeros((quads_px.shape[0], n_labels + 1), dtype=np.bool_)
    for q in range(quads_px.shape[0]):
        quad = quads_px[q]
        area2 = 0.0
        for a in range(4):
            b = (a + 1) % 4
            area2 += quad[a, 0] * quad[b, 1] - quad[b, 0] * quad[a, 1]
        sign = 1.0 if area2 >= 0.0 else -1.0
        c0 = max(int(np.ceil(quad[:, 0].min())), 0)
        c1 = min(int(np.floor(quad[:, 0].max())), w - 1)
        r0 = max(int(np.ceil(quad[:, 1].min())), 0)
        r1 = min(int(np.floor(quad[:, 1].max())), h - 1)
        hit = False
        for r in range(r0, r1 + 1):
            for c in range(c0, c1 + 1):
                inside = True
                for a in range(4):
                    b = (a + 1) % 4
                    cross = (quad[b, 0] - quad[a, 0]) * (r - quad[a, 1]) - (quad[b, 1] - quad[a, 1]) * (c - quad[a, 0])
                    if sign * cross < 0.0:
                        inside = False
                        break
                if inside:
                    out[q, labels[r, c]] = True
                    hit = True
        if not hit:
            for a in range(5):
                x = quad[:, 0].mean() if a == 4 else quad[a, 0]
                y = quad[:, 1].mean() if a == 4 else quad[a, 1]
                c = int(np.floor(x + 0.5))
                r = int(np.floor(y + 0.5))
                if 0 <= r < h and 0 <= c < w:
                    out[q, labels[r, c]] = True
    return out


def traversability(
    polygon_m,
    corners_m,
    blocks,
    access_corners_m,
    access_depth_m,
    door_zones_m,
    resolution_m=0.05,
    radius_m=0.25,
    open_edges=(),
):
    """Whether people can walk from the doors to every side that must stay accessible.

    Follows Henderson et al. (Sec. 4): the floor minus blocking footprints is eroded by
    a disk the size of a person, the free part of the door zones is added back (people
    enter there), and the doors and all access zones must reach one common component.
    Past an open edge (the photo's edge: the room goes on) the floor continues by a
    person's width, so that only walls and furniture narrow the way.

    Parameters
    ----------
    polygon_m : (m, 2) array_like
        Floor polygon in meters, possibly non-convex.
    corners_m : (n, 4, 2) array_like
        Footprint corners in meters.
    blocks : (n,) array_like of bool
        Items that obstruct walking.
    access_corners_m : (n, 4, 4, 2) array_like
        Access rectangles from :func:`layout.geometry.access_box_corners`.
    access_depth_m : (n, 4) array_like
        Access depth per side (back, left, front, right) in meters; 0 = no access needed.
    door_zones_m : (d, 4, 2) array_like
        Clearance zone of each door inside the room, in meters.
    resolution_m : float
        Pixel side in meters.
    radius_m : float
        Half the width of a walking person in meters.
    open_edges : sequence of int
        Edges ``k -> k+1`` of ``polygon_m`` that are no wall.

    Returns
    -------
    Traversability
    """
    floor = _as_polygon(polygon_m, "polygon_m")
    corners = _as_boxes(corners_m)
    n = len(corners)
    blocks = _as_flags(blocks, n, "blocks")
    access = np.asarray(access_corners_m, dtype=np.float64)
    if access.shape != (n, 4, 4, 2):
        raise ValueError(f"access_corners_m must have shape ({n}, 4, 4, 2), got {access.shape}")
    depth = np.asarray(access_depth_m, dtype=np.float64)
    if depth.shape != (n, 4):
        raise ValueError(f"access_depth_m must have shape ({n}, 4), got {depth.shape}")
    doors = _as_boxes(np.asarray(door_zones_m, dtype=np.float64).reshape(-1, 4, 2), "door_zones_m")
    resolution_m = float(resolution_m)
    radius_m = float(radius_m)
    if not resolution_m > 0 or not radius_m >= 0:
        raise ValueError("resolution_m must be > 0 and radius_m >= 0")

    edges = np.asarray(open_edges, dtype=np.int64).reshape(-1)
    a, b = floor[edges], floor[(edges + 1) % len(floor)]
    out = (b - a)[:, ::-1] * [1.0, -1.0] * (radius_m + 2 * resolution_m) / np.maximum(
        np.linalg.norm(b - a, axis=1, keepdims=True), 1e-12)  # outward for a counter-clockwise floor
    beyond = np.stack([a, b, b + out, a + out], axis=1)
    reach = np.concatenate([floor, beyond.reshape(-1, 2)])
    # One blank pixel around the floor so that erosion sees the walls on every side.
    origin = reach.min(axis=0) - resolution_m
    shape = tuple(
        int(v) for v in np.ceil((reach.max(axis=0) - origin) / resolution_m)[::-1] + 1
    )
    raster = _Raster(origin, resolution_m, shape)
    free = raster.mask(floor) | raster.mask_all(beyond)
    free[raster.mask_all(corners[blocks])] = False
    r = int(round(radius_m / resolution_m))
    dy, dx = np.ogrid[-r:r + 1, -r:r + 1]
    disk = dx * dx + dy * dy <= r * r
    # cv2.erode is the same binary erosion (outside the image counts as blocked), in C.
    passable = cv2.erode(free.astype(np.uint8), disk.astype(np.uint8), borderType=cv2.BORDER_CONSTANT,
                         borderValue=0).astype(bool)
    door_masks = [raster.mask(zone) & free for zone in doors]
    for m in door_masks:
        passable |= m
    count, labels = cv2.connectedComponents(passable.astype(np.uint8), connectivity=8, ltype=cv2.CV_32S)
    n_components = count - 1

    def touched(where):
        return set(np.unique(labels[where]).tolist()) - {0}

    door_touch = [touched(m) for m in door_masks]
    sides = [(int(i), int(k)) for i, k in zip(*np.nonzero(depth > 0))]
    quads = np.array([access[i, k] for i, k in sides], dtype=np.float64).reshape(-1, 4, 2)
    quads_px = (quads - origin) / resolution_m - 0.5  # pixel-center coordinates (x=col, y=row)
    side_touch = [set(np.flatnonzero(row).tolist()) - {0}
                  for row in _labels_in_quads(labels.astype(np.int64), n_components, quads_px)]
    n_doors = np.zeros(n_components + 1, dtype=np.int64)
    n_sides = np.zeros(n_components + 1, dtype=np.int64)
    for t in door_touch:
        n_doors[list(t)] += 1
    for t in side_touch:
        n_sides[list(t)] += 1
    # The background (label 0) is in no touched set, yet with its low label it would
    # win a tie at zero counts.
    n_doors[0] = n_sides[0] = -1
    main = int(np.lexsort((-np.arange(n_components + 1), n_sides, n_doors))[-1])
    unreachable = tuple(s for s, t in zip(sides, side_touch) if main not in t)
    blocked = tuple(j for j, t in enumerate(door_touch) if main not in t)
    return Traversability(
        ok=not unreachable and not blocked,
        n_components=int(n_components),
        unreachable=unreachable,
        blocked_doors=blocked,
        passable=passable,
        origin_m=origin,
        resolution_m=resolution_m,
    )


# Overlaps smaller than this (m²) are contacts of touching boxes, not collisions.
MIN_OVERLAP_M2 = 1e-4


def item_geometry(layout):
    """The layout's items: indices, footprint corners (n, 4, 2), z ranges (n, 2), access
    zones and depths per side."""
    m = layout.model
    items = m.items
    size = m.particle_size_m[items]
    pos = layout.position_m[items]
    yaw = layout.yaw_rad[items]
    corners = box_corners(pos[:, :2], yaw, size[:, 0], size[:, 1])
    z = np.stack([pos[:, 2] - 0.5 * size[:, 2], pos[:, 2] + 0.5 * size[:, 2]], axis=1)
    depth = m.particle_access_depth_m[items]
    access = access_box_corners(pos[:, :2], yaw, size[:, 0], size[:, 1], depth)
    return items, corners, z, access, depth


def _shared_sides(model, items, corners, access, depth):
    """Access sides taken by a member of the same group (a chair at its table): the
    solver lets group mates stand there, so walkability does not ask for them."""
    parent = model.particle_parent[items]
    center = corners.mean(axis=1)
    reach = np.linalg.norm(corners[:, 0] - center, axis=1) + depth.max(axis=1)
    collides = model.particle_collides[items]
    owner, mate = [], []  # pairs of group mates close enough to matter
    for g in np.unique(parent[parent >= 0]):
        members = np.flatnonzero(parent == g)
        owners = members[depth[members].max(axis=1) > 0]
        mates = members[collides[members]]
        dist = np.linalg.norm(center[owners][:, None] - center[mates][None], axis=-1)
        near = (dist < reach[owners][:, None] + reach[mates][None]) & (owners[:, None] != mates[None])
        a, b = np.nonzero(near)
        owner.append(owners[a])
        mate.append(mates[b])
    taken = np.zeros(depth.shape, bool)
    if owner:
        owner, mate = np.concatenate(owner), np.concatenate(mate)
        pair, k = np.nonzero(depth[owner] > 0)
        a, b = owner[pair], mate[pair]
        area = pairwise_intersection_area(access[a, k], corners[b])
        taken[a[area > MIN_OVERLAP_M2], k[area > MIN_OVERLAP_M2]] = True
    return taken


def walkability(layout) -> Traversability:
    """Henderson et al.'s traversability of a layout (see :func:`layout.metrics.traversability`),
    not asking for access sides that a group mate stands in."""
    m = layout.model
    items, corners, _, access, depth = item_geometry(layout)
    doors = layout.corners_m(m.door_particles) if len(m.door_particles) else np.zeros((0, 4, 2))
    required = np.where(_shared_sides(m, items, corners, access, depth), 0.0, depth)
    return traversability(m.floor_polygon_m, corners, m.particle_collides[items], access, required, doors,
                          open_edges=np.flatnonzero(~m.floor_edge_wall))
