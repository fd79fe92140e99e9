"""The sun's direction from sunlit patches on the floor: drawn patches, and the synthetic
photographer's sunny rooms."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from augment.camera.board import Board
from augment.camera.calibration import Calibration, Intrinsics
from augment.camera.calibrate import calibrate_photo, exif_intrinsics
from augment.render.gl import Renderer
from augment.render.settings import RENDER
from augment.render.staged import Lighting, _Caster, _floor_gain, _in_beam, _vertex_light, estimate_lighting
from augment.render.sun import SunOnFloor, find_sun, sun_elevation_rad, unit_colour, wall_angles_rad

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


def test_the_suns_colour_against_the_shade_is_read_off_its_patch(rng):
    """A brown floor (albedo 0.6, 0.45, 0.3) under bluish shade light 0.25 x (0.9, 1, 1.15)
    and a warm sun adding 0.5 x (1.25, 1, 0.7): the sunlit floor over the shade is
    1 + sun / shade per channel, (3.78, 3.0, 2.22), whatever the floor's colour. The
    key light then shines in the sun's own colour, (2.78, 2.0, 1.22) at luminance 1."""
    x, y = _floor_points()
    a = math.radians(30.0)
    lit = (x > -0.8) & (np.abs(y - (x + 0.8) * math.tan(a) + 0.1) < 0.4)
    shade, sun_light = 0.25 * np.array([0.9, 1.0, 1.15]), 0.5 * np.array([1.25, 1.0, 0.7])
    light = np.where(lit[..., None], shade + sun_light, shade)
    linear = np.array([0.6, 0.45, 0.3]) * light * rng.normal(1.0, 0.01, x.shape)[..., None]
    image = np.round(255 * np.clip(linear, 0, 1) ** (1 / 2.2)).astype(np.uint8)
    mask = x < 1.5
    image[~mask] = 200
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0))
    expected = 1 + sun_light / shade
    np.testing.assert_allclose(sun.ratio_rgb, expected, rtol=0.05)
    colour = np.array(unit_colour(np.asarray(sun.ratio_rgb) - 1.0))
    np.testing.assert_allclose(colour / colour[1], (expected - 1) / (expected[1] - 1), rtol=0.06)
    assert colour @ [0.2126, 0.7152, 0.0722] == pytest.approx(1.0)
    # A grey sun over grey shade: white, and a ratio below 1 in a channel says nothing.
    assert unit_colour([2.0, 2.0, 2.0]) == pytest.approx((1.0, 1.0, 1.0))
    assert unit_colour([1.0, -0.5, 1.0]) == (1.0, 1.0, 1.0)


@pytest.mark.parametrize("tinted", [True, False])
def test_a_sun_faint_in_light_is_read_off_its_colour(rng, tinted):
    """A brown floor (albedo 0.6, 0.45, 0.3) lit warm by lamps, 0.3 x (1, 0.7, 0.35), and a
    white sun adding 0.1: its patch is 1.44 times the shade in luminance (0.155 / 0.108),
    too faint for the sun's edges (1.5), but 1 + 0.1 / shade = (1.33, 1.48, 1.95) per
    channel: read in the blue, its contrast the luminance's. The same step in luminance
    with the lamps' colour (tinted False) stays unread: colour reads no fainter light."""
    x, y = _floor_points()
    a = math.radians(30.0)
    lit = (x > -0.8) & (np.abs(y - (x + 0.8) * math.tan(a) + 0.1) < 0.4)
    albedo, shade = np.array([0.6, 0.45, 0.3]), 0.3 * np.array([1.0, 0.7, 0.35])
    lum = np.array([0.2126, 0.7152, 0.0722])
    contrast = 1 + 0.1 * (albedo @ lum) / ((albedo * shade) @ lum)
    assert contrast == pytest.approx(1.436, abs=0.001)
    sun_light = 0.1 * np.ones(3) if tinted else (contrast - 1) * shade
    light = np.where(lit[..., None], shade + sun_light, shade)
    linear = albedo * light * rng.normal(1.0, 0.01, x.shape)[..., None]
    image = np.round(255 * np.clip(linear, 0, 1) ** (1 / 2.2)).astype(np.uint8)
    mask = x < 1.5
    image[~mask] = 200
    walls = np.radians([0.0, 90.0])
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls)
    if not tinted:
        assert sun is None
        return
    axis = math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180
    assert abs(axis - 30.0) < 2.0
    assert sun.contrast == pytest.approx(contrast, rel=0.05)
    np.testing.assert_allclose(sun.ratio_rgb, 1 + sun_light / shade, rtol=0.05)
    assert sun.downstream * sun.axes_xy[0][0] > 0  # it runs into the wall at x = 1.5 m


def test_the_key_light_shines_in_its_own_colour():
    """A white face turned up to a key light straight overhead, all of the light: what
    it sends back is the irradiance times the key's colour, highlight included."""
    lighting = Lighting((0.5, 0.5, 0.5), (0.0, 0.0, -1.0), 1.0, 0.01, (0.3, 0.3, 0.3), "sun",
                        key_rgb=(1.2, 1.0, 0.7))
    plain = replace(RENDER.staged, front_fill=0.0, bounce=0.0)
    one = np.ones(1)
    fill, key = _vertex_light(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), np.ones((1, 3)), one, 0 * one,
                              np.zeros((1, 3)), one, lighting, np.array([0.5, 0.0, 3.0]), np.array([0.0, 1.0]), plain)
    np.testing.assert_allclose(fill, 0.0, atol=1e-12)
    np.testing.assert_allclose(key[0] / key[0, 1], [1.2, 1.0, 0.7], rtol=1e-9)


