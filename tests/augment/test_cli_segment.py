"""``stage segment``: the floor mask, overlay and polygon of a sample photo with ground
truth (samples/photos/room_4, a synthetic render), and its refusals."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import cv2
import numpy as np

from augment import cli

SAMPLES = Path(__file__).resolve().parents[2] / "samples" / "photos"
PHOTO = SAMPLES / "room_4.jpg"


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def truth_mask():
    return cv2.imread(str(SAMPLES / "room_4_floor.png"), cv2.IMREAD_GRAYSCALE) > 127


def test_segment_writes_mask_overlay_and_polygon(tmp_path, capsys):
    before = hashlib.sha256(PHOTO.read_bytes()).hexdigest()
    code, out, err = run(["segment", PHOTO, "--out", tmp_path / "r4" / "floor.png"], capsys)
    assert code == 0, err
    mask = cv2.imread(str(tmp_path / "r4" / "floor.png"), cv2.IMREAD_UNCHANGED)
    assert mask.shape == (960, 1280) and set(np.unique(mask)) <= {0, 255}
    truth = truth_mask()
    assert np.logical_and(mask > 0, truth).sum() / np.logical_or(mask > 0, truth).sum() > 0.95
    overlay = cv2.imread(str(tmp_path / "r4" / "floor_overlay.png"))
    assert overlay.shape == (960, 1280 + 960, 3)
    report = json.loads((tmp_path / "r4" / "floor.json").read_text())
    assert report["method"] == "onnx+grabcut"
    assert len(report["floor"]["polygon_m"]) == len(report["floor"]["edge_kind"]) >= 3
    # The room's truth: 12.1 m^2 of floor in view (benchmarks/segmentation.py measures many).
    assert abs(report["floor"]["area_m2"] - 12.1) < 0.6
    assert "12." in out and "m\u00b2" in out
    assert hashlib.sha256(PHOTO.read_bytes()).hexdigest() == before


def test_segment_with_grabcut_alone(tmp_path, capsys):
    code, _, err = run(["segment", PHOTO, "--method", "grabcut", "--out", tmp_path / "g.png", "-q"], capsys)
    assert code == 0, err
    mask = cv2.imread(str(tmp_path / "g.png"), cv2.IMREAD_GRAYSCALE) > 0
    truth = truth_mask()
    assert np.logical_and(mask, truth).sum() / np.logical_or(mask, truth).sum() > 0.9


def test_photo_without_board_is_segmented_with_a_warning(tmp_path, capsys):
    image = cv2.imread(str(PHOTO))
    board_free = image[:400]  # the top of the room: walls and far floor, no board
    path = tmp_path / "top.png"
    cv2.imwrite(str(path), board_free)
    code, _, err = run(["segment", path, "--out", tmp_path / "m.png", "-q"], capsys)
    assert code == 0 and "no calibration" in err and "board" in err
    assert (tmp_path / "m.png").exists() and (tmp_path / "m_overlay.png").exists()
    assert not (tmp_path / "m.json").exists()  # no board, no metric polygon
    code, _, err = run(["segment", path, "--method", "grabcut", "--out", tmp_path / "n.png"], capsys)
    assert code == 2 and "--method grabcut needs the board" in err
    assert not (tmp_path / "n.png").exists()


def test_segment_refusals_name_the_problem(tmp_path, capsys):
    code, _, err = run(["segment", PHOTO, "--out", tmp_path / "floor.jpg"], capsys)
    assert code == 2 and "--out" in err and ".png" in err
    code, _, err = run(["segment", PHOTO, "--model", tmp_path / "none.onnx", "--out", tmp_path / "a.png"], capsys)
    assert code == 2 and "none.onnx" in err and "grabcut" in err
    tiny = tmp_path / "tiny.png"
    cv2.imwrite(str(tiny), np.zeros((20, 30, 3), np.uint8))
    code, _, err = run(["segment", tiny, "--out", tmp_path / "b.png"], capsys)
    assert code == 2 and "too small" in err
    code, _, err = run(["segment", PHOTO, "--mean", "1,2", "--out", tmp_path / "c.png"], capsys)
    assert code == 2 and "R,G,B" in err
    # A profile that is not there is an error, not a photo "without calibration".
    code, _, err = run(["segment", PHOTO, "--camera", tmp_path / "none.json", "--out", tmp_path / "c.png"], capsys)
    assert code == 2 and "--camera" in err and "stage calibrate" in err
    assert not any(tmp_path.glob("[abc]*.png"))


def test_measure_writes_the_report_and_three_overlays(tmp_path, capsys):
    code, out, err = run(["measure", PHOTO, "--out", tmp_path / "m"], capsys)
    assert code == 0, err
    report = json.loads((tmp_path / "m" / "report.json").read_text())
    assert report["calibration"]["intrinsics"]["source"] == "single-view"
    truth = json.loads((SAMPLES / "room_4.json").read_text())
    height = truth["camera"]["height_m"] - 0.001  # the paper lies 1 mm up
    assert abs(report["calibration"]["camera_height_m"] - height) / height < 0.02
    assert abs(report["floor"]["area_m2"] - 12.1) < 0.6
    # This photo does not show the ceiling: the height is the stated fallback, said twice.
    assert report["height"]["fallback"] and report["height"]["height_m"] == 2.5
    assert "wall height not measured" in err and "assumed" in out
    for name in ("overlay_calibration.png", "overlay_floor.png", "overlay_height.png"):
        assert cv2.imread(str(tmp_path / "m" / name)).shape[0] == 960
    assert set(report["timings"]) == {"calibrate_s", "segment_s", "height_s"}
