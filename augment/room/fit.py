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
import functools
import itertools
import math
import re
from pathlib import Path

import cv2
import numpy as np

from layout import report as layout_report
from layout.builder import LayoutBuilder
from layout.camera import Camera, in_view_share, seats_at
from layout.camera import faults as camera_faults
from layout.catalog import CATALOG
from layout.errors import LayoutError
from layout.geometry import edge_distances, polygon_area
from layout.presets import DEFAULT_ROOM, PRESETS, corner_sets
from layout.spec import Opening

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


# Kinds that serve another and go when the last piece they serve goes: no stager shows
# a coffee table without seating, a nightstand without its bed.
SERVES = {"coffee_table": (("sofa", "armchair"), "seating"),
          "rug": (("sofa", "coffee_table", "bed", "single_bed"), "seating or a bed"),
          "nightstand": (("bed", "single_bed"), "a bed"), "office_chair": (("desk",), "a desk")}


# Kinds that dress a group: one of them alone (a plant, a lone side table) is no staging.
DRESSING = ("plant", "side_table", "floor_lamp", *SERVES)


def _lone_dressing(kinds) -> bool:
    """Whether furniture of ``kinds`` (names) is one piece that only dresses a group."""
    kinds = list(kinds)
    return len(kinds) == 1 and kinds[0] in DRESSING


def _alone(item) -> str:
    name = item.kind.name.replace("_", " ")
    return f"alone, {'an' if name[0] in 'aeiou' else 'a'} {name} is no staging"


def _why_gone(kind: str, reason: str) -> str:
    """Why a piece left out with others goes: it served them (:data:`SERVES`), or it
    stood on them."""
    if kind in SERVES:
        return f"it goes with {SERVES[kind][1]}, and none is left"
    return f"stood on a dropped item ({reason})"


def _drop(spec, ids: list[str]):
    """``spec`` without the items ``ids`` (and what only they used: what stands on them,
    what serves only them, :data:`SERVES`)."""
    gone = set(ids)
    # Items stacked on a dropped item would fall to the floor: they go too.
    for c in spec.constraints:
        if c.type == "stack":
            chain = c.args["chain"]
            for k, i in enumerate(chain):
                if i in gone:
                    gone.update(chain[k + 1:])
                    break
    had = {i.kind.name for i in spec.items}
    while True:  # a rug goes with the coffee table that went with the sofa
        left = {i.kind.name for i in spec.items if i.id not in gone}
        orphans = {i.id for i in spec.items if i.id not in gone and i.kind.name in SERVES
                   and set(SERVES[i.kind.name][0]) & had and not set(SERVES[i.kind.name][0]) & left}
        if not orphans:
            break
        gone |= orphans
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


# What follows an item's id in the note that it is kept bare (fit_spec, solve_suggestions),
# retracted when the item is left out after all.
BARE_NOTE = " stands without "


def _bare_note(item, why: str) -> str:
    return f"{item.id}{BARE_NOTE}{item.kind.bare_part}: {why}"


def _without_bare_notes(notes: list, ids) -> None:
    """Take back the notes that pieces ``ids`` stand bare (they were left out after all)."""
    notes[:] = [n for n in notes if not n.startswith(tuple(i + BARE_NOTE for i in ids))]


def _too_tall_for_view(top_m: float) -> str:
    return f"{top_m:.2f} m tall, {IN_NO_VIEW} (a photo taken from higher or farther back shows more)"


def _kept_bare(spec, items, why: str, notes: list):
    """``spec`` with ``items`` at their kind's ``bare_height_m`` (a TV stand without its TV,
    a bed without its headboard), each with a line in ``notes`` saying ``why``."""
    lowered = {i.id: dataclasses.replace(i, kind=dataclasses.replace(
        i.kind, size_m=(*i.kind.size_m[:2], i.kind.bare_height_m))) for i in items}
    notes.extend(_bare_note(i, why) for i in items)
    return dataclasses.replace(spec, items=tuple(lowered.get(i.id, i) for i in spec.items))


def _bare_notes(items, noted=()) -> list[str]:
    """The notes of :func:`_kept_bare` for those of ``items`` (a corner set's) that stand
    at their kind's bare height, but for pieces ``noted`` already says so of: a corner set
    is fitted to the photo on its own."""
    said = tuple(n for n in noted if BARE_NOTE in n)
    return [_bare_note(i, _too_tall_for_view(CATALOG[i.kind.name].size_m[2]))
            for i in items if 0.0 < i.kind.bare_height_m == i.kind.size_m[2] and i.kind.name in CATALOG
            and not any(n.startswith(i.id + BARE_NOTE) for n in said)]


def _lowerable(item) -> bool:
    """Whether ``item`` stands on the floor at more than its kind's bare height."""
    return item.elevation_m == 0.0 and 0.0 < item.kind.bare_height_m < item.kind.size_m[2]


def _stands_in_view(camera: Camera, polygon_m, size_m) -> bool:
    """Whether a box of ``size_m`` stands whole in the photo somewhere on the floor
    (:func:`layout.camera.in_view_share`): asked of the same sizes again for each corner set."""
    K, pose = (np.asarray(a, np.float64).tobytes() for a in (camera.K, camera.camera_from_floor))
    return _in_view(K, pose, tuple(int(v) for v in camera.size_px),
                    np.ascontiguousarray(polygon_m, dtype=np.float64).tobytes(), tuple(float(v) for v in size_m))


@functools.lru_cache(maxsize=256)
def _in_view(K: bytes, camera_from_floor: bytes, size_px: tuple, polygon: bytes, size_m: tuple) -> bool:
    camera = Camera(np.frombuffer(K).reshape(3, 3), np.frombuffer(camera_from_floor).reshape(4, 4), size_px)
    return in_view_share(camera, np.frombuffer(polygon).reshape(-1, 2), size_m) > 0.0


