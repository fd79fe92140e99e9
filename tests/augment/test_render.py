"""Rendering furniture into photos: geometry against the ground truth of a synthetic photo,
shadows, occlusion, the furniture's sizes, and the renderer's hygiene."""
from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np
import pytest
import trimesh

from augment.camera.board import Board
from augment.camera.calibration import Calibration, Intrinsics
from augment.floor.polygon import FloorPolygon
from augment.photo.io import read_photo
from augment.render.furniture import (BUILDERS, Folds, Material, Part, PlacedItem, _crowned_box_mesh, _cushion,
                                      _draped_mesh, _Shop, build_furniture, furniture_for, furniture_from_asset,
                                      load_asset, placed_items, world_from_item)
from augment.render.gl import Renderer
from augment.render.look import CLEAN
from augment.render.settings import RENDER
from augment.render.staged import (Lighting, _Caster, _casters, _composite, _floor_gain, _furniture_meshes,
                                   _nearer_edge_upstream, _on_wall_m, _plain_wall_upstream, _render_scale, _roll_off,
                                   _wall_shading, _walls_run_on,
                                   _window, _window_casts, _window_casts_either, _window_on_wall, _window_sun,
                                   estimate_lighting, floor_matte, render_staged, wall_segments, write_jpeg)
from augment.render.sun import SunOnFloor
from augment.synth.scene import furniture_meshes
from layout.catalog import CATALOG

PHOTOS = Path(__file__).resolve().parents[2] / "samples" / "photos"
LIGHT = Lighting((0.8, 0.78, 0.75), (0.3, 0.5, -0.81), 0.5, 0.08, (0.3, 0.25, 0.2), "test")


def _truth_calibration(name: str, scale: float = 1.0, distortion=None):
    """The photo ``name`` (resized by ``scale``), its floor mask, and a Calibration built
    from its ground truth: exact K and pose, floor frame = the board's."""
    truth = json.loads((PHOTOS / f"{name}.json").read_text())
    image = read_photo(PHOTOS / f"{name}.jpg")
    mask = cv2.imread(str(PHOTOS / f"{name}_floor.png"), cv2.IMREAD_GRAYSCALE) > 127
    K = np.array(truth["K"], dtype=np.float64)
    if scale != 1.0:
        h, w = image.shape[:2]
        size = (round(w * scale), round(h * scale))
        image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
        mask = cv2.resize(mask.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0
        K[:2, :2] *= scale
        K[0, 2], K[1, 2] = (K[0, 2] + 0.5) * scale - 0.5, (K[1, 2] + 0.5) * scale - 0.5
    pose = np.array(truth["camera_from_world"]) @ np.array(truth["board"]["world_from_board"])
    dist = np.zeros(5) if distortion is None else np.asarray(distortion, dtype=np.float64)
    R, t = pose[:3, :3], pose[:3, 3]
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    horizon = np.linalg.inv(K).T @ R[:, 2]
    calibration = Calibration(
        size_px=(image.shape[1], image.shape[0]), intrinsics=Intrinsics(K, dist, "truth", 0.0),
        camera_from_floor=pose, camera_height_m=float(-R[:, 2] @ t),
        floor_plane_camera=np.append(R[:, 2], -R[:, 2] @ t),
        image_from_floor=H / H[2, 2], horizon=-horizon / np.hypot(*horizon[:2]), rms_px=0.0,
        corners_px=np.zeros((0, 2)), corner_ids=np.zeros(0, np.int64), detector="truth", board=Board())
    return image, mask, calibration


@pytest.fixture(scope="module")
def renderer():
    with Renderer() as r:
        yield r


@pytest.fixture(scope="module")
def room_small():
    return _truth_calibration("room_1", 0.5)


def _box_parts():
    """An exact unit box (no bevels) as furniture parts, base at z = 0."""
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    box.apply_translation((0, 0, 0.5))
    v = box.vertices[box.faces].reshape(-1, 3)
    n = np.repeat(box.face_normals, 3, axis=0)
    from augment.render.furniture import Material
    return (Part(v, n, np.arange(len(v)).reshape(-1, 3), Material("grey", (0.4, 0.4, 0.4), 0.8)),)


def _project(calibration, points):
    pose = calibration.camera_from_floor
    px, _ = cv2.projectPoints(np.asarray(points, dtype=np.float64).reshape(-1, 1, 3),
                              cv2.Rodrigues(pose[:3, :3])[0], pose[:3, 3], calibration.intrinsics.K,
                              calibration.intrinsics.distortion)
    return px.reshape(-1, 2)


def _box_corners(center_xy, size, yaw=0.0):
    w, d, h = size
    c, s = np.cos(yaw), np.sin(yaw)
    out = []
    for z in (0.0, h):
        for x, y in ((-d / 2, -w / 2), (d / 2, -w / 2), (d / 2, w / 2), (-d / 2, w / 2)):
            out.append((center_xy[0] + c * x - s * y, center_xy[1] + s * x + c * y, z))
    return np.array(out)


def _hull_mask(shape, px):
    """Pixels (h, w) bool whose centers lie inside the convex hull of ``px``, subpixel exact."""
    mask = np.zeros(shape, np.uint8)
    hull = cv2.convexHull(np.round(px * 256).astype(np.int32).reshape(-1, 1, 2))
    cv2.fillConvexPoly(mask, hull, 1, lineType=cv2.LINE_8, shift=8)
    return mask.astype(bool)


def _band(mask):
    """Pixels within one pixel of the mask's boundary."""
    m = mask.astype(np.uint8)
    k = np.ones((3, 3), np.uint8)
    return (cv2.dilate(m, k) - cv2.erode(m, k)).astype(bool)


def _render_box(renderer, image, calibration, center_xy, size, yaw=0.0, **kw):
    item = PlacedItem("test_box", (center_xy[0], center_xy[1], size[2] / 2), yaw, size, "box")
    parts = _box_parts()
    return render_staged(image, calibration, [item], renderer, assets={"test_box": parts}, lighting=LIGHT,
                         seed=0, **kw)


# --------------------------------------------------------------------------------------
# Geometry
# --------------------------------------------------------------------------------------

def test_box_base_corners_land_on_the_true_projection(renderer):
    """A 0.6 x 0.4 x 0.5 m box on the floor of a synthetic photo, camera and floor from its
    ground truth: the silhouette's base corners are within 1 px of where K and the pose put
    them (the render is the photo's own camera, to the pixel center convention)."""
    image, _, calibration = _truth_calibration("room_1")
    size = (0.6, 0.4, 0.5)
    staged = _render_box(renderer, image, calibration, (0.2, 0.3), size, yaw=0.4, supersample=1.0)
    corners = _box_corners((0.2, 0.3), size, 0.4)
    px = _project(calibration, corners)
    hull = cv2.convexHull(px.astype(np.float32)).reshape(-1, 2)
    alpha = staged.alpha
    checked = 0
    for k in range(4):  # base corners on the silhouette
        p = px[k]
        if np.min(np.linalg.norm(hull - p, axis=1)) > 1e-3:
            continue  # inside the silhouette: hidden behind the box
        # Along the bisector of the hull's corner: covered 1.5 px inside, empty 1.5 px outside.
        i = int(np.argmin(np.linalg.norm(hull - p, axis=1)))
        a, b = hull[i - 1] - p, hull[(i + 1) % len(hull)] - p
        inward = a / np.linalg.norm(a) + b / np.linalg.norm(b)
        inward /= np.linalg.norm(inward)
        inside, outside = np.rint(p + 1.5 * inward).astype(int), np.rint(p - 1.5 * inward).astype(int)
        assert alpha[inside[1], inside[0]] > 0.5, f"corner {k} at {p}: not covered just inside"
        assert alpha[outside[1], outside[0]] < 0.5, f"corner {k} at {p}: covered just outside"
        checked += 1
    assert checked >= 2
    # The whole silhouette: same area and centroid as the projected hull.
    expected = _hull_mask(alpha.shape, px)
    ys, xs = np.nonzero(expected)
    w = alpha[alpha > 0]
    yy, xx = np.nonzero(alpha > 0)
    assert abs(alpha.sum() - expected.sum()) / expected.sum() < 0.01
    assert np.hypot(np.average(xx, weights=w) - xs.mean(), np.average(yy, weights=w) - ys.mean()) < 0.2


def test_unit_cube_at_the_board_origin_covers_exactly_its_hull(renderer, room_small):
    image, _, calibration = room_small
    staged = _render_box(renderer, image, calibration, (0.0, 0.0), (1.0, 1.0, 1.0), supersample=1.0)
    expected = _hull_mask(staged.alpha.shape, _project(calibration, _box_corners((0, 0), (1, 1, 1))))
    covered = staged.alpha > 0.5
    wrong = covered != expected
    assert expected.sum() > 5000
    assert not (wrong & ~_band(expected)).any(), "pixels off the cube's outline differ"
    # On the outline the 4x multisampled coverage is the pixel's share of the cube.
    assert abs(staged.alpha.sum() - expected.sum()) < 0.005 * expected.sum()


def test_the_suns_beam_edge_crosses_a_face_where_it_falls(renderer, room_small):
    """A unit cube at the origin, the sun travelling along (0.3, 0.5, -0.81) (half the
    light), the empty room's floor sunlit where x < 0.1. The light through the cube's top,
    1 m up, lands 0.37 m further along x (0.3 / 0.81), so the top is in the sun where
    x < -0.27: 5 cm either side of that line it shows the key light and not, each within
    3 % of 15 cm further on (a step where the edge falls, not a ramp between the face's
    corners)."""
    image, _, calibration = room_small
    x = (np.arange(500) + 0.5) * 0.01 - 2.5
    lit = np.broadcast_to(x < 0.1, (500, 500)).copy()
    sun = SunOnFloor(((1.0, 0.0),), True, 2.0, 2.0, (0.0, 0.0), 0, 0.5, (-2.5, -2.5), 0.01, lit, np.ones_like(lit))
    item = PlacedItem("test_box", (0.0, 0.0, 0.5), 0.0, (1.0, 1.0, 1.0), "box")
    staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()}, seed=0,
                           lighting=replace(LIGHT, source="sun", sun=sun), look=CLEAN, supersample=1.0)
    at = np.rint(_project(calibration, [(x, 0.0, 1.0) for x in (-0.47, -0.32, -0.22, -0.07)])).astype(int)
    assert np.all(staged.alpha[at[:, 1], at[:, 0]] == 1.0)
    light = ((staged.image[at[:, 1], at[:, 0]].astype(float) / 255) ** 2.2).mean(axis=1)
    far_sun, sun_side, shade_side, far_shade = light
    assert sun_side > 1.5 * shade_side
    assert sun_side == pytest.approx(far_sun, rel=0.03) and shade_side == pytest.approx(far_shade, rel=0.03)


