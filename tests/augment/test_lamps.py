"""Ceiling lamps from their pools of light on the floor: their light on surfaces, pools
painted on a sample photo's floor, and the shadows they cast."""
from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from augment.render.furniture import PlacedItem, furniture_for
from augment.render.gl import Renderer
from augment.render.lamps import Lamp, find_lamps
from augment.render.settings import RENDER
from augment.render.staged import (GAMMA, Lighting, _Caster, _floor_gain, _FloorGrid, _in_room, _lamp_view, _LightMap,
                                   estimate_lighting)
from tests.augment.test_render import PHOTOS, _truth_calibration

CEILING_M = 2.5
HEIGHT_M = CEILING_M - RENDER.lamps.below_ceiling_m


def test_a_lamps_light_on_the_floor_and_on_the_furniture():
    lamp = Lamp((0.5, -0.2, 2.4), 1.5, 0.8)
    up = np.array([[0.0, 0, 1]])
    assert lamp.on_floor([[0.5, -0.2]])[0] == pytest.approx(0.8)
    # On the floor, the same light either way; 1.2 m off, (1 + 1.44 / 2.25) ** -1.5 of the peak.
    floor = np.array([[0.5 + 1.2, -0.2, 0.0]])
    assert lamp.on(floor, up)[0] == pytest.approx(lamp.on_floor(floor)[0])
    assert lamp.on_floor(floor)[0] == pytest.approx(0.8 * (1 + 1.44 / 2.25) ** -1.5)
    # A face turned to the lamp at the same point: its cosine is 1.2 / d, the floor's 2.4 / d.
    facing = np.array([[-1.0, 0, 0]])
    assert lamp.on(floor, facing)[0] == pytest.approx(0.5 * lamp.on_floor(floor)[0])
    assert lamp.on(floor, -facing)[0] == 0.0  # turned away
    assert lamp.on(np.array([[0.5, -0.2, 2.45]]), -up)[0] == 0.0  # above the lamp: none
    # A table top 0.75 m up right under it: the inverse square of the nearer lamp.
    top = np.array([[0.5, -0.2, 0.75]])
    assert lamp.on(top, up)[0] == pytest.approx(0.8 * (2.4 / 1.65) ** 2)


def _painted_floor(calibration, mask, light, rng):
    """room_1 (half size) with its floor painted grey under ``light(xy)`` (linear, (n,) or
    (n, 3)), with a plank-like texture of +-8 %."""
    h, w = mask.shape
    rows, cols = np.nonzero(mask)
    xy = calibration.floor_from_pixels(np.column_stack([cols, rows]).astype(np.float64))
    planks = 1.0 + 0.08 * np.sin(xy[:, 0] * 2 * np.pi / 0.19) * np.sign(np.sin(xy[:, 1] * 2 * np.pi / 1.3))
    lit = np.asarray(light(xy)).reshape(len(xy), -1)
    linear = np.clip(0.18 * lit * (planks * rng.uniform(0.97, 1.03, len(xy)))[:, None], 0, 1)
    image = np.full((h, w, 3), 200, np.uint8)
    image[rows, cols] = np.round(255 * linear ** (1 / GAMMA)).astype(np.uint8)
    return image, xy


@pytest.mark.parametrize("share", [0.6, 1.0])
def test_a_pool_painted_on_the_floor_is_found_where_it_is(rng, share):
    """A pool 0.6 of the lamp's height wide is found as painted; a bare bulb's (1.0) where
    it is, but lighting as one 0.8 wide: a little less under it, less than painted 1.2 m off."""
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    rows, cols = np.nonzero(mask)
    seen = calibration.floor_from_pixels(np.column_stack([cols, rows]).astype(np.float64))
    centre = np.median(seen, axis=0)
    width = share * HEIGHT_M

    def light(xy):  # a window's gradient and a spot's pool, 1.5 times the floor's light under it
        return 1.0 + 0.15 * (xy[:, 0] - centre[0]) + 1.5 * (1 + ((xy - centre) ** 2).sum(1) / width ** 2) ** -1.5

    painted, _ = _painted_floor(calibration, mask, light, rng)
    before = painted.copy()
    lamps = find_lamps(painted, mask, calibration, CEILING_M, 0.18)
    np.testing.assert_array_equal(painted, before)
    assert len(lamps) == 1
    lamp = lamps[0]
    assert np.hypot(*(np.asarray(lamp.position_m[:2]) - centre)) < 0.1
    assert lamp.position_m[2] == pytest.approx(HEIGHT_M)
    if share <= RENDER.lamps.max_width_share:
        assert lamp.width_m == pytest.approx(width)
        assert lamp.peak == pytest.approx(1.5, rel=0.15)
        return
    assert lamp.width_m == pytest.approx(RENDER.lamps.max_width_share * HEIGHT_M)
    assert 0.8 < lamp.peak < 1.3  # the narrower pool under the painted one: about 1.0
    off = centre + [1.2, 0.0]
    assert lamp.on_floor([off])[0] < 0.8 * 1.5 * (1 + 1.44 / width ** 2) ** -1.5