def test_in_a_sunny_room_only_the_sky_and_ambient_of_the_fill_rise_with_the_sun():
    """With the sun in the room the furniture's light map is the shade's, so the sky and
    the ambient of the fill rise by the sun's contrast c = 1 / (1 - f): a face turned up in the
    shade is lit as the shade's floor. The light from behind the camera and off the floor
    is the shade's own, not c times it (it was: on the tuning renders with sun, shaded
    fronts came out up to twice the truth's, 9601/1's sofa among them)."""
    f, sky = 0.6, RENDER.staged.sky_share
    c = 1.0 / (1.0 - f)
    shade = Lighting((0.5, 0.4, 0.3), (0.0, 0.8, -0.6), f, 0.01, (0.2, 0.15, 0.1), "sun")
    sunny = replace(shade, sun=_sun_over(lambda x, y: x > 1.0))
    normals = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    k = len(normals)
    args = (np.zeros((k, 3)), normals, np.full((k, 3), 0.6), np.ones(k), np.zeros(k), np.zeros((k, 3)), np.ones(k))
    view = (np.array([0.0, -3.0, 1.5]), np.array([0.0, 1.0]), RENDER.staged)
    fill_shade, key_shade = _vertex_light(*args, shade, *view)
    fill_sunny, key_sunny = _vertex_light(*args, sunny, *view)
    sky_part = (1.0 - f) * (sky * (0.5 + 0.5 * normals[:, 2]) + 1.0 - sky)
    expected = (c - 1.0) * sky_part[:, None] * np.array([0.5, 0.4, 0.3]) * 0.6
    np.testing.assert_allclose(fill_sunny - fill_shade, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(key_sunny, key_shade, rtol=1e-12)
    # Turned up: the shade's floor (albedo x irradiance) and the front fill's share of it.
    front = np.array([0.0, -1.0, 0.35]) / np.linalg.norm([0.0, -1.0, 0.35])
    np.testing.assert_allclose(fill_sunny[0], (1.0 + RENDER.staged.front_fill * front[2]) * 0.6
                               * np.array([0.5, 0.4, 0.3]), rtol=1e-9)
    # Toward the camera: less than c times the sunless fill (what the old code gave).
    assert np.all(fill_sunny[1] < c * fill_shade[1] * 0.9)


def _photo_of_a_sunny_floor(rng, band_centre_m, shade, sun):
    """A brown floor (albedo 0.55, 0.45, 0.35) with the board's sheet (paper, 0.85) at the
    origin, under ``shade`` (3,) light and ``sun`` (3,) more in a band 1.6 m wide along
    30 degrees, ``band_centre_m`` across from the origin; seen 2.5 m up, 65 degrees down.
    Returns the photo, its floor mask and its exact calibration."""
    w, h, f = 640, 480, 500.0
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])
    down = math.radians(65.0)
    z = np.array([0.0, math.cos(down), -math.sin(down)])
    world_from_camera = np.eye(4)
    world_from_camera[:3, :3] = np.column_stack([[1.0, 0.0, 0.0], np.cross(z, [1.0, 0.0, 0.0]), z])
    world_from_camera[:3, 3] = [0.0, -1.2, 2.5]
    camera_from_floor = np.linalg.inv(world_from_camera)
    R, t = camera_from_floor[:3, :3], camera_from_floor[:3, 3]
    image_from_floor = K @ np.column_stack([R[:, 0], R[:, 1], t])
    v, u = np.mgrid[0:h, 0:w]
    p = np.stack([u, v, np.ones_like(u)], -1).astype(float) @ np.linalg.inv(image_from_floor).T
    x, y = p[..., 0] / p[..., 2], p[..., 1] / p[..., 2]
    a = math.radians(30.0)
    lit = (np.abs(-math.sin(a) * x + math.cos(a) * y - band_centre_m) < 0.8) & (x > -1.5)
    paper = (np.abs(x) < 0.21) & (np.abs(y) < 0.1485)
    albedo = np.where(paper[..., None], 0.85, np.array([0.55, 0.45, 0.35]))
    light = np.where(lit[..., None], shade + sun, shade)
    linear = albedo * light * rng.normal(1.0, 0.01, x.shape)[..., None]
    image = np.round(255 * np.clip(linear, 0, 1) ** (1 / 2.2)).astype(np.uint8)
    mask = y < 3.0
    image[~mask] = 190  # a wall
    horizon = np.linalg.inv(K).T @ R[:, 2]
    horizon *= np.sign(horizon @ [w / 2, h - 1, 1])
    calibration = Calibration(
        size_px=(w, h), intrinsics=Intrinsics(K, np.zeros(5), "truth", 0.0), camera_from_floor=camera_from_floor,
        camera_height_m=2.5, floor_plane_camera=np.append(R[:, 2], -R[:, 2] @ t),
        image_from_floor=image_from_floor / image_from_floor[2, 2], horizon=horizon / np.hypot(*horizon[:2]),
        rms_px=0.0, corners_px=np.zeros((0, 2)), corner_ids=np.zeros(0, np.int64), detector="truth", board=Board())
    return image, mask, calibration


