"""The floor polygon in meters, from a floor mask and the board's calibration.

The outline of the floor region under the board is taken back through the floor
homography into the floor frame (the board's: origin at its center, z up), simplified so
walls come out straight, and each edge is labelled with what bounds it: a wall or an
object standing on the floor (``"boundary"``), the photo's edge (``"image"``: the floor
goes on beyond it), or the distance beyond which the floor is not believed (``"far"``).
Only the first kind is a real limit of the room; the others are the *visible-extent
caveat*. The mask's other parts (:func:`augment.floor.segment.floor_parts`: one a carton or a
wall corner cut off at the photo's edge, floor clicked behind a carton) are outlined the
same way and joined on by corridors a millimeter wide.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from layout.geometry import polygon_area, self_intersection

from .segment import border_pixels, floor_distance_m, floor_footprint_m2, floor_parts
from .settings import FLOOR

EDGE_KINDS = ("boundary", "image", "far")


@dataclass(frozen=True)
class FloorPolygon:
    """The visible floor as a polygon in the floor frame.

    Attributes
    ----------
    polygon_m : (n, 2) float64
        Vertices in meters, counter-clockwise seen from above.
    edge_kind : tuple of str, length n
        Edge i runs from vertex i to vertex i+1: ``"boundary"`` (wall or object),
        ``"image"`` (the photo's edge cut the floor off) or ``"far"`` (beyond
        ``FLOOR.segment.max_floor_distance_m``).
    area_m2 : float
    caveat : str
        Empty when every edge is a boundary; else what the polygon leaves out.
    """

    polygon_m: np.ndarray
    edge_kind: tuple[str, ...]
    area_m2: float
    caveat: str

    def to_json(self) -> dict:
        return {"polygon_m": self.polygon_m.round(4).tolist(), "edge_kind": list(self.edge_kind),
                "area_m2": round(self.area_m2, 4), "caveat": self.caveat}


def _drop_notches(poly: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Indices of ``poly`` left after removing vertices whose triangle with their
    neighbours is smaller than ``FLOOR.polygon.notch_area_m2`` (smallest first,
    repeatedly)."""
    idx = list(range(len(poly)))
    while len(idx) > 3:
        p = poly[idx]
        prev, nxt = np.roll(p, 1, axis=0), np.roll(p, -1, axis=0)
        tri = 0.5 * np.abs((p[:, 0] - prev[:, 0]) * (nxt[:, 1] - prev[:, 1])
                           - (p[:, 1] - prev[:, 1]) * (nxt[:, 0] - prev[:, 0]))
        tri[keep[idx]] = np.inf
        i = int(np.argmin(tri))
        if tri[i] >= FLOOR.polygon.notch_area_m2:
            break
        del idx[i]
    return np.asarray(idx)


def _simplified(points: np.ndarray, tolerance: float, index: np.ndarray) -> np.ndarray:
    """``index`` of the closed outline ``points`` (n, 2) that Douglas-Peucker keeps at
    ``tolerance``, in order."""
    approx = cv2.approxPolyDP(points.astype(np.float32).reshape(-1, 1, 2), tolerance, True)[:, 0, :]
    # approxPolyDP returns a subset of the input points: find their indices, in order.
    lookup = {tuple(p): i for i, p in enumerate(points.astype(np.float32))}
    return index[np.array(sorted(lookup[tuple(p)] for p in approx))]


def _pixel_edge(contour: np.ndarray) -> np.ndarray:
    """Move a traced outline from its boundary pixels' centers out to their outer edges.

    A floor pixel is floor over its whole square, so the floor ends at the pixel's outer
    edge; an outline through the centers leaves out a half-pixel band all round, which
    at a far wall is centimeters deep.
    A staircase of pixels at angle a to the rows reaches out 0.5 max(|cos a|, |sin a|)
    on average, hence the offset along the outward normal.
    """
    n = len(contour)
    if n < 5:
        return contour
    tangent = np.roll(contour, -2, axis=0) - np.roll(contour, 2, axis=0)
    # Outward is to the right of travel for a positively oriented outline, left otherwise.
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]]) * np.sign(polygon_area(contour))
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    reach = 0.5 * np.abs(normal).max(axis=1, keepdims=True)
    return contour + reach * normal


def _span(a: int, b: int, n: int) -> np.ndarray:
    """Indices from a to b along a closed outline of n points, both ends included."""
    return np.arange(a, b + 1) if b > a else np.concatenate([np.arange(a, n), np.arange(0, b + 1)])


