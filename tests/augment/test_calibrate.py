"""Calibration against known answers: OpenCV's real photos and their published
calibration, synthetic renders with exact ground truth, and hand-made projections."""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from augment.board import Board
from augment.calibrate import (CalibrationError, _focal_from_homography, calibrate_file, calibrate_photo,
                               camera_profile, detect_board, exif_intrinsics, load_profile, read_photo,
                               single_view_intrinsics)
from augment.gl import Renderer
from augment.synth import render_sample
from augment.synth.camera import look_pose

DATA = Path(__file__).resolve().parents[1] / "data" / "opencv-chessboard"
LEFT = sorted(DATA.glob("left*.jpg"))
OPENCV = Board(9, 6, 25)


def _reference():
    fs = cv2.FileStorage(str(DATA / "left_intrinsics.yml"), cv2.FILE_STORAGE_READ)
    K = fs.getNode("camera_matrix").mat()
    fs.release()
    return K


def test_profile_from_opencv_photos_matches_their_calibration():
    profile = camera_profile(LEFT, OPENCV)
    K, ref = np.array(profile["K"]), _reference()
    assert len(profile["images"]) == 13 and profile["skipped"] == []
    assert abs(K[0, 0] - ref[0, 0]) / ref[0, 0] < 0.01
    assert abs(K[0, 2] - ref[0, 2]) < 3 and abs(K[1, 2] - ref[1, 2]) < 3
    assert profile["rms_px"] < 0.5
    assert 0 < profile["focal_uncertainty"] < 0.01
    # Barrel distortion like OpenCV's (k1 = -0.266).
    assert -0.32 < profile["distortion"][0] < -0.22


def test_single_view_focal_on_real_photos():
    """No photo of the set is near face-on (17-42 degrees of tilt), so none is refused;
    with k1 fit from the board the focal errors stay within 6 %, median about 1 %."""
    ref = _reference()[0, 0]
    errors = []
    for path in LEFT:
        c = calibrate_file(path, OPENCV)
        assert c.intrinsics.source == "single-view" and "k1" in c.intrinsics.note
        errors.append(abs(c.intrinsics.K[0, 0] - ref) / ref)
        assert c.rms_px < 0.5
    assert max(errors) < 0.06 and np.median(errors) < 0.015


def test_face_on_board_is_refused_not_guessed():
    """A camera looking straight down at the board: the perspective carries no focal length."""
    board = Board()
    K = np.array([[800.0, 0, 639.5], [0, 800.0, 479.5], [0, 0, 1]])
    camera_from_board = np.linalg.inv(look_pose([0.02, -0.01, 1.2], 0.3, np.pi / 2 - 0.02, 0.0))
    pts = board.corners_m() @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
    px = pts @ K.T
    px = px[:, :2] / px[:, 2:3] + np.random.default_rng(0).normal(0, 0.05, (len(pts), 2))
    with pytest.raises(CalibrationError, match="face-on"):
        single_view_intrinsics(px, board, (1280, 960))


def test_focal_from_homography_by_hand():
    K = np.array([[700.0, 0, 0], [0, 700.0, 0], [0, 0, 1]])
    R = cv2.Rodrigues(np.array([0.6, 0.2, 0.1]))[0]
    t = np.array([0.1, -0.2, 2.0])
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    assert np.isclose(_focal_from_homography(H / H[2, 2]), 700.0)
    # Face-on: the board plane parallel to the image gives no constraint.
    assert _focal_from_homography(K @ np.column_stack([[1, 0, 0], [0, 1, 0], t])) is None


@pytest.fixture(scope="module")
def renders():
    with Renderer() as renderer:
        return [render_sample([99, seed], renderer, size_px=(2016, 1512)) for seed in (3, 11, 19, 23)]