def test_no_lamp_is_hung_behind_a_wall(rng):
    """The same pool, with a wall said to stand 0.3 m before its centre: the lamp above
    it would hang in the next room, so none is put there."""
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    rows, cols = np.nonzero(mask)
    centre = np.median(calibration.floor_from_pixels(np.column_stack([cols, rows]).astype(np.float64)), axis=0)
    width = 0.6 * HEIGHT_M
    painted, _ = _painted_floor(calibration, mask,
                                lambda xy: 1.0 + 1.5 * (1 + ((xy - centre) ** 2).sum(1) / width ** 2) ** -1.5, rng)
    assert len(find_lamps(painted, mask, calibration, CEILING_M, 0.18)) == 1

    def inside(xy):
        return np.asarray(xy)[:, 0] < centre[0] - 0.3

    lamps = find_lamps(painted, mask, calibration, CEILING_M, 0.18, inside=inside)
    assert all(inside(np.array([lamp.position_m[:2]]))[0] for lamp in lamps)


@pytest.mark.parametrize("beyond_m, pool_rgb, lamp", [(-0.6, (0.85, 1.0, 1.2), True), (0.3, (0.85, 1.0, 1.2), False),
                                                     (0.3, (1.2, 1.0, 0.7), True)])
def test_a_pool_whose_peak_is_out_of_view_is_a_lamp_by_its_warm_light(rng, beyond_m, pool_rgb, lamp):
    """A pool whose centre lies 0.3 m short of the floor in view (toward the camera: the
    photo shows its flank only, falling off one way as a window's light does) hangs a lamp
    only in light warmer than the floor's at large (grey here); 0.6 m inside the view,
    whatever its colour."""
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    rows, cols = np.nonzero(mask)
    seen = calibration.floor_from_pixels(np.column_stack([cols, rows]).astype(np.float64))
    pose = calibration.camera_from_floor
    foot = (-pose[:3, :3].T @ pose[:3, 3])[:2]
    toward = np.median(seen, axis=0) - foot
    toward /= np.linalg.norm(toward)
    nearest = float(np.min((seen - foot) @ toward))  # the floor in view starts this far ahead
    centre = foot + (nearest - beyond_m) * toward
    width = 0.8 * HEIGHT_M

    def light(xy):
        pool = 1.5 * (1 + ((xy - centre) ** 2).sum(1) / width ** 2) ** -1.5
        return 1.0 + pool[:, None] * np.asarray(pool_rgb)

    painted, _ = _painted_floor(calibration, mask, light, rng)
    lamps = find_lamps(painted, mask, calibration, CEILING_M, 0.18)
    assert len(lamps) == int(lamp)
    if lamp:
        assert np.hypot(*(np.asarray(lamps[0].position_m[:2]) - centre)) < 0.3


def test_the_room_ends_at_the_walls_in_view():
    """A far wall along y = 3 m and a left one along x = -2 m, seen from (0, -1): points
    past either (by more than 0.1 m) are out of the room; where no wall is seen, in."""
    walls = np.array([[[-2.0, 3.0], [2.0, 3.0]], [[-2.0, -2.0], [-2.0, 3.0]]])
    inside = _in_room(walls, (0.0, -1.0))
    points = np.array([[0.0, 2.95], [0.0, 3.05], [0.0, 3.5], [1.0, 3.2], [3.0, 0.0], [-2.5, 0.0], [2.5, 3.5]])
    assert inside(points).tolist() == [True, True, False, False, True, False, True]


@pytest.mark.parametrize("slope", [0.0, 0.3])
def test_no_lamp_on_an_even_floor_or_a_windows_gradient(rng, slope):
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    painted, _ = _painted_floor(calibration, mask, lambda xy: 1.0 + slope * xy[:, 0], rng)
    assert find_lamps(painted, mask, calibration, CEILING_M, 0.18) == ()