def _farthest_between(outline: np.ndarray, a: int, b: int) -> int | None:
    """Index of the outline point between ``a`` and ``b`` farthest from their chord, or
    None when they are neighbours."""
    span = _span(a, b, len(outline))[1:-1]
    if len(span) == 0:
        return None
    chord = outline[b] - outline[a]
    offset = outline[span] - outline[a]
    distance = np.abs(chord[0] * offset[:, 1] - chord[1] * offset[:, 0])
    return int(span[np.argmax(distance)])


def _fit_corners(outline: np.ndarray, vertex_idx: np.ndarray) -> np.ndarray:
    """Polygon corners where the straight lines fitted to neighbouring edges meet.

    The simplified polygon's vertices are outline points, and the outline rounds a
    room's corners off by a pixel or so; each edge is refitted (least squares) to the
    outline points it stands for, and a corner moves to where its two lines cross, unless
    they are nearly parallel or cross far from it (then the outline point stays).
    """
    n = len(vertex_idx)
    lines = []
    for a, b in zip(vertex_idx, np.roll(vertex_idx, -1)):
        pts = outline[_span(a, b, len(outline))]
        center = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - center, full_matrices=False)
        lines.append((center, vt[0]))
    poly = outline[vertex_idx].copy()
    for i in range(n):
        (p, d), (q, e) = lines[i - 1], lines[i]
        cross = d[0] * e[1] - d[1] * e[0]
        if abs(cross) < np.sin(np.radians(FLOOR.polygon.corner_min_deg)):
            continue
        corner = p + d * ((q - p)[0] * e[1] - (q - p)[1] * e[0]) / cross
        if np.linalg.norm(corner - poly[i]) <= 2 * FLOOR.polygon.simplify_m:
            poly[i] = corner
    return poly


