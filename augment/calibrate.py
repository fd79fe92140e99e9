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

import json
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from .board import Board

# Tolerances and limits, in one place.
DETECT_MAX_SIDE_PX = 1280      # detect in a copy no larger than this, refine at full size
MIN_BOARD_EXTENT_PX = 60       # smaller boards give too few pixels for a pose
MAX_RMS_PX = 2.0               # worse reprojection means a bent, moved or mis-sized board
# Single-view focal needs perspective: the board's normal must be tilted from the optical
# axis (a fronto-parallel board says nothing about f) but not so far that it is a sliver.
MIN_TILT_DEG = 15.0
MAX_TILT_DEG = 80.0
MAX_SINGLE_VIEW_UNCERTAINTY = 0.05   # relative focal uncertainty allowed before refusing
_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 1e-3)
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
        Detected inner corners, in the board's row-by-row order.
    detector : str
    board : Board
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
    detector: str
    board: Board
    warnings: tuple[str, ...] = field(default=())

    @property
    def world_from_camera(self) -> np.ndarray:
        """Camera pose in the floor frame, (4, 4)."""
        return np.linalg.inv(self.camera_from_floor)

    def floor_from_pixels(self, points_px: np.ndarray) -> np.ndarray:
        """Floor coordinates (k, 2) meters of pixels (k, 2), distortion removed first."""
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
            "board": {"inner_corners": [self.board.cols, self.board.rows], "square_mm": self.board.square_mm},
            "corners_px": self.corners_px.round(3).tolist(),
            "warnings": list(self.warnings),
        }