def fit_spec(spec, polygon_m, height_m: float, camera=None, notes: list | None = None):
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
    camera : layout.camera.Camera, optional
        The photo's camera: a unit that would be cut by the photo's edge or stand in its
        foreground wherever it stood (:func:`layout.camera.in_view_share`) is dropped too,
        or kept at its kind's ``bare_height_m`` (a TV stand without its TV) where that fits.
    notes : list, optional
        What was changed rather than dropped is appended to it.

    Returns
    -------
    spec : Spec
        With the measured room and the items that fit (no preset, no doors or windows).
    dropped : list of dict
        ``{"id", "kind", "reason"}`` per dropped item, in the order they were dropped.
    """
    fit = ROOM.fit
    notes = [] if notes is None else notes
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
            reasons.setdefault(i, _why_gone(kinds[i], reason))

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
        elif camera is not None and any(i.kind.collides for i in unit):  # a rug may run out of the photo
            top = max(i.kind.size_m[2] + i.elevation_m for i in unit)
            if _stands_in_view(camera, poly, (w, d, top)):
                continue
            why = _too_tall_for_view(top)
            # Its pieces without their top parts (a bed with its nightstands, headboard off).
            lower = [i for i in unit if _lowerable(i)]
            bare = {i.id for i in lower}
            bare_top = max((i.kind.bare_height_m if i.id in bare else i.kind.size_m[2]) + i.elevation_m for i in unit)
            if lower and _stands_in_view(camera, poly, (w, d, bare_top)):
                spec = _kept_bare(spec, lower, why, notes)
            else:
                drop(unit, why)
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


def corner_specs(source, fitted, calibration=None) -> list:
    """The preset's corner sets (:func:`layout.presets.corner_sets`) fitted to the floor of
    ``fitted`` (its polygon, height, open edges and doors) and the photo's camera (that of
    ``calibration``, also where ``fitted`` is laid out without it), for suggestions that
    would otherwise repeat the first: those that keep their first piece in view, whole or
    bare (a bed without its headboard; said where the set is staged), in order. None for
    a spec file's furniture: that is what the user chose."""
    from layout.spec import spec_from_dict

    if not isinstance(source, str):
        return []
    camera = layout_camera(calibration) if calibration is not None and ROOM.fit.for_camera else fitted.camera
    room = {"height": fitted.height_m, "polygon": np.asarray(fitted.polygon_m).round(6).tolist(),
            "open_edges": list(fitted.open_edges)}
    out = []
    for k, parts in enumerate(corner_sets(source)):
        spec = spec_from_dict({"room": room, **parts}, where=f"preset {source}, corner set {k + 1}")
        notes = []
        spec, dropped = fit_spec(spec, fitted.polygon_m, fitted.height_m, camera, notes)
        if not spec.items or parts["items"][0]["id"] in {d["id"] for d in dropped}:
            continue
        out.append(dataclasses.replace(spec, camera=camera, doors=fitted.doors, windows=fitted.windows))
    return out


_TALL = re.compile(r"(\d+\.\d+ m) tall, (.*)")  # a reason that names the piece's height


def dropped_summary(dropped: list) -> str:
    """``"a, b: why; c: why"``: the dropped items grouped by reason, in order. Reasons
    that differ only in the piece's height are said once: ``"a 0.85 m, b, c 1.00 m tall:
    each would ..."``."""
    by_reason = {}  # reason without the height -> {id: height or None}
    for d in dropped:
        tall = _TALL.fullmatch(d["reason"])
        reason, height = (tall[2], tall[1]) if tall else (d["reason"], None)
        by_reason.setdefault(reason, {}).setdefault(d["id"], height)  # a corner set's piece of the same id
    parts = []
    for reason, items in by_reason.items():
        if not any(items.values()):
            parts.append(f"{', '.join(items)}: {reason}")
        elif len(items) == 1:
            ((item, height),) = items.items()
            parts.append(f"{item}: {height} tall, {reason}")
        else:  # the pieces in turn, those of one height in a row named with it once
            named = ", ".join(" ".join([", ".join(i for i, _ in run)] + ([h] if h else []))
                              for h, run in itertools.groupby(items.items(), key=lambda kv: kv[1]))
            parts.append(f"{named} tall: {re.sub(r'^it ', 'each ', reason)}")
    return "; ".join(parts)


def too_small(area_m2: float, dropped: list) -> FurnishError:
    what = dropped_summary(dropped)
    return FurnishError(f"floor too small for any furniture: the photo shows {area_m2:.2f} m\u00b2 of floor"
                        + (f" ({what})" if what else "")
                        + ". Show more of the floor: step back, turn toward the room, or hold the camera higher")


def no_view(dropped: list) -> FurnishError:
    """The photo shows too little above the floor for any piece to stand whole in it, where
    it belongs: no staged photo with pieces cut by its edge or standing off their walls."""
    return FurnishError("no furniture stands whole in this photo (" + dropped_summary(dropped) + "). It shows too "
                        "little above the floor: step back, and hold the camera higher and level")


def no_wall(dropped: list) -> FurnishError:
    """Laid out as a plan (no camera), the main piece finds no place at a wall."""
    return FurnishError("no furniture finds its place on this floor (" + dropped_summary(dropped) + "): the "
                        "outline leaves its main piece no place at a wall. Check the floor in overlay_floor.png, "
                        "or give other furniture (--spec)")


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
    # A door is kept clear as the floor's edge is kept; no item stands deep in another's
    # clearance (a sofa across a TV stand's front); no piece is cut by the photo's edge or
    # stands in its foreground.
    from layout.solver import ACCESS_CLEAR_M

    return (rep["overlaps"]["count"] == 0 and rep["outside_m2"] == 0.0
            and all(a <= ROOM.fit.door_graze_m2 for a in rep["door_clearance_m2"])
            and rep["clearances"]["deepest_m"] <= ACCESS_CLEAR_M
            and not rep.get("camera", {}).get("cut"))


def layout_camera(calibration) -> Camera:
    """The photo's camera as the layout sees it (:class:`layout.camera.Camera`)."""
    return Camera(calibration.intrinsics.K, calibration.camera_from_floor, tuple(calibration.size_px))


IN_NO_VIEW = "it would be cut by the photo's edge or stand in its foreground wherever it stood"


# Starts for another arrangement when random ones repeat an earlier suggestion
# (layout.solver.turned_state): half a turn, mirrored, a quarter turn each way.
TURNS = ((math.pi, False), (0.0, True), (0.5 * math.pi, False), (-0.5 * math.pi, False))
# Closer than this (apart_m) to an earlier suggestion, a try is that suggestion again.
PINNED_M = 0.01


def footprint_m2(lay) -> float:
    """Floor the pieces of ``lay`` that stand on it take up (a rug, which others stand on, not counted)."""
    m = lay.model
    items = [i for i in lay.items if m.particle_collides[i]]
    return float(np.sum(m.particle_size_m[items, 0] * m.particle_size_m[items, 1]))


