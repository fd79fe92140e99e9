"""The camera: what one photo's calibration says, the value every later stage reads.

:class:`Calibration` maps pixels to the floor and back (the floor frame is the board's:
origin at the center of its squares, z up, meters; camera axes follow OpenCV: x right, y
down, z forward); :class:`Intrinsics` is K with its lens distortion and where they came
from. Only :mod:`augment.camera.calibrate` makes them.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from ..errors import CalibrationError
from .board import CHARUCO_DICTIONARY, Board
from .settings import CAMERA


@dataclass(frozen=True)
class Intrinsics:
    """K (3, 3) and distortion (5,), where they came from, and the relative uncertainty
    of the focal length (one standard deviation, e.g. 0.01 = 1 %)."""

    K: np.ndarray
    distortion: np.ndarray
    source: str
    focal_uncertainty: float
    note: str = ""


def turn_points(points_px, quarter_turns: int, size_px: tuple[int, int]) -> np.ndarray:
    """Pixels (n, 2) of a photo of ``size_px = (width, height)`` where they show once it
    is turned as ``np.rot90(photo, quarter_turns)``."""
    pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2).copy()
    w, h = size_px
    for _ in range(int(quarter_turns) % 4):
        pts = np.column_stack([pts[:, 1], w - 1 - pts[:, 0]])
        w, h = h, w
    return pts


def _distortion_reach(distortion: np.ndarray) -> float:
    """The largest distorted radius (in focal lengths) the radial terms (k1, k2, k3, and
    OpenCV's rational k4, k5, k6 when given) map to one undistorted radius each; inf when
    they grow outward as far as a lens can see (five focal lengths)."""
    k1, k2, _, _, k3, k4, k5, k6 = (list(np.ravel(distortion)) + [0.0] * 8)[:8]
    if k1 == k2 == k3 == k4 == k5 == k6 == 0:
        return np.inf
    r = np.linspace(0.0, 5.0, 5001)
    r2 = r * r
    below = 1 + k4 * r2 + k5 * r2 ** 2 + k6 * r2 ** 3
    distorted = r * (1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3) / np.where(below > 0, below, np.inf)
    turn = np.flatnonzero((np.diff(distorted) <= 0) | (below[1:] <= 0))
    return float(distorted[turn[0]]) if len(turn) else np.inf


@dataclass(frozen=True)
class Calibration:
    """Everything later stages need to map pixels to the floor and back.

    Attributes
    ----------
    size_px : (width, height)
    intrinsics : Intrinsics
    camera_from_floor : (4, 4) float64
        Floor frame (meters, z up) to camera frame (OpenCV axes).
    camera_height_m : float
        Height of the camera center above the floor.
    floor_plane_camera : (4,) float64
        ``(n, d)`` with ``n . X + d = 0`` for floor points X in camera coordinates; n
        points up, away from the floor, so ``d`` is the camera height.
    image_from_floor : (3, 3) float64
        Homography from floor meters (x, y) to undistorted pixels; invert for pixels to floor.
    horizon : (3,) float64
        The floor's vanishing line ``a x + b y + c = 0`` in pixels, ``a^2 + b^2 = 1``;
        floor pixels have ``a x + b y + c > 0``.
    rms_px : float
        Reprojection RMS of the board corners.
    corners_px : (n, 2) float64
        Detected inner corners, sorted by ``corner_ids``.
    corner_ids : (n,) int64
        Which board corner each is (rows of :meth:`Board.corners_m`): all of them for a
        checkerboard, those in view for a ChArUco board.
    detector : str
    board : Board
    warnings : tuple of str
    """

    size_px: tuple[int, int]
    intrinsics: Intrinsics
    camera_from_floor: np.ndarray
    camera_height_m: float
    floor_plane_camera: np.ndarray
    image_from_floor: np.ndarray
    horizon: np.ndarray
    rms_px: float
    corners_px: np.ndarray
    corner_ids: np.ndarray
    detector: str
    board: Board
    warnings: tuple[str, ...] = field(default=())

    def scaled(self, scale: float) -> "Calibration":
        """The same calibration for the photo resized by ``scale`` (pixel-grid work at a
        working size)."""
        if scale == 1.0:
            return self
        S = np.diag([scale, scale, 1.0])
        horizon = self.horizon.copy()
        horizon[2] *= scale
        return replace(self, intrinsics=replace(self.intrinsics, K=S @ self.intrinsics.K),
                       image_from_floor=S @ self.image_from_floor, horizon=horizon,
                       size_px=(round(self.size_px[0] * scale), round(self.size_px[1] * scale)))

    def turned(self, quarter_turns: int) -> "Calibration":
        """The same calibration for the photo turned as ``np.rot90(photo, quarter_turns)``
        (counter-clockwise as shown, negative clockwise)."""
        cal = self
        for _ in range(int(quarter_turns) % 4):
            w, _ = cal.size_px
            # Pixel (u, v) shows at (v, w - 1 - u); the camera's x axis is its old y, its
            # y axis its old -x.
            T = np.array([[0.0, 1, 0], [-1, 0, w - 1], [0, 0, 1]])
            R = np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])
            K, dist, size = quarter_turn(cal.intrinsics.K, cal.intrinsics.distortion, cal.size_px, clockwise=False)
            camera_from_floor = cal.camera_from_floor.copy()
            camera_from_floor[:3] = R @ camera_from_floor[:3]
            H = T @ cal.image_from_floor
            horizon = np.linalg.inv(T).T @ cal.horizon
            cal = replace(cal, size_px=size, intrinsics=replace(cal.intrinsics, K=K, distortion=dist),
                          camera_from_floor=camera_from_floor,
                          floor_plane_camera=np.append(R @ cal.floor_plane_camera[:3], cal.floor_plane_camera[3]),
                          image_from_floor=H / H[2, 2], horizon=horizon / np.hypot(horizon[0], horizon[1]),
                          corners_px=turn_points(cal.corners_px, 1, cal.size_px))
        return cal

    @property
    def roll_deg(self) -> float:
        """How far to turn the photo counter-clockwise, in degrees (-180 to 180), for the
        room to stand level in it, the floor toward its bottom: the camera's roll. A photo
        whose orientation was lost, or taken with the camera held sideways, shows the room
        turned by about a quarter or a half."""
        a, b = self.horizon[:2]  # toward the floor
        return float(np.degrees(np.arctan2(-a, b)))

    @property
    def upright_turns(self) -> int:
        """How many quarter turns (``np.rot90``'s k) bring the room nearest to level."""
        return round(self.roll_deg / 90) % 4

    @property
    def world_from_camera(self) -> np.ndarray:
        """Camera pose in the floor frame, (4, 4)."""
        return np.linalg.inv(self.camera_from_floor)

    def lens_maps(self, points_px: np.ndarray) -> np.ndarray:
        """(k,) bool: pixels (k, 2) the lens model undistorts, those nearer the principal
        point than where its radial distortion stops growing outward (a share
        ``CAMERA.calibrate.lens_reach_share`` of that radius: near it the mapping
        stretches without bound). A model fit from the board alone holds near the board
        and can turn back before the photo's corners; undistorting a pixel beyond gives a
        point anywhere."""
        pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
        K = self.intrinsics.K
        radius = np.hypot((pts[:, 0] - K[0, 2]) / K[0, 0], (pts[:, 1] - K[1, 2]) / K[1, 1])
        return radius < CAMERA.calibrate.lens_reach_share * _distortion_reach(self.intrinsics.distortion)

    def floor_from_pixels(self, points_px: np.ndarray) -> np.ndarray:
        """Floor coordinates (k, 2) meters of pixels (k, 2), distortion removed first
        (meaningless where the lens model does not reach: :meth:`lens_maps`)."""
        pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 1, 2)
        if np.any(self.intrinsics.distortion):
            pts = cv2.undistortPoints(pts, self.intrinsics.K, self.intrinsics.distortion, P=self.intrinsics.K)
        return cv2.perspectiveTransform(pts, np.linalg.inv(self.image_from_floor)).reshape(-1, 2)

    def pixels_from_floor(self, points_m: np.ndarray) -> np.ndarray:
        """Pixels (k, 2) of floor points (k, 2) or (k, 3) meters, with lens distortion."""
        p = np.asarray(points_m, dtype=np.float64)
        if p.shape[-1] == 2:
            p = np.column_stack([p, np.zeros(len(p))])
        R, t = self.camera_from_floor[:3, :3], self.camera_from_floor[:3, 3]
        px, _ = cv2.projectPoints(p.reshape(-1, 1, 3), cv2.Rodrigues(R)[0], t, self.intrinsics.K,
                                  self.intrinsics.distortion)
        return px.reshape(-1, 2)

    def to_json(self) -> dict:
        i = self.intrinsics
        return {
            "size_px": list(self.size_px),
            "intrinsics": {"K": i.K.tolist(), "distortion": i.distortion.tolist(), "source": i.source,
                           "focal_px": float(i.K[0, 0]), "focal_uncertainty": i.focal_uncertainty, "note": i.note},
            "camera_from_floor": self.camera_from_floor.tolist(),
            "camera_height_m": self.camera_height_m,
            "floor_plane_camera": self.floor_plane_camera.tolist(),
            "image_from_floor": self.image_from_floor.tolist(),
            "horizon": self.horizon.tolist(),
            "rms_px": self.rms_px,
            "detector": self.detector,
            "board": board_json(self.board),
            "corners_px": self.corners_px.round(3).tolist(),
            "corner_ids": self.corner_ids.tolist(),
            "warnings": list(self.warnings),
        }


def board_json(board: Board) -> dict:
    out = {"kind": board.kind, "inner_corners": [board.cols, board.rows], "square_mm": board.square_mm}
    if board.kind == "charuco":
        out["dictionary"] = CHARUCO_DICTIONARY
    return out


def quarter_turn(K: np.ndarray, dist: np.ndarray, size_px, clockwise: bool):
    """Intrinsics of the frame turned a quarter: K (3, 3), distortion and the new size.

    Turned clockwise, sensor pixel (u, v) shows at (h - 1 - v, u): the camera's x axis is
    its old -y and its y axis its old x, so fx and fy swap and the tangential terms
    become (p2, -p1); anticlockwise (u, v) shows at (v, w - 1 - u) and they become
    (-p2, p1). Radial terms do not change."""
    w, h = size_px
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    d = np.zeros(max(5, len(dist)))
    d[: len(dist)] = dist
    if np.any(d[8:]):
        raise CalibrationError("the profile's thin-prism or tilt terms cannot be turned; calibrate the camera "
                               "held the way the photo was taken")
    if clockwise:
        K2 = np.array([[fy, 0, h - 1 - cy], [0, fx, cx], [0, 0, 1.0]])
        d[2], d[3] = d[3], -d[2]
    else:
        K2 = np.array([[fy, 0, cy], [0, fx, w - 1 - cx], [0, 0, 1.0]])
        d[2], d[3] = -d[3], d[2]
    return K2, d[: max(5, len(dist))], (h, w)
