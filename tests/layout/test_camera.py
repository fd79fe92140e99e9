"""The photo's camera in the layout: the frame as planes, the judgement, the solver."""
from __future__ import annotations

import math

import numpy as np
import pytest

from layout import LayoutBuilder, Solver
from layout.camera import CAMERA, Camera, CameraRules, in_view_share, judge
from layout.errors import LayoutError
from layout.spec import build, spec_from_dict

K = [[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]]


def looking_along_x(height_m: float, pitch_down_deg: float = 0.0, at=(0.0, 0.0)) -> np.ndarray:
    """camera_from_floor of a camera at ``at``, ``height_m`` up, looking along +x, tilted down."""
    p = math.radians(pitch_down_deg)
    # Camera axes in the floor frame: x right = -y; z ahead = (cos p, 0, -sin p); y down = z x x.
    ahead = np.array([math.cos(p), 0.0, -math.sin(p)])
    right = np.array([0.0, -1.0, 0.0])
    down = np.cross(ahead, right)
    R = np.stack([right, down, ahead])
    center = np.array([at[0], at[1], height_m])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = -R @ center
    return T


def level_camera(**rules):
    return Camera(K, looking_along_x(1.5), (640, 480))


def test_projection_of_a_hand_placed_point():
    cam = level_camera()
    uv, z = cam.project([[5.0, 0.0, 1.5], [5.0, 1.0, 0.5]])
    np.testing.assert_allclose(uv, [[320.0, 240.0], [320.0 - 100.0, 240.0 + 100.0]])
    np.testing.assert_allclose(z, [5.0, 5.0])
    np.testing.assert_allclose(cam.center_m, [0.0, 0.0, 1.5])


def test_frame_planes_are_the_image_edges_and_the_foreground_line():
    """Level camera 1.5 m up, f = 500 px, 640 x 480: a floor point at distance x shows at row
    240 + 750 / x, so the foreground line (row 480 * 0.85 = 408) lies 750 / 168 = 4.464 m out;
    the margin (1 % of 640 = 6.4 px) moves the left edge to u = 6.4, i.e. y = 313.6 x / 500."""
    rules = CameraRules(foreground=0.15, margin=0.01)
    planes = Camera(K, looking_along_x(1.5), (640, 480)).frame_planes(rules)
    np.testing.assert_allclose(np.linalg.norm(planes[:, :3], axis=1), 1.0)

    def inside(p):
        return bool(np.all(planes[:, :3] @ p + planes[:, 3] >= 0))

    x_fore = 750.0 / 168.0
    assert not inside([x_fore - 0.01, 0.0, 0.0]) and inside([x_fore + 0.01, 0.0, 0.0])
    y_left = 313.6 * 10.0 / 500.0
    assert inside([10.0, y_left - 0.01, 1.5]) and not inside([10.0, y_left + 0.01, 1.5])
    # The top edge: row 6.4 is 233.6 px above the centre, so 233.6 / 500 m up per metre out.
    z_top = 1.5 + 233.6 * 10.0 / 500.0
    assert inside([10.0, 0.0, z_top - 0.01]) and not inside([10.0, 0.0, z_top + 0.01])
    assert not inside([-1.0, 0.0, 1.0])  # behind the camera


def _room(camera=None, items=(("box", (0.6, 0.6, 2.2)),)):
    b = LayoutBuilder([[0, -3], [9, -3], [9, 3], [0, 3]], 3.0)
    ids = [b.add_item(name, size, kind=name) for name, size in items]
    if camera is not None:
        b.set_camera(camera)
    return b.finalize(), ids


