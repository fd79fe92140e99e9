"""The furniture for the measured floor: a room preset or a spec fitted to it, and its
layouts solved with what does not fit left out.

The floor in view is the room: the layouts are made on the measured polygon shrunk by a
wall margin, at the measured height; items taller than the room, too large for the floor
at any angle, or beyond the floor's share for furniture are dropped, and when a
suggestion still cannot place everything, the least important remaining item goes.

Its tuning is ``ROOM.fit`` (:mod:`augment.room.settings`), read at call time.
"""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import cv2
import numpy as np

from layout import report as layout_report
from layout.builder import LayoutBuilder
from layout.errors import LayoutError
from layout.geometry import polygon_area
from layout.presets import DEFAULT_ROOM, PRESETS

from ..errors import FurnishError
from .doors import doors_on_floor, open_edges
from .settings import ROOM


def _rect_fits(polygon_m: np.ndarray, width_m: float, depth_m: float) -> bool:
    """Whether a ``width_m`` x ``depth_m`` rectangle fits inside the polygon at some
    position and orientation (rasterized at ``ROOM.fit.fit_cell_m``; 180 / ``fit_angles``
    degree steps)."""
    fit = ROOM.fit
    cell = fit.fit_cell_m
    kw, kd = max(1, math.ceil(width_m / cell)), max(1, math.ceil(depth_m / cell))
    for theta in np.linspace(0.0, np.pi, fit.fit_angles, endpoint=False):
        c, s = math.cos(theta), math.sin(theta)
        p = polygon_m @ np.array([[c, -s], [s, c]])  # the rectangle's axes become x and y
        lo = p.min(axis=0)
        cols, rows = (np.ceil((p.max(axis=0) - lo) / cell)).astype(int) + 1
        if kw > cols or kd > rows:
            continue
        raster = np.zeros((rows, cols), np.uint8)
        cv2.fillPoly(raster, [np.round((p - lo) / cell).astype(np.int32)], 1)
        if cv2.erode(raster, np.ones((kd, kw), np.uint8), borderValue=0).any():
            return True
    return False


