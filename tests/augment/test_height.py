"""Wall height from vertical edges: hand-built cameras and rooms with known answers, and
synthetic renders with exact ground truth."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import augment.synth.camera as synth_camera
from augment.camera import lines as L
from augment.camera.board import Board
from augment.camera.calibrate import calibrate_file
from augment.camera.settings import CAMERA
from augment.draw.height import height_overlay
from augment.draw.settings import DRAW
from augment.render.gl import Renderer
from augment.room import height as H
from augment.room.settings import ROOM
from augment.synth import render_sample
from augment.synth.camera import look_pose

SAMPLES = Path(__file__).resolve().parents[2] / "samples" / "photos"
SIZE = (640, 480)
K = np.array([[480.0, 0.0, 319.5], [0.0, 480.0, 239.5], [0.0, 0.0, 1.0]])
# A camera 1.4 m up in a 7 x 5 m room, looking across it 3 degrees down, rolled 2 degrees.
CAMERA_FROM_FLOOR = np.linalg.inv(look_pose([0.0, 0.0, 1.4], 0.0, np.radians(3.0), np.radians(2.0)))
ROOM_X_M, ROOM_Y_M, ROOM_H_M = (-1.0, 6.0), (-2.5, 2.5), 2.7


def project(points_m: np.ndarray) -> np.ndarray:
    cam = np.asarray(points_m, dtype=float) @ CAMERA_FROM_FLOOR[:3, :3].T + CAMERA_FROM_FLOOR[:3, 3]
    px = cam @ K.T
    return px[:, :2] / px[:, 2:3]


def verticals(feet_m, bottom_m, top_m) -> np.ndarray:
    """Segments (n, 4) of vertical 3D edges at floor points ``feet_m`` from ``bottom_m`` to ``top_m`` up."""
    feet = np.asarray(feet_m, dtype=float)
    lo = project(np.column_stack([feet, np.full(len(feet), bottom_m)]))
    hi = project(np.column_stack([feet, np.full(len(feet), top_m)]))
    return np.hstack([lo, hi])


def horizontal(a_m, b_m) -> np.ndarray:
    return np.hstack([project([a_m]), project([b_m])])


def room_floor_mask() -> np.ndarray:
    """Exact floor pixels of the box room: rays that meet the floor inside it."""
    w, h = SIZE
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    rays = np.stack([u, v, np.ones_like(u)], -1).reshape(-1, 3) @ np.linalg.inv(K).T
    world_from_camera = np.linalg.inv(CAMERA_FROM_FLOOR)
    d = rays @ world_from_camera[:3, :3].T
    origin = world_from_camera[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -origin[2] / d[:, 2]
    p = origin[:2] + s[:, None] * d[:, :2]
    inside = (s > 0) & (p[:, 0] > ROOM_X_M[0]) & (p[:, 0] < ROOM_X_M[1]) & (p[:, 1] > ROOM_Y_M[0]) & \
        (p[:, 1] < ROOM_Y_M[1])
    return inside.reshape(h, w)


def hand_built_room() -> dict[str, np.ndarray]:
    back = ROOM_X_M[1]
    return {
        "corners": verticals([[back, -2.5], [back, 2.5]], 0.0, ROOM_H_M),
        "door": verticals([[back, 0.6], [back, 1.5]], 0.0, 2.05),
        # A window from a 0.9 m sill to 2.3 m: its frame does not reach the floor.
        "window": verticals([[back, -1.9], [back, -0.8]], 0.9, 2.3),
        "lines": np.vstack([horizontal([back, -2.5, 0.0], [back, 2.5, 0.0]),
                            horizontal([back, -2.5, ROOM_H_M], [back, 2.5, ROOM_H_M]),
                            horizontal([back, 0.6, 2.05], [back, 1.5, 2.05]),
                            horizontal([back, -1.9, 2.3], [back, -0.8, 2.3]),
                            horizontal([back, -1.9, 0.9], [back, -0.8, 0.9])]),
    }


def test_hand_built_room_is_in_view():
    for seg in hand_built_room().values():
        pts = seg.reshape(-1, 2)
        assert np.all((pts >= 10) & (pts <= np.array(SIZE) - 11)), "the test's room must be in the frame"


def test_segment_heights_are_exact_on_projected_verticals():
    rng = np.random.default_rng(0)
    feet = rng.uniform([1.5, -2.0], [6.0, 2.0], size=(50, 2))
    tops_m = rng.uniform(0.3, 3.5, size=50)
    bases_px = project(np.column_stack([feet, np.zeros(50)]))
    tops_px = project(np.column_stack([feet, tops_m]))
    heights, feet_m = H.segment_heights(bases_px, tops_px, K, CAMERA_FROM_FLOOR)
    np.testing.assert_allclose(heights, tops_m, rtol=1e-6)
    np.testing.assert_allclose(feet_m, feet, atol=1e-9)


def test_top_off_the_vertical_is_measured_along_it():
    """A top displaced across the vertical's image line projects onto it (least squares along the line)."""
    feet = np.array([[3.0, 0.5]])
    base = project(np.column_stack([feet, [0.0]]))
    top = project(np.column_stack([feet, [2.5]]))
    vp = L.vertical_vanishing_point(K, CAMERA_FROM_FLOOR)
    along = vp[:2] - top[0] * vp[2]
    across = np.array([-along[1], along[0]]) / np.linalg.norm(along)
    heights, _ = H.segment_heights(base, top + 3.0 * across, K, CAMERA_FROM_FLOOR)
    np.testing.assert_allclose(heights, [2.5], rtol=1e-6)