def apart_m(a, b) -> float:
    """How far apart two suggestions are as arrangements: infinitely with other
    furniture, else the symmetric chamfer distance between pieces of the same kind (a
    swap of two chairs is no change), two pieces as far apart as their centres or, if
    more, their footprints' corners (nearest to nearest, so a square plant turned 90
    degrees has not moved, but a sideboard turned to the next wall has)."""
    kinds_a = np.array([a.model.kinds[i] for i in a.items])
    kinds_b = np.array([b.model.kinds[i] for i in b.items])
    if sorted(kinds_a) != sorted(kinds_b):
        return math.inf
    dists = []
    for kind in np.unique(kinds_a):
        ia, ib = np.asarray(a.items)[kinds_a == kind], np.asarray(b.items)[kinds_b == kind]
        ca, cb = a.corners_m(ia), b.corners_m(ib)  # (n, 4, 2)
        centres = np.linalg.norm(a.position_m[ia, None, :2] - b.position_m[None, ib, :2], axis=-1)
        gaps = np.linalg.norm(ca[:, None, :, None] - cb[None, :, None], axis=-1)  # (na, nb, 4, 4)
        corners = 0.5 * (gaps.min(3).mean(2) + gaps.min(2).mean(2))
        d = np.maximum(centres, corners)
        dists.extend(d.min(1))
        dists.extend(d.min(0))
    return float(np.mean(dists))


def _residuals(lay) -> dict:
    from layout.solver import State, residuals

    return residuals(lay.model, State(lay.position_m, lay.yaw_rad))


def broken_rules(lay, r: dict | None = None) -> list[dict]:
    """The rules a layout breaks by more than a glance shows: a wall-bound item off its
    wall, a facing off by more than ``ROOM.fit.rule_angle_deg``, a distance or a place
    ("in front of", "beside") off by more than ``ROOM.fit.rule_distance_m``.

    Returns
    -------
    list of dict
        ``{"rule": "wall" | "facing" | "distance" | "place", "items": [ids], "off": value}``
        with ``off`` in meters, or degrees for a facing; in the model's constraint order.
        ``r``: the layout's residuals when already computed.
    """
    fit, m = ROOM.fit, lay.model
    r = _residuals(lay) if r is None else r
    names = m.names
    out = []
    for c in np.flatnonzero(np.abs(r["wall_distance"]) > fit.rule_distance_m):
        out.append({"rule": "wall", "items": [names[m.wall_distance_item[c]]], "off": float(r["wall_distance"][c])})
    for c in np.flatnonzero(np.abs(r["distance"]) > fit.rule_distance_m):
        out.append({"rule": "distance", "items": [names[i] for i in m.distance_pairs[c]],
                    "off": float(r["distance"][c])})
    # The centre-of-mass kinds give half the squared distance, m².
    place_m = np.sqrt(2.0 * np.abs(r["heat"]))
    for c in np.flatnonzero(place_m > fit.rule_distance_m):
        members = [names[i] for i in m.heat_members[m.heat_start[c]:m.heat_start[c + 1]]]
        frame = [names[m.heat_frame[c]]] if m.heat_frame[c] >= 0 else []
        out.append({"rule": "place", "items": members + frame, "off": float(place_m[c])})
    for c in np.flatnonzero(np.abs(r["orientation"]) > np.radians(fit.rule_angle_deg)):
        out.append({"rule": "facing", "items": [names[i] for i in m.orientation_pairs[c]],
                    "off": float(np.degrees(r["orientation"][c]))})
    return out


def rule_count(lay) -> int:
    """How many rules :func:`broken_rules` judges in a layout."""
    counts = lay.model.counts()
    return sum(counts[k] for k in ("wall_distance", "distance", "heat", "orientation"))


def _astray(lay, r: dict | None = None, may_float=frozenset()) -> set:
    """The pieces a stager would not leave so: wall-bound ones more than
    ``ROOM.fit.astray_m`` off their wall's distance, out in the room (a TV stand in the
    middle of the room) or pushed to a wall they should stand clear of (a desk facing into
    the room, its chair's place gone), or at their wall but turned more than
    ``ROOM.fit.astray_deg`` from it (a bed askew); and both of two that should face each
    other (a sofa and its TV) turned that far off. The pieces ``may_float`` (ids) may stand
    out in the room, turned as their group has them; a piece that faces them goes instead.
    ``r``: the layout's residuals when already computed."""
    from layout import _codes as codes

    fit, m = ROOM.fit, lay.model
    r = _residuals(lay) if r is None else r
    far = set(m.wall_distance_item[r["wall_distance"] > fit.astray_m])  # out in the room
    off = set(m.wall_distance_item[r["wall_distance"] < -fit.astray_m]) | {i for i in far
                                                                          if m.names[i] not in may_float}
    askew = np.abs(r["wall_orientation"]) > np.radians(fit.astray_deg)  # the nearest wall: theirs unless far
    off.update(i for i in m.wall_orientation_item[askew] if i not in far)
    turned = (np.abs(r["orientation"]) > np.radians(fit.astray_deg)) & (m.orientation_mode == codes.FACE)
    off.update(i for i in m.orientation_pairs[turned].ravel() if m.names[i] not in may_float)
    return {m.names[i] for i in off}


def _in_groups(model) -> set:
    """The ids of the pieces that form a group a stager may pull out into the room: two
    that face each other or keep a distance (a sofa and its TV), and a piece with another
    placed in front of it (a coffee table before the sofa, armchairs at the table's ends)
    with those. A rug under it or a side table at its arm alone make no group."""
    from layout import _codes as codes

    i = set(model.distance_pairs.ravel()) | set(model.orientation_pairs[model.orientation_mode == codes.FACE].ravel())
    for c in np.flatnonzero(model.heat_frame >= 0):
        members = model.heat_members[model.heat_start[c]:model.heat_start[c + 1]]
        ahead = [k for k in members if k != model.heat_frame[c] and model.particle_collides[k]]
        if ahead and model.heat_target_m[c, 0] > 0.0:
            i |= set(ahead) | {model.heat_frame[c]}
    return {model.names[k] for k in i}


