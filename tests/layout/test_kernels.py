"""Each constraint kind on a hand-computed case, and its gradient against finite differences.

The generic check: for a scalar constraint C with k = 1, PBD moves particle i by
Δp_i = −C w_i ∇_i C / Σ_j w_j ‖∇_j C‖² (Eqs. 2–3). We measure ∇C by central
differences of the residual kernel and compare with what the projection kernel did.
"""
import math

import numpy as np
import pytest

from layout import LayoutBuilder, LayoutError
from layout import _codes as codes
from layout import _kernels as K

ROOM = [[0, 0], [10, 0], [10, 10], [0, 10]]
L_ROOM = [[0, 0], [6, 0], [6, 3], [3, 3], [3, 6], [0, 6]]


def _state(model, xy, yaw=None, z=None):
    n = model.n
    pos = np.zeros((n, 3))
    pos[:, :2] = xy
    pos[:, 2] = 0.5 * model.particle_size_m[:, 2] if z is None else z
    yaw = np.zeros(n) if yaw is None else np.asarray(yaw, dtype=np.float64)
    return pos, yaw.copy()


def _cs(yaw):
    return np.stack([np.cos(yaw), np.sin(yaw)], axis=1)


def _project(kernel, arrays, model, pos, yaw, *extra):
    P = model.packed()[0]
    acc = np.zeros((model.n, 6))
    degen = np.zeros(len(codes.KINDS), np.int64)
    if extra:
        kernel(arrays, *extra, P, pos, yaw, acc, False, 1, 30.0, degen)
    else:
        kernel(arrays, P, pos, yaw, acc, False, 1, 30.0, degen)
    return degen


def _fd_gradient(residual, pos, movable, h=1e-6):
    """Central differences of a scalar residual w.r.t. x and y of each movable particle."""
    grad = np.zeros((len(pos), 2))
    for i in movable:
        for a in range(2):
            p1, p2 = pos.copy(), pos.copy()
            p1[i, a] += h
            p2[i, a] -= h
            grad[i, a] = (residual(p1) - residual(p2)) / (2 * h)
    return grad


def _check_pbd_step(model, residual, before, after, movable):
    """The kernel's step equals −C w ∇C / Σ w ‖∇C‖² with ∇C from finite differences."""
    C = residual(before)
    g = _fd_gradient(residual, before, movable)
    w = model.particle_inv_mass
    denom = sum(w[i] * g[i] @ g[i] for i in movable)
    for i in movable:
        expected = -C * w[i] * g[i] / denom
        np.testing.assert_allclose(after[i, :2] - before[i, :2], expected, atol=1e-6)
    assert abs(residual(after)) < abs(C)


def _scalar(residual_kernel, arrays, model, yaw, index=0, *extra):
    P = model.packed()[0]

    def f(pos):
        out = np.zeros(64)
        if extra:
            residual_kernel(arrays, *extra, P, pos, yaw, out)
        else:
            residual_kernel(arrays, P, pos, yaw, out)
        return out[index]

    return f


def test_distance_hand_case_and_gradient():
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1, 1, 1))  # mass 1
    c = b.add_item("c", (1, 1, 0.5))  # mass 0.5: moves twice as far
    b.distance(a, c, 1.0, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[2, 5], [5, 5]])
    before = pos.copy()
    _project(K.project_distance, m.packed()[1], m, pos, yaw)
    # C = 3 - 1 = 2; w = (1, 2): a moves 2 * 1/3 right, c moves 2 * 2/3 left.
    np.testing.assert_allclose(pos[:, :2], [[2 + 2 / 3, 5], [5 - 4 / 3, 5]])
    _check_pbd_step(m, _scalar(K.residual_distance, m.packed()[1], m, yaw), before, pos, [a, c])


@pytest.mark.parametrize("mode,start,moves", [("min", 3.0, False), ("min", 0.5, True), ("max", 0.5, False), ("max", 3.0, True)])
def test_distance_inequalities(mode, start, moves):
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1, 1, 1))
    c = b.add_item("c", (1, 1, 1))
    b.distance(a, c, 1.0, mode=mode, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[5, 5], [5 + start, 5]])
    _project(K.project_distance, m.packed()[1], m, pos, yaw)
    gap = pos[1, 0] - pos[0, 0]
    assert math.isclose(gap, 1.0) if moves else math.isclose(gap, start)


def test_focal_distance_pins_the_focal_point():
    b = LayoutBuilder(ROOM)
    tv = b.add_item("tv", (1.5, 0.4, 0.6))
    chairs = [b.add_item(f"c{k}", (0.5, 0.5, 0.9)) for k in range(2)]
    b.focal_distance(tv, chairs, 2.0, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[5, 5], [5, 8], [8, 5]])
    _project(K.project_distance, m.packed()[1], m, pos, yaw)
    np.testing.assert_allclose(pos[:, :2], [[5, 5], [5, 7], [7, 5]])


