"""Ground truth derived from geometry alone, to check renders against (and for overlays)."""
from __future__ import annotations

import cv2
import numpy as np

_NEAR_M = 0.01
_SHIFT = 4  # cv2.fillPoly fixed-point bits: polygons drawn to 1/16 pixel


def project_floor_polygon(polygon_m: np.ndarray, K: np.ndarray, camera_from_world: np.ndarray) -> np.ndarray:
    """The floor polygon (z = 0) as the camera sees it, clipped at the camera plane.

    Parameters
    ----------
    polygon_m : (n, 2) float
        Floor outline, world meters.
    K : (3, 3) float
    camera_from_world : (4, 4) float
        OpenCV camera axes.

    Returns
    -------
    polygon_px : (k, 2) float64
        Image points (x, y); empty when the floor is behind the camera.
    """
    world = np.column_stack([polygon_m, np.zeros(len(polygon_m))])
    cam = world @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
    # The floor behind the camera would project through infinity and flip.
    clipped = _clip(cam, 2, _NEAR_M, keep_above=True)
    if len(clipped) == 0:
        return np.zeros((0, 2))
    uvw = clipped @ np.asarray(K, dtype=np.float64).T
    return uvw[:, :2] / uvw[:, 2:3]


def _clip(points: np.ndarray, axis: int, bound: float, keep_above: bool) -> np.ndarray:
    """Sutherland-Hodgman: the part of a polygon (k, d) on one side of ``x[axis] = bound``."""
    out = []
    for i in range(len(points)):
        p, q = points[i], points[(i + 1) % len(points)]
        p_in = (p[axis] >= bound) if keep_above else (p[axis] <= bound)
        q_in = (q[axis] >= bound) if keep_above else (q[axis] <= bound)
        if p_in:
            out.append(p)
        if p_in != q_in:
            out.append(p + (bound - p[axis]) / (q[axis] - p[axis]) * (q - p))
    return np.array(out).reshape(-1, points.shape[1])


def polygon_mask(polygon_px: np.ndarray, size_px: tuple[int, int]) -> np.ndarray:
    """Pixels whose centers fall inside ``polygon_px``; (height, width) bool."""
    width, height = size_px
    mask = np.zeros((height, width), np.uint8)
    # Clip to a margin around the image: far vertices (floor near the horizon, or just in
    # front of the camera) would overflow cv2's fixed-point coordinates.
    pts = np.asarray(polygon_px, dtype=np.float64)
    for axis, extent in ((0, width), (1, height)):
        pts = _clip(pts, axis, -extent, keep_above=True) if len(pts) else pts
        pts = _clip(pts, axis, 2 * extent, keep_above=False) if len(pts) else pts
    if len(pts) >= 3:
        cv2.fillPoly(mask, [np.round(pts * (1 << _SHIFT)).astype(np.int32)], 1, cv2.LINE_8, _SHIFT)
    return mask.astype(bool)


