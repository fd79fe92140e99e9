"""The synthetic photographer's ground truth, checked against the renders themselves."""
from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from skimage.measure import points_in_poly

from augment.camera.board import Board
from augment.render.furniture import PlacedItem, furniture_for, world_from_item
from augment.render.gl import Renderer, Scene, gl_from_cv_pose, pyrender, pyrender_camera
from augment.synth import CEILING, FLOOR, WALL, render_labels, render_sample, write_sample
from augment.synth.__main__ import main as synth_main
from augment.synth.camera import (CAMERA_HEIGHT_M, HFOV_DEG, PITCH_DOWN_DEG, Shot, look_pose, random_handling,
                                  random_shot)
from augment.synth.rooms import ROOM_SIDE_M, WALL_HEIGHT_M, random_polygon, random_room
from augment.synth.scene import SEG_FLOOR, SEG_WALL, _Batch
from augment.synth.truth import polygon_mask, project_floor_polygon, sun_exit
from layout.geometry import self_intersection

SEEDS = range(6)


@pytest.fixture(scope="module")
def renderer():
    with Renderer() as r:
        yield r


@pytest.fixture(scope="module")
def samples(renderer):
    return [render_sample(seed, renderer, size_px=(1280, 960)) for seed in SEEDS]


def _unproject(sample, mask):
    """World points (k, 3) of the pixels in ``mask``, from the rendered depth."""
    K = np.array(sample.truth["K"])
    world_from_camera = np.linalg.inv(np.array(sample.truth["camera_from_world"]))
    v, u = np.nonzero(mask & (sample.depth_m > 0))
    z = sample.depth_m[v, u].astype(np.float64)
    cam = np.column_stack([(u - K[0, 2]) / K[0, 0] * z, (v - K[1, 2]) / K[1, 1] * z, z])
    return cam @ world_from_camera[:3, :3].T + world_from_camera[:3, 3]


def test_board_corners_reproject_onto_detected_corners(samples, tmp_path):
    """Corners projected with the true K and pose land on OpenCV's detections in the
    written JPEG (< 0.5 px), with no systematic offset (a half-pixel convention slip
    would show as a bias of 0.5 px). Detections are refined with cornerSubPix, as the
    calibration does: the SB detector alone is off by up to 0.5 px on 9 px squares.
    Measured at 1280 x 960: median 0.03-0.1 px, worst corner 0.45 px, mean offset 0.02 px."""
    detected = 0
    offsets = []
    for k, sample in enumerate(samples):
        paths = write_sample(sample, tmp_path, f"{k:05d}")
        gray = cv2.imread(str(paths["image"]), cv2.IMREAD_GRAYSCALE)
        cols, rows = sample.truth["board"]["inner_corners"]
        found, corners = cv2.findChessboardCornersSB(gray, (cols, rows), flags=cv2.CALIB_CB_ACCURACY)
        if not found:
            continue
        detected += 1
        truth_px = np.array(sample.truth["board"]["corners_px"])
        step_px = np.linalg.norm(np.diff(truth_px.reshape(rows, cols, 2), axis=1), axis=-1).min()
        half = int(np.clip(0.4 * step_px, 2, 8))
        corners = cv2.cornerSubPix(gray, corners.reshape(-1, 1, 2).astype(np.float32), (half, half), (-1, -1),
                                   (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3)).reshape(-1, 2)
        assert all(sample.truth["board"]["corners_visible"])
        d = corners[:, None, :] - truth_px[None]
        nearest = np.argmin(np.linalg.norm(d, axis=-1), axis=1)
        assert len(set(nearest)) == cols * rows  # one-to-one
        err = corners - truth_px[nearest]
        assert np.linalg.norm(err, axis=1).max() < 0.5, (k, np.linalg.norm(err, axis=1).max())
        offsets.append(err.mean(axis=0))
    assert detected >= 4, f"board found in only {detected} of {len(samples)} renders"
    assert np.abs(np.mean(offsets, axis=0)).max() < 0.1


def test_floor_mask_matches_the_reprojected_floor_polygon(renderer):
    """Without clutter, the rendered floor is the floor polygon seen through K and the
    pose, less thin baseboards and door casings along the walls. In L- and U-shaped
    rooms a wall can hide part of the floor, so the full match is checked on rectangles
    and containment on every room."""
    rectangles = 0
    for seed in range(10, 30):
        sample = render_sample(seed, renderer, size_px=(640, 480), clutter=False, photographic=False)
        t = sample.truth
        polygon = np.array(t["room"]["polygon_m"])
        poly_px = project_floor_polygon(polygon, np.array(t["K"]), np.array(t["camera_from_world"]))
        expected = polygon_mask(poly_px, tuple(t["size_px"]))
        # Floor pixels outside the polygon are only anti-aliasing slivers at its edge.
        assert (sample.floor_mask & ~expected).sum() < 0.002 * expected.sum(), seed
        if len(polygon) == 4:
            rectangles += 1
            iou = (expected & sample.floor_mask).sum() / (expected | sample.floor_mask).sum()
            assert iou > 0.97, (seed, iou)
            if rectangles == 3:
                break
    assert rectangles == 3


