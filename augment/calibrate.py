"""Camera and floor calibration from one photo with a checkerboard lying on the floor.

From the board Stager recovers the intrinsics (from a saved camera profile, the photo's
EXIF focal length, or the board itself), the camera's pose above the floor, the metric
scale and the floor plane: the map from pixels to floor meters that every later stage uses.

Conventions: images are (row, col) arrays, points are (x, y) pixels with pixel centers at
integers (OpenCV). The floor frame is the board's frame: origin at the center of the
squares, z up out of the floor, meters (see :mod:`augment.board`). Camera axes follow
OpenCV (x right, y down, z forward). Poses are 4x4 arrays named ``camera_from_floor``.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .board import CHARUCO_DICTIONARY, Board, charuco_board
from .height import LINE_SIDE_PX, detect_segments, floor_colored, is_vertical, toward_vanishing_point

# Tolerances and limits, in one place.
DETECT_MAX_SIDE_PX = 1280      # look for a checkerboard in a copy no larger than this
MIN_BOARD_EXTENT_PX = 60       # smaller boards give too few pixels for a pose
MIN_CHARUCO_CORNERS = 6        # a partly hidden ChArUco board needs this many corners, not in a line
MAX_RMS_PX = 2.0               # worse reprojection means a bent, moved or mis-sized board
# Single-view focal needs perspective: the board's normal must be tilted from the optical
# axis (a fronto-parallel board says nothing about f) but not so far that it is a sliver.
MIN_TILT_DEG = 15.0
MAX_TILT_DEG = 85.0
MAX_SINGLE_VIEW_UNCERTAINTY = 0.05   # relative focal uncertainty allowed before refusing
# Where people hold a phone to photograph a room: crouching to arms raised. Outside, the
# board's printed scale is the likelier mistake (a print scaled to fit the page, another
# board's --square): every length scales with it, the camera's height too.
CAMERA_HEIGHT_M = (0.3, 2.5)
USUAL_CAMERA_HEIGHT_M = (1.0, 1.8)  # standing, as most photos of a room are taken
# A crop keeps the whole frame's EXIF focal length (as do phones' modes that crop the
# sensor, when the maker does not restate it), which then does not fit the photo. Where
# the board's own view rules the EXIF value out by this many standard deviations of the
# two together, the board's is used. On 1,132 renders with their true focal length as
# EXIF the largest gap was 2.0 of them (a board's estimate 8.7 % off), on OpenCV's 26
# photos 1.5; OpenCV's photos cropped a quarter off their sides give 4-9 of them.
EXIF_GAP_SIGMAS = 3.0
# The focal length's deviation scales with the corners' noise, which the fit estimates from
# its residuals; with few corners (a partly hidden board) the fit absorbs much of the noise
# and the estimate comes out low. The noise is taken to be at least the corner accuracy the
# detectors reach on the synthetic renders (benchmarks/calibration.py): about 0.05 px RMS
# for checkerboard saddle points, 0.2 px for ChArUco corners (smaller windows, markers near).
CORNER_NOISE_FLOOR_PX = {"chessboard": 0.05, "charuco": 0.2}
# Corners are refined to the saddle point of the intensity in a window of this fraction of
# the corner spacing: 0.4 stays inside the squares next to a checkerboard corner; a
# ChArUco marker begins 1/8 of a square from each corner, so its window is smaller.
SADDLE_WINDOW = {"chessboard": 0.4, "charuco": 0.15}
MAX_SADDLE_RADIUS_PX = 24
# Now and then a detector puts a corner of a small board a quarter to two thirds of a
# square off, 2-8 px (25 of 837 renders of seeds 903-906, 930-936 and 960-961 had one over
# 2 px), and the saddle search started there does not reach the true corner; one such
# corner tipped the floor of seed 960 render 34 to the wrong tilt (area +340 %). Each
# corner is checked against where its neighbours put it (those up to OUTLIER_REACH
# corners away, through a homography: local, so that lens distortion does not matter);
# the worst one more than OUTLIER_SQUARES of the corner spacing off (and 1 px) is searched
# again from there, or else moved there, and the check repeats. On OpenCV's
# barrel-distorted photos the worst is 0.053 of a square.
OUTLIER_SQUARES, OUTLIER_REACH = 0.25, 2
# A detector can return a grid of the right size that is not the board's: on a small,
# blurred board SB once took the paper's edge for a row of corners at both ends, partly a
# square or two off (seed 937 render 61: 13.6 px; each corner consistent with its
# neighbours, so the mend above cannot see it, and the floor's tilt came out 31 degrees
# wrong). The squares such a grid outlines do not alternate dark and light as printed.
# Each square's middle (the middle half each way, through the homography of all corners)
# is compared with its neighbours: every inner square (between the inner corners) must
# differ from them the printed way by at least MIN_SQUARE_CONTRAST of the median inner
# difference. Over 320 renders the true grids' worst inner square reads 0.46 (a board
# partly behind a carton), the next 0.69; OpenCV's photos' 0.66; 937/61's grid -2.8.
# The ring of squares outside the inner corners is not judged: a carton over the board's
# edge hides it while the detector still finds every corner (seed [7, 60], 5 % hidden).
MIN_SQUARE_CONTRAST = 0.3
# A grid is a patch of a larger board when this share of the squares along a side of the
# next ring out alternates as printed (the side's end squares left out: they border the
# paper). Not all: a lens's distortion two squares past the grid, where the grid's
# homography is extrapolated, puts a square or two off.
GOES_ON_SHARE = 0.75
# When the whole photo yields no checkerboard, the strongest saddle points are grouped and
# the detectors rerun on crops around the largest groups (a small board in a big, busy
# photo is found far more often on its own), enlarged twice when its squares are small.
CROP_CANDIDATES = 3
CROP_MARGIN = 0.3              # of the group's extent, on each side
CROP_ZOOM_BELOW_PX = 16        # corner spacing under which a crop is also tried enlarged 2x
# A board far away or seen low is squashed along the view and often blurred, and then
# neither detector finds it on the crop (46 of 640 renders with the whole board in view,
# boards up to 180 px across). The group's saddle points show the squash: an affine map
# that makes their spread round undoes most of it, and the detectors run once more on
# that view, its corners this far apart (the first; the others where it fails: the
# detectors' luck turns with the scale on boards whose rows are 6-9 px apart).
RECTIFIED_SPACINGS_PX = (28.0, 20.0, 40.0)
# A small or far board is a nearly affine view of a plane, which two tilts explain about
# equally well (the planar pose ambiguity): on the synthetic renders the wrong one fit a
# little better in 1 of 857, and both were within 2x of each other's RMS in 18. Within
# this ratio the photo's vertical edges decide: the right tilt sends them to its vertical
# vanishing point (together at least this many photo sides long, twice the other's), and
# the pose is refit to the board and those edges together.
AMBIGUOUS_RMS_RATIO = 2.0
MIN_VERTICAL_SUPPORT = 0.25
VERTICAL_SUPPORT_RATIO = 2.0
LINE_NOISE_PX = 0.5            # least noise of a detected segment's end, in the detector's copy
FLOOR_SIDE_FRACTION = 0.004    # a segment's sides are read this far off it (x the longer side)
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
_SB_FLAGS = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE
_CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
# Board sizes people print; tried only to suggest a fix when the given size is not found.
_COMMON_SIZES = ((9, 6), (8, 6), (7, 5), (7, 6), (6, 4), (8, 5), (10, 7), (6, 9), (5, 7))
# 35 mm film's diagonal: "35 mm equivalent" focal lengths are scaled by diagonals.
_FILM_DIAGONAL_MM = float(np.hypot(36.0, 24.0))


class CalibrationError(ValueError):
    """A photo that cannot be calibrated; the message says why and what would work."""


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


# How far out, as a share of the radius where the lens model's distortion stops growing,
# a pixel is mapped to the floor: near that radius the mapping stretches without bound.
LENS_REACH_SHARE = 0.98


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
            K, dist, size = _quarter_turn(cal.intrinsics.K, cal.intrinsics.distortion, cal.size_px, clockwise=False)
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
        point than where its radial distortion stops growing outward. A model fit from
        the board alone holds near the board and can turn back before the photo's corners
        (OpenCV's left13: k1 -0.25, k2 -0.13 turn at 0.64 focal lengths, the corners lie
        at 0.74); undistorting a pixel beyond gives a point anywhere."""
        pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
        K = self.intrinsics.K
        radius = np.hypot((pts[:, 0] - K[0, 2]) / K[0, 0], (pts[:, 1] - K[1, 2]) / K[1, 1])
        return radius < LENS_REACH_SHARE * _distortion_reach(self.intrinsics.distortion)

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
            "board": _board_json(self.board),
            "corners_px": self.corners_px.round(3).tolist(),
            "corner_ids": self.corner_ids.tolist(),
            "warnings": list(self.warnings),
        }