@pytest.mark.parametrize("band_centre_m", [0.0, 1.3])  # the board in the sun, and beside it in the shade
def test_the_rest_of_the_light_takes_the_shades_colour_where_the_board_lies_in_the_sun(rng, band_centre_m):
    """Bluish shade 0.2 x (0.85, 1, 1.2) and a warm sun adding 0.45 x (1.25, 1, 0.7). The
    paper shows the shade's light plus the sun's where it lies in the sun, (1.13, 1, 0.85)
    of green: the light but the key's is then the paper's over the sun's contrast per
    channel, the shade's (0.85, 1, 1.2), as where the paper lies in the shade. The key is
    the sun's own colour, sun / shade at luminance 1: (1.375, 0.934, 0.545)."""
    shade, sun = 0.2 * np.array([0.85, 1.0, 1.2]), 0.45 * np.array([1.25, 1.0, 0.7])
    image, mask, calibration = _photo_of_a_sunny_floor(rng, band_centre_m, shade, sun)
    lighting = estimate_lighting(image, calibration, mask)
    assert lighting.source == "sun"
    irradiance = np.asarray(lighting.irradiance_rgb)
    np.testing.assert_allclose(irradiance / irradiance[1], shade / shade[1], rtol=0.04)
    np.testing.assert_allclose(lighting.key_rgb, unit_colour(sun / shade), rtol=0.05)


def test_a_patch_that_ends_on_the_floor_gives_no_sign(rng):
    image, mask = _sunny_floor(rng, reach_wall=False)
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0))
    assert sun is not None and sun.downstream == 0


def test_light_planks_at_a_wall_are_not_the_suns_far_end(rng):
    """The patch of :func:`_sunny_floor` ending on the floor, and two light planks (level
    150 over the floor's 80, edges along the walls) running into the wall at x = 1.5 m past
    its far end: as bright as the sun's threshold, but no edge along the sun bounds them,
    so they are not in the sun and do not say which way the light goes."""
    image, mask = _sunny_floor(rng, reach_wall=False)
    x, y = _floor_points()
    planks = (x > 0.3) & (np.abs(y - 0.75) < 0.07) | (x > 0.6) & (np.abs(y - 1.05) < 0.07)
    image[planks & mask] = 150
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), np.radians([0.0, 90.0]))
    assert abs(math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180 - 30.0) < 2.0
    assert sun.downstream == 0
    assert np.all(sun.sunlit(np.stack([x, y], axis=-1)[planks & mask & (x < 1.4)]) < 0.5)


def test_a_small_patch_counts_only_when_its_far_end_runs_into_a_wall(rng):
    """A patch 12 cm wide along 30 degrees, 0.86 m of edges in all (under the 1 m that
    makes a patch the sun): running into the wall at x = 1.5 m it is found, the light
    travelling toward the wall (+x); as small, ending on the floor, it is not, as nothing
    says which way its light goes (a reversed sun is worse than none)."""
    def patch(x0, width, end_x):
        x, y = _floor_points()
        lit = (x > x0) & (x < end_x) & (np.abs(y - (x - x0) * math.tan(math.radians(30.0))) < width / 2)
        level = np.where(lit, 170.0, 80.0) + rng.normal(0, 2.0, x.shape)
        image = np.repeat(np.clip(level, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
        mask = x < 1.5
        image[~mask] = 200
        return image, mask

    sun = find_sun(*patch(1.2, 0.12, 9.0), FLOOR_FROM_IMAGE, (0.0, 0.0))
    assert sun is not None and 0.5 <= sun.edge_m < RENDER.sun.min_edge_m
    assert sun.downstream * sun.axes_xy[0][0] > 0
    assert abs(math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180 - 30.0) < 3.0
    image, mask = patch(1.0, 0.1, 1.2)
    assert find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0)) is None
    found = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), settings=replace(RENDER.sun, min_edge_m=0.5))
    assert found is not None and found.downstream == 0 and found.edge_m < RENDER.sun.min_edge_m


def test_a_soft_edged_patch_is_read_at_the_coarser_scale(rng):
    """A sun patch 2.4 times as bright as the shade ((120 / 80) ** 2.2, as in the
    photographer's rooms), its light blurred by 4 cm (a window far from the floor, a soft
    photo): the 1.5 cm scale finds no edge steep enough, the 3 cm scale finds the sun's
    azimuth."""
    import cv2
    image, mask = _sunny_floor(rng)
    level = np.where(image > 120, 120.0, 80.0) + rng.normal(0, 2.0, image.shape)
    soft = cv2.GaussianBlur(np.clip(level, 0, 255).astype(np.uint8), (0, 0), 0.04 / MM)
    soft[~mask] = 200
    walls = np.radians([0.0, 90.0])
    fine_only = replace(RENDER.sun, edge_scales=RENDER.sun.edge_scales[:1])
    assert find_sun(soft, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls, settings=fine_only) is None
    sun = find_sun(soft, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls)
    axis = math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180
    assert abs(axis - 30.0) < 2.0


