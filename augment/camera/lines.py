"""Line segments and the floor's vertical vanishing point: the helpers that calibration
(settling a board's tilt by the room's vertical edges) and the wall height share.

Images are (row, col) arrays; segments are (n, 4) ``x1, y1, x2, y2`` pixels.
"""
from __future__ import annotations

import cv2
import numpy as np

from .settings import CAMERA


def as_segments(segments_px) -> np.ndarray:
    s = np.ascontiguousarray(segments_px, dtype=np.float64)
    if s.ndim != 2 or s.shape[1] != 4:
        raise ValueError(f"segments_px of shape {s.shape}: expected (n, 4) rows x1, y1, x2, y2")
    if not np.all(np.isfinite(s)):
        raise ValueError("segments_px holds non-finite values")
    return s


def as_camera(K, camera_from_floor) -> tuple[np.ndarray, np.ndarray]:
    K = np.ascontiguousarray(K, dtype=np.float64)
    pose = np.ascontiguousarray(camera_from_floor, dtype=np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[2, 2] == 0:
        raise ValueError(f"K of shape {K.shape} is not a finite 3x3 camera matrix")
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise ValueError(f"camera_from_floor of shape {pose.shape}: expected a finite 4x4 pose")
    R = pose[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-6):
        raise ValueError("camera_from_floor's rotation block is not orthonormal")
    return K / K[2, 2], pose


def to_gray(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] in (3, 4):
        image = cv2.cvtColor(np.ascontiguousarray(image[..., :3]), cv2.COLOR_RGB2GRAY)
    elif image.ndim != 2:
        raise ValueError(f"image of shape {image.shape}: expected (h, w) gray or (h, w, 3) RGB")
    if image.dtype != np.uint8:
        raise ValueError(f"image of dtype {image.dtype}: expected uint8")
    return image


def shrink_factor(shape: tuple[int, ...], side_px: int | None = None) -> int:
    """The whole factor that shrinks an image of ``shape`` to about ``side_px`` across
    (default ``CAMERA.lines.side_px``)."""
    side_px = CAMERA.lines.side_px if side_px is None else side_px
    return max(1, round(max(shape[:2]) / side_px))


def downscale(image: np.ndarray, k: int) -> np.ndarray:
    """``image`` shrunk by the whole factor ``k`` (area average; the last ``< k`` rows and
    columns are dropped, so the scale is exact and OpenCV's fast path applies)."""
    if k == 1:
        return image
    h, w = image.shape[:2]
    cropped = image[: h - h % k, : w - w % k]
    return cv2.resize(cropped, (w // k, h // k), interpolation=cv2.INTER_AREA)


def to_full(points: np.ndarray, k: int) -> np.ndarray:
    """Pixel coordinates (..., 2m) in a copy shrunk by ``k`` to the full image (pixel centers at integers)."""
    return (np.asarray(points, dtype=np.float64) + 0.5) * k - 0.5


def to_small(points: np.ndarray, k: int) -> np.ndarray:
    return (np.asarray(points, dtype=np.float64) + 0.5) / k - 0.5


def prepare_lines(image: np.ndarray, gray: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None, int]:
    """The gray copy lines are found on (area-averaged), for an RGB photo a color copy at
    the same size (only for color statistics: sampled, not averaged, which is faster), and
    the factor they are shrunk by. ``gray`` is the photo in gray when already at hand."""
    image = np.asarray(image)
    k = shrink_factor(image.shape)
    small = downscale(to_gray(image) if gray is None else gray, k)
    color = None
    if image.ndim == 3:
        color = cv2.resize(np.ascontiguousarray(image[..., :3]), (small.shape[1], small.shape[0]),
                           interpolation=cv2.INTER_LINEAR)
    return small, color, k


def detect_raw(small: np.ndarray, method: str) -> np.ndarray:
    """Segments (n, 4) in the pixels of ``small``."""
    settings = CAMERA.lines
    min_len = max(8, int(settings.min_segment_fraction * max(small.shape)))
    if method == "fld":
        detector = cv2.ximgproc.createFastLineDetector(min_len, 1.414, settings.canny_low, settings.canny_high, 3, True)
        blur = settings.blur_px
        found = detector.detect(cv2.GaussianBlur(small, (blur, blur), 0) if blur > 1 else small)
    else:
        found = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD).detect(small)[0]
    if found is None:
        return np.zeros((0, 4))
    seg = found.reshape(-1, 4).astype(np.float64)
    return seg[np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) >= min_len]


def detect_segments(image: np.ndarray, *, side_px: int | None = None, method: str = "fld") -> np.ndarray:
    """Straight line segments of a photo.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        Gray or RGB photo. Not modified.
    side_px : int, optional
        Lines are found on a copy shrunk by the whole factor that brings the longer side
        closest to this (area-averaged), which bounds the time on large photos;
        coordinates are scaled back. Default ``CAMERA.lines.side_px``.
    method : {"fld", "lsd"}
        OpenCV's FastLineDetector (Canny edges, then line fitting; default) or the LSD
        line segment detector.

    Returns
    -------
    segments_px : (n, 4) float64
        Rows ``x1, y1, x2, y2`` in full-resolution pixels.
    """
    gray = to_gray(image)
    side_px = CAMERA.lines.side_px if side_px is None else side_px
    if method not in ("fld", "lsd"):
        raise ValueError(f"method {method!r}: expected 'fld' or 'lsd'")
    if side_px < 64:
        raise ValueError(f"side_px {side_px} is too small to find lines (at least 64)")
    k = shrink_factor(gray.shape, side_px)
    return to_full(detect_raw(downscale(gray, k), method), k)


def vertical_vanishing_point(K: np.ndarray, camera_from_floor: np.ndarray) -> np.ndarray:
    """The image of the floor normal: where vertical edges converge.

    Parameters
    ----------
    K : (3, 3) float64
        Camera matrix, pixels.
    camera_from_floor : (4, 4) float64
        Floor frame (meters, z up) to camera frame (OpenCV axes).

    Returns
    -------
    vp : (3,) float64
        Homogeneous pixel ``K R [0, 0, 1]`` of the *upward* direction, unit norm. Its third
        coordinate is 0 for a level camera (vertical edges parallel in the image); it is
        negative when the camera looks down (then the upward direction points behind the
        camera and the edges converge below the image).
    """
    K, pose = as_camera(K, camera_from_floor)
    vp = K @ pose[:3, 2]
    return vp / np.linalg.norm(vp)


def toward_vanishing_point(points_px: np.ndarray, vp: np.ndarray) -> np.ndarray:
    """Unit directions (n, 2) in the image from each of ``points_px`` (n, 2) toward the
    homogeneous image point ``vp`` (3,), a vanishing point at infinity included."""
    toward = vp[:2] - np.asarray(points_px, dtype=np.float64) * vp[2]
    return toward / np.linalg.norm(toward, axis=1, keepdims=True)


def vertical_alignment(segments_px: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How well each segment could be the image of a vertical 3D edge.

    Parameters
    ----------
    segments_px : (n, 4) float64
        Rows ``x1, y1, x2, y2``, undistorted pixels.
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64

    Returns
    -------
    cos_3d : (n,) float64
        The paper's cosine, in 3D: the largest cosine between the floor normal and any 3D
        direction the segment can be the image of (those in its interpretation plane,
        spanned by the segment and the camera center). 1 for a vertical edge.
    angle_to_vp_deg : (n,) float64
        Image angle between the segment and the line from its midpoint to the vertical
        vanishing point, degrees in [0, 90].
    vp_distance_px : (n,) float64
        The larger distance of the two endpoints from that line, pixels.
    """
    seg = as_segments(segments_px)
    K, pose = as_camera(K, camera_from_floor)
    up_camera = pose[:3, 2]
    p1 = np.column_stack([seg[:, :2], np.ones(len(seg))])
    p2 = np.column_stack([seg[:, 2:], np.ones(len(seg))])
    normals = np.cross(p1, p2) @ K  # K^T l: the interpretation planes' normals, camera frame
    norm = np.linalg.norm(normals, axis=1)
    sin = np.abs(normals @ up_camera) / np.where(norm > 0, norm, 1.0)
    cos_3d = np.where(norm > 0, np.sqrt(np.clip(1 - sin ** 2, 0, 1)), 0.0)
    mid = (seg[:, :2] + seg[:, 2:]) / 2
    toward = toward_vanishing_point(mid, K @ up_camera)
    direction = seg[:, 2:] - seg[:, :2]
    length = np.linalg.norm(direction, axis=1)
    along = np.abs(np.sum(direction * toward, axis=1)) / np.where(length > 0, length, 1.0)
    angle = np.degrees(np.arccos(np.clip(along, 0, 1)))
    half = np.abs(direction[:, 0] * toward[:, 1] - direction[:, 1] * toward[:, 0]) / 2
    return cos_3d, angle, half


def sample_image(image: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Nearest-pixel values of ``image`` at points (..., 2), clipped to the frame."""
    h, w = image.shape[:2]
    x = (points[..., 0] + 0.5).astype(np.intp)      # floor(x + 0.5) for x >= 0; clipped below
    y = (points[..., 1] + 0.5).astype(np.intp)
    np.minimum(np.maximum(x, 0, out=x), w - 1, out=x)
    np.minimum(np.maximum(y, 0, out=y), h - 1, out=y)
    return image[y, x]


def is_vertical(segments_px: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray, side_px: int) -> np.ndarray:
    """Which segments can be images of vertical edges.

    Parameters
    ----------
    segments_px : (n, 4) float64
        Rows ``x1, y1, x2, y2``, undistorted pixels.
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64
    side_px : int
        The photo's longer side, pixels (the vanishing-point tolerance scales with it).

    Returns
    -------
    (n,) bool
        3D cosine at least ``CAMERA.lines.min_vertical_cos`` and both ends within
        ``CAMERA.lines.vp_distance_fraction * side_px`` of the line to the vertical
        vanishing point.
    """
    settings = CAMERA.lines
    cos_3d, _, vp_dist = vertical_alignment(segments_px, K, camera_from_floor)
    return (cos_3d >= settings.min_vertical_cos) & (vp_dist <= settings.vp_distance_fraction * side_px)


def floor_share(color: np.ndarray, k: int, shape: tuple[int, int], points_px: np.ndarray, K: np.ndarray,
                 pose: np.ndarray) -> np.ndarray | None:
    """Share of each row of ``points_px`` (n, m, 2), full-size pixels, whose colour is the
    floor's around the board (the floor frame's origin): Lab, the floor's from a ring of
    floor points ``CAMERA.lines.floor_ring_m`` around the origin, within
    ``CAMERA.lines.floor_color_z`` spreads. None when too little of that ring is in view
    to say. (n,) float."""
    settings = CAMERA.lines
    lab = cv2.cvtColor(cv2.GaussianBlur(color, (5, 5), 0), cv2.COLOR_RGB2LAB).astype(np.float64)
    angles = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    radii = np.linspace(*settings.floor_ring_m, 5)
    ring = np.column_stack([np.outer(radii, np.cos(angles)).ravel(), np.outer(radii, np.sin(angles)).ravel()])
    R, t = pose[:3, :3], pose[:3, 3]
    cam = ring @ R[:, :2].T + t
    px = cam @ K.T
    px = px[:, :2] / px[:, 2:3]
    h, w = shape
    ok = (cam[:, 2] > 0) & (px[:, 0] >= 0) & (px[:, 0] <= w - 1) & (px[:, 1] >= 0) & (px[:, 1] <= h - 1)
    if ok.sum() < 20:
        return None
    ref = sample_image(lab, to_small(px[ok], k))
    center = np.median(ref, axis=0)
    scale = 1.4826 * np.median(np.abs(ref - center), axis=0) + settings.floor_color_slack
    z = np.abs(sample_image(lab, to_small(points_px, k)) - center) / scale
    return np.all(z < settings.floor_color_z, axis=-1).mean(axis=1)


def floor_colored(image: np.ndarray, points_px: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray
                  ) -> np.ndarray:
    """Whether each group of points looks like the floor around the board.

    Parameters
    ----------
    image : (h, w, 3) uint8
        RGB photo.
    points_px : (n, m, 2) float64
        n groups of m points, pixels.
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64

    Returns
    -------
    (n,) bool
        At least ``CAMERA.lines.floor_share`` of the group's points have the floor's
        colour (Lab, read on a ring ``CAMERA.lines.floor_ring_m`` around the board); all
        False when too little of that ring is in view to say. A weak test: walls and
        floors can share a colour.
    """
    _, color, k = prepare_lines(image)
    points = np.asarray(points_px, dtype=np.float64)
    if color is None:
        return np.zeros(len(points), bool)
    K, pose = as_camera(K, camera_from_floor)
    share = floor_share(color, k, image.shape[:2], points, K, pose)
    return np.zeros(len(points), bool) if share is None else share >= CAMERA.lines.floor_share