def _join_nearest(region: np.ndarray, part: np.ndarray) -> None:
    """Add ``part`` to ``region`` (uint8, in place), joined by a one-pixel seam where the
    two come nearest."""
    gap = cv2.distanceTransform((region == 0).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    py, px = np.nonzero(part)
    k = int(np.argmin(gap[py, px]))
    ry, rx = np.nonzero(region)
    j = int(np.argmin((rx - px[k]) ** 2 + (ry - py[k]) ** 2))
    region[part] = 1
    cv2.line(region, (int(rx[j]), int(ry[j])), (int(px[k]), int(py[k])), 1, 1, lineType=8)


def floor_polygon(mask: np.ndarray, calibration, keep_px: np.ndarray | None = None) -> FloorPolygon:
    """Simplified floor polygon (meters) of the floor region of ``mask`` under the board
    (else the largest) and the mask's other substantial parts, joined on.

    Parameters
    ----------
    mask : (rows, cols) bool
        Floor mask at the calibrated photo's size, cleaned up (as
        :func:`augment.floor.segment.segment_floor` leaves it): every part of it large enough
        to hold something counts. Not modified.
    calibration : Calibration
        The photo's calibration (:func:`augment.camera.calibrate.calibrate_photo`).
    keep_px : (k, 2) float, optional
        Photo pixels (x, y) the user clicked as floor: the parts of the mask under them
        count however few pixels they cover (a far patch behind a carton). Not modified.

    Returns
    -------
    FloorPolygon

    Raises
    ------
    ValueError
        When the mask's size differs from the calibration's, or no floor lies below the
        horizon.
    """
    mask = np.asarray(mask, dtype=bool)
    cols, rows = calibration.size_px
    if mask.shape != (rows, cols):
        raise ValueError(f"floor mask of {mask.shape[1]} x {mask.shape[0]} px does not match the "
                         f"calibrated photo's {cols} x {rows} px")
    scale = min(1.0, FLOOR.polygon.long_px / max(rows, cols))
    small_cal = calibration.scaled(scale)
    size = small_cal.size_px
    small = cv2.resize(mask.astype(np.uint8), size, interpolation=cv2.INTER_AREA) > 0 if scale < 1 else mask
    distance = floor_distance_m(small.shape, small_cal)
    near = distance <= FLOOR.segment.max_floor_distance_m
    region = (small & near).astype(np.uint8)
    # The outline is the floor's outer edge, holes and all; fill them first, or the opening
    # below breaks a thin rim of floor behind a carton at a far wall and the outline runs
    # round the carton instead.
    outer, _ = cv2.findContours(region, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(region, outer, -1, 1, -1)
    # Opening removes hair-thin spurs (a skirting board's shadow) before tracing.
    region = cv2.morphologyEx(region, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    # The mask is cleaned up already: a part cut off inside the photo is there because
    # someone kept it (a click on floor behind a carton, a painted mask).
    labels, main, parts = floor_parts(region, small_cal, distance_m=distance, reach_edge=False)
    if main == 0:
        raise ValueError(f"no floor in the mask below the horizon and within {FLOOR.segment.max_floor_distance_m:g} m "
                         "once strips a pixel or two wide are dropped")
    if keep_px is not None and len(keep_px):
        x, y = np.round(np.asarray(keep_px, dtype=np.float64).reshape(-1, 2) * scale).astype(int).T
        inside = (x >= 0) & (x < labels.shape[1]) & (y >= 0) & (y < labels.shape[0])
        clicked = set(labels[y[inside], x[inside]].tolist()) - {0, main, *parts}
        parts = [*parts, *sorted(clicked)]
    region = (labels == main).astype(np.uint8)
    # Outline points next to floor beyond FLOOR.segment.max_floor_distance_m are "far" edges.
    far_ring = cv2.dilate((~near).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    poly, edge_kind = _join_parts(region, [labels == k for k in parts], far_ring, scale, calibration)
    area = abs(polygon_area(poly))
    return FloorPolygon(poly, tuple(edge_kind), area, _caveat(poly, edge_kind))


def _join_parts(region: np.ndarray, parts: list[np.ndarray], far_ring: np.ndarray, scale: float,
                calibration) -> tuple[np.ndarray, list[str]]:
    """The polygon and edge kinds (:func:`_outline_polygon`) of ``region`` (uint8,
    modified) with ``parts`` joined on.

    Each part is outlined on its own and bridged on (:func:`_bridge`). A part cut off at
    the photo's edge meets the rest beyond it, so its corridor is an ``"image"`` edge; one
    cut off inside the photo lies behind what stands between, so its corridor is a
    ``"boundary"``. A seam traced with the rest instead would put the two sides of a
    pixel-wide corridor within the simplification's reach of each other, and the
    straightened polygon could cross itself there. A part so near that, simplified, it
    touches the region cannot be bridged: it is joined to the region by a one-pixel seam
    where the two come nearest and outlined with it, as one.
    """
    parts = list(parts)
    while True:
        outlined = _outline_polygon(region, far_ring, scale, calibration)
        if outlined is None:
            raise ValueError("the floor region is too small or too thin to outline")
        poly, kinds = outlined
        for k, part in enumerate(parts):
            outlined = _outline_polygon(part, far_ring, scale, calibration)
            if outlined is None:
                continue
            at_edge = bool(border_pixels(part).any())
            joined = _bridge(poly, kinds, *outlined, corridor="image" if at_edge else "boundary")
            if joined is None:
                _join_nearest(region, part)
                del parts[k]
                break
            poly, kinds = joined
        else:
            return poly, kinds


def _outline_polygon(region: np.ndarray, far_ring: np.ndarray, scale: float,
                     calibration) -> tuple[np.ndarray, list[str]] | None:
    """The simplified polygon (meters, counter-clockwise) of the largest outline of
    ``region`` (the photo scaled by ``scale``) and the kind of each edge, ``"far"`` where
    the outline runs through ``far_ring``; None when the region is too small or too thin
    to outline."""
    contours, _ = cv2.findContours(region.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    contour = max(contours, key=cv2.contourArea)[:, 0, :].astype(np.float64)
    if len(contour) < 3 or cv2.contourArea(contour.astype(np.float32)) < 16:
        return None

    h, w = region.shape
    border = FLOOR.polygon.border_px
    on_border = ((contour[:, 0] <= border - 1) | (contour[:, 0] >= w - border)
                 | (contour[:, 1] <= border - 1) | (contour[:, 1] >= h - border))
    ci, cj = contour[:, 1].astype(int), contour[:, 0].astype(int)
    at_far = far_ring[ci, cj] & ~on_border
    kind = np.where(on_border, 1, np.where(at_far, 2, 0))

    # Pixel centers of the scaled image map back to full-size pixel coordinates.
    outline_px = (_pixel_edge(contour) + 0.5) / scale - 0.5
    floor_m = calibration.floor_from_pixels(outline_px)
    # First in the photo, then on the floor: at a far wall one row of pixels is
    # centimeters deep, and the steps of GrabCut's coarse mask would stay as teeth.
    px_idx = _simplified(contour, FLOOR.polygon.simplify_share * max(h, w), np.arange(len(contour)))
    vertex_idx = _simplified(floor_m[px_idx], FLOOR.polygon.simplify_m, px_idx)
    # A vertex where the edge kind changes (the floor meets the photo's edge) stays.
    changes = kind != np.roll(kind, 1)
    pinned = np.isin(vertex_idx, np.flatnonzero(changes))
    keep = _drop_notches(floor_m[vertex_idx], pinned)
    vertex_idx = vertex_idx[keep]
    poly = _fit_corners(floor_m, vertex_idx)
    # At a neck of the floor a few pixels wide the refitted corners on its two sides can
    # pass each other: those of crossing edges go back to the outline's own points. Where
    # the outline's points cross too (a corner dropped as a notch, or Douglas-Peucker's
    # own chords across a long thin strip), each crossing edge takes back the outline
    # point farthest from it, until the polygon is simple.
    while (pair := self_intersection(poly)) is not None:
        edges = [i % len(poly) for i in pair]
        ends = sorted({i for e in edges for i in (e, (e + 1) % len(poly))})
        moved = [i for i in ends if not np.array_equal(poly[i], floor_m[vertex_idx[i]])]
        if moved:
            poly[moved] = floor_m[vertex_idx[moved]]
            continue
        split = [k for k in (_farthest_between(floor_m, vertex_idx[e], vertex_idx[(e + 1) % len(poly)])
                             for e in edges) if k is not None]
        if not split:
            break
        poly = np.vstack([poly, floor_m[split]])[np.argsort(np.concatenate([vertex_idx, split]), kind="stable")]
        vertex_idx = np.sort(np.concatenate([vertex_idx, split]))
    if len(poly) < 3 or abs(polygon_area(poly)) < FLOOR.polygon.notch_area_m2:
        return None  # a strip too thin to hold anything straightens to a line

    edge_kind = []
    for a, b in zip(vertex_idx, np.roll(vertex_idx, -1)):
        span = _span(a, b, len(kind))
        votes = np.bincount(kind[span[1:-1]] if len(span) > 2 else kind[span], minlength=3)
        edge_kind.append(EDGE_KINDS[int(np.argmax(votes))])
    if polygon_area(poly) < 0:
        # Reverse vertices; edge i (i -> i+1) becomes the edge between the same two
        # vertices, which now sits at a shifted index.
        poly = poly[::-1].copy()
        edge_kind = edge_kind[::-1]
        edge_kind = edge_kind[1:] + edge_kind[:1]
    return poly, edge_kind


def _bridge(poly: np.ndarray, kinds: list[str], part: np.ndarray,
            part_kinds: list[str], corridor: str = "boundary") -> tuple[np.ndarray, list[str]] | None:
    """One simple polygon of two disjoint counter-clockwise ones, ``poly`` and ``part``
    (each with the kinds of its edges), or None.

    A corridor ``FLOOR.polygon.bridge_m`` wide (its two sides edges of kind ``corridor``)
    runs between the nearest pair of their corners that it joins into a simple polygon,
    and the outline goes out along it, round ``part`` and back. Its area is negligible.
    None when none of the ``FLOOR.polygon.bridge_tries`` nearest pairs does (the two touch
    or overlap).
    """
    gap = np.linalg.norm(poly[:, None, :] - part[None, :, :], axis=2)
    for flat in np.argsort(gap, axis=None)[:FLOOR.polygon.bridge_tries]:
        i, j = np.unravel_index(flat, gap.shape)
        d = part[j] - poly[i]
        if gap[i, j] <= FLOOR.polygon.bridge_m:
            continue
        # Going out, the floor is on the corridor's left; the outline keeps to its right.
        right = 0.5 * FLOOR.polygon.bridge_m * np.array([d[1], -d[0]]) / gap[i, j]
        out = np.vstack([poly[:i], poly[i] + right, part[j] + right, part[j + 1:], part[:j],
                         part[j] - right, poly[i] - right, poly[i + 1:]])
        if self_intersection(out) is None:
            out_kinds = (kinds[:i] + [corridor, part_kinds[j]] + part_kinds[j + 1:] + part_kinds[:j]
                         + [corridor, kinds[i]] + kinds[i + 1:])
            return out, out_kinds
    return None


def _caveat(poly: np.ndarray, edge_kind: list[str]) -> str:
    lengths = np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1)
    parts = []
    far = f"{FLOOR.segment.max_floor_distance_m:g} m from the camera"
    for name, say in (("image", "the photo's edge"), ("far", far)):
        sel = np.array([k == name for k in edge_kind])
        if sel.any():
            parts.append(f"{lengths[sel].sum():.2f} m of outline at {say}")
    if not parts:
        return ""
    return ("visible floor only: " + "; ".join(parts)
            + " - the room goes on beyond those edges, so its area may be larger")


def floor_area_m2(mask: np.ndarray, calibration) -> float:
    """Area (m^2) of the floor pixels of ``mask``, each weighted by its footprint on the
    floor (the homography's local area scale). Measures a mask, holes and all."""
    y, x = np.nonzero(np.asarray(mask, dtype=bool))
    return float(floor_footprint_m2(np.column_stack([x, y]), calibration).sum())


