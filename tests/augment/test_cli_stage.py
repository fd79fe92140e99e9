"""The ``stage`` command line (augment.app.cli) and the calibration overlay (augment.draw.calibration)."""
from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from augment.app import cli
from augment.camera.board import Board, parse_board
from augment.camera.calibrate import calibrate_file
from augment.draw.calibration import calibration_overlay
from augment.photo.io import read_photo
from augment.render.gl import Renderer
from augment.synth import render_sample, write_sample

OPENCV_DATA = Path(__file__).resolve().parents[1] / "data" / "opencv-chessboard"
# From left_intrinsics.yml (OpenCV's own calibration of these photos).
OPENCV_FX, OPENCV_CX, OPENCV_CY = 535.916, 342.283, 235.571
# A synthetic room whose board the detector finds (seed [2026, 4] is samples/photos/room_4).
SYNTH_SEED = [2026, 4]


@pytest.fixture(scope="module")
def synth_photo(tmp_path_factory):
    """(path of the JPEG, ground truth) of one rendered room photo, 1280 x 960."""
    folder = tmp_path_factory.mktemp("synth")
    with Renderer() as renderer:
        sample = render_sample(SYNTH_SEED, renderer, size_px=(1280, 960))
    paths = write_sample(sample, folder, "room")
    return paths["image"], sample.truth


@pytest.fixture(scope="module")
def synth_calibration(synth_photo):
    path, _ = synth_photo
    return read_photo(path), calibrate_file(path, Board())


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


# --------------------------------------------------------------------------- stage board


@pytest.mark.parametrize("paper, expected_pt", [("A4", (841.89, 595.28)), ("A3", (1190.55, 841.89))])
def test_board_writes_the_paper_sized_pdf(tmp_path, capsys, paper, expected_pt):
    out = tmp_path / "new folder" / "board.pdf"
    code, stdout, err = run(["board", "--paper", paper, "--out", out], capsys)
    assert code == 0, err
    pdf = out.read_bytes()
    assert pdf.startswith(b"%PDF")
    (box,) = re.findall(rb"/MediaBox\s*\[\s*([-\d.\s]+)\]", pdf)
    x0, y0, x1, y1 = (float(v) for v in box.split())
    assert (x0, y0) == (0.0, 0.0)
    assert (x1, y1) == pytest.approx(expected_pt, abs=0.1)
    square = {"A4": "30", "A3": "45"}[paper]
    assert f"--square {square}" in stdout