def test_a_patch_too_soft_for_its_edges_is_bounded_by_its_light(rng):
    """A sun patch 2.9 times as bright as the shade ((130 / 80) ** 2.2), its light
    blurred by 15 cm: find_sun reads no edge at either scale. Given the sun's azimuth (a
    window in view), bright_floor keeps the patch's core (the floor over 2.2 times the
    median): all but 5 % of the true patch more than 10 cm inside its edges, nothing beyond
    10 cm outside them, 60-100 % of its area; and reads its contrast within 15 %."""
    import cv2

    from augment.render.sun import bright_floor

    image, mask = _sunny_floor(rng)
    patch = (image[..., 0] > 120) & mask
    level = np.where(patch, 130.0, 80.0)
    soft = cv2.GaussianBlur(level, (0, 0), 0.15 / MM) + rng.normal(0, 2.0, level.shape)
    soft = np.repeat(np.clip(soft, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
    soft[~mask] = 200
    walls = np.radians([0.0, 90.0])
    assert find_sun(soft, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls) is None
    axis = (math.cos(math.radians(30.0)), math.sin(math.radians(30.0)))
    sun = bright_floor(soft, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), axis)
    x, y = _floor_points()
    lit = sun.sunlit(np.stack([x, y], axis=-1)) > 0.5
    reach = round(0.1 / MM)
    inner = cv2.erode(patch.astype(np.uint8), np.ones((2 * reach + 1,) * 2, np.uint8)) > 0
    outer = cv2.dilate(patch.astype(np.uint8), np.ones((2 * reach + 1,) * 2, np.uint8)) > 0
    assert (lit & inner).sum() >= 0.95 * inner.sum()
    assert not (lit & ~outer & mask).any()
    assert 0.6 * patch.sum() <= lit.sum() <= patch.sum()
    assert sun.axes_xy[0] == pytest.approx(axis) and sun.downstream == 0
    assert sun.contrast == pytest.approx((130 / 80) ** 2.2, rel=0.15)
    flat = np.full_like(soft, 80)
    assert bright_floor(flat, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), axis) is None


@pytest.mark.parametrize("sunny", [True, False])
def test_a_sun_patch_on_contrasty_planks_is_read_off_its_edges_that_leave_the_walls(rng, sunny):
    """Planks 15 cm wide along a wall, alternately 1.35 and 0.75 times the floor's level,
    ends every 1.2 m: about 80 m of steps along the walls. The sun patch of
    :func:`_sunny_floor` (sides along 30 degrees, 2.1 times the shade) adds about 5 m of
    steps, under a tenth of the planks' weight: its azimuth is read from the edges that
    leave the walls' directions alone. Without the sun, the planks give none."""
    x, y = _floor_points()
    row = np.floor(y / 0.15)
    plank = np.where(row % 2 == 0, 1.35, 0.75) * np.where(np.floor(x / 1.2 + 0.5 * row) % 2 == 0, 1.0, 0.9)
    patch, mask = _sunny_floor(rng)
    lit = (patch[..., 0] > 120) & mask if sunny else np.zeros_like(mask)
    level = 80.0 * plank * np.where(lit, 170.0 / 80.0, 1.0) + rng.normal(0, 2.0, x.shape)
    image = np.repeat(np.clip(level, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
    image[~mask] = 200
    walls = np.radians([0.0, 90.0])
    sun = find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls)
    if not sunny:
        assert sun is None
        # With one wall in view, planks laid across it run along the walls out of view.
        across = np.where(np.floor(x / 0.15) % 2 == 0, 1.35, 0.75) * 80.0 + rng.normal(0, 2.0, x.shape)
        image = np.repeat(np.clip(across, 0, 255)[..., None], 3, axis=2).astype(np.uint8)
        assert find_sun(image, mask, FLOOR_FROM_IMAGE, (0.0, 0.0), walls[:1]) is None
        return
    axis = math.degrees(math.atan2(sun.axes_xy[0][1], sun.axes_xy[0][0])) % 180
    assert abs(axis - 30.0) < 2.0
    assert sun.downstream * sun.axes_xy[0][0] > 0  # the patch runs into the wall at x = 1.5 m
    found = sun.sunlit(np.stack([x, y], axis=-1)[mask]) > 0.5
    # The sunlit dark planks are hardly brighter than the shaded light ones: some are lost.
    assert (found & lit[mask]).sum() / (found | lit[mask]).sum() > 0.7
    assert not (found & ~lit[mask]).sum() > 0.02 * found.sum()


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


def _estimated(sample, settings=None):
    """The light estimated from a synthetic photo (the room's walls from its true
    outline), and ``world_from_floor`` (4, 4): its floor frame in the photographer's world."""
    truth = sample.truth
    cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(truth["K"][0][0], truth["size_px"]))
    world_from_board = np.asarray(truth["board"]["world_from_board"])
    # The calibration's floor frame is the board's, up to its half-turn symmetry.
    M = np.linalg.inv(world_from_board) @ np.linalg.inv(np.asarray(truth["camera_from_world"])) @ cal.camera_from_floor
    turn = round(math.atan2(M[1, 0], M[0, 0]) / math.pi) * math.pi
    world_from_floor = world_from_board.copy()
    world_from_floor[:3, :3] = world_from_board[:3, :3] @ np.array(
        [[math.cos(turn), -math.sin(turn), 0], [math.sin(turn), math.cos(turn), 0], [0, 0, 1]])
    room = np.asarray(truth["room"]["polygon_m"])
    outline = ((np.column_stack([room, np.zeros(len(room))]) - world_from_board[:3, 3]) @ world_from_floor[:3, :3])
    lighting = estimate_lighting(sample.image, cal, sample.floor_mask, settings, floor_polygon=outline[:, :2])
    return lighting, world_from_floor


def _sun_error_deg(sample, settings=None):
    """The key light estimated from a synthetic photo, and its angle on the floor to the
    photographer's sun, degrees."""
    sun = next(lt for lt in sample.truth["render"]["lights"] if lt["kind"] == "sun")
    lighting, world_from_floor = _estimated(sample, settings)
    true_xy = (world_from_floor[:3, :3].T @ np.asarray(sun["direction"]))[:2]
    got_xy = np.asarray(lighting.direction[:2])
    cos = true_xy @ got_xy / np.linalg.norm(true_xy) / np.linalg.norm(got_xy)
    return lighting, math.degrees(math.acos(np.clip(cos, -1, 1)))


