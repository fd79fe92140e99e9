"""Calibrating a photo: the camera and the floor from one photo with the board on the floor.

From the board Stager recovers the intrinsics (from a saved camera profile, the photo's
EXIF focal length, or the board itself), the camera's pose above the floor, the metric
scale and the floor plane: a :class:`~augment.camera.calibration.Calibration`, the map
from pixels to floor meters that every later stage uses.

Conventions: images are (row, col) arrays, points are (x, y) pixels with pixel centers at
integers (OpenCV). The floor frame is the board's frame: origin at the center of the
squares, z up out of the floor, meters (see :mod:`augment.camera.board`). Camera axes
follow OpenCV (x right, y down, z forward). Poses are 4x4 arrays named ``camera_from_floor``.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from layout.fileio import path_problem

from ..errors import CalibrationError
from ..photo.exif import exif_focal_px, exif_orientation
from ..photo.io import read_photo, read_user_file
from .board import Board
from .calibration import Calibration, Intrinsics, board_json, quarter_turn
from .detect import BoardDetection, detect_board, suggest_board
from .lines import detect_segments, floor_colored, is_vertical, toward_vanishing_point
from .settings import CAMERA


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
    f by tens of percent, and k1 alone leaves a few percent.

    The uncertainty combines the fit's standard deviation with the change in f when the
    principal point moves by 2 % of the image (phones are not exactly centered). The
    deviation scales with the corners' noise, which the fit estimates from its residuals;
    with few corners (a partly hidden board) it absorbs much of the noise and the estimate
    comes out low, so the noise is taken to be at least
    ``CAMERA.calibrate.corner_noise_floor_px``, what the detectors reach.

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
    settings = CAMERA.calibrate
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
        if tilt_deg >= settings.min_tilt_deg:
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
    if tilt_deg < settings.min_tilt_deg or tilt_deg > settings.max_tilt_deg:
        what = "almost face-on" if tilt_deg < settings.min_tilt_deg else "almost edge-on"
        raise CalibrationError(
            f"the board is seen {what} (tilted {tilt_deg:.0f} degrees from the view direction; a single photo "
            f"needs {settings.min_tilt_deg:.0f}-{settings.max_tilt_deg:.0f}) to measure the focal length. {advice}")
    shifted = []
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        c = center + 0.02 * np.array([dx * width, dy * height])
        shifted.append(abs(_fit_focal(obj, corners_px, size_px, f, c, use_radial)[1][0, 0] - f) / f)
    f_std *= max(1.0, settings.corner_noise_floor_px[board.kind] / max(rms, 1e-12))
    uncertainty = float(np.hypot(f_std / f if np.isfinite(f_std) else np.inf, max(shifted)))
    if not uncertainty <= settings.max_single_view_uncertainty:
        raise CalibrationError(
            f"the focal length from this single view is uncertain by {100 * uncertainty:.0f} % "
            f"(at most {100 * settings.max_single_view_uncertainty:.0f} % is accepted). {advice}")
    note = f"board tilted {tilt_deg:.0f} degrees; principal point assumed at the image center"
    if use_radial:
        note += f"; lens distortion k1 = {dist[0]:.3f}, k2 = {dist[1]:.3f} fit from the board"
    return Intrinsics(K, dist if use_radial else np.zeros(5), "single-view", uncertainty, note)


def exif_intrinsics(focal_px: float, size_px: tuple[int, int]) -> Intrinsics:
    width, height = size_px
    K = np.array([[focal_px, 0, (width - 1) / 2], [0, focal_px, (height - 1) / 2], [0, 0, 1.0]])
    # Makers round 35 mm equivalents to whole millimeters and crop differently: ~3 %.
    return Intrinsics(K, np.zeros(5), "exif", 0.03, "EXIF 35 mm equivalent focal length; principal point at center")


# What a camera's calibration can be: OpenCV's distortion models, and focal lengths from
# a fisheye's to a long telephoto's, in multiples of the photo's longer side.
DISTORTION_TERMS = (4, 5, 8, 12, 14)
FOCAL_SIDES = (0.1, 20.0)
MAX_DISTORTION = 1e3
MAX_PROFILE_SIDE_PX = 100_000
MAX_PROFILE_BYTES = 1 << 20


def _profile_problem(K, dist, w0, h0, data) -> str | None:
    """What is wrong with a profile's values, or None."""
    if not all(isinstance(v, int) and not isinstance(v, bool) and 0 < v <= MAX_PROFILE_SIDE_PX for v in (w0, h0)):
        return (f"size_px {str(data['size_px'])[:40]} must be the photos' width and height, whole pixels up to "
                f"{MAX_PROFILE_SIDE_PX:,}")
    if not (np.isfinite(K).all() and np.isfinite(dist).all()):
        return "K and distortion hold a number that is not finite"
    lo, hi = (f * max(w0, h0) for f in FOCAL_SIDES)
    if not (lo <= K[0, 0] <= hi and lo <= K[1, 1] <= hi):
        return (f"focal lengths K[0][0] = {K[0, 0]:.4g} and K[1][1] = {K[1, 1]:.4g} px must lie between {lo:.0f} "
                f"and {hi:.0f} px for {w0}x{h0} photos")
    if not (-w0 <= K[0, 2] <= 2 * w0 and -h0 <= K[1, 2] <= 2 * h0) or np.any(K[2] != [0, 0, 1]) or K[1, 0] != 0:
        return "K is not a camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with its center near the photo's"
    if len(dist) not in DISTORTION_TERMS:
        return (f"distortion has {len(dist)} coefficients; OpenCV's models have "
                f"{', '.join(map(str, DISTORTION_TERMS))}")
    if np.abs(dist).max(initial=0.0) > MAX_DISTORTION:
        return f"a distortion coefficient is {np.abs(dist).max():.3g}; a lens's are at most {MAX_DISTORTION:g}"
    for field, top in (("rms_px", float("inf")), ("focal_uncertainty", 1.0)):
        value = data.get(field, 0.0)
        if value is None or (type(value) is float and math.isnan(value)):
            continue  # not known: the defaults stand
        if type(value) not in (int, float) or not 0 <= value < top:
            return (f"{field} {str(value)[:30]} must be a number from 0" + (f" below {top:g}" if top < 2 else "")
                    + " (what `stage calibrate` writes)")
    return None


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
    if path_problem(path) is None and path.stat().st_size > MAX_PROFILE_BYTES:
        raise CalibrationError(f"camera profile {path} is {path.stat().st_size:,} bytes; a profile from `stage "
                               f"calibrate` is a short JSON text (at most {MAX_PROFILE_BYTES >> 10} KB)")
    raw, problem = read_user_file(path)
    if problem is not None:
        raise CalibrationError(f"camera profile {path} {problem}"
                               + ("; make one with `stage calibrate`" if problem.startswith("does not") else ""))
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
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
    problem = _profile_problem(K, dist, w0, h0, data)
    if problem is not None:
        raise CalibrationError(f"camera profile {path}: {problem}; {remake}")
    rms = _known(data.get("rms_px"), 0.0)
    note = f"camera profile {path.name} (RMS {rms:.2f} px)"
    width, height = size_px
    if abs(w0 / h0 - width / height) > 0.01 and abs(h0 / w0 - width / height) <= 0.01:
        K, dist, (w0, h0) = quarter_turn(K, dist, (w0, h0), clockwise=orientation != 8)
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
    return Intrinsics(K, dist, "profile", _known(data.get("focal_uncertainty"), 0.005), note)


