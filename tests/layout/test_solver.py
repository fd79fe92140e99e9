"""The solver end to end: the paper's scenarios, determinism, groups, modes, bad input."""
import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from layout import LayoutBuilder, LayoutError, Solver, State, diversity, residuals
from layout._kernels import inside_polygon
from layout.geometry import box_corners, polygon_area
from layout.metrics import box_overlaps
from layout.report import evaluate
from layout.solver import _deepest_intrusion_m, _random_inside, _stratified_inside, initial_state
from layout.spec import build, load_spec

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def _clean(layout):
    ev = evaluate(layout)
    return ev["overlaps"]["count"] == 0 and ev["outside_m2"] == 0.0 and ev["traversable"], ev


@pytest.mark.parametrize(
    "name,seeds",
    [("living_room", (0, 1)), ("desk", (0, 1)), ("tp_bedroom", (0, 2, 4)), ("tp_picnic", (0,)), ("picnic", (0,)),
     ("theater", (0,)), ("l_shaped_office", (0, 1))],
)
def test_paper_scenarios_solve_clean(name, seeds):
    # tp_bedroom seed 4 needs more than 11 runs: none of its first 11 is clean and walkable.
    model, solver = build(load_spec(SAMPLES / f"{name}.toml"))
    for seed in seeds:
        ok, ev = _clean(solver.solve(model, seed=seed))
        assert ok, (name, seed, ev["overlaps"], ev["outside_items"], ev["unreachable"])


def test_same_seed_same_layout_other_seed_other_layout():
    model, solver = build(load_spec(SAMPLES / "living_room.toml"))
    a, b, c = solver.solve(model, seed=3), solver.solve(model, seed=3), solver.solve(model, seed=4)
    np.testing.assert_array_equal(a.position_m, b.position_m)
    np.testing.assert_array_equal(a.yaw_rad, b.yaw_rad)
    assert a.energy == b.energy and a.iterations == b.iterations
    assert np.abs(a.position_m - c.position_m).max() > 0.1
    suggestions = solver.suggest(model, 3, seed=3)
    np.testing.assert_array_equal(suggestions[0].position_m, a.position_m)
    assert diversity(suggestions) > 0.1


def test_rigid_group_members_keep_their_offsets():
    model, solver = build(load_spec(SAMPLES / "tp_picnic.toml"))
    layout = solver.solve(model, seed=0)
    names = list(model.names)
    table = names.index("table_1")
    for c, (ox, oy) in enumerate([(0.8, 0), (0, 0.8), (-0.8, 0), (0, -0.8)]):
        chair = names.index(f"chair_1_{c + 1}")
        yaw = layout.yaw_rad[table]
        expect = layout.position_m[table, :2] + [ox * math.cos(yaw) - oy * math.sin(yaw),
                                                 ox * math.sin(yaw) + oy * math.cos(yaw)]
        np.testing.assert_allclose(layout.position_m[chair, :2], expect, atol=1e-9)


def test_non_rigid_tier_members_sit_on_their_arc_in_order():
    model, solver = build(load_spec(SAMPLES / "theater.toml"))
    layout = solver.solve(model, seed=1)
    names = list(model.names)
    c = next(k for k in range(len(model.curve_group)) if names[model.curve_group[k]] == "center_3")
    g = model.curve_group[c]
    members = model.curve_members[model.curve_start[c]:model.curve_start[c + 1]]
    cx, cy, radius = model.curve_params[c][:3]
    center = layout.position_m[g, :2]  # the arc's center is the group's origin here
    assert (cx, cy) == (0.0, 0.0)
    r = np.linalg.norm(layout.position_m[members, :2] - center, axis=1)
    np.testing.assert_allclose(r, radius, atol=0.05)
    # Neighbours along the arc keep the tier's spacing.
    ang = np.sort(np.arctan2(*(layout.position_m[members, :2] - center).T[::-1]))
    np.testing.assert_allclose(np.diff(ang) * radius, model.curve_spacing_m[c], atol=0.05)