def _off_their_spots(lay, r: dict | None = None) -> set:
    """Pieces placed at a partner (a side table at the sofa's arm, a rug under it) that
    break their place by more than a glance shows (:func:`broken_rules`'
    ``ROOM.fit.rule_distance_m`` off their spot, or ``rule_angle_deg`` turned from their
    partner): a coffee table off the sofa's middle, a rug askew. A stager puts such a
    piece right or takes it out of that shot."""
    from layout import _codes as codes

    fit, m = ROOM.fit, lay.model
    r = _residuals(lay) if r is None else r
    off = set()
    for c in np.flatnonzero((np.sqrt(2.0 * np.abs(r["heat"])) > fit.rule_distance_m) & (m.heat_frame >= 0)):
        off.update(m.heat_members[m.heat_start[c]:m.heat_start[c + 1]])
    askew = (np.abs(r["orientation"]) > np.radians(fit.rule_angle_deg)) & (m.orientation_mode == codes.PARALLEL)
    off.update(m.orientation_pairs[askew, 0])
    return {m.names[i] for i in off}


def _taken_out(lay, spec, ids: set, built: dict | None = None):
    """``lay`` with the items ``ids`` (and what stands on them) taken out, the rest where
    it stood: a layout of ``spec`` without them. ``built``: models of ``spec`` built
    before, by what they leave out (the same pieces go from many tries)."""
    from layout.solver import Layout, State, energy_terms
    from layout.spec import build

    gone = frozenset(ids) | ({i.id for i in spec.items} - set(lay.model.names))  # a try of a subset
    built = {} if built is None else built
    if (key := (id(spec), gone)) not in built:
        built[key] = spec, build(_drop(spec, sorted(gone))[0])[0]  # the spec held: its id stays its own
    model = built[key][1]
    at = [lay.model.names.index(n) for n in model.names]
    pos, yaw = lay.position_m[at].copy(), lay.yaw_rad[at].copy()
    return Layout.from_state(model, pos, yaw, energy_terms(model, State(pos, yaw)), lay.trace, lay.iterations,
                             lay.best_iteration, lay.seed, lay.time_s, runs=lay.runs)


def _armchairs_from_behind(lay, rep: dict) -> set:
    """Armchairs whose backs face the lens (:func:`layout.camera.judge`): a stager takes
    such a chair out of the shot rather than show its back."""
    kinds = dict(zip(lay.model.names, lay.model.kinds))
    return {n for n in rep.get("camera", {}).get("from_behind", ()) if kinds.get(n) == "armchair"}


# Why a piece is left out of one suggestion (:class:`_Pick`).
OFF_SPOT = "in view, it found no place at the piece it goes with"
# What the catalog puts against a wall a stager never leaves off it, even as the room's main
# piece (a bed's head, storage, a TV), but a desk: it may face into the room, as a sofa may
# stand in it, in its group.
MAY_FLOAT = ("desk",)
UNSEEN = "it would stand hidden behind the others"
IN_FRONT = "it would hide a piece that stays behind it"
LOOMS = "it would stand tall in the foreground and wall off the room"
HIDING_ROUNDS = 3  # taking a piece out can show or hide others: judge again this often at most


class _Pick:
    """The best try of one suggestion: clean first, then no seating (or lone TV) seen from
    behind and no tall piece looming in the foreground, then not one piece of dressing
    alone (:data:`DRESSING`), then furnishing at least ``ROOM.fit.sparse_share`` of the
    floor the first suggestion furnishes
    (:func:`footprint_m2`), then different from the earlier suggestions, then with the fewest faults (the camera's,
    :func:`broken_rules`, a piece taken out). A piece off its spot (:func:`_off_their_spots`)
    or hidden behind others (:func:`layout.camera.judge`) is taken out of the try, as a
    stager takes it out of the shot, with the pieces placed at it (a desk's chair); where
    the hidden piece stays (the most important unit, a member of a rigid set) or comes
    before it in the spec's order, the piece in front of it goes instead. A tall piece that
    looms in the foreground goes too, unless it stays."""

    def __init__(self, earlier: list, spec, anchor=frozenset(), built: dict | None = None):
        self.earlier = earlier
        self.spec = spec
        self.built = {} if built is None else built  # models with pieces taken out (_taken_out)
        self.anchor = anchor  # the ids of the most important unit: it stays, astray or not,
        # unless a stager never leaves it off its wall
        kinds = {i.id: i.kind for i in spec.items}
        self.floats = frozenset(i for i in anchor if not kinds[i].against_wall or kinds[i].name in MAY_FLOAT)
        groups = {g.id: g for g in spec.groups}
        # A member of a rigid set (a table's chairs) goes only with its set.
        self.in_sets = {i.id for i in spec.items if _rigid_root(i, groups) is not None}
        self.rank = {i.id: k for k, i in enumerate(spec.items)}  # the spec's order: most important first
        self.best = None
        self.cut = None  # the cut pieces of the unclean try that cut fewest
        self.astray = None  # the pieces off their walls of the otherwise clean try with fewest
        self.pinned = 0  # clean tries that came back exactly as an earlier suggestion

    def offer(self, lay) -> bool:
        """Consider a try; True once it is all one could want."""
        rep = layout_report.evaluate(lay, walkable=False)  # judged in full for the one kept
        if not _clean(rep):
            now = set(rep.get("camera", {}).get("cut", ()))
            self.cut = now if self.cut is None or len(now) < len(self.cut) else self.cut
            return False
        r = _residuals(lay)
        # The main piece stands out in the room only with its group: alone, a stager puts it at a wall.
        floats = self.floats & _in_groups(lay.model)
        astray = _astray(lay, r, floats) | (_armchairs_from_behind(lay, rep) - floats)
        if astray:
            return self._astray_try(astray)
        # A piece goes with those placed at it (a side table at an armchair), a desk with its
        # chair and the chair with its desk; a chair at a desk that stays, stays.
        m = lay.model
        with_it = {}
        for c in np.flatnonzero(m.heat_frame >= 0):
            with_it.setdefault(m.names[m.heat_frame[c]], set()).update(
                m.names[i] for i in m.heat_members[m.heat_start[c]:m.heat_start[c + 1]])
        stays = set(self.anchor | self.in_sets)
        for table, seats in seats_at(m).items():
            for seat in seats:
                with_it.setdefault(seat, set()).update({table} | with_it.get(table, set()))
            stays.update(seats if table in stays else ())
        taken = {}
        for judged in range(HIDING_ROUNDS + 1):
            if taken:
                # Taking a piece out moves nothing else: the try stays clean.
                lay = _taken_out(lay, self.spec, taken, self.built)
                rep, r = layout_report.evaluate(lay, walkable=False), _residuals(lay)
            camera = rep.get("camera", {})
            # Again each round: without a piece, those placed at it get another spot (a lamp
            # beside the armchair once its side table is gone).
            hiding = {i: OFF_SPOT for i in _off_their_spots(lay, r) - self.anchor}
            for h in camera.get("hidden", ()):
                front = camera["hidden_by"].get(h, h)
                # The less important of the two goes (a plant, not the coffee table it hides).
                if front not in stays and (h in stays or self.rank.get(front, -1) > self.rank.get(h, -1)):
                    goes, why = front, IN_FRONT
                else:
                    goes, why = (h, UNSEEN) if h not in stays else (None, None)
                if goes is not None:
                    hiding.update(dict.fromkeys({goes} | with_it.get(goes, set()), why))
            for t in camera.get("looms", ()):
                if t not in stays:
                    hiding.update(dict.fromkeys({t} | with_it.get(t, set()), LOOMS))
            if not hiding or judged == HIDING_ROUNDS or {lay.model.names[i] for i in lay.items} <= set(hiding):
                break
            taken |= hiding
        if taken and (astray := _astray(lay, r, self.floats & _in_groups(lay.model))):
            # Its group taken out, the main piece stands alone where the group wanted it.
            return self._astray_try(astray)
        # Seating shown from behind, one piece that only dresses a group (a lone plant) and
        # a lone armchair where the first suggestion staged a sofa set are worse than a
        # repeat, which the suggestion's own style makes another look; a fault is a little
        # less than a perfect one.
        nearest = min((apart_m(old, lay) for old in self.earlier), default=math.inf)
        sparse = bool(self.earlier) and footprint_m2(lay) < ROOM.fit.sparse_share * footprint_m2(self.earlier[0])
        # What looms still is a piece that stays (a corner set's wardrobe): as bad as a back.
        key = (bool(camera.get("from_behind") or camera.get("looms")),
               _lone_dressing(lay.model.kinds[i] for i in lay.items), sparse, nearest < ROOM.fit.min_difference_m,
               camera_faults(camera) + len(broken_rules(lay, r)) + len(taken))
        self.pinned += nearest < PINNED_M
        if self.best is None or key < self.best[0]:
            self.best = (key, lay, taken)
        return key == (False, False, False, False, 0)

    def _astray_try(self, astray: set) -> bool:
        """An unclean try with pieces ``astray``: kept as the fewest seen so far, not offered."""
        self.astray = astray if self.astray is None or len(astray) < len(self.astray) else self.astray
        return False

    @property
    def twin(self) -> bool:
        return self.best is not None and self.best[0][3]

    @property
    def lacking(self) -> bool:
        """The best so far repeats an earlier suggestion, shows seating from behind, a lone
        piece of dressing or little furniture: other starts are worth trying (other subsets only for a repeat)."""
        return self.best is not None and any(self.best[0][:4])