def test_distance_degenerate_is_counted_not_applied():
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1, 1, 1))
    c = b.add_item("c", (1, 1, 1))
    b.distance(a, c, 1.0, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[5, 5], [5, 5]])
    degen = _project(K.project_distance, m.packed()[1], m, pos, yaw)
    assert degen[codes.K_DISTANCE] == 1
    np.testing.assert_array_equal(pos[:, :2], [[5, 5], [5, 5]])


def test_lane_keeps_item_box_clear_and_gradient():
    b = LayoutBuilder(ROOM)
    stage = b.add_item("stage", (4, 2, 0.5))
    seat = b.add_item("seat", (0.4, 0.4, 0.9))
    b.lane(stage, [seat], angle_rad=0.0, length_m=5.0, half_width_m=0.5, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[2, 5], [4, 5.3]])
    before = pos.copy()
    _project(K.project_lane, m.packed()[2], m, pos, yaw)
    # Lane along +x from the stage center; the seat must be 0.5 + 0.2 (its half width) away.
    np.testing.assert_allclose(pos[:, :2], [[2, 5], [4, 5.7]])
    # With the origin free, the ghost point carries the stage along (w-weighted split).
    b2 = LayoutBuilder(ROOM)
    s2 = b2.add_item("stage", (4, 2, 0.5))
    t2 = b2.add_item("seat", (0.4, 0.4, 0.9))
    b2.lane(s2, [t2], angle_rad=0.0, length_m=5.0, half_width_m=0.5, pin_origin=False, k0=1.0, schedule="constant")
    m2 = b2.finalize()
    pos2, yaw2 = _state(m2, [[2, 5], [4, 5.3]])
    before = pos2.copy()
    _project(K.project_lane, m2.packed()[2], m2, pos2, yaw2)
    _check_pbd_step(m2, _scalar(K.residual_lane, m2.packed()[2], m2, yaw2), before, pos2, [s2, t2])


def test_heat_point_halves_the_error_and_gradient():
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1, 1, 1))
    c = b.add_item("c", (1, 1, 2))
    b.heat([a, c], (5, 5), k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[2, 2], [4, 8]])
    before = pos.copy()
    _project(K.project_heat, m.packed()[3], m, pos, yaw)
    # C = ½‖e‖² is quadratic: one Newton step on it halves e, and with w = 1/m every
    # member moves by the same -e/2.
    mass = np.array([1.0, 2.0])
    com = lambda p: (mass[:, None] * p[:, :2]).sum(0) / mass.sum()  # noqa: E731
    e0 = com(before) - 5
    np.testing.assert_allclose(com(pos) - 5, e0 / 2)
    np.testing.assert_allclose(pos[:, :2] - before[:, :2], [-e0 / 2, -e0 / 2])
    _check_pbd_step(m, _scalar(K.residual_heat, m.packed()[3], m, yaw), before, pos, [a, c])


def test_heat_point_in_a_parent_frame():
    b = LayoutBuilder(ROOM)
    desk = b.add_item("desk", (1.6, 0.8, 0.75), fixed=True, position_m=(5, 5), yaw_rad=math.pi / 2)
    laptop = b.add_item("laptop", (0.3, 0.2, 0.02))
    b.heat([laptop], (0.3, 0.0), frame=desk, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[5, 5], [5, 5]], yaw=[math.pi / 2, 0])
    for _ in range(40):
        _project(K.project_heat, m.packed()[3], m, pos, yaw)
    # 0.3 m towards the desk's front, which faces +y.
    np.testing.assert_allclose(pos[1, :2], [5, 5.3], atol=1e-9)


def test_symmetry_projects_center_onto_focal_axis_and_gradient():
    b = LayoutBuilder(ROOM)
    tv = b.add_item("tv", (1.5, 0.4, 0.6), fixed=True)
    a = b.add_item("a", (0.8, 0.8, 0.8))
    c = b.add_item("c", (0.8, 0.8, 0.8))
    b.symmetry(tv, [a, c], k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[1, 5], [3, 6], [4, 7]])
    before = pos.copy()
    _project(K.project_symmetry, m.packed()[4], m, pos, yaw)
    # TV faces +x from (1, 5); the chairs' center (3.5, 6.5) projects to (3.5, 5):
    # e = (0, 1.5), halved by the step.
    np.testing.assert_allclose(pos[1:, :2].mean(0), [3.5, 5.75])
    _check_pbd_step(m, _scalar(K.residual_symmetry, m.packed()[4], m, yaw), before, pos, [a, c])


