"""Far strips of floor given back up to the wall's foot, on ray-cast rooms with known answers."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from augment.floor.settings import FLOOR
from augment.floor.wall_foot import (
    _clashes,
    _one_board_two_feet,
    _Sums,
    reach_wall_foot,
)
from tests.augment.test_skirting import WALL_Y_M, _room, _second_floor_strip


def _far_strip(depth_m: float, rgb, board_m: float = 0.10, yaw_deg: float = 0.0, **room):
    """A second floor's strip before the wall (:func:`_second_floor_strip`), the mask
    stopping at the threshold, as the floor model and GrabCut leave it. Returns the photo,
    the true floor, the mask, the strip and the calibration."""
    image, truth, strip, calibration = _second_floor_strip(depth_m, rgb, board_m, yaw_deg, **room)
    return image, truth, truth & ~strip, strip, calibration


@pytest.mark.parametrize("depth_m, rgb", [(0.3, (90, 90, 95)), (0.5, (128, 120, 112)), (0.8, (60, 70, 60))])
def test_a_far_strip_past_a_threshold_is_given_back_up_to_the_board(depth_m, rgb):
    """The mask ends at the threshold, 30-80 cm before the wall; the white board standing on
    the wall says where the floor ends: every column reaches the floor line, none passes it."""
    image, truth, mask, strip, calibration = _far_strip(depth_m, rgb)
    before = image.copy(), mask.copy()
    reached = reach_wall_foot(image, mask, calibration)
    assert (strip & ~reached).sum() < 0.03 * strip.sum()
    assert (reached & ~truth).sum() < 0.01 * strip.sum()
    floor_line, top = np.argmax(truth, axis=0), np.argmax(reached, axis=0)
    assert np.percentile(np.abs(top - floor_line), 95) <= 1
    np.testing.assert_array_equal(before[0], image)  # inputs untouched
    np.testing.assert_array_equal(before[1], mask)


def test_a_strip_on_a_wall_seen_at_an_angle_is_given_back():
    """Turned 30 degrees, the strip and the board grow from one side of the photo to the other."""
    image, truth, mask, strip, calibration = _far_strip(0.4, (90, 90, 95), yaw_deg=30.0)
    reached = reach_wall_foot(image, mask, calibration)
    assert (strip & ~reached).sum() < 0.05 * strip.sum()
    assert (reached & ~truth).sum() < 0.01 * strip.sum()


def test_a_board_with_a_lit_bevel_on_its_top_marks_the_foot():
    """A board nearly the wall's colour (11 apart) with a bright bevel along its top, 2 of
    its 10 cm: the board's face below the bevel is plain, and the strip is given back up
    to it."""
    image, truth, mask, strip, calibration = _far_strip(0.3, (90, 90, 95), board_rgb=(196, 178, 168),
                                                        bevel_rgb=(245, 236, 226))
    reached = reach_wall_foot(image, mask, calibration)
    assert (strip & ~reached).sum() < 0.03 * strip.sum()
    assert (reached & ~truth).sum() < 0.01 * strip.sum()


@pytest.mark.parametrize("depth_m", [0.25, 0.3])
def test_a_strip_of_nearly_the_boards_colour_is_told_from_the_board(depth_m):
    """A dark carpet strip (70, 56, 35) under a dark board (84, 52, 37), 15 apart: the step
    from the strip to the board is under a floor line's, and the two read as one board
    standing on the mask's edge, 0.19-0.20 m tall upright. Plain both, parted by a sharp
    step, a board's height over a strip's: the floor reaches the board's foot."""
    image, truth, mask, strip, calibration = _far_strip(depth_m, (70, 56, 35), board_rgb=(84, 52, 37))
    reached = reach_wall_foot(image, mask, calibration)
    assert (strip & ~reached).sum() < 0.03 * strip.sum()
    assert (reached & ~truth).sum() < 0.01 * strip.sum()