def test_vertical_vanishing_point_is_where_verticals_meet():
    seg = verticals([[2.0, -1.0], [4.0, 1.5], [3.0, 0.2]], 0.0, 2.0)
    vp = L.vertical_vanishing_point(K, CAMERA_FROM_FLOOR)
    for s in seg:
        line = np.cross([*s[:2], 1.0], [*s[2:], 1.0])
        assert abs(line @ vp) / np.linalg.norm(line[:2]) < 1e-6


def test_room_height_from_hand_built_segments_is_exact():
    """Corners, door frames and the floor and ceiling lines, no mask: the corners' height
    exactly (door frames, 2.05 m, are too low to be a room)."""
    room = hand_built_room()
    seg = np.vstack([room["corners"], room["door"], room["lines"][:3]])
    result = H.height_from_segments(seg, K, CAMERA_FROM_FLOOR, SIZE)
    assert not result.fallback
    assert abs(result.height_m - ROOM_H_M) / ROOM_H_M < 1e-6
    assert result.inliers.sum() == 2 and 0 < result.confidence <= 1


def test_floor_mask_rejects_window_frames():
    """A window frame's lower end is its sill, not the floor. Taken for a foot, it makes a
    taller wall than the room's (farther away); the floor mask shows the sill is not where
    the floor ends, and the estimate is the corners' height."""
    room = hand_built_room()
    window_only = np.vstack([room["window"], room["lines"][3:]])
    fooled = H.height_from_segments(window_only, K, CAMERA_FROM_FLOOR, SIZE)
    assert not fooled.fallback and fooled.height_m > ROOM_H_M + 0.3, "without a mask a window passes for a wall"

    mask = room_floor_mask()
    seg = np.vstack([room["corners"], room["door"], room["window"], room["lines"]])
    result = H.height_from_segments(seg, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask)
    assert not result.fallback
    assert abs(result.height_m - ROOM_H_M) / ROOM_H_M < 0.01    # feet moved to the mask's pixel boundary
    assert set(result.kinds[result.inliers]) <= {"edge", "ceiling"}
    window_tops = room["window"][:, 2:]
    used_tops = result.tops_px[result.inliers]
    assert np.min(np.linalg.norm(used_tops[:, None] - window_tops[None], axis=2)) > 5
    assert H.height_from_segments(window_only, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask).fallback