def test_visual_balance_weights_by_footprint_and_gradient():
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (2, 1, 0.5))  # area 2
    c = b.add_item("c", (1, 1, 2))  # area 1
    b.balance([a, c], k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[2, 2], [8, 2]])
    before = pos.copy()
    _project(K.project_balance, m.packed()[5], m, pos, yaw)
    area = np.array([2.0, 1.0])
    center = (area[:, None] * pos[:, :2]).sum(0) / 3
    e0 = np.array([(2 * 2 + 8) / 3, 2]) - 5
    np.testing.assert_allclose(center - 5, e0 / 2)
    _check_pbd_step(m, _scalar(K.residual_balance, m.packed()[5], m, yaw), before, pos, [a, c])


def test_wall_distance_and_orientation():
    b = LayoutBuilder(ROOM)
    w = b.add_item("wardrobe", (1.2, 0.6, 2.0))
    b.wall_distance(w, k0=1.0)
    b.wall_orientation(w, k0=1.0)
    m = b.finalize()
    pos, yaw = _state(m, [[1.0, 4.0]], yaw=[0.4])
    before = pos.copy()
    R = m.packed()[11]
    _project(K.project_wall_distance, m.packed()[6], m, pos, yaw, R)
    # Nearest wall is x = 0; the center goes to half the depth from it.
    np.testing.assert_allclose(pos[0, :2], [0.3, 4.0])
    _check_pbd_step(m, _scalar(K.residual_wall_distance, m.packed()[6], m, yaw, 0, R), before, pos, [w])
    _project(K.project_wall_orientation, m.packed()[7], m, pos, yaw, R)
    assert abs(yaw[0]) < 1e-12  # faces the room: +x, the wall's inward normal


def test_wall_distance_pulls_a_center_outside_back_in():
    b = LayoutBuilder(ROOM)
    w = b.add_item("w", (1, 0.5, 1))
    b.wall_distance(w, 0.25, k0=1.0)
    m = b.finalize()
    pos, yaw = _state(m, [[-0.5, 4.0]])
    _project(K.project_wall_distance, m.packed()[6], m, pos, yaw, m.packed()[11])
    np.testing.assert_allclose(pos[0, :2], [0.25, 4.0])


def test_pairwise_orientation_face_and_parallel():
    b = LayoutBuilder(ROOM)
    sofa = b.add_item("sofa", (2, 0.9, 0.8))
    tv = b.add_item("tv", (1.5, 0.4, 0.6))
    table = b.add_item("table", (1, 0.6, 0.4))
    b.face(sofa, tv, mutual=True, k0=1.0, schedule="constant")
    b.parallel(table, sofa, k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, [[2, 5], [2, 8], [5, 5]], yaw=[0.0, 0.5, 0.8])
    _project(K.project_orientation, m.packed()[8], m, pos, yaw)
    # The sofa turns to face +y (pi/2), the TV faces back (-pi/2).
    assert math.isclose(K.wrap(yaw[1]), -math.pi / 2)
    # Parallel runs after the sofa turned: the error (0 - (0.8 - pi/2)) mod pi is shared
    # by inverse mass between the table and the sofa.
    wt, ws = m.particle_inv_mass[2], m.particle_inv_mass[0]
    err = (-(0.8 - math.pi / 2) + math.pi / 2) % math.pi - math.pi / 2
    assert math.isclose(yaw[2], 0.8 + err * wt / (wt + ws))
    assert math.isclose(yaw[0], math.pi / 2 - err * ws / (wt + ws))
    assert math.isclose((yaw[2] - yaw[0]) % math.pi, 0.0, abs_tol=1e-12)


def test_stack_puts_top_centered_on_base():
    b = LayoutBuilder(ROOM)
    book = b.add_item("book", (0.2, 0.3, 0.04))
    top = b.add_item("top", (0.2, 0.3, 0.04))
    b.stack(book, top)
    m = b.finalize()
    pos, yaw = _state(m, [[1, 1], [1.1, 1.0]], z=[0.02, 0.5])
    _project(K.project_stack, m.packed()[9], m, pos, yaw)
    assert math.isclose(pos[1, 2], 0.06)  # base center + half of both heights
    assert math.isclose(pos[0, 2], 0.02)  # the base does not float up
    np.testing.assert_allclose(pos[0, :2], pos[1, :2])