def test_the_solver_keeps_a_tall_item_whole_in_the_frame():
    """A 2.2 m box in a 9 x 6 m room seen by a level camera (1.5 m up): near the camera its
    top leaves the frame and the first 4.5 m are foreground. Without the camera some random
    starts leave it cut; with it, none does."""
    cam = Camera(K, looking_along_x(1.5), (640, 480))
    plain, _ = _room()
    framed, (box,) = _room(cam)
    cut_plain = [bool(judge(Solver().solve(plain, seed=s), camera=cam)["cut"]) for s in range(8)]
    assert any(cut_plain)
    for s in range(8):
        lay = Solver().solve(framed, seed=s)
        assert judge(lay)["cut"] == [], s
        corners = lay.position_m[box] + np.array([[dx, dy, dz] for dx in (-.3, .3) for dy in (-.3, .3)
                                                  for dz in (-1.1, 1.1)])
        uv, _ = cam.project(corners)
        assert uv[:, 0].min() >= -1 and uv[:, 0].max() <= 641 and uv[:, 1].min() >= -1
        assert uv[:, 1].max() <= 480 * (1 - CAMERA.foreground) + 1


def test_a_rug_may_lie_in_the_foreground_and_run_out_of_the_photo():
    """A rug lies flat: held at a spot 3 m out, in the foreground (which reaches 4.46 m,
    see above) and reaching past the left edge (y = 313.6 x / 500 = 1.25 m at 2 m out), it
    stays there; a box of its footprint, 0.5 m tall, held at the same spot, is pushed
    into the frame and out of the foreground."""
    cam = Camera(K, looking_along_x(1.5), (640, 480))
    for collides, stays in ((False, True), (True, False)):
        b = LayoutBuilder([[0, -3], [9, -3], [9, 3], [0, 3]], 3.0)
        item = b.add_item("rug", (2.0, 1.4, 0.01 if not collides else 0.5), kind="rug", collides=collides)
        b.heat([item], (3.0, 1.2))
        b.set_camera(cam)
        lay = Solver().solve(b.finalize(), seed=0)
        at = lay.position_m[item, :2]
        assert (np.linalg.norm(at - [3.0, 1.2]) < 0.05) == stays, (collides, at)
        if not stays:
            assert judge(lay)["cut"] == []


def test_no_place_in_view_for_what_the_frame_cannot_hold():
    """Pitched 40 degrees down from 1.2 m the top edge meets the floor-level ray at about
    1.2 / tan(40 - 25.6 deg) = 4.7 m (half the vertical view is atan(240 / 500)), and the
    foreground takes the near floor: a 2 m wardrobe is cut wherever it stands in a 4 m deep
    room, a coffee table is not."""
    cam = Camera(K, looking_along_x(1.2, 40.0), (640, 480))
    poly = [[0, -2], [4, -2], [4, 2], [0, 2]]
    assert in_view_share(cam, poly, (1.2, 0.6, 2.0)) == 0.0
    assert in_view_share(cam, poly, (1.1, 0.6, 0.45)) > 0.05


def test_judge_finds_hidden_and_from_behind():
    cam = Camera(K, looking_along_x(1.2, 10.0), (640, 480))
    b = LayoutBuilder([[0, -3], [12, -3], [12, 3], [0, 3]], 3.0)
    front = b.add_item("wall_of_boxes", (2.0, 0.5, 2.0), kind="bookcase")
    back = b.add_item("hidden_chair", (0.8, 0.8, 0.9), kind="armchair")
    sofa = b.add_item("sofa", (2.0, 0.9, 0.85), kind="sofa")
    b.set_camera(cam)
    model = b.finalize()
    pos = model.particle_init_position_m.copy()
    yaw = np.zeros(model.n)
    pos[front] = [8.0, 0.0, 1.0]
    pos[back] = [9.5, 0.0, 0.45]  # right behind the boxes, seen from the camera
    pos[sofa] = [5.0, 2.0, 0.425]  # nearer than the floor's middle (6 m)
    yaw[sofa] = 0.0  # facing +x, away from the camera: its back is toward the lens
    from layout.solver import Layout

    lay = Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0)
    j = judge(lay)
    assert j["hidden"] == ["hidden_chair"] and j["visible"]["hidden_chair"] < 0.1
    assert j["visible"]["wall_of_boxes"] == 1.0
    assert j["from_behind"] == ["sofa"]
    yaw[sofa] = math.pi  # turned to face the camera
    assert judge(Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0))["from_behind"] == []