def test_a_door_in_view_bounds_the_height_from_below_and_a_given_height_is_used():
    """The ceiling out of view, a door's frame (2.05 m) standing on the floor: not a
    measurement, but the walls are at least 2.05 m; the fallback is 2.5 m, or the
    user's height when given, and a door taller than the fallback raises it. A height
    the photo shows is measured whatever the user gives."""
    room, mask = hand_built_room(), room_floor_mask()
    door = np.vstack([room["door"], room["lines"][2]])
    result = H.height_from_segments(door, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask)
    assert result.fallback and result.height_m == ROOM.height.fallback_m
    assert "reaches 2.05 m, so the walls are at least that high: assuming 2.5 m" in result.reason
    assert result.at_least_m == pytest.approx(2.05, rel=0.01) and result.to_json()["at_least_m"] == result.at_least_m
    given = H.height_from_segments(door, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask, given_m=2.8)
    assert given.fallback and given.height_m == 2.8 and given.reason.endswith("using the given 2.8 m")
    tall = np.vstack([verticals([[ROOM_X_M[1], 0.6], [ROOM_X_M[1], 1.5]], 0.0, 2.6),
                      horizontal([ROOM_X_M[1], 0.6, 2.6], [ROOM_X_M[1], 1.5, 2.6])])
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(ROOM.height, "min_m", 2.7)  # 2.6 m is then a door, not a wall
        raised = H.height_from_segments(tall, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask)
    assert raised.fallback and raised.height_m == pytest.approx(2.6, rel=1e-6)
    seen = np.vstack([room["corners"], room["door"], room["lines"][:3]])
    measured = H.height_from_segments(seen, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask, given_m=3.1)
    assert not measured.fallback and abs(measured.height_m / ROOM_H_M - 1) < 0.01


def test_tilted_segments_are_not_vertical():
    """Edges leaning 5 degrees in 3D fail the 3D test (yet pass the paper's cos > 0.9), and
    alone they give no height."""
    feet = np.array([[3.0, -1.0], [4.0, 0.5], [2.5, 1.2]])
    lean = np.tan(np.radians(5.0)) * 2.5
    lo = project(np.column_stack([feet, np.zeros(3)]))
    hi = project(np.column_stack([feet + [0.0, lean], np.full(3, 2.5)]))
    tilted = np.hstack([lo, hi])
    cos_3d, angle_deg, _ = L.vertical_alignment(tilted, K, CAMERA_FROM_FLOOR)
    assert np.all(cos_3d < CAMERA.lines.min_vertical_cos) and np.all(cos_3d > 0.9)
    assert np.all(angle_deg > 0.5)
    upright, _, dist = L.vertical_alignment(verticals(feet, 0.0, 2.5), K, CAMERA_FROM_FLOOR)
    np.testing.assert_allclose(upright, 1.0, atol=1e-9)
    assert np.all(dist < 1e-6)
    result = H.height_from_segments(tilted, K, CAMERA_FROM_FLOOR, SIZE)
    assert result.fallback and result.height_m == ROOM.height.fallback_m


def test_inputs_are_not_modified_and_results_are_read_only():
    room = hand_built_room()
    seg = np.vstack([room["corners"], room["lines"]])
    mask = room_floor_mask()
    copies = [a.copy() for a in (seg, K, CAMERA_FROM_FLOOR, mask)]
    result = H.height_from_segments(seg, K, CAMERA_FROM_FLOOR, SIZE, floor_mask=mask)
    H.segment_heights(seg[:, :2], seg[:, 2:], K, CAMERA_FROM_FLOOR)
    for before, after in zip(copies, (seg, K, CAMERA_FROM_FLOOR, mask)):
        np.testing.assert_array_equal(before, after)
    with pytest.raises(ValueError):
        result.heights_m[0] = 1.0


def test_bad_inputs_name_the_value():
    with pytest.raises(ValueError, match="segments_px"):
        H.height_from_segments(np.zeros((3, 3)), K, CAMERA_FROM_FLOOR, SIZE)
    with pytest.raises(ValueError, match="floor_mask"):
        H.height_from_segments(np.zeros((0, 4)), K, CAMERA_FROM_FLOOR, SIZE, floor_mask=np.zeros((10, 10), bool))
    with pytest.raises(ValueError, match="camera_from_floor"):
        H.segment_heights(np.zeros((1, 2)), np.zeros((1, 2)), K, np.eye(3))
    with pytest.raises(ValueError, match="bases_px"):
        H.segment_heights(np.zeros((2, 2)), np.zeros((1, 2)), K, CAMERA_FROM_FLOOR)


@pytest.fixture(scope="module")
def sample_calibration():
    return calibrate_file(SAMPLES / "room_1.jpg", Board())


def test_blank_photo_falls_back(sample_calibration):
    w, h = sample_calibration.size_px
    blank = np.full((h, w, 3), 128, np.uint8)
    result = H.measure_height(blank, sample_calibration)
    assert result.fallback and result.height_m == ROOM.height.fallback_m and result.confidence == 0.0
    assert "assuming 2.5 m" in result.reason
    with pytest.raises(ValueError, match="calibration is for"):
        H.measure_height(blank[:100], sample_calibration)