def test_sun_direction_in_a_synthetic_room(renderer):
    """The photographer's sun through a window out of view, read from its patch on the
    floor of the photo: the light travels away from the camera's side."""
    from augment.synth import render_sample

    sample = render_sample([9600, 0], renderer, size_px=(1280, 960), clutter=False)
    lighting, angle = _sun_error_deg(sample)
    assert lighting.source == "sun" and angle < 5.0
    windows_only = replace(RENDER.staged, sun_from_floor=False)
    assert _sun_error_deg(sample, windows_only)[0].source != "sun"
    # Without the sun the floor shows no patches and the light is the window's or the default.
    dim = render_sample([9600, 16], renderer, size_px=(1280, 960), clutter=False)
    assert not any(lt["kind"] == "sun" for lt in dim.truth["render"]["lights"])
    cal = calibrate_photo(dim.image, Board(), intrinsics=exif_intrinsics(dim.truth["K"][0][0], (1280, 960)))
    assert estimate_lighting(dim.image, cal, dim.floor_mask).source != "sun"


def test_a_sun_whose_rim_is_not_sharp_enough_to_be_sure_is_taken_softer(renderer, monkeypatch):
    """Render [9600, 0]'s sun, its rim sharp enough to be sure (q = rim step over share lit
    times contrast, at least 1): the sun's hard light. Asked to be sure only from 2q - 0.6,
    it is half sure: its softness and key half way to a window's (by hand)."""
    from augment.synth import render_sample

    sample = render_sample([9600, 0], renderer, size_px=(1280, 960), clutter=False)
    sure, _ = _sun_error_deg(sample)
    q, st = sure.sun.rim_sharpness, RENDER.staged
    assert sure.source == "sun" and q >= RENDER.sun.rim_step_per_lit_sure
    assert sure.softness_rad == st.sun_softness_rad
    monkeypatch.setattr(RENDER, "sun", replace(RENDER.sun, rim_step_per_lit_sure=2 * q - RENDER.sun.rim_step_per_lit))
    half, _ = _sun_error_deg(sample)
    half_way = st.sun_softness_rad + 0.5 * (st.window_softness_rad - st.sun_softness_rad)
    assert half.softness_rad == pytest.approx(half_way)
    assert half.key_fraction == pytest.approx(st.window_key + 0.5 * (sure.key_fraction - st.window_key))


def test_sun_through_the_window_in_view(renderer):
    """The window in view, slid down along the sun's edges, lands on its patch on the
    floor: it casts it, and the light travels from that window (here toward the camera)."""
    from augment.synth import render_sample

    sample = render_sample([9601, 28], renderer, size_px=(1600, 1200), clutter=False)
    lighting, angle = _sun_error_deg(sample)
    assert lighting.source == "sun" and lighting.way == "window_casts" and angle < 5.0


def test_a_lit_door_is_no_window(renderer):
    """Render [9801, 33]: the brightest thing on its walls is a cream door at the photo's
    edge, lit by the sun; it reaches the floor, so the key light is not taken from it as
    from a window (it was, 160 degrees off the sun, before the sill test)."""
    from augment.synth import render_sample

    sample = render_sample([9801, 33], renderer, size_px=(1280, 960), clutter=False)
    assert _sun_error_deg(sample)[0].source != "window"
    no_sill = replace(RENDER.staged, window_min_sill_m=0.0)
    assert _sun_error_deg(sample, no_sill)[0].source == "window"


def test_a_soft_sun_patch_below_a_window_in_view_bounds_the_sun(renderer):
    """Render [9800, 38]: the sun through the window in view onto the floor, its patch too
    soft for find_sun's edges. The key light is the window's, its way and height where the
    window's outline, slid down along the sun, lands on that floor (within 6 and 4 deg of
    the photographer's sun), and the floor it takes as sunlit (:func:`bright_floor`) is in
    the photographer's sun: 90 % of it at least, by the room's geometry (the ray to the
    sun leaves through a window)."""
    from augment.synth import render_sample
    from augment.synth.truth import sun_exit

    sample = render_sample([9800, 38], renderer, size_px=(1280, 960), clutter=False)
    lighting, world_from_floor = _estimated(sample)
    assert lighting.source == "window" and lighting.sun is not None
    # Its way and height: where the window's outline, slid down along the sun, lands on it.
    light = next(lt for lt in sample.truth["render"]["lights"] if lt["kind"] == "sun")
    true_floor = world_from_floor[:3, :3].T @ np.asarray(light["direction"])
    got = np.asarray(lighting.direction)
    cos = true_floor[:2] @ got[:2] / np.linalg.norm(true_floor[:2]) / np.linalg.norm(got[:2])
    assert lighting.way == "window_patch" and math.degrees(math.acos(min(cos, 1.0))) < 6.0
    assert math.degrees(math.asin(-got[2])) == pytest.approx(math.degrees(math.asin(-true_floor[2])), abs=4.0)
    sun = lighting.sun
    rows, cols = np.nonzero(sun.lit)
    xy = np.column_stack([sun.lo_m[0] + (cols + 0.5) * sun.cell_m, sun.lo_m[1] + (rows + 0.5) * sun.cell_m])
    world = np.column_stack([xy, np.zeros(len(xy)), np.ones(len(xy))]) @ world_from_floor.T
    truth = sample.truth
    light = next(lt for lt in truth["render"]["lights"] if lt["kind"] == "sun")
    windows = [(np.asarray(w["segment_m"]), w["bottom_m"], w["top_m"]) for w in truth["room"]["windows"]]
    lit = sun_exit(world[:, :3], light["direction"], np.asarray(truth["room"]["polygon_m"]), truth["room"]["height_m"],
                   windows) > 0
    assert len(xy) > 500 and lit.mean() >= 0.9