def _far_start(model, earlier: list, rng, candidates: int = 8):
    """Of ``candidates`` random starts of ``model``, the one whose pieces stand farthest
    from where the nearest earlier suggestion put pieces of their kinds (mean over the
    pieces; a kind that suggestion has not counts as the floor's size)."""
    from layout.solver import initial_state

    items = list(model.items)
    span = float(np.ptp(model.floor_polygon_m, axis=0).max())
    # Per earlier suggestion, per piece of this model: where that suggestion put its kind.
    spots = []
    for old in earlier:
        kinds = np.array([old.model.kinds[i] for i in old.items])
        where = old.position_m[list(old.items), :2]
        spots.append([where[kinds == model.kinds[i]] for i in items])
    best, best_d = None, -1.0
    for _ in range(candidates):
        start = initial_state(model, rng)
        d = min((float(np.mean([np.linalg.norm(at - start.position_m[i, :2], axis=1).min(initial=span)
                                for i, at in zip(items, old)])) for old in spots), default=math.inf)
        if d > best_d:
            best, best_d = start, d
    return best


def _kinds(spec) -> list:
    return sorted(i.kind.name for i in spec.items)


def _arrangement(spec) -> tuple:
    """The furniture and the kinds of rule that place it: a corner set alike in these is
    the spec again (one desk against a wall and one facing into the room are not)."""
    return sorted((i.kind.name, i.rules) for i in spec.items), sorted(c.type for c in spec.constraints)


def _corner_instead(spec, corner, dropped: list, why: dict) -> tuple:
    """``corner`` (a corner set, :func:`corner_specs`) to lay out in place of all of ``spec``'s
    furniture, which no suggestion can show whole in the photo (``why``: id -> reason),
    and the note that says so."""
    dropped.extend({"id": i.id, "kind": i.kind.name, "reason": why[i.id]} for i in spec.items)
    return corner, (f"staged as a corner ({', '.join(i.id for i in corner.items)}): the floor in view shows too "
                    "little for the room's furniture to stand whole in the photo")


def _padded(door: Opening) -> Opening:
    """A found door whose zone reaches ``ROOM.fit.found_door_margin_m`` past its found
    sides and depth: the finder puts a side a few centimeters in, now and then ten."""
    return dataclasses.replace(door, margin_m=ROOM.fit.found_door_margin_m)


def _doors_as_found(spec):
    """``spec`` with its doors' zones as found (no margin, :func:`_padded`), or None
    where no door has a margin."""
    if not any(d.margin_m for d in spec.doors):
        return None
    return dataclasses.replace(spec, doors=tuple(dataclasses.replace(d, margin_m=0.0) for d in spec.doors))