def test_overlay_draws_on_a_copy(sample_calibration):
    w, h = sample_calibration.size_px
    photo = np.full((h, w, 3), 90, np.uint8)
    room = hand_built_room()
    seg = np.vstack([room["corners"], room["lines"][:2]]) * (w / SIZE[0])
    result = H.height_from_segments(seg, sample_calibration.intrinsics.K, sample_calibration.camera_from_floor,
                                    (w, h))
    before = photo.copy()
    out = height_overlay(photo, sample_calibration, result)
    np.testing.assert_array_equal(photo, before)
    assert out.shape == (h, w, 3) and out.dtype == np.uint8 and np.any(out != photo)


def test_overlay_marks_the_edge_that_bounds_the_height_from_below(sample_calibration):
    """Not measured, bounded by a door's casing 2.05 m tall: that edge is drawn thick in
    amber and labeled "at least"; a shorter edge stays thin and grey. Without the bound
    both are grey."""
    w, h = sample_calibration.size_px
    photo = np.full((h, w, 3), 90, np.uint8)
    fallback = H.HeightResult(2.5, 0.0, True, "not measured", bases_px=np.array([[300.0, 700], [900, 700]]),
                              tops_px=np.array([[300.0, 400], [900, 200]]), heights_m=np.array([1.2, 2.05]),
                              feet_m=np.zeros((2, 2)), kinds=np.array(["edge", "edge"]), weights=np.zeros(2),
                              inliers=np.zeros(2, bool), at_least_m=2.05)
    settings = DRAW.height
    out = height_overlay(photo, sample_calibration, fallback)
    assert tuple(out[450, 900]) == settings.bound_rgb and tuple(out[550, 300]) == settings.other_rgb
    assert (np.abs(out[450, 890:911].astype(int) - settings.bound_rgb).sum(axis=1) == 0).sum() >= 3  # thick
    plain = height_overlay(photo, sample_calibration, dataclasses.replace(fallback, at_least_m=None))
    assert tuple(plain[450, 900]) == settings.other_rgb


# Synthetic renders: seeds [1002, i] at 640 x 480 with the phone held nearly level (pitch
# -3 to 8 degrees down), so the ceiling is in view; measured with the true pose and floor
# mask (the segmentation's stand-in). Errors seen: 0.04-0.66 % on five such renders
# with the room bright, 2.9 % on render 16 whose only ceiling line is dim (the sun
# lights a small patch of floor, not the walls): the product's target, 3 %.
RENDER_TOLERANCE = 0.03


@pytest.fixture(scope="module")
def level_renders():
    saved = synth_camera.PITCH_DOWN_DEG
    synth_camera.PITCH_DOWN_DEG = (-3.0, 8.0)
    try:
        with Renderer() as renderer:
            return {i: render_sample([1002, i], renderer, size_px=SIZE) for i in (0, 16, 22)}
    finally:
        synth_camera.PITCH_DOWN_DEG = saved


def _truth_pose(truth: dict) -> np.ndarray:
    """camera_from_floor in the board's frame (as a calibration gives it), on the floor 1 mm below."""
    pose = np.array(truth["camera_from_world"]) @ np.array(truth["board"]["world_from_board"])
    pose[:3, 3] -= 0.001 * pose[:3, 2]
    return pose


@pytest.mark.parametrize("index", [16, 22])
def test_synthetic_render_height(level_renders, index):
    sample = level_renders[index]
    truth = sample.truth
    seg = L.detect_segments(sample.image)
    result = H.height_from_segments(seg, np.array(truth["K"]), _truth_pose(truth), SIZE, sample.floor_mask,
                                    image=sample.image)
    assert not result.fallback, result.reason
    assert abs(result.height_m / truth["room"]["height_m"] - 1) < RENDER_TOLERANCE
    assert result.confidence > 0.5


def test_synthetic_render_without_ceiling_falls_back(level_renders):
    sample = level_renders[0]
    truth = sample.truth
    seg = L.detect_segments(sample.image)
    result = H.height_from_segments(seg, np.array(truth["K"]), _truth_pose(truth), SIZE, sample.floor_mask,
                                    image=sample.image)
    assert result.fallback and "assuming" in result.reason
