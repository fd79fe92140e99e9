"""SA-McMC: the comparison method, not Stager's solver.

Simulated annealing with a Metropolis–Hastings state search, after Yu et al. 2011
("Make it Home") as Weiss et al. 2018 Sec. 4.3 ran it against their position-based
solver: each step proposes a change of one attribute of one body (a translation or a
rotation, or a swap of two bodies' positions), accepts it with probability
min(1, exp(−ΔE / T)), and lowers T linearly over about 20,000 evenly spaced steps; it
stops early when the best energy improved by less than 0.1 % over the last 1,500.

The energy is exactly the PBD solver's (:func:`layout.energy_terms`, Eq. 1), evaluated
in full after every proposal, with the same numba kernels and a Verlet pair list; an
incremental energy (only the terms of the moved body) would make each step cheaper
and is left out, as in the paper's implementation.

>>> from layout import LayoutBuilder
>>> from layout.annealing import Annealer
>>> b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]])
>>> bed = b.add_item("bed", (1.6, 2.1, 0.5))
>>> layout = Annealer(iterations=2000).solve(b.finalize(), seed=0)
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import _codes as codes
from . import _kernels as K
from .errors import LayoutError
from .model import Model, State
from .geometry import polygon_area
from .solver import Layout, _cell_size, energy_terms, initial_state


@dataclass(frozen=True)
class Annealer:
    """Settings of the SA-McMC baseline.

    Parameters
    ----------
    iterations : length of the linear annealing schedule (proposals).
    t_start : starting temperature as a fraction of the initial energy; T falls
        linearly to 0 over ``iterations``.
    step_m : standard deviation of a translation at the start, as a fraction of the
        square root of the floor area; it shrinks with T down to 2 % of that.
    step_rad : standard deviation of a rotation at the start (shrinks likewise).
    p_rotate, p_swap : probability of a rotation and of a swap proposal (the rest
        are translations).
    window, min_gain : stop when the best energy improved by less than the fraction
        ``min_gain`` over the last ``window`` proposals (the paper: 0.1 %, 1,500).
    collision : "box" or "sphere", as for :class:`layout.Solver`.
    pad_m : padding of the pair list (rebuilt when a body has moved by half of it).
    """

    iterations: int = 20_000
    t_start: float = 0.001
    step_m: float = 0.1
    step_rad: float = 0.5
    p_rotate: float = 0.3
    p_swap: float = 0.1
    window: int = 1500
    min_gain: float = 1e-3
    collision: str = "box"
    pad_m: float = 0.3

    def __post_init__(self):
        if self.collision not in codes.COLLISION_NAMES:
            raise LayoutError(f"annealer.collision: {self.collision!r} is not 'box' or 'sphere'")
        for name in ("iterations", "window"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise LayoutError(f"annealer.{name}: {value!r} must be an integer >= 1")
        if not (self.p_rotate >= 0 and self.p_swap >= 0 and self.p_rotate + self.p_swap <= 1):
            raise LayoutError("annealer.p_rotate, p_swap: must be >= 0 and add up to at most 1")
        for name in ("t_start", "step_m", "step_rad", "pad_m"):
            if not getattr(self, name) > 0:
                raise LayoutError(f"annealer.{name}: {getattr(self, name)!r} must be > 0")

    def solve(self, model: Model, seed=None, state: State | None = None) -> Layout:
        """Anneal from a random start drawn with ``seed`` (or from ``state``).

        Returns the best layout seen; its ``trace`` is the energy of the current state
        after every proposal (index 0: the start) and ``iterations`` the proposals made.
        """
        rng = np.random.default_rng(seed)
        start = initial_state(model, rng) if state is None else state.copy()
        bodies = np.flatnonzero(
            (model.particle_body == np.arange(model.n))
            & (model.particle_inv_mass > 0)
            & (model.particle_role != codes.OBSTACLE)
        ).astype(np.int64)
        if len(bodies) == 0:
            raise LayoutError("annealer: the layout has nothing that may move")
        step = self.step_m * math.sqrt(abs(polygon_area(model.floor_polygon_m)))
        t0 = time.perf_counter()
        pos, yaw, trace, best_it, iters = _anneal(
            model.packed(),
            np.ascontiguousarray(start.position_m, dtype=np.float64),
            np.ascontiguousarray(start.yaw_rad, dtype=np.float64),
            bodies,
            self.iterations,
            float(self.t_start),
            float(step),
            float(self.step_rad),
            float(self.p_rotate),
            float(self.p_swap),
            self.window,
            float(self.min_gain),
            int(rng.integers(2**31 - 1)),
            codes.COLLISION_NAMES[self.collision],
            np.array(codes.ENERGY_WEIGHTS),
            _cell_size(model),
            float(self.pad_m),
        )
        elapsed = time.perf_counter() - t0
        terms = energy_terms(model, State(pos, yaw), self.collision)
        return Layout.from_state(model, pos, yaw, terms, trace, iters, best_it, seed, elapsed)


@njit(cache=True, error_model="numpy")
def _move(b, dx, dy, da, pos, yaw, mstart, mlist):
    """Move body b and its rigid members (a proposal)."""
    if K.move(b, dx, dy, 0.0, da, pos, yaw, mstart):
        K.carry(b, dx, dy, 0.0, da, pos, yaw, mstart, mlist)


@njit(cache=True, error_model="numpy")
def _copy_body(b, src_pos, src_yaw, mstart, mlist, dst_pos, dst_yaw):
    """Copy the pose of body b and its rigid members (to save or to restore it)."""
    dst_pos[b] = src_pos[b]
    dst_yaw[b] = src_yaw[b]
    for q in range(mstart[b], mstart[b + 1]):
        m = mlist[q]
        dst_pos[m] = src_pos[m]
        dst_yaw[m] = src_yaw[m]


@njit(cache=True, error_model="numpy")
def _shift(b, pos, ref_pos, mstart, mlist):
    """How far body b or one of its rigid members is from its pose in the pair list."""
    d = math.sqrt((pos[b, 0] - ref_pos[b, 0]) ** 2 + (pos[b, 1] - ref_pos[b, 1]) ** 2)
    for q in range(mstart[b], mstart[b + 1]):
        m = mlist[q]
        d = max(d, math.sqrt((pos[m, 0] - ref_pos[m, 0]) ** 2 + (pos[m, 1] - ref_pos[m, 1]) ** 2))
    return d


@njit(cache=True, error_model="numpy")
def _anneal(M, pos, yaw, bodies, iterations, t_start, step_m, step_rad, p_rotate, p_swap, window, min_gain, seed,
            model, weights, cell_m, pad_m):
    np.random.seed(seed)
    P = M[0]
    mstart = P.mstart
    mlist = P.mlist
    n = pos.shape[0]
    reach = np.empty(n)
    for i in range(n):
        reach[i] = P.radius[i] + P.access_max[i]
    pairs = K.candidate_pairs(P, pos, yaw, cell_m, pad_m)
    cs = np.empty((n, 2))
    K.trig(yaw, cs)
    cs_yaw = yaw.copy()
    ref_pos = pos.copy()
    ref_yaw = yaw.copy()
    keep_pos = pos.copy()
    keep_yaw = yaw.copy()
    e = math.sqrt(K.energy_terms(M, pos, yaw, cs, pairs, model, weights).sum())
    temp0 = t_start * max(e, 1e-9)
    best_e = e
    best_pos = pos.copy()
    best_yaw = yaw.copy()
    best_it = 0
    trace = np.empty(iterations + 1)
    best_trace = np.empty(iterations + 1)
    trace[0] = e
    best_trace[0] = e
    it = 0
    while it < iterations:
        it += 1
        cool = 1.0 - (it - 1) / iterations
        temp = temp0 * cool
        shrink = 0.02 + 0.98 * cool
        b = bodies[np.random.randint(bodies.shape[0])]
        b2 = -1
        u = np.random.random()
        _copy_body(b, pos, yaw, mstart, mlist, keep_pos, keep_yaw)
        if u < p_swap and bodies.shape[0] > 1:
            b2 = bodies[np.random.randint(bodies.shape[0])]
            if b2 == b:
                b2 = -1
            else:
                _copy_body(b2, pos, yaw, mstart, mlist, keep_pos, keep_yaw)
                dx = pos[b2, 0] - pos[b, 0]
                dy = pos[b2, 1] - pos[b, 1]
                _move(b, dx, dy, 0.0, pos, yaw, mstart, mlist)
                _move(b2, -dx, -dy, 0.0, pos, yaw, mstart, mlist)
        elif u < p_swap + p_rotate:
            _move(b, 0.0, 0.0, np.random.normal() * step_rad * shrink, pos, yaw, mstart, mlist)
        else:
            s = step_m * shrink
            _move(b, np.random.normal() * s, np.random.normal() * s, 0.0, pos, yaw, mstart, mlist)
        # Keep the pair list valid for the proposed state: a rotation swings the
        # clearance boxes at the body's reach.
        moved = _shift(b, pos, ref_pos, mstart, mlist) + reach[b] * abs(yaw[b] - ref_yaw[b])
        if b2 >= 0:
            moved = max(moved, _shift(b2, pos, ref_pos, mstart, mlist))
        rebuilt = moved > 0.5 * pad_m
        if rebuilt:
            pairs = K.candidate_pairs(P, pos, yaw, cell_m, pad_m)
            ref_pos[:] = pos
            ref_yaw[:] = yaw
        K.trig_update(yaw, cs, cs_yaw)
        e_new = math.sqrt(K.energy_terms(M, pos, yaw, cs, pairs, model, weights).sum())
        d_e = e_new - e
        if d_e <= 0.0 or (temp > 0.0 and np.random.random() < math.exp(-d_e / temp)):
            e = e_new
            if e < best_e:
                best_e = e
                best_it = it
                best_pos[:] = pos
                best_yaw[:] = yaw
        else:
            _copy_body(b, keep_pos, keep_yaw, mstart, mlist, pos, yaw)
            if b2 >= 0:
                _copy_body(b2, keep_pos, keep_yaw, mstart, mlist, pos, yaw)
            if rebuilt:
                pairs = K.candidate_pairs(P, pos, yaw, cell_m, pad_m)
                ref_pos[:] = pos
                ref_yaw[:] = yaw
        trace[it] = e
        best_trace[it] = best_e
        # The paper's extra stop rule.
        if it >= window and best_trace[it - window] - best_e <= min_gain * best_trace[it - window]:
            break
    return best_pos, best_yaw, trace[: it + 1], best_it, it