def test_a_wall_seen_between_things_is_given_back_between_each():
    """A carton 100 px wide stands in the strip 40 px from the photo's right edge: the foot
    is found along the 820 columns left of it, and the 40 right of it (fewer than the
    96 one stretch needs on its own) reach it too; the carton's columns keep their edge
    (but for two each side, which read the board beside it through the rows' blur)."""
    image, _, mask, strip, calibration = _far_strip(0.3, (90, 90, 95))
    carton = np.zeros_like(mask)
    carton[:, 820:920] = ~mask[:, 820:920] & (np.cumsum(mask[:, 820:920], axis=0) == 0)
    image[carton] = (150, 110, 80)
    reached = reach_wall_foot(image, mask, calibration)
    right = strip.copy()
    right[:, :920] = False
    assert right.sum() > 0 and (right & ~reached).sum() < 0.05 * right.sum()
    assert (strip & ~reached)[:, :820].sum() < 0.03 * strip[:, :820].sum()
    np.testing.assert_array_equal(reached[:, 822:918], mask[:, 822:918])


def test_a_mask_at_the_floor_line_is_left_alone():
    image, truth, _, calibration = _room(0.10)
    np.testing.assert_array_equal(reach_wall_foot(image, truth, calibration), truth)


def test_a_mask_holding_the_board_does_not_climb_the_wall():
    """The board still in the mask (the trim left it): nothing above its top is floor."""
    image, _, mask, calibration = _room(0.10)
    np.testing.assert_array_equal(reach_wall_foot(image, mask, calibration), mask)


def test_without_a_board_the_strip_stays_out():
    """Nothing in the photo says where the floor ends: a wall without a board, straight
    above the strip, looks like the strip's own far edge. Known limit."""
    image, _, mask, _, calibration = _far_strip(0.3, (90, 90, 95), board_m=0.0)
    np.testing.assert_array_equal(reach_wall_foot(image, mask, calibration), mask)


def test_a_strip_taller_than_a_third_of_a_meter_upright_stays_out(monkeypatch):
    """The last meter before the wall, from a camera 1.5 m up 3 m off, spans as many rows as
    0.37 m standing upright there: as tall as a carton's face before the wall, whose lid
    looks like a board. Not given back; allowed that tall, it would be."""
    image, _, mask, strip, calibration = _far_strip(1.0, (90, 90, 95))
    np.testing.assert_array_equal(reach_wall_foot(image, mask, calibration), mask)
    monkeypatch.setattr(FLOOR.wall_foot, "strip_m", (0.05, 0.5))
    assert (strip & ~reach_wall_foot(image, mask, calibration)).sum() < 0.03 * strip.sum()


def _carton_taken_for_floor(width_m: float, height_m: float = 0.35, depth_m: float = 0.4):
    """:func:`_room` (a 10 cm white board on the wall) with a carton ``width_m`` wide standing
    against the wall straight ahead, in the mask: GrabCut took it for floor. Returns the
    photo, the mask, the carton's pixels and, per column, the wall's foot (the true floor's
    top row)."""
    image, truth, _, calibration = _room(0.10)
    x, y, z = np.meshgrid([-width_m / 2, width_m / 2], [WALL_Y_M - depth_m, WALL_Y_M], [0.0, height_m])
    corners = calibration.pixels_from_floor(np.column_stack([x.ravel(), y.ravel(), z.ravel()]))
    carton = np.zeros(truth.shape, np.uint8)
    cv2.fillConvexPoly(carton, cv2.convexHull(np.round(corners).astype(np.int32)), 1)
    carton = carton > 0
    image[carton] = (185, 150, 105)
    return image, truth | carton, carton, np.argmax(truth, axis=0), calibration