def test_curve_segment_arc_and_spacing():
    b = LayoutBuilder(ROOM)
    g = b.add_group("row", position_m=(5, 5), yaw_rad=0.0, fixed=True)
    seats = [b.add_item(f"s{k}", (0.5, 0.5, 0.9), group=g) for k in range(3)]
    b.curve(g, seats, segment_m=((-2, 0), (2, 0)), spacing_m=1.0, k0=1.0, schedule="constant")
    g2 = b.add_group("tier", position_m=(5, 2), yaw_rad=0.0, fixed=True)
    s4 = b.add_item("s4", (0.5, 0.5, 0.9), group=g2)
    b.curve(g2, [s4], arc=((0, 0), 2.0, 0.0, math.pi), k0=1.0, schedule="constant")
    m = b.finalize()
    pos, yaw = _state(m, np.zeros((m.n, 2)))
    pos[[0, 4], :2] = [[5, 5], [5, 2]]
    pos[seats, :2] = [[5.5, 5.4], [4.9, 4.8], [5.2, 5.1]]
    pos[s4, :2] = [6, 3]
    _project(K.project_curve, m.packed()[10], m, pos, yaw)
    # Pulled onto y = 5, then neighbours in curve order (s1 at 4.9, s2 at 5.2, s0 at
    # 5.5) are spaced, Gauss-Seidel: s1-s2 part by 0.7 (s1 4.55, s2 5.55); then s2-s0,
    # 0.05 apart with s2 now past s0, part by 0.95 along s0 -> s2 (s2 6.025, s0 5.025).
    np.testing.assert_allclose(pos[seats, 1], 5.0)
    np.testing.assert_allclose(pos[seats, 0], [5.025, 4.55, 6.025])
    # The arc point nearest (1, 1) in the tier frame is at 45 degrees on radius 2.
    np.testing.assert_allclose(pos[s4, :2], [5 + math.sqrt(2), 2 + math.sqrt(2)])
    for _ in range(50):
        _project(K.project_curve, m.packed()[10], m, pos, yaw)
    np.testing.assert_allclose(np.diff(np.sort(pos[seats, 0])), [1.0, 1.0], atol=1e-6)


def test_boundary_l_shape_reflex_corner_and_outside_corner():
    # a: a diamond (0.7071 m square at 45 degrees) whose corners all lie on the floor
    # but which contains the reflex corner (3, 3) of the L. In its frame the corner is
    # at (0.1414, 0): 0.2121 m deep along x, 0.3536 m along y, so it is pushed 0.2121 m
    # back along its own x axis, (-0.15, -0.15) in the floor frame.
    side = math.sqrt(0.5)
    b = LayoutBuilder(L_ROOM)
    b.add_item("a", (side, side, 1))
    b.add_item("c", (1, 2, 1))
    m = b.finalize()
    P, R = m.packed()[0], m.packed()[11]
    pos, yaw = _state(m, [[2.9, 2.9], [5.8, 1.0]], yaw=[math.pi / 4, 0])
    K.project_boundary(R, P, pos, yaw)
    np.testing.assert_allclose(pos[0, :2], [2.75, 2.75], atol=1e-6)
    # c (depth 2 along x) pokes 0.8 m through the wall x = 6.
    np.testing.assert_allclose(pos[1, :2], [5.0, 1.0], atol=1e-6)
    out = np.zeros(m.n)
    K.residual_boundary(R, P, pos, yaw, out)
    np.testing.assert_allclose(out, 0.0)


@pytest.mark.parametrize("model", [codes.BOX, codes.SPHERE])
def test_collision_box_and_sphere(model):
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1, 1, 1))
    c = b.add_item("c", (1, 1, 1))
    m = b.finalize()
    P, R = m.packed()[0], m.packed()[11]
    pos, yaw = _state(m, [[5, 5], [5.8, 5.1]])
    before = pos.copy()
    pairs = K.candidate_pairs(P, pos, yaw, 1.0, 0.05)
    assert pairs.tolist() == [[0, 1]]
    K.project_collision(P, R, pairs, pos, yaw, _cs(yaw), np.zeros((2, 6)), False, 1.0, model, 0.0,
                        np.zeros(len(codes.KINDS), np.int64))
    if model == codes.BOX:
        # Depth 0.2 along x (the axis of least penetration), split equally.
        np.testing.assert_allclose(pos[:, :2], [[4.9, 5], [5.9, 5.1]])
    else:
        np.testing.assert_allclose(np.linalg.norm(pos[1, :2] - pos[0, :2]), math.sqrt(2))

    def residual(p):
        out = np.zeros(1)
        K.residual_collision(P, R, pairs, p, _cs(yaw), model, out)
        return out[0]

    _check_pbd_step(m, residual, before, pos, [a, c])


def test_collision_ignores_items_at_different_heights_and_rigid_mates():
    b = LayoutBuilder(ROOM)
    desk = b.add_item("desk", (1.4, 0.7, 0.75))
    lamp = b.add_item("lamp", (0.2, 0.2, 0.4), elevation_m=0.75)
    g = b.add_group("set", rigid=True)
    b.add_item("x", (1, 1, 1), group=g, offset_m=(0, 0))
    b.add_item("y", (1, 1, 1), group=g, offset_m=(0.5, 0))
    m = b.finalize()
    P, R = m.packed()[0], m.packed()[11]
    pos, yaw = _state(m, [[5, 5], [5, 5], [2, 2], [0, 0], [0, 0]])
    pos[lamp, 2] = 0.95
    pos[g, 2] = 0.0
    K.sync_members(P, pos, yaw)
    pairs = K.candidate_pairs(P, pos, yaw, 1.0, 0.05)
    out = np.zeros(max(1, len(pairs)))
    K.residual_collision(P, R, pairs, pos, _cs(yaw), codes.BOX, out)
    assert np.all(out == 0.0)  # lamp rests on the desk; x and y are one rigid body
    assert desk == 0


