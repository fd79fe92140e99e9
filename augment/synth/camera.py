"""Where the photographer stands and where the board lies: hand-held phone cameras.

Cameras follow OpenCV: x right, y down, z forward; ``K`` has pixel centers at integers.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera.board import Board
from .rooms import Room, contains

CAMERA_HEIGHT_M = (1.0, 1.8)
PITCH_DOWN_DEG = (5.0, 40.0)
ROLL_DEG = (-5.0, 5.0)
HFOV_DEG = (50.0, 80.0)
# Landscape sizes of phone photos (4:3 and 16:9); portrait swaps them.
IMAGE_SIZES_PX = ((640, 480), (800, 600), (1024, 768), (1280, 720), (1280, 960),
                  (1600, 1200), (1920, 1080), (2016, 1512))
MIN_SQUARE_PX = 6.0
# Paper lies on the floor; rendering it this high keeps it from fighting with the floor's depth.
BOARD_LIFT_M = 0.001


@dataclass(frozen=True)
class Shot:
    """A camera: intrinsics, pose and image size.

    K : (3, 3) float64, pixels. world_from_camera : (4, 4) float64, meters.
    size_px : (width, height).
    """

    K: np.ndarray
    world_from_camera: np.ndarray
    size_px: tuple[int, int]

    @property
    def camera_from_world(self) -> np.ndarray:
        return np.linalg.inv(self.world_from_camera)

    def project(self, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project world points (k, 3): pixels (k, 2) and depth along the axis (k,) meters."""
        p = np.asarray(points_m, dtype=np.float64)
        cam = p @ self.camera_from_world[:3, :3].T + self.camera_from_world[:3, 3]
        uv = cam @ self.K.T
        return uv[:, :2] / uv[:, 2:3], cam[:, 2]

    def unproject(self, u_px: np.ndarray, v_px: np.ndarray, depth_m: np.ndarray) -> np.ndarray:
        """World points (k, 3) of pixels (k,) ``u_px``, ``v_px`` at depth along the axis ``depth_m`` (k,)."""
        rays = np.linalg.solve(self.K, np.stack([u_px, v_px, np.ones_like(u_px)]).astype(np.float64))
        cam = rays * np.asarray(depth_m, dtype=np.float64)
        return cam.T @ self.world_from_camera[:3, :3].T + self.world_from_camera[:3, 3]

    def in_view(self, points_m: np.ndarray) -> np.ndarray:
        """Whether each world point (k, 3) lies in front of the camera and inside the frame (k,)."""
        px, depth = self.project(points_m)
        width, height = self.size_px
        return (depth > 0) & (px[:, 0] >= 0) & (px[:, 0] < width) & (px[:, 1] >= 0) & (px[:, 1] < height)


def camera_matrix(width_px: int, height_px: int, hfov_rad: float) -> np.ndarray:
    """Square pixels, principal point at the image center, horizontal FOV ``hfov_rad``."""
    f = width_px / 2 / np.tan(hfov_rad / 2)
    return np.array([[f, 0, (width_px - 1) / 2], [0, f, (height_px - 1) / 2], [0, 0, 1.0]])


def look_pose(position_m, yaw_rad: float, pitch_down_rad: float, roll_rad: float) -> np.ndarray:
    """``world_from_camera`` for a camera at ``position_m`` looking along compass ``yaw_rad``
    (from +x, counter-clockwise), tilted down by ``pitch_down_rad``, rolled by ``roll_rad``
    (clockwise in the image)."""
    cy, sy = np.cos(yaw_rad), np.sin(yaw_rad)
    cp, sp = np.cos(pitch_down_rad), np.sin(pitch_down_rad)
    forward = np.array([cp * cy, cp * sy, -sp])
    right = np.array([sy, -cy, 0.0])
    down = np.cross(forward, right)
    cr, sr = np.cos(roll_rad), np.sin(roll_rad)
    right, down = cr * right + sr * down, -sr * right + cr * down
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([right, down, forward])
    pose[:3, 3] = position_m
    return pose


def board_pose(center_m, yaw_rad: float) -> np.ndarray:
    """``world_from_board`` for a board lying face up on the floor."""
    c, s = np.cos(yaw_rad), np.sin(yaw_rad)
    pose = np.eye(4)
    pose[:2, :2] = [[c, -s], [s, c]]
    pose[:3, 3] = [center_m[0], center_m[1], BOARD_LIFT_M]
    return pose


def random_size(rng: np.random.Generator) -> tuple[int, int]:
    w, h = IMAGE_SIZES_PX[rng.integers(len(IMAGE_SIZES_PX))]
    return (h, w) if rng.random() < 0.3 else (w, h)