def test_pose_height_and_horizon_with_true_intrinsics(renders):
    """Given the true K, the pose is exact: camera height within 0.5 % and the horizon is
    the true vanishing line of the floor."""
    for sample in renders:
        t = sample.truth
        K = np.array(t["K"])
        c = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(K[0, 0], tuple(t["size_px"])))
        height = t["camera"]["height_m"] - 0.001  # the paper lies 1 mm up
        assert abs(c.camera_height_m - height) / height < 0.005
        up = np.array(t["camera_from_world"])[:3, 2]
        horizon = np.linalg.inv(K).T @ up
        horizon /= np.hypot(*horizon[:2])
        horizon *= np.sign(horizon @ c.horizon)
        # Direction within 0.1 degrees, position within 2 px on a 2016 px photo.
        assert np.allclose(c.horizon[:2], horizon[:2], atol=2e-3) and abs(c.horizon[2] - horizon[2]) < 2
        # Floor pixels lie on the positive side; the board's pixels are floor pixels.
        assert (np.column_stack([c.corners_px, np.ones(len(c.corners_px))]) @ c.horizon > 0).all()
        # Mapping board corners to the floor and back is the identity.
        floor = c.floor_from_pixels(c.corners_px)
        assert np.allclose(c.pixels_from_floor(floor), c.corners_px, atol=1e-6)


def test_single_view_on_synthetic_photos(renders):
    """From the board alone: focal length and camera height within 2.5 %."""
    for sample in renders:
        t = sample.truth
        image = sample.image.copy()
        c = calibrate_photo(image, Board())
        assert np.array_equal(image, sample.image)  # input untouched
        assert c.intrinsics.source == "single-view"
        f = t["K"][0][0]
        assert abs(c.intrinsics.K[0, 0] - f) / f < 0.025
        height = t["camera"]["height_m"] - 0.001
        assert abs(c.camera_height_m - height) / height < 0.025
        assert c.rms_px < 0.3


def test_wrong_board_size_is_named_and_the_right_one_suggested():
    image = read_photo(LEFT[0])
    with pytest.raises(CalibrationError, match=r"no 7x5 checkerboard .*use --board 9x6"):
        calibrate_photo(image, Board(7, 5, 25), where=str(LEFT[0]))
    gray = np.full((480, 640), 128, np.uint8)
    with pytest.raises(CalibrationError, match="inner corners"):
        calibrate_photo(gray, Board())
    assert detect_board(gray, Board()) is None


def test_profile_scales_to_another_resolution_and_refuses_another_aspect(tmp_path):
    path = tmp_path / "profile.json"
    path.write_text(json.dumps({"K": [[500, 0, 319.5], [0, 500, 239.5], [0, 0, 1]],
                                "distortion": [0.1, 0, 0, 0, 0], "size_px": [640, 480], "rms_px": 0.2}))
    same = load_profile(path, (640, 480))
    assert same.source == "profile" and same.K[0, 0] == 500
    double = load_profile(path, (1280, 960))
    # Pixel centers at integers: the center 319.5 of 640 px becomes 639.5 of 1280 px.
    assert np.allclose(double.K, [[1000, 0, 639.5], [0, 1000, 479.5], [0, 0, 1]])
    with pytest.raises(CalibrationError, match="aspect ratio"):
        load_profile(path, (1280, 720))
    with pytest.raises(CalibrationError, match="does not exist"):
        load_profile(tmp_path / "missing.json", (640, 480))
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(CalibrationError, match="cannot read"):
        load_profile(tmp_path / "bad.json", (640, 480))


def test_unreadable_photo(tmp_path):
    bad = tmp_path / "notes.jpg"
    bad.write_text("not an image")
    with pytest.raises(CalibrationError, match="not an image"):
        read_photo(bad)
    with pytest.raises(CalibrationError, match="does not exist"):
        read_photo(tmp_path / "missing.jpg")


def test_exif_focal_length_is_used_before_the_board(tmp_path, renders):
    """A photo whose EXIF says 26 mm (35 mm equivalent) gets f = 26 / 43.27 x diagonal."""
    from PIL import Image

    sample = renders[0]
    exif = Image.Exif()
    exif.get_ifd(0x8769)[0xA405] = 26  # FocalLengthIn35mmFilm
    path = tmp_path / "phone.jpg"
    Image.fromarray(sample.image).save(path, quality=92, exif=exif)
    c = calibrate_file(path, Board())
    w, h = sample.truth["size_px"]
    assert c.intrinsics.source == "exif"
    assert np.isclose(c.intrinsics.K[0, 0], 26 / np.hypot(36, 24) * np.hypot(w, h))
    # Without EXIF the same pixels fall back to the board.
    plain = tmp_path / "plain.jpg"
    Image.fromarray(sample.image).save(plain, quality=92)
    assert calibrate_file(plain, Board()).intrinsics.source == "single-view"
