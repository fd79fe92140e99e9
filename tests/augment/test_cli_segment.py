"""``stage segment``: the floor mask, overlay and polygon of a sample photo with ground
truth (samples/photos/room_4, a synthetic render), and its refusals."""
from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from augment.app import cli

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
    assert report["method"] == "onnx+grabcut" and 0 <= report["disputed_share"] < 0.1
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
    # Every command that reads the photo refuses it alike, naming it (not "no board found").
    # So is a strip cut from a panorama (its board search copy would be 10 px high) and
    # an empty file.
    # A photo cut short (a copy that stopped) and a TIFF of floats are said to be so, not
    # "not an image".
    strip, empty, text = tmp_path / "strip.png", tmp_path / "empty.jpg", tmp_path / "text.jpg"
    cut, floats = tmp_path / "cut.jpg", tmp_path / "floats.tif"
    cv2.imwrite(str(strip), np.zeros((64, 8000, 3), np.uint8))
    empty.write_bytes(b"")
    text.write_text("not a photo")
    cut.write_bytes(Path(PHOTO).read_bytes()[:-5000])
    Image.fromarray(np.zeros((480, 640), np.float32)).save(floats)
    refusals = {tiny: ["is 30 x 20 px: too small", "64 px"],
                strip: ["is 8000 x 64 px, 125 times as wide as it is high", "at most 4 to 1", "panorama"],
                empty: ["is empty (0 bytes)"], text: ["is not an image Stager can read", "JPEG"],
                cut: ["is cut short: a JPEG file that ends before its picture does", "copy it again"],
                floats: ["is a TIFF of floating-point samples", "8- or 16-bit"]}
    for photo, needles in refusals.items():
        for argv in (["segment", photo, "--out", tmp_path / "b.png"], ["measure", photo, "--out", tmp_path / "m"],
                     ["furnish", photo, "--out", tmp_path / "f"]):
            code, _, err = run(argv, capsys)
            assert code == 2 and err.startswith(f"error: photo {photo} ") and err.count("\n") == 1, (argv, err)
            assert all(n in err for n in needles), (argv, err)
    # The mask written over the photo it was found in: refused, the photo intact.
    own = tmp_path / "own.png"
    cv2.imwrite(str(own), cv2.imread(str(PHOTO)))
    before = own.read_bytes()
    code, _, err = run(["segment", own, "--out", own], capsys)
    assert code == 2 and f"--out {own}: is the input {own}" in err and own.read_bytes() == before
    code, _, err = run(["segment", PHOTO, "--mean", "1,2", "--out", tmp_path / "c.png"], capsys)
    assert code == 2 and "R,G,B" in err
    # A model given with --method grabcut was ignored silently.
    for extra, flag in ((["--model", PHOTO], "--model"), (["--floor-class", "2"], "--floor-class")):
        code, _, err = run(["segment", PHOTO, "--method", "grabcut", *extra, "--out", tmp_path / "d.png"], capsys)
        assert code == 2 and err.startswith(f"error: {flag}: no model is used with --method grabcut"), err
    for option, value, words in (("--mean", "nan,0,0", "R,G,B"), ("--input-size", "100000x100000", "to 4096")):
        code, _, err = run(["segment", PHOTO, option, value, "--out", tmp_path / "c.png"], capsys)
        assert code == 2 and f"argument {option}: '{value}'" in err and words in err, err
    # A profile that is not there is an error, not a photo "without calibration".
    code, _, err = run(["segment", PHOTO, "--camera", tmp_path / "none.json", "--out", tmp_path / "c.png"], capsys)
    assert code == 2 and "--camera" in err and "stage calibrate" in err
    assert not any(tmp_path.glob("[abc]*.png"))


def test_segment_loads_neither_the_solver_nor_matplotlib(tmp_path):
    # Finding the floor needs no layout solver (numba kernels) and no plots: importing
    # them cost `stage segment` about a second of its 2.5 s.
    code = ("import sys; from augment.app import cli; "
            f"assert cli.main(['segment', {str(PHOTO)!r}, '--out', {str(tmp_path / 'f.png')!r}, '-q']) == 0; "
            "print(sorted(m for m in ('numba', 'matplotlib', 'layout.builder', 'augment.pipeline') "
            "if m in sys.modules))")
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]" and (tmp_path / "f.png").is_file()


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
    # The user's height stands in for the fallback, said so.
    code, out, err = run(["measure", PHOTO, "--height", "2.7", "--out", tmp_path / "h"], capsys)
    report = json.loads((tmp_path / "h" / "report.json").read_text())
    assert code == 0 and report["height"]["given"] and report["height"]["height_m"] == 2.7
    assert report["height"]["reason"].endswith("using the given 2.7 m") and "given with --height" in out