def test_a_strong_coloured_sun_leaves_the_shade_its_own_colour(renderer, room_small):
    """The cube of the test above, its top half in a sun far bluer than it is red, bright
    enough that sun and shade together pass white in blue: out of the beam the top shows
    the shade's light alone, grey as under a white sun (not all the light less the key,
    whose blue was clipped: yellow)."""
    image, _, calibration = room_small
    x = (np.arange(500) + 0.5) * 0.01 - 2.5
    lit = np.broadcast_to(x < 0.1, (500, 500)).copy()
    sun = SunOnFloor(((1.0, 0.0),), True, 2.0, 2.0, (0.0, 0.0), 0, 0.5, (-2.5, -2.5), 0.01, lit, np.ones_like(lit))
    item = PlacedItem("test_box", (0.0, 0.0, 0.5), 0.0, (1.0, 1.0, 1.0), "box")
    at = np.rint(_project(calibration, [(0.1, 0.0, 1.0), (-0.4, 0.0, 1.0)])).astype(int)
    colours = {}
    for key_rgb in ((1.0, 1.0, 1.0), (0.55, 0.95, 1.5)):
        light = replace(LIGHT, source="sun", sun=sun, key_rgb=key_rgb, irradiance_rgb=(2.0, 2.0, 2.0))
        staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()}, seed=0,
                               lighting=light, look=CLEAN, supersample=1.0)
        colours[key_rgb] = staged.image[at[:, 1], at[:, 0]].astype(float)
    white, blue = colours.values()
    assert blue[1, 2] > blue[1, 0] + 40  # in the sun: blue
    # In the shade: grey as under a white sun (a little darker: the sunlit corner's light
    # rolls off more, and its vertex shares the face).
    assert np.ptp(white[0]) <= 2 and np.ptp(blue[0]) <= 2
    assert blue[0, 0] == pytest.approx(white[0, 0], abs=10)


def test_a_blurrier_photo_is_rendered_coarser_but_never_sharper_than_it_needs():
    """The render scale of a 12 MP region: 0.6 by default; where the photo's edge spread
    is wide, low enough that the render's (0.55 px / scale) stays at 0.7 of it; never
    below 0.35. A small region is supersampled (2x) in a sharp photo, only as far as that
    edge spread asks in a softer one, and not at all where one photo pixel is enough."""
    st = RENDER.staged
    assert _render_scale(12e6, None, 0.0, st) == pytest.approx(0.6)
    assert _render_scale(12e6, None, 1.0, st) == pytest.approx(0.6)
    assert _render_scale(12e6, None, 1.5, st) == pytest.approx(0.55 / (0.7 * 1.5))
    assert _render_scale(12e6, None, 4.0, st) == pytest.approx(0.35)
    assert _render_scale(0.3e6, None, 0.0, st) == 2.0
    assert _render_scale(0.3e6, None, 0.3, st) == 2.0
    assert _render_scale(0.3e6, None, 0.5, st) == 1.5  # 0.55 / (0.7 * 0.5) = 1.57, in quarter steps
    assert _render_scale(0.3e6, None, 1.5, st) == 1.0
    assert _render_scale(0.3e6, None, 4.0, st) == 1.0
    assert _render_scale(12e6, 1.5, 4.0, st) == 1.5


def test_distorted_lens_follows_the_distortion(renderer):
    """With radial distortion the render is warped like the photo: the cube's outline is
    where cv2.projectPoints puts it, within the 1-px band."""
    image, _, calibration = _truth_calibration("room_1", 0.5, distortion=(-0.12, 0.02, 0, 0, 0))
    staged = _render_box(renderer, image, calibration, (0.0, 0.0), (1.0, 1.0, 1.0), supersample=1.0)
    edges = _box_corners((0, 0), (1, 1, 1))
    pairs = [(a, b) for a in range(8) for b in range(a + 1, 8) if np.sum(edges[a] != edges[b]) == 1]
    dense = np.concatenate([edges[a] + np.linspace(0, 1, 60)[:, None] * (edges[b] - edges[a]) for a, b in pairs])
    expected = _hull_mask(staged.alpha.shape, _project(calibration, dense))
    wrong = (staged.alpha > 0.5) != expected
    wrong[[0, -1]] = wrong[:, [0, -1]] = False  # the band is not defined on the photo's edge
    assert expected.sum() > 5000
    assert not (wrong & ~_band(expected)).any()


# --------------------------------------------------------------------------------------
# Shadows and occlusion
# --------------------------------------------------------------------------------------

def test_floor_under_a_table_darkens_and_far_floor_is_untouched(renderer):
    image, mask, calibration = _truth_calibration("room_2", 0.5)
    pose = calibration.camera_from_floor
    cam = (-pose[:3, :3].T @ pose[:3, 3])[:2]
    forward = pose[2, :2] / np.linalg.norm(pose[2, :2])
    cx, cy = cam + 2.6 * forward
    table = PlacedItem("dining_table", (cx, cy, 0.375), 0.2, (1.6, 0.9, 0.75), "table")
    staged = render_staged(image, calibration, [table], renderer, floor_mask=mask, lighting=LIGHT)
    # Floor points under the top, inset from its edge, that the camera sees between the legs.
    g = np.stack(np.meshgrid(np.linspace(-0.3, 0.3, 13), np.linspace(-0.6, 0.6, 25)), -1).reshape(-1, 2)
    c, s = np.cos(0.2), np.sin(0.2)
    floor = np.column_stack([cx + c * g[:, 0] - s * g[:, 1], cy + s * g[:, 0] + c * g[:, 1], np.zeros(len(g))])
    px = np.rint(_project(calibration, floor)).astype(int)
    h, w = mask.shape
    ok = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
    px = px[ok]
    seen = (staged.alpha[px[:, 1], px[:, 0]] == 0) & mask[px[:, 1], px[:, 0]]
    assert seen.sum() >= 10, "the test needs floor visible under the table"
    before = image[px[seen, 1], px[seen, 0]].astype(float).sum(axis=1)
    after = staged.image[px[seen, 1], px[seen, 0]].astype(float).sum(axis=1)
    assert np.all(after <= before) and np.median(after / before) < 0.85
    # Everything outside the rendered region is untouched.
    x0, y0, x1, y1 = staged.roi_px
    outside = np.ones(mask.shape, bool)
    outside[y0:y1, x0:x1] = False
    assert np.array_equal(staged.image[outside], image[outside])
    # Floor pixels 2.3 m and more from the table's center (beyond its shadow and the reach of its
    # occlusion, 1.75 x its height from its edge): unchanged.
    ys, xs = np.mgrid[0:h:3, 0:w:3]
    xy = cv2.perspectiveTransform(np.stack([xs, ys], -1).reshape(-1, 1, 2).astype(np.float64),
                                  np.linalg.inv(calibration.image_from_floor)).reshape(-1, 2)
    far = ((np.hypot(xy[:, 0] - cx, xy[:, 1] - cy) > 2.3) & mask[ys.ravel(), xs.ravel()]
           & (staged.alpha[ys.ravel(), xs.ravel()] == 0))
    assert far.sum() > 500
    fy, fx = ys.ravel()[far], xs.ravel()[far]
    assert np.array_equal(staged.image[fy, fx], image[fy, fx])


def _cell(grid, raster, u, z):
    """A wall raster's cell at (u, z) meters in the wall's frame; 0 off the raster."""
    col, row = np.floor(grid.to_px(np.array([u, z]))).astype(int)
    return float(raster[row, col]) if 0 <= row < raster.shape[0] and 0 <= col < raster.shape[1] else 0.0


def test_a_walls_occlusion_behind_a_plate_standing_before_it_is_the_view_factor():
    """A plate 1 m square standing 0.7 m before a wall, parallel to it: the wall point
    behind its centre loses the plate's view factor of the light from the room (the
    textbook formula for a plane element facing a parallel rectangle, four corner
    rectangles), the wall 3 m along it nothing. The same plate behind the wall hides
    nothing (the raster is not made)."""
    wall = np.array([[[-5.0, 0.0], [5.0, 0.0]]])
    normal = np.array([[0.0, 1.0]])  # the room lies at y > 0

    def plate(y):
        return _Caster(np.array([[x, yy, z] for x in (-0.5, 0.5) for yy in (y, y + 0.01) for z in (1.0, 2.0)]),
                       None, 1.0, 2.0)
    shading = _wall_shading([plate(0.7)], wall, normal, (), RENDER.staged)[0]
    grid, hidden = shading.grid, shading.hidden
    a = b = 0.5 / 0.7
    corner = (a / np.hypot(1, a) * np.arctan(b / np.hypot(1, a)) + b / np.hypot(1, b) * np.arctan(a / np.hypot(1, b)))
    view_factor = 4 * corner / (2 * np.pi)
    assert 0.3 < view_factor < 0.5

    def at(u, z):
        return _cell(grid, hidden, u, z)
    assert abs(at(5.0, 1.5) - view_factor) < 0.04
    assert at(5.0 + 1.0, 1.5) < at(5.0 + 0.6, 1.5) < at(5.0, 1.5)
    assert at(2.0, 1.5) == 0.0 and at(8.0, 1.5) == 0.0
    assert _wall_shading([plate(-0.71)], wall, normal, (), RENDER.staged) == [None]


def test_a_lamps_shadow_on_a_wall_is_the_plate_moved_onto_the_wall_from_the_lamp():
    """A lamp 2.4 m up, 1 m before a wall; a plate (1 m wide, 1.0-2.0 m high) 0.3 m before
    the wall between them: its shadow on the wall is the plate's corners carried along
    the lamp's rays, 1 / (1 - 0.3) = 1.43 times as large about the lamp's foot on the wall,
    from 0.40 m to 1.83 m high (worked out by hand). Standing 1.2 m out, past the lamp,
    the plate casts nothing on that wall."""
    from augment.render.lamps import Lamp

    wall = np.array([[[-5.0, 0.0], [5.0, 0.0]]])
    normal = np.array([[0.0, 1.0]])
    lamp = Lamp((0.0, 1.0, 2.4), 1.0, 1.0)

    def plate(y):
        return _Caster(np.array([[x, yy, z] for x in (-0.5, 0.5) for yy in (y, y + 0.01) for z in (1.0, 2.0)]),
                       None, 1.0, 2.0)
    shading = _wall_shading([plate(0.29)], wall, normal, (lamp,), RENDER.staged)[0]
    (shade,) = shading.lamp_shadows
    def at(u, z):
        return _cell(shading.grid, shade, 5.0 + u, z)
    inside = [(0.0, 1.1), (0.6, 0.5), (-0.6, 1.7), (0.0, 0.5), (0.0, 1.75)]
    outside = [(0.0, 1.95), (0.0, 0.3), (0.85, 1.1), (-0.85, 1.1), (0.0, 2.3)]
    assert all(at(u, z) > 0.9 for u, z in inside), [at(u, z) for u, z in inside]
    assert all(at(u, z) < 0.1 for u, z in outside), [at(u, z) for u, z in outside]
    (beyond,) = _wall_shading([plate(1.2)], wall, normal, (lamp,), RENDER.staged)[0].lamp_shadows
    assert not beyond.any()