def test_a_carton_against_the_wall_is_cut_at_the_walls_foot():
    """The mask runs up the carton's face and lid, past the wall's foot, between two
    stretches of the board: on the floor plane that lid lies beyond the wall. It is cut
    along the foot, which the board either side says where it runs; the rest of the mask
    (the carton's face below the foot, the floor) is kept."""
    image, mask, carton, foot_row, calibration = _carton_taken_for_floor(0.6)
    rows = np.arange(mask.shape[0])[:, None]
    past = carton & (rows < foot_row[None] - 1)
    assert past.sum() > 5000  # the carton's lid reaches 0.35 m up, 60 rows above the foot
    reached = reach_wall_foot(image, mask, calibration)
    assert (reached & past).sum() < 0.02 * past.sum()
    assert not (mask & ~reached & (rows >= foot_row[None] + 1)).any()
    np.testing.assert_array_equal(reached[:, ~carton.any(axis=0)], mask[:, ~carton.any(axis=0)])


def test_what_rises_past_the_foot_for_more_than_a_meter_is_left_alone(monkeypatch):
    """Floor past the wall's line that goes on for more than ``thing_m`` along it is the room
    going on (a recess, another wall's floor), not a thing against the wall."""
    image, mask, _, _, calibration = _carton_taken_for_floor(1.6)
    np.testing.assert_array_equal(reach_wall_foot(image, mask, calibration), mask)
    monkeypatch.setattr(FLOOR.wall_foot, "thing_m", 2.0)
    assert (reach_wall_foot(image, mask, calibration) != mask).any()


def test_a_far_strip_the_mask_reached_in_part_is_not_cut():
    """Without a board, a far strip of a second floor looks like one beside the columns
    where the mask stops at the threshold; where the mask reached the wall it rises past
    that "foot" to the "board's" top, like a carton's lid. The mask is left as it is."""
    image, truth, strip, calibration = _second_floor_strip(0.3, (170, 90, 60), board_m=0.0)
    mask = truth & ~strip
    mask[:, 400:480] = truth[:, 400:480]
    np.testing.assert_array_equal(reach_wall_foot(image, mask, calibration), mask)


def test_a_foot_seen_beside_the_strip_must_run_on_along_it():
    """Lines ``row = slope * col + intercept``. The foot and board seen at the mask's edge in
    columns 0-200 against a strip found in columns 230-500: on the same lines they agree;
    5 px off, at the columns where they meet, something stands before the wall; a foot
    seen far off (columns 700-900) is another stretch and says nothing."""
    foot, board = (0.1, 300.0), (0.1, 280.0)
    seen = [(foot, board, 0, 200)]
    assert not _clashes(foot, board, 230, 500, seen)
    assert _clashes((0.1, 305.0), board, 230, 500, seen)
    assert _clashes(foot, (0.1, 275.0), 230, 500, seen)
    # A slope off by 0.03 is 6 px where the two meet (column 200), 0 at column 0.
    assert _clashes((0.13, 300.0), board, 230, 500, seen)
    assert not _clashes((0.1, 320.0), board, 230, 500, [(foot, board, 700, 900)])


def _two_feet_under_one_board(strip_sd: float):
    """Lines ``row = 0.05 * col + c``: the wall's foot at c = 300 (its board's top at 290)
    seen in columns 0-200, and in columns 260-400 a foot 15 rows lower under the same
    board's top, the mask's edge on each and at row 308 + 0.05 col between. Between the two
    feet in columns 260-400 the band is wood-brown with ``strip_sd`` of noise per channel."""
    cols = np.arange(401)
    rows = np.round(np.select([cols <= 200, cols >= 260], [300 + 0.05 * cols, 315 + 0.05 * cols],
                              308 + 0.05 * cols)).astype(np.int64)
    band = np.full((400, 401, 3), (200.0, 190.0, 170.0), np.float32)  # wall
    band[290:] = (230.0, 228.0, 222.0)  # the board's rows, roughly
    y = np.arange(400)[:, None]
    between = (y > 300 + 0.05 * cols[None] + 1) & (y < 315 + 0.05 * cols[None] - 1) & (cols[None] >= 260)
    noise = np.random.default_rng(0).normal(0, strip_sd, (between.sum(), 3))
    band[between] = (140.0, 110.0, 80.0) + noise
    seen = [((0.05, 300.0), (0.05, 290.0), 0, 200), ((0.05, 315.0), (0.05, 290.0), 260, 400)]
    return band, cols, rows, seen


