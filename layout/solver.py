"""The position-based layout solver (Weiss et al. 2018, Algorithm 1).

>>> from layout import LayoutBuilder, Solver
>>> b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]])
>>> bed = b.add_item("bed", (1.6, 2.1, 0.5))
>>> b.against_wall(bed)
>>> layout = Solver().solve(b.finalize(), seed=0)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from . import _codes as codes
from . import _kernels as K
from .errors import LayoutError
from .geometry import box_corners, polygon_area
from .metrics import walkability
from .model import Model, State

# Thesis Table 5.1: which constraints are projected in each of six interleaved
# iterations (columns: wall, others, collision).
TABLE_5_1 = (
    (False, False, True),
    (False, True, True),
    (True, False, True),
    (False, True, True),
    (False, False, True),
    (True, True, True),
)


# Kinds that make a layout unusable when violated, and the weighted energy below which
# they count as satisfied (about a millimetre of penetration).
HARD_KINDS = ("collision", "boundary")
HARD_CLEAN = 1e-4

# An item deeper than this (m) in another's clearance spoils a suggestion even when
# nothing collides: a nightstand held in front of its bed by its maximum distance, a
# local minimum PBD does not leave. Such a run counts as unusable and is restarted.
ACCESS_CLEAR_M = 0.10

# From this many items placed at random, the start is stratified (see initial_state).
STRATIFY_FROM = 100


@dataclass(frozen=True)
class Layout:
    """One solved layout.

    Attributes
    ----------
    model : the problem it solves.
    position_m : (n, 3) float64 — center of every particle (items, groups, obstacles).
    yaw_rad : (n,) float64 — facing direction, wrapped to [-pi, pi).
    energy : float — E of Eq. (1) for this layout.
    energy_by_kind : dict of kind -> g_j Σ C_j² (the squared terms before the root).
    trace : (t,) float64 — energy before each iteration.
    iterations, best_iteration : iterations run, and the one whose state was returned.
    seed : the seed of the random start.
    time_s : wall time of the solve (JIT compile excluded once warm).
    degenerate : dict of kind -> projections skipped for a zero-length direction.
    runs : random starts it took (see ``Solver.restarts``).
    """

    model: Model
    position_m: np.ndarray
    yaw_rad: np.ndarray
    energy: float
    energy_by_kind: dict
    trace: np.ndarray
    iterations: int
    best_iteration: int
    seed: int | None
    time_s: float
    degenerate: dict = field(default_factory=dict)
    runs: int = 1

    @classmethod
    def from_state(cls, model, pos, yaw, terms, trace, iterations, best_iteration, seed, time_s, **extra):
        """A Layout from solver state: yaw wrapped to [-pi, pi), energy from its terms."""
        return cls(
            model=model,
            position_m=pos,
            yaw_rad=(yaw + np.pi) % (2.0 * np.pi) - np.pi,
            energy=float(np.sqrt(sum(terms.values()))),
            energy_by_kind=terms,
            trace=trace,
            iterations=int(iterations),
            best_iteration=int(best_iteration),
            seed=None if seed is None else int(seed),
            time_s=time_s,
            **extra,
        )

    @property
    def items(self) -> np.ndarray:
        return self.model.items

    def corners_m(self, indices=None) -> np.ndarray:
        """(k, 4, 2) footprint corners of the given particles (default: the items)."""
        idx = self.items if indices is None else np.asarray(indices)
        size = self.model.particle_size_m[idx]
        return box_corners(self.position_m[idx, :2], self.yaw_rad[idx], size[:, 0], size[:, 1])

    def as_written(self) -> Layout:
        """This layout with the items' positions and yaws as :meth:`to_dict` writes them
        (:data:`WRITTEN_DECIMALS`): what is rendered from it, a layout file read back
        renders to the very same pixels (a micrometre can flip a rounding in a render)."""
        pos, yaw = self.position_m.copy(), self.yaw_rad.copy()
        for i in self.items:
            pos[i] = [_written(v) for v in pos[i]]
            yaw[i] = _written(yaw[i])
        return replace(self, position_m=pos, yaw_rad=yaw)

    def to_dict(self) -> dict:
        """JSON-ready description: room, doors, windows and items (meters, radians)."""
        m = self.model
        return {
            "room": {
                "polygon_m": m.floor_polygon_m.tolist(),
                "open_edges": [int(e) for e in np.flatnonzero(~m.floor_edge_wall)],
                "height_m": m.wall_height_m,
                "doors_m": m.door_segments_m.tolist(),
                "windows_m": m.window_segments_m.tolist(),
            },
            "items": [
                {
                    "id": m.names[i],
                    "kind": m.kinds[i],
                    "position_m": [_written(v) for v in self.position_m[i]],
                    "yaw_rad": _written(self.yaw_rad[i]),
                    "size_m": [float(v) for v in m.particle_size_m[i]],
                    "group": m.names[m.particle_parent[i]] if m.particle_parent[i] >= 0 else None,
                }
                for i in self.items
            ],
            "energy": self.energy,
            "seed": self.seed,
            "iterations": self.iterations,
        }


# Decimals of the meters and radians in a layout file: micrometres, microradians.
WRITTEN_DECIMALS = 6


def _written(v) -> float:
    # Python's round is correctly rounded, so rounding what it gave changes nothing.
    return round(float(v), WRITTEN_DECIMALS)


def _inside(polygon_m, points_m):
    """(k,) bool: which of the (k, 2) points lie inside the polygon (even-odd rule)."""
    return K.points_inside(np.ascontiguousarray(polygon_m, dtype=np.float64),
                           np.ascontiguousarray(points_m, dtype=np.float64).reshape(-1, 2))


def _random_inside(polygon_m, k, rng):
    """k points uniformly distributed inside a simple polygon (rejection sampling)."""
    lo, hi = polygon_m.min(0), polygon_m.max(0)
    out = np.empty((0, 2))
    while len(out) < k:
        cand = rng.uniform(lo, hi, size=(max(16, 2 * (k - len(out))), 2))
        out = np.concatenate([out, cand[_inside(polygon_m, cand)]])
    return out[:k]


def _stratified_inside(polygon_m, k, rng):
    """k random points inside a simple polygon, one per cell of a square grid whose
    cells (about ``area / k`` each) are drawn at random: jittered-grid sampling."""
    lo, hi = polygon_m.min(0), polygon_m.max(0)
    cell = np.sqrt(polygon_area(polygon_m) / k)
    while True:
        gx, gy = np.meshgrid(np.arange(lo[0], hi[0], cell), np.arange(lo[1], hi[1], cell))
        cand = np.stack([gx.ravel(), gy.ravel()], axis=1) + rng.uniform(0.0, cell, size=(gx.size, 2))
        keep = _inside(polygon_m, cand)
        if keep.sum() >= k:
            return cand[keep][rng.choice(int(keep.sum()), k, replace=False)]
        # Cells cut by the outline often lose their point: a finer grid has enough.
        cell *= 0.95


def initial_state(model: Model, rng: np.random.Generator, stratify_from: int = STRATIFY_FROM) -> State:
    """Random start (Algorithm 1, line 2) for every free body.

    Positions are uniform on the floor, as in the paper, when fewer than
    ``stratify_from`` bodies need one (curve members, which start on their curve,
    not counted). From that many on (beyond the paper) they are stratified, one per
    random cell of a grid (:func:`_stratified_inside`): a uniform start piles a crowd
    onto itself, and separating it pulls partners apart, while in a furnished room of a
    few items the paper's start solves better (docs/layout.md).

    Particles with a start pose in the model keep it; rigid-group members follow their
    group; stacked items start on their base.
    """
    n = model.n
    pos = model.particle_init_position_m.copy()
    yaw = model.particle_init_yaw_rad.copy()
    free = model.particle_body == np.arange(n)
    need_xy = free & np.isnan(pos[:, 0])
    k = int(need_xy.sum())
    # Curve members are put on their curve below: only the others' spread matters.
    on_curve = np.zeros(n, bool)
    on_curve[model.curve_members] = True
    sample = _stratified_inside if (need_xy & ~on_curve).sum() >= max(1, stratify_from) else _random_inside
    pos[need_xy, :2] = sample(model.floor_polygon_m, k, rng)
    need_yaw = free & np.isnan(yaw)
    yaw[need_yaw] = rng.uniform(-np.pi, np.pi, size=int(need_yaw.sum()))
    pos[~free] = 0.0
    yaw[~free] = 0.0
    _start_near_partners(model, pos, need_xy, rng)
    _start_on_curves(model, pos, yaw, rng)
    P = model.packed()[0]
    K.sync_members(P, pos, yaw)
    for base, top in model.stack_pairs:
        if model.particle_body[top] == top:
            pos[top, :2] = pos[base, :2]
            pos[top, 2] = pos[base, 2] + 0.5 * (model.particle_size_m[base, 2] + model.particle_size_m[top, 2])
    return State(pos, yaw)


def turned_state(layout: Layout, angle_rad: float, mirror: bool = False) -> State:
    """A start for another arrangement: ``layout`` turned by ``angle_rad`` about its
    floor's centroid (mirrored across the floor's x axis through it first, with
    ``mirror``); the solver then pulls it back onto the floor. From it the solver finds
    the layout's turned counterpart where the floor allows one, which random starts
    that all fall into the same minimum do not."""
    m = layout.model
    center = m.floor_polygon_m.mean(axis=0)
    pos = layout.position_m.copy()
    yaw = layout.yaw_rad.copy()
    rel = pos[:, :2] - center
    if mirror:
        rel[:, 1] = -rel[:, 1]
        yaw = -yaw
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    pos[:, :2] = center + rel @ np.array([[c, s], [-s, c]])
    yaw = yaw + angle_rad
    fixed = m.particle_inv_mass == 0.0
    pos[fixed] = layout.position_m[fixed]
    yaw[fixed] = layout.yaw_rad[fixed]
    return State(pos, yaw)


def _start_near_partners(model, pos, random_xy, rng):
    """A free item tied to another by a "max" distance constraint starts at a random
    point within that distance of its partner instead of anywhere on the floor
    (beyond the paper, like :func:`_start_on_curves`). The paper's uniform start
    leaves such partners on opposite sides of a large floor, and pulling them
    together through a crowd takes hundreds of iterations. "eq" distances are left
    alone: they mostly seat chairs around a focal point, and chairs that arrive from
    random directions spread around their table, while chairs started next to it
    bunch up.

    Each item moves at most once, in constraint order, so a chain of constraints
    starts as a chain; ``random_xy`` (n,) marks the items whose start was random.
    """
    moved = np.zeros(model.n, bool)
    body = model.particle_body
    for (i, j), rest, mode in zip(model.distance_pairs, model.distance_rest_m, model.distance_mode):
        if mode != codes.MAX or body[i] != i or body[j] != j:
            continue
        if random_xy[j] and not moved[j]:
            anchor, mover = i, j
        elif random_xy[i] and not moved[i]:
            anchor, mover = j, i
        else:
            continue
        for _ in range(16):
            r = rest * np.sqrt(rng.uniform())
            a = rng.uniform(-np.pi, np.pi)
            x, y = pos[anchor, 0] + r * np.cos(a), pos[anchor, 1] + r * np.sin(a)
            if K.inside_polygon(model.floor_polygon_m, x, y):
                pos[mover, :2] = x, y
                moved[mover] = True
                break


def _start_on_curves(model, pos, yaw, rng):
    """Members of a curve group that have no start position start on their curve, in
    random order at jittered, evenly spread curve parameters (instead of anywhere on
    the floor): their order along the curve then matches their positions, so the
    spacing constraints spread them instead of making them pass through each other."""
    for c in range(len(model.curve_group)):
        g = model.curve_group[c]
        members = model.curve_members[model.curve_start[c]:model.curve_start[c + 1]]
        members = members[np.isnan(model.particle_init_position_m[members, 0])]
        n = len(members)
        t = (rng.permutation(n) + 0.5 + rng.uniform(-0.25, 0.25, size=n)) / max(n, 1)
        p = model.curve_params[c]
        if model.curve_kind[c] == codes.ARC:
            phi = p[3] + t * (p[4] - p[3])
            local = np.stack([p[0] + p[2] * np.cos(phi), p[1] + p[2] * np.sin(phi)], axis=1)
        else:
            local = p[None, 0:2] + t[:, None] * (p[None, 2:4] - p[None, 0:2])
        cg, sg = np.cos(yaw[g]), np.sin(yaw[g])
        pos[members, 0] = pos[g, 0] + cg * local[:, 0] - sg * local[:, 1]
        pos[members, 1] = pos[g, 1] + sg * local[:, 0] + cg * local[:, 1]


@dataclass(frozen=True)
class Solver:
    """Settings of the position-based solver.

    Parameters
    ----------
    max_iterations : hard cap on iterations.
    min_iterations : never stop before this many: with the default rate the growing
        collision stiffness reaches 0.9 only after about 100 iterations, and an early
        low-energy state still has its collisions to work out.
    patience : stop when the best energy has not improved (by more than the fraction
        ``tolerance`` plus ``abs_tolerance``) for this many iterations.
    tolerance, abs_tolerance : the improvement of the energy that counts for
        ``patience``; the best layout seen is returned either way.
    rate : M of the stiffness schedule k_l = 1 − (1 − k0)^(M/l) (and l/M for GROW).
    method : "gauss-seidel" (each correction visible at once) or "jacobi" (batch
        average per constraint kind, over-relaxed by ``omega``).
    omega : Jacobi over-relaxation (1.2 after Macklin et al.).
    collision : "box" — exact oriented boxes, pushed along the axis of least
        penetration; or "sphere" — the paper's bounding circles.
    collision_stiffness : k0 of the growing collision stiffness.
    access_stiffness : constant stiffness of the accessibility constraints.
    gap_m : clearance the collision projection aims for, so touching boxes part.
    order : six rows of (wall, others, collision) flags, thesis Table 5.1.
    energy_every : evaluate the energy (to keep the best layout and decide when to
        stop) every this many iterations; 1 is the paper's every iteration. Between
        evaluations the trace repeats the last value.
    pad_m : slack of the collision pair list: an item's pair boxes (footprint and
        clearances, axis-aligned and turned) are padded by half of it plus ``gap_m``,
        and its pairs are found again once it has moved by half of it.
    threads_from : from this many boxes in the pair list (items that collide or need
        clearance, and door and window zones), the collision, clearance and floor
        passes run on two threads; below it the thread start-up costs more than it
        saves (benchmarks/scaling.py). The layout depends on the choice (the order of
        the projections changes), not on timing.
    restarts : fresh random starts allowed when a run's best layout still collides,
        leaves the floor, is not walkable or has an item more than ``ACCESS_CLEAR_M``
        inside another's clearance (0: one run, as in the paper). In a tightly packed
        room one run in three can be clean: 20 leave next to none unclean.
    stratify_from : from this many bodies placed at random, the start is stratified
        instead of uniform (:func:`initial_state`).
    polish_rounds : after the loop, at most this many rounds of collision and
        boundary projection at full stiffness on the best layout (kept if its energy
        is no higher); 0 returns the best layout as seen, as in the paper.
    """

    max_iterations: int = 1000
    min_iterations: int = 100
    patience: int = 50
    tolerance: float = 1e-2
    abs_tolerance: float = 5e-3
    rate: float = 30.0
    method: str = "gauss-seidel"
    omega: float = 1.2
    collision: str = "box"
    collision_stiffness: float = 0.5
    access_stiffness: float = 0.5
    gap_m: float = 0.002
    order: tuple = TABLE_5_1
    energy_every: int = 3
    pad_m: float = 0.1
    polish_rounds: int = 30
    threads_from: int = 5000
    restarts: int = 20
    stratify_from: int = STRATIFY_FROM

    def __post_init__(self):
        if self.method not in ("gauss-seidel", "jacobi"):
            raise LayoutError(f"solver.method: {self.method!r} is not 'gauss-seidel' or 'jacobi'")
        if self.collision not in codes.COLLISION_NAMES:
            raise LayoutError(f"solver.collision: {self.collision!r} is not 'box' or 'sphere'")
        # Bounds no layout comes near: a run past them would take hours or all the memory
        # (the two thresholds only count items, and may be huge to mean "never").
        for name, lowest, highest in (("max_iterations", 1, 100_000), ("min_iterations", 0, 100_000),
                                      ("patience", 1, 100_000), ("energy_every", 1, 10_000), ("restarts", 0, 1_000),
                                      ("polish_rounds", 0, 10_000), ("threads_from", 0, 2**62),
                                      ("stratify_from", 0, 2**62)):
            value = getattr(self, name)
            whole = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
            if not (whole and lowest <= value <= highest):
                raise LayoutError(f"solver.{name}: {_shown(value)} must be a whole number from {lowest} to {highest:,}")
        if not 1.0 <= self.rate <= 1e6:
            raise LayoutError(f"solver.rate: {self.rate!r} must lie in [1, 1e6] (the paper's M)")
        if not 0.0 < self.omega < 2.0:
            raise LayoutError(f"solver.omega: {self.omega!r} must lie in (0, 2) (over-relaxation)")
        if not 0.0 < self.pad_m <= 10.0:
            raise LayoutError(f"solver.pad_m: {self.pad_m!r} must lie in (0, 10] meters")
        for name in ("collision_stiffness", "access_stiffness"):
            if not 0.0 < getattr(self, name) <= 1.0:
                raise LayoutError(f"solver.{name}: {getattr(self, name)!r} must lie in (0, 1]")

    def solve(self, model: Model, seed=None, state: State | None = None) -> Layout:
        """Solve from a random start drawn with ``seed`` (or from ``state``).

        When the best layout of a run still collides, leaves the floor, is not
        walkable (:func:`layout.metrics.walkability`) or has an item more than
        ``ACCESS_CLEAR_M`` inside another's clearance, the solver starts again from a
        fresh random start of the same generator, up to ``restarts`` times, and
        returns the best run: clean first, then walkable, then clear, then lowest
        energy. The returned layout says how many runs it took; its time covers all
        of them.
        """
        rng = np.random.default_rng(seed)
        best = None
        t0 = time.perf_counter()
        for run in range(self.restarts + 1):
            start = initial_state(model, rng, self.stratify_from) if state is None or run > 0 else state.copy()
            pos, yaw, trace, best_it, iters, degen = self._run(model, start)
            K.sync_members(model.packed()[0], pos, yaw)
            terms = energy_terms(model, State(pos, yaw), self.collision)
            clean = sum(terms[k] for k in HARD_KINDS) <= HARD_CLEAN
            # Walkability is only worth checking (a rasterization) for a clean layout.
            walkable = clean and (self.restarts == 0 or _walkable(model, pos, yaw))
            clear = (self.restarts == 0
                     or _deepest_intrusion_m(model, State(pos, yaw), self.collision) <= ACCESS_CLEAR_M)
            key = (not clean, not walkable, not clear, float(np.sqrt(sum(terms.values()))))
            if best is None or key < best[0]:
                best = (key, pos, yaw, trace, best_it, iters, degen, terms)
            if clean and walkable and clear:
                break
        elapsed = time.perf_counter() - t0
        # All the runs it took, not the index of the best one (they differ when no run
        # is clean and walkable).
        runs = run + 1
        _, pos, yaw, trace, best_it, iters, degen, terms = best
        return Layout.from_state(model, pos, yaw, terms, trace, iters, best_it, seed, elapsed,
                                 degenerate={k: int(v) for k, v in zip(codes.KINDS, degen) if v}, runs=runs)

    def _run(self, model: Model, start: State):
        return K.solve_loop(
            model.packed(),
            np.ascontiguousarray(start.position_m, dtype=np.float64),
            np.ascontiguousarray(start.yaw_rad, dtype=np.float64),
            self.max_iterations,
            self.min_iterations,
            self.patience,
            float(self.tolerance),
            float(self.abs_tolerance),
            float(self.rate),
            self.method == "jacobi",
            float(self.omega),
            np.array(self.order, dtype=np.bool_),
            codes.COLLISION_NAMES[self.collision],
            float(self.collision_stiffness),
            float(self.access_stiffness),
            float(self.gap_m),
            _cell_size(model),
            float(self.pad_m),
            np.array(codes.ENERGY_WEIGHTS),
            self.energy_every,
            self.polish_rounds,
            self.threads_from,
        )

    def suggest(self, model: Model, n: int, seed: int = 0) -> list[Layout]:
        """``n`` layouts from ``n`` random starts; start k uses seed ``seed + k``."""
        if not (isinstance(n, int) and n >= 1):
            raise LayoutError(f"suggestions: {n!r} must be an integer >= 1")
        return [self.solve(model, seed=seed + k) for k in range(n)]


# What the command lines say before a solve that compiles.
COMPILE_NOTE = ("the first run on this machine compiles the layout solver (numba): 2-3 minutes, once "
                "(`make setup` does it ahead); later runs load it in about a second")


def _shown(value) -> str:
    """A number as a message names it: a huge one by its first digits and its length."""
    text = repr(value)
    return text if len(text) <= 20 else f"{text[:8]}…({len(text)} digits)"


def compiled() -> bool:
    """Whether the solver's loop is ready without compiling: compiled in this process, or
    in numba's disk cache for this source (the first run on a machine compiles it for
    1-2 minutes). True when that cannot be told: the cache's index is not numba's public
    API."""
    if K.solve_loop.signatures:
        return True
    try:
        return bool(K.solve_loop._cache._cache_file._load_index())
    except Exception:
        return True


def _walkable(model, pos, yaw) -> bool:
    probe = Layout.from_state(model, pos, yaw, {}, np.zeros(0), 0, 0, None, 0.0)
    return walkability(probe).ok


def _cell_size(model: Model) -> float:
    """Spatial-hash cell: about two typical padded footprints (kept with the frozen model,
    asked for on every run)."""
    cached = model.__dict__.get("_cell_m")
    if cached is None:
        items = model.items
        size = model.particle_size_m[items]
        reach = 0.5 * np.hypot(size[:, 0], size[:, 1]) + model.particle_access_depth_m[items].max(1)
        cached = float(max(0.25, 2.0 * np.median(reach)))
        object.__setattr__(model, "_cell_m", cached)
    return cached


def energy_terms(model: Model, state: State, collision: str = "box") -> dict:
    """g_j Σ C_j² per constraint kind for a state (E = sqrt of the sum)."""
    P = model.packed()[0]
    pairs = K.candidate_pairs(P, state.position_m, state.yaw_rad, _cell_size(model), 0.05)
    cs = np.empty((model.n, 2))
    K.trig(state.yaw_rad, cs)
    terms = K.energy_terms(model.packed(), state.position_m, state.yaw_rad, cs, pairs,
                           codes.COLLISION_NAMES[collision], np.array(codes.ENERGY_WEIGHTS))
    return {k: float(v) for k, v in zip(codes.KINDS, terms)}


def clearance_intrusions(model: Model, state: State, collision: str = "box"):
    """Pairs of items of which one stands in the other's clearance (access sides).

    Parameters
    ----------
    model, state, collision
        As for :func:`residuals` (a Layout serves as the state).

    Returns
    -------
    pairs : (k, 2) int64
        Particle indices (i < j) of the items; members of one group are never a pair.
    depth_m : (k,) float64
        How far in, > 0: the root-sum-square of the penetrations into each access
        box either item has against the other (0.25 for an item 25 cm inside).
    """
    P = model.packed()[0]
    # Copies: a Layout's arrays are read-only, and the kernel is compiled for writable ones.
    pos = np.array(state.position_m, dtype=np.float64)
    yaw = np.array(state.yaw_rad, dtype=np.float64)
    pairs = K.candidate_pairs(P, pos, yaw, _cell_size(model), 0.05)
    cs = np.empty((model.n, 2))
    K.trig(yaw, cs)
    depth = np.zeros(len(pairs))
    if len(pairs):
        K.residual_access(P, pairs, pos, cs, codes.COLLISION_NAMES[collision], depth)
    inside = depth < 0.0
    return pairs[inside, :2].astype(np.int64), -depth[inside]


def _deepest_intrusion_m(model, state, collision) -> float:
    """How deep (m) the worst item stands in another's clearance, 0 if none does."""
    _, depth = clearance_intrusions(model, state, collision)
    return float(depth.max()) if len(depth) else 0.0