def test_l_shaped_room_keeps_everything_inside_and_off_the_notch():
    b = LayoutBuilder([[0, 0], [6, 0], [6, 3], [3, 3], [3, 6], [0, 6]], 2.6)
    b.add_door((1.5, 0.0), 0.9)
    for k in range(6):
        i = b.add_item(f"box{k}", (1.2, 0.6, 1.0), access_m=(0, 0, 0.6, 0))
        b.against_wall(i)
    layout = Solver().solve(b.finalize(), seed=0)
    ok, ev = _clean(layout)
    assert ok, ev


@pytest.mark.parametrize("overrides", [dict(method="jacobi"), dict(collision="sphere")])
def test_jacobi_and_sphere_modes_solve_the_living_room(overrides):
    model, solver = build(load_spec(SAMPLES / "living_room.toml"))
    solver = dataclasses.replace(solver, **overrides)
    results = [_clean(solver.solve(model, seed=s))[0] for s in range(3)]
    assert sum(results) >= 2


def test_restarts_are_reported_and_paper_mode_runs_once():
    model, solver = build(load_spec(SAMPLES / "tp_bedroom.toml"))
    paper = dataclasses.replace(solver, restarts=0)
    runs = [paper.solve(model, seed=s).runs for s in range(3)]
    assert runs == [1, 1, 1]
    assert max(solver.solve(model, seed=s).runs for s in range(6)) > 1


def test_energy_trace_and_best_layout():
    model, solver = build(load_spec(SAMPLES / "living_room.toml"))
    paper = dataclasses.replace(solver, restarts=0, polish_rounds=0)
    gains = []
    for seed in range(5):
        layout = paper.solve(model, seed=seed)
        assert len(layout.trace) == layout.iterations + 1
        # The returned layout is the best seen: its energy is the trace's minimum.
        assert math.isclose(layout.energy, np.nanmin(layout.trace), rel_tol=1e-9)
        gains.append(layout.trace[0] / layout.energy)
    # Some starts end in a worse local minimum (about half of them in this room,
    # over 150 seeds), but every run gains a lot, and typically tenfold.
    assert min(gains) > 3 and np.median(gains) > 10


def test_builder_never_modifies_inputs():
    poly = np.array([[0, 0], [0, 4], [5, 4], [5, 0]], dtype=float)  # clockwise
    size = np.array([1.0, 0.5, 0.8])
    before = poly.copy(), size.copy()
    b = LayoutBuilder(poly)
    b.add_item("a", size)
    model = b.finalize()
    np.testing.assert_array_equal(poly, before[0])
    np.testing.assert_array_equal(size, before[1])
    assert polygon_area(model.floor_polygon_m) > 0  # stored counter-clockwise


def _two_items():
    b = LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]])
    b.add_item("a", (0.5, 0.5, 0.5))
    b.add_item("b", (0.5, 0.5, 0.5))
    return b


def _stacked_in_a_loop():
    b = _two_items()
    b.add_item("c", (0.3, 0.3, 0.3))
    b.stack(1, 2)  # c on b
    b.stack(0, 1)  # b on a
    b.stack(2, 0)  # a on c: round in a loop