def test_a_lower_foot_under_the_same_board_is_a_far_strip():
    """Hand-computed: the floor reaches the higher foot over the lower stretch and the
    columns between (rows 310-320 there), not in the columns already on it; the lower
    stretch is no longer a wall's foot seen. A plain strip between the two feet is the
    board's foot under a moulding line, and nothing changes."""
    band, cols, rows, seen = _two_feet_under_one_board(strip_sd=12.0)
    left, top_row = _one_board_two_feet(_Sums(band, cols), 0, cols, rows, np.full(len(cols), 200.0), seen)
    assert left == seen[:1]
    assert np.isinf(top_row[:201]).all()
    np.testing.assert_allclose(top_row[201:], 300 + 0.05 * cols[201:])
    band, cols, rows, seen = _two_feet_under_one_board(strip_sd=1.0)
    left, top_row = _one_board_two_feet(_Sums(band, cols), 0, cols, rows, np.full(len(cols), 200.0), seen)
    assert left == seen and np.isinf(top_row).all()
    # A strip taller than FLOOR.wall_foot.strip_m (0.35 m) upright is not floor either.
    band, cols, rows, seen = _two_feet_under_one_board(strip_sd=12.0)
    _, top_row = _one_board_two_feet(_Sums(band, cols), 0, cols, rows, np.full(len(cols), 20.0), seen)
    assert np.isinf(top_row).all()


def _segmented_render(key, **stress):
    """A render of the synthetic photographer (``key``: seed and index, ``stress``: a stress
    set's options), calibrated through its true focal length: a function that segments its
    floor with the shipped model as the settings stand when called, and the true floor."""
    from augment.camera.board import Board
    from augment.camera.calibrate import calibrate_photo, exif_intrinsics
    from augment.floor.model import DEFAULT_MODEL, FloorModel
    from augment.floor.segment import segment_floor
    from augment.render.gl import Renderer
    from augment.synth import render_sample

    with Renderer() as renderer:
        sample = render_sample(key, renderer, **stress)
    w, h = sample.truth["size_px"]
    calibration = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
    model = FloorModel(DEFAULT_MODEL)
    return (lambda: segment_floor(sample.image, model, calibration).mask), sample.floor_mask


def test_a_render_whose_far_strip_the_model_drops(monkeypatch):
    """A render of the synthetic photographer (seed 991, render 24: concrete past a stepped
    threshold along the far wall, under a board): the floor model and GrabCut leave out
    7 % of the floor, all of it that strip; reaching the wall's foot gives it back."""
    segment, truth = _segmented_render([991, 24], two_floors=1.0, far_floor=1.0)
    mask = segment()
    assert (truth & ~mask).sum() < 0.01 * truth.sum()
    assert (mask & ~truth).sum() < 0.01 * truth.sum()
    monkeypatch.setattr(FLOOR.wall_foot, "strip_m", (1.0, 1.0))  # no strip given back
    assert (truth & ~segment()).sum() > 0.05 * truth.sum()


def test_a_render_whose_sun_patch_ends_before_the_wall(monkeypatch):
    """A render of the synthetic photographer (seed 987, render 0, threshold set): a sun
    patch on the tiles ends a hand's width before the far wall; the mask stops at its edge,
    and the shaded strip above reads with the board as one taller board. The board's top
    seen beside it, over a foot 15 rows higher, gives the strip back (1.8 % of the floor's
    pixels missed without it)."""
    from augment.floor import wall_foot

    segment, truth = _segmented_render([987, 0], two_floors=1.0)
    mask = segment()
    assert (truth & ~mask).sum() < 0.003 * truth.sum()
    assert (mask & ~truth).sum() < 0.01 * truth.sum()
    monkeypatch.setattr(wall_foot, "_one_board_two_feet", lambda band, y0, cols, rows, px_per_m, seen:
                        (seen, np.full(len(cols), np.inf)))
    assert (truth & ~segment()).sum() > 0.01 * truth.sum()