def test_wall_bound_pair_slides_along_the_wall():
    b = LayoutBuilder(ROOM)
    a = b.add_item("a", (1.0, 0.6, 2))
    c = b.add_item("c", (1.0, 0.6, 2))
    b.against_wall(a)
    b.against_wall(c)
    m = b.finalize()
    P, R = m.packed()[0], m.packed()[11]
    pos, yaw = _state(m, [[0.3, 5.0], [0.3, 5.6]])
    pairs = K.candidate_pairs(P, pos, yaw, 1.0, 0.05)
    K.project_collision(P, R, pairs, pos, yaw, _cs(yaw), np.zeros((2, 6)), False, 1.0, codes.BOX, 0.0,
                        np.zeros(len(codes.KINDS), np.int64))
    # Both keep x = 0.3 (on the wall) and end 1 m apart along it.
    np.testing.assert_allclose(pos[:, 0], [0.3, 0.3])
    assert math.isclose(pos[1, 1] - pos[0, 1], 1.0)


@pytest.mark.parametrize("model", [codes.BOX, codes.SPHERE])
def test_accessibility_active_only_when_boxes_intersect(model):
    b = LayoutBuilder(ROOM)
    b.add_item("sofa", (1.0, 1.0, 0.8), access_m=(0, 0, 0.5, 0))
    b.add_item("table", (0.4, 0.4, 0.4))
    m = b.finalize()
    P = m.packed()[0]
    acc = np.zeros((2, 6))
    degen = np.zeros(len(codes.KINDS), np.int64)
    # Front access box spans x in [5.5, 6.0]; the table spans [6.05, 6.45]: inactive.
    pos, yaw = _state(m, [[5, 5], [6.25, 5]])
    pairs = K.candidate_pairs(P, pos, yaw, 1.0, 0.05)
    before = pos.copy()
    K.project_access(P, pairs, pos, yaw, _cs(yaw), acc, False, 1.0, model, degen)
    np.testing.assert_array_equal(pos, before)
    # Now 0.1 m inside the access box.
    pos, yaw = _state(m, [[5, 5], [6.1, 5]])
    before = pos.copy()
    K.project_access(P, pairs, pos, yaw, _cs(yaw), acc, False, 1.0, model, degen)
    w = m.particle_inv_mass
    if model == codes.BOX:
        moved = (pos[1, 0] - before[1, 0]) - (pos[0, 0] - before[0, 0])
        assert math.isclose(moved, 0.1)
        assert math.isclose((pos[1, 0] - before[1, 0]) / -(pos[0, 0] - before[0, 0]), w[1] / w[0])
    else:
        # Paper: distance from the access center to the table is at least b_i + ad_jk.
        a_center = pos[0, :2] + [0.75, 0]
        need = math.hypot(0.2, 0.2) + math.hypot(0.25, 0.5)
        assert math.isclose(np.linalg.norm(pos[1, :2] - a_center), need)


def test_jacobi_flush_averages_with_over_relaxation():
    pos = np.zeros((2, 3))
    yaw = np.zeros(2)
    acc = np.zeros((2, 6))
    no_members = (np.zeros(3, np.int64), np.zeros(0, np.int64))
    assert not K.push(0, 1.0, 0.0, 0.0, pos, yaw, acc, True, no_members[0])
    assert not K.push(0, 3.0, 2.0, 0.0, pos, yaw, acc, True, no_members[0])
    assert not K.turn(1, 0.5, pos, yaw, acc, True, no_members[0])
    assert not pos.any() and not yaw.any()  # nothing moves before the flush
    K.flush(pos, yaw, acc, 1.2, *no_members)
    np.testing.assert_allclose(pos[0], [1.2 * 2.0, 1.2 * 1.0, 0.0])
    assert math.isclose(yaw[1], 0.6)
    assert not acc.any()