def residuals(model: Model, state: State, collision: str = "box") -> dict:
    """The value C_j of every constraint, by kind (0 where an inequality holds).

    Parameters
    ----------
    model : Model
    state : State
        Positions (n, 3) in meters and yaws (n,) in radians, e.g. a Layout's.
    collision : "box" or "sphere", as the solver that produced the state.

    Returns
    -------
    dict of kind -> (c,) float64
        Static kinds have one value per constraint, in the order they were added (the
        CoM kinds heat, symmetry and balance give ½‖e‖² in m², the orientation kinds
        radians, the rest meters); ``boundary`` one per particle; ``collision`` and
        ``access`` one per candidate pair (negative = penetration depth).
    """
    P, D, L, H, S, B, W, WO, O, ST, U, R = model.packed()
    pos = np.ascontiguousarray(state.position_m, dtype=np.float64)
    yaw = np.ascontiguousarray(state.yaw_rad, dtype=np.float64)
    pairs = K.candidate_pairs(P, pos, yaw, _cell_size(model), 0.05)
    cs = np.stack([np.cos(yaw), np.sin(yaw)], axis=1)
    code = codes.COLLISION_NAMES[collision]
    calls = {
        "distance": (len(D.rest), lambda out: K.residual_distance(D, P, pos, yaw, out)),
        "lane": (len(L.origin), lambda out: K.residual_lane(L, P, pos, yaw, out)),
        "heat": (len(H.frame), lambda out: K.residual_heat(H, P, pos, yaw, out)),
        "symmetry": (len(S.focal), lambda out: K.residual_symmetry(S, P, pos, yaw, out)),
        "balance": (len(B.target), lambda out: K.residual_balance(B, P, pos, yaw, out)),
        "wall_distance": (len(W.item), lambda out: K.residual_wall_distance(W, R, P, pos, yaw, out)),
        "wall_orientation": (len(WO.item), lambda out: K.residual_wall_orientation(WO, R, P, pos, yaw, out)),
        "orientation": (len(O.mode), lambda out: K.residual_orientation(O, P, pos, yaw, out)),
        "stack": (len(ST.k0), lambda out: K.residual_stack(ST, P, pos, yaw, out)),
        "curve": (len(U.group), lambda out: K.residual_curve(U, P, pos, yaw, out)),
        "boundary": (model.n, lambda out: K.residual_boundary(R, P, pos, yaw, out)),
        "collision": (len(pairs), lambda out: K.residual_collision(P, R, pairs, pos, cs, code, out)),
        "access": (len(pairs), lambda out: K.residual_access(P, pairs, pos, cs, code, out)),
    }
    result = {}
    for kind, (count, fill) in calls.items():
        out = np.zeros(max(count, 1))
        fill(out)
        result[kind] = out[:count]
    return result


def diversity(layouts: list[Layout]) -> float:
    """How different suggestions are: mean over pairs of layouts of the symmetric
    chamfer distance (m) between item centers of the same kind (so swapping two
    identical chairs counts as no change)."""
    if len(layouts) < 2:
        return 0.0
    m = layouts[0].model
    items = m.items
    kinds = np.array([m.kinds[i] for i in items])
    total, count = 0.0, 0
    for a in range(len(layouts)):
        for b in range(a + 1, len(layouts)):
            pa = layouts[a].position_m[items, :2]
            pb = layouts[b].position_m[items, :2]
            dists = []
            for kind in np.unique(kinds):
                sel = kinds == kind
                d = np.linalg.norm(pa[sel][:, None] - pb[sel][None], axis=-1)
                dists.extend(d.min(1))
                dists.extend(d.min(0))
            total += float(np.mean(dists))
            count += 1
    return total / count