def test_a_lamp_casts_its_shadow_away_from_it():
    """A box 0.4 m tall between x = 0.85 and 1.15 m, a lamp 2.4 m above the origin: its
    top edge's shadow reaches 1.15 x 2.4 / 2.0 = 1.38 m. Without ambient occlusion or a
    key light, the floor there keeps the rest of the light and the lamp's diffuse share
    (off its shade, the ceiling, the walls): (1 + share x the lamp's) / (1 + the lamp's)."""
    x, y = np.meshgrid([0.85, 1.15], [-0.15, 0.15])
    box = np.column_stack([np.repeat(np.column_stack([x.ravel(), y.ravel()]), 2, axis=0), np.tile([0.0, 0.4], 4)])
    lamp = Lamp((0.0, 0.0, 2.4), 1.5, 1.0)
    light = Lighting((0.8, 0.8, 0.8), (0.0, 0.0, -1.0), 0.0, 0.05, (0.4, 0.4, 0.4), "test", lamps=(lamp,))
    plain = replace(RENDER.staged, ao_strength=0.0, contact_strength=0.0)
    shading = _floor_gain([_Caster(box, None, 0.0, 0.4)], light, ((-0.5, -0.5), (2.0, 0.5)), plain)
    gain, grid = shading.gain, shading.grid

    def at(px, py):
        col, row = np.floor(grid.to_px([px, py])).astype(int)
        return float(gain[row, col])

    share = RENDER.staged.lamp_diffuse_share
    assert 0.0 < share < 1.0
    lamp_light = lamp.on_floor([[1.25, 0.0]])[0]
    behind = (1.0 + share * lamp_light) / (1.0 + lamp_light)
    assert at(1.25, 0.0) == pytest.approx(behind ** (1 / GAMMA), abs=0.02)
    assert at(0.6, 0.0) == pytest.approx(1.0, abs=1e-3)  # between the lamp and the box
    assert at(1.6, 0.0) == pytest.approx(1.0, abs=1e-3)  # past the shadow's end
    assert at(1.25, 0.4) == pytest.approx(1.0, abs=1e-3)  # beside it


def test_the_floors_light_map_reads_any_number_of_points():
    """The lamps' shares read the light map at every cell of a fine floor raster: far more
    points than one OpenCV map may hold (32767); a ramp reads back exactly."""
    grid = _FloorGrid(np.array([0.0, 0.0]), 0.04, (50, 100))
    cols = np.arange(100, dtype=np.float32)
    light = _LightMap(grid, np.tile(1.0 + 0.01 * cols, (50, 1)).astype(np.float32))
    xy = np.column_stack([np.linspace(0.5, 3.5, 70001), np.full(70001, 1.0)])
    expected = 1.0 + 0.01 * (xy[:, 0] / 0.04 - 0.5)
    np.testing.assert_allclose(light.at(xy), expected, atol=1e-4)


def test_what_stands_under_a_table_top_gets_none_of_the_lamps_light():
    """A lamp 2.4 m above a table 0.75 m high: the top's upper face sees it, a point under
    the top (on a leg's height, facing up) does not, nor does the floor there; a point
    beside the table does."""
    item = PlacedItem("dining_table", (0.0, 0.0, 0.375), 0.0, (1.6, 0.9, 0.75), "table")
    placed = [(item, furniture_for(item, 0))]
    lamp = Lamp((0.3, 0.2, 2.4), 1.5, 1.0)
    with Renderer() as renderer:
        view = _lamp_view(renderer, placed, lamp)
    points = np.array([[0.0, 0.0, 0.752], [0.1, 0.0, 0.35], [0.1, 0.0, 0.0], [1.5, 0.0, 0.0]])
    up = np.tile([0.0, 0.0, 1.0], (4, 1))
    np.testing.assert_allclose(view.visible(points, up), [1.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize("name", ["room_1", "room_2", "room_4"])
def test_the_sample_photos_lamps_hang_near_their_true_ceiling_lights(name):
    """The sample photos are the synthetic photographer's, with their lights in the truth:
    every lamp found is within 0.95 m of a true ceiling light (a pool's centre out of view
    is guessed short), at the given ceiling; room_2 is lit by the sun alone."""
    image, mask, calibration = _truth_calibration(name)
    truth = json.loads((PHOTOS / f"{name}.json").read_text())
    board_from_world = np.linalg.inv(np.asarray(truth["board"]["world_from_board"]))
    spots = [(board_from_world @ np.append(light["position_m"], 1.0))[:2]
             for light in truth["render"]["lights"] if light["kind"] == "ceiling"]
    lamps = estimate_lighting(image, calibration, mask, ceiling_m=2.6).lamps
    assert (len(lamps) > 0) == (len(spots) > 0)
    for lamp in lamps:
        assert min(np.hypot(*(np.asarray(lamp.position_m[:2]) - s)) for s in spots) < 0.95
        assert lamp.position_m[2] == pytest.approx(2.6 - RENDER.lamps.below_ceiling_m)