def test_rigid_group_moves_and_turns_as_one_body():
    b = LayoutBuilder(ROOM)
    g = b.add_group("beds", rigid=True)
    a = b.add_item("a", (1, 2, 0.5), group=g, offset_m=(-0.6, 0))
    c = b.add_item("c", (1, 2, 0.5), group=g, offset_m=(0.6, 0), yaw_rad=math.pi)
    m = b.finalize()
    P = m.packed()[0]
    pos, yaw = _state(m, np.zeros((3, 2)))
    pos[g] = [5, 5, 0]
    K.sync_members(P, pos, yaw)
    np.testing.assert_allclose(pos[[a, c], :2], [[4.4, 5], [5.6, 5]])
    acc = np.zeros((3, 6))
    # A correction on a member goes to the body and carries every member along.
    assert K.push(P.body[a], 0.5, 0.0, 0.0, pos, yaw, acc, False, P.mstart)
    K.carry(P.body[a], 0.5, 0.0, 0.0, 0.0, pos, yaw, P.mstart, P.mlist)
    assert K.turn(P.body[c], math.pi / 2, pos, yaw, acc, False, P.mstart)
    K.carry(P.body[c], 0.0, 0.0, 0.0, math.pi / 2, pos, yaw, P.mstart, P.mlist)
    np.testing.assert_allclose(pos[[g, a, c], :2], [[5.5, 5], [5.5, 4.4], [5.5, 5.6]], atol=1e-12)
    np.testing.assert_allclose(yaw[[g, a, c]], [math.pi / 2, math.pi / 2, 1.5 * math.pi])
    expect = pos.copy()
    K.sync_members(P, pos, yaw)  # the incremental update matches the composed pose
    np.testing.assert_allclose(pos, expect, atol=1e-12)


@pytest.mark.parametrize("schedule,expect", [("constant", 0.5), ("decay", 1 - 0.5 ** (30 / 60)), ("grow", 1 - 0.5 ** (60 / 30))])
def test_stiffness_schedules(schedule, expect):
    assert math.isclose(K.stiffness(0.5, codes.SCHEDULE_NAMES[schedule], 60, 30.0), expect)


def test_spatial_hash_matches_brute_force(rng):
    b = LayoutBuilder([[0, 0], [30, 0], [30, 30], [0, 30]], 3.0)
    n = 400
    sizes = rng.uniform(0.2, 2.0, size=(n, 3))
    sizes[:4, :2] = [[9.0, 2.0], [7.0, 6.0], [0.3, 12.0], [8.0, 8.0]]  # checked against all
    for k in range(n):
        b.add_item(f"i{k}", sizes[k], access_m=(0, 0, rng.choice([0, 0.5]), 0))
    m = b.finalize()
    pos, yaw = _state(m, rng.uniform(0, 30, size=(n, 2)), yaw=rng.uniform(-3, 3, n))
    P = m.packed()[0]
    pairs = {tuple(p) for p in K.candidate_pairs(P, pos, yaw, 1.0, 0.0)}
    # Brute force on the world boxes of footprint plus access boxes (the access box of
    # side k, back, left, front, right, extends the footprint there): listed when both
    # their bounding boxes and the turned boxes themselves meet.
    a = m.particle_access_depth_m
    local = np.stack([
        np.stack([-0.5 * sizes[:, 1] - a[:, 0], -0.5 * sizes[:, 0] - a[:, 3]], 1),
        np.stack([0.5 * sizes[:, 1] + a[:, 2], -0.5 * sizes[:, 0] - a[:, 3]], 1),
        np.stack([0.5 * sizes[:, 1] + a[:, 2], 0.5 * sizes[:, 0] + a[:, 1]], 1),
        np.stack([-0.5 * sizes[:, 1] - a[:, 0], 0.5 * sizes[:, 0] + a[:, 1]], 1),
    ], 1)
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    wx = pos[:, None, 0] + c * local[..., 0] - s * local[..., 1]
    wy = pos[:, None, 1] + s * local[..., 0] + c * local[..., 1]
    lo, hi = np.stack([wx.min(1), wy.min(1)], 1), np.stack([wx.max(1), wy.max(1)], 1)
    corners = np.stack([wx, wy], axis=-1)
    bounding = {
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if np.all(lo[i] <= hi[j] + 1e-12) and np.all(lo[j] <= hi[i] + 1e-12)
    }
    expect = {(i, j) for i, j in bounding if _rects_meet(corners[i], corners[j])}
    assert pairs == expect
    assert 0 < len(pairs) < n * (n - 1) // 20  # a real test: some pairs, far from all
    assert len(expect) < 0.9 * len(bounding)  # the turned boxes drop pairs


def _rects_meet(a, b):
    """Separating-axis test of two rectangles given by their (4, 2) corners."""
    for rect in (a, b):
        for k in range(2):
            axis = rect[k + 1] - rect[k]
            pa, pb = a @ axis, b @ axis
            if pa.max() < pb.min() - 1e-9 or pb.max() < pa.min() - 1e-9:
                return False
    return True


def _boxes_meet(box, obb, body, movable):
    """Brute force over the boxes of a pair grid: (i, j) particle pairs, i < j."""
    lo, hi = box[:, :2] - box[:, 2:], box[:, :2] + box[:, 2:]
    meet = np.all((lo[:, None] <= hi[None] + 1e-12) & (lo[None] <= hi[:, None] + 1e-12), axis=-1)
    meet &= (body[:, None] != body[None]) & (movable[:, None] | movable[None])
    q, r = np.nonzero(np.triu(meet, 1))
    center, c, s, hd, hw = obb[:, :2], obb[:, 2], obb[:, 3], obb[:, 4], obb[:, 5]
    corners = np.stack([center + np.stack([c * u * hd - s * v * hw, s * u * hd + c * v * hw], 1)
                        for u, v in ((-1, -1), (1, -1), (1, 1), (-1, 1))], axis=1)
    turned = np.array([_rects_meet(corners[a], corners[b]) for a, b in zip(q, r)], bool)
    return q[turned], r[turned]