def _gray(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.ndim == 2:
        return image if image.dtype == np.uint8 else cv2.convertScaleAbs(image)
    if image.ndim == 3 and image.shape[2] in (3, 4):
        return cv2.cvtColor(image[..., :3], cv2.COLOR_RGB2GRAY)
    raise ValueError(f"image of shape {image.shape}: expected (h, w) gray or (h, w, 3) RGB")


def _min_spacing_px(corners: np.ndarray, board: Board) -> float:
    grid = corners.reshape(board.rows, board.cols, 2)
    return float(min(np.linalg.norm(np.diff(grid, axis=0), axis=-1).min(),
                     np.linalg.norm(np.diff(grid, axis=1), axis=-1).min()))


def _refine(gray: np.ndarray, corners: np.ndarray, board: Board) -> np.ndarray:
    # The search window must stay inside one square, or a neighbouring corner pulls.
    half = int(np.clip(0.4 * _min_spacing_px(corners, board), 2, 11))
    refined = cv2.cornerSubPix(gray, corners.reshape(-1, 1, 2).astype(np.float32), (half, half), (-1, -1),
                               _SUBPIX_CRITERIA)
    return refined.reshape(-1, 2).astype(np.float64)


def _find(small: np.ndarray, pattern: tuple[int, int]):
    """Corners in ``small`` or None, and which detector found them."""
    found, corners = cv2.findChessboardCornersSB(
        small, pattern, flags=cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
    if found:
        return corners.reshape(-1, 2), "sb"
    found, corners = cv2.findChessboardCorners(
        small, pattern, flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if found:
        return corners.reshape(-1, 2), "classic"
    return None, None


def detect_board(image: np.ndarray, board: Board) -> tuple[np.ndarray, str] | None:
    """Find the board's inner corners.

    Detection runs on a copy at most ``DETECT_MAX_SIDE_PX`` on its long side (the SB
    detector, then the classic one); the corners are then refined with ``cornerSubPix`` at
    full resolution.

    Parameters
    ----------
    image : (h, w) or (h, w, 3) uint8
        Gray or RGB photo. Not modified.

    Returns
    -------
    corners_px : (cols * rows, 2) float64, row by row as the detector orders them
    detector : str, ``"sb"`` or ``"classic"``
        Or None when no board of this size is in the photo.
    """
    gray = _gray(image)
    scale = min(1.0, DETECT_MAX_SIDE_PX / max(gray.shape))
    small = gray if scale == 1.0 else cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    corners, detector = _find(small, (board.cols, board.rows))
    if corners is None:
        return None
    # Map pixel centers of the small copy back: x_full = (x_small + 0.5) / scale - 0.5.
    corners = (corners + 0.5) / scale - 0.5
    return _refine(gray, corners, board), detector


def _suggest_sizes(image: np.ndarray, board: Board) -> list[tuple[int, int]]:
    gray = _gray(image)
    scale = min(1.0, 800 / max(gray.shape))
    small = cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA) if scale < 1 else gray
    found = []
    for size in _COMMON_SIZES:
        if size in ((board.cols, board.rows), (board.rows, board.cols)):
            continue
        ok, _ = cv2.findChessboardCorners(small, size, flags=cv2.CALIB_CB_ADAPTIVE_THRESH
                                          | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK)
        if ok:
            found.append(size)
    return found


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
    """LM refinement of f (and k1 when ``radial``) with the pose; principal point fixed."""
    flags = (cv2.CALIB_USE_INTRINSIC_GUESS | cv2.CALIB_FIX_PRINCIPAL_POINT | cv2.CALIB_FIX_ASPECT_RATIO
             | cv2.CALIB_ZERO_TANGENT_DIST | cv2.CALIB_FIX_K2 | cv2.CALIB_FIX_K3)
    if not radial:
        flags |= cv2.CALIB_FIX_K1
    K = np.array([[f0, 0, center[0]], [0, f0, center[1]], [0, 0, 1.0]])
    rms, K, dist, rvecs, _, std, _, _ = cv2.calibrateCameraExtended(
        [obj.astype(np.float32)], [corners_px.reshape(-1, 1, 2).astype(np.float32)], size_px, K,
        np.zeros(5), flags=flags)
    # With a fixed aspect ratio OpenCV reports the deviation on fx or fy, depending on version.
    f_std = float(np.nanmax(std[:2, 0]))
    return float(rms), K, dist.ravel(), cv2.Rodrigues(rvecs[0])[0], f_std


def single_view_intrinsics(corners_px: np.ndarray, board: Board, size_px: tuple[int, int]) -> Intrinsics:
    """Focal length from the board alone: principal point at the image center, square
    pixels. A closed form from the board homography starts a Levenberg-Marquardt fit of f
    with the pose (``calibrateCameraExtended``). When the lens bends straight lines (the
    fit without distortion leaves more than 0.5 px of error and a radial term k1 removes a
    third of it) k1 is fit too: without it a barrel lens biases f by tens of percent.

    The uncertainty combines the fit's standard deviation with the change in f when the
    principal point moves by 2 % of the image (phones are not exactly centered).

    Raises
    ------
    CalibrationError
        When the board is seen nearly face-on or nearly edge-on, or f is too uncertain.
    """
    width, height = size_px
    center = np.array([(width - 1) / 2, (height - 1) / 2])
    obj = board.corners_m()
    H, _ = cv2.findHomography(obj[:, :2], corners_px - center)
    f0 = _focal_from_homography(H)
    advice = ("Give the camera's focal length another way: a photo with EXIF data, or a camera "
              "profile from `stage calibrate shots/*.jpg` (--camera profile.json).")
    if f0 is None or not (0.2 * max(size_px) < f0 < 10 * max(size_px)):
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
    uncertainty = float(np.hypot(f_std / f if np.isfinite(f_std) else np.inf, max(shifted)))
    if not uncertainty <= MAX_SINGLE_VIEW_UNCERTAINTY:
        raise CalibrationError(
            f"the focal length from this single view is uncertain by {100 * uncertainty:.0f} % "
            f"(at most {100 * MAX_SINGLE_VIEW_UNCERTAINTY:.0f} % is accepted). {advice}")
    note = f"board tilted {tilt_deg:.0f} degrees; principal point assumed at the image center"
    if use_radial:
        note += f"; lens distortion k1 = {dist[0]:.3f} fit from the board"
    return Intrinsics(K, dist if use_radial else np.zeros(5), "single-view", uncertainty, note)


def exif_focal_px(path, size_px: tuple[int, int]) -> float | None:
    """Focal length in pixels from the EXIF 35 mm equivalent focal length, or None."""
    from PIL import Image

    try:
        with Image.open(path) as im:
            exif = im.getexif()
            sub = exif.get_ifd(0x8769)
    except (OSError, ValueError):
        return None
    f35 = sub.get(0xA405) or exif.get(0xA405)
    if not f35:
        return None
    return float(f35) / _FILM_DIAGONAL_MM * float(np.hypot(*size_px))


def exif_intrinsics(focal_px: float, size_px: tuple[int, int]) -> Intrinsics:
    width, height = size_px
    K = np.array([[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1.0]])
    # Makers round 35 mm equivalents to whole millimeters and crop differently: ~3 %.
    return Intrinsics(K, np.zeros(5), "exif", 0.03, "EXIF 35 mm equivalent focal length; principal point at center")


def load_profile(path, size_px: tuple[int, int]) -> Intrinsics:
    """Intrinsics from a camera profile JSON (``stage calibrate``), scaled to ``size_px``.

    Raises
    ------
    CalibrationError
        When the file is unreadable, lacks a field, or was made for another aspect ratio.
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text())
        K = np.array(data["K"], dtype=np.float64).reshape(3, 3)
        dist = np.array(data["distortion"], dtype=np.float64).ravel()
        w0, h0 = data["size_px"]
    except FileNotFoundError:
        raise CalibrationError(f"camera profile {path} does not exist; make one with `stage calibrate`") from None
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise CalibrationError(
            f"camera profile {path}: cannot read it ({type(error).__name__}: {error}); expected the JSON "
            "written by `stage calibrate` with fields K, distortion, size_px") from None
    width, height = size_px
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
    rms = float(data.get("rms_px", 0.0))
    return Intrinsics(K, dist, "profile", float(data.get("focal_uncertainty", 0.005)),
                      f"camera profile {path.name} (RMS {rms:.2f} px)")


def _pose(corners_px: np.ndarray, board: Board, intrinsics: Intrinsics):
    """camera_from_board (4, 4) and corners in an order whose board z faces the camera."""
    obj = board.corners_m()
    K, dist = intrinsics.K, intrinsics.distortion
    for attempt in range(2):
        ok, rvec, tvec = cv2.solvePnP(obj, corners_px, K, dist, flags=cv2.SOLVEPNP_ITERATIVE)
        rvec, tvec = cv2.solvePnPRefineLM(obj, corners_px, K, dist, rvec, tvec)
        R = cv2.Rodrigues(rvec)[0]
        camera_in_board = -R.T @ tvec.ravel()
        if camera_in_board[2] > 0:
            break
        # The detector may list rows in the mirrored order: the board frame would point
        # into the floor. Reversing the rows flips it.
        corners_px = corners_px.reshape(board.rows, board.cols, 2)[::-1].reshape(-1, 2)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, tvec.ravel()
    return pose, corners_px


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
    found = detect_board(image, board)
    if found is None:
        others = _suggest_sizes(image, board)
        hint = (f" A {others[0][0]}x{others[0][1]} board is in the photo: use --board {others[0][0]}x{others[0][1]}."
                if others else " Check --board: it counts inner corners (where four squares meet), "
                "not squares; a board of 8 x 6 squares is --board 7x5.")
        raise CalibrationError(
            f"no {board.cols}x{board.rows} checkerboard found in {where} (tried OpenCV's SB and classic "
            f"detectors).{hint} The whole board must be in view, flat and not glared.")
    corners, detector = found
    extent = corners.max(axis=0) - corners.min(axis=0)
    if extent.max() < MIN_BOARD_EXTENT_PX:
        raise CalibrationError(
            f"the board in {where} is only {extent.max():.0f} px across (at least {MIN_BOARD_EXTENT_PX} needed): "
            "move the board closer to the camera or use a larger board")
    if intrinsics is None:
        intrinsics = single_view_intrinsics(corners, board, size_px)
    camera_from_floor, corners = _pose(corners, board, intrinsics)
    projected, _ = cv2.projectPoints(board.corners_m(), cv2.Rodrigues(camera_from_floor[:3, :3])[0],
                                     camera_from_floor[:3, 3], intrinsics.K, intrinsics.distortion)
    rms = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - corners) ** 2, axis=1))))
    if rms > MAX_RMS_PX:
        raise CalibrationError(
            f"the board in {where} fits its model with an RMS of {rms:.2f} px (at most {MAX_RMS_PX} accepted): "
            "the board may be bent or not flat on the floor, or --square/--board may not match the print")
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
    warnings = []
    if intrinsics.source == "single-view":
        warnings.append("focal length estimated from the board alone (no EXIF, no camera profile): "
                        f"uncertain by about {100 * intrinsics.focal_uncertainty:.1f} %")
    return Calibration(size_px, intrinsics, camera_from_floor, d, np.append(normal, d), image_from_floor,
                       horizon, rms, corners, detector, board, tuple(warnings))


def read_photo(path) -> np.ndarray:
    """An RGB photo (h, w, 3) uint8 from ``path``.

    Raises
    ------
    CalibrationError
        When the file is missing or not an image OpenCV can decode.
    """
    path = Path(path)
    data = np.fromfile(str(path), dtype=np.uint8) if path.is_file() else None
    if data is None:
        raise CalibrationError(f"photo {path} does not exist or is not a file")
    image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    if image is None:
        raise CalibrationError(f"photo {path} is not an image OpenCV can read (JPEG, PNG, TIFF, WebP, ...)")
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def calibrate_file(path, board: Board, profile=None) -> Calibration:
    """Calibrate a photo file: a camera profile first, then EXIF, then the board alone."""
    image = read_photo(path)
    size_px = (image.shape[1], image.shape[0])
    if profile is not None:
        intrinsics = load_profile(profile, size_px)
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
        ``per_view_rms_px``, ``images`` and ``board``.

    Raises
    ------
    CalibrationError
        Fewer than 3 usable photos, or photos of different sizes.
    """
    paths = [Path(p) for p in paths]
    obj, img, used, size = [], [], [], None
    skipped = []
    for path in paths:
        image = read_photo(path)
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
        obj.append(board.corners_m().astype(np.float32))
        img.append(found[0].reshape(-1, 1, 2).astype(np.float32))
        used.append(path.name)
    if len(used) < 3:
        raise CalibrationError(
            f"a {board.cols}x{board.rows} board was found in {len(used)} of {len(paths)} photos; at least 3 are "
            "needed (10-20 from different angles is better). Check --board (inner corners).")
    flags = cv2.CALIB_FIX_ASPECT_RATIO
    K0 = np.eye(3)
    rms, K, dist, _, _, std_intr, _, per_view = cv2.calibrateCameraExtended(
        obj, img, size, K0, np.zeros(5), flags=flags)
    return {
        "K": K.tolist(), "distortion": dist.ravel().tolist(), "size_px": list(size), "rms_px": float(rms),
        # With a fixed aspect ratio OpenCV reports the deviation on fx or fy, by version.
        "focal_uncertainty": float(np.nanmax(std_intr[:2, 0]) / K[0, 0]),
        "per_view_rms_px": per_view.ravel().round(4).tolist(),
        "images": used, "skipped": skipped,
        "board": {"inner_corners": [board.cols, board.rows], "square_mm": board.square_mm},
    }