def test_the_floor_darkens_in_a_thin_line_where_a_leg_stands_on_it():
    """A leg 4 cm square lit from the side: on its lit side (no key shadow there) the
    floor half a centimetre from its foot is darker than the same leg lifted 5 cm leaves
    it, by 7 % or more; 8 cm away the contact line adds nothing (it is thin): the gain is
    what it is without it."""
    light = Lighting((0.8, 0.8, 0.8), (0.7071, 0.0, -0.7071), 0.5, 0.05, (0.4, 0.4, 0.4), "test")

    def gain_at(z0, distances_m, settings=RENDER.staged):
        leg = np.array([[x, y, z] for x in (-0.02, 0.02) for y in (-0.02, 0.02) for z in (z0, z0 + 0.4)])
        shading = _floor_gain([_Caster(leg, None, z0, z0 + 0.4)], light, ((-0.6, -0.6), (0.6, 0.6)), settings)
        gain, grid = shading.gain, shading.grid
        cells = np.floor(grid.to_px(np.array([[-0.02 - d, 0.0] for d in distances_m]))).astype(int)
        return gain[cells[:, 1], cells[:, 0]]

    standing, lifted = gain_at(0.0, (0.005, 0.08)), gain_at(0.05, (0.005, 0.08))
    assert standing[0] < lifted[0] - 0.07 and standing[0] < 0.85
    no_contact = gain_at(0.0, (0.005, 0.08), replace(RENDER.staged, contact_strength=0.0))
    assert standing[0] < no_contact[0] - 0.05 and abs(standing[1] - no_contact[1]) < 0.002


def test_walls_in_the_mask_and_the_polygon_hide_what_stands_behind_them(renderer, room_small):
    """A floor mask cut off 3.2 m from the camera (a wall there): a box beyond it is
    hidden, a box before it shows. The same wall as a floor-polygon edge does the same."""
    image, _, calibration = room_small
    h, w = image.shape[:2]
    pose = calibration.camera_from_floor
    cam = -pose[:3, :3].T @ pose[:3, 3]
    ys, xs = np.mgrid[0:h, 0:w]
    xy = cv2.perspectiveTransform(np.stack([xs, ys], -1).reshape(-1, 1, 2).astype(np.float64),
                                  np.linalg.inv(calibration.image_from_floor)).reshape(h, w, 2)
    rays = np.linalg.inv(calibration.intrinsics.K) @ np.stack([xs.ravel(), ys.ravel(), np.ones(h * w)])
    down = ((pose[:3, :3].T @ rays)[2] < 0).reshape(h, w)
    forward = pose[2, :3][:2] / np.linalg.norm(pose[2, :3][:2])  # camera's viewing direction on the floor
    along = (xy - cam[:2]) @ forward
    wall_at = 3.2
    mask = down & (along < wall_at)
    near = cam[:2] + forward * 2.2
    far = cam[:2] + forward * 4.2
    for where, expect_visible in ((near, True), (far, False)):
        staged = _render_box(renderer, image, calibration, where, (0.5, 0.5, 0.8), floor_mask=mask)
        assert (staged.alpha > 0.5).sum() > 200 if expect_visible else (staged.alpha > 0.5).sum() < 20
    side = np.array([-forward[1], forward[0]])
    wall = cam[:2] + forward * wall_at
    poly = np.array([cam[:2] - 5 * side - 2 * forward, cam[:2] + 5 * side - 2 * forward,
                     wall + 5 * side, wall - 5 * side])
    e1, e2 = poly[1] - poly[0], poly[2] - poly[1]
    if e1[0] * e2[1] - e1[1] * e2[0] < 0:  # counter-clockwise
        poly = poly[::-1]
    staged = _render_box(renderer, image, calibration, far, (0.5, 0.5, 0.8), floor_polygon=poly)
    assert (staged.alpha > 0.5).sum() < 20
    staged = _render_box(renderer, image, calibration, near, (0.5, 0.5, 0.8), floor_polygon=poly)
    assert (staged.alpha > 0.5).sum() > 200


def test_a_box_by_a_wall_casts_its_shadow_on_the_wall_where_the_light_would_put_it(renderer, room_small):
    """A 0.5 x 0.5 x 0.8 m box 15 cm in front of a wall (a floor-polygon edge, the mask
    cut there), lit along d toward the wall and sideways: the wall darkens inside the box's
    shadow on the wall's plane (its corners moved along d onto the plane, worked out
    here), by the key light's share of the wall's light, over what the box's occlusion of
    the room's light takes (lit the other way, away from the wall: 1-20 % there, and all
    the wall loses 0.3 m and more outside the shadow and above the box). A window's pane
    in the shadow keeps its light (it shows the outside)."""
    image, _, calibration = room_small
    h, w = image.shape[:2]
    pose = calibration.camera_from_floor
    R = pose[:3, :3]
    cam = -R.T @ pose[:3, 3]
    ys, xs = np.mgrid[0:h, 0:w]
    rays = R.T @ np.linalg.inv(calibration.intrinsics.K) @ np.stack([xs.ravel(), ys.ravel(), np.ones(h * w)])
    forward = R[2, :2] / np.linalg.norm(R[2, :2])
    side = np.array([-forward[1], forward[0]])
    wall_at = 3.2
    with np.errstate(divide="ignore", invalid="ignore"):
        floor_at = np.where(rays[2] < 0, cam[2] / -rays[2], np.inf)
    along = (cam[:2] @ forward) + floor_at * (rays[:2].T @ forward)
    mask = ((rays[2] < 0) & (along - cam[:2] @ forward < wall_at)).reshape(h, w)
    wall = cam[:2] + forward * wall_at
    poly = np.array([cam[:2] - 5 * side - 2 * forward, cam[:2] + 5 * side - 2 * forward, wall + 5 * side,
                     wall - 5 * side])
    e1, e2 = poly[1] - poly[0], poly[2] - poly[1]
    if e1[0] * e2[1] - e1[1] * e2[0] < 0:
        poly = poly[::-1]
    size = (0.5, 0.5, 0.8)
    center = cam[:2] + forward * (wall_at - 0.15 - 0.25) + side * 0.3
    yaw = float(np.arctan2(forward[1], forward[0]))
    corners = _box_corners(center, size, yaw)
    d = np.append(0.6 * forward + 0.5 * side, -0.62)
    d /= np.linalg.norm(d)
    # The box's shadow on the wall's plane, in (across, up) wall coordinates.
    s = (wall_at - (corners[:, :2] - cam[:2]) @ forward) / (d[:2] @ forward)
    on_wall = corners + s[:, None] * d
    hull = cv2.convexHull(np.column_stack([on_wall[:, :2] @ side, on_wall[:, 2]]).astype(np.float32))
    # Wall points in view, on a 5 cm grid, and how far each lies inside the shadow (< 0: outside).
    u, z = np.meshgrid(np.arange(-2.0, 2.0, 0.05), np.arange(0.02, 2.0, 0.05))
    pts = np.column_stack([(wall + np.outer(u.ravel(), side)), z.ravel()])
    px = np.rint(_project(calibration, pts)).astype(int)
    seen = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
    pts, px = pts[seen], px[seen]
    inside = np.array([cv2.pointPolygonTest(hull, (float(p[:2] @ side), float(p[2])), True) for p in pts])
    results = {}
    for name, direction in (("toward", d), ("away", d * [-1, -1, 1])):
        light = Lighting((0.8, 0.78, 0.75), tuple(direction), 0.5, 0.02, (0.3, 0.25, 0.2), "test")
        item = PlacedItem("test_box", (center[0], center[1], size[2] / 2), yaw, size, "box")
        staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()},
                               lighting=light, seed=0, floor_mask=mask, floor_polygon=poly)
        clear = staged.alpha[px[:, 1], px[:, 0]] == 0
        results[name] = (staged.gain[px[:, 1], px[:, 0]], clear)
        full = staged
    gain, clear = results["toward"]
    shadowed = clear & (inside > 0.08)
    assert shadowed.sum() >= 10, "the test needs the wall's shadow in view beside the box"
    # The key light's share of the wall's light: 0.5 of the floor's, times how squarely it meets the wall.
    square = -(d[:2] @ -forward) / -d[2]
    share = 0.5 * square / (0.5 * square + 0.5 * RENDER.staged.wall_ambient_share)
    expected = (1.0 - share) ** (1 / 2.2)  # photo gamma
    # Lit the other way, the wall keeps its key light: what it loses there is the box's
    # occlusion of the room's light alone, which the shadow darkens further by its share.
    away, clear_away = results["away"]
    both = shadowed & clear_away
    assert both.sum() >= 10 and np.all(away[both] > 0.8) and np.all(away[both] < 0.99)
    # The row at the wall's foot (2 cm up) is a pixel the floor's and the wall's gains share
    # (the floor matte and the sampled walls blend over a pixel or two): looser there.
    foot = pts[:, 2] < 0.05
    assert np.allclose(gain[both & ~foot], expected * away[both & ~foot], atol=0.015)
    assert np.allclose(gain[both & foot], expected * away[both & foot], atol=0.03)
    lit = clear & clear_away & (inside < -0.3) & (pts[:, 2] > size[2] + 0.3)
    assert lit.sum() >= 10
    # There the occlusion takes its share of the light but the key's.
    hidden = 1.0 - away[lit] ** 2.2
    assert np.allclose(gain[lit], (1.0 - (1.0 - share) * hidden) ** (1 / 2.2), atol=0.003)
    assert np.all(gain[lit] > 0.95)
    # Floor the mask leaves out (a strip 20 cm wide before the box) takes the floor's shadows all the same.
    xy = cam[:2] + (rays[:2] * np.where(np.isfinite(floor_at), floor_at, 0.0)).T
    before = (xy - center) @ forward
    strip = (mask.ravel() & (before > -0.45) & (before < -0.25) & (np.abs((xy - center) @ side) < 0.25)).reshape(h, w)
    staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()}, lighting=light,
                           seed=0, floor_mask=mask & ~strip, floor_polygon=poly)
    at = strip & (staged.alpha == 0)
    assert at.sum() >= 50 and np.median(staged.gain[at]) < 0.97
    assert np.abs(staged.gain[at] - full.gain[at]).max() < 0.03
    # The far edge where the floor leaves the view rather than at a wall: what stands past
    # it is not known, and keeps its light, though the floor's raster runs on there.
    far = [bool(np.all(np.abs((np.roll(poly, -1, axis=0)[k] - cam[:2]) @ forward - wall_at) < 1e-6)
                and np.all(np.abs((poly[k] - cam[:2]) @ forward - wall_at) < 1e-6)) for k in range(4)]
    open_far = FloorPolygon(poly, tuple("far" if f else "boundary" for f in far), 0.0, "")
    light = Lighting((0.8, 0.78, 0.75), tuple(d), 0.5, 0.02, (0.3, 0.25, 0.2), "test")
    staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()}, lighting=light,
                           seed=0, floor_mask=mask, floor_polygon=open_far)
    past = staged.gain[px[:, 1], px[:, 0]]
    assert sum(far) == 1 and np.all(past[shadowed & ~foot] == 1.0) and np.all(past[shadowed & foot] > 0.9)
    # A window in the shadow's middle: its pane shows the outside and keeps its light; the
    # wall beside it is shadowed as before.
    across = (pts[:, :2] - wall) @ side
    lo, hi = np.quantile(across[shadowed], [0.2, 0.7])
    pane = np.array([[lo, 0.05], [hi, 0.05], [hi, 2.0], [lo, 2.0]])
    corners_px = _project(calibration, np.column_stack([wall + np.outer(pane[:, 0], side), pane[:, 1]]))
    staged = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()}, lighting=light,
                           seed=0, floor_mask=mask, floor_polygon=poly, windows_px=[corners_px])
    in_pane = shadowed & (across > lo + 0.05) & (across < hi - 0.05) & (pts[:, 2] > 0.1)
    beside = shadowed & ((across < lo - 0.08) | (across > hi + 0.08))
    assert in_pane.sum() >= 5 and beside.sum() >= 5
    assert np.all(staged.gain[px[in_pane, 1], px[in_pane, 0]] == 1.0)
    assert np.all(staged.gain[px[beside, 1], px[beside, 0]] <= expected + 0.02)