def _wider(pick, spec, model, corners, solver, layouts: list, built: dict, seed: int, step: int):
    """A repeat after every usual try: ``ROOM.fit.twin_tries`` more tries, in turn of the
    furniture, of it without each of its less important units and of every corner set
    (those shown already too: elsewhere on the floor, or fewer of them, they are another
    picture), from seeds ``step`` apart past those tried before, each one run (the
    restarts' best is the spot the earlier suggestions took) judged only when it is no
    repeat and walkable; the first pick that is no repeat and better than ``pick``, else
    ``pick``. ``model`` is ``spec``'s, built already."""
    from layout.metrics import walkability
    from layout.spec import build

    fit = ROOM.fit
    once = dataclasses.replace(solver, restarts=0)
    # (what the pick is judged as, what is solved): fewer pieces are the furniture with some left out.
    variants = [(spec, spec)] + [(spec, _drop(spec, [i.id for i in u])[0]) for u in _units(spec)[:0:-1]] \
        + [(c, c) for c in corners]
    picks, models = {}, {0: model}
    first = seed + (fit.seed_tries + fit.far_starts) * step
    for t in range(fit.twin_tries):
        v = t % len(variants)
        judged_as, solved = variants[v]
        if v not in models:
            models[v] = build(solved)[0]
        if v not in picks:
            picks[v] = _Pick(layouts, judged_as, anchor=frozenset(i.id for i in _units(judged_as)[0]), built=built)
        lay = once.solve(models[v], seed=first + t // len(variants) * step)
        if min(apart_m(old, lay) for old in layouts) < fit.min_difference_m or not walkability(lay).ok:
            continue
        other = picks[v]
        other.offer(lay)
        if other.best is not None and not other.twin and other.best[0] < pick.best[0]:
            return other
    return pick


def _said_once(said: list[str]) -> list[str]:
    """Notes ``"suggestion K <what>"``, those of several suggestions alike said once:
    ``"suggestions 3 and 4 repeat an earlier one: ..."`` (in the order first said)."""
    by_what = {}
    for note in said:
        _, k, what = note.split(" ", 2)
        by_what.setdefault(what, []).append(k)
    merged = []
    for what, ks in by_what.items():
        verb, rest = what.split(" ", 1)
        merged.append(f"suggestion {ks[0]} {what}" if len(ks) == 1 else
                      f"suggestions {', '.join(ks[:-1])} and {ks[-1]} {verb.removesuffix('s')} {rest}")
    return merged


def solve_suggestions(spec, suggestions: int, seed: int, area_m2: float, dropped: list, progress,
                      notes: list | None = None, corners=()):
    """Solve ``suggestions`` layouts, suggestion K from seed ``seed + K - 1``.

    A try that collides, leaves the floor, blocks a door, stands deep in a clearance, is
    cut by the photo's edge or leaves a wall-bound piece off its wall (:func:`_astray`)
    is not clean. From a clean try a piece off its spot at its partner or hardly seen
    behind the others is taken out (:class:`_Pick`, with a line in ``notes``); of the
    clean ones the first that shows no seating from behind, is a different arrangement
    from the earlier suggestions (:func:`apart_m` at least ``ROOM.fit.min_difference_m``)
    and has no fault (the camera finds nothing hidden, :func:`layout.camera.judge`; the
    rules hold, :func:`broken_rules`; nothing taken out) is kept, else the best in that
    order. Tries go
    on from seed ``seed + K - 1 + N``, then ``+ 2N`` (``ROOM.fit.seed_tries`` in all). When all of
    them repeat an earlier suggestion, the first suggestion turned and mirrored
    (:data:`TURNS`) is tried as a start, then the furniture without one of its less
    important units (another subset), then other furniture: ``corners``, specs on the
    same floor (:func:`corner_specs`), each tried once per photo, then more seeds for
    each of these (:func:`_wider`); a twin is kept, with a line in ``notes``, when nothing
    gives anything else, and the later suggestions then keep their seeds' best.

    A later suggestion with no clean try of its own takes the first as one (a repeat)
    and searches on from there. When the first has no clean layout, the least important
    unit with an item cut by the photo's edge is dropped, else the one with a piece astray
    (the most important unit, a sofa or a desk, may stand out in the room with its group;
    alone, or a bed or a piece of storage (against a wall in the catalog, but a desk:
    :data:`MAY_FLOAT`), it is astray off its wall
    and takes all the furniture with it), else the least important unit (the spec's last),
    and all are solved again; before the last unit goes, all are solved once more with
    ``ROOM.fit.last_tries`` seeds for the first suggestion. The last unit gone (or all
    but one piece of dressing, :data:`DRESSING`), a corner set is staged in their place;
    with none left, all is tried again with the found doors' zones as found (no margin,
    :func:`_padded`), then the photo is refused:
    no piece is shown cut by the photo's edge or standing off its wall."""
    from layout.solver import turned_state
    from layout.spec import build

    fit = ROOM.fit
    notes = [] if notes is None else notes
    built = {}  # models with pieces taken out, shared by the tries (_taken_out)
    corners, cornered = [c for c in corners if _arrangement(c) != _arrangement(spec)], None
    first_try = (spec, list(dropped), list(corners))
    tries, longer = fit.seed_tries, False  # seeds for the first suggestion; the longer search made
    while True:
        model, solver = build(spec)
        solver = dataclasses.replace(solver, restarts=min(solver.restarts, fit.restarts),
                                     min_iterations=min(solver.min_iterations, fit.min_iterations))
        layouts, reports, failed, cut, astray, said, tried = [], [], None, None, None, [], set()
        forced = False  # a suggestion's whole search found only repeats
        for k in range(suggestions):
            pick = _Pick(layouts, spec, anchor=frozenset(i.id for i in _units(spec)[0]), built=built)
            for t in range(tries if k == 0 else fit.seed_tries):  # the later ones may repeat the first
                # Twice the very same arrangement: the photo pins it, other seeds will not help.
                if pick.offer(solver.solve(model, seed=seed + k + t * suggestions)) or pick.pinned >= 2 \
                        or (t >= fit.seed_tries and pick.best is not None):  # the longer search: any clean one
                    break
            pick.pinned = 0
            borrowed = pick.best is None and bool(layouts)
            if borrowed:
                # No clean try of its own: the first suggestion is one, and the photo may allow
                # no other; the searches for another arrangement below start from it (not
                # with fewer of these pieces: where all of them found no place, fewer do not).
                pick.offer(layouts[0])
            # After one suggestion's whole search found only repeats, the next one's (with one
            # more to differ from) would too: it keeps its seeds' best.
            hopeless = forced and pick.twin
            # Turned starts from the first suggestion, when it holds all the furniture.
            for angle, mirror in TURNS if pick.lacking and layouts and layouts[0].model.n == model.n \
                    and not hopeless else ():
                if pick.offer(solver.solve(model, seed=seed + k, state=turned_state(layouts[0], angle, mirror))) \
                        or not pick.lacking or pick.pinned >= 2:
                    break
            # Starts far from the earlier suggestions: random ones settle where those did.
            for t in range(fit.far_starts if pick.lacking and layouts and not hopeless else 0):
                far_seed = seed + k + (fit.seed_tries + t) * suggestions
                start = _far_start(model, layouts, np.random.default_rng(far_seed))
                if pick.offer(solver.solve(model, seed=far_seed, state=start)) or not pick.lacking:
                    break
            if pick.twin and not hopeless and not borrowed:
                for unit in _units(spec)[:0:-1]:
                    smaller, _ = _drop(spec, [i.id for i in unit])
                    sub_model, _ = build(smaller)
                    for t in range(fit.seed_tries):
                        if pick.offer(solver.solve(sub_model, seed=seed + k + t * suggestions)) or not pick.lacking:
                            break
                    if not pick.lacking:
                        break
            for c, corner in enumerate(corners if pick.twin and not hopeless else ()):
                if c in tried:
                    continue
                tried.add(c)
                other = _Pick(layouts, corner, anchor=frozenset(i.id for i in _units(corner)[0]), built=built)
                corner_model, _ = build(corner)
                for t in range(fit.seed_tries):
                    if other.offer(solver.solve(corner_model, seed=seed + k + t * suggestions)) or not other.lacking:
                        break
                if other.best is not None and other.best[0] < pick.best[0]:
                    pick = other
                if not pick.twin:
                    break
            if pick.twin and not forced:
                pick = _wider(pick, spec, model, corners, solver, layouts, built, seed + k, suggestions)
                forced = pick.twin
            progress.step()
            if pick.best is None:
                failed, cut, astray = k + 1, pick.cut, pick.astray
                break
            # Its seed names the suggestion (it picks the designs and the default style, here
            # and when layout_K.json is rendered again), whichever try's start it came from.
            layouts.append(dataclasses.replace(pick.best[1], seed=seed + k))
            reports.append(layout_report.evaluate(pick.best[1]))
            taken = pick.best[2]
            for why in (OFF_SPOT, UNSEEN, IN_FRONT, LOOMS):
                if ids := sorted(i for i, w in taken.items() if w == why):
                    said.append(f"suggestion {k + 1} leaves out {', '.join(ids)}: {why}")
            left = sorted(set(i.id for i in _drop(pick.spec, taken)[0].items) - set(pick.best[1].model.names))
            kept = [i for i in pick.spec.items if i.id in pick.best[1].model.names]
            if pick.spec is not spec:
                # A corner set left with the room's own furniture shows it elsewhere: nothing to say.
                if sorted(i.kind.name for i in kept) != _kinds(spec):
                    said.append(f"suggestion {k + 1} stages another corner set ({', '.join(i.id for i in kept)}): "
                                "the floor in view leaves room for one arrangement of the room's furniture")
                said.extend(_bare_notes(kept))
            elif pick.twin:
                said.append(f"suggestion {k + 1} repeats an earlier one: the floor in view leaves no other "
                            "arrangement of this furniture")
            elif left:
                said.append(f"suggestion {k + 1} leaves out {', '.join(left)} to differ from the others: the floor "
                            "in view leaves room for one arrangement of all of it")
        if failed is None:
            # A piece left out on the way that a suggestion stages after all (the same id and
            # kind: a corner set's) is in the photos: it is not said to be left out.
            staged = {(lay.model.names[i], lay.model.kinds[i]) for lay in layouts for i in lay.items}
            dropped[:] = [d for d in dropped if (d["id"], d["kind"]) not in staged]
            bare = _bare_notes(spec.items, notes) if cornered else []
            notes.extend(([cornered] if cornered else []) + bare + _said_once(said))
            return spec, layouts, reports
        units = _units(spec)
        kinds = {i.id: i.kind.name for i in spec.items}
        by_cut = [u for u in units if (cut or set()) & {i.id for i in u}]
        by_astray = [u for u in units if (astray or set()) & {i.id for i in u}]
        if by_cut:
            reason = "the photo's edge or its foreground would cut it wherever it stood with the rest"
            gone_units = by_cut[-1:]
        elif by_astray:
            reason = "it found no place against a wall, or facing its partner, on the floor in view with the rest"
            # The main piece with no place at a wall: the rest without it is no staging either.
            gone_units = units if by_astray[-1] is units[0] else by_astray[-1:]
        else:
            reason = (f"suggestion {failed} could not place everything without overlaps or leaving the "
                      f"{area_m2:.1f} m\u00b2 floor")
            gone_units = units[-1:]
        asked = {i.id for u in gone_units for i in u}
        rest, gone = _drop(spec, sorted(asked))
        why = {i: reason if i in asked else _why_gone(kinds[i], reason) for i in gone}
        lone = spec.camera is not None and bool(corners) and _lone_dressing(i.kind.name for i in rest.items)
        lower = [i for u in gone_units for i in u if _lowerable(i)] if by_cut or by_astray else []
        if spec.camera is not None and lower and (longer or (rest.items and not lone)):
            # Cut by the photo's edge, or kept off its wall by where it may stand whole in the
            # photo (after the longer search, where all would go): without its top part first.
            spec = _kept_bare(spec, lower, f"with it, {reason}", notes)
            progress.grow(suggestions)
            continue
        why.update({i.id: _alone(i) for i in rest.items} if lone else {})
        if not rest.items or lone:  # what serves the units dropped goes with them (SERVES)
            if not longer:
                # Before the main piece, and all with it, goes: a longer search, once.
                tries, longer = fit.last_tries, True
                progress.grow(suggestions)
                continue
            tries = fit.seed_tries
            if spec.camera is not None and corners:
                _without_bare_notes(notes, [i.id for i in spec.items])
                spec, cornered = _corner_instead(spec, corners.pop(0), dropped, why)
                progress.grow(suggestions)
                continue
            if (loose := _doors_as_found(first_try[0])) is not None:
                spec, cornered = loose, None
                dropped[:] = first_try[1]
                corners = [_doors_as_found(c) or c for c in first_try[2]]
                first_try = (loose, first_try[1], corners)
                progress.grow(suggestions)
                continue
            dropped.extend({"id": i.id, "kind": i.kind.name, "reason": why[i.id]} for i in spec.items)
            # No piece cut by the photo's edge, nor standing off its wall: rather no staged
            # photo, and the reason.
            if spec.camera is not None and (by_cut or by_astray):
                raise no_view(dropped)
            raise no_wall(dropped) if by_astray else too_small(area_m2, dropped)
        spec = rest
        dropped.extend({"id": i, "kind": kinds[i], "reason": why[i]} for i in sorted(gone))
        # A piece kept bare for the frame and left out after all is said once, as left out.
        _without_bare_notes(notes, gone)
        progress.grow(suggestions)


def _window_on_wall(segment_m: np.ndarray, poly: np.ndarray, open_edges_: list[int]):
    """A found window (the floor points (2, 2) under its sides) on the layout floor ``poly``:
    its middle (2,) and width, meters, as found when its middle is near a wall; else the
    part of it along one wall (a window running on past the photo's edge); None when no
    ``ROOM.fit.window_on_wall_m`` of it runs along a wall."""
    fit = ROOM.fit
    middle = segment_m.mean(axis=0)
    walls = [k for k in range(len(poly)) if k not in open_edges_]
    if walls and edge_distances(middle[None], poly)[0][walls].min() <= fit.door_from_wall_m:
        return middle, float(np.linalg.norm(segment_m[1] - segment_m[0]))
    best = None
    for k in walls:
        a, b = poly[k], poly[(k + 1) % len(poly)]
        length = float(np.linalg.norm(b - a))
        u = (b - a) / max(length, 1e-12)
        off = segment_m - a
        if np.abs(off[:, 0] * u[1] - off[:, 1] * u[0]).max() > fit.door_from_wall_m:
            continue  # not along this wall
        t0, t1 = np.clip(np.sort(off @ u), 0.0, length)
        if best is None or t1 - t0 > best[1] - best[0]:
            best = (t0, t1, a, u)
    if best is None or best[1] - best[0] < fit.window_on_wall_m:
        return None
    t0, t1, a, u = best
    return a + u * 0.5 * (t0 + t1), float(t1 - t0)


def furniture_for_floor(source, floor, height_m: float, where: Path, *, doors=None, found_doors=(),
                        found_windows=(), calibration=None, asset_kinds=(), warnings: list):
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
    found_doors : (n, 4) array_like
        Doors found in the photo (:func:`augment.room.openings.find_openings`), the same way;
        one that will not do as a door of the layout's floor is left out, not refused.
    found_windows : sequence of augment.room.openings.FoundWindow
        Windows found in the photo: furniture taller than a sill keeps
        ``ROOM.fit.window_clearance_m`` from it; one running on past the floor in view keeps
        its part along the wall (:func:`_window_on_wall`); one wider than its wall is left out.
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
        The floor is no usable room, or too small for any of the furniture (a preset: for
        any of its corner sets too, or for more than one piece of dressing, :data:`DRESSING`).
    """
    poly = _layout_floor(floor, height_m, where)
    edges = open_edges(poly, floor)
    spec = _spec_for_floor(source, poly, height_m, warnings, edges)
    camera = layout_camera(calibration) if calibration is not None and ROOM.fit.for_camera else None
    notes = []
    fitted, dropped = fit_spec(spec, poly, height_m, camera, notes)
    warnings += notes
    fitted = dataclasses.replace(fitted, camera=camera)
    if doors is not None and len(doors):
        fitted = dataclasses.replace(fitted, doors=doors_on_floor(doors, calibration, poly, edges))
    found = []
    for d in np.asarray(found_doors, dtype=np.float64).reshape(-1, 4):
        try:
            (door,) = doors_on_floor([d], calibration, poly, edges)
        except FurnishError:
            continue  # not a door of this floor's walls: a false find
        # Its zone as deep as its widest leaf can be: wider, it is a double door or a
        # folding or sliding closet, whose leaves are narrower.
        door = dataclasses.replace(door, where=f"found {door.where}",
                                   clearance_m=min(door.width_m, ROOM.fit.max_leaf_m))
        for door in (_padded(door), door):
            try:
                LayoutBuilder(poly, height_m, open_edges=edges).add_door(door.at_m, *door.zone_m)
            except LayoutError:
                continue  # wider than its wall: as found, or (not even that) a false find
            found.append(door)
            break
    windows = []
    for w in found_windows:
        on_wall = _window_on_wall(np.asarray(w.segment_m, dtype=np.float64), poly, edges)
        if on_wall is None:
            continue  # it stands beyond the floor in view, or off its walls: a false find
        middle_m, width_m = on_wall
        # The finder reads the glass; the frame and casing either side, often the wall's colour, go with it.
        for pad_m in (ROOM.fit.found_window_margin_m, 0.0):
            window = Opening(tuple(float(v) for v in middle_m), width_m + 2.0 * pad_m,
                             ROOM.fit.window_clearance_m, w.top_m - w.sill_m, w.sill_m, "found in the photo")
            try:
                LayoutBuilder(poly, height_m, open_edges=edges).add_window(window.at_m, window.width_m, window.sill_m,
                                                                           window.height_m, window.clearance_m)
            except LayoutError:
                continue  # wider than the layout's wall: a false find, or a window round a corner
            windows.append(window)
            break
    fitted = dataclasses.replace(fitted, doors=fitted.doors + tuple(found), windows=tuple(windows))
    lone = isinstance(source, str) and _lone_dressing(i.kind.name for i in fitted.items)
    if not fitted.items or lone:
        # A preset's corner set where none of its furniture fits (a dining set on 3 m², a table
        # the frame cuts wherever it stands), whole in the frame, or only a plant does.
        corners = corner_specs(source, fitted, calibration)
        alone = {i.id: _alone(i) for i in fitted.items}
        if not corners:
            dropped.extend({"id": i.id, "kind": i.kind.name, "reason": alone[i.id]} for i in fitted.items)
            raise no_view(dropped) if any(IN_NO_VIEW in d["reason"] for d in dropped) else \
                too_small(floor.area_m2, dropped)
        fitted, note = _corner_instead(fitted, corners[0], dropped, alone)
        warnings.append(note)
    kinds = {i.kind.name for i in fitted.items}
    unused = sorted(set(asset_kinds) - kinds)
    if unused:
        warnings.append(f"no item of kind {', '.join(unused)} to show your model(s) on; the furniture is "
                        + ", ".join(sorted(kinds)))
    return fitted, dropped