def _painted_rectangle(width_m: float, depth_m: float, scale: float = 1.0) -> np.ndarray:
    """A floor mask (255 = floor) of a width_m x depth_m rectangle centered on room_4's
    board, painted through the render's true camera, its image ``scale`` times the photo's."""
    truth = json.loads((SAMPLES / "room_4.json").read_text())
    camera_from_board = np.array(truth["camera_from_world"]) @ np.array(truth["board"]["world_from_board"])
    w, d = width_m / 2, depth_m / 2
    corners = np.array([[-w, -d, 0, 1], [w, -d, 0, 1], [w, d, 0, 1], [-w, d, 0, 1]], float).T
    uvw = np.array(truth["K"]) @ (camera_from_board @ corners)[:3]
    px = (uvw[:2] / uvw[2]).T * scale
    cols, rows = (round(v * scale) for v in truth["size_px"])
    assert np.all((px > 0) & (px < [cols, rows]))  # the rectangle is in view
    mask = np.zeros((rows, cols), np.uint8)
    cv2.fillPoly(mask, [np.round(px * 16).astype(np.int32)], 255, cv2.LINE_AA, shift=4)
    return mask


def _sides_m(polygon) -> list:
    p = np.array(polygon)
    return sorted(np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1).round(3))


def test_measure_with_the_users_floor_mask(tmp_path, capsys):
    # A user paints a 1.2 x 0.8 m rectangle of the floor: the floor measured is that
    # rectangle, whether the mask is the photo's size, half of it, or a layer of white
    # painted opaque on transparent white.
    rectangle = _painted_rectangle(1.2, 0.8)
    layer = np.dstack([np.full(rectangle.shape + (3,), 255, np.uint8), rectangle])
    for name, image in (("full.png", rectangle), ("half.png", _painted_rectangle(1.2, 0.8, 0.5)),
                        ("layer.png", layer)):
        mask = tmp_path / name
        cv2.imwrite(str(mask), image)
        before = hashlib.sha256(mask.read_bytes()).hexdigest()
        code, out, err = run(["measure", PHOTO, "--floor-mask", mask, "--out", tmp_path / name[:-4]], capsys)
        assert code == 0, err
        assert hashlib.sha256(mask.read_bytes()).hexdigest() == before
        floor = json.loads((tmp_path / name[:-4] / "report.json").read_text())["floor"]
        assert floor["method"] == "user mask" and "(user mask)" in out
        assert abs(floor["area_m2"] - 0.96) < 0.03 * 0.96, floor
        sides = _sides_m(floor["polygon_m"])
        assert len(sides) == 4 and np.allclose(sides, [0.8, 0.8, 1.2, 1.2], rtol=0.03), sides


def test_a_photo_or_mask_that_cannot_be_read_is_named(tmp_path, capsys, monkeypatch):
    # As a user without read permission sees it (root, running the tests, may read all).
    mask = tmp_path / "mask.png"
    cv2.imwrite(str(mask), _painted_rectangle(1.2, 0.8))
    real_read = Path.read_bytes

    def read_bytes(path):
        if path.name in ("room_4.jpg", "mask.png") and locked[0] == path.name:
            raise PermissionError(13, "Permission denied")
        return real_read(path)

    monkeypatch.setattr(Path, "read_bytes", read_bytes)
    locked = ["room_4.jpg"]
    code, _, err = run(["segment", PHOTO, "--out", tmp_path / "a.png"], capsys)
    assert code == 2 and err == f"error: photo {PHOTO} cannot be read (Permission denied); check that you may read it\n"
    locked = ["mask.png"]
    code, _, err = run(["measure", PHOTO, "--floor-mask", mask, "--out", tmp_path / "m"], capsys)
    assert code == 2 and f"floor mask {mask}: cannot be read (Permission denied)" in err and err.count("\n") == 1
    assert not any(tmp_path.glob("a*.png")) and not (tmp_path / "m").exists()