def test_walls_run_on_past_the_photos_edge_only():
    """A 4 x 3 m floor whose near edge is the photo's: the side walls run on past it by
    2 m; the far wall, between two walls, stays as it is; a plain outline is all walls."""
    square = np.array([[0, 0], [4, 0], [4, 3], [0, 3]], dtype=float)
    poly = FloorPolygon(square, ("image", "boundary", "boundary", "boundary"), 12.0, "")
    assert np.allclose(_walls_run_on(poly, 2.0), [[[4, -2], [4, 3]], [[4, 3], [0, 3]], [[0, 3], [0, -2]]])
    assert np.allclose(_walls_run_on(square, 2.0), wall_segments(square))


# --------------------------------------------------------------------------------------
# Furniture
# --------------------------------------------------------------------------------------

@pytest.mark.parametrize("kind", sorted(CATALOG))
def test_every_kind_fills_its_box_exactly(kind):
    """Bounds equal the item's size within 1 mm (width along the item's y, depth along x),
    at the catalog size and at another; at the catalog size the builders themselves come
    within RENDER.furniture.fit_slack_m of it (the final fit only trims)."""
    assert kind in BUILDERS
    w, d, h = CATALOG[kind].size_m
    for size, seed in (((w, d, h), 0), ((w * 1.2, d * 0.9, h * 1.1), 3)):
        f = build_furniture(kind, size, style_seed=seed)
        lo, hi = f.bounds_m
        assert np.allclose(lo, [-size[1] / 2, -size[0] / 2, 0.0], atol=1e-3), (kind, f.style, lo)
        assert np.allclose(hi, [size[1] / 2, size[0] / 2, size[2]], atol=1e-3), (kind, f.style, hi)
        if seed == 0:  # round things (tables, pots) are stretched into ovals at other sizes
            raw = f.raw_bounds_m
            target = np.array([[-size[0] / 2, -size[1] / 2, 0.0], [size[0] / 2, size[1] / 2, size[2]]])
            assert np.abs(raw - target).max() < RENDER.furniture.fit_slack_m, (kind, f.style, raw - target)
        assert all(np.all(np.isfinite(p.vertices)) and np.allclose(np.linalg.norm(p.normals, axis=1), 1, atol=1e-6)
                   for p in f.parts)


def test_cloth_without_folds_is_the_rectangle_rolled_over_its_rim_and_hanging_straight():
    """Hand-made shape: the top at z_top over the rectangle less the roll's radius; past
    its rim every point lies on the quarter circle of the roll (radius r about the rim
    r below the top) or straight below its end, hanging as far as each side says."""
    lo, hi, z_top, r, hang = (-0.5, -1.0), (0.5, 1.0), 0.6, 0.05, (0.1, 0.12, 0.02, 0.15)
    v, n, faces, uv, cavity = _draped_mesh(lo, hi, z_top, r, hang)
    assert np.allclose(v[:, :2].min(0), lo, atol=1e-9) and np.allclose(v[:, :2].max(0), hi, atol=1e-9)
    assert v[:, 2].max() == pytest.approx(z_top) and v[:, 2].min() == pytest.approx(z_top - r - max(hang))
    core_lo, core_hi = np.add(lo, r), np.subtract(hi, r)
    off = v[:, :2] - np.clip(v[:, :2], core_lo, core_hi)  # how far past the top's rim, horizontally
    h = np.linalg.norm(off, axis=1)
    roll = v[:, 2] >= z_top - r
    assert np.allclose(v[roll & (h < 1e-9), 2], z_top, atol=2e-4)  # the top (and the skirt's strip under its edge)
    on_roll = roll & (h > 1e-6)
    assert np.allclose(np.hypot(h[on_roll], v[on_roll, 2] - (z_top - r)), r, atol=1e-9)
    assert np.allclose(h[~roll], r, atol=1e-9)
    # Normals point away from the rim's axis (up on the top), and the cloth is all lit: no folds.
    axis = np.column_stack([np.clip(v[:, :2], core_lo, core_hi), np.full(len(v), z_top - r)])
    away = np.where(roll[:, None], v - axis, np.column_stack([off, np.zeros(len(v))]))
    away[h < 1e-9] = (0, 0, 1)
    assert np.min(np.einsum("ij,ij->i", n, away / np.linalg.norm(away, axis=1, keepdims=True))) > 0.9
    assert np.all(cavity == 1.0)
    tri = v[faces]
    assert np.all(np.einsum("ij,ij->i", np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), n[faces].sum(1)) >= 0)


def test_hanging_cloth_folds_in_toward_its_hem_alike_in_every_layer():
    """Below the rim height the cloth folds in, by up to the folds' depth and most at the
    hem, darkened by how deep; layers laid one over the other fold alike, so at equal
    heights the outer never comes inside the inner."""
    folds = Folds(np.random.default_rng(5), 0.04, rim_z=0.45, full_m=0.08)
    v, n, faces, uv, cavity = _draped_mesh((-0.5, -1.0), (0.5, 1.0), 0.55, 0.05, (0.15,) * 4, folds)
    side = (v[:, 0] < -0.44) & (v[:, 2] <= 0.5 + 1e-9) & (np.abs(v[:, 1]) < 0.9)  # the left side hanging at x = -0.5
    inward = v[side, 0] + 0.5
    assert inward.min() >= -1e-9 and inward.max() <= 0.04 + 1e-9
    assert np.all(np.abs(inward[v[side, 2] > 0.45 + 1e-9]) < 1e-9)  # above the rim height: no folds
    hem = side & (v[:, 2] < 0.36)
    assert np.ptp(v[hem, 0]) > 0.02  # folds at the hem, at least half as deep as they may be
    assert np.allclose(cavity[side], 1 - folds.valley_dark * inward / 0.04, atol=1e-9)
    # A second layer 8 mm further out (its top 1 cm higher): at the same height and place along
    # the side, 8 mm outside the first.
    w, *_ = _draped_mesh((-0.508, -1.0), (0.508, 1.0), 0.565, 0.05, (0.15,) * 4, folds)
    for y in (-0.3, 0.0, 0.41):
        for z in (0.45, 0.4):
            def x_at(mesh, y=y, z=z):
                pts = mesh[(mesh[:, 0] < -0.44) & (np.abs(mesh[:, 1] - y) < 0.011) & (np.abs(mesh[:, 2] - z) < 0.012)]
                return pts[np.argmin(np.abs(pts[:, 2] - z) + np.abs(pts[:, 1] - y)), 0], pts
            inner, _ = x_at(v)
            outer, _ = x_at(w)
            assert outer < inner, (y, z, outer, inner)