def test_console_script_exits_with_the_command_status(tmp_path):
    # `stage` runs through augment.app.cli.run (which skips the interpreter's last garbage
    # collections): the status and the output must be what main gives.
    out = tmp_path / "board.pdf"
    ok = subprocess.run([sys.executable, "-m", "augment.app.cli", "board", "--out", str(out)],
                        capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    assert out.read_bytes().startswith(b"%PDF") and "--square 45" in ok.stdout
    bad = subprocess.run([sys.executable, "-m", "augment.app.cli", "board", "--paper", "A4", "--square", "60",
                          "--out", str(tmp_path / "b.pdf")], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.startswith("error:")


def test_outputs_and_inputs_that_cannot_be_are_refused(tmp_path, capsys):
    """A PDF written to board.txt, squares of 1e-300 mm (they ran on, to "the board is
    seen almost face-on"), a folder as the camera profile (it was "no such file")."""
    code, _, err = run(["board", "--out", tmp_path / "board.txt"], capsys)
    assert code == 2 and f"--out {tmp_path / 'board.txt'}: it is written as PDF" in err
    assert f"e.g. {tmp_path / 'board.pdf'}" in err and list(tmp_path.iterdir()) == []
    photo = OPENCV_DATA / "left01.jpg"
    code, _, err = run(["check", photo, "--square", "1e-300"], capsys)
    assert code == 2 and "--square: '1e-300': expected the side of one printed square in millimeters, 5 to 1000" \
        in err
    code, _, err = run(["check", photo, "--board", "9x6", "--square", "25", "--camera", tmp_path], capsys)
    assert code == 2 and f"--camera {tmp_path}: is a folder; make a camera profile" in err
    code, _, err = run(["measure", photo, "--height", "250", "--out", tmp_path / "m"], capsys)
    assert code == 2 and "--height: '250': expected the wall height in meters, 1.8 to 6, e.g. 2.6" in err
    assert not (tmp_path / "m").exists()


@pytest.mark.parametrize("name", ["left05", "left13"])
def test_a_board_held_up_in_a_real_photo_is_no_floor_to_furnish(name, tmp_path, capsys):
    """OpenCV's photos show the board held up, the "floor" its tilted plane; with no EXIF
    the lens is fit from the board. left05's horizon runs near the mask's top, where an
    upright meter spans millions of pixels (the skirting trim asked for 28.7 GiB);
    left13's fit distortion turns back before the photo's corners, where its floor
    points went kilometers out (the layout's inset asked for 51.6 GiB). Each is now the
    one error a user can act on."""
    code, _, err = run(["furnish", OPENCV_DATA / f"{name}.jpg", "--board", "9x6", "--square", "25",
                        "--suggestions", "1", "--out", tmp_path / "out"], capsys)
    assert code == 2 and "floor too small for any furniture" in err and "Traceback" not in err, err


def test_board_that_does_not_fit_is_refused(tmp_path, capsys):
    code, _, err = run(["board", "--paper", "A4", "--square", "60", "--out", tmp_path / "b.pdf"], capsys)
    assert code == 2
    assert err.startswith("error: ") and "--square 32" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_board_writes_a_charuco_board(tmp_path, capsys):
    out = tmp_path / "charuco.pdf"
    code, stdout, err = run(["board", "--paper", "A4", "--board", "charuco:7x5", "--out", out], capsys)
    assert code == 0, err
    assert out.read_bytes().startswith(b"%PDF")
    assert "ChArUco board (markers DICT_4X4_50)" in stdout and "--board charuco:7x5 --square 30" in stdout


# --------------------------------------------------------------------------- stage calibrate


def test_calibrate_matches_opencvs_reference_profile(tmp_path, capsys):
    shots = sorted(OPENCV_DATA.glob("left*.jpg"))
    assert len(shots) >= 10
    out = tmp_path / "profile.json"
    code, stdout, err = run(["calibrate", *shots, "--board", "9x6", "--square", "25", "--out", out], capsys)
    assert code == 0, err
    profile = json.loads(out.read_text())
    K = np.array(profile["K"])
    assert K[0, 0] == pytest.approx(OPENCV_FX, rel=0.01)
    assert K[1, 1] == pytest.approx(OPENCV_FX, rel=0.01)
    assert K[0, 2] == pytest.approx(OPENCV_CX, abs=0.01 * 640)
    assert K[1, 2] == pytest.approx(OPENCV_CY, abs=0.01 * 480)
    assert profile["rms_px"] < 0.5
    assert len(profile["images"]) == len(shots)
    assert "fx" in stdout and "RMS" in stdout and str(out) in stdout


def test_calibrate_reads_a_folder_of_heic_shots(tmp_path, capsys):
    """An iPhone saves HEIC: a folder of its shots was refused as holding no photos."""
    import pillow_heif
    from PIL import Image

    pillow_heif.register_heif_opener()
    folder = tmp_path / "shots"
    folder.mkdir()
    four = sorted(OPENCV_DATA.glob("left*.jpg"))[:4]
    for i, shot in enumerate(four):
        Image.open(shot).convert("RGB").save(folder / f"IMG_{i:04d}.HEIC", format="HEIF", quality=95)
    (folder / "notes.txt").write_text("not a photo")
    code, _, err = run(["calibrate", folder, "--board", "9x6", "--square", "25", "-q",
                        "--out", tmp_path / "p.json"], capsys)
    assert code == 0, err
    profile = json.loads((tmp_path / "p.json").read_text())
    assert profile["images"] == [f"IMG_{i:04d}.HEIC" for i in range(4)]
    assert np.array(profile["K"])[0, 0] == pytest.approx(OPENCV_FX, rel=0.05)


def test_calibrate_quiet_prints_nothing(tmp_path, capsys):
    shots = sorted(OPENCV_DATA.glob("left*.jpg"))[:4]
    code, stdout, err = run(["calibrate", *shots, "--board", "9x6", "--square", "25", "-q",
                             "--out", tmp_path / "p.json"], capsys)
    assert (code, stdout, err) == (0, "", "")


def test_calibrate_counts_a_repeated_shot_once(tmp_path, capsys):
    # The same view twice would weigh double, and three copies of one shot made a
    # "profile" of one view (focal +-13 %).
    four = sorted(OPENCV_DATA.glob("left*.jpg"))[:4]
    copy = tmp_path / "copy.jpg"
    copy.write_bytes(four[0].read_bytes())
    code, stdout, err = run(["calibrate", *four, copy, four[1], "--board", "9x6", "--square", "25",
                             "--out", tmp_path / "p.json"], capsys)
    assert code == 0, err
    profile = json.loads((tmp_path / "p.json").read_text())
    assert profile["images"] == [p.name for p in four]
    assert profile["repeated"] == [f"copy.jpg (= {four[0].name})", f"{four[1].name} again"]
    assert f"counted once: copy.jpg (= {four[0].name}), {four[1].name} again" in stdout
    code, _, err = run(["calibrate", "-q", "--board", "9x6", "--square", "25", "--out", tmp_path / "q.json",
                        four[0], copy, four[0]], capsys)
    assert code == 2 and "found in 1 of 1 different photos, 2 more repeated one" in err, err


def test_calibrate_names_a_broken_shot_and_goes_on(tmp_path, capsys):
    """A shot cut short among good ones stopped the whole calibration; it is now named and
    left out. With too few good shots left, the error names it too."""
    four = sorted(OPENCV_DATA.glob("left*.jpg"))[:4]
    cut = tmp_path / "cut.jpg"
    cut.write_bytes(four[0].read_bytes()[:-3000])
    code, stdout, err = run(["calibrate", *four[1:], cut, "--board", "9x6", "--square", "25",
                             "--out", tmp_path / "p.json"], capsys)
    assert code == 0, err
    profile = json.loads((tmp_path / "p.json").read_text())
    assert profile["images"] == [p.name for p in four[1:]] and len(profile["unreadable"]) == 1
    assert profile["unreadable"][0].startswith("cut.jpg (is cut short: a JPEG file")
    assert "; not read: cut.jpg (is cut short" in stdout
    code, _, err = run(["calibrate", *four[1:3], cut, "--board", "9x6", "--square", "25",
                        "--out", tmp_path / "q.json"], capsys)
    assert code == 2 and "found in 2 of 2 different photos; 1 could not be read: cut.jpg (is cut short" in err, err


# --------------------------------------------------------------------------- stage check


def test_check_writes_calibration_and_overlay(synth_photo, tmp_path, capsys):
    path, truth = synth_photo
    out = tmp_path / "out" / "check"
    code, stdout, err = run(["check", path, "--out", out], capsys)
    assert code == 0, err
    report = json.loads((out / "calibration.json").read_text())
    assert report["camera_height_m"] == pytest.approx(truth["camera"]["height_m"], rel=0.03)
    assert report["board"]["inner_corners"] == [7, 5]
    photo = read_photo(path)
    overlay = read_photo(out / "overlay_calibration.png")
    assert overlay.shape == photo.shape
    assert np.mean(np.any(overlay != photo, axis=2)) > 0.05
    assert "camera" in stdout and "RMS" in stdout
    assert sorted(p.name for p in out.iterdir()) == ["calibration.json", "overlay_calibration.png"]


def test_overlay_draws_axes_and_grid_and_leaves_the_photo_alone(synth_calibration):
    photo, calibration = synth_calibration
    before = photo.copy()
    overlay = calibration_overlay(photo, calibration)
    np.testing.assert_array_equal(photo, before)
    assert overlay.shape == photo.shape and overlay.dtype == np.uint8
    assert overlay is not photo and not np.shares_memory(overlay, photo)
    h, w = photo.shape[:2]

    def changed_near(px, radius=3):
        x, y = np.round(px).astype(int)
        a = overlay[max(0, y - radius):y + radius + 1, max(0, x - radius):x + radius + 1].astype(int)
        b = photo[max(0, y - radius):y + radius + 1, max(0, x - radius):x + radius + 1].astype(int)
        return np.abs(a - b).max() > 40

    origin = calibration.pixels_from_floor(np.zeros((1, 3)))[0]
    assert 0 <= origin[0] < w and 0 <= origin[1] < h
    assert changed_near(origin)
    # Along the x axis, outside the board's squares: red.
    x_axis = calibration.pixels_from_floor(np.array([[0.3, 0.0, 0.0]]))[0]
    r, g, b = overlay[int(round(x_axis[1])), int(round(x_axis[0]))].astype(int)
    assert r > 150 and r > g + 60 and r > b + 60
    # The z axis stands up: blue above the origin.
    z_axis = calibration.pixels_from_floor(np.array([[0.0, 0.0, 0.3]]))[0]
    assert z_axis[1] < origin[1]
    r, g, b = overlay[int(round(z_axis[1])), int(round(z_axis[0]))].astype(int)
    assert b > 150 and b > r + 60
    # A grid line 1 m from the board, where it shows in the lower half away from the caption.
    along = np.linspace(-3, 3, 121)
    points = np.vstack([np.column_stack([np.full_like(along, 1.0), along]),
                        np.column_stack([along, np.full_like(along, -1.0)])])
    px = calibration.pixels_from_floor(points)
    inside = (px[:, 0] > 20) & (px[:, 0] < w - 20) & (px[:, 1] > h / 2) & (px[:, 1] < h - 20)
    assert inside.sum() >= 5
    assert np.mean([changed_near(p, radius=1) for p in px[inside]]) > 0.9


def test_overlay_refuses_an_image_of_another_size(synth_calibration):
    photo, calibration = synth_calibration
    with pytest.raises(ValueError, match="1280x960"):
        calibration_overlay(photo[:, :-2], calibration)


# --------------------------------------------------------------------------- bad input


def test_missing_photo(tmp_path, capsys):
    missing = tmp_path / "no such photo.jpg"
    code, stdout, err = run(["check", missing, "--out", tmp_path / "out"], capsys)
    assert code == 2
    assert err.startswith("error: ") and str(missing) in err and "Traceback" not in err
    assert stdout == ""
    assert not (tmp_path / "out").exists()


def test_photo_without_a_board(tmp_path, capsys):
    gray = tmp_path / "gray.png"
    ok, png = cv2.imencode(".png", np.full((480, 640, 3), 128, np.uint8))
    gray.write_bytes(png.tobytes())
    code, _, err = run(["check", gray, "--out", tmp_path / "out"], capsys)
    assert code == 2
    assert "no 7x5 checkerboard" in err and str(gray) in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text", ["7*5", "1x5", "7x", "seven"])
def test_bad_board_text(tmp_path, capsys, text):
    code, _, err = run(["check", tmp_path / "photo.jpg", "--board", text], capsys)
    assert code == 2
    assert "--board" in err and repr(text) in err and "inner corners" in err and "Traceback" not in err


@pytest.mark.parametrize("text, named", [("aruco:7x5", "'aruco'"), ("charuco:7*5", "charuco:7x5")])
def test_bad_board_kind(tmp_path, capsys, text, named):
    code, _, err = run(["check", tmp_path / "photo.jpg", "--board", text], capsys)
    assert code == 2
    assert "--board" in err and named in err and "ChArUco" in err and "Traceback" not in err


def test_parse_board():
    assert parse_board("7x5") == (7, 5, "chessboard")
    assert parse_board(" ChArUco : 9X6 ") == (9, 6, "charuco")
    assert parse_board("checkerboard:7x5") == (7, 5, "chessboard")


def test_unwritable_out(synth_photo, tmp_path, capsys):
    path, _ = synth_photo
    blocker = tmp_path / "a file"
    blocker.write_text("")
    code, _, err = run(["check", path, "--out", blocker / "sub"], capsys)
    assert code == 2
    assert "--out" in err and "is a file" in err


def test_no_arguments_prints_usage(capsys):
    code, stdout, _ = run([], capsys)
    assert code == 0 and "calibrate" in stdout and "check" in stdout and "board" in stdout


# --------------------------------------------------------------------------- ChArUco


@pytest.fixture(scope="module")
def charuco_photo(tmp_path_factory):
    """(path, truth) of a 1280x960 room photo with the default ChArUco board 40 % under a
    carton (seed [7, 60] lays the board near enough for its markers to read)."""
    folder = tmp_path_factory.mktemp("charuco")
    with Renderer() as renderer:
        sample = render_sample([7, 60], renderer, size_px=(1280, 960), board=Board(kind="charuco"), board_hidden=0.4)
    paths = write_sample(sample, folder, "room")
    return paths["image"], sample.truth


def test_check_a_partly_hidden_charuco_board(charuco_photo, tmp_path, capsys):
    path, truth = charuco_photo
    out = tmp_path / "check"
    code, stdout, err = run(["check", path, "--board", "charuco:7x5", "--out", out], capsys)
    assert code == 0, err
    report = json.loads((out / "calibration.json").read_text())
    assert report["board"] == {"kind": "charuco", "inner_corners": [7, 5], "square_mm": 45.0,
                               "dictionary": "DICT_4X4_50"}
    seen = report["corner_ids"]
    assert 12 <= len(seen) < 35 and len(report["corners_px"]) == len(seen)
    assert all(truth["board"]["corners_visible"][k] for k in seen)
    assert report["camera_height_m"] == pytest.approx(truth["camera"]["height_m"], rel=0.03)
    assert f"{len(seen)} of 35 corners" in stdout and "ChArUco" in stdout
    assert "corners were seen" in err


def test_overlay_marks_the_corners_seen_on_a_partial_board(charuco_photo):
    path, _ = charuco_photo
    photo = read_photo(path)
    calibration = calibrate_file(path, Board(kind="charuco"))
    overlay = calibration_overlay(photo, calibration)
    for x, y in np.round(calibration.corners_px).astype(int):
        # A ring of the corner's row color around it (radius about a quarter of the spacing).
        patch = np.abs(overlay[y - 6:y + 7, x - 6:x + 7].astype(int) - photo[y - 6:y + 7, x - 6:x + 7]).max(axis=2)
        assert (patch > 60).mean() > 0.1


# --------------------------------------------------------------------------- stage serve


def test_serve_refuses_where_it_cannot_listen(tmp_path, capsys):
    # uvicorn logged these and exited 3 (or OverflowError's traceback for --port 99999);
    # now one line each, before anything is created.
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code, _, err = run(["serve", "--port", str(port), "--jobs", tmp_path / "jobs"], capsys)
    assert code == 2 and f"--port {port}: cannot listen there (Address already in use)" in err, err
    assert not (tmp_path / "jobs").exists()
    code, _, err = run(["serve", "--port", "99999"], capsys)
    assert code == 2 and "argument --port: '99999': expected a whole number from 1 to 65535" in err
    # An address of no interface here (TEST-NET-1; no name lookup needed).
    code, _, err = run(["serve", "--host", "192.0.2.1", "--jobs", tmp_path / "jobs"], capsys)
    assert code == 2 and "--host 192.0.2.1 --port 8000: cannot listen there" in err, err
    (tmp_path / "file").write_text("")
    code, _, err = run(["serve", "--jobs", tmp_path / "file" / "jobs"], capsys)
    assert code == 2 and f"--jobs {tmp_path / 'file' / 'jobs'}: {tmp_path / 'file'} is a file" in err, err