def test_labels_follow_what_the_photo_shows_behind_a_two_sided_wall(renderer):
    """A camera 1.5 m up looks level at the back of a two-sided wall 5 m away, with floor
    on both sides. pyrender's label pass culls the wall's back face that the colour pass
    draws; the labels must still end the floor at the wall's foot, f * 1.5 / 5 = 150 px
    below the image center (the label of a back face is not known: it counts as other)."""
    f, size = 500.0, (640, 480)
    K = np.array([[f, 0, 319.5], [0, f, 239.5], [0, 0, 1]])
    scene = Scene(bg_color=np.ones(4))
    material = pyrender.MetallicRoughnessMaterial(baseColorFactor=(0.6, 0.6, 0.6, 1.0), doubleSided=True)
    floor, wall = _Batch(), _Batch()
    floor.quad([[-20, 0.2, 0], [20, 0.2, 0], [20, 30, 0], [-20, 30, 0]], [0, 0, 1.0])
    wall.quad([[-20, 5, 0], [20, 5, 0], [20, 5, 10], [-20, 5, 10]], [0, 1.0, 0])  # faces away
    seg_node_map = {scene.add(floor.mesh(material), name="mesh000"): SEG_FLOOR,
                    scene.add(wall.mesh(material), name="mesh001"): SEG_WALL}
    world_from_camera = look_pose([0, 0, 1.5], np.pi / 2, 0.0, 0.0)
    scene.add(pyrender_camera(K), pose=gl_from_cv_pose(world_from_camera), name="camera")
    _, depth_m = renderer.render(scene, *size)
    labels = render_labels(renderer, scene, seg_node_map, depth_m)
    foot_row = 239.5 + f * 1.5 / 5
    assert (labels[int(foot_row) + 2:] == FLOOR).all()
    assert not (labels[:int(foot_row) - 1] == FLOOR).any()


def test_board_pixels_count_as_floor(samples):
    for sample in samples:
        b = sample.truth["board"]
        pose = np.array(b["world_from_board"])
        board = Board(*b["inner_corners"], b["square_mm"], tuple(b["sheet_mm"]))
        outline = board.outline_m() @ pose[:3, :3].T + pose[:3, 3]
        K, cfw = np.array(sample.truth["K"]), np.array(sample.truth["camera_from_world"])
        inside = polygon_mask(project_floor_polygon(outline[:, :2], K, cfw), tuple(sample.truth["size_px"]))
        assert sample.floor_mask[inside].mean() > 0.98


def test_wall_height_seen_in_the_image_agrees(samples, renderer):
    """Ceiling pixels lie at the recorded wall height, floor pixels at zero."""
    for sample in samples:
        floor = _unproject(sample, sample.labels == FLOOR)
        assert len(floor) > 1000
        assert np.median(np.abs(floor[:, 2])) < 0.005
    # The ceiling shows in about one photo in six (the phone tilts 5-40 degrees down).
    with_ceiling = 0
    for seed in range(40):
        sample = render_sample(seed, renderer, size_px=(320, 240), clutter=False, photographic=False)
        ceiling = _unproject(sample, sample.labels == CEILING)
        if len(ceiling) > 100:
            with_ceiling += 1
            assert np.median(np.abs(ceiling[:, 2] - sample.truth["room"]["height_m"])) < 0.01
            if with_ceiling == 3:
                break
    assert with_ceiling == 3


def test_same_seed_same_photo_and_truth(renderer):
    a = render_sample(3, renderer, size_px=(320, 240))
    b = render_sample(3, renderer, size_px=(320, 240))
    c = render_sample(4, renderer, size_px=(320, 240))
    assert np.array_equal(a.image, b.image) and a.truth == b.truth
    assert not np.array_equal(a.image, c.image)


def test_floor_polygons_are_simple_and_counter_clockwise():
    shapes = set()
    for seed in range(2000):
        poly = random_polygon(np.random.default_rng(seed))
        shapes.add(len(poly))
        x, y = poly[:, 0], poly[:, 1]
        assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 2.5 ** 2 * 0.4  # CCW, not a sliver
        assert self_intersection(poly) is None
        # Every wall at least 0.5 m long, so doors and windows have room.
        assert np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1).min() > 0.5
    assert shapes == {4, 6, 8}  # rectangles, L and U shapes all occur