def inset_polygon(polygon_m, margin_m: float, cell_m: float | None = None) -> np.ndarray | None:
    """The polygon shrunk by ``margin_m`` on every side (rasterized at ``cell_m``, the
    largest piece left, straightened within a cell), counter-clockwise; None when
    nothing is left.

    Parameters
    ----------
    polygon_m : (n, 2) float64
    margin_m : float
    cell_m : float, optional
        Default ``ROOM.fit.inset_cell_m``.

    Returns
    -------
    (m, 2) float64 or None
    """
    cell_m = ROOM.fit.inset_cell_m if cell_m is None else cell_m
    poly = np.ascontiguousarray(polygon_m, dtype=np.float64)
    if margin_m <= 0:
        return poly.copy()
    r = max(1, round(margin_m / cell_m))
    lo = poly.min(axis=0) - (r + 2) * cell_m
    cols, rows = (np.ceil((poly.max(axis=0) + (r + 2) * cell_m - lo) / cell_m)).astype(int) + 1
    raster = np.zeros((rows, cols), np.uint8)
    cv2.fillPoly(raster, [np.round((poly - lo) / cell_m).astype(np.int32)], 1)
    raster = cv2.erode(raster, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    contours, _ = cv2.findContours(raster, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    contour = max(contours, key=cv2.contourArea)
    approx = cv2.approxPolyDP(contour, 1.0, True)[:, 0, :].astype(np.float64)
    if len(approx) < 3:
        return None
    out = approx * cell_m + lo
    return out if polygon_area(out) > 0 else out[::-1].copy()


def _rigid_root(item, groups: dict) -> str | None:
    """The outermost rigid group that ``item`` is fixed in (through rigid groups only)."""
    root, g = None, item.group
    while g is not None and groups[g].rigid:
        root, g = g, groups[g].parent
    return root


def _unit_rect(members, groups: dict) -> tuple[float, float]:
    """Width and depth of the bounding rectangle of a rigid group's members, in the
    group's frame."""
    corners = []
    for it in members:
        w, d = it.kind.size_m[:2]
        yaw, off = it.yaw_rad or 0.0, np.array(it.offset_m[:2], dtype=np.float64)
        local = np.array([[dx, dy] for dx in (-d / 2, d / 2) for dy in (-w / 2, w / 2)])
        g = it.group
        while g is not None and groups[g].rigid:
            c, s = math.cos(yaw), math.sin(yaw)
            local = local @ np.array([[c, s], [-s, c]]) + off
            parent = groups[g]
            yaw, off = parent.yaw_rad or 0.0, np.array(parent.offset_m[:2], dtype=np.float64)
            g = parent.parent if parent.parent is not None and groups[parent.parent].rigid else None
        corners.append(local)
    pts = np.concatenate(corners)
    depth, width = pts.max(axis=0) - pts.min(axis=0)
    return float(width), float(depth)


def _blocks_floor(item, stacked: set) -> bool:
    return item.kind.collides and item.elevation_m == 0.0 and item.id not in stacked


def _stacked_tops(constraints) -> set:
    return {i for c in constraints if c.type == "stack" for i in c.args["chain"][1:]}


_ONE_ID = ("b", "focal", "origin", "frame")


_MANY_IDS = ("a", "members", "items")


def _without(constraints, gone: set) -> tuple:
    """Constraints with the ``gone`` ids removed from member lists; a constraint whose
    single-id field or stack names one, or whose list empties, goes."""
    kept = []
    for c in constraints:
        args = dict(c.args)
        if any(args.get(f) in gone for f in _ONE_ID):
            continue
        if c.type == "stack" and gone.intersection(args["chain"]):
            continue
        lost = False
        for f in _MANY_IDS:
            if args.get(f) is not None:
                left = tuple(i for i in args[f] if i not in gone)
                lost |= not left
                args[f] = left
        if not lost:
            kept.append(dataclasses.replace(c, args=args))
    return tuple(kept)


def _prune_groups(groups, items) -> tuple:
    """Groups that still hold an item, directly or through a subgroup."""
    alive = set()
    for it in items:
        g = it.group
        while g is not None and g not in alive:
            alive.add(g)
            g = next(x for x in groups if x.id == g).parent
    return tuple(g for g in groups if g.id in alive)


def _drop(spec, ids: list[str]):
    """``spec`` without the items ``ids`` (and what only they used)."""
    gone = set(ids)
    # Items stacked on a dropped item would fall to the floor: they go too.
    for c in spec.constraints:
        if c.type == "stack":
            chain = c.args["chain"]
            for k, i in enumerate(chain):
                if i in gone:
                    gone.update(chain[k + 1:])
                    break
    items = tuple(i for i in spec.items if i.id not in gone)
    return dataclasses.replace(spec, items=items, groups=_prune_groups(spec.groups, items),
                               constraints=_without(spec.constraints, gone)), gone


def _units(spec) -> list[list]:
    """The items in droppable units, most important first (the spec's order): a rigid
    group is one unit, any other item its own."""
    groups = {g.id: g for g in spec.groups}
    units, by_root = [], {}
    for it in spec.items:
        root = _rigid_root(it, groups)
        if root is None:
            units.append([it])
        elif root in by_root:
            by_root[root].append(it)
        else:
            by_root[root] = [it]
            units.append(by_root[root])
    return units


def fit_spec(spec, polygon_m, height_m: float):
    """Fit a spec's furniture to a measured floor.

    The room becomes ``polygon_m`` and ``height_m`` (the spec's doors and windows, in
    another frame, are dropped); items that cannot be placed are dropped: taller than
    the room, a footprint (a rigid group's: all its members) that
    does not fit inside the floor at any angle, and, in the spec's order, those that
    would take the summed footprint of floor-standing items over ``ROOM.fit.max_fill`` of the
    floor's area.

    Parameters
    ----------
    spec : layout.spec.Spec
        Furnished already (a preset furnished for this floor).
    polygon_m : (n, 2) float64
        The floor, meters, counter-clockwise.
    height_m : float
        Wall height, meters.

    Returns
    -------
    spec : Spec
        With the measured room and the items that fit (no preset, no doors or windows).
    dropped : list of dict
        ``{"id", "kind", "reason"}`` per dropped item, in the order they were dropped.
    """
    fit = ROOM.fit
    poly = np.ascontiguousarray(polygon_m, dtype=np.float64)
    area = abs(polygon_area(poly))
    kinds = {i.id: i.kind.name for i in spec.items}
    spec = dataclasses.replace(spec, polygon_m=poly, height_m=float(height_m), preset=None, doors=(), windows=())
    reasons = {}

    def drop(unit, reason):
        nonlocal spec
        spec, gone = _drop(spec, [i.id for i in unit])
        for i in unit:
            reasons.setdefault(i.id, reason)
        for i in sorted(gone - {i.id for i in unit}):
            reasons.setdefault(i, f"stood on a dropped item ({reason})")

    # Too tall: the item alone (a chair of a table set may go, the table stays).
    for it in spec.items:
        top = it.kind.size_m[2] + it.elevation_m
        if top > height_m + 1e-9:
            drop([it], f"{top:.2f} m tall, the room is {height_m:.2f} m high")
    groups = {g.id: g for g in spec.groups}
    for unit in _units(spec):
        w, d = unit[0].kind.size_m[:2] if len(unit) == 1 else _unit_rect(unit, groups)
        if not _rect_fits(poly, w, d):
            drop(unit, f"its footprint {w:.2f} x {d:.2f} m fits the {area:.1f} m\u00b2 floor at no angle")
    stacked = _stacked_tops(spec.constraints)
    budget, used = fit.max_fill * area, 0.0
    for unit in _units(spec):
        fp = sum(i.kind.size_m[0] * i.kind.size_m[1] for i in unit if _blocks_floor(i, stacked))
        if used + fp > budget + 1e-9:
            drop(unit, f"no room left: {used + fp:.2f} m\u00b2 of furniture would cover more than "
                       f"{100 * fit.max_fill:.0f} % of the {area:.1f} m\u00b2 floor")
        else:
            used += fp
    return spec, [{"id": i, "kind": kinds[i], "reason": r} for i, r in reasons.items()]


def furniture_source(room: str | None, spec):
    """``(description, preset name or loaded Spec)``; checked before any photo work."""
    from layout.spec import load_spec

    if room is not None and spec is not None:
        raise LayoutError(f"give a room preset or a spec file, not both (room {room!r}, spec {spec})")
    if spec is not None:
        return f"spec {spec}", load_spec(spec)
    name = DEFAULT_ROOM if room is None else str(room)
    if name not in PRESETS:
        import difflib

        close = difflib.get_close_matches(name, PRESETS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise LayoutError(f"room {name!r} is not a preset; {hint}choose one of {', '.join(PRESETS)}")
    return f"preset {name}", name


def _spec_for_floor(source, polygon_m: np.ndarray, height_m: float, warnings: list, open_edges=()):
    """The furniture spec on the measured floor: a preset furnished for its area, or a
    spec file's items (its room, doors, windows and item positions are in its own frame,
    not the photo's: they are replaced or left out, with a warning). ``open_edges`` are
    the floor's edges that are not walls."""
    from layout.spec import spec_from_dict

    poly = np.asarray(polygon_m, dtype=np.float64).round(6).tolist()
    room = {"height": height_m, "polygon": poly, "open_edges": list(open_edges)}
    if isinstance(source, str):
        return spec_from_dict({"room": {"preset": source, **room}}, where=f"preset {source}")
    sp = source
    if sp.doors or sp.windows:
        warnings.append(f"{sp.path}: its {len(sp.doors)} door(s) and {len(sp.windows)} window(s) are placed in "
                        "the spec's own room, not the photo's floor; they are left out (mark the photo's doors "
                        "to keep them clear: --door, or Mark a door in the web app)")
    if sp.preset is not None:
        furnished = spec_from_dict({"room": {"preset": sp.preset, **room},
                                    "constraints": list(sp.constraint_tables)}, where=str(sp.path))
        return dataclasses.replace(furnished, path=sp.path, solver=sp.solver)
    placed = [i.id for i in sp.items if i.at_m is not None or i.fixed]
    placed += [g.id for g in sp.groups if g.at_m is not None or g.fixed]
    if placed:
        warnings.append(f"{sp.path}: positions (at, fixed) of {', '.join(placed)} are in the spec's own room, "
                        "not the photo's floor; they are ignored")
    return dataclasses.replace(
        sp, items=tuple(dataclasses.replace(i, at_m=None, fixed=False) for i in sp.items),
        groups=tuple(dataclasses.replace(g, at_m=None, fixed=False) for g in sp.groups), open_edges=tuple(open_edges))


def dropped_summary(dropped: list) -> str:
    """``"a, b: why; c: why"``: the dropped items grouped by reason, in order."""
    by_reason = {}
    for d in dropped:
        by_reason.setdefault(d["reason"], []).append(d["id"])
    return "; ".join(f"{', '.join(ids)}: {reason}" for reason, ids in by_reason.items())


def too_small(area_m2: float, dropped: list) -> FurnishError:
    what = dropped_summary(dropped)
    return FurnishError(f"floor too small for any furniture: the photo shows {area_m2:.2f} m\u00b2 of floor"
                        + (f" ({what})" if what else "")
                        + ". Show more of the floor: step back, turn toward the room, or hold the camera higher")


def _layout_floor(floor, height_m: float, photo: Path) -> np.ndarray:
    """The floor the layouts are made on: the measured polygon shrunk by the wall margin
    (the measured one itself when shrinking leaves no usable polygon)."""
    for poly in (inset_polygon(floor.polygon_m, ROOM.fit.wall_margin_m), floor.polygon_m):
        if poly is None:
            continue
        try:
            return LayoutBuilder(poly, height_m).polygon_m
        except LayoutError as error:
            problem = error
    raise FurnishError(f"photo {photo}: the measured floor outline is not a usable room ({problem}); "
                       "try a photo with more of the floor in view")


def _clean(rep: dict) -> bool:
    # A door the user marked is kept clear as the floor's edge is kept.
    return (rep["overlaps"]["count"] == 0 and rep["outside_m2"] == 0.0
            and all(a <= ROOM.fit.door_graze_m2 for a in rep["door_clearance_m2"]))


def solve_suggestions(spec, suggestions: int, seed: int, area_m2: float, dropped: list, progress):
    """Solve ``suggestions`` layouts, suggestion K from seed ``seed + K - 1``; one that
    collides, leaves the floor or repeats an earlier suggestion (closer than
    ``ROOM.fit.min_difference_m``, :func:`layout.diversity`) is solved again from seed
    ``seed + K - 1 + N``, then ``+ 2N`` (``ROOM.fit.seed_tries`` in all). A twin is kept when
    no try gives anything else (a floor may allow only so many arrangements). When a
    suggestion has no clean layout, the least important unit (the spec's last) is
    dropped and all are solved again."""
    from layout import diversity
    from layout.spec import build

    fit = ROOM.fit
    while True:
        model, solver = build(spec)
        layouts, reports, failed = [], [], None
        for k in range(suggestions):
            twin = None
            for t in range(fit.seed_tries):
                lay = solver.solve(model, seed=seed + k + t * suggestions)
                rep = layout_report.evaluate(lay)
                if not _clean(rep):
                    continue
                if all(diversity([old, lay]) >= fit.min_difference_m for old in layouts):
                    break
                twin = twin or (lay, rep)
            else:
                lay, rep = twin if twin is not None else (lay, rep)
            progress.step()
            if not _clean(rep):
                failed = k + 1
                break
            layouts.append(lay)
            reports.append(rep)
        if failed is None:
            return spec, layouts, reports
        units = _units(spec)
        reason = (f"suggestion {failed} could not place everything without overlaps or leaving the "
                  f"{area_m2:.1f} m\u00b2 floor")
        kinds = {i.id: i.kind.name for i in spec.items}
        if len(units) == 1:
            dropped.extend({"id": i.id, "kind": i.kind.name, "reason": reason} for i in units[0])
            raise too_small(area_m2, dropped)
        spec, gone = _drop(spec, [i.id for i in units[-1]])
        dropped.extend({"id": i, "kind": kinds[i], "reason": reason} for i in sorted(gone))
        progress.grow(suggestions)


def furniture_for_floor(source, floor, height_m: float, where: Path, *, doors=None, calibration=None,
                        asset_kinds=(), warnings: list):
    """The furniture to lay out on a measured floor (the pipeline's ``furniture`` stage).

    Parameters
    ----------
    source : str or layout.spec.Spec
        A room preset's name or a loaded spec (:func:`furniture_source`).
    floor : FloorPolygon
    height_m : float
        The wall height the layouts are made for.
    where : Path
        The photo, for messages.
    doors : (n, 4) array_like, optional
        The doors the user marked (:func:`augment.room.doors.doors_on_floor`); needs
        ``calibration``.
    asset_kinds : iterable of str
        Kinds the user gave models of: a warning names those no item shows.
    warnings : list
        Warnings are appended to it.

    Returns
    -------
    spec : Spec
        On the layout's floor (the measured one shrunk by ``ROOM.fit.wall_margin_m``), the items
        that fit.
    dropped : list of dict
        ``{"id", "kind", "reason"}`` of the items left out.

    Raises
    ------
    FurnishError
        The floor is no usable room, or too small for any of the furniture.
    """
    poly = _layout_floor(floor, height_m, where)
    edges = open_edges(poly, floor)
    spec = _spec_for_floor(source, poly, height_m, warnings, edges)
    fitted, dropped = fit_spec(spec, poly, height_m)
    if doors is not None and len(doors):
        fitted = dataclasses.replace(fitted, doors=doors_on_floor(doors, calibration, poly, edges))
    if not fitted.items:
        raise too_small(floor.area_m2, dropped)
    kinds = {i.kind.name for i in fitted.items}
    unused = sorted(set(asset_kinds) - kinds)
    if unused:
        warnings.append(f"no item of kind {', '.join(unused)} to show your model(s) on; the furniture is "
                        + ", ".join(sorted(kinds)))
    return fitted, dropped