def test_verlet_refresh_lists_exactly_the_pairs_of_its_boxes(rng):
    b = LayoutBuilder([[0, 0], [20, 0], [20, 20], [0, 20]], 3.0)
    n = 300
    sizes = rng.uniform(0.2, 1.5, size=(n, 3))
    sizes[:2, :2] = [[9.0, 2.0], [0.3, 8.0]]  # big: checked against every box
    for k in range(n):
        b.add_item(f"i{k}", sizes[k], access_m=(0, 0, rng.choice([0, 0.5]), 0), fixed=k % 50 == 7,
                   position_m=(1.0, 1.0) if k % 50 == 7 else None)
    m = b.finalize()
    P = m.packed()[0]
    pos, yaw = _state(m, rng.uniform(0, 20, size=(n, 2)), yaw=rng.uniform(-3, 3, n))
    pad = 0.1
    G = K.pair_grid(P, pos, yaw, 1.0, pad, 0.5 * pad, 1)
    pairs = K.all_pairs(G)
    npairs = len(pairs)
    idx, body, movable, box, obb = G[0], G[1], G[2], G[5], G[6]
    movers_seen = 0
    for step in range(25):
        # Most items creep (below half the padding since their box was made, in
        # total), some jump or turn.
        free = m.particle_inv_mass[m.particle_body] > 0
        creep = rng.uniform(-0.004, 0.004, size=(n, 2))
        jump = (rng.uniform(size=n) < 0.1)[:, None] * rng.uniform(-0.5, 0.5, size=(n, 2))
        pos[free, :2] += (creep + jump)[free]
        turn = free & (rng.uniform(size=n) < 0.05)
        yaw[turn] += rng.uniform(-0.3, 0.3, size=int(turn.sum()))
        before = box.copy()
        pairs, npairs = K.refresh_pairs(G, P, pos, yaw, pairs, npairs)
        movers_seen += int(np.any(box != before, axis=1).sum())
        listed = [tuple(p) for p in pairs[:npairs, :2]]
        assert len(listed) == len(set(listed))  # each pair once
        # Exactly the pairs of the boxes as last made...
        q, r = _boxes_meet(box, obb, body, movable)
        expect = {(min(i, j), max(i, j)) for i, j in zip(idx[q], idx[r])}
        assert set(listed) == expect
        # ...which include every pair whose boxes meet now.
        assert {tuple(p) for p in K.candidate_pairs(P, pos, yaw, 1.0, 0.0)} <= set(listed)
    assert movers_seen > 100  # a real test: boxes were remade


def test_verlet_refresh_grows_an_empty_list():
    b = LayoutBuilder([[0, 0], [10, 0], [10, 10], [0, 10]], 3.0)
    b.add_item("a", (1.0, 1.0, 1.0))
    b.add_item("b", (1.0, 1.0, 1.0))
    m = b.finalize()
    P = m.packed()[0]
    pos, yaw = _state(m, [[2.0, 2.0], [8.0, 8.0]])
    G = K.pair_grid(P, pos, yaw, 1.0, 0.1, 0.05, 1)
    pairs = K.all_pairs(G)
    assert len(pairs) == 0
    pos[1, :2] = [2.5, 2.5]
    pairs, npairs = K.refresh_pairs(G, P, pos, yaw, pairs, 0)
    assert npairs == 1 and tuple(pairs[0, :2]) == (0, 1)