def test_a_floor_mask_is_read_upright_alpha_and_all(tmp_path, monkeypatch):
    # An editor's layer: white everywhere, opaque (floor) on the stored image's left
    # quarter only, saved with an EXIF turn. The alpha turns with the colour; so does a
    # 16-bit grey mask's floor, whose mid greys count at half of 65535, not of 255.
    from PIL import Image

    from augment.floor.segment import read_floor_mask

    stored = np.zeros((60, 80), np.uint8)
    stored[:, :20] = 255
    stored[10:20, 40:50] = 140  # a stroke at 55 % grey: floor
    stored[30:40, 40:50] = 110  # at 43 %: not floor
    layer = np.dstack([np.full((60, 80, 3), 255, np.uint8), stored])
    turns = {1: lambda a: a, 3: lambda a: np.rot90(a, 2), 6: lambda a: np.rot90(a, -1), 8: lambda a: np.rot90(a, 1)}
    for orientation, upright in turns.items():
        truth = upright(stored) > 127
        for name, image in (("layer", Image.fromarray(layer, "RGBA")),
                            ("grey16", Image.fromarray(stored.astype(np.uint16) * 257))):
            exif = Image.Exif()
            exif[0x0112] = orientation
            path = tmp_path / f"{name}_{orientation}.png"
            image.save(path, exif=exif.tobytes())
            seg = read_floor_mask(path, truth.shape[::-1])
            assert np.array_equal(seg.mask, truth), (name, orientation)
    # A mask drawn at a 200 MP photo's size is past Pillow's size guard (here set at 1,000
    # pixels, which refuses over twice that): read all the same.
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1_000)
    assert np.array_equal(read_floor_mask(path, truth.shape[::-1]).mask, truth)


def test_bad_floor_masks_are_refused(tmp_path, capsys):
    good = _painted_rectangle(1.2, 0.8)
    cases = {"missing.png": None,
             "text.png": b"not a picture",
             "tall.png": cv2.transpose(good),                    # turned a quarter
             "wide.png": np.zeros((960, 1500), np.uint8),        # another shape
             "black.png": np.zeros_like(good),                   # no floor
             "inverted.png": 255 - good,                         # the board on "not floor"
             "line.png": _painted_rectangle(1.2, 0.004),         # a line, no floor to outline
             "photo.png": cv2.imread(str(PHOTO))}                # the photo itself, by mistake
    needles = {"missing.png": ["no such file", "stage segment"], "text.png": ["not an image"],
               "tall.png": ["960 x 1280", "1280 x 960", "turned a quarter"], "wide.png": ["1500 x 960"],
               "black.png": ["no floor in it"], "inverted.png": ["board's center", "inverted"],
               "line.png": ["no floor outline", "a pixel or two wide", "not a line"],
               "photo.png": ["of its pixels are neither near black nor near white", "looks like a photo"]}
    for name, content in cases.items():
        path = tmp_path / name
        if isinstance(content, bytes):
            path.write_bytes(content)
        elif content is not None:
            cv2.imwrite(str(path), content)
        code, _, err = run(["measure", PHOTO, "--floor-mask", path, "--out", tmp_path / "m"], capsys)
        assert code == 2 and err.startswith("error: ") and err.count("\n") == 1, err
        assert f"{path}" in err and all(n in err for n in needles[name]), err
        assert not (tmp_path / "m").exists()
    code, _, err = run(["measure", PHOTO, "--floor-mask", tmp_path / "tall.png", "--model", tmp_path / "x.onnx"],
                       capsys)
    assert code == 2 and "not allowed with" in err


def _inside_point(region):
    """The pixel farthest from the region's edge, as (x, y)."""
    depth = cv2.distanceTransform(np.pad(region, 1).astype(np.uint8), cv2.DIST_L2, 5)[1:-1, 1:-1]
    y, x = np.unravel_index(int(np.argmax(depth)), depth.shape)
    return int(x), int(y)


