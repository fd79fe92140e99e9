"""Quality numbers and output files of solved layouts.

:func:`evaluate` measures one :class:`~layout.solver.Layout` exactly (overlaps,
area outside the floor, door clearance, walkability); :func:`write_outputs` writes
what ``layout solve`` hands out: ``layout_K.json`` and ``plan_K.png`` per suggestion
and ``energy.png`` with every suggestion's energy trace.
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from . import camera, metrics
from .errors import LayoutError
from .fileio import folder_problem, replaced_input, staged_folder
from .geometry import SIDE_NAMES
from .metrics import MIN_OVERLAP_M2, item_geometry, walkability
from .solver import ACCESS_CLEAR_M, clearance_intrusions

# Area outside the floor below this (m²) is rounding, not a misplaced item.
MIN_OUTSIDE_M2 = 1e-4
# Clearance intrusions listed by evaluate: shallower ones are the solver's tolerance.
MIN_INTRUSION_M = 0.01


def evaluate(layout, walkable: bool = True) -> dict:
    """Exact quality measures of a layout.

    Parameters
    ----------
    layout : Layout
    walkable : bool
        Also judge walkability (``traversable`` … ``blocked_doors``), a rasterization
        and the costliest measure: a caller weighing many tries leaves it to the one kept.

    Returns
    -------
    report : dict (JSON-ready)
        ``energy``; ``overlaps`` (count, ``area_m2`` total and ``pairs`` as
        ``[id, id, area_m2]``) of colliding items whose boxes interpenetrate in 3-D;
        ``outside_m2`` (total footprint area outside the floor) and ``outside_items``;
        ``traversable`` (every door and every access side reachable on foot, after
        Henderson et al.), ``components``, ``unreachable`` (``[id, side]``),
        ``blocked_doors`` (door numbers from 1); ``door_clearance_m2`` (furniture area
        inside each door's swing zone) and ``door_blockers`` (ids of the items there,
        per door); ``clearances``: ``deepest_m``, how far the worst item stands inside
        another's clearance (0 if none), and ``pairs`` as ``[id, id, depth_m]`` of those
        more than ``MIN_INTRUSION_M`` in (:func:`layout.solver.clearance_intrusions`);
        ``camera`` when the layout was made for a photo (:func:`layout.camera.judge`).

    Notes
    -----
    Items that do not collide (rugs) block nothing. An access side covered by a member
    of the item's own group is not required to be reachable (see
    :func:`layout.builder.LayoutBuilder.add_group`).
    """
    m = layout.model
    items, corners, z, access, depth = item_geometry(layout)
    ids = [m.names[i] for i in items]
    collides = m.particle_collides[items]
    pairs, area = metrics.box_overlaps(corners, z, collides, min_area_m2=MIN_OVERLAP_M2)
    # Members of one rigid group stand where their offsets put them (a chair pulled in
    # under its table): their boxes may meet.
    apart = m.particle_body[items[pairs[:, 0]]] != m.particle_body[items[pairs[:, 1]]]
    pairs, area = pairs[apart], area[apart]
    polygon = m.floor_polygon_m
    outside = metrics.area_outside(polygon, corners)
    doors = layout.corners_m(m.door_particles) if len(m.door_particles) else np.zeros((0, 4, 2))
    trav = walkability(layout) if walkable else None
    intruding, depth = clearance_intrusions(m, layout)
    clearance = metrics.door_clearance(doors, corners, collides) if len(doors) else np.zeros(0)
    blockers = [
        [ids[i] for i in np.flatnonzero(collides)
         if metrics.convex_intersection_area(zone, corners[i]) > MIN_OVERLAP_M2]
        for zone in doors
    ]
    return {
        "energy": float(layout.energy),
        "iterations": int(layout.iterations),
        "time_ms": round(1000.0 * layout.time_s, 3),
        "overlaps": {
            "count": int(len(pairs)),
            "area_m2": float(area.sum()),
            "pairs": [[ids[a], ids[b], float(s)] for (a, b), s in zip(pairs, area)],
        },
        "outside_m2": float(outside[outside > MIN_OUTSIDE_M2].sum()),
        "outside_items": [ids[k] for k in np.flatnonzero(outside > MIN_OUTSIDE_M2)],
        **({} if trav is None else {
            "traversable": bool(trav.ok),
            "components": int(trav.n_components),
            "unreachable": [[ids[i], SIDE_NAMES[k]] for i, k in trav.unreachable],
            "blocked_doors": [int(d) + 1 for d in trav.blocked_doors],
        }),
        "door_clearance_m2": [float(a) for a in clearance],
        "door_blockers": blockers,
        "clearances": {
            "deepest_m": float(depth.max()) if len(depth) else 0.0,
            "pairs": [[m.names[a], m.names[b], float(d)] for (a, b), d in zip(intruding, depth)
                      if d > MIN_INTRUSION_M],
        },
        **({} if m.camera is None else {"camera": camera.judge(layout)}),
    }


def lane_segments(model, layout):
    """(l, 2, 2) traffic-lane vectors of a layout in the floor frame, one per lane
    (lanes shared by several items are drawn once)."""
    seen, out = set(), []
    for o, start, ang, length in zip(model.lane_origin, model.lane_start_m, model.lane_angle_rad,
                                     model.lane_length_m):
        key = (int(o), float(start[0]), float(start[1]), float(ang), float(length))
        if key in seen:
            continue
        seen.add(key)
        x, y, a = layout.position_m[o, 0], layout.position_m[o, 1], layout.yaw_rad[o]
        c, s = np.cos(a), np.sin(a)
        p0 = np.array([x + c * start[0] - s * start[1], y + s * start[0] + c * start[1]])
        p1 = p0 + length * np.array([np.cos(a + ang), np.sin(a + ang)])
        out.append([p0, p1])
    return np.array(out, dtype=np.float64).reshape(-1, 2, 2)


def _finite(x):
    """JSON has no NaN/inf: write them as null."""
    if isinstance(x, float) and not np.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def output_files(layouts, reports=None, title=""):
    """The files of ``layout solve`` for a list of suggestions, in memory.

    Parameters
    ----------
    layouts : sequence of Layout
        Suggestion K (from 1) is ``layouts[K - 1]``.
    reports : sequence of dict, optional
        :func:`evaluate` of each layout (computed when not given).
    title : str
        Prefix of the plan titles.

    Returns
    -------
    files : dict of str to bytes
        ``layout_K.json`` and ``plan_K.png`` for each K, then ``energy.png`` (of
        solved layouts only).
    """
    from . import plot  # matplotlib takes half a second to import: only once plans are drawn

    reports = [evaluate(lay) for lay in layouts] if reports is None else list(reports)
    files = {}
    for k, (lay, rep) in enumerate(zip(layouts, reports), start=1):
        data = lay.to_dict()
        data["metrics"] = rep
        data["energy_by_kind"] = dict(lay.energy_by_kind)
        files[f"layout_{k}.json"] = (json.dumps(_finite(data), indent=2, allow_nan=False) + "\n").encode()
        m = lay.model
        items, corners, _, access, depth = item_geometry(lay)
        index = {name: n for n, name in enumerate(m.names[i] for i in items)}
        overlap = [[index[a], index[b]] for a, b, _ in rep["overlaps"]["pairs"]]
        doors = lay.corners_m(m.door_particles) if len(m.door_particles) else None
        verdict = "walkable" if rep["traversable"] else "NOT walkable"
        if rep["clearances"]["deepest_m"] > ACCESS_CLEAR_M:
            verdict += f", an item {100 * rep['clearances']['deepest_m']:.0f} cm inside a clearance"
        files[f"plan_{k}.png"] = plot.figure_png(plot.plan_figure(
            m.floor_polygon_m, corners, [m.names[i] for i in items], lay.yaw_rad[items],
            door_zones_m=doors, door_segments_m=m.door_segments_m,
            window_segments_m=m.window_segments_m, lanes_m=lane_segments(m, lay),
            overlap_pairs=overlap, access_corners_m=access, access_depth_m=depth,
            kinds=[m.kinds[i] for i in items], open_edges=np.flatnonzero(~m.floor_edge_wall),
            title=(f"{title}suggestion {k}: {rep['overlaps']['count']} overlaps, {verdict}\n"
                   f"rule energy {lay.energy:.3g} (0: every rule of the spec met)"),
        ))
    traces = {f"suggestion {k}": lay.trace[np.isfinite(lay.trace)] for k, lay in enumerate(layouts, 1)}
    if all(len(t) for t in traces.values()):  # a layout read back from its file has no trace
        files["energy.png"] = plot.figure_png(plot.energy_figure(traces, title=f"{title}energy per iteration"))
    return files


# What one suggestion K writes: the layout and its plan; ``stage furnish`` adds its own.
SUGGESTION_FILES = ("layout_{k}.json", "plan_{k}.png")


def earlier_suggestion_files(out_dir, per_suggestion=SUGGESTION_FILES, inputs=()) -> list[str]:
    """Names of the files in ``out_dir`` that an earlier run wrote per suggestion.

    A suggestion K is taken for an earlier run's where ``layout_K.json`` is a layout as
    :meth:`~layout.solver.Layout.to_dict` writes it (an object with ``room`` and
    ``items``); its files are then ``per_suggestion`` (patterns of ``k``) that exist and
    are none of this run's ``inputs`` (paths or None). Written again, they are replaced;
    the others would be left over from a run with more suggestions, or other options,
    and would not match what this run reports.
    """
    out = Path(out_dir)
    if not out.is_dir():
        return []
    names = []
    for path in out.iterdir():
        match = re.fullmatch(r"layout_([1-9][0-9]*)\.json", path.name)
        if match is None or not path.is_file():
            continue
        try:
            earlier = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError):
            continue
        if isinstance(earlier, dict) and {"room", "items"} <= earlier.keys():
            k = int(match[1])
            names += [n for n in (p.format(k=k) for p in per_suggestion)
                      if (out / n).is_file() and replaced_input([out / n], inputs) is None]
    return sorted(names)


def write_outputs(layouts, out_dir, reports=None, title="", inputs=()):
    """Write :func:`output_files` into ``out_dir`` (created if missing), all or none
    (:func:`~layout.fileio.staged_folder`); none may replace one of ``inputs`` (the run's
    input files, paths). An earlier run's suggestions that this run does not write again
    (:func:`earlier_suggestion_files`) are taken away, so the folder holds one run.

    Returns
    -------
    paths : list of Path
        ``layout_K.json`` and ``plan_K.png`` for each K, then ``energy.png`` (of
        solved layouts only).

    Raises
    ------
    LayoutError
        When ``out_dir`` cannot be an output folder (:func:`~layout.fileio.folder_problem`), or
        an output would replace one of ``inputs``; nothing is written then.
    OSError
        When ``out_dir`` cannot be written; nothing is changed in it then.
    """
    out = Path(out_dir)
    if (problem := folder_problem(out)) is not None:
        raise LayoutError(f"--out {out}: {problem}")
    files = output_files(layouts, reports, title)
    if (clash := replaced_input([out / name for name in files], inputs)) is not None:
        raise LayoutError(f"--out {out}: {clash[0].name} there is the input {clash[1]}, which is never "
                          "overwritten; write the outputs to another folder")
    with staged_folder(out, stale=earlier_suggestion_files(out, inputs=inputs)) as staging:
        for name, data in files.items():
            (staging / name).write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
    return [out / name for name in files]