def test_a_tv_no_seat_faces_is_not_shown_edge_on():
    """Camera at the origin looking along +x; a TV on its stand at (6, 0). Facing the
    camera, or turned 65 degrees from it, it is fine; edge-on (90 degrees) or from behind,
    past the 70 allowed, it is judged as seating from behind is. Bare (its TV left off for
    the frame: 0.55 m) it is a cabinet; with a sofa facing it, the group decides."""
    from layout.solver import Layout

    cam = Camera(K, looking_along_x(1.2, 10.0), (640, 480))

    def judged(turn_rad, height_m=1.25, sofa=False):
        b = LayoutBuilder([[0, -4], [12, -4], [12, 4], [0, 4]], 3.0)
        tv = b.add_item("tv", (1.6, 0.45, height_m), kind="tv_stand")
        if sofa:
            seat = b.add_item("sofa", (2.0, 0.9, 0.85), kind="sofa")
            b.face(seat, tv)
        b.set_camera(cam)
        model = b.finalize()
        pos, yaw = model.particle_init_position_m.copy(), np.zeros(model.n)
        pos[tv], yaw[tv] = [6.0, 0.0, 0.5 * height_m], math.pi + turn_rad
        if sofa:
            pos[seat], yaw[seat] = [6.0, 3.0, 0.425], -0.5 * math.pi
        return judge(Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0))["from_behind"]

    assert judged(0.0) == [] and judged(math.radians(65)) == []
    assert judged(math.radians(90)) == ["tv"] and judged(math.pi) == ["tv"]
    assert judged(math.radians(90), height_m=0.55) == []
    assert judged(math.radians(90), sofa=True) == []


def test_a_desk_is_seen_through_its_chair_but_not_through_a_bookcase():
    """Level camera 1.2 m up looking along +x. A desk 0.75 m high at x = 8 with its chair
    (placed at it by a heat rule) at x = 7 in front: the chair's 1 m box covers the desk's
    whole outline (from 1.2 m up, its top edge hides the floor out to 40 m), yet the desk
    is not hidden (seats_at); a 2 m bookcase at x = 6 hides both, and hidden_by names it."""
    from layout.camera import seats_at
    from layout.solver import Layout

    cam = Camera(K, looking_along_x(1.2, 10.0), (640, 480))
    b = LayoutBuilder([[0, -3], [12, -3], [12, 3], [0, 3]], 3.0)
    desk = b.add_item("desk", (1.2, 0.6, 0.75), kind="desk")
    chair = b.add_item("chair", (1.4, 0.6, 1.0), kind="office_chair")
    shelf = b.add_item("shelf", (1.6, 0.4, 2.0), kind="bookcase")
    b.heat([chair], (0.65, 0.0), frame=desk)
    b.set_camera(cam)
    model = b.finalize()
    assert seats_at(model) == {"desk": ["chair"]}
    pos = model.particle_init_position_m.copy()
    yaw = np.zeros(model.n)
    pos[desk], pos[chair], pos[shelf] = [8.0, 0.0, 0.375], [7.0, 0.0, 0.5], [6.0, 4.0, 1.0]
    lay = Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0)
    j = judge(lay)
    assert j["visible"]["desk"] == 1.0 and j["hidden"] == []
    pos[shelf] = [6.0, 0.0, 1.0]
    j = judge(Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0))
    assert j["hidden"] == ["desk", "chair"] and j["visible"]["desk"] < 0.1
    assert j["hidden_by"] == {"desk": "shelf", "chair": "shelf"}