def test_segment_with_clicks_records_and_marks_them(tmp_path, capsys):
    from augment.draw.settings import DRAW

    truth = truth_mask()
    fx, fy = _inside_point(truth)
    col = truth.shape[1] // 2
    wx, wy = col, int(np.argmax(truth[:, col])) - 40  # the far wall, above the floor's edge
    code, _, err = run(["segment", PHOTO, "--floor-at", f"{fx},{fy}", "--not-floor-at", f"{wx},{wy}",
                        "--out", tmp_path / "f.png", "-q"], capsys)
    assert code == 0, err
    report = json.loads((tmp_path / "f.json").read_text())
    assert report["clicks"] == [{"x_px": fx, "y_px": fy, "floor": True}, {"x_px": wx, "y_px": wy, "floor": False}]
    mask = cv2.imread(str(tmp_path / "f.png"), cv2.IMREAD_GRAYSCALE) > 0
    assert mask[fy, fx] and not mask[wy, wx]
    truth_iou = np.logical_and(mask, truth).sum() / np.logical_or(mask, truth).sum()
    assert truth_iou > 0.95
    overlay = cv2.imread(str(tmp_path / "f_overlay.png"))[..., ::-1]
    colors = DRAW.floor.click_colors
    assert tuple(overlay[fy, fx]) == colors[1] and tuple(overlay[wy, wx]) != colors[1]
    assert tuple(overlay[wy - 8, wx]) == colors[0]  # the red disc, between the arms of its white cross


def test_bad_clicks_are_refused(tmp_path, capsys):
    cases = [(["segment", PHOTO, "--floor-at", "12"], ["--floor-at", "'12'", "give X,Y"]),
             (["segment", PHOTO, "--not-floor-at", "a,b"], ["--not-floor-at", "'a,b'"]),
             (["segment", PHOTO, "--floor-at", "5000,10"], ["floor at 5000,10", "outside the photo (1280 x 960 px)"]),
             # room_1's horizon crosses its middle column 48 px below the top.
             (["segment", PHOTO.with_name("room_1.jpg"), "--floor-at", "640,20"],
              ["floor at 640,20", "above the horizon"]),
             (["measure", PHOTO, "--floor-mask", PHOTO, "--not-floor-at", "10,900"],
              ["--not-floor-at 10,900", "--floor-mask", "used as it is"]),
             (["furnish", PHOTO, PHOTO.with_name("room_1.jpg"), "--floor-at", "10,900"],
              ["--floor-at 10,900", "one photo"])]
    for argv, needles in cases:
        code, _, err = run([*argv, "--out", tmp_path / "x" / "floor.png" if argv[0] == "segment" else tmp_path / "x"],
                           capsys)
        assert code == 2 and err.count("\n") <= 2, err
        assert all(n in err for n in needles), err
        assert not (tmp_path / "x").exists()


def test_one_click_brings_back_floor_in_a_cartons_shadow(tmp_path, capsys):
    """room_2: the floor in the shadow of the carton at the left edge is missed; one click
    there brings it back, to the render's true 16.96 m² of floor in view."""
    photo = SAMPLES / "room_2.jpg"
    truth = cv2.imread(str(SAMPLES / "room_2_floor.png"), cv2.IMREAD_GRAYSCALE) > 127
    areas, masks = [], []
    for name, clicks in (("found", []), ("clicked", ["--floor-at", "16,196"])):
        code, _, err = run(["segment", photo, *clicks, "--out", tmp_path / name / "floor.png", "-q"], capsys)
        assert code == 0, err
        areas.append(json.loads((tmp_path / name / "floor.json").read_text())["floor"]["area_m2"])
        masks.append(cv2.imread(str(tmp_path / name / "floor.png"), cv2.IMREAD_GRAYSCALE) > 0)
    # As found, the floor is 1.1 % short (0.9 % with the previous skirting models; more
    # before the mask's edge moved up to the floor line where GrabCut stopped short of it).
    assert areas[0] < 16.96 * 0.995 and abs(areas[1] - 16.96) < 0.01 * 16.96, areas
    shadow = np.zeros_like(truth)
    shadow[100:300, :120] = True  # the photo's left edge, below the carton
    assert (truth & shadow & ~masks[1]).sum() < 0.3 * (truth & shadow & ~masks[0]).sum()
    # GrabCut runs again on the whole photo, so edges elsewhere move by a pixel or so, and
    # the foot of the carton's shaded face, of the shadow's colour, comes with the floor
    # (2,420 pixels of floor brought back against 1,982 taken wrongly; with the region a
    # disc of 5 % of the long side, 2,365 against 1,276; since the edge moves up to the
    # floor line without a click, 2,025 against 1,935; since that step reads the rows above
    # square-on walls too, it finds more of the far floor itself and the click's gains
    # elsewhere shrink: 1,679 against 1,949, of which 1,537 floor and 1,868 carton face in
    # the shadow's box). A known weakness, bounded here so that it cannot grow unseen: the
    # click takes the carton's shaded foot nearly as much as the floor it brings back.
    gained = (masks[1] & truth & ~masks[0]).sum()
    assert (masks[1] & ~truth & ~masks[0]).sum() < 1.25 * gained, gained