def test_the_boards_paper_is_no_sunlit_floor(renderer):
    """Render [9801, 44]: a dark floor, a window in view, the sun out of view (none of
    the floor in view sunlit). The board's white paper is the only floor far brighter than
    the rest: it is no sun patch, so the window gives a soft, modest key and no floor is
    taken as sunlit (before, the paper made the window's light a hard sun)."""
    from augment.synth import render_sample

    sample = render_sample([9801, 44], renderer, size_px=(1280, 960), clutter=False)
    sun = next(lt for lt in sample.truth["render"]["lights"] if lt["kind"] == "sun")
    assert sun["floor_in_view"] == 0.0
    lighting, _ = _estimated(sample)
    assert lighting.source == "window" and lighting.sun is None
    assert lighting.key_fraction == pytest.approx(RENDER.staged.window_key)
    assert lighting.softness_rad == pytest.approx(RENDER.staged.window_softness_rad)


def _sun_over(lit_where, share=0.5):
    """A SunOnFloor over the square (-2, -2)-(2, 2) m, 1 cm cells, lit where
    ``lit_where(x, y)``; all of it seen."""
    n = 400
    y, x = (np.mgrid[0:n, 0:n] + 0.5) * 0.01 - 2.0
    lit = lit_where(x, y)
    return SunOnFloor(((1.0, 0.0),), True, 2.0, 2.5, (0.0, 0.0), 1, share, (-2.0, -2.0), 0.01, lit,
                      np.ones_like(lit))


@pytest.mark.parametrize("x_from, x_to, seen_to, expected_deg", [
    (-1.0, 1.0, 2.0, math.degrees(math.atan(1.2 / (0.98 * 2.0)))),  # whole in view: the glass over the run
    (-0.25, 0.25, 2.0, 60.0),  # a run this short would put the sun higher than it is let go
    (-1.0, 0.5, 0.5, 35.0),  # into the photo's edge: 1.47 m or more, under the default's 35 deg anyway
    (-1.9, 1.5, 1.5, math.degrees(math.atan(1.2 / (0.98 * 3.4)))),  # into it, but long enough to lower the sun
])
def test_the_suns_height_from_how_far_its_patch_runs(x_from, x_to, seen_to, expected_deg):
    """Hand-computed: a window's glass 1.2 m tall casts a patch 1.2 m / tan(elevation)
    long; where the patch runs out of view its run only caps the default height."""
    sun = _sun_over(lambda x, y: (x >= x_from) & (x < x_to) & (np.abs(y) < 0.3))
    x = (np.arange(sun.lit.shape[1]) + 0.5) * 0.01 - 2.0
    sun = replace(sun, seen=np.broadcast_to(x < seen_to, sun.lit.shape).copy())
    got = math.degrees(sun_elevation_rad(sun, math.radians(35.0)))
    assert got == pytest.approx(expected_deg, abs=0.5)


def test_the_floor_under_the_boards_sheet_takes_the_sun_along_it():
    """A band of sun |y| < 0.5 m along the sun's axis (x); the sheet, left out of the
    floor seen, straddles its edge (x within 0.2 m, y 0.3-0.7 m). Under it the band goes
    on straight: in the sun at y = 0.4, in shade at y = 0.6; without the sheet known, the
    share in the sun (0.3) there."""
    sun = _sun_over(lambda x, y: np.abs(y) < 0.5, share=0.3)
    y, x = (np.mgrid[0:400, 0:400] + 0.5) * 0.01 - 2.0
    sheet = (np.abs(x) < 0.2) & (y > 0.3) & (y < 0.7)
    left_out = replace(sun, lit=sun.lit & ~sheet, seen=~sheet)
    np.testing.assert_allclose(left_out.sunlit(np.array([[0.0, 0.4], [0.0, 0.6]])), [0.3, 0.3])
    np.testing.assert_allclose(replace(left_out, sheet=sheet).sunlit(np.array([[0.0, 0.4], [0.0, 0.6]])), [1.0, 0.0])


def test_only_what_stands_in_the_beam_gets_the_sun():
    """Light travelling +x, 45 degrees down; the floor sunlit for x < 0. A point 1 m up at
    x = -1.5 is in the beam (the light through it lands at x = -0.5, sunlit in the empty
    room); 1 m up at x = -0.5 it is not (it would land at x = 0.5), though the floor below
    it is sunlit; off the floor seen, the share in the sun."""
    d = (math.sqrt(0.5), 0.0, -math.sqrt(0.5))
    sun = _sun_over(lambda x, y: x < 0, share=0.3)
    light = Lighting((0.8, 0.8, 0.8), d, 0.6, 0.01, (0.4, 0.4, 0.4), "sun", sun)
    got = _in_beam(np.array([[-1.5, 0.0, 1.0], [-0.5, 0.0, 1.0], [-0.3, 0.0, 0.0], [0.5, 0.0, 0.0], [9.0, 0.0, 0.0]]),
                   light)
    np.testing.assert_allclose(got, [1.0, 0.0, 1.0, 0.0, 0.3])