def test_pair_runs_share_no_movable_body(rng):
    b = LayoutBuilder([[0, 0], [12, 0], [12, 12], [0, 12]], 3.0)
    for k in range(120):
        b.add_item(f"i{k}", (0.6, 0.5, 0.8), access_m=(0, 0, 0.4, 0))
    for g in range(6):  # rigid pairs: one body, two footprints
        group = b.add_group(f"g{g}", rigid=True)
        for k in range(2):
            b.add_item(f"g{g}m{k}", (0.5, 0.5, 0.8), group=group, offset_m=(0.6 * k, 0.0))
    b.add_item("pillar", (0.8, 0.8, 2.0), position_m=(6.0, 6.0), fixed=True)
    m = b.finalize()
    P = m.packed()[0]
    pos, yaw = _state(m, rng.uniform(0.5, 11.5, size=(m.n, 2)), yaw=rng.uniform(-3, 3, m.n))
    K.sync_members(P, pos, yaw)
    pairs = K.candidate_pairs(P, pos, yaw, 1.0, 0.3)
    side = K.body_sides(P, pos, 2)
    run = np.array([K.pair_run(side[i], side[j]) for i, j in pairs])
    movable_bodies = []
    for t in range(2):
        these = pairs[run == t]
        bodies = set(P.body[these.ravel()])
        movable_bodies.append({x for x in bodies if P.inv_mass[x] > 0})
        assert all(side[x] == t for x in these.ravel() if P.inv_mass[P.body[x]] > 0)
        assert len(these) > 10
    assert not movable_bodies[0] & movable_bodies[1]
    across = pairs[run == 2]
    assert len(across) > 0
    assert all(side[i] != side[j] and side[i] >= 0 and side[j] >= 0 for i, j in across)
    # Both sides hold about half of the movable bodies.
    free = [x for x in range(m.n) if P.body[x] == x and P.inv_mass[x] > 0]
    assert abs(sum(side[x] for x in free) - len(free) / 2) <= 1
    # One thread: everything on side 0.
    assert set(K.body_sides(P, pos, 1)[[x for x in range(m.n) if P.inv_mass[P.body[x]] > 0]]) == {0}


def test_nested_rigid_groups_compose_offsets_once():
    b = LayoutBuilder(ROOM)
    outer = b.add_group("outer", rigid=True)
    mid = b.add_group("mid", rigid=True, group=outer, offset_m=(1, 0))
    inner = b.add_group("inner", rigid=True, group=mid, offset_m=(1, 0), yaw_rad=math.pi / 2)
    item = b.add_item("item", (0.5, 0.5, 0.5), group=inner, offset_m=(1, 0))
    m = b.finalize()
    pos, yaw = np.zeros((m.n, 3)), np.zeros(m.n)
    K.sync_members(m.packed()[0], pos, yaw)
    # (1, 0) + (1, 0) + the item's (1, 0) turned by the inner group's quarter turn.
    np.testing.assert_allclose(pos[item, :2], [2.0, 1.0], atol=1e-12)
    assert math.isclose(yaw[item], math.pi / 2)
    assert m.particle_body[item] == outer


def test_open_edge_is_no_wall():
    """Edge 3 (x = 0, from (0, 10) to (0, 0)) is open, like a photo's edge: the wardrobe
    1 m from it goes to the nearest wall, y = 0, 4 m away, faces +y, and stays inside."""
    b = LayoutBuilder(ROOM, open_edges=[3])
    w = b.add_item("wardrobe", (1.2, 0.6, 2.0))
    b.wall_distance(w, k0=1.0)
    b.wall_orientation(w, k0=1.0)
    m = b.finalize()
    np.testing.assert_array_equal(m.floor_edge_wall, [True, True, True, False])
    pos, yaw = _state(m, [[1.0, 4.0]], yaw=[0.4])
    R = m.packed()[11]
    out = np.zeros(1)
    K.residual_wall_distance(m.packed()[6], R, m.packed()[0], pos, yaw, out)
    assert out[0] == pytest.approx(4.0 - 0.3)  # distance to y = 0, less half the depth
    _project(K.project_wall_distance, m.packed()[6], m, pos, yaw, R)
    np.testing.assert_allclose(pos[0, :2], [1.0, 0.3])
    _project(K.project_wall_orientation, m.packed()[7], m, pos, yaw, R)
    assert yaw[0] == pytest.approx(np.pi / 2)


def test_room_without_walls_has_no_wall_constraints():
    b = LayoutBuilder(ROOM, open_edges=[0, 1, 2, 3])
    w = b.add_item("wardrobe", (1.2, 0.6, 2.0))
    b.against_wall(w)
    m = b.finalize()
    pos, yaw = _state(m, [[4.0, 4.0]], yaw=[0.4])
    before, yaw_before = pos.copy(), yaw.copy()
    R = m.packed()[11]
    _project(K.project_wall_distance, m.packed()[6], m, pos, yaw, R)
    _project(K.project_wall_orientation, m.packed()[7], m, pos, yaw, R)
    np.testing.assert_array_equal(pos, before)
    np.testing.assert_array_equal(yaw, yaw_before)


def test_open_edges_follow_a_clockwise_polygon():
    # Given clockwise, the corners are reversed: edge 0 ((0,0)->(0,10)) becomes edge 2.
    b = LayoutBuilder([[0, 0], [0, 10], [10, 10], [10, 0]], open_edges=[0])
    np.testing.assert_array_equal(b.polygon_m, [[10, 0], [10, 10], [0, 10], [0, 0]])
    np.testing.assert_array_equal(b.edge_wall, [True, True, False, True])


@pytest.mark.parametrize("bad", [4, -1, 1.5, "2"])
def test_open_edge_that_is_no_edge_is_refused(bad):
    with pytest.raises(LayoutError, match=r"room.open_edges: .* is not an edge number 0-3"):
        LayoutBuilder(ROOM, open_edges=[bad])
