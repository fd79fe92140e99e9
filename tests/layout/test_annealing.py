"""The SA-McMC baseline: it lowers the energy, obeys its stop rule, and is reproducible."""
import numpy as np
import pytest

from layout import LayoutBuilder, LayoutError, Solver, State
from layout.annealing import Annealer
from layout.report import evaluate
from layout.solver import ACCESS_CLEAR_M, _deepest_intrusion_m


def _tiny(seed=0):
    """A bed against a wall, a nightstand within 1.6 m of it and a desk against a wall
    in a 4 x 3 m room, all three starting within 0.3 m of the room's center."""
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]])
    bed = b.add_item("bed", (1.4, 2.0, 0.5), access_m=(0, 0, 0.6, 0))
    stand = b.add_item("nightstand", (0.4, 0.4, 0.5))
    desk = b.add_item("desk", (1.2, 0.6, 0.75), access_m=(0, 0, 0.6, 0))
    b.against_wall(bed)
    b.distance(bed, stand, 1.6, mode="max")
    b.against_wall(desk)
    model = b.finalize()
    rng = np.random.default_rng(seed)
    pos = np.zeros((model.n, 3))
    pos[:, :2] = [2.0, 1.5] + rng.uniform(-0.3, 0.3, size=(model.n, 2))
    pos[:, 2] = 0.5 * model.particle_size_m[:, 2]
    return model, State(pos, rng.uniform(-np.pi, np.pi, size=model.n))


# From starts 1 and 7 one PBD run stalls with the nightstand in the bed's front
# clearance, held there by its maximum distance (a local minimum, see the README); SA
# escapes it, and so do Stager's restarts (below). Starts 0 and 2 check that both
# methods descend.
@pytest.mark.parametrize("seed", [0, 2])
def test_both_methods_lower_the_energy_from_the_same_start(seed):
    model, start = _tiny(seed)
    sa = Annealer().solve(model, seed=seed, state=start)
    pbd = Solver(restarts=0).solve(model, seed=seed, state=start)
    e0 = sa.trace[0]
    assert e0 > 10.0  # the pile collides: weight 150 on the penetrations
    assert sa.energy < 0.1 * e0
    assert pbd.energy < 0.1 * e0
    # The returned layout is the best state SA visited.
    assert sa.energy == pytest.approx(sa.trace.min(), rel=1e-9)


def test_restarts_leave_a_nightstand_stuck_in_the_beds_clearance():
    # Start 7: nothing collides and every side is reachable, so only the clearance
    # tells that the run is stuck.
    model, start = _tiny(7)
    paper = Solver(restarts=0).solve(model, seed=7, state=start)
    assert paper.runs == 1
    assert evaluate(paper)["traversable"] and evaluate(paper)["overlaps"]["count"] == 0
    assert _deepest_intrusion_m(model, paper, "box") > 0.4
    layout = Solver().solve(model, seed=7, state=start)
    assert layout.runs > 1
    assert _deepest_intrusion_m(model, layout, "box") <= ACCESS_CLEAR_M
    assert layout.energy < 0.01 * paper.energy


def test_sa_stops_by_the_papers_rule_and_not_before():
    model, start = _tiny()
    window = 300
    layout = Annealer(iterations=20_000, window=window).solve(model, seed=1, state=start)
    assert layout.iterations < 20_000
    best = np.minimum.accumulate(layout.trace)
    it = layout.iterations
    assert len(layout.trace) == it + 1
    # At the stop the best energy improved by at most 0.1 % over the last window ...
    assert best[it - window] - best[it] <= 1e-3 * best[it - window]
    # ... and one proposal earlier it still had not met that rule.
    assert best[it - 1 - window] - best[it - 1] > 1e-3 * best[it - 1 - window]


def test_sa_runs_its_whole_schedule_when_the_window_is_longer():
    model, start = _tiny()
    layout = Annealer(iterations=500, window=1500).solve(model, seed=2, state=start)
    assert layout.iterations == 500


def test_sa_is_reproducible_and_rejects_bad_settings():
    model, start = _tiny()
    a = Annealer(iterations=800).solve(model, seed=5, state=start)
    b = Annealer(iterations=800).solve(model, seed=5, state=start)
    np.testing.assert_array_equal(a.position_m, b.position_m)
    np.testing.assert_array_equal(a.trace, b.trace)
    with pytest.raises(LayoutError, match="iterations"):
        Annealer(iterations=0)
    with pytest.raises(LayoutError, match="p_rotate"):
        Annealer(p_rotate=0.8, p_swap=0.5)