def test_a_box_in_the_shade_casts_no_sun_shadow():
    """A 40 cm box with the sun from -x at 45 degrees: 10 cm behind it (+x) the floor loses
    most of the sun where the floor is sunlit, and none of it where the floor is in shade:
    there it is as bright as 10 cm in front of it (-x), where only occlusion darkens it
    (alike within the sky's sampling, 0.03)."""
    d = (math.sqrt(0.5), 0.0, -math.sqrt(0.5))
    box = np.array([[x, y, z] for x in (-0.2, 0.2) for y in (-0.2, 0.2) for z in (0.0, 0.4)])
    at = np.array([[0.3, 0.0], [-0.3, 0.0]])
    gains = {}
    for name, lit_where in (("sunlit", lambda x, y: np.ones_like(x, bool)),
                            ("shade", lambda x, y: np.zeros_like(x, bool))):
        light = Lighting((0.8, 0.8, 0.8), d, 0.6, 0.01, (0.4, 0.4, 0.4), "sun", _sun_over(lit_where))
        shading = _floor_gain([_Caster(box, None, 0.0, 0.4)], light, ((-1, -1), (1, 1)), RENDER.staged)
        gain, grid = shading.gain, shading.grid
        cells = np.floor(grid.to_px(at)).astype(int)
        gains[name] = gain[cells[:, 1], cells[:, 0]].astype(float)
    behind, front = gains["sunlit"]
    assert behind < 0.8 and behind < front - 0.2
    behind, front = gains["shade"]
    assert abs(behind - front) < 0.03 and front > 0.8


def _sky_hidden(point, lo, hi, n=300):
    """The share of a uniform, cosine-weighted sky a box (lo, hi corners) hides from a floor
    point: an n x n stratified grid of directions, each tested against the box's slabs."""
    u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
    r, phi = np.sqrt(u.ravel()), 2 * np.pi * v.ravel()
    d = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - r * r)], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (np.asarray(lo) - point) / d, (np.asarray(hi) - point) / d
    near = np.nanmax(np.minimum(t0, t1), axis=1)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    return float(np.mean((near <= far) & (far > 0)))


@pytest.mark.parametrize("lo, hi, points", [
    # A cabinet 2 m wide, 0.5 m deep, 0.8 m tall: 20, 40, 80 cm in front of it.
    ((-0.25, -1.0, 0.0), (0.25, 1.0, 0.8), [(0.45, 0.0), (0.65, 0.0), (1.05, 0.0)]),
    # A 1.2 x 0.6 m tabletop 42 cm up: under its middle, under its edge, 30 cm beside it.
    ((-0.6, -0.3, 0.42), (0.6, 0.3, 0.45), [(0.0, 0.0), (0.0, 0.3), (0.0, 0.6)]),
])
def test_occlusion_is_the_share_of_the_sky_a_box_hides(lo, hi, points):
    """No key light: the floor loses the share of a uniform sky the box hides, integrated
    numerically (beside the cabinet it matches a wall's 0.5 (1 - d / sqrt(d^2 + h^2))
    within 0.03), within 0.03. The blurred footprints this replaced lost 0.25 where the
    sky says 0.37, 20 cm from the cabinet."""
    lo, hi = np.array(lo), np.array(hi)
    box = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    light = Lighting((0.8, 0.8, 0.8), (0.0, 0.0, -1.0), 0.0, 0.3, (0.4, 0.4, 0.4), "default", None)
    shading = _floor_gain([_Caster(box, None, lo[2], hi[2])], light, ((-2, -2), (2, 2)), RENDER.staged)
    for x, y in points:
        cell = np.floor(shading.grid.to_px(np.array([[x, y]]))).astype(int)[0]
        lost = 1.0 - float(shading.gain[cell[1], cell[0]]) ** 2.2
        hidden = _sky_hidden(np.array([x, y, 0.0]), lo, hi)
        assert abs(lost - RENDER.staged.ao_strength * hidden) < 0.03, ((x, y), lost, hidden)


def test_the_sun_patch_edge_is_as_soft_as_the_photos():
    """The floor sunlit for x < 0 along a ragged edge (off by up to 3 cm, in steps every
    10 cm of y; 1 cm cells), its edges found at a 2 cm scale: along x, the sun's share
    falls from 1 at -10 cm to 0 at +10 cm, steadily, through 0.5 within 1 cm of the edge
    there; along the edge's mean line its spread is under two thirds of the raster's, which flips
    between 0 and 1. With no scale, it is the raster."""
    from dataclasses import replace

    rng = np.random.default_rng(5)
    ragged = np.repeat(rng.uniform(-0.03, 0.03, 40), 10)  # the edge's x per 1 cm row of y

    def left_of_edge(x, y):
        return x < ragged[np.clip(((y[:, :1] + 2.0) / 0.01).astype(int), 0, 399)]

    sun = _sun_over(left_of_edge)
    soft = replace(sun, edge_sigma_m=0.02)
    ys = np.linspace(-1.5, 1.5, 301)
    for x, want in ((-0.1, 1.0), (0.1, 0.0)):
        assert np.allclose(soft.sunlit(np.column_stack([np.full_like(ys, x), ys])), want, atol=0.05)
    xs = np.linspace(-0.1, 0.1, 201)
    profile = soft.sunlit(np.column_stack([xs, np.full_like(xs, 0.055)]))  # row 205, mid-step
    assert np.all(np.diff(profile) <= 1e-9)
    assert abs(xs[np.argmin(np.abs(profile - 0.5))] - ragged[205]) < 0.01
    at_edge = np.column_stack([np.full_like(ys, float(np.mean(ragged))), ys])
    raw = sun.sunlit(at_edge)
    assert raw.min() == 0.0 and raw.max() == 1.0
    assert np.std(soft.sunlit(at_edge)) < 0.65 * np.std(raw)