@pytest.mark.parametrize(
    "make,message",
    [
        (lambda: LayoutBuilder([[0, 0], [1, 1]]), "at least 3 vertices"),
        (lambda: LayoutBuilder([[0, 0], [2, 2], [2, 0], [0, 2]]), "intersect"),
        (lambda: LayoutBuilder([[0, 0], [1, 0], [np.nan, 1]]), "finite"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 0], [4, 3], [0, 3]]), r"corners 1 and 2 are the same point \[4"),
        # Millimeters typed as meters: 4 km across (a 1e12 m room ended in a 1e26-cell grid).
        (lambda: LayoutBuilder([[0, 0], [4000, 0], [4000, 3000], [0, 3000]]), "4000 m across.*not millimeters"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]]).add_item("a", (1, -1, 1)), "greater than 0"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]]).add_item("a", (1, np.nan, 1)), "not a finite"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]]).distance(0, 1, 1.0), "no item or group"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]], 2.5).add_item("tall", (1, 1, 3)), "exceeds the room"),
        (lambda: Solver(method="newton"), "gauss-seidel"),
        # A lane 1e300 m long overflowed the energies (an empty trace crashed the plot).
        (lambda: _two_items().lane(0, [1], angle_rad=0.0, length_m=1e300, half_width_m=1.0), "lane length: 1e\\+300 is beyond any room"),
        (lambda: _two_items().distance(0, 1, 5000.0), "at most 1000"),
        (lambda: LayoutBuilder([[0, 0], [4, 0], [4, 4], [0, 4]]).add_item("a", (1, 1, 1), position_m=(1e9, 0)),
         "position.*beyond any room"),
        (lambda: _stacked_in_a_loop(), "'a' on 'c', which already rests on 'a'.*loop"),
        (lambda: Solver(restarts=-1), "restarts"),
    ],
)
def test_bad_input_raises_one_clear_error(make, message):
    with pytest.raises(LayoutError, match=message):
        make()


def test_items_that_cannot_fit():
    b = LayoutBuilder([[0, 0], [2, 0], [2, 2], [0, 2]])
    b.add_item("huge", (1.9, 1.9, 1))
    b.add_item("other", (1.0, 1.0, 1))
    with pytest.raises(LayoutError, match="add up to"):
        b.finalize()
    b = LayoutBuilder([[0, 0], [2, 0], [2, 2], [0, 2]])
    b.add_item("long", (0.5, 3.5, 1))
    with pytest.raises(LayoutError, match="does not fit"):
        b.finalize()


def test_residuals_by_kind_match_the_energy():
    model, solver = build(load_spec(SAMPLES / "living_room.toml"))
    layout = solver.solve(model, seed=2)
    res = residuals(model, State(layout.position_m, layout.yaw_rad))
    assert len(res["distance"]) == len(model.distance_rest_m)
    assert len(res["orientation"]) == len(model.orientation_mode)
    # The access energy also counts clearances leaving the floor; every other kind is
    # exactly g_j times the sum of its squared residuals.
    from layout._codes import ENERGY_WEIGHTS, KINDS
    for kind, g in zip(KINDS, ENERGY_WEIGHTS):
        if kind != "access":
            assert math.isclose(g * float((res[kind] ** 2).sum()), layout.energy_by_kind[kind], rel_tol=1e-9, abs_tol=1e-12)


def _crowd(n, seed):
    """n boxes of 0.4-1.0 m with a front clearance on a square floor they cover to
    30 %, in pairs kept within 1.5 m."""
    rng = np.random.default_rng(seed)
    size = rng.uniform(0.4, 1.0, size=(n, 2))
    side = float(np.sqrt((size[:, 0] * size[:, 1]).sum() / 0.3))
    b = LayoutBuilder([[0, 0], [side, 0], [side, side], [0, side]])
    items = [b.add_item(f"box_{i}", (w, d, 0.8), access_m=(0, 0, 0.3, 0)) for i, (w, d) in enumerate(size)]
    for i in range(0, n - 1, 2):
        b.distance(items[i], items[i + 1], 1.5, mode="max")
    return b.finalize()


def test_two_threads_are_reproducible_and_clean():
    """With ``threads_from`` boxes or more the pair passes run on two threads: the
    result must not depend on their timing, and the layout must still be clean."""
    n = 600
    model = _crowd(n, 3)
    threaded = Solver(restarts=0, threads_from=n)
    runs = [threaded.solve(model, seed=5) for _ in range(3)]
    for again in runs[1:]:
        np.testing.assert_array_equal(runs[0].position_m, again.position_m)
        np.testing.assert_array_equal(runs[0].trace, again.trace)
    # The threads change the order of the projections, so the layout differs from
    # the one-thread run's, but it is as good.
    single = Solver(restarts=0).solve(model, seed=5)
    assert not np.array_equal(single.position_m, runs[0].position_m)
    for layout in (runs[0], single):
        ev = evaluate(layout)
        assert ev["overlaps"]["count"] == 0 and ev["outside_m2"] == 0.0
        assert layout.energy < 0.05 * layout.trace[0]