def overlay(photo: np.ndarray, floor_mask: np.ndarray, corners_px: np.ndarray) -> np.ndarray:
    """The photo with the floor tinted and the board corners marked (a new array)."""
    out = photo.copy()
    tint = np.array([40, 200, 60], np.float32)
    out[floor_mask] = (0.55 * out[floor_mask] + 0.45 * tint).astype(np.uint8)
    contours, _ = cv2.findContours(floor_mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(out, contours, -1, (20, 120, 30), max(1, photo.shape[1] // 400), cv2.LINE_AA)
    radius = max(2, photo.shape[1] // 250)
    for x, y in np.asarray(corners_px):
        cv2.circle(out, (int(round(x * 16)), int(round(y * 16))), radius * 16, (230, 30, 30), -1, cv2.LINE_AA, 4)
    return out


def sun_exit(points_m: np.ndarray, direction, polygon_m: np.ndarray, height_m: float, windows,
             margin_m: float = 0.0) -> np.ndarray:
    """Where the ray from each floor point toward the sun leaves the room.

    Parameters
    ----------
    points_m : (k, 3) float
        Points on the floor, world frame, meters.
    direction : (3,) float
        The way sunlight travels (pointing down).
    polygon_m : (n, 2) float
        The room's outline.
    height_m : float
        Its ceiling height.
    windows : iterable of ((2, 2) float, float, float)
        Each window's two floor-plan ends, bottom and top heights, meters.
    margin_m : float
        Points whose ray passes within this of a window's edge (or the ceiling) count as
        neither.

    Returns
    -------
    (k,) int
        +1 through a window (in the sun, but for the frames' shadows), -1 through a wall or
        the ceiling (in the shade), 0 within ``margin_m`` of an edge.
    """
    points_m = np.asarray(points_m, dtype=np.float64)
    d = np.asarray(direction, dtype=np.float64)
    back = -d / np.linalg.norm(d[:2])  # 1 m across the floor per unit
    poly = np.asarray(polygon_m, dtype=np.float64)
    exit_t = np.full(len(points_m), np.inf)
    exit_xy = np.zeros((len(points_m), 2))
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        e = b - a
        den = back[0] * e[1] - back[1] * e[0]
        if abs(den) < 1e-12:
            continue
        w = a - points_m[:, :2]
        s = (w[:, 0] * e[1] - w[:, 1] * e[0]) / den
        u = (w[:, 0] * back[1] - w[:, 1] * back[0]) / den
        hit = (s > 1e-6) & (u >= 0) & (u <= 1) & (s < exit_t)
        exit_t[hit] = s[hit]
        exit_xy[hit] = points_m[hit, :2] + s[hit, None] * back[:2]
    z = points_m[:, 2] + exit_t * back[2]
    verdict = np.where(np.abs(z - height_m) < margin_m, 0, -1)
    for ends, bottom, top in windows:
        a, b = np.asarray(ends, dtype=np.float64)
        length = float(np.linalg.norm(b - a))
        u = (b - a) / length
        along = (exit_xy - a) @ u
        on = np.abs((exit_xy - a) @ np.array([-u[1], u[0]])) < 0.05
        inside = on & (along > margin_m) & (along < length - margin_m) & (z > bottom + margin_m) & (z < top - margin_m)
        near = on & (along > -margin_m) & (along < length + margin_m) & (z > bottom - margin_m) & (z < top + margin_m)
        verdict = np.where(inside, 1, np.where(near, 0, verdict))
    return verdict


def floor_in_world(truth: dict, camera_from_floor: np.ndarray) -> np.ndarray:
    """(4, 4) ``world_from_floor``: the floor frame of a calibration of the sample's photo in
    the sample's world. That frame is the board's, up to the checkerboard's half-turn
    symmetry, which the estimated pose ``camera_from_floor`` tells; its small errors are the
    calibration's and stay in any comparison."""
    world_from_board = np.asarray(truth["board"]["world_from_board"])
    M = np.linalg.inv(world_from_board) @ np.linalg.inv(np.asarray(truth["camera_from_world"])) @ camera_from_floor
    turn = round(np.arctan2(M[1, 0], M[0, 0]) / (np.pi / 2)) * (np.pi / 2)
    c, s = round(np.cos(turn)), round(np.sin(turn))
    return world_from_board @ np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def true_doors_on_floor(truth: dict, camera_from_floor: np.ndarray, kind: str = "doors") -> list[np.ndarray]:
    """The sample's true doors (or ``kind="windows"``) as (2, 2) segments of the floor
    under their sides, in the floor frame of a calibration of its photo
    (:func:`floor_in_world`), meters; a window's sill and top are its truth's
    ``bottom_m`` and ``top_m``."""
    floor_from_world = np.linalg.inv(floor_in_world(truth, camera_from_floor))
    return [(np.column_stack([d["segment_m"], np.zeros(2), np.ones(2)]) @ floor_from_world.T)[:, :2]
            for d in truth["room"][kind]]