def _drawn_floor(lit_box_m):
    """A top-down view of a floor 6 x 4 m (x from -1 m, y from -2 m, 2 cm cells), all seen,
    lit in the box ((x0, x1), (y0, y1)), meters."""
    cell, lo = 0.02, (-1.0, -2.0)
    y, x = np.mgrid[0:200, 0:300] * cell + np.array(lo)[::-1, None, None]
    (x0, x1), (y0, y1) = lit_box_m
    lit = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)
    return SunOnFloor(((1.0, 0.0),), False, 0.0, 3.0, (0.0, 0.0), 0, float(lit.mean()), lo, cell, lit,
                      np.ones(lit.shape, bool))


@pytest.mark.parametrize("lit_box_m, aim, mirrored", [
    (((1.0, 1.8), (-0.35, 0.35)), None, True),  # the window's mirror image is bright
    (((2.2, 2.9), (-0.35, 0.35)), None, False),  # bright floor between it and the wall: a sun's patch
    (((1.0, 1.8), (-0.35, 0.35)), (-0.8, 0.0, -0.6), True),  # the sun fitted comes at the camera
    (((1.0, 1.8), (-0.35, 0.35)), (-0.6, 0.45, -0.66), False),  # ... 37 degrees off it: a sun
])
def test_a_glossy_floor_mirroring_the_window_is_no_sun(lit_box_m, aim, mirrored):
    """A window 1 m wide on the wall x = 3 m (sill 0.9 m, head 2.1 m), the camera 1.2 m
    above the floor's origin: mirrored below the floor, its sill is seen 3 x 1.2 / 2.1 =
    1.71 m from the camera, its head 3 x 1.2 / 3.3 = 1.09 m, its sides within 0.29 m of
    the axis (by hand)."""
    from augment.render.staged import _mirrors_window

    outline = np.array([[3.0, -0.5, 0.9], [3.0, 0.5, 0.9], [3.0, 0.5, 2.1], [3.0, -0.5, 2.1]])
    window = (outline, np.array([0.0, 1.0]), np.array([-1.0, 0.0]))
    assert _mirrors_window(window, _drawn_floor(lit_box_m), (0.0, 0.0, 1.2), aim, RENDER.staged) is mirrored


@pytest.fixture(scope="module")
def real_rooms(tmp_path_factory):
    """Photos of samples/real (Curtis Adams / Pexels, Pexels License) with the print pasted
    where ``rooms.json`` puts it, saved as JPEG, calibrated and their floor segmented, as
    the pipeline does: name -> (image, calibration, floor mask, floor polygon)."""
    import json
    from pathlib import Path

    from augment.floor.model import DEFAULT_MODEL, FloorModel
    from augment.floor.polygon import floor_polygon
    from augment.floor.segment import segment_floor
    from augment.photo.io import read_photo
    from augment.synth.photo import save_as_phone
    from augment.synth.prints import paste_planned

    real = Path(__file__).resolve().parents[2] / "samples" / "real"
    plans = json.loads((real / "rooms.json").read_text())
    model = FloorModel(DEFAULT_MODEL)
    out = {}
    for name in ("bedroom_closets", "bedroom_windows", "dining_room"):
        path = tmp_path_factory.mktemp("real") / f"{name}.jpg"
        pasted = paste_planned(read_photo(real / f"{name}.jpg"), plans[name])[0]
        save_as_phone(path, pasted, plans[name]["focal_px"], 92)
        photo = read_photo(path)
        cal = calibrate_photo(photo, Board(), intrinsics=exif_intrinsics(plans[name]["focal_px"], photo.shape[1::-1]))
        mask = segment_floor(photo, calibration=cal, model=model).mask
        out[name] = (photo, cal, mask, floor_polygon(mask, cal))
    return out


def _real_lighting(real_rooms, name, **staged):
    image, cal, mask, polygon = real_rooms[name]
    return estimate_lighting(image, cal, mask, replace(RENDER.staged, **staged), floor_polygon=polygon)


def test_real_glossy_floors_read_as_their_windows_sheen(real_rooms):
    """The two dark glossy plank floors mirror their windows: their bright floor lies under
    the window's mirror image and its rim steps less than a sure sun's. Read as the
    window's soft light, with the floor's gloss from the window's reflection (a sun read
    there left them without reflections, its light from a wrong way)."""
    for name in ("bedroom_windows", "dining_room"):
        lighting = _real_lighting(real_rooms, name)
        assert lighting.source == "window" and lighting.sun is None, (name, lighting.source, lighting.way)
        assert lighting.floor_gloss >= 0.2, (name, lighting.floor_gloss)


def test_no_hard_sun_on_real_wood_floors_lit_by_daylight(real_rooms, monkeypatch):
    """Three real rooms without sun: laminate lit by daylight falling off away from the
    windows, and two dark glossy plank floors that mirror their windows. No hard key
    light: their lighter floor's rim does not step like a sun's edge (0.2-0.7 of the
    share lit times the contrast): no sun read, or one taken mostly as a window's light,
    nearly white. Without the rim's step the grain and the planks are a hard sun."""
    st = RENDER.staged
    for name in real_rooms:
        lighting = _real_lighting(real_rooms, name)
        assert lighting.softness_rad > 0.3 and lighting.key_fraction < 0.33, (name, lighting)
        assert max(lighting.key_rgb) < 1.3, (name, lighting.key_rgb)
    assert _real_lighting(real_rooms, "bedroom_closets").sun is None
    monkeypatch.setattr(RENDER, "sun", replace(RENDER.sun, rim_step_per_lit=0.0, rim_step_per_lit_sure=1e-9))
    hard = [_real_lighting(real_rooms, name) for name in real_rooms]
    assert sum(lt.source == "sun" and lt.softness_rad <= st.sun_softness_rad for lt in hard) >= 2