def test_runs_counts_every_run_taken_when_none_is_clean():
    # Two 1.9 m squares in a 3 m room always overlap: every restart is used.
    b = LayoutBuilder([[0, 0], [3, 0], [3, 3], [0, 3]])
    b.add_item("a", (1.9, 1.9, 0.5))
    b.add_item("b", (1.9, 1.9, 0.5))
    layout = Solver(restarts=3, max_iterations=150).solve(b.finalize(), seed=0)
    assert evaluate(layout)["overlaps"]["count"] == 1
    assert layout.runs == 4


def test_deepest_intrusion_into_a_clearance_by_hand():
    # A 1.4 x 2.0 m bed at (2, 2) facing +x: its 0.6 m front clearance spans x 3.0-3.6,
    # y 1.3-2.7. A 0.4 m stool centered at x = 3.55 covers x 3.35-3.75: 0.25 m inside
    # (the clearance's far edge is the shallowest way out); at x = 3.7, 0.1 m; at 3.85, none.
    b = LayoutBuilder([[0, 0], [6, 0], [6, 4], [0, 4]])
    b.add_item("bed", (1.4, 2.0, 0.5), access_m=(0, 0, 0.6, 0))
    b.add_item("stool", (0.4, 0.4, 0.5))
    model = b.finalize()
    for x, depth in ((3.55, 0.25), (3.7, 0.1), (3.85, 0.0)):
        pos = np.array([[2.0, 2.0, 0.25], [x, 2.0, 0.25]])
        assert _deepest_intrusion_m(model, State(pos, np.zeros(2)), "box") == pytest.approx(depth, abs=1e-9)
    # Behind the bed, which has no clearance there: none.
    pos = np.array([[2.0, 2.0, 0.25], [0.45, 2.0, 0.25]])
    assert _deepest_intrusion_m(model, State(pos, np.zeros(2)), "box") == 0.0


def test_stratified_start_puts_one_point_in_each_cell():
    square = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    points = _stratified_inside(square, 100, np.random.default_rng(0))
    # Cells of 1 m: all 100 are taken (a uniform sample leaves about a third empty).
    assert len(np.unique(np.floor(points).astype(int), axis=0)) == 100
    uniform = _random_inside(square, 100, np.random.default_rng(0))
    assert len(np.unique(np.floor(uniform).astype(int), axis=0)) < 80
    ell = np.array([[0, 0], [6, 0], [6, 2], [2, 2], [2, 6], [0, 6]], float)
    points = _stratified_inside(ell, 50, np.random.default_rng(1))
    assert points.shape == (50, 2)
    assert all(inside_polygon(ell, x, y) for x, y in points)
    assert len(np.unique(points, axis=0)) == 50


def test_a_crowd_starts_stratified_and_settles_lower():
    model = _crowd(300, 4)
    size = model.particle_size_m[model.items]
    z = np.stack([np.zeros(len(size)), size[:, 2]], axis=1)
    energies = {}
    for stratify_from in (10**9, 100):  # the paper's uniform start, then Stager's
        solver = Solver(restarts=0, stratify_from=stratify_from)
        energies[stratify_from] = [solver.solve(model, seed=seed).energy for seed in range(8)]
    for seed in range(8):
        overlaps = []
        for stratify_from in (10**9, 100):
            start = initial_state(model, np.random.default_rng(seed), stratify_from=stratify_from)
            corners = box_corners(start.position_m[model.items, :2], start.yaw_rad[model.items], size[:, 0], size[:, 1])
            overlaps.append(len(box_overlaps(corners, z, np.ones(len(size), bool))[0]))
        assert overlaps[1] < overlaps[0], (seed, overlaps)
    # Partners and clearances settle better from the spread start (measured: median
    # 0.88 against 1.24, lower in 6 of 8).
    assert np.median(energies[100]) < 0.85 * np.median(energies[10**9]), energies