def _board_json(board: Board) -> dict:
    out = {"kind": board.kind, "inner_corners": [board.cols, board.rows], "square_mm": board.square_mm}
    if board.kind == "charuco":
        out["dictionary"] = CHARUCO_DICTIONARY
    return out


@dataclass(frozen=True)
class BoardDetection:
    """The board's inner corners found in a photo.

    Attributes
    ----------
    corners_px : (n, 2) float64
        Corner positions, full resolution, refined to the saddle point of the intensity.
    ids : (n,) int64
        Which corner of the board each one is: the row of :meth:`Board.corners_m`. A
        checkerboard gives all ``cols * rows`` in the detector's order (which may read the
        board mirrored: :func:`calibrate_photo` settles that from the pose); a ChArUco
        board gives the corners it shows, at least ``MIN_CHARUCO_CORNERS``.
    detector : str
        ``"sb"`` or ``"classic"`` (OpenCV's checkerboard detectors), with ``" crop"`` when
        found only on a crop around the board, ``" rectified"`` when only on a view of it
        with its foreshortening undone (:func:`_find_rectified`); ``"charuco"``.
    """

    corners_px: np.ndarray
    ids: np.ndarray
    detector: str

    def object_points_m(self, board: Board) -> np.ndarray:
        """The detected corners in the board frame, (n, 3) meters."""
        return board.corners_m()[self.ids]


def _gray(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim == 2:
        return image if image.dtype == np.uint8 else cv2.convertScaleAbs(image)
    if image.ndim == 3 and image.shape[2] in (3, 4):
        return cv2.cvtColor(image[..., :3], cv2.COLOR_RGB2GRAY)
    raise ValueError(f"image of shape {image.shape}: expected (h, w) gray or (h, w, 3) RGB")


def corner_spacing_px(corners_px: np.ndarray, ids: np.ndarray, board: Board) -> float:
    """The smallest distance between detected corners that are neighbors on the board, px.

    Parameters
    ----------
    corners_px : (n, 2) float
    ids : (n,) int
        Board corner numbers (:class:`BoardDetection`).
    board : Board
    """
    corners = np.asarray(corners_px, dtype=np.float64).reshape(-1, 2)
    ids = np.asarray(ids, dtype=np.int64)
    grid = np.full((board.rows * board.cols, 2), np.nan)
    grid[ids] = corners
    grid = grid.reshape(board.rows, board.cols, 2)
    steps = np.concatenate([np.linalg.norm(np.diff(grid, axis=0), axis=-1).ravel(),
                            np.linalg.norm(np.diff(grid, axis=1), axis=-1).ravel()])
    steps = steps[np.isfinite(steps)]
    if len(steps):
        return float(steps.min())
    # No two neighbors (a sparse ChArUco view): the nearest pair, over its board distance.
    d_px = np.linalg.norm(corners[:, None] - corners[None], axis=-1)
    row, col = np.divmod(ids, board.cols)
    d_sq = np.hypot(row[:, None] - row[None], col[:, None] - col[None])
    np.fill_diagonal(d_sq, np.inf)
    return float(np.min(d_px / d_sq))


def _saddle_refine(gray: np.ndarray, corners: np.ndarray, radius: int) -> tuple[np.ndarray, np.ndarray]:
    """Corners moved to the saddle point of the intensity around them.

    A quadratic surface is fit by weighted least squares (Gaussian weights, sd half the
    radius) to a ``2 radius + 1`` window resampled centered on the current estimate, and
    the estimate moved to the surface's saddle point until it stops moving. The window is
    symmetric about the corner, so the blur and the tone curve of a photo, both symmetric
    about an X-junction, do not bias it; on the synthetic renders and OpenCV's photos it
    lands closer to the truth than ``cornerSubPix`` (whose 0.1-0.4 px errors on small,
    foreshortened boards cost several percent of focal length).

    Returns
    -------
    refined : (n, 2) float64
        Where a corner did not converge (no saddle, or it wandered off) its input is kept.
    converged : (n,) bool
    """
    n = 2 * radius + 1
    offsets = np.arange(-radius, radius + 1, dtype=np.float64)
    y, x = np.meshgrid(offsets, offsets, indexing="ij")
    x, y = x.ravel(), y.ravel()
    weight = np.exp(-(x * x + y * y) / (2 * (0.5 * radius) ** 2))
    fit = np.linalg.pinv(np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)]) * weight[:, None])
    image = gray.astype(np.float32)
    refined = np.array(corners, dtype=np.float64).reshape(-1, 2)
    converged = np.zeros(len(refined), bool)
    for k, start in enumerate(refined.copy()):
        p = start.copy()
        for _ in range(20):
            patch = cv2.getRectSubPix(image, (n, n), (float(p[0]), float(p[1])))
            a, b, c, d, e, _ = fit @ (patch.ravel().astype(np.float64) * weight)
            hessian = np.array([[2 * a, b], [b, 2 * c]])
            if np.linalg.det(hessian) >= 0:  # not a saddle
                break
            step = np.linalg.solve(hessian, -np.array([d, e]))
            p = p + step
            if np.abs(step).max() > radius or np.linalg.norm(p - start) > radius:
                break
            if np.linalg.norm(step) < 0.005:
                refined[k], converged[k] = p, True
                break
    return refined, converged


def _refine(gray: np.ndarray, corners: np.ndarray, ids: np.ndarray, board: Board) -> np.ndarray:
    """Full-resolution corners: saddle points; a checkerboard corner where no saddle
    converges falls back to ``cornerSubPix`` (ChArUco corners come refined by OpenCV)."""
    spacing = corner_spacing_px(corners, ids, board)
    radius = int(np.clip(round(SADDLE_WINDOW[board.kind] * spacing), 2, MAX_SADDLE_RADIUS_PX))
    refined, converged = _saddle_refine(gray, corners, radius)
    if board.kind == "chessboard" and not converged.all():
        # The search window must stay inside one square, or a neighbouring corner pulls.
        half = int(np.clip(0.4 * spacing, 2, 11))
        rest = cv2.cornerSubPix(gray, refined[~converged].reshape(-1, 1, 2).astype(np.float32), (half, half),
                                (-1, -1), _SUBPIX_CRITERIA)
        refined[~converged] = rest.reshape(-1, 2)
    return _mend_outliers(gray, refined, ids, board, spacing, radius)


def _neighbours_say(corners: np.ndarray, ids: np.ndarray, board: Board) -> np.ndarray:
    """(n, 2): where each corner's neighbours on the board (up to ``OUTLIER_REACH``
    corners away, the corner itself left out) put it through a homography; NaN where
    fewer than 6 are detected."""
    grid = np.column_stack(np.divmod(ids, board.cols))
    on_board = board.corners_m()[ids][:, :2]
    out = np.full((len(ids), 2), np.nan)
    for i in range(len(ids)):
        near = np.abs(grid - grid[i]).max(axis=1) <= OUTLIER_REACH
        near[i] = False
        if near.sum() < 6:
            continue
        H, _ = cv2.findHomography(on_board[near], corners[near], 0)
        if H is not None:
            out[i] = cv2.perspectiveTransform(on_board[i].reshape(1, 1, 2), H).reshape(2)
    return out


def _mend_outliers(gray: np.ndarray, corners: np.ndarray, ids: np.ndarray, board: Board, spacing: float,
                   radius: int) -> np.ndarray:
    """``corners`` with those far from where their neighbours put them searched again
    from there (``OUTLIER_SQUARES``), worst first."""
    corners = corners.copy()
    limit = max(OUTLIER_SQUARES * spacing, 1.0)
    mended = set()
    while len(mended) < len(ids) // 4:
        said = _neighbours_say(corners, ids, board)
        off = np.linalg.norm(said - corners, axis=1)
        if not np.isfinite(off).any():
            break
        i = int(np.nanargmax(off))
        if off[i] <= limit or i in mended:
            break
        mended.add(i)
        found, converged = _saddle_refine(gray, said[i][None], radius)
        near = converged[0] and np.linalg.norm(found[0] - said[i]) < limit
        corners[i] = found[0] if near else said[i]
    return corners