def test_a_cushion_bulges_by_its_crown_and_keeps_its_box():
    lo, hi, crown = np.array([0.0, 0.0, 0.0]), np.array([0.6, 0.5, 0.14]), np.array([0.01, 0.015, 0.03])
    v, n, faces, uv = _crowned_box_mesh(lo, hi, 0.03, crown)
    assert np.allclose(v.min(0), lo, atol=1e-9) and np.allclose(v.max(0), hi, atol=1e-9)
    top = v[:, 2] > hi[2] - 1e-9  # only the middle of the top reaches the box
    assert np.allclose(v[top, :2].mean(0), (lo[:2] + hi[:2]) / 2, atol=0.02)
    # The normals follow the bulge: on the flat sides' inner parts, within 3 degrees of the
    # faces around each vertex, and tilted off the box's axes there by up to the bulge's slope.
    tri = v[faces]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    acc = np.zeros_like(v)
    np.add.at(acc, faces.ravel(), np.repeat(fn, 3, axis=0))
    a = np.abs(n).argmax(axis=1)
    inner_lo, inner_hi = lo + crown + 0.03 + 0.01, hi - crown - 0.03 - 0.01
    flat = np.all([(a == k) | ((v[:, k] > inner_lo[k]) & (v[:, k] < inner_hi[k])) for k in range(3)], axis=0)
    acc = acc[flat] / np.linalg.norm(acc[flat], axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", acc, n[flat]), -1, 1))).max() < 3
    tilt = np.degrees(np.arccos(np.abs(n[flat & (a == 2), 2])))
    assert 2.0 < tilt.max() < np.degrees(np.arctan(2 * crown[2] / (hi[0] - lo[0] - 2 * crown[0] - 0.06) * 2))


def test_piping_runs_round_a_cushions_big_faces_along_the_middle_of_its_rims():
    """A 4 mm cord round each of the two big faces where their panels meet the sides: on
    the 45 degree line of the rounded rims and of the corners' spheres, so on the
    cushion's surface, closed round; it casts no shadow."""
    shop = _Shop()
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([0.6, 0.55, 0.13])  # a seat cushion, thin along z
    _cushion(shop, lo, hi, Material("fabric", (0.5, 0.5, 0.5)), round_m=0.04)
    cushion, *cords = shop.parts
    assert len(cords) == 2 and not any(c.casts_shadow for c in cords)
    piping = replace(cords[0], vertices=np.vstack([c.vertices for c in cords]),
                     normals=np.vstack([c.normals for c in cords]))
    crown = np.array([0.07, 0.07, 0.2]) * 0.13
    half = (hi - lo) / 2 - crown
    r = min(0.04, 0.999 * half.min())  # as the mesh rounds it
    centre = (lo + hi) / 2
    core = half - r
    line = piping.vertices - piping.normals * 0.002  # the cords' centre lines
    rel = line - centre
    # r from the rounded box's core (its rims' and corners' centres), 45 degrees off the big faces.
    assert np.allclose(np.linalg.norm(rel - np.clip(rel, -core, core), axis=1), r, atol=1e-9)
    assert np.allclose(np.abs(rel[:, 2]), core[2] + r / np.sqrt(2), atol=1e-9)
    # Closed round each face: every ring joins the next, the last the first.
    for cord in cords:
        rings = len(cord.vertices) // 6
        joined = np.unique(np.sort(cord.faces // 6, axis=1)[:, [0, 2]], axis=0)
        pairs = {tuple(p) for p in joined if p[0] != p[1]}
        assert all((i, (i + 1) % rings) in pairs or ((i + 1) % rings, i) in pairs for i in range(rings))
    nearest = np.min(np.linalg.norm(cushion.vertices[:, None] - line[None, ::7], axis=2), axis=0)
    assert nearest.max() < 0.012


def test_a_stuffed_or_draped_parts_outline_stands_in_for_its_shape_in_the_shadows():
    """The few points of Part.outline: their hull seen from above is the part's own within
    6 %, from the sides within 12 % (a bulge's crown is cut by chords), and the floor's
    casters take them."""
    from scipy.spatial import ConvexHull

    sofa = build_furniture("sofa", style_seed=2)
    bed = build_furniture("bed", style_seed=1)
    stand_ins = [p for f in (sofa, bed) for p in f.parts if p.outline is not None]
    assert len(stand_ins) >= 8 and all(len(p.outline) <= 68 < len(p.vertices) for p in stand_ins)
    for part in stand_ins:
        for axes, tolerance in (((0, 1), 0.06), ((1, 2), 0.12), ((0, 2), 0.12)):
            ratio = ConvexHull(part.outline[:, axes]).volume / ConvexHull(part.vertices[:, axes]).volume
            assert 1 - tolerance <= ratio <= 1 + 1e-9, (part.material.name, axes, ratio)
    item = PlacedItem("sofa", (0.0, 0.0, sofa.size_m[2] / 2), 0.0, sofa.size_m, "s")
    counts = [len(c.points) for c in _casters([(item, sofa)], RENDER.staged)]
    assert sum(n <= 68 for n in counts) >= 8  # every cushion's caster is its outline


@pytest.mark.parametrize("seed", range(4))
def test_a_beds_headboard_rises_above_its_propped_pillows(seed):
    """A double bed of the catalog (1.05 m): a part reaches the box's top at the head end,
    and everything reaching toward the foot (mattress, bedding, pillows) stays at least
    15 cm below it, the pillows propped on the 0.55 m mattress. Kept bare (0.5 m) the same
    bed has no headboard above its pillows and stays in its box."""
    W, D, H = CATALOG["bed"].size_m
    bed = build_furniture("bed", style_seed=seed)
    points = np.vstack([p.vertices for p in bed.parts])
    toward_foot = points[points[:, 0] > -D / 2 + 0.3]  # built with its front toward +x
    assert points[:, 2].max() == pytest.approx(H, abs=1e-6)
    assert 0.55 + 0.15 < toward_foot[:, 2].max() <= H - 0.15
    bare = build_furniture("bed", (W, D, CATALOG["bed"].bare_height_m), style_seed=seed)
    assert max(float(p.vertices[:, 2].max()) for p in bare.parts) <= 0.5 + 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_a_beds_duvet_is_lofty_and_hangs_over_the_mattress_to_the_frame(seed):
    """The duvet (the longest cloth) lies at least 6 cm above the mattress and hangs down
    its sides and foot to within 2 cm of the frame it sinks into (5 cm up the mattress's
    foot): no band of bare mattress below the hem, as a made bed has none. (Once it
    hung 16 cm, leaving 5 cm of mattress bare.)"""
    bed = build_furniture("bed", style_seed=seed)
    mattress = next(p for p in bed.parts if p.material.name == "mattress")
    cloths = [p for p in bed.parts if p.cavity is not None]
    duvet = max(cloths, key=lambda p: np.ptp(p.vertices[:, 0]))
    frame_top = mattress.vertices[:, 2].min() + 0.05
    v = duvet.vertices  # built with its front (the foot) toward +x, its width along y
    assert v[:, 2].max() >= mattress.vertices[:, 2].max() + 0.06
    width = np.ptp(v[:, 1])
    reach = 0.05  # the hanging cloth folds in by up to 4 cm
    for side in (v[:, 1] < v[:, 1].min() + reach, v[:, 1] > v[:, 1].max() - reach, v[:, 0] > v[:, 0].max() - reach):
        along = v[side, 0] if np.ptp(v[side, 0]) > width / 2 else v[side, 1]
        slices = np.floor((along - along.min()) / 0.05).astype(int)
        inner = np.unique(slices)[2:-2]  # clear of the rounded corners
        lowest = np.array([v[side][slices == k, 2].min() for k in inner])
        assert len(inner) >= 8 and lowest.max() <= frame_top + 0.02, (lowest.max(), frame_top)


def test_a_parts_cavity_darkens_its_light_in_the_staged_render_and_the_photographers():
    """Part.cavity multiplies the light of each vertex: staged (vertex colours, photo gamma)
    and the photographer's physically based meshes (vertex colour times base colour)."""
    box = build_furniture("side_table", (0.4, 0.4, 0.5), style_seed=0)
    shaded = replace(box, parts=tuple(replace(p, cavity=np.full(len(p.vertices), 0.5)) for p in box.parts))
    item = PlacedItem("side_table", (0.0, 0.0, 0.25), 0.0, (0.4, 0.4, 0.5), "t")
    cam = np.array([2.0, 0.0, 1.5])
    plain = _furniture_meshes([(item, box)], LIGHT, cam, np.array([-1.0, 0.0]), RENDER.staged)[0]
    dark = _furniture_meshes([(item, shaded)], LIGHT, cam, np.array([-1.0, 0.0]), RENDER.staged)[0]
    a = np.concatenate([m.primitives[0].color_0[:, :3] for m in plain])
    b = np.concatenate([m.primitives[0].color_0[:, :3] for m in dark])
    lit = a > 0.05
    assert np.allclose(b[lit] / a[lit], 0.5 ** (1 / 2.2), rtol=1e-4)
    synth = furniture_meshes([(shaded, np.eye(4))])
    assert all(np.allclose(m.primitives[0].color_0[:, :3], 0.5) for m in synth)


def test_styles_vary_and_seeds_repeat():
    a = build_furniture("sofa", style_seed=1)
    b = build_furniture("sofa", style_seed=1)
    assert a.style == b.style and all(np.array_equal(p.vertices, q.vertices) for p, q in zip(a.parts, b.parts))
    styles = {build_furniture("sofa", style_seed=s).style for s in range(12)}
    colours = {build_furniture("sofa", style_seed=s).parts[0].material.color_rgb for s in range(12)}
    assert len(styles) >= 2 and len(colours) >= 6


def test_a_tables_chairs_match_and_plants_vary():
    """The four chairs of a dining set (ids dining_chair_1 to _4, kind chair) are one design,
    as a stager buys them, in every style and suggestion seed; two plants are two."""
    def design(kind, name, seed, style):
        f = furniture_for(PlacedItem(kind, (0.0, 0.0, 0.5), 0.0, CATALOG[kind].size_m, name), seed, style=style)
        return f.style, [(p.vertices.round(6).tobytes(), p.material.color_rgb) for p in f.parts]

    for seed in range(3):
        for style in ("scandinavian", "industrial", None):
            chairs = {str(design("chair", f"dining_chair_{k}", seed, style)) for k in range(1, 5)}
            assert len(chairs) == 1
    assert design("plant", "plant_1", 0, None) != design("plant", "plant_2", 0, None)


def test_placed_item_mesh_in_the_floor_frame():
    """Front toward the yaw: a yaw of 90 degrees puts the depth along y."""
    item = PlacedItem("dresser", (1.0, 2.0, 0.4), np.pi / 2, (1.0, 0.5, 0.8), "d")
    lo, hi = furniture_for(item).to_trimesh(world_from_item(item)).bounds
    assert np.allclose(lo, [0.5, 1.75, 0.0], atol=1e-3) and np.allclose(hi, [1.5, 2.25, 0.8], atol=1e-3)


def test_user_model_is_scaled_to_the_item(tmp_path):
    """A GLB (glTF: y up, front toward +z) stands in for a kind, stretched onto its box."""
    mesh = trimesh.creation.box((2.0, 1.0, 0.5))  # glTF: 2 wide (x), 1 tall (y), 0.5 deep (z)
    mesh.visual.face_colors = [200, 30, 30, 255]
    path = tmp_path / "thing.glb"
    mesh.export(path)
    f = furniture_from_asset("sofa", (2.1, 0.95, 0.85), load_asset(path))
    lo, hi = f.bounds_m
    assert np.allclose(lo, [-0.475, -1.05, 0], atol=1e-6) and np.allclose(hi, [0.475, 1.05, 0.85], atol=1e-6)
    assert f.parts[0].material.color_rgb[0] > 0.5 > f.parts[0].material.color_rgb[1]
    # A flat model does for a rug (1 cm tall), not for a sofa.
    sheet = tmp_path / "sheet.obj"
    sheet.write_text("v 0 0 0\nv 2 0 0\nv 0 0 1.4\nf 1 2 3\n")
    lo, hi = furniture_from_asset("rug", (2.0, 1.4, 0.01), load_asset(sheet)).bounds_m
    assert np.allclose(hi - lo, [1.4, 2.0, 0.0], atol=1e-6)
    with pytest.raises(ValueError, match="flat"):
        furniture_from_asset("sofa", (2.1, 0.95, 0.85), load_asset(sheet))


def test_layout_dict_gives_placed_items():
    layout = {"items": [{"id": "s", "kind": "sofa", "position_m": [1, 2, 0.425], "yaw_rad": 0.5,
                         "size_m": [2.1, 0.95, 0.85], "group": None}]}
    (item,) = placed_items(layout)
    assert item.kind == "sofa" and item.elevation_m == pytest.approx(0.0) and item.yaw_rad == 0.5


# --------------------------------------------------------------------------------------
# Hygiene: inputs, reuse, outputs
# --------------------------------------------------------------------------------------

def test_inputs_untouched_renders_repeatable_and_layer_recomposes(renderer, room_small, tmp_path):
    image, mask, calibration = room_small
    image_before, mask_before = image.copy(), mask.copy()
    items = [PlacedItem("sofa", (0.2, 0.8, 0.425), -1.3, (2.1, 0.95, 0.85), "sofa"),
             PlacedItem("rug", (0.0, 0.0, 0.005), 0.3, (2.0, 1.4, 0.01), "rug"),
             PlacedItem("plant", (-0.9, 0.3, 0.5), 0.0, (0.4, 0.4, 1.0), "plant")]
    first = render_staged(image, calibration, items, renderer, floor_mask=mask, layer=True)
    assert np.array_equal(image, image_before) and np.array_equal(mask, mask_before)
    # One renderer, several renders: other items in between, then the same render again.
    render_staged(image, calibration, items[:1], renderer, lighting=LIGHT)
    again = render_staged(image, calibration, items, renderer, floor_mask=mask, layer=True)
    assert np.array_equal(first.image, again.image)
    assert first.image.shape == image.shape and not np.array_equal(first.image, image)
    # The RGBA layer over the photo gives the staged photo.
    a = first.layer[..., 3:].astype(float) / 255
    over = first.layer[..., :3] * a + image * (1 - a)
    assert np.abs(over - first.image).max() <= 3
    path = write_jpeg(tmp_path / "staged.jpg", first.image)
    back = cv2.imread(str(path))
    assert back.shape == image.shape and not list(tmp_path.glob(".*.tmp"))
    assert np.abs(back[..., ::-1].astype(int) - first.image).mean() < 3


def test_exposure_and_colour_follow_the_photo():
    """The board's white squares set the exposure and white balance: a photo half as bright
    (in linear light) gives half the irradiance; a warm cast, a warm light."""
    image, mask, calibration = _truth_calibration("room_2", 0.5)
    base = np.array(estimate_lighting(image, calibration, mask).irradiance_rgb)
    linear = (image / 255.0) ** 2.2
    for gains in ((0.5, 0.5, 0.5), (1.0, 0.8, 0.6)):
        shifted = np.clip(255 * (linear * gains) ** (1 / 2.2) + 0.5, 0, 255).astype(np.uint8)
        got = np.array(estimate_lighting(shifted, calibration, mask).irradiance_rgb)
        assert np.allclose(got / base, gains, rtol=0.08), (gains, got / base)


def test_key_light_comes_from_the_window():
    """room_1 shows a window and no sun on its floor: the key light travels from the window
    into the room, high and soft (its direction is a guess: no shadow falls farther than
    what casts it is tall)."""
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    lighting = estimate_lighting(image, calibration, mask)
    assert lighting.source == "window" and lighting.way == "line_to_window"
    truth = json.loads((PHOTOS / "room_1.json").read_text())
    board_from_world = np.linalg.inv(np.array(truth["board"]["world_from_board"]))
    window = np.mean(truth["room"]["windows"][0]["segment_m"], axis=0)
    window = (board_from_world @ [window[0], window[1], 0.0, 1.0])[:2]
    pose = calibration.camera_from_floor
    cam = (-pose[:3, :3].T @ pose[:3, 3])[:2]
    d = np.array(lighting.direction)
    assert d[2] < 0 and float(d[:2] @ (window - cam)) < 0
    assert -d[2] > np.linalg.norm(d[:2]) and lighting.softness_rad >= 0.3


def test_a_window_is_a_compact_bright_quadrilateral_with_sharp_edges():
    """Grey walls (120) with a line of lit trim 3 px wide along the ceiling, brighter than
    anything: no window. A lamp's round glow on the wall (Gaussian, 250 at its middle,
    sigma 25 px), brighter than the rest: no window either, its light fades out past
    any outline. A 40 x 30 px pane (230) beside them: that is the window, at its centre."""
    settings = RENDER.staged
    lum = np.full((240, 320), 120.0)
    cv2.line(lum, (0, 60), (319, 10), 255.0, 3)
    candidates = np.ones((240, 320), bool)
    assert _window(lum, candidates, settings) is None
    yy, xx = np.mgrid[:240, :320]
    lum = np.maximum(lum, 120.0 + 130.0 * np.exp(-((xx - 80.0) ** 2 + (yy - 90.0) ** 2) / (2 * 25.0 ** 2)))
    assert _window(lum, candidates, settings) is None
    lum[100:130, 200:240] = 230.0
    center, blob = _window(lum, candidates, settings)
    assert tuple(center) == pytest.approx((219.5, 114.5), abs=0.01)
    assert blob.sum() == 40 * 30 and blob[100:130, 200:240].all()


def test_a_blown_out_window_on_bright_walls_is_a_window():
    """Bright walls (200) leave a window no room to be 1.35 x brighter: a 40 x 30 px pane
    blown out to 252 in a cream frame (220, 3 px) is still the window; a lamp's glow on
    the same walls (Gaussian to 252) is not."""
    settings = RENDER.staged
    lum = np.full((240, 320), 200.0)
    candidates = np.ones((240, 320), bool)
    yy, xx = np.mgrid[:240, :320]
    glow = np.maximum(lum, 200.0 + 52.0 * np.exp(-((xx - 80.0) ** 2 + (yy - 90.0) ** 2) / (2 * 25.0 ** 2)))
    assert _window(glow, candidates, settings) is None
    lum[97:133, 197:243] = 220.0
    lum[100:130, 200:240] = 252.0
    found = _window(lum, candidates, settings)
    assert found is not None and tuple(found[0]) == pytest.approx((219.5, 114.5), abs=0.01)


def test_a_bright_blob_reaching_down_the_wall_to_the_floor_is_no_window():
    """A level camera 1.4 m up looking along +y at a wall 4 m away (f = 250 px, 320 x 240):
    a pixel's row y meets the wall 1.4 - 4 (y - 120) / 250 m up (row 151 at 0.9 m, row
    207.5 at the floor). A bright pane from 0.9 to 2.0 m up is the window; the same
    brightness from the floor to 1.2 m up is sun on the wall (or a lit door), not one."""
    K = np.array([[250.0, 0, 160], [0, 250.0, 120], [0, 0, 1]])
    pose = np.eye(4)
    pose[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    pose[:3, 3] = [0.0, 1.4, 0.0]
    walls = np.array([[[-5.0, 4.0], [5.0, 4.0]]])
    assert _on_wall_m(160.0, 151.25, K, pose, walls)[0] == pytest.approx([0.0, 4.0, 0.9])
    assert _on_wall_m(10.0, 207.5, K, pose, walls)[0][2] == pytest.approx(0.0, abs=1e-9)
    assert np.isnan(_on_wall_m(160.0, 100.0, K, pose, walls[:, ::-1] - [0.0, 8.0])[0]).all()  # wall behind
    settings = RENDER.staged
    candidates = np.ones((240, 320), bool)
    height = lambda x, y: _on_wall_m(x, y, K, pose, walls)[0][2]  # noqa: E731
    lum = np.full((240, 320), 120.0)
    lum[83:151, 200:240] = 230.0  # 2.0 to 0.9 m up
    assert tuple(_window(lum, candidates, settings, height)[0]) == pytest.approx((219.5, 116.5), abs=0.01)
    lum = np.full((240, 320), 120.0)
    lum[158:208, 200:240] = 230.0  # 0.8 m to the floor
    assert _window(lum, candidates, settings) is not None
    assert _window(lum, candidates, settings, height) is None


def _window_before_camera():
    """A level camera 1.4 m up looking along +y at a wall 4 m away (f = 250 px, 320 x 240)
    with a window 1 m wide from 0.92 to 1.99 m up (rows 83-150, columns 129-190); and a
    top-down view of the floor in front of the wall (2 cm cells, x -3 to 3 m, y 0 to
    3.9 m seen): the window on its wall, the view's cells' (x, y) and what it sees."""
    K = np.array([[250.0, 0, 160], [0, 250.0, 120], [0, 0, 1]])
    pose = np.eye(4)
    pose[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    pose[:3, 3] = [0.0, 1.4, 0.0]
    blob = np.zeros((240, 320), bool)
    blob[83:151, 129:191] = True
    window = _window_on_wall(blob, np.array([[-5.0, 4.0], [5.0, 4.0]]), 1.0, K, pose, (0.0, 0.0))
    ys, xs = np.mgrid[0:201, 0:301] * 0.02 + np.array([0.0, -3.0])[:, None, None]
    return window, xs, ys, ys <= 3.9


def _sun_on(lit, seen, axis_xy=(0.0, 1.0)):
    return SunOnFloor((axis_xy,), True, 2.0, 3.0, (0.0, 2.0), 0, float(lit.mean()), (-3.0, 0.0), 0.02, lit, seen)


def test_the_window_in_view_casts_the_patches_it_lands_on():
    """The window of :func:`_window_before_camera` lies on its wall where drawn. Sun 40 deg
    up through it, travelling -y, lands 1.63-2.90 m from the camera: with a patch there, read
    along +y, the window says the light travels the other way (-1). A patch running from
    that wall's foot (the sun climbing it: the window's sill would shade the floor before
    it) or one off to the side: the window does not cast it (0)."""
    window, xs, ys, seen = _window_before_camera()
    outline, along, inward = window
    assert outline.min(axis=0) == pytest.approx([-0.496, 4.0, 0.92], abs=0.01)
    assert outline.max(axis=0) == pytest.approx([0.48, 4.0, 1.992], abs=0.01)
    assert abs(along[0]) == pytest.approx(1.0) and inward == pytest.approx([0.0, -1.0])

    def casts(x_m, y_m):
        lit = seen & (xs >= x_m[0]) & (xs <= x_m[1]) & (ys >= y_m[0]) & (ys <= y_m[1])
        return _window_casts(window, _sun_on(lit, seen), RENDER.staged)

    assert casts((-0.5, 0.48), (1.63, 2.90)) == -1.0
    assert casts((-0.5, 0.48), (2.0, 3.9)) == 0.0
    assert casts((1.5, 2.5), (1.63, 2.90)) == 0.0


def test_the_window_in_view_tells_which_edge_family_is_the_suns():
    """The patch the window of :func:`_window_before_camera` casts with the sun 40 deg up
    straight into the room (x -0.5 to 0.48 m, y 1.63 to 2.90 m), read with two edge
    families neither along a wall, the strongest across the sun (along x): the window
    casts it along the second, which becomes the sun's, the light travelling -y. Where the
    second runs along a wall it is the window's sill, not the sun's: nothing swapped."""
    window, xs, ys, seen = _window_before_camera()
    lit = seen & (xs >= -0.5) & (xs <= 0.48) & (ys >= 1.63) & (ys <= 2.90)
    sun = replace(_sun_on(lit, seen), axes_xy=((1.0, 0.0), (0.0, 1.0)), along_wall=False)
    assert _window_casts(window, sun, RENDER.staged) == 0.0
    found, cast = _window_casts_either(window, sun, RENDER.staged)
    assert found.axes_xy == ((0.0, 1.0), (1.0, 0.0)) and cast == -1.0
    walled = replace(sun, along_wall=True)
    assert _window_casts_either(window, walled, RENDER.staged) == (walled, 0.0)


def test_the_sun_through_the_window_in_view_is_where_its_light_lands():
    """Bright floor with no edges read, where the window of :func:`_window_before_camera`
    lands with the sun 40 deg up travelling 21 deg off straight into the room: that is the
    sun's way and height (within the search's 3 and 2 deg steps). A small bright square
    off to the side, or bright floor from the wall's foot on (the sun climbing that wall),
    is no window's patch: None."""
    window, xs, ys, seen = _window_before_camera()
    outline = window[0]
    way = np.array([math.sin(math.radians(21.0)), -math.cos(math.radians(21.0))])
    corners = outline[:, :2] + way * outline[:, 2:] / math.tan(math.radians(40.0))
    patch = np.zeros(seen.shape, np.uint8)
    cv2.fillConvexPoly(patch, np.round((corners - [-3.0, 0.0]) / 0.02).astype(np.int32), 1)
    direction = _window_sun(window, _sun_on(patch > 0, seen), RENDER.staged)
    assert direction is not None
    assert math.degrees(math.atan2(direction[0], -direction[1])) == pytest.approx(21.0, abs=3.0)
    assert math.degrees(math.asin(-direction[2])) == pytest.approx(40.0, abs=2.0)
    square = seen & (np.abs(xs - 2.5) <= 0.1) & (np.abs(ys - 1.0) <= 0.1)
    assert _window_sun(window, _sun_on(square, seen), RENDER.staged) is None
    from_wall = seen & (xs >= -0.5) & (xs <= 0.48) & (ys >= 1.6)
    assert _window_sun(window, _sun_on(from_wall, seen), RENDER.staged) is None


def _level_camera_before_a_wall(cy_px=120.0):
    """A level camera 1.4 m up looking along +y at a plain grey wall 4 m away (f = 250 px,
    320 x 240, the principal point's row ``cy_px``): K, camera_from_floor, the wall, the
    photo's luminance and the walls' median light."""
    K = np.array([[250.0, 0, 160], [0, 250.0, cy_px], [0, 0, 1]])
    pose = np.eye(4)
    pose[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    pose[:3, 3] = [0.0, 1.4, 0.0]
    return K, pose, np.array([[[-5.0, 4.0], [5.0, 4.0]]]), np.full((240, 320), 120.0), 120.0


def test_a_plain_wall_in_view_where_the_suns_window_would_be():
    """The wall of :func:`_level_camera_before_a_wall`: patches at (0, 2) lit from +y would
    need a window on that wall at x = 0, which the photo shows as plain grey wall; once a
    bright pane is painted there, not; from -y there is no wall to tell."""
    K, pose, walls, lum, walls_lum = _level_camera_before_a_wall()
    center = np.array([0.0, 2.0])
    assert _plain_wall_upstream(center, np.array([0.0, 1.0]), walls, K, None, pose, lum, walls_lum, 1.0)
    assert not _plain_wall_upstream(center, np.array([0.0, -1.0]), walls, K, None, pose, lum, walls_lum, 1.0)
    lum[70:160, 140:180] = 230.0
    assert not _plain_wall_upstream(center, np.array([0.0, 1.0]), walls, K, None, pose, lum, walls_lum, 1.0)


def test_a_plain_wall_tells_where_the_photo_cuts_it_off_above_window_height():
    """The wall of :func:`_level_camera_before_a_wall` with the principal point on the top
    row: only what is below the camera's 1.4 m shows (1.0 m up at row 25), so the wall from
    1.4 to 2 m is cut off. Every window covers 1.0-1.4 m, so the plain wall there still
    rules the window out; a pane over that band keeps it."""
    K, pose, walls, lum, walls_lum = _level_camera_before_a_wall(cy_px=0.0)
    center, up = np.array([0.0, 2.0]), np.array([0.0, 1.0])
    assert _plain_wall_upstream(center, up, walls, K, None, pose, lum, walls_lum, 1.0)
    assert not _plain_wall_upstream(center, up, walls, K, None, pose, lum, walls_lum, 1.0, band_m=(0.9, 2.0))
    lum[0:40, 140:180] = 230.0
    assert not _plain_wall_upstream(center, up, walls, K, None, pose, lum, walls_lum, 1.0)


def test_a_sun_whose_window_is_out_of_view_comes_from_the_nearer_photo_edge():
    """A floor in view 4 m wide, 3 m deep: its far edge a wall, its sides and near edge the
    photo's edges. Patches at x = 1 with their edges along x: looking back along -x the
    floor leaves the view 1 m away, along +x 3 m away, and neither way meets a wall, so
    the window is past the left edge and the light travels along +x. Patches at x = 3.5
    are lit from the right (-1). Along y the far wall is met: the walls tell, not this."""
    poly = FloorPolygon(np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]]),
                        ("image", "image", "boundary", "image"), 12.0, "")
    walls = wall_segments(poly)
    assert _nearer_edge_upstream(np.array([1.0, 1.5]), np.array([1.0, 0.0]), walls, poly) == 1.0
    assert _nearer_edge_upstream(np.array([1.0, 1.5]), np.array([-1.0, 0.0]), walls, poly) == -1.0
    assert _nearer_edge_upstream(np.array([3.5, 1.5]), np.array([1.0, 0.0]), walls, poly) == -1.0
    assert _nearer_edge_upstream(np.array([2.0, 1.5]), np.array([1.0, 0.0]), walls, poly) == 0.0  # halfway: no telling
    assert _nearer_edge_upstream(np.array([1.0, 1.5]), np.array([0.0, 1.0]), walls, poly) == 0.0


@pytest.mark.parametrize("gloss, brighter", [(0.002, 1.6), (0.3, 1.0)])
def test_furniture_takes_the_light_of_the_floor_it_stands_on(renderer, gloss, brighter):
    """The floor on one side of the board made 1.6 times as bright (linear): a table
    standing there is lit 1.6 times as bright, one on the other side as before (the matte
    synthetic samples read a gloss of 0-0.002). On a floor glossy enough to mirror the
    furniture the brighter side may be a window's reflection, no light: both as before."""
    image, mask, calibration = _truth_calibration("room_2", 0.5)
    h, w = mask.shape
    ys, xs = np.mgrid[0:h, 0:w]
    pts = np.stack([xs, ys, np.ones_like(xs)], axis=-1).reshape(-1, 3) @ np.linalg.inv(calibration.image_from_floor).T
    floor_x = (pts[:, 0] / pts[:, 2]).reshape(h, w)
    floor_y = (pts[:, 1] / pts[:, 2]).reshape(h, w)
    bright = mask & (floor_x > 0)
    linear = (image / 255.0) ** 2.2
    linear[bright] *= 1.6
    lit = np.clip(255 * np.minimum(linear, 1.0) ** (1 / 2.2) + 0.5, 0, 255).astype(np.uint8)
    means = {}
    for side, sel in (("bright", mask & (floor_x > 0.8)), ("dim", mask & (floor_x < -0.8))):
        x, y = float(np.median(floor_x[sel])), float(np.median(floor_y[sel]))
        item = [PlacedItem("side_table", (x, y, 0.275), 0.0, (0.45, 0.45, 0.55), "t")]
        for photo in ("as taken", "lit"):
            done = render_staged(image if photo == "as taken" else lit, calibration, item, renderer, floor_mask=mask,
                                 lighting=replace(LIGHT, floor_gloss=gloss), look=CLEAN, self_shadows=False)
            solid = done.alpha > 0.99
            assert solid.sum() > 200
            means[side, photo] = float(((done.image[solid] / 255.0) ** 2.2).mean())
    assert means["bright", "lit"] / means["bright", "as taken"] == pytest.approx(brighter, rel=0.1)
    assert means["dim", "lit"] / means["dim", "as taken"] == pytest.approx(1.0, abs=0.05)


def test_bad_inputs_are_named(renderer, room_small):
    image, mask, calibration = room_small
    with pytest.raises(ValueError, match="uint8"):
        render_staged(image.astype(np.float32), calibration, [], renderer)
    with pytest.raises(ValueError, match="floor_mask"):
        render_staged(image, calibration, [], renderer, floor_mask=mask[:10], lighting=LIGHT)
    with pytest.raises(ValueError, match="calibration is for"):
        render_staged(image[:100], calibration, [], renderer, lighting=LIGHT)
    with pytest.raises(ValueError, match="size_m"):
        build_furniture("sofa", (2.0, -1.0, 0.8))
    empty = render_staged(image, calibration, [], renderer, lighting=LIGHT)
    assert np.array_equal(empty.image, image)


def test_a_style_keeps_every_piece_in_its_palette():
    """Each style's woods, paints, fabrics, leathers, bedding and pots are the only ones its
    pieces show (metals fall back where a piece takes only some); the styles differ."""
    from augment.render.furniture import BEDDING, FABRICS, LEATHERS, PAINTS, POTS, RUG_WOOLS, WOODS
    from augment.render.styles import STYLES

    palettes = {"woods": WOODS, "paints": PAINTS, "fabrics": FABRICS, "leathers": LEATHERS, "bedding": BEDDING,
                "pots": POTS, "rugs": RUG_WOOLS}
    seen = {}
    for name, style in STYLES.items():
        used = set()
        for kind in ("sofa", "armchair", "coffee_table", "tv_stand", "bed", "nightstand", "bookcase", "plant",
                     "dining_table", "chair", "desk", "wardrobe", "rug"):
            for seed in range(4):
                built = build_furniture(kind, rng=np.random.default_rng(seed), style=name)
                used |= {p.material.name.removesuffix(" inside") for p in built.parts}
                assert kind != "rug" or built.style in style.rug_patterns, (name, built.style)
        for palette, options in palettes.items():
            allowed = set(getattr(style, palette))
            assert not (used & {o[0] for o in options}) - allowed, (name, palette, used - allowed)
        seen[name] = frozenset(used)
    assert len(set(seen.values())) == len(STYLES)
    with pytest.raises(ValueError, match="choose one of scandinavian"):
        build_furniture("sofa", style="baroque")


def test_a_bushs_leaves_are_one_double_sided_part_of_known_shape():
    """Two leaves drawn at once (4 steps each): one part casting no shadow, both sides.
    The first, 1 m along +x from the origin and 0.2 m wide, flat: its midrib droops to
    (1, 0, -0.25) at the tip, its edges are 0.1 m off the midrib halfway (0.5, +-0.1,
    -0.0625), it faces up and down at the stalk, a side each; the second lies wholly
    around its own base. A bush is hundreds of such leaves over a dozen shaded clumps
    that cast its shadows."""
    from augment.render.furniture import _mat, _Shop

    shop = _Shop()
    mat = _mat(np.random.default_rng(0), "leaves", (60, 100, 50), 0.6)
    part = shop.leaves([[0, 0, 0], [5, 5, 1]], [[1, 0, 0], [0, 0, 1]], [1.0, 0.3], [0.2, 0.1], mat, [0.0, 0.3],
                       [0.0, 0.0])
    assert shop.parts == [part] and not part.casts_shadow and not part.convex
    half = len(part.vertices) // 2
    first = part.vertices[:half][:15]  # the first leaf's midrib (5), left edge (5), right edge (5)
    np.testing.assert_allclose(first[4], (1.0, 0.0, -0.25), atol=1e-12)
    np.testing.assert_allclose(sorted(first[[7, 12], 1]), (-0.1, 0.1), atol=1e-12)
    np.testing.assert_allclose(first[[7, 12], 0], 0.5)
    np.testing.assert_allclose(first[[7, 12], 2], -0.0625)
    np.testing.assert_allclose(part.vertices[half:], part.vertices[:half])
    np.testing.assert_allclose(part.normals[half:], -part.normals[:half])
    assert abs(part.normals[0, 2]) > 0.99  # the stalk: the droop is slight there
    assert len(part.faces) == 2 * 2 * 4 * 4  # two sides, two leaves, four triangles a step
    second = part.vertices[15:30]
    assert np.linalg.norm(second - (5, 5, 1), axis=1).max() <= 0.3 + 1e-9
    bush = next(f for f in (build_furniture("plant", (0.45, 0.45, 1.1), style_seed=s) for s in range(40))
                if f.style == "bush")
    leaves = sum(len(p.faces) for p in bush.parts if not p.casts_shadow) // (2 * 4 * 4)
    clumps = [p for p in bush.parts if p.casts_shadow and p.material.name == "leaves"]
    assert leaves >= 200 and len(clumps) >= 12


def test_light_past_the_knee_rolls_off_toward_white_keeping_its_hue():
    light = np.array([[0.5, 0.4, 0.3], [1.0, 0.5, 0.25], [1.6, 0.8, 0.4], [2.4, 1.2, 0.6]])
    out = light * _roll_off(light, 0.8)[:, None]
    np.testing.assert_allclose(out[0], light[0])  # below the knee: as it was
    assert out[1, 0] == pytest.approx(0.8 + 0.2 * (1.0 - np.exp(-1.0)))  # 0.2 past it: 1 - 1/e of the rest
    np.testing.assert_allclose(out[1:, 1] / out[1:, 0], 0.5)
    np.testing.assert_allclose(out[1:, 2] / out[1:, 0], 0.25)
    assert np.all(np.diff(out[:, 0]) > 0) and out[-1, 0] < 1.0


def test_an_overexposed_table_keeps_its_shading_and_hue(renderer):
    """A dark wooden side table (seed 26: square, dark walnut) in light 20 times too bright
    for it: without a shoulder every pixel would clip to flat white; with it, none clips,
    top and sides still differ, and the wood stays redder than it is blue."""
    image, mask, calibration = _truth_calibration("room_2", 0.5)
    xy = calibration.floor_from_pixels(np.argwhere(mask)[:, ::-1].astype(np.float64))
    x, y = np.median(xy[xy[:, 0] > 0.8], axis=0)
    item = [PlacedItem("side_table", (x, y, 0.275), 0.0, (0.45, 0.45, 0.55), "t")]
    levels = {}
    for gain in (1.0, 20.0):
        light = replace(LIGHT, irradiance_rgb=tuple(gain * np.asarray(LIGHT.irradiance_rgb)))
        done = render_staged(image, calibration, item, renderer, floor_mask=mask, lighting=light, look=CLEAN,
                             self_shadows=False, seed=26)
        levels[gain] = done.image[done.alpha > 0.99].astype(float)
    bright = levels[20.0]
    assert len(bright) > 2000 and bright.max() < 255
    assert np.percentile(bright[:, 0], 90) - np.percentile(bright[:, 0], 10) > 10
    assert np.median(bright[:, 0]) > np.median(levels[1.0][:, 0]) + 80
    assert np.median(bright[:, 0] - bright[:, 2]) > 40


def _carton_edge(shape=(240, 320), slope=0.6):
    """A grey floor (128) below the line y = 40 + slope x and a yellow carton above it,
    anti-aliased over a pixel; and the floor as a segmentation at a quarter of the size,
    enlarged (linear, cut at one half), gives it: in steps."""
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]].astype(np.float64) + 0.5
    floor = np.clip(ys - (40.0 + slope * xs) + 0.5, 0.0, 1.0)
    photo = (floor[..., None] * np.array([128.0, 128.0, 128.0]) + (1 - floor[..., None]) * np.array([200.0, 180.0, 60.0]))
    small = cv2.resize(floor, (shape[1] // 4, shape[0] // 4), interpolation=cv2.INTER_AREA) > 0.5
    coarse = cv2.resize(small.astype(np.float32), shape[::-1], interpolation=cv2.INTER_LINEAR) > 0.5
    return np.rint(photo).astype(np.uint8), floor, coarse


def test_the_floor_matte_follows_the_photos_edge_not_the_masks_steps():
    """The mask of :func:`_carton_edge` strays from the carton's edge in steps, 2 px and
    more; the matte (radius 8 px: two of the segmentation's pixels, as the renderer's
    settings make it) lies on the edge, its half-way line within 0.25 px of the true one
    in every column away from the borders; the inputs untouched. Worked out at half the
    size and enlarged, within 0.5 px."""
    photo, floor, coarse = _carton_edge()
    before = (photo.copy(), coarse.copy())
    matte = floor_matte(photo, coarse, 8.0, 50.0)
    assert np.array_equal(photo, before[0]) and np.array_equal(coarse, before[1])
    assert matte.dtype == np.uint8 and matte.shape == coarse.shape and matte.min() == 0 and matte.max() == 255

    def edge_rows(share):  # per column, where the share of floor (0-1, or 0-255) crosses one half, going down
        rows = np.arange(share.shape[0], dtype=np.float64)
        share = share / 255.0 if share.dtype == np.uint8 else share
        return np.array([np.interp(0.5, share[:, c], rows) for c in range(share.shape[1])])

    true = edge_rows(floor)
    inner = slice(16, 300)
    assert np.abs(edge_rows(coarse.astype(np.float32)) - true)[inner].max() >= 2.0
    assert np.abs(edge_rows(matte) - true)[inner].max() <= 0.25
    half = floor_matte(photo, coarse, 8.0, 50.0, scale=0.5)
    assert half.shape == coarse.shape
    assert np.abs(edge_rows(half) - true)[inner].max() <= 0.5


def test_the_composite_mixes_the_floors_shadow_and_the_walls_by_the_share_of_floor():
    """One pixel of photo 200 under no furniture: the floor's gain 0.5, the wall's 0.8,
    its ray meeting the floor first for a quarter of it; 40 % of it floor (102 of 255).
    Its gain is 0.4 x 0.5 + 0.6 x (0.25 x 0.5 + 0.75 x 0.8) = 0.635, the photo
    200 x 0.635 = 127; with no floor mask, the floor's 0.5."""
    def one(v, dtype=np.float32):
        return np.full((1, 1), v, dtype)

    photo = np.full((1, 1, 3), 200, np.uint8)
    for use_floor, gain in ((True, 0.635), (False, 0.5)):
        out, alpha, g = np.zeros((1, 1, 3), np.uint8), one(0.0), one(0.0)
        _composite(photo, np.zeros((1, 1, 4), np.uint8), one(0, np.uint8), one(0.5), one(0.8), one(0.25),
                   one(102, np.uint8), use_floor, out, alpha, g)
        assert g[0, 0] == pytest.approx(gain, abs=1e-6)
        assert out[0, 0].tolist() == [round(200 * gain)] * 3


def test_a_glossy_floor_mirrors_the_furniture_below_its_base(renderer, room_small):
    """A 0.6 x 0.4 x 0.5 m box on room_1's floor, the floor mirroring 0.3 of the light:
    the staged photo changes only on floor the box leaves uncovered, within its mirror
    image (its corners at -z seen by the camera, and its blur around them), most of all
    right below its base, and changes there toward the box's colour (the box itself
    changes too: a floor that glossy lends it no light map). A floor too matte (below
    ``min_reflection_gloss``) mirrors nothing."""
    image, mask, calibration = room_small
    item = PlacedItem("test_box", (0.2, 0.3, 0.25), 0.4, (0.6, 0.4, 0.5), "box")

    def staged(gloss):
        return render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()},
                             lighting=replace(LIGHT, floor_gloss=gloss), floor_mask=mask, seed=0, look=CLEAN)

    plain, glossy = staged(0.0), staged(0.3)
    assert np.array_equal(staged(0.5 * RENDER.staged.min_reflection_gloss).image, plain.image)
    np.testing.assert_array_equal(glossy.alpha, plain.alpha)
    change = np.abs(glossy.image.astype(np.float32) - plain.image).max(axis=2)
    change[plain.alpha > 0.01] = 0.0  # the box, its edge too
    changed = change > 2
    assert changed.sum() > 300
    assert not (changed & ~mask).any()
    corners = _box_corners((0.2, 0.3), (0.6, 0.4, 0.5), 0.4) * [1, 1, -1]
    # The reflection's blur: 1.5 cm at the box's distance, 3 sigma of it around the mirror image.
    blur_px = RENDER.staged.reflection_blur_m * calibration.intrinsics.K[0, 0] / np.linalg.norm(
        calibration.camera_from_floor[:3, :3] @ [0.2, 0.3, 0.0] + calibration.camera_from_floor[:3, 3])
    grow = 2 * math.ceil(3 * blur_px) + 3
    mirror = cv2.dilate(_hull_mask(change.shape, _project(calibration, corners)).astype(np.uint8),
                        np.ones((grow, grow), np.uint8)) > 0
    assert not (changed & ~mirror).any()
    # Strongest just below the base (what stands on the floor mirrors sharpest), toward the box.
    base = _hull_mask(change.shape, _project(calibration, corners[:4]))
    low = _hull_mask(change.shape, _project(calibration, corners * [1, 1, 0.3]))
    assert change[low & ~base & (plain.alpha < 0.01)].mean() > 2 * change[mirror & ~low].mean()
    box = plain.image[plain.alpha > 0.99].astype(np.float32).mean(axis=0)
    ring = changed & ~base
    before = np.abs(plain.image[ring].astype(np.float32) - box).mean()
    assert np.abs(glossy.image[ring].astype(np.float32) - box).mean() < before
    # The mirror shows the key light too, whether the key's shadows are worked out per
    # pixel (its light then drawn apart from the fill) or not.
    flat = render_staged(image, calibration, [item], renderer, assets={"test_box": _box_parts()},
                         lighting=replace(LIGHT, floor_gloss=0.3), floor_mask=mask, seed=0, look=CLEAN,
                         self_shadows=False)
    np.testing.assert_allclose(glossy.image[ring].astype(float).mean(), flat.image[ring].astype(float).mean(), atol=0.5)