def test_rooms_and_cameras_stay_in_their_ranges():
    for seed in range(60):
        rng = np.random.default_rng(seed)
        room = random_room(rng)
        extent = room.polygon_m.max(axis=0) - room.polygon_m.min(axis=0)
        assert ROOM_SIDE_M[0] <= extent.min() and extent.max() <= ROOM_SIDE_M[1]
        assert WALL_HEIGHT_M[0] <= room.height_m <= WALL_HEIGHT_M[1]
        for o in room.openings:
            assert 0 <= o.bottom_m < o.top_m < room.height_m
        shot = random_shot(rng, room, random_handling(rng, (640, 480)))
        R, t = shot.world_from_camera[:3, :3], shot.world_from_camera[:3, 3]
        assert np.allclose(R.T @ R, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
        assert CAMERA_HEIGHT_M[0] <= t[2] <= CAMERA_HEIGHT_M[1]
        pitch = np.degrees(np.arcsin(-R[2, 2]))
        assert PITCH_DOWN_DEG[0] - 1e-9 <= pitch <= PITCH_DOWN_DEG[1] + 1e-9
        hfov = np.degrees(2 * np.arctan(320 / shot.K[0, 0]))
        assert HFOV_DEG[0] - 1e-9 <= hfov <= HFOV_DEG[1] + 1e-9


def test_look_pose_by_hand():
    # Level camera at 1 m looking along +y with a 3 degree roll: forward is +y, and the
    # image x axis dips by 3 degrees.
    pose = look_pose([0.0, 0.0, 1.0], np.pi / 2, 0.0, np.radians(3))
    assert np.allclose(pose[:3, 2], [0, 1, 0])
    assert np.isclose(abs(np.degrees(np.arcsin(pose[2, 0]))), 3.0)
    # 30 degrees down, no roll: the image x axis stays level and y points down-forward.
    pose = look_pose([0.0, 0.0, 1.5], 0.0, np.radians(30), 0.0)
    assert np.allclose(pose[:3, 0], [0, -1, 0])
    assert np.allclose(pose[:3, 2], [np.cos(np.pi / 6), 0, -0.5])
    assert pose[2, 1] < 0


def test_project_floor_polygon_by_hand():
    """A level camera 1 m up at the origin, looking along +x, f = 100 px, c = (50, 50):
    the floor point (4, -1) is 1 m right of and 1 m below the axis at 4 m depth, so at
    (75, 75); the part of the rectangle behind the camera is clipped away."""
    K = np.array([[100.0, 0, 50], [0, 100.0, 50], [0, 0, 1]])
    camera_from_world = np.linalg.inv(look_pose([0.0, 0.0, 1.0], 0.0, 0.0, 0.0))
    rectangle = np.array([[-1.0, -1.0], [4.0, -1.0], [4.0, 1.0], [-1.0, 1.0]])
    px = project_floor_polygon(rectangle, K, camera_from_world)
    assert np.isfinite(px).all() and len(px) == 4
    assert np.allclose(px[1], [75.0, 75.0]) and np.allclose(px[2], [25.0, 75.0])
    # The clipped edge lies at 1 cm depth: far below the image.
    assert (px[[0, 3], 1] > 1000).all()
    mask = polygon_mask(px, (100, 100))
    assert mask[80:, 30:70].all() and not mask[:75].any()


def test_shot_unprojects_pixels_by_hand():
    """The camera of the case above: pixel (75, 75) at 4 m depth is the floor point
    (4, -1, 0), (25, 25) at 2 m is (2, 0.5, 1.5); projecting them back gives the pixels."""
    shot = Shot(np.array([[100.0, 0, 50], [0, 100.0, 50], [0, 0, 1]]), look_pose([0.0, 0.0, 1.0], 0.0, 0.0, 0.0),
                (100, 100))
    points = shot.unproject(np.array([75, 25]), np.array([75, 25]), np.array([4.0, 2.0]))
    assert np.allclose(points, [[4.0, -1.0, 0.0], [2.0, 0.5, 1.5]])
    px, depth = shot.project(points)
    assert np.allclose(px, [[75, 75], [25, 25]]) and np.allclose(depth, [4.0, 2.0])


def test_board_geometry():
    board = Board(7, 5, 50)
    corners = board.corners_m()
    assert corners.shape == (35, 3)
    assert np.allclose(corners[1] - corners[0], [0.05, 0, 0]) and np.allclose(corners[7] - corners[0], [0, 0.05, 0])
    assert np.allclose(corners.mean(axis=0), 0)
    assert np.allclose(board.size_m, (0.5, 0.4))  # one-square margins
    image = board.image(px_per_square=10)
    assert image.shape == (6 * 10 + 20, 8 * 10 + 20)
    assert image[0].min() == 255 and image[10, 10] == 0 and image[10, 20] == 255
    with pytest.raises(ValueError, match="inner corners"):
        Board(1, 5, 50)


def test_default_board_fills_an_a3_sheet():
    board = Board()
    assert (board.cols, board.rows, board.square_mm) == (7, 5, 45.0)
    assert board.sheet_mm == (420.0, 297.0)
    image = board.image(px_per_square=45)  # 1 px per mm
    # 8 x 6 squares of 45 mm centered: margins of 30 mm left and right, 13.5 mm top and
    # bottom (whole pixels: 14, so the sheet image is 1 px taller than the paper).
    assert image.shape[1] == 420 and abs(image.shape[0] - 297) <= 1
    dark_rows, dark_cols = np.nonzero(image == 0)
    assert (dark_cols.min(), dark_cols.max()) == (30, 30 + 8 * 45 - 1)
    assert abs(dark_rows.min() - 13.5) <= 0.5 and dark_rows.max() - dark_rows.min() == 6 * 45 - 1
    with pytest.raises(ValueError, match="more than the 420 x 297 mm sheet"):
        Board(7, 5, 50, sheet_mm=(420.0, 297.0))


def test_cli_writes_a_dataset_and_a_contact_sheet(tmp_path, capsys):
    out = tmp_path / "ds"
    sheet = tmp_path / "sheet.png"
    code = synth_main(["--count", "3", "--seed", "5", "--out", str(out), "--size", "160x120",
                       "--workers", "1", "--sheet", str(sheet), "--quiet"])
    assert code == 0 and capsys.readouterr().out == ""
    for i in range(3):
        truth = json.loads((out / f"{i:05d}.json").read_text())
        assert truth["size_px"] == [160, 120] and truth["seed"] == [5, i]
        image = cv2.imread(str(out / truth["image"]))
        mask = cv2.imread(str(out / truth["floor_mask"]), cv2.IMREAD_GRAYSCALE)
        assert image.shape == (120, 160, 3) and mask.shape == (120, 160)
        assert set(np.unique(mask)) <= {0, 255} and (mask == 255).any()
    photos, truths = cv2.imread(str(sheet)), cv2.imread(str(tmp_path / "sheet_truth.png"))
    assert photos.shape == truths.shape and photos.shape[0] > 100
    assert not np.array_equal(photos, truths)  # the floor is tinted
    assert not list(out.glob(".*tmp"))  # atomic writes leave no temporaries


def test_cli_rejects_bad_arguments(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        synth_main(["--count", "2", "--out", str(tmp_path), "--size", "640by480"])
    assert exit_info.value.code == 2
    assert "--size '640by480'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        synth_main(["--count", "0", "--out", str(tmp_path)])
    assert "--count 0" in capsys.readouterr().err


def test_furnished_rooms_hide_the_floor_under_furniture(renderer):
    """With ``furnished=1`` every room gets catalog furniture, and the middle of each solid
    piece (a point inside its body) is not floor in the mask."""
    solid = {"sofa", "armchair", "bookcase", "wardrobe", "dresser", "bed", "tv_stand", "nightstand"}
    checked = 0
    for seed in range(8):
        sample = render_sample(seed, renderer, size_px=(640, 480), furnished=1.0, photographic=False)
        pieces = [c for c in sample.truth["room"]["clutter"] if c["kind"] not in ("box", "radiator")]
        assert pieces, f"seed {seed}: no furniture"
        K, cfw = np.array(sample.truth["K"]), np.array(sample.truth["camera_from_world"])
        for c in pieces:
            if c["kind"] not in solid:
                continue
            middle = np.append(np.mean(c["footprint_m"], axis=0), 0.5 * c["height_m"])
            p = cfw[:3, :3] @ middle + cfw[:3, 3]
            if p[2] <= 0.1:
                continue
            u, v = (K @ p)[:2] / p[2]
            if 0 <= u < 640 and 0 <= v < 480:
                assert not sample.floor_mask[int(v), int(u)], (seed, c["kind"])
                checked += 1
    assert checked >= 2


def test_cli_rejects_a_bad_furnished_chance(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        synth_main(["--count", "1", "--out", str(tmp_path), "--furnished", "1.5"])
    assert exit_info.value.code == 2
    assert "--furnished 1.5" in capsys.readouterr().err


def test_taller_baseboards_change_only_the_boards(renderer):
    """Another baseboard range keeps the random stream: the same room, camera and floor
    mask, and a few percent of the photo changes, most of it off the floor (the boards;
    the rest is their light and shade on the floor)."""
    default = render_sample(6, renderer, size_px=(320, 240), photographic=False)
    tall = render_sample(6, renderer, size_px=(320, 240), photographic=False, baseboard_m=(0.18, 0.18))
    assert tall.truth["camera_from_world"] == default.truth["camera_from_world"]
    assert tall.truth["room"] == default.truth["room"]
    assert np.array_equal(tall.floor_mask, default.floor_mask)
    changed = np.any(tall.image != default.image, axis=2)
    assert 0 < changed.mean() < 0.05
    assert (changed & ~tall.floor_mask).sum() >= 0.8 * changed.sum()


def _trim_and_floor_chromaticity(sample):
    """Mean r, g, b / (r + g + b) of the 3 px above the floor's top edge where they are
    not floor, wall or ceiling (the baseboard), and of the floor just below it."""
    def chroma(pixels):
        pixels = np.concatenate(pixels).astype(np.float64) + 1
        return (pixels / pixels.sum(axis=1, keepdims=True)).mean(axis=0)

    top = np.argmax(sample.floor_mask, axis=0)
    cols = np.flatnonzero(sample.floor_mask.any(axis=0) & (top > 6))
    trim = [sample.image[top[c] - 4:top[c] - 1, c] for c in cols
            if (sample.labels[top[c] - 4:top[c] - 1, c] == 0).all()]
    floor = [sample.image[top[c] + 2:top[c] + 6, c] for c in cols]
    return chroma(trim), chroma(floor)


@pytest.mark.parametrize("seed", [6, 7])
def test_trim_like_floor_paints_the_baseboards_the_floors_colour(renderer, seed):
    """The skirting check's hardest boards: the same room and camera, the boards of the
    floor's hue (a white or brown trim differs from these floors by 0.09-0.17 in
    chromaticity)."""
    default = render_sample(seed, renderer, size_px=(320, 240), photographic=False)
    hue = render_sample(seed, renderer, size_px=(320, 240), photographic=False, trim_like_floor=1.0)
    assert hue.truth["room"] == default.truth["room"]
    assert hue.truth["camera_from_world"] == default.truth["camera_from_world"]
    assert hue.truth["render"]["trim_like_floor"] and "trim_like_floor" not in default.truth["render"]
    trim, floor = _trim_and_floor_chromaticity(default)
    assert np.abs(trim - floor).max() > 0.06
    trim, floor = _trim_and_floor_chromaticity(hue)
    assert np.abs(trim - floor).max() < 0.04


@pytest.mark.parametrize("seed", [6, 7])
def test_trim_dark_paints_the_baseboards_dark(renderer, seed):
    """Charcoal or black boards, which the photographer's white and wood trims never are:
    the same room and camera, the boards' pixels far darker than before."""
    default = render_sample(seed, renderer, size_px=(320, 240), photographic=False)
    dark = render_sample(seed, renderer, size_px=(320, 240), photographic=False, trim_dark=1.0)
    assert dark.truth["room"] == default.truth["room"]
    assert dark.truth["camera_from_world"] == default.truth["camera_from_world"]
    assert dark.truth["render"]["trim_dark"] and "trim_dark" not in default.truth["render"]
    board = (default.labels == 0) & ~default.floor_mask  # the "other" class: trim, frames, doors
    top = np.argmax(default.floor_mask, axis=0)
    rows = np.arange(default.labels.shape[0])[:, None]
    board &= (rows >= top - 3) & (rows < top)  # just above the floor line: the baseboard
    assert board.sum() > 50
    assert dark.image[board].mean() < 0.7 * default.image[board].mean()
    assert dark.image[board].mean() < 90


@pytest.mark.parametrize("option", ["--trim-like-floor", "--trim-dark"])
def test_cli_rejects_a_bad_trim_chance(tmp_path, capsys, option):
    with pytest.raises(SystemExit) as exit_info:
        synth_main(["--count", "1", "--out", str(tmp_path / "new"), option, "-0.5"])
    assert exit_info.value.code == 2
    assert f"{option} -0.5" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()


def test_cli_rejects_a_bad_baseboard_range(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        synth_main(["--count", "1", "--out", str(tmp_path / "new"), "--baseboard-m", "0.3", "0.1"])
    assert exit_info.value.code == 2
    assert "--baseboard-m 0.3 0.1" in capsys.readouterr().err
    assert not (tmp_path / "new").exists()  # refused before anything was written


def test_floor_cells_cover_an_l_shaped_room_and_split_at_the_threshold():
    """By hand: a 4 x 3 m L-room missing its 2 x 1 m corner, cut at x = 1.5 m: the cells
    cover its 10 m^2 exactly, and those past the threshold its 2.5 x 2 + 0.5 x 1 m."""
    from augment.synth.scene import _floor_cells

    room = np.array([[0, 0], [4, 0], [4, 2], [2, 2], [2, 3], [0, 3]], float)
    cells = _floor_cells(room, {0: [1.5], 1: []})
    area = np.ptp(cells[:, :, 0], axis=1) * np.ptp(cells[:, :, 1], axis=1)
    assert area.sum() == pytest.approx(10.0)
    past = cells.mean(axis=1)[:, 0] > 1.5
    assert area[past].sum() == pytest.approx(2.5 * 2 + 0.5 * 1)
    # A cut outside the room changes nothing.
    assert np.ptp(_floor_cells(room, {0: [9.0], 1: [np.inf]})[:, :, 0], axis=1).sum() > 0


@pytest.mark.parametrize("seed", [3, 8])
def test_two_floors_keep_one_floor_mask_and_leave_the_board_on_the_first(renderer, seed):
    """A second floor material past a threshold is floor like the first: the same room
    and camera give the same floor mask; the second floor is in view, away from the
    board, and the photo's floor there differs from the floor around the board."""
    from augment.synth.scene import _second_floor

    default = render_sample(seed, renderer, size_px=(320, 240), photographic=False)
    two = render_sample(seed, renderer, size_px=(320, 240), photographic=False, two_floors=1.0)
    assert two.truth["room"] == default.truth["room"]
    assert "second_floor" in two.truth["render"] and "second_floor" not in default.truth["render"]
    assert two.truth["render"]["second_floor"]["area_m2"] > 0.5
    assert iou_of(two.floor_mask, default.floor_mask) > 0.99
    # The threshold is drawn never under the board, for any draw.
    rng = np.random.default_rng(0)
    room = random_room(rng)
    handling = random_handling(rng, (640, 480))
    shot = random_shot(rng, room, handling)
    center = room.polygon_m.mean(axis=0)
    for _ in range(50):
        inside, _, _ = _second_floor(rng, room, shot, center, 0.4)
        ring = center + 0.4 * np.column_stack([np.cos(np.linspace(0, 6.3, 16)), np.sin(np.linspace(0, 6.3, 16))])
        assert not inside(ring).any()


def test_a_far_second_floor_is_a_strip_along_a_wall():
    """``far``: the threshold runs 0.25-1.2 m before a wall (where the room leaves that
    much room past the board), mostly the wall the camera faces, never under the board."""
    from augment.synth.scene import _second_floor

    rng = np.random.default_rng(1)
    checked, faced = 0, 0
    for _ in range(40):
        room = random_room(rng)
        shot = random_shot(rng, room, random_handling(rng, (640, 480)))
        center = room.polygon_m.mean(axis=0)
        inside, cuts, _ = _second_floor(rng, room, shot, center, 0.4, far=True)
        ring = center + 0.4 * np.column_stack([np.cos(np.linspace(0, 6.3, 16)), np.sin(np.linspace(0, 6.3, 16))])
        assert not inside(ring).any()
        axis = 0 if len(cuts[0]) == 2 else 1
        line = cuts[axis][0]
        sign = np.sign(line - center[axis])
        wall = room.polygon_m[:, axis].max() if sign > 0 else room.polygon_m[:, axis].min()
        forward = shot.world_from_camera[:2, 2]
        faced += axis == int(np.argmax(np.abs(forward))) and sign == np.sign(forward[axis])
        if sign * (wall - center[axis]) - 0.4 > 1.4:
            checked += 1
            assert 0.25 <= sign * (wall - line) <= 1.2
    assert checked >= 20 and faced >= 20


def iou_of(a, b):
    return (a & b).sum() / (a | b).sum()


def test_low_sun_lands_on_the_floor_in_view(renderer):
    """A low, strong sun: 6-32 degrees above the horizon, through a window, aimed so that
    the sunlit patch of a window's middle lies in the room and in view (when some draw
    of 40 gets it there: on most photos)."""
    landed = []
    for seed in range(8):
        t = render_sample(seed, renderer, size_px=(320, 240), photographic=False, low_sun=1.0).truth
        suns = [light for light in t["render"]["lights"] if light["kind"] == "sun"]
        if not t["room"]["windows"]:
            assert not any(light.get("low") for light in suns)
            continue
        assert len(suns) == 1 and suns[0]["low"]
        d = np.array(suns[0]["direction"])
        assert 6 <= np.degrees(np.arcsin(-d[2])) <= 32
        K, camera_from_world = np.array(t["K"]), np.array(t["camera_from_world"])
        seen = []
        for w in t["room"]["windows"]:
            src = np.append(np.mean(w["segment_m"], axis=0), (w["bottom_m"] + w["top_m"]) / 2)
            patch = src + d * src[2] / -d[2]
            cam = camera_from_world[:3, :3] @ patch + camera_from_world[:3, 3]
            u, v, _ = K @ cam / cam[2]
            inside = points_in_poly(patch[None, :2], np.array(t["room"]["polygon_m"]))[0]
            seen.append(cam[2] > 0 and 0 <= u < 320 and 0 <= v < 240 and inside)
        landed.append(any(seen))
    assert len(landed) >= 5 and np.mean(landed) >= 0.75, landed



def test_sunlight_enters_only_through_the_windows(renderer):
    """The floor is in the sun where a ray toward the sun leaves through a window, and in
    the shade where it meets a wall or the ceiling: median light (linear) 1.6 times as
    high at least (1.9-5.2 on these seeds). pyrender's shadow maps cull faces turned from
    the sun: without the building's outside the walls let the sun through (0.9-1.3)."""
    checked = 0
    for seed in range(8):
        sample = render_sample(seed, renderer, size_px=(320, 240), photographic=False, clutter=False, low_sun=1.0)
        t = sample.truth
        sun = [light for light in t["render"]["lights"] if light["kind"] == "sun"]
        if not sun:
            continue
        floor = (sample.labels == FLOOR) & (sample.depth_m > 0)
        points = _unproject(sample, floor)
        windows = [(w["segment_m"], w["bottom_m"], w["top_m"]) for w in t["room"]["windows"]]
        verdict = sun_exit(points, sun[0]["direction"], np.array(t["room"]["polygon_m"]), t["room"]["height_m"],
                           windows, margin_m=0.1)
        light = ((sample.image[floor].astype(np.float64) / 255.0) ** 2.2).mean(axis=1)
        if (verdict == 1).sum() < 200 or (verdict == -1).sum() < 200:
            continue
        checked += 1
        assert np.median(light[verdict == 1]) > 1.6 * np.median(light[verdict == -1]), seed
        if checked == 1:  # without the outside the walls let the sun through
            flood = render_sample(seed, renderer, size_px=(320, 240), photographic=False, clutter=False,
                                  low_sun=1.0, outside=False)
            assert np.array_equal(flood.labels, sample.labels)
            lit = ((flood.image[floor].astype(np.float64) / 255.0) ** 2.2).mean(axis=1)
            assert np.median(lit[verdict == 1]) < 1.4 * np.median(lit[verdict == -1]), seed
        # The truth's share of the floor in view in the sun (every 4th pixel, no margin).
        assert (verdict == 1).mean() - 0.02 <= sun[0]["floor_in_view"] <= (verdict >= 0).mean() + 0.02, seed
    assert checked >= 3, checked


def test_a_shadowed_fill_lights_the_same_and_casts_shadows(renderer):
    """The realism benchmark's truth: with ``shadowed_fill`` the ceiling's fill light is a
    wide spot. The empty room looks the same (the same light below the horizontal); a
    cabinet (seed 1: a sideboard on legs) standing on the board's spot darkens the floor
    more than with the fill shining through it."""
    seed, size = [9700, 5], (640, 480)
    plain = render_sample(seed, renderer, size, clutter=False, photographic=False)
    spot = render_sample(seed, renderer, size, clutter=False, photographic=False, shadowed_fill=True)
    floor = plain.labels == FLOOR
    assert np.abs(plain.image.astype(int) - spot.image.astype(int))[floor].mean() < 1.0
    world_from_board = np.asarray(plain.truth["board"]["world_from_board"])
    item = PlacedItem("dresser", (0.0, 0.0, 0.4), 0.0, (0.8, 0.45, 0.8), "cabinet")
    pieces = [(furniture_for(item, 1), world_from_board @ world_from_item(item))]
    lit = [render_sample(seed, renderer, size, clutter=False, photographic=False, board_drawn=False, pieces=pieces,
                         shadowed_fill=shadowed) for shadowed in (False, True)]
    seen = (lit[0].labels == FLOOR) & (lit[1].labels == FLOOR)
    grey = [cv2.cvtColor(s.image, cv2.COLOR_RGB2GRAY).astype(float)[seen] for s in lit]
    assert grey[1].sum() < grey[0].sum()
    assert (grey[1] < grey[0] - 8).sum() > 400  # a shadow behind it (776 pixels), not a shade


def _plate_part(half_m, z_m, thickness_m=0.01):
    """A square plate (2 half_m a side), its underside at height z_m, item frame."""
    import trimesh

    from augment.render.furniture import Material, Part

    box = trimesh.creation.box((2 * half_m, 2 * half_m, thickness_m))
    box.apply_translation((0.0, 0.0, z_m + thickness_m / 2))
    return Part(np.asarray(box.vertices, float), np.asarray(box.vertex_normals, float), np.asarray(box.faces),
                Material("plate", (0.5, 0.5, 0.5)))


def test_bounce_visibility_under_a_plate_is_the_view_factor(renderer):
    """Below the centre of a square plate, the share of a uniform sky seen is one minus
    the plate's view factor (four corner rectangles: the textbook formula for a plane
    element below a corner of a parallel rectangle); far away, all of it."""
    from augment.render.furniture import Furniture
    from augment.render.staged import hemisphere_directions
    from augment.synth.bounce import bounce_visibility

    d = hemisphere_directions(48)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0) and (d[:, 2] > 0).all()
    # Cosine-weighted: the mean of cos(theta) over the hemisphere so weighted is 2/3.
    assert abs(d[:, 2].mean() - 2 / 3) < 0.01
    half, z = 0.5, 0.7
    plate = Furniture("plate", "test", (2 * half, 2 * half, z), (_plate_part(half, z),))
    seen = bounce_visibility(renderer, [(plate, np.eye(4))], np.array([[0.0, 0.0, 0.0], [20.0, 0.0, 0.0]]))
    a = b = half / z
    corner = (a / np.hypot(1, a) * np.arctan(b / np.hypot(1, a)) + b / np.hypot(1, b) * np.arctan(a / np.hypot(1, b)))
    view_factor = 4 * corner / (2 * np.pi)
    assert 0.3 < view_factor < 0.5  # the case is a telling one
    assert abs(seen[0] - (1 - view_factor)) < 0.05
    assert seen[1] == 1.0
    # A wall point facing +x, the plate standing 0.7 m in front of it, parallel: the same
    # view factor about the wall's normal. Facing +y, the plate 2-3 m to that side hides
    # about 1 % (its solid angle times its cosine over pi).
    upright = np.array([[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 1.5], [0, 0, 0, 1.0]])  # item z -> world x
    wall = np.array([[0.0, 0.0, 1.5]])
    facing = bounce_visibility(renderer, [(plate, upright)], wall, (1.0, 0.0, 0.0))
    assert abs(facing[0] - (1 - view_factor)) < 0.05
    aside = upright + np.array([[0, 0, 0, 0], [0, 0, 0, 2.5], [0, 0, 0, 0], [0, 0, 0, 0]])
    beside = bounce_visibility(renderer, [(plate, aside)], wall, (0.0, 1.0, 0.0))
    assert beside[0] >= 0.95  # 1 % is under one of 48 directions


def test_occluded_bounce_darkens_only_the_floor_and_walls_near_furniture(renderer):
    from augment.render.furniture import Furniture

    seed = 3
    plain = render_sample(seed, renderer, size_px=(320, 240), clutter=False, photographic=False)
    board_xy = np.asarray(plain.truth["board"]["world_from_board"])[:2, 3]
    plate = Furniture("plate", "test", (0.8, 0.8, 0.5), (_plate_part(0.4, 0.5),))
    pose = np.eye(4)
    pose[:2, 3] = board_xy
    pieces = [(plate, pose)]
    through = render_sample(seed, renderer, size_px=(320, 240), clutter=False, photographic=False,
                            board_drawn=False, pieces=pieces)
    hidden = render_sample(seed, renderer, size_px=(320, 240), clutter=False, photographic=False,
                           board_drawn=False, pieces=pieces, occluded_bounce=True)
    floor = hidden.labels == FLOOR
    lit = floor | (hidden.labels == WALL)
    assert np.array_equal(hidden.image[~lit], through.image[~lit])
    darker = hidden.image.astype(int).sum(axis=2) < through.image.astype(int).sum(axis=2)
    assert (hidden.image.astype(int) <= through.image.astype(int)).all()
    # The walls lose less the farther they are from the plate, and less than the floor under it.
    loss = (through.image.astype(int) - hidden.image.astype(int)).max(axis=2)
    wall = hidden.labels == WALL
    away = np.linalg.norm(_unproject(hidden, wall)[:, :2] - board_xy, axis=1)
    assert np.median(loss[wall][away < 1.0]) > np.median(loss[wall][away >= 1.0])
    under = np.linalg.norm(_unproject(hidden, floor)[:, :2] - board_xy, axis=1) < 0.3
    assert np.percentile(loss[wall], 99) < np.median(loss[floor & (hidden.depth_m > 0)][under])
    # The floor under the plate, seen between its edge and the floor: darker.
    rows, cols = np.nonzero(floor & darker)
    assert len(rows) > 50
    points = _unproject(hidden, floor & darker)
    assert np.median(np.linalg.norm(points[:, :2] - board_xy, axis=1)) < 0.8
    with pytest.raises(ValueError, match="choose one"):
        render_sample(seed, renderer, size_px=(320, 240), occluded_bounce=True, shadowed_fill=True)