def test_floor_mask_white_above_the_horizon(tmp_path, capsys):
    """No floor shows above the horizon (room_1's crosses the photo near its top): white
    there is left out with a warning where a brush spilled over, and a mask white over
    the walls up to there is refused."""
    from augment.camera.board import Board
    from augment.camera.calibrate import calibrate_file
    from augment.floor.segment import below_horizon

    photo = SAMPLES / "room_1.jpg"
    truth = cv2.imread(str(SAMPLES / "room_1_floor.png"), cv2.IMREAD_GRAYSCALE) > 127
    horizon = calibrate_file(photo, Board()).horizon
    horizon = horizon / np.hypot(*horizon[:2])
    sky = ~below_horizon(truth.shape, horizon)
    spill = sky & below_horizon(truth.shape, horizon, -20.0)  # a brush 20 px over the horizon
    spill[:, :300] = spill[:, 900:] = False
    for name, mask in (("spilled.png", truth | spill), ("walls.png", truth | sky)):
        share = (mask & sky).sum() / mask.sum()
        path = tmp_path / name
        cv2.imwrite(str(path), mask.astype(np.uint8) * 255)
        code, out, err = run(["measure", photo, "--floor-mask", path, "--out", tmp_path / name[:-4]], capsys)
        if name == "spilled.png":
            assert 0.005 < share < 0.1 and code == 0, (share, err)
            assert f"{share:.1%} of its white lies above the horizon" in err and "left out" in err, err
            floor = json.loads((tmp_path / "spilled" / "report.json").read_text())["floor"]
            code, _, err = run(["measure", photo, "--floor-mask", SAMPLES / "room_1_floor.png",
                                "--out", tmp_path / "truth"], capsys)
            assert code == 0 and "above the horizon" not in err, err
            assert floor == json.loads((tmp_path / "truth" / "report.json").read_text())["floor"]
        else:
            assert share > 0.1 and code == 2 and err.count("\n") == 1, (share, err)
            assert f"{share:.0%} of its white lies above the horizon" in err and "paint only the floor" in err, err


def test_a_board_printed_at_another_scale_is_said(tmp_path, capsys):
    """Every length scales with --square: given 5 or 150 mm for room_3's 45 mm squares,
    the camera comes out 5/45 and 150/45 of its true height, outside where people hold a
    phone (0.3-2.5 m); the warning says so, and what the squares would measure with the
    camera 1.0-1.8 m up, which brackets the true 45 mm."""
    import re

    from augment.camera.board import Board
    from augment.camera.calibrate import calibrate_file

    photo = SAMPLES / "room_3.jpg"
    height_m = calibrate_file(photo, Board()).camera_height_m
    assert 1.0 < height_m < 1.8
    code, _, err = run(["segment", photo, "--out", tmp_path / "right.png"], capsys)
    assert code == 0 and "m above the floor" not in err, err
    for square in (5, 150):
        code, _, err = run(["segment", photo, "--square", square, "--out", tmp_path / f"{square}.png"], capsys)
        found = re.search(r"the camera comes out ([\d.]+) m above the floor, by the board's squares of "
                          rf"{square} mm: .* give it as --square \(with the camera 1-1.8 m up, they would be "
                          r"(\d+)-(\d+) mm\)", err)
        assert code == 0 and found, err
        assert float(found[1]) == pytest.approx(height_m * square / 45, abs=0.006)
        assert int(found[2]) < 45 < int(found[3])