def test_a_tall_piece_looms_where_it_fills_much_of_the_frame():
    """Level camera 1.2 m up, f = 500 px, 640 x 480. A wardrobe 1.2 m wide, 0.6 m deep,
    2 m tall, its front 2.7 m out: the front face (the hull of its outline, the lens
    between its floor and top) spans 2 x 500 x 0.6 / 2.7 = 222.2 px by 500 x 2 / 2.7 =
    370.4 px, 26.8 % of the frame: it looms (the rule's 15 %), not with a limit of 30 %.
    At 7.7 m it fills 3.3 %; a 1 m chest there as near sits below the lens and the photo
    shows the room past it; with the lens 2.5 m up the wardrobe does not loom either."""
    from layout.solver import Layout

    def judged(height_m, x_m, lens_m=1.2, rules=None):
        b = LayoutBuilder([[0, -3], [12, -3], [12, 3], [0, 3]], 3.0)
        b.add_item("piece", (1.2, 0.6, height_m), kind="wardrobe")
        b.set_camera(Camera(K, looking_along_x(lens_m), (640, 480)), rules)
        model = b.finalize()
        pos = model.particle_init_position_m.copy()
        pos[0] = [x_m, 0.0, height_m / 2]
        return judge(Layout.from_state(model, pos, np.zeros(model.n), {}, np.zeros(0), 0, 0, None, 0.0))["looms"]

    assert judged(2.0, 3.0) == ["piece"]
    assert judged(2.0, 3.0, rules=CameraRules(max_cover=0.25)) == ["piece"]
    assert judged(2.0, 3.0, rules=CameraRules(max_cover=0.29)) == []
    assert judged(2.0, 8.0) == [] and judged(2.0, 8.0, rules=CameraRules(max_cover=0.03)) == ["piece"]
    assert judged(1.0, 3.0) == []
    assert judged(2.0, 3.0, lens_m=2.5) == []


def test_a_spec_names_its_camera():
    T = looking_along_x(1.5).tolist()
    doc = {"room": {"polygon": [[0, -3], [9, -3], [9, 3], [0, 3]], "height": 3.0},
           "camera": {"K": K, "camera_from_floor": T, "size_px": [640, 480]},
           "items": [{"id": "box", "size": [0.6, 0.6, 2.2]}]}
    model, _ = build(spec_from_dict(doc, where="my.toml"))
    assert model.camera is not None and model.floor_frame_planes.shape == (4, 4)
    bad = {**doc, "camera": {**doc["camera"], "K": [[0, 0, 320], [0, 500, 240], [0, 0, 1]]}}
    with pytest.raises(LayoutError, match=r"my.toml: camera: camera.K = .*positive focal lengths"):
        spec_from_dict(bad, where="my.toml")
    below = {**doc, "camera": {**doc["camera"], "camera_from_floor": looking_along_x(-1.0).tolist()}}
    with pytest.raises(LayoutError, match=r"my.toml: camera: .*stands -1.00 m above the floor"):
        spec_from_dict(below, where="my.toml")
    with pytest.raises(LayoutError, match=r"my.toml: camera: size_px = \[640\] must be \[width, height\]"):
        spec_from_dict({**doc, "camera": {**doc["camera"], "size_px": [640]}}, where="my.toml")


def test_rays_enter_turned_boxes_where_hand_computed():
    """The visibility rays' slab test (layout._kernels.ray_box_entry): a 1 m cube 2 m ahead
    is entered at 1.5 m; behind the ray it is missed; from inside, at 0. A box turned to
    face +y (2 m wide across it, 0.5 m deep along it) centred 3 m along y spans y 2.75 to
    3.25 and x -1 to 1: entered at 2.75 m, missed from 2.2 m to the side."""
    from layout._kernels import ray_box_entry

    pos = np.array([[2.0, 0.0, 0.5], [0.0, 3.0, 0.5]])
    yaw = np.array([0.0, math.pi / 2])
    size = np.array([[1.0, 1.0, 1.0], [2.0, 0.5, 1.0]])
    dirs = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    out = np.empty((3, 2))
    ray_box_entry(np.array([0.0, 0.0, 0.5]), dirs, pos, yaw, size, out)
    np.testing.assert_allclose(out[0, 0], 1.5)
    assert out[1, 0] == np.inf and out[0, 1] == np.inf and out[1, 1] == np.inf
    np.testing.assert_allclose(out[2, 1], 2.75)
    assert out[2, 0] == np.inf
    ray_box_entry(np.array([2.2, 0.0, 0.5]), dirs, pos, yaw, size, out)
    assert out[2, 1] == np.inf and out[0, 0] == 0.0 and out[1, 0] == 0.0