def _known(value, default: float) -> float:
    """A profile's number, or ``default`` where it is missing or not known (null, NaN)."""
    return default if value is None or (isinstance(value, float) and math.isnan(value)) else float(value)


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
        if camera_in_board[2] > 0 or detection.detector == "charuco":
            break  # ids read from ChArUco markers are printed on the board: never mirrored
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
        Line segments ``x1, y1, x2, y2`` (:func:`augment.camera.lines.detect_segments`), pixels.
    K : (3, 3) float64
    poses : list of (4, 4) camera_from_floor
    side_px : int
        The photo's longer side.

    Returns
    -------
    (len(poses),) float64
        Total length of the segments that pass :mod:`augment.room.height`'s test for a vertical
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
    offset = (CAMERA.calibrate.floor_side_fraction * max(np.asarray(image).shape[:2])) * across[:, None, :]
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
    ``CAMERA.calibrate.line_noise_px`` of the detector's shrunk copy.
    """
    settings = CAMERA.calibrate
    corner_sigma = max(_pose_rms(obj_m, corners_px, pose, intrinsics), settings.corner_noise_floor_px["chessboard"])
    line_floor = settings.line_noise_px * max(1.0, side_px / CAMERA.lines.side_px)
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
    photo's vertical edges side with, refit to them and the board together.

    A small or far board is a nearly affine view of a plane, which two tilts explain
    about equally well (the planar pose ambiguity). Within
    ``CAMERA.calibrate.ambiguous_rms_ratio`` of each other's RMS the photo's vertical
    edges decide: the right tilt sends them to its vertical vanishing point.
    """
    settings = CAMERA.calibrate
    readings = tilt_readings(corners_px, obj_m, intrinsics)
    if len(readings) < 2 or readings[1][1] > settings.ambiguous_rms_ratio * max(readings[0][1], 1e-6):
        return pose
    segments = detect_segments(image)
    side = max(np.asarray(image).shape[:2])
    support = vertical_support(segments, intrinsics.K, [r[0] for r in readings], side)
    best = int(np.argmax(support))
    if (support[best] >= settings.min_vertical_support
            and support[best] >= settings.vertical_support_ratio * support[1 - best]):
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
    settings = CAMERA.calibrate
    height, width = np.asarray(image).shape[:2]
    size_px = (width, height)
    detection = detect_board(image, board)
    if detection is None:
        other = suggest_board(image, board)
        if other is not None:
            hint = f" The photo shows a board that --board {other} finds: use --board {other}."
        elif board.kind == "charuco":
            hint = (f" Check --board: it counts inner corners (where four squares meet), not squares, and "
                    f"at least {CAMERA.detect.min_charuco_corners} corners with their markers must be visible "
                    "and sharp.")
        else:
            hint = (" Check --board: it counts inner corners (where four squares meet), "
                    "not squares; a board of 8 x 6 squares is --board 7x5.")
        if board.kind == "chessboard":
            hint += (f" The whole board must be in view (a ChArUco board, --board charuco:{board.cols}x{board.rows}, "
                     "may be partly hidden).")
        tried = ("OpenCV's ChArUco detector, then its checkerboard detectors" if board.kind == "charuco"
                 else "OpenCV's SB and classic detectors, on the whole photo and on crops")
        small = ""
        if max(size_px) < settings.small_photo_boards * settings.min_board_extent_px:
            # A thumbnail or a messaging app's copy: the board is a few dozen pixels at most.
            small = (f" The photo is only {width} x {height} px, too small to find a board in: "
                     "use the camera's own full-size photo.")
        raise CalibrationError(f"no {board.describe()} found in {where} (tried {tried}).{small}{hint} "
                               "It must lie flat and not be glared.")
    extent = detection.corners_px.max(axis=0) - detection.corners_px.min(axis=0)
    if extent.max() < settings.min_board_extent_px:
        raise CalibrationError(
            f"the board in {where} is only {math.floor(extent.max())} px across (at least "
            f"{settings.min_board_extent_px} needed): move the board closer to the camera or use a larger board")
    warnings = []
    if board.kind == "charuco" and detection.detector != "charuco":
        warnings.append("the ChArUco board's markers were too small or blurred to read: its squares were found as "
                        "a checkerboard's, which works only with the whole board in view")
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
    if rms > settings.max_rms_px:
        raise CalibrationError(
            f"the board in {where} fits its model with an RMS of {rms:.2f} px (at most {settings.max_rms_px} "
            "accepted): the board may be bent or not flat on the floor, or --square/--board may not match the print"
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
    if not settings.camera_height_m[0] <= d <= settings.camera_height_m[1]:
        usual = settings.usual_camera_height_m
        low, high = (board.square_mm * h / d for h in usual)
        warnings.append(f"the camera comes out {d:.2f} m above the floor, by the board's squares of "
                        f"{board.square_mm:g} mm: if it was not, the printed squares are another size (a print "
                        "scaled to fit the page has smaller ones) and every length is off by as much; measure "
                        f"one and give it as --square (with the camera {usual[0]:g}-"
                        f"{usual[1]:g} m up, they would be {low:.0f}-{high:.0f} mm)")
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


def _exif_or_board(exif: Intrinsics, detection, board: Board, size_px, where: str, warnings: list) -> Intrinsics:
    """The EXIF intrinsics, or the board's own (:func:`single_view_intrinsics`) where its
    view rules them out (``CAMERA.calibrate.exif_gap_sigmas`` standard deviations of the
    two together), with a warning in ``warnings``.

    A crop keeps the whole frame's EXIF focal length (as do phones' modes that crop the
    sensor, when the maker does not restate it), which then does not fit the photo."""
    try:
        seen = single_view_intrinsics(detection.corners_px, board, size_px, detection.ids)
    except CalibrationError:  # a view that cannot tell the focal length cannot contradict it
        return exif
    gap = exif.K[0, 0] / seen.K[0, 0] - 1
    if abs(gap) <= CAMERA.calibrate.exif_gap_sigmas * np.hypot(exif.focal_uncertainty, seen.focal_uncertainty):
        return exif
    warnings.append(f"the EXIF focal length of {where} ({exif.K[0, 0]:.0f} px) and the board's view "
                    f"({seen.K[0, 0]:.0f} px \u00b1 {100 * seen.focal_uncertainty:.1f} %) disagree by "
                    f"{100 * abs(gap):.0f} %: the photo was cropped, or taken in a mode that crops the sensor, and "
                    "its EXIF describes the whole frame; the board's focal length is used. A crop also moves the "
                    "lens's center off the photo's middle: for the best measures give the photo as the camera "
                    "took it")
    return seen


def calibrate_file(path, board: Board, profile=None, image=None) -> Calibration:
    """Calibrate a photo file: a camera profile first, then EXIF, then the board alone.
    ``image`` is the photo as :func:`read_photo` reads ``path``, when already read."""
    image = read_photo(path) if image is None else image
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
        "board": board_json(board),
    }