def square_contrast(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> np.ndarray:
    """How each square outlined by a checkerboard's corners differs from its neighbours,
    the way the printed board alternates, in units of the median inner square's difference.

    Parameters
    ----------
    gray : (h, w) uint8
    corners_px : (cols * rows, 2) float
        All inner corners, in :meth:`Board.corners_m` order (or the detector's: mirrored
        or turned readings give the same values).
    board : Board

    Returns
    -------
    (rows + 1, cols + 1) float64
        One per printed square, the ring outside the inner corners included: about 1 for a
        square as dark or light as printed against its neighbours, negative for one the
        wrong way round.
    """
    on_board = board.corners_m()[:, :2]
    H, _ = cv2.findHomography(on_board, np.asarray(corners_px, np.float64).reshape(-1, 2), 0)
    offsets = np.linspace(-0.25, 0.25, 3) * board.square_m
    du, dv = (a.ravel() for a in np.meshgrid(offsets, offsets))
    row, col = np.mgrid[-1:board.rows, -1:board.cols]
    x = ((col + 0.5 - (board.cols - 1) / 2) * board.square_m)[..., None] + du
    y = ((row + 0.5 - (board.rows - 1) / 2) * board.square_m)[..., None] + dv
    px = cv2.perspectiveTransform(np.stack([x, y], -1).reshape(-1, 1, 2), H).reshape(1, -1, 2).astype(np.float32)
    value = cv2.remap(gray, px[..., 0].copy(), px[..., 1].copy(), cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    value = value.reshape(board.rows + 1, board.cols + 1, -1).mean(axis=-1, dtype=np.float64)
    # Against the neighbours and relative to their brightness, not one threshold: a shadow
    # across the board darkens its white squares below the sunlit black ones.
    padded = np.pad(value, 1, constant_values=np.nan)
    around = np.nanmean([padded[:-2, 1:-1], padded[2:, 1:-1], padded[1:-1, :-2], padded[1:-1, 2:]], axis=0)
    parity = np.where((row + col) % 2 == 0, 1.0, -1.0)
    relative = parity * (value - around) / (value + around + 1.0)
    # Its sign says which squares are the black ones, which depends on how the detector
    # read the board.
    scale = np.median(relative[1:-1, 1:-1])
    return relative / (scale if scale != 0 else 1.0)


def squares_alternate(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> bool:
    """Whether the squares between a checkerboard's detected corners alternate as printed
    (``MIN_SQUARE_CONTRAST``): False for a grid a detector fit partly to something else.
    A grid read a whole square along everywhere still alternates, and passes."""
    return bool((square_contrast(gray, corners_px, board)[1:-1, 1:-1] >= MIN_SQUARE_CONTRAST).all())


def board_goes_on(gray: np.ndarray, corners_px: np.ndarray, board: Board) -> bool:
    """Whether the checkerboard goes on past the squares around the detected corners:
    along some side, most squares of the next ring out (``GOES_ON_SHARE``) alternate as
    printed (``MIN_SQUARE_CONTRAST``). Then the grid is a patch of a larger board (a 9x6 board
    given as 7x5, which the detectors find in it), not the board."""
    H, _ = cv2.findHomography(board.corners_m()[:, :2], np.asarray(corners_px, np.float64).reshape(-1, 2), 0)
    wider = Board(board.cols + 2, board.rows + 2, board.square_mm)  # its paper does not matter here
    wider_px = cv2.perspectiveTransform(wider.corners_m()[None, :, :2], H)[0]
    ring = square_contrast(gray, wider_px, wider) >= MIN_SQUARE_CONTRAST
    sides = (ring[0, 2:-2], ring[-1, 2:-2], ring[2:-2, 0], ring[2:-2, -1])
    return any(side.mean() >= GOES_ON_SHARE for side in sides)


def _is_the_board(gray: np.ndarray, corners, board: Board) -> bool:
    """Whether a detector's grid is the board: its squares alternate as printed, and it
    is not a patch of a larger board."""
    return squares_alternate(gray, corners, board) and not board_goes_on(gray, corners, board)


def _find_chessboard(gray: np.ndarray, board: Board):
    """Corners (cols * rows, 2) in ``gray`` or None, and which detector found them
    (:func:`_is_the_board`)."""
    pattern = (board.cols, board.rows)
    found, corners = cv2.findChessboardCornersSB(gray, pattern, flags=_SB_FLAGS)
    if found and _is_the_board(gray, corners, board):
        return corners.reshape(-1, 2).astype(np.float64), "sb"
    found, corners = cv2.findChessboardCorners(gray, pattern, flags=_CLASSIC_FLAGS)
    if found and _is_the_board(gray, corners, board):
        return corners.reshape(-1, 2).astype(np.float64), "classic"
    return None, None


def _saddle_points(gray: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` strongest saddle points (local maxima of ``-det(Hessian)``): (k, 2)
    pixels and their strengths. Checkerboard corners, black against white, top the list."""
    blurred = cv2.GaussianBlur(gray.astype(np.float32) / 255.0, (0, 0), 1.5)
    xx = cv2.Sobel(blurred, cv2.CV_32F, 2, 0, ksize=3)
    yy = cv2.Sobel(blurred, cv2.CV_32F, 0, 2, ksize=3)
    xy = cv2.Sobel(blurred, cv2.CV_32F, 1, 1, ksize=3)
    strength = np.maximum(xy * xy - xx * yy, 0)
    peaks = (strength == cv2.dilate(strength, np.ones((5, 5), np.uint8))) & (strength > 0)
    rows, cols = np.nonzero(peaks)
    order = np.argsort(-strength[rows, cols], kind="stable")[:count]
    return np.column_stack([cols[order], rows[order]]).astype(np.float64), strength[rows[order], cols[order]]


def _board_candidates(gray: np.ndarray, board: Board) -> list[tuple[np.ndarray, float]]:
    """Where a board may be: groups of strong saddle points, each as its strongest
    ``cols * rows`` points (k, 2) and their median nearest-neighbor distance, largest total
    strength first.

    Two saddle points join a group when they are closer than three times the nearer of
    their nearest-neighbor distances: a board's corners chain up along its rows and
    columns even when foreshortened 3:1, while stray saddles stay apart."""
    n = board.corner_count
    points, strength = _saddle_points(gray, 4 * n)
    if len(points) < max(n // 2, 2):
        return []
    # Neighbours from a k-d tree, groups as the linked graph's components: a board of
    # many corners gives thousands of points, too many for a dense distance matrix.
    tree = cKDTree(points)
    nearest = tree.query(points, k=2)[0][:, 1]
    balls = tree.query_ball_point(points, 3 * nearest)
    i = np.repeat(np.arange(len(points)), [len(b) for b in balls])
    j = np.concatenate(balls).astype(np.intp)
    keep = (i != j) & (np.linalg.norm(points[i] - points[j], axis=1) <= 3 * np.minimum(nearest[i], nearest[j]))
    links = coo_matrix((np.ones(int(keep.sum())), (i[keep], j[keep])), shape=(len(points), len(points)))
    label = connected_components(links, directed=False)[1]
    groups = []
    # Components in the order of their strongest point, as before (ties in total strength).
    for value in label[np.sort(np.unique(label, return_index=True)[1])]:
        # The group's strongest n: the board's corners, without the paper's edge and the
        # floor's grain that join it (points are sorted by strength).
        members = np.flatnonzero(label == value)[:n]
        if len(members) >= n // 2:
            groups.append((float(strength[members].sum()), points[members], float(np.median(nearest[members]))))
    groups.sort(key=lambda g: -g[0])
    return [(p, spacing) for _, p, spacing in groups[:CROP_CANDIDATES]]


def _find_in_crops(gray: np.ndarray, small: np.ndarray, scale: float, board: Board):
    """Corners found on crops of ``gray`` around the board candidates seen in ``small``."""
    height, width = gray.shape
    for points, spacing in _board_candidates(small, board):
        points = (points + 0.5) / scale - 0.5
        lo, hi = points.min(axis=0), points.max(axis=0)
        margin = CROP_MARGIN * (hi - lo).max() + 4
        x0, y0 = np.maximum(np.floor(lo - margin), 0).astype(int)
        x1, y1 = np.minimum(np.ceil(hi + margin), [width - 1, height - 1]).astype(int)
        crop = gray[y0:y1 + 1, x0:x1 + 1]
        zooms = (1, 2) if spacing / scale < CROP_ZOOM_BELOW_PX else (1,)
        for zoom in zooms:
            view = crop if zoom == 1 else cv2.resize(crop, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_CUBIC)
            corners, detector = _find_chessboard(view, board)
            if corners is not None:
                return (corners + 0.5) / zoom - 0.5 + [x0, y0], f"{detector} crop"
        corners, detector = _find_rectified(gray, points, board, (x0, y0, x1, y1))
        if corners is not None:
            return corners, f"{detector} rectified"
    return None, None


def _find_rectified(gray: np.ndarray, points: np.ndarray, board: Board, box: tuple[int, int, int, int]):
    """Corners found on an affine view of ``gray`` in which the saddle points ``points``
    (k, 2), a board candidate, spread evenly every way, mapped back to ``gray``; or None.
    The view holds all of ``box`` (x0, y0, x1, y1), the crop around them: cut shorter, a
    larger board (9x6 given as 7x5) shows a 7x5 patch of whole squares, which the
    detectors take for the board.

    A grid of cols x rows corners a unit apart spreads (cols^2 - 1) / 12 and
    (rows^2 - 1) / 12 along its sides; the view gives each direction the mean of the two,
    at each of ``RECTIFIED_SPACINGS_PX`` a unit in turn, so its squares come out within a
    factor of about 1.5 of square whatever the squash. The map is symmetric and positive:
    no mirror.
    """
    center = points.mean(axis=0)
    spread, axes = np.linalg.eigh(np.cov((points - center).T))
    if spread.min() <= 1e-6:
        return None, None
    even = axes @ np.diag(1 / np.sqrt(spread)) @ axes.T * np.sqrt((board.cols ** 2 + board.rows ** 2 - 2) / 24)
    x0, y0, x1, y1 = box
    corners_box = (np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]]) - center) @ even.T
    around = int(np.median(gray[y0:y1 + 1, x0:x1 + 1]))  # what the view shows past the crop
    for spacing in RECTIFIED_SPACINGS_PX:
        A = even * spacing
        lo, hi = corners_box.min(axis=0) * spacing, corners_box.max(axis=0) * spacing
        to_view = np.hstack([A, (-lo - A @ center)[:, None]])
        size = tuple(int(v) for v in np.ceil(hi - lo) + 1)
        view = cv2.warpAffine(gray, to_view, size, flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_CONSTANT,
                              borderValue=around)
        corners, detector = _find_chessboard(view, board)
        if corners is not None:
            back = cv2.invertAffineTransform(to_view)
            return corners @ back[:, :2].T + back[:, 2], detector
    return None, None


def _detect_chessboard(gray: np.ndarray, board: Board) -> BoardDetection | None:
    scale = min(1.0, DETECT_MAX_SIDE_PX / max(gray.shape))
    small = gray if scale == 1.0 else cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    corners, detector = _find_chessboard(small, board)
    if corners is not None:
        # Map pixel centers of the small copy back: x_full = (x_small + 0.5) / scale - 0.5.
        corners = (corners + 0.5) / scale - 0.5
    else:
        corners, detector = _find_in_crops(gray, small, scale, board)
        if corners is None:
            return None
    ids = np.arange(board.corner_count)
    return BoardDetection(_refine(gray, corners, ids, board), ids, detector)


def _charuco_detector(board: Board):
    params = cv2.aruco.DetectorParameters()
    params.minMarkerPerimeterRate = 0.01  # markers of a board across the room are small
    charuco = cv2.aruco.CharucoParameters()
    charuco.tryRefineMarkers = True      # look again for missed markers where the board says
    return cv2.aruco.CharucoDetector(charuco_board(board.cols, board.rows), charuco, params)


def _detect_charuco(gray: np.ndarray, board: Board) -> BoardDetection | None:
    # Full resolution: marker bits are small, and reading them is cheap.
    corners, charuco_ids, _, _ = _charuco_detector(board).detectBoard(gray)
    if charuco_ids is None or len(charuco_ids) < MIN_CHARUCO_CORNERS:
        return None
    if charuco_board(board.cols, board.rows).checkCharucoCornersCollinear(charuco_ids):
        return None
    ids = board.corner_ids(charuco_ids)
    corners = corners.reshape(-1, 2).astype(np.float64)
    order = np.argsort(ids)
    ids, corners = ids[order], corners[order]
    return BoardDetection(_refine(gray, corners, ids, board), ids, "charuco")


def detect_board(image: np.ndarray, board: Board) -> BoardDetection | None:
    """Find the board's inner corners.

    A checkerboard is looked for in a copy at most ``DETECT_MAX_SIDE_PX`` on its long side
    (OpenCV's SB detector, then the classic one); when neither finds it, on crops around
    the strongest groups of saddle points, at full resolution and enlarged (small,
    foreshortened boards in large photos). A checkerboard grid whose inner squares do not
    alternate as printed (:func:`squares_alternate`) is passed over. A ChArUco board's
    markers are read at full resolution; any ``MIN_CHARUCO_CORNERS`` corners not in a line
    will do. Corners are then refined at full resolution to the saddle point of the
    intensity.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        Gray or RGB photo. Not modified.
    board : Board

    Returns
    -------
    BoardDetection or None
        None when no board of this kind and size is in the photo.
    """
    gray = _gray(image)
    if board.kind == "charuco":
        return _detect_charuco(gray, board)
    return _detect_chessboard(gray, board)


def _suggest_board(image: np.ndarray, board: Board) -> str | None:
    """A ``--board`` value that would find a board in this photo, or None."""
    gray = _gray(image)
    scale = min(1.0, 800 / max(gray.shape))
    small = cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA) if scale < 1 else gray
    if board.kind == "chessboard":
        # ChArUco markers of Stager's dictionary: the board is a ChArUco one.
        markers = cv2.aruco.ArucoDetector(charuco_board(board.cols, board.rows).getDictionary()).detectMarkers(gray)[1]
        if markers is not None and len(markers) >= 4:
            return f"charuco:{board.cols}x{board.rows}"
    for size in ((board.cols, board.rows),) + _COMMON_SIZES:
        if board.kind == "chessboard" and size in ((board.cols, board.rows), (board.rows, board.cols)):
            continue
        ok, _ = cv2.findChessboardCorners(small, size, flags=_CLASSIC_FLAGS | cv2.CALIB_CB_FAST_CHECK)
        if ok:
            return f"{size[0]}x{size[1]}"
    return None


def _focal_from_homography(H: np.ndarray) -> float | None:
    """Closed-form f from a plane homography whose image coordinates are centered on the
    principal point, assuming square pixels and no skew (Zhang's two constraints).

    Returns None when the view carries no focal information (fronto-parallel)."""
    h1, h2 = H[:, 0], H[:, 1]
    # Rows: h1' w h2 = 0 and h1' w h1 - h2' w h2 = 0 with w = diag(x, x, 1), x = 1 / f^2.
    A = np.array([h1[0] * h2[0] + h1[1] * h2[1], h1[0] ** 2 + h1[1] ** 2 - h2[0] ** 2 - h2[1] ** 2])
    b = -np.array([h1[2] * h2[2], h1[2] ** 2 - h2[2] ** 2])
    x = float(A @ b / (A @ A)) if A @ A > 0 else -1.0
    return 1.0 / np.sqrt(x) if x > 0 else None


def _fit_focal(obj, corners_px, size_px, f0, center, radial: bool):
    """LM refinement of f (and k1, k2 when ``radial``) with the pose; principal point fixed."""
    flags = (cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_PRINCIPAL_POINT | cv2.CALIB_FIX_ASPECT_RATIO
             | cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K3)
    if not radial:
        flags |= cv2.CALIB_FIX_K1 | cv2.CALIB_FIX_K2
    K = np.array([[f0, 0, center[0]], [0, f0, center[1]], [0, 0, 1.0]])
    rms, K, dist, rvecs, _, std, _, _ = cv2.calibrateCameraExtended(
        [obj.astype(np.float32)], [corners_px.reshape(-1, 1, 2).astype(np.float32)], size_px, K,
        np.zeros(5), flags=flags)
    # With a fixed aspect ratio OpenCV reports the deviation on fx or fy, depending on version.
    f_std = float(np.nanmax(std[:2, 0]))
    return float(rms), K, dist.ravel(), cv2.Rodrigues(rvecs[0])[0], f_std


def single_view_intrinsics(corners_px: np.ndarray, board: Board, size_px: tuple[int, int],
                           ids: np.ndarray | None = None) -> Intrinsics:
    """Focal length from the board alone: principal point at the image center, square
    pixels. A closed form from the board homography starts a Levenberg-Marquardt fit of f
    with the pose (``calibrateCameraExtended``). When the lens bends straight lines (the
    fit without distortion leaves more than 0.5 px of error and a radial model removes a
    third of it) the radial terms k1 and k2 are fit too: without them a barrel lens biases
    f by tens of percent, and k1 alone leaves a few percent (OpenCV's photos: the largest
    focal error falls from 5.3 to 4.6 %).

    The uncertainty combines the fit's standard deviation (its corner noise at least
    ``CORNER_NOISE_FLOOR_PX``) with the change in f when the principal point moves by 2 % of
    the image (phones are not exactly centered).

    Parameters
    ----------
    corners_px : (n, 2) float64
        Detected corners (undistorted model: no lens correction applied).
    board : Board
    size_px : (width, height)
    ids : (n,) int, optional
        Which board corners they are (:class:`BoardDetection`); all, in order, when None.

    Raises
    ------
    CalibrationError
        When the board is seen nearly face-on or nearly edge-on, or f is too uncertain.
    """
    width, height = size_px
    center = np.array([(width - 1) / 2, (height - 1) / 2])
    corners_px = np.asarray(corners_px, dtype=np.float64).reshape(-1, 2)
    obj = board.corners_m()[np.arange(board.corner_count) if ids is None else np.asarray(ids)]
    H, _ = cv2.findHomography(obj[:, :2], corners_px - center)
    f0 = None if H is None else _focal_from_homography(H)
    advice = ("Give the camera's focal length another way: a photo with EXIF data, or a camera "
              "profile from `stage calibrate shots/*.jpg` (--camera profile.json).")
    if f0 is None or not (0.2 * max(size_px) < f0 < 10 * max(size_px)):
        # Little perspective: a face-on board, or a small, far one (nearly an affine view).
        # An affine fit's foreshortening tells them apart: its singular values' ratio is the
        # cosine of the board's tilt from the view direction.
        affine, _ = cv2.estimateAffine2D(obj[:, :2].astype(np.float32), corners_px.astype(np.float32))
        ratio = np.linalg.svd(affine[:, :2], compute_uv=False) if affine is not None else np.ones(2)
        tilt_deg = float(np.degrees(np.arccos(min(1.0, ratio[1] / ratio[0]))))
        if tilt_deg >= MIN_TILT_DEG:
            extent = corners_px.max(axis=0) - corners_px.min(axis=0)
            raise CalibrationError(
                f"the board is too small in the photo ({extent.max():.0f} px across a {max(size_px)} px photo) "
                f"for its perspective to tell the focal length, though it is tilted about {tilt_deg:.0f} degrees. "
                f"Lay it nearer the camera, or: {advice}")
        raise CalibrationError(
            "the board is seen almost face-on, so its perspective does not tell the focal length. "
            "Take the photo from standing height looking across the floor (the board well "
            f"foreshortened), or: {advice}")
    fit = _fit_focal(obj, corners_px, size_px, f0, center, radial=False)
    use_radial = False
    if fit[0] > 0.5:
        radial = _fit_focal(obj, corners_px, size_px, f0, center, radial=True)
        if radial[0] < (2 / 3) * fit[0]:
            fit, use_radial = radial, True
    rms, K, dist, R, f_std = fit
    f = float(K[0, 0])
    tilt_deg = float(np.degrees(np.arccos(min(1.0, abs(R[2, 2])))))
    if tilt_deg < MIN_TILT_DEG or tilt_deg > MAX_TILT_DEG:
        what = "almost face-on" if tilt_deg < MIN_TILT_DEG else "almost edge-on"
        raise CalibrationError(
            f"the board is seen {what} (tilted {tilt_deg:.0f} degrees from the view direction; "
            f"a single photo needs {MIN_TILT_DEG:.0f}-{MAX_TILT_DEG:.0f}) to measure the focal length. {advice}")
    shifted = []
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        c = center + 0.02 * np.array([dx * width, dy * height])
        shifted.append(abs(_fit_focal(obj, corners_px, size_px, f, c, use_radial)[1][0, 0] - f) / f)
    f_std *= max(1.0, CORNER_NOISE_FLOOR_PX[board.kind] / max(rms, 1e-12))
    uncertainty = float(np.hypot(f_std / f if np.isfinite(f_std) else np.inf, max(shifted)))
    if not uncertainty <= MAX_SINGLE_VIEW_UNCERTAINTY:
        raise CalibrationError(
            f"the focal length from this single view is uncertain by {100 * uncertainty:.0f} % "
            f"(at most {100 * MAX_SINGLE_VIEW_UNCERTAINTY:.0f} % is accepted). {advice}")
    note = f"board tilted {tilt_deg:.0f} degrees; principal point assumed at the image center"
    if use_radial:
        note += f"; lens distortion k1 = {dist[0]:.3f}, k2 = {dist[1]:.3f} fit from the board"
    return Intrinsics(K, dist if use_radial else np.zeros(5), "single-view", uncertainty, note)


def _exif(path) -> tuple[dict, dict]:
    """The EXIF tags of an image file (HEIC too): its main directory and its Exif
    sub-directory, both empty when it has none or cannot be opened."""
    from .imageio import pillow_open

    try:
        with pillow_open(path) as im:
            exif = im.getexif()
            return dict(exif), dict(exif.get_ifd(0x8769))
    except (OSError, ValueError):
        return {}, {}


def exif_focal_px(path, size_px: tuple[int, int]) -> float | None:
    """Focal length in pixels from the EXIF 35 mm equivalent focal length, or None."""
    main, sub = _exif(path)
    f35 = sub.get(0xA405) or main.get(0xA405)
    if not f35:
        return None
    return float(f35) / _FILM_DIAGONAL_MM * float(np.hypot(*size_px))


def exif_intrinsics(focal_px: float, size_px: tuple[int, int]) -> Intrinsics:
    width, height = size_px
    K = np.array([[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1.0]])
    # Makers round 35 mm equivalents to whole millimeters and crop differently: ~3 %.
    return Intrinsics(K, np.zeros(5), "exif", 0.03, "EXIF 35 mm equivalent focal length; principal point at center")


def exif_orientation(path) -> int | None:
    """The EXIF orientation tag of an image file (1-8), or None."""
    value = _exif(path)[0].get(0x0112)
    return int(value) if value else None


def _quarter_turn(K: np.ndarray, dist: np.ndarray, size_px, clockwise: bool):
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


def load_profile(path, size_px: tuple[int, int], orientation: int | None = None) -> Intrinsics:
    """Intrinsics from a camera profile JSON (``stage calibrate``), scaled to ``size_px``.

    A photo whose frame is the profile's turned a quarter (the phone held the other way)
    gets the turned intrinsics: ``orientation``, the photo's EXIF orientation tag, says
    which way (6 clockwise, 8 anticlockwise; clockwise when it does not say, and the
    note tells).

    Raises
    ------
    CalibrationError
        When the file is unreadable, lacks a field, or was made for another aspect ratio.
    """
    path = Path(path)
    remake = "make it again with `stage calibrate`"
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise CalibrationError(f"camera profile {path} does not exist; make one with `stage calibrate`") from None
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as error:
        # RecursionError: JSON nested thousands deep is no profile either.
        raise CalibrationError(f"camera profile {path}: cannot read it as JSON ({type(error).__name__}: "
                               f"{str(error)[:120]}); expected the JSON written by `stage calibrate`") from None
    if not isinstance(data, dict):
        raise CalibrationError(f"camera profile {path}: holds a JSON {type(data).__name__}, not the object with "
                               f"fields K, distortion, size_px that `stage calibrate` writes; {remake}")
    missing = [field for field in ("K", "distortion", "size_px") if field not in data]
    if missing:
        raise CalibrationError(f"camera profile {path}: lacks the field{'s' * (len(missing) > 1)} "
                               f"{', '.join(missing)}; {remake}")
    try:
        K = np.array(data["K"], dtype=np.float64).reshape(3, 3)
        dist = np.array(data["distortion"], dtype=np.float64).ravel()
        w0, h0 = data["size_px"]
    except (ValueError, TypeError):
        raise CalibrationError(f"camera profile {path}: K must be 3 rows of 3 numbers, distortion a list of "
                               f"numbers and size_px [width, height] (K = {str(data['K'])[:60]}, distortion = "
                               f"{str(data['distortion'])[:60]}, size_px = {str(data['size_px'])[:30]}); "
                               f"{remake}") from None
    if not (np.isfinite(K).all() and np.isfinite(dist).all()):
        problem = "K and distortion hold a number that is not finite"
    elif not (K[0, 0] > 0 and K[1, 1] > 0):
        problem = f"focal lengths K[0][0] = {K[0, 0]:g} and K[1][1] = {K[1, 1]:g} must be positive"
    elif not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in (w0, h0)):
        problem = f"size_px {data['size_px']!r} must be the photos' width and height, whole pixels"
    elif type(data.get("rms_px", 0.0)) not in (int, float):
        problem = f"rms_px {str(data['rms_px'])[:30]} must be a number (the calibration's error in pixels)"
    else:
        problem = None
    if problem is not None:
        raise CalibrationError(f"camera profile {path}: {problem}; {remake}")
    rms = float(data.get("rms_px", 0.0))
    note = f"camera profile {path.name} (RMS {rms:.2f} px)"
    width, height = size_px
    if abs(w0 / h0 - width / height) > 0.01 and abs(h0 / w0 - width / height) <= 0.01:
        K, dist, (w0, h0) = _quarter_turn(K, dist, (w0, h0), clockwise=orientation != 8)
        way = {6: "clockwise (EXIF)", 8: "anticlockwise (EXIF)"}.get(orientation, "clockwise (assumed: no EXIF "
                                                                                   "orientation)")
        note += f", turned a quarter {way}"
    if (w0, h0) != (width, height):
        if abs(w0 / h0 - width / height) > 0.01:
            raise CalibrationError(
                f"camera profile {path} was made from {w0}x{h0} photos, this photo is {width}x{height}: "
                "a different aspect ratio (another camera mode or a cropped photo); calibrate this mode")
        s = width / w0
        K = K.copy()
        K[:2, :] *= s
        # Pixel centers at integers: the image edge, at -0.5, is what scales.
        K[:2, 2] += 0.5 * s - 0.5
    return Intrinsics(K, dist, "profile", float(data.get("focal_uncertainty", 0.005)), note)


def _pose(detection: BoardDetection, board: Board, intrinsics: Intrinsics):
    """camera_from_board (4, 4) and the corner ids, read so that board z faces the camera."""
    K, dist = intrinsics.K, intrinsics.distortion
    ids = detection.ids
    for attempt in range(2):
        obj = board.corners_m()[ids]
        ok, rvec, tvec = cv2.solvePnP(obj, detection.corners_px, K, dist, flags=cv2.SOLVEPNP_ITERATIVE)
        rvec, tvec = cv2.solvePnPRefineLM(obj, detection.corners_px, K, dist, rvec, tvec)
        R = cv2.Rodrigues(rvec)[0]
        camera_in_board = -R.T @ tvec.ravel()
        if camera_in_board[2] > 0 or board.kind == "charuco":
            break  # ChArUco ids are printed on the board: never mirrored
        # A checkerboard detector may read the rows in the mirrored order: the board frame
        # would point into the floor. Reading the rows the other way flips it.
        row, col = np.divmod(ids, board.cols)
        ids = (board.rows - 1 - row) * board.cols + col
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, tvec.ravel()
    return pose, ids


def _pose_rms(obj: np.ndarray, corners_px: np.ndarray, pose: np.ndarray, intrinsics: Intrinsics) -> float:
    projected, _ = cv2.projectPoints(obj, cv2.Rodrigues(pose[:3, :3])[0], pose[:3, 3], intrinsics.K,
                                     intrinsics.distortion)
    return float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - corners_px) ** 2, axis=1))))


def tilt_readings(corners_px: np.ndarray, obj_m: np.ndarray, intrinsics: Intrinsics
                  ) -> list[tuple[np.ndarray, float]]:
    """Both poses a planar board's corners allow, each refined, with its RMS.

    Parameters
    ----------
    corners_px : (n, 2) float64
        Detected corners, pixels.
    obj_m : (n, 3) float64
        The same corners on the board (z = 0), meters.
    intrinsics : Intrinsics

    Returns
    -------
    list of (camera_from_board (4, 4), rms_px), best fit first; only poses that put the
    camera on the printed side of the board.
    """
    corners = np.ascontiguousarray(corners_px, dtype=np.float64)
    obj = np.ascontiguousarray(obj_m, dtype=np.float64)
    K, dist = intrinsics.K, intrinsics.distortion
    _, rvecs, tvecs, _ = cv2.solvePnPGeneric(obj, corners, K, dist, flags=cv2.SOLVEPNP_IPPE)
    readings = []
    for rvec, tvec in zip(rvecs, tvecs):
        rvec, tvec = cv2.solvePnPRefineLM(obj, corners, K, dist, rvec.copy(), tvec.copy())
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
        # IPPE returns NaN for some exact (noise-free) views.
        if np.isfinite(pose).all() and (-pose[:3, :3].T @ pose[:3, 3])[2] > 0:
            readings.append((pose, _pose_rms(obj, corners, pose, intrinsics)))
    return sorted(readings, key=lambda r: r[1])


def vertical_support(segments_px: np.ndarray, K: np.ndarray, poses: list[np.ndarray], side_px: int) -> np.ndarray:
    """How much of the photo's straight edges each pose's floor normal explains.

    Parameters
    ----------
    segments_px : (n, 4) float64
        Line segments ``x1, y1, x2, y2`` (:func:`augment.height.detect_segments`), pixels.
    K : (3, 3) float64
    poses : list of (4, 4) camera_from_floor
    side_px : int
        The photo's longer side.

    Returns
    -------
    (len(poses),) float64
        Total length of the segments that pass :mod:`augment.height`'s test for a vertical
        edge under each pose, in photo sides.
    """
    length = np.hypot(segments_px[:, 2] - segments_px[:, 0], segments_px[:, 3] - segments_px[:, 1])
    return np.array([length[is_vertical(segments_px, K, pose, side_px)].sum() / side_px for pose in poses])


def _vertical_residuals_px(segments_px: np.ndarray, K: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Distances (2n,) of the segments' ends from the lines joining their midpoints to the
    vertical vanishing point ``K R e3``."""
    mid = (segments_px[:, :2] + segments_px[:, 2:]) / 2
    toward = toward_vanishing_point(mid, K @ R[:, 2])
    across = np.column_stack([-toward[:, 1], toward[:, 0]])
    return np.concatenate([np.sum((segments_px[:, :2] - mid) * across, axis=1),
                           np.sum((segments_px[:, 2:] - mid) * across, axis=1)])


def _fit_with_verticals(obj_m: np.ndarray, corners_px: np.ndarray, intrinsics: Intrinsics, pose: np.ndarray,
                        segments_px: np.ndarray, corner_sigma_px: float, line_sigma_px: float) -> np.ndarray:
    """Gauss-Newton on the board's corners and the vertical edges together, each residual
    divided by its noise, from ``pose``."""
    K, dist = intrinsics.K, intrinsics.distortion

    def residuals(x):
        projected, _ = cv2.projectPoints(obj_m, x[:3], x[3:], K, dist)
        return np.concatenate([(projected.reshape(-1, 2) - corners_px).ravel() / corner_sigma_px,
                               _vertical_residuals_px(segments_px, K, cv2.Rodrigues(x[:3])[0]) / line_sigma_px])

    x = np.concatenate([cv2.Rodrigues(pose[:3, :3])[0].ravel(), pose[:3, 3]])
    step = np.concatenate([np.full(3, 1e-7), np.full(3, 1e-7 * max(1.0, float(np.linalg.norm(x[3:]))))])
    for _ in range(10):
        r = residuals(x)
        J = np.column_stack([(residuals(x + np.eye(6)[k] * step[k]) - r) / step[k] for k in range(6)])
        delta = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + delta
        if np.abs(delta[:3]).max() < 1e-9:
            break
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = cv2.Rodrigues(x[:3])[0], x[3:]
    return out


def _on_the_floor(image: np.ndarray, segments_px: np.ndarray, K: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """(n,) bool: segments with the floor's colour on both sides (planks, tile joints)."""
    start, end = segments_px[:, None, :2], segments_px[:, None, 2:]
    along = np.linspace(0.1, 0.9, 7)[None, :, None]
    points = start + along * (end - start)
    direction = (end - start)[:, 0]
    across = np.column_stack([-direction[:, 1], direction[:, 0]])
    across /= np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)
    offset = (FLOOR_SIDE_FRACTION * max(np.asarray(image).shape[:2])) * across[:, None, :]
    return floor_colored(image, np.concatenate([points - offset, points + offset], axis=1), K, pose)


def _wall_edges(segments_px: np.ndarray, K: np.ndarray, pose: np.ndarray, side_px: int,
                on_floor: np.ndarray) -> np.ndarray:
    """(n,) bool: segments that can be vertical edges and are not lines on the floor.

    Planks and tiles running away from the camera pass the vertical test too (a floor
    line straight away from the camera images through the vertical vanishing point), give
    or take a few pixels over a long segment. What rises above the horizon is not on the
    floor; below it, a segment with the floor's colour on both sides is taken to be.
    """
    rays = np.column_stack([segments_px.reshape(-1, 2), np.ones(2 * len(segments_px))]) @ np.linalg.inv(K).T
    rises = (rays @ pose[:3, 2]).reshape(-1, 2).max(axis=1) > 0
    return (rises | ~on_floor) & is_vertical(segments_px, K, pose, side_px)


def _level_with_verticals(image: np.ndarray, obj_m: np.ndarray, corners_px: np.ndarray, intrinsics: Intrinsics,
                          pose: np.ndarray, segments_px: np.ndarray, side_px: int) -> np.ndarray:
    """The pose refit to the board and the photo's vertical edges together.

    Where the board cannot fix the tilt well (its two readings fit nearly alike), a few
    long vertical edges can. The edges are reselected under each refit. Each residual is
    divided by its noise: the corners' from their fit, the edges' from theirs, at least
    ``LINE_NOISE_PX`` of the detector's shrunk copy.
    """
    corner_sigma = max(_pose_rms(obj_m, corners_px, pose, intrinsics), CORNER_NOISE_FLOOR_PX["chessboard"])
    line_floor = LINE_NOISE_PX * max(1.0, side_px / LINE_SIDE_PX)
    line_sigma = corner_sigma  # first refit: edges weigh like corners
    on_floor = _on_the_floor(image, segments_px, intrinsics.K, pose)
    for _ in range(4):
        vertical = segments_px[_wall_edges(segments_px, intrinsics.K, pose, side_px, on_floor)]
        if len(vertical) == 0:
            break
        pose = _fit_with_verticals(obj_m, corners_px, intrinsics, pose, vertical, corner_sigma, line_sigma)
        line_sigma = max(float(np.sqrt(np.mean(_vertical_residuals_px(vertical, intrinsics.K, pose[:3, :3]) ** 2))),
                         line_floor)
    return pose


def _settle_tilt(image: np.ndarray, corners_px: np.ndarray, obj_m: np.ndarray, intrinsics: Intrinsics,
                 pose: np.ndarray, warnings: list) -> np.ndarray:
    """``pose``, unless the board's fit cannot tell its two tilts apart: then the tilt the
    photo's vertical edges side with, refit to them and the board together."""
    readings = tilt_readings(corners_px, obj_m, intrinsics)
    if len(readings) < 2 or readings[1][1] > AMBIGUOUS_RMS_RATIO * max(readings[0][1], 1e-6):
        return pose
    segments = detect_segments(image)
    side = max(np.asarray(image).shape[:2])
    support = vertical_support(segments, intrinsics.K, [r[0] for r in readings], side)
    best = int(np.argmax(support))
    if support[best] >= MIN_VERTICAL_SUPPORT and support[best] >= VERTICAL_SUPPORT_RATIO * support[1 - best]:
        return _level_with_verticals(image, obj_m, corners_px, intrinsics, readings[best][0], segments, side)
    (_, rms0), (_, rms1) = readings
    warnings.append(f"the board is too small in the photo to fix the floor's tilt for sure: two tilts fit it "
                    f"(RMS {rms0:.2f} and {rms1:.2f} px) and the photo's vertical edges do not tell them apart; "
                    "the better fit was taken. A board nearer the camera, or larger, settles it")
    return pose


def calibrate_photo(image: np.ndarray, board: Board, *, intrinsics: Intrinsics | None = None,
                    where: str = "the photo") -> Calibration:
    """Calibrate one photo: detect the board, settle the intrinsics, solve the pose.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        The photo (RGB or gray). Not modified.
    board : Board
    intrinsics : Intrinsics, optional
        From a profile or EXIF; estimated from the board when None.
    where : str
        How to name the photo in messages (its path).

    Raises
    ------
    CalibrationError
        No board, a board too small, a view that cannot give the focal length, or a fit
        too poor to trust; the message says what to change.
    """
    height, width = np.asarray(image).shape[:2]
    size_px = (width, height)
    detection = detect_board(image, board)
    if detection is None:
        other = _suggest_board(image, board)
        if other is not None:
            hint = f" The photo shows a board that --board {other} finds: use --board {other}."
        elif board.kind == "charuco":
            hint = (f" Check --board: it counts inner corners (where four squares meet), not squares, and "
                    f"at least {MIN_CHARUCO_CORNERS} corners with their markers must be visible and sharp.")
        else:
            hint = (" Check --board: it counts inner corners (where four squares meet), "
                    "not squares; a board of 8 x 6 squares is --board 7x5.")
        if board.kind == "chessboard":
            hint += (f" The whole board must be in view (a ChArUco board, --board charuco:{board.cols}x{board.rows}, "
                     "may be partly hidden).")
        tried = ("OpenCV's ChArUco detector" if board.kind == "charuco"
                 else "OpenCV's SB and classic detectors, on the whole photo and on crops")
        raise CalibrationError(f"no {board.describe()} found in {where} (tried {tried}).{hint} "
                               "It must lie flat and not be glared.")
    extent = detection.corners_px.max(axis=0) - detection.corners_px.min(axis=0)
    if extent.max() < MIN_BOARD_EXTENT_PX:
        raise CalibrationError(
            f"the board in {where} is only {extent.max():.0f} px across (at least {MIN_BOARD_EXTENT_PX} needed): "
            "move the board closer to the camera or use a larger board")
    warnings = []
    exif_ruled_out = False
    if intrinsics is None:
        intrinsics = single_view_intrinsics(detection.corners_px, board, size_px, detection.ids)
    elif intrinsics.source == "exif":
        chosen = _exif_or_board(intrinsics, detection, board, size_px, where, warnings)
        exif_ruled_out, intrinsics = chosen is not intrinsics, chosen
    camera_from_floor, ids = _pose(detection, board, intrinsics)
    corners = detection.corners_px
    camera_from_floor = _settle_tilt(image, corners, board.corners_m()[ids], intrinsics, camera_from_floor, warnings)
    rms = _pose_rms(board.corners_m()[ids], corners, camera_from_floor, intrinsics)
    if rms > MAX_RMS_PX:
        raise CalibrationError(
            f"the board in {where} fits its model with an RMS of {rms:.2f} px (at most {MAX_RMS_PX} accepted): "
            "the board may be bent or not flat on the floor, or --square/--board may not match the print"
            + (f"; or the photo's EXIF focal length ({intrinsics.K[0, 0]:.0f} px) does not fit it: a cropped "
               "photo keeps the whole frame's; give the photo as the camera took it"
               if intrinsics.source == "exif" else ""))
    R, t = camera_from_floor[:3, :3], camera_from_floor[:3, 3]
    normal = R[:, 2]  # floor z (up) in camera coordinates
    d = -float(normal @ t)
    image_from_floor = intrinsics.K @ np.column_stack([R[:, 0], R[:, 1], t])
    image_from_floor /= image_from_floor[2, 2]
    horizon = np.linalg.inv(intrinsics.K).T @ normal
    horizon /= np.hypot(horizon[0], horizon[1])
    # Orient it so the board (on the floor) is on the positive side.
    center = corners.mean(axis=0)
    if horizon @ [center[0], center[1], 1.0] < 0:
        horizon = -horizon
    if not CAMERA_HEIGHT_M[0] <= d <= CAMERA_HEIGHT_M[1]:
        low, high = (board.square_mm * h / d for h in USUAL_CAMERA_HEIGHT_M)
        warnings.append(f"the camera comes out {d:.2f} m above the floor, by the board's squares of "
                        f"{board.square_mm:g} mm: if it was not, the printed squares are another size (a print "
                        "scaled to fit the page has smaller ones) and every length is off by as much; measure "
                        f"one and give it as --square (with the camera {USUAL_CAMERA_HEIGHT_M[0]:g}-"
                        f"{USUAL_CAMERA_HEIGHT_M[1]:g} m up, they would be {low:.0f}-{high:.0f} mm)")
    if intrinsics.source == "single-view" and not exif_ruled_out:  # its own warning says why
        warnings.append("focal length estimated from the board alone (no EXIF, no camera profile): "
                        f"uncertain by about {100 * intrinsics.focal_uncertainty:.1f} %")
    if len(ids) < board.corner_count:
        warnings.append(f"{len(ids)} of the board's {board.corner_count} corners were seen (part of it is hidden "
                        "or out of the frame)")
    order = np.argsort(ids)
    calibration = Calibration(size_px, intrinsics, camera_from_floor, d, np.append(normal, d), image_from_floor,
                              horizon, rms, corners[order], ids[order], detection.detector, board, tuple(warnings))
    turns = calibration.upright_turns
    if turns:
        side = {1: "left", 2: "top", 3: "right"}[turns]
        calibration = replace(calibration, warnings=calibration.warnings + (
            f"the photo shows the room turned, the floor at its {side} (its orientation lost, or the camera held "
            "so): the floor is found with the room turned upright, and the staged images keep the photo's turn; "
            "if the room stands upright in the photo, the board is not lying flat on the floor",))
    return calibration


def read_photo(path) -> np.ndarray:
    """An RGB photo (h, w, 3) uint8 from ``path``.

    Raises
    ------
    CalibrationError
        When the file is missing, not an image Stager can decode, or of a size that will not
        do (too small, or a panorama).
    """
    from .imageio import decode_image, decode_problem, read_user_file, size_problem

    path = Path(path)
    if path.is_dir():
        raise CalibrationError(f"photo {path} is a folder; give a photo file, e.g. {path / 'room.jpg'}")
    if not path.is_file():
        raise CalibrationError(f"photo {path} does not exist; check the path")
    data, problem = read_user_file(path)
    if problem is not None:
        raise CalibrationError(f"photo {path} {problem}")
    image = decode_image(data)
    if image is None:
        raise CalibrationError(f"photo {path} {decode_problem(data)}")
    if (problem := size_problem(image.shape[1], image.shape[0])) is not None:
        raise CalibrationError(f"photo {path} {problem}")
    return image


def _exif_or_board(exif: Intrinsics, detection, board: Board, size_px, where: str, warnings: list) -> Intrinsics:
    """The EXIF intrinsics, or the board's own (:func:`single_view_intrinsics`) where its
    view rules them out (``EXIF_GAP_SIGMAS``), with a warning in ``warnings``."""
    try:
        seen = single_view_intrinsics(detection.corners_px, board, size_px, detection.ids)
    except CalibrationError:  # a view that cannot tell the focal length cannot contradict it
        return exif
    gap = exif.K[0, 0] / seen.K[0, 0] - 1
    if abs(gap) <= EXIF_GAP_SIGMAS * np.hypot(exif.focal_uncertainty, seen.focal_uncertainty):
        return exif
    warnings.append(f"the EXIF focal length of {where} ({exif.K[0, 0]:.0f} px) and the board's view "
                    f"({seen.K[0, 0]:.0f} px \u00b1 {100 * seen.focal_uncertainty:.1f} %) disagree by "
                    f"{100 * abs(gap):.0f} %: the photo was cropped, or taken in a mode that crops the sensor, and "
                    "its EXIF describes the whole frame; the board's focal length is used. A crop also moves the "
                    "lens's center off the photo's middle: for the best measures give the photo as the camera "
                    "took it")
    return seen


def calibrate_file(path, board: Board, profile=None) -> Calibration:
    """Calibrate a photo file: a camera profile first, then EXIF, then the board alone."""
    image = read_photo(path)
    size_px = (image.shape[1], image.shape[0])
    if profile is not None:
        intrinsics = load_profile(profile, size_px, exif_orientation(path))
    else:
        focal = exif_focal_px(path, size_px)
        intrinsics = None if focal is None else exif_intrinsics(focal, size_px)
    return calibrate_photo(image, board, intrinsics=intrinsics, where=str(path))


def camera_profile(paths, board: Board) -> dict:
    """A camera profile from several photos of a board (multi-image ``calibrateCamera``).

    Square pixels are assumed (``CALIB_FIX_ASPECT_RATIO``), the five-term distortion is fit.

    Returns
    -------
    profile : dict
        JSON-ready: ``K``, ``distortion``, ``size_px``, ``rms_px``, ``focal_uncertainty``,
        ``per_view_rms_px``, ``images`` (used), ``skipped`` (no board found), ``repeated``
        (the same picture as an earlier shot, counted once), ``unreadable`` (files that
        are there but are not a photo Stager reads, with why) and ``board``.

    Raises
    ------
    CalibrationError
        Fewer than 3 usable photos, or photos of different sizes.
    """
    paths = [Path(p) for p in paths]
    obj, img, used, size = [], [], [], None
    skipped, repeated, unreadable, seen = [], [], [], {}
    for path in paths:
        try:
            image = read_photo(path)
        except CalibrationError as error:
            if not path.is_file():  # a path that is not there: its error, now
                raise
            # One broken file among twenty shots need not stop the calibration: it is named.
            unreadable.append(f"{path.name} ({str(error).removeprefix(f'photo {path} ')})")
            continue
        # The same view twice (a shot named twice, or copied) would weigh double and can
        # make three shots out of one: it counts once.
        digest = hashlib.sha256(image.tobytes()).digest()
        if digest in seen:
            repeated.append(f"{path.name} again" if path.name == seen[digest] else f"{path.name} (= {seen[digest]})")
            continue
        seen[digest] = path.name
        s = (image.shape[1], image.shape[0])
        if size is None:
            size = s
        elif s != size:
            raise CalibrationError(f"{path} is {s[0]}x{s[1]} but {used[0] if used else paths[0]} is "
                                   f"{size[0]}x{size[1]}: calibration shots must come from one camera mode")
        found = detect_board(image, board)
        if found is None:
            skipped.append(path.name)
            continue
        obj.append(found.object_points_m(board).astype(np.float32))
        img.append(found.corners_px.reshape(-1, 1, 2).astype(np.float32))
        used.append(path.name)
    if len(used) < 3:
        again = f", {len(repeated)} more repeated one: {', '.join(repeated)}" if repeated else ""
        broken = f"; {len(unreadable)} could not be read: {', '.join(unreadable)}" if unreadable else ""
        raise CalibrationError(
            f"a {board.describe()} was found in {len(used)} of {len(seen)} different photos{again}{broken}; at "
            "least 3 are needed (10-20 from different angles is better). Check --board (inner corners).")
    flags = cv2.CALIB_FIX_ASPECT_RATIO
    K0 = np.eye(3)
    rms, K, dist, _, _, std_intr, _, per_view = cv2.calibrateCameraExtended(
        obj, img, size, K0, np.zeros(5), flags=flags)
    return {
        "K": K.tolist(), "distortion": dist.ravel().tolist(), "size_px": list(size), "rms_px": float(rms),
        # With a fixed aspect ratio OpenCV reports the deviation on fx or fy, by version.
        "focal_uncertainty": float(np.nanmax(std_intr[:2, 0]) / K[0, 0]),
        "per_view_rms_px": per_view.ravel().round(4).tolist(),
        "images": used, "skipped": skipped, "repeated": repeated, "unreadable": unreadable,
        "board": _board_json(board),
    }
