"""The sun's direction from sunlit patches on the floor: drawn patches, and the synthetic
photographer's sunny rooms."""
from __future__ import annotations

import math

import numpy as np
import pytest

from augment.camera.board import Board
from augment.camera.calibrate import calibrate_photo, exif_intrinsics
from augment.render.gl import Renderer
from augment.render.staged import estimate_lighting
from augment.render.sun import find_sun, wall_angles_rad

# A camera 3 m above the floor looking straight down: 6 mm of floor a pixel, x right, y down.
W, H, MM = 640, 480, 0.006
FLOOR_FROM_IMAGE = np.array([[MM, 0, -320 * MM], [0, MM, -240 * MM], [0, 0, 1.0]])


@pytest.fixture(scope="module")
def renderer():
    with Renderer() as r:
        yield r


def _floor_points():
    v, u = np.mgrid[0:H, 0:W]
    return (u - 320) * MM, (v - 240) * MM


def _sunny_floor(rng, axis_deg=30.0, reach_wall=True):
    """A floor with a sun patch: near edge along a wall (x = -0.8 m), sides along
    ``axis_deg``, 0.8 m wide; a wall (not floor) from x = 1.5 m on. Returns image, mask."""
    x, y = _floor_points()
    a = math.radians(axis_deg)
    along = (x + 0.8) / math.cos(a)  # distance along the axis from the near edge, at this y offset
    across = y - (x + 0.8) * math.tan(a)
    end = 10.0 if reach_wall else 1.2
    lit = (x > -0.8) & (along < end) & (np.abs(across + 0.1) < 0.4)
    level = np.where(lit, 170.0, 80.0) + rng.normal(0, 2.0, x.shape)
    image = np.repeat(np.clip(level, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
    mask = x < 1.5
    image[~mask] = 200  # the wall, lit
    return image, mask


def test_the_sun_s_azimuth_from_its_patch_and_the_walls(rng):
    image, mask = _sunny_floor(rng)
    before = image.copy()
    walls = wall_angles_rad(np.array([[-2.0, -2.0], [1.5, -2.0], [1.5, 2.0], [-2.0, 2.0]]))
    np.testing.assert_allclose(np.sort(np.degrees(walls)), [0.0, 90.0], atol=0.5)
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls)
    np.testing.assert_array_equal(image, before)
    axis = math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180
    assert abs(axis - 30.0) < 2.0
    assert sun.along_wall  # the near edge runs along a wall: the sides are the sun's
    assert 2.5 < sun.contrast < 6.0  # (170 / 80) ** 2.2 = 5.3: the median over an edge's flanks reads less
    # The patch runs into the wall at x = 1.5 m: the light travels toward +x.
    assert sun.downstream * sun.axes_xy[0][0] > 0


def test_a_patch_that_ends_on_the_floor_gives_no_sign(rng):
    image, mask = _sunny_floor(rng, reach_wall=False)
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0))
    assert sun is not None and sun.downstream == 0


@pytest.mark.parametrize("kind", ["planks", "plain"])
def test_no_sun_on_planks_or_a_plain_floor(rng, kind):
    x, y = _floor_points()
    level = 80.0 + rng.normal(0, 2.0, x.shape)
    if kind == "planks":  # 15 cm planks, each 10 % lighter or darker, seams dark
        level *= np.where((np.floor(y / 0.15) % 2) == 0, 1.1, 0.9)
        level[(y % 0.15) < 0.006] = 40
    image = np.repeat(np.clip(level, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
    walls = np.radians([0.0, 90.0])  # planks are laid along a wall
    assert find_sun(image, np.ones((H, W), bool), FLOOR_FROM_IMAGE, (0.0, 0.0), walls) is None


def test_sun_direction_in_a_synthetic_room(renderer):
    """The photographer's sun through a window (truth: its direction), read from the floor
    of the photo; the room's walls from its true outline."""
    from augment.synth import render_sample

    sample = render_sample([9600, 0], renderer, size_px=(1280, 960), clutter=False)
    truth = sample.truth
    sun = next(lt for lt in truth["render"]["lights"] if lt["kind"] == "sun")
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(truth["K"][0][0], (1280, 960)))
    world_from_board = np.asarray(truth["board"]["world_from_board"])
    # The calibration's floor frame is the board's, up to its half-turn symmetry.
    M = np.linalg.inv(world_from_board) @ np.linalg.inv(np.asarray(truth["camera_from_world"])) @ cal.camera_from_floor
    turn = round(math.atan2(M[1, 0], M[0, 0]) / math.pi) * math.pi
    world_from_floor = world_from_board[:3, :3] @ np.array(
        [[math.cos(turn), -math.sin(turn), 0], [math.sin(turn), math.cos(turn), 0], [0, 0, 1]])
    room = np.asarray(truth["room"]["polygon_m"])
    outline = ((np.column_stack([room, np.zeros(len(room))]) - world_from_board[:3, 3]) @ world_from_floor)[:, :2]
    lighting = estimate_lighting(sample.image, cal, sample.floor_mask, floor_polygon=outline)
    true_xy = (world_from_floor.T @ np.asarray(sun["direction"]))[:2]
    got_xy = np.asarray(lighting.direction[:2])
    angle = math.degrees(math.acos(np.clip(true_xy @ got_xy / np.linalg.norm(true_xy) / np.linalg.norm(got_xy), -1, 1)))
    assert lighting.source == "sun" and angle < 5.0
    # Without the sun the floor shows no patches and the light is the window's or the default.
    dim = render_sample([9600, 16], renderer, size_px=(1280, 960), clutter=False)
    assert not any(lt["kind"] == "sun" for lt in dim.truth["render"]["lights"])
    cal = calibrate_photo(dim.image, Board(), intrinsics=exif_intrinsics(dim.truth["K"][0][0], (1280, 960)))
    assert estimate_lighting(dim.image, cal, dim.floor_mask).source != "sun"