def _camera_position(rng, room: Room):
    lo, hi = room.polygon_m.min(axis=0), room.polygon_m.max(axis=0)
    for _ in range(200):
        p = rng.uniform(lo, hi)
        if contains(room.polygon_m, p[None], margin_m=0.35)[0]:
            return p
    raise RuntimeError("no camera position inside the room")  # a 2.5 m room always has one


@dataclass(frozen=True)
class Handling:
    """How the photographer holds the phone: everything but where they stand and aim."""

    K: np.ndarray
    size_px: tuple[int, int]
    height_m: float
    pitch_down_rad: float
    roll_rad: float


def random_handling(rng: np.random.Generator, size_px: tuple[int, int]) -> Handling:
    """Lens (horizontal FOV 50-80 degrees), height 1.0-1.8 m, pitch 5-40 degrees down,
    roll within 5 degrees, all uniform."""
    width, height = size_px
    return Handling(camera_matrix(width, height, np.radians(rng.uniform(*HFOV_DEG))), (width, height),
                    float(rng.uniform(*CAMERA_HEIGHT_M)), float(np.radians(rng.uniform(*PITCH_DOWN_DEG))),
                    float(np.radians(rng.uniform(*ROLL_DEG))))


def random_shot(rng: np.random.Generator, room: Room, handling: Handling) -> Shot:
    """Stand somewhere inside ``room`` and aim across it, holding the phone as ``handling``."""
    xy = _camera_position(rng, room)
    # Photographers aim across the room, not at the nearest wall.
    lo, hi = room.polygon_m.min(axis=0), room.polygon_m.max(axis=0)
    target = xy
    for _ in range(50):
        t = rng.uniform(lo, hi)
        if np.linalg.norm(t - xy) > 1.5 and contains(room.polygon_m, t[None])[0]:
            target = t
            break
    yaw = np.arctan2(*(target - xy)[::-1]) + np.radians(rng.normal(0, 15))
    pose = look_pose([xy[0], xy[1], handling.height_m], yaw, handling.pitch_down_rad, handling.roll_rad)
    return Shot(handling.K, pose, handling.size_px)


def place_board(rng: np.random.Generator, room: Room, shot: Shot, board: Board,
                tries: int = 40) -> np.ndarray | None:
    """A ``world_from_board`` pose with the whole sheet on the floor and in view, its squares
    large enough to detect, or None when this shot cannot show it.
    """
    width, height = shot.size_px
    margin_px = max(8.0, 0.03 * max(width, height))
    # Squares smaller than this (along their foreshortened side) defeat corner detectors.
    # Small training frames only need the board visible: they get the framing of a 640 px
    # photo, scaled down.
    min_step_px = MIN_SQUARE_PX * min(1.0, max(width, height) / 640)
    # All candidates at once, tested in order: the first that passes every test wins.
    uv = rng.uniform([0.15 * width, 0.4 * height], [0.85 * width, 0.94 * height], size=(tries, 2))
    yaw = rng.uniform(0, 2 * np.pi, size=tries)
    R, origin = shot.world_from_camera[:3, :3], shot.world_from_camera[:3, 3]
    rays = np.column_stack([uv, np.ones(tries)]) @ np.linalg.inv(shot.K).T @ R.T
    down = rays[:, 2] < -1e-3
    centers = origin + rays * (-origin[2] / np.where(down, rays[:, 2], -1.0))[:, None]
    ok = down & (np.linalg.norm(centers[:, :2] - origin[:2], axis=1) <= 4.5)
    c, s_ = np.cos(yaw), np.sin(yaw)
    rot = np.stack([np.stack([c, -s_], -1), np.stack([s_, c], -1)], -2)  # (tries, 2, 2)
    outline = np.einsum("tij,kj->tki", rot, board.outline_m()[:, :2]) + centers[:, None, :2]
    ok &= contains(room.polygon_m, outline.reshape(-1, 2), margin_m=0.05).reshape(tries, 4).all(axis=1)
    lifted = np.concatenate([outline, np.full((tries, 4, 1), BOARD_LIFT_M)], axis=2)
    px, depth = shot.project(lifted.reshape(-1, 3))
    px, depth = px.reshape(tries, 4, 2), depth.reshape(tries, 4)
    ok &= (depth > 0.2).all(axis=1) & (px >= margin_px).all(axis=(1, 2)) \
        & (px[..., 0] <= width - 1 - margin_px).all(axis=1) & (px[..., 1] <= height - 1 - margin_px).all(axis=1)
    corners = board.corners_m()
    for t in np.flatnonzero(ok):
        pose = board_pose(centers[t], yaw[t])
        grid = shot.project(corners @ pose[:3, :3].T + pose[:3, 3])[0].reshape(board.rows, board.cols, 2)
        step = min(np.linalg.norm(np.diff(grid, axis=0), axis=-1).min(),
                   np.linalg.norm(np.diff(grid, axis=1), axis=-1).min())
        if step >= min_step_px:
            return pose
    return None
