"""Layout specs in TOML: a room, its furniture, and the rules it should follow.

:func:`load_spec` reads and checks a spec file; :func:`build` turns it into a
:class:`~layout.model.Model` and a :class:`~layout.solver.Solver`. Every mistake is
reported as one :class:`~layout.errors.LayoutError` whose message starts with the
file, names the entry (``items[3] (id "sofa")``, ``constraints[2] (type "face")``,
``room.polygon``) and the offending value, and says what would work. Entries are
counted from 0 in the order they appear in the file.

Format
------
Lengths are meters (at most 1000; a room at most 200 across), angles degrees (fields
ending in ``_deg``; converted to radians).
Only the fields listed here are allowed: a misspelt field is an error, not ignored.

``[room]`` (required)
    ``polygon``  list of ``[x, y]`` floor corners, any orientation, a simple polygon
    with at least 3 vertices, each listed once, at most 200 m across. May be left out when the floor is passed to
    :func:`build` (``polygon_m``, e.g. measured from a photo).
    ``height``   ceiling height (default 2.5); taller items are refused.
    ``preset``   furnish automatically (``layout presets`` lists them: living_room,
    bedroom, dining_room, office, game_room, outdoor_yard); the furniture set is
    chosen by floor area. A spec with a preset has no ``[[items]]`` or ``[[groups]]``;
    it may add ``[[constraints]]`` on the preset's item ids.
    ``doors``    list of ``{ at = [x, y], width = 0.9, clearance = <width>,
    height = 2.1 }``: a door on the wall nearest ``at`` (which must be within 0.5 m
    of a wall); its swing zone, ``clearance`` deep, stays free.
    ``windows``  list of ``{ at = [x, y], width = 1.2, sill = 0.9, height = 1.2,
    clearance = 0.4 }``: items taller than the sill keep ``clearance`` away.
    ``open_edges`` list of edge numbers (edge k runs from polygon corner k to k + 1)
    that are not walls, e.g. where a photo cut the floor off: items stay inside
    them, but none is put against them.

``[camera]`` (optional)
    The photo the layout is made for (:mod:`layout.camera`): ``K`` (3 x 3 intrinsics,
    pixels), ``camera_from_floor`` (4 x 4, floor frame to OpenCV camera axes, meters),
    ``size_px`` ([width, height]). Every item then stays whole in the frame and out of
    the foreground, and the restarts prefer layouts that hide nothing and show seating
    from its good side.

``[solver]`` (optional)
    Settings of :class:`layout.Solver`: ``max_iterations``, ``min_iterations``,
    ``restarts``, ``polish_rounds``, ``energy_every``, ``threads_from``,
    ``stratify_from`` (ints), ``patience`` (int), ``rate``, ``method``
    ("gauss-seidel" | "jacobi"), ``omega``, ``collision`` ("box" | "sphere"),
    ``collision_stiffness``, ``access_stiffness``.

``[[groups]]`` (optional)
    ``id``        unique name (items and groups share one namespace).
    ``rigid``     members keep their ``offset``/``yaw_deg`` relative to the group
    (default false). Members of one group may stand in each other's clearances
    (chairs at their table).
    ``group``     parent group (nesting; a non-rigid group cannot sit in a rigid one).
    ``offset``    ``[x, y]`` in a rigid parent's frame.
    ``at``, ``yaw_deg``, ``fixed``  start pose; ``fixed = true`` pins it (needs ``at``).
    ``curve``     non-rigid groups only: members are laid along a curve in the group's
    frame, ``{ arc = { center = [x, y], radius = r, start_deg = a0, end_deg = a1 },
    spacing = 0.6 }`` or ``{ segment = [[x0, y0], [x1, y1]], spacing = 0.6 }``, with
    optional ``anchor_fixed`` (the paper's immovable curve point; default false),
    ``stiffness`` and ``schedule``. ``spacing`` (default 0 = free) is the distance
    between neighbours along the curve.

``[[items]]`` (at least one, unless there is a preset)
    ``id``        unique name.
    ``kind``      a catalog kind (``layout kinds``): default size, clearances and
    default rules. Any other word is a plain label and then needs ``size``.
    ``size``      ``[width, depth, height]``, all > 0; depth runs along the facing.
    ``count``     n copies with ids ``<id>_1`` … ``<id>_n``; the bare id in a member
    list (or an ``item``/``a`` field) stands for all of them.
    ``group``     the item's group.
    ``offset``    ``[x, y]`` in a rigid group's frame (with ``count``: a list of n).
    ``yaw_deg``   facing: relative to a rigid group, else the start yaw (fixed
    items default to 0; with ``count``: one value or a list of n).
    ``at``        ``[x, y]`` start position (with ``count``: a list of n);
    ``fixed = true`` pins the item there.
    ``access``    ``[back, left, front, right]`` clearance depths (≥ 0).
    ``collides``  false for floor coverings (default from the kind, else true).
    ``elevation`` height of the underside above the floor (default 0).
    ``rules``     apply the kind's default rules (default true), see
    :func:`layout.catalog.apply_default_rules`. A nightstand or office chair with no
    group is put in a new non-rigid group ``<partner>_set`` with its bed or desk so
    that it may stand in the partner's clearance.

``[[constraints]]`` (optional)
    ``type`` and its fields (``*`` marks required fields):

    ============== =========================================================
    distance        a*, b*, distance*, mode ("eq" | "min" | "max")
    focal_distance  focal*, members*, distance*, mode
    lane            origin*, length*, half_width*, members (default "*" = every
                    item but the origin), angle_deg (from the origin's facing),
                    start = [x, y] (in the origin's frame)
    heat            members*, target* = [x, y], frame (an id: target in its frame)
    symmetry        focal*, members*, angle_deg (axis from the focal's facing)
    balance         members (default: every item on the floor but rugs and
                    those the default rules place at a partner)
    wall            item or items*, distance (of the center; default half the
                    depth), mode
    wall_orientation item or items*, angle_deg (0 = facing into the room)
    against_wall    item or items*, gap
    face            a*, b*, angle_deg, mutual (b faces a too)
    parallel        a*, b*, angle_deg
    stack           base* and top*, or items* = [bottom, …, top]
    ============== =========================================================

    Every constraint may set ``stiffness`` (k0 in [0, 1]) and ``schedule``
    ("constant" | "decay" | "grow"). Ids may name items or groups, except in
    ``against_wall`` and ``stack`` (items only). Where a field takes one id (``b``,
    ``focal``, ``origin``, ``frame``, ``base``, ``top``) a counted id is an error.
"""
from __future__ import annotations

import dataclasses
import difflib
import json
import math
import tomllib
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import catalog
from .builder import MAX_CORNERS, LayoutBuilder
from .catalog import Kind, RuleItem
from .errors import LayoutError
from .fileio import path_problem
from .geometry import edge_distances, polygon_area
from .solver import Solver

TOP_LEVEL = ("room", "camera", "solver", "groups", "items", "constraints")
ROOM_FIELDS = ("polygon", "height", "preset", "doors", "windows", "open_edges")
DOOR_FIELDS = ("at", "width", "clearance", "height")
WINDOW_FIELDS = ("at", "width", "sill", "height", "clearance")
SOLVER_FIELDS = {
    "max_iterations": int,
    "min_iterations": int,
    "restarts": int,
    "polish_rounds": int,
    "energy_every": int,
    "threads_from": int,
    "stratify_from": int,
    "patience": int,
    "rate": float,
    "method": str,
    "omega": float,
    "collision": str,
    "collision_stiffness": float,
    "access_stiffness": float,
}
GROUP_FIELDS = ("id", "rigid", "group", "offset", "at", "yaw_deg", "fixed", "curve")
CURVE_FIELDS = ("arc", "segment", "spacing", "anchor_fixed", "stiffness", "schedule")
ARC_FIELDS = ("center", "radius", "start_deg", "end_deg")
ITEM_FIELDS = ("id", "kind", "size", "count", "group", "offset", "yaw_deg", "at", "fixed",
               "access", "collides", "elevation", "rules")
COMMON_FIELDS = ("type", "stiffness", "schedule")
# type -> (required fields, optional fields); "item|items" means one of the two.
CONSTRAINT_FIELDS = {
    "distance": (("a", "b", "distance"), ("mode",)),
    "focal_distance": (("focal", "members", "distance"), ("mode",)),
    "lane": (("origin", "length", "half_width"), ("members", "angle_deg", "start")),
    "heat": (("members", "target"), ("frame",)),
    "symmetry": (("focal", "members"), ("angle_deg",)),
    "balance": ((), ("members",)),
    "wall": (("item|items",), ("distance", "mode")),
    "wall_orientation": (("item|items",), ("angle_deg",)),
    "against_wall": (("item|items",), ("gap",)),
    "face": (("a", "b"), ("angle_deg", "mutual")),
    "parallel": (("a", "b"), ("angle_deg",)),
    "stack": (("base|items",), ("top",)),
}
MODES = ("eq", "min", "max")
SCHEDULES = ("constant", "decay", "grow")
DOOR_SNAP_M = 0.5
MAX_COUNT = 1000
# Sizes no room reaches; past them checking and solving would take minutes or more.
MAX_ENTRIES = 20_000      # items (after count), groups, constraints, each
MAX_GROUP_DEPTH = 16      # groups inside groups
MAX_OPENINGS = 100        # doors, and windows
MAX_SPEC_BYTES = 256 << 10  # a spec is a short text; the web app takes no more either
MAX_LAYOUT_BYTES = 4 << 20  # a layout_K.json of the most items a spec may hold, with its metrics


def _show(value):
    """A value as it would be written in TOML (roughly)."""
    try:
        return json.dumps(value, allow_nan=True)
    except (TypeError, ValueError):
        return repr(value)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


@dataclass(frozen=True)
class Opening:
    """A door or window as given in the spec (the builder snaps it onto a wall).
    ``margin_m``: its zone reaches this much past its sides and its depth (an opening
    found in a photo, whose sides are a few centimeters unsure)."""

    at_m: tuple
    width_m: float
    clearance_m: float | None
    height_m: float
    sill_m: float = 0.0
    where: str = ""
    margin_m: float = 0.0

    @property
    def zone_m(self) -> tuple[float, float]:
        """The width and depth of the zone kept clear (a door's depth is its width
        unless its clearance is given), the margin added."""
        depth = self.width_m if self.clearance_m is None else self.clearance_m
        return self.width_m + 2 * self.margin_m, depth + self.margin_m


@dataclass(frozen=True)
class Curve:
    """A group's curve: ``segment_m`` ((x0, y0), (x1, y1)) or ``arc`` (center, r, a0, a1)."""

    segment_m: tuple | None
    arc: tuple | None
    spacing_m: float
    anchor_fixed: bool
    stiffness: float | None
    schedule: str | None


@dataclass(frozen=True)
class Group:
    id: str
    rigid: bool
    parent: str | None
    offset_m: tuple
    at_m: tuple | None
    yaw_rad: float | None
    fixed: bool
    curve: Curve | None
    where: str
    automatic: bool = False


@dataclass(frozen=True)
class Item:
    """One item after ``count`` expansion; ``kind`` carries the effective size,
    access and collision flag."""

    id: str
    kind: Kind
    in_catalog: bool
    group: str | None
    offset_m: tuple
    yaw_rad: float | None
    at_m: tuple | None
    fixed: bool
    elevation_m: float
    rules: bool
    where: str


@dataclass(frozen=True)
class Constraint:
    """A constraint with ids resolved (tuples of item/group ids) and angles in radians."""

    type: str
    args: dict
    stiffness: float | None
    schedule: str | None
    where: str


@dataclass(frozen=True)
class Spec:
    """A checked spec file (see the module docstring for the format).

    Attributes
    ----------
    path : Path
    polygon_m : (m, 2) ndarray or None
        The floor from the file; ``None`` when it must come from :func:`build`.
    height_m : float
    preset : str or None
    doors, windows : tuple of Opening
    solver : Solver
    groups, items, constraints : tuples of Group, Item, Constraint
        With a preset: as furnished for the file's own floor (re-furnished by
        :func:`build` for another floor).
    open_edges : tuple of int
        Edges of ``polygon_m`` (counter-clockwise order) that are not walls.
    camera : layout.camera.Camera or None
        The photo the layout is made for.
    """

    path: Path
    polygon_m: np.ndarray | None
    height_m: float
    preset: str | None
    doors: tuple
    windows: tuple
    solver: Solver
    groups: tuple
    items: tuple
    constraints: tuple
    constraint_tables: tuple = ()
    open_edges: tuple = ()
    camera: object = None


class _Reader:
    """Checks values of one file; every error names the file."""

    def __init__(self, path):
        self.file = str(path)

    def error(self, where, message):
        return LayoutError(f"{self.file}: {where}: {message}")

    @contextmanager
    def context(self, where):
        """Re-raise builder errors with the file (and the entry, if given) in front."""
        try:
            yield
        except LayoutError as e:
            prefix = self.file if where is None else f"{self.file}: {where}"
            raise LayoutError(f"{prefix}: {e}") from None

    # ------------------------------------------------------------ primitive values

    def table(self, value, where, allowed, required=()):
        if not isinstance(value, dict):
            raise self.error(where, f"expected a table {{ ... }}, got {_show(value)}")
        unknown = [k for k in value if k not in allowed]
        if unknown:
            close = difflib.get_close_matches(unknown[0], allowed, n=1) if len(unknown[0]) <= 100 else []
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise self.error(where, f"unknown field {unknown[0]!r}; {hint}allowed fields: "
                                    f"{', '.join(allowed)}")
        for r in required:
            names = r.split("|")
            if not any(n in value for n in names):
                raise self.error(where, f"missing field {' or '.join(repr(n) for n in names)}")
        return value

    def array_of_tables(self, doc, key):
        value = doc.get(key, [])
        if not isinstance(value, list):
            raise self.error(key, f"expected an array of tables [[{key}]], got {_show(value)}")
        if len(value) > MAX_ENTRIES:
            raise self.error(key, f"{len(value):,} entries; at most {MAX_ENTRIES:,}")
        return value

    def number(self, value, where, field, *, positive=False, nonnegative=False, unit="m"):
        if not _is_number(value):
            raise self.error(where, f"{field} = {_show(value)} is not a number"
                                    + (f" (expected {unit})" if unit else ""))
        v = float(value)
        if not math.isfinite(v):
            raise self.error(where, f"{field} = {_show(value)} is not a finite number")
        if positive and v <= 0:
            raise self.error(where, f"{field} = {_show(value)} must be greater than 0")
        if nonnegative and v < 0:
            raise self.error(where, f"{field} = {_show(value)} must not be negative")
        return v

    def integer(self, value, where, field, *, minimum=None, maximum=None):
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(where, f"{field} = {_show(value)} is not an integer")
        if minimum is not None and value < minimum:
            raise self.error(where, f"{field} = {value} must be at least {minimum}")
        if maximum is not None and value > maximum:
            raise self.error(where, f"{field} = {value} must be at most {maximum}")
        return value

    def boolean(self, value, where, field):
        if not isinstance(value, bool):
            raise self.error(where, f"{field} = {_show(value)} is not true or false")
        return value

    def string(self, value, where, field, choices=None):
        if not isinstance(value, str):
            raise self.error(where, f"{field} = {_show(value)} is not a string")
        if choices is not None and value not in choices:
            close = difflib.get_close_matches(value, choices, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise self.error(where, f"{field} = {_show(value)} is not one of "
                                    f"{', '.join(repr(c) for c in choices)}; {hint}".rstrip("; "))
        return value

    def vector(self, value, where, field, n, meaning):
        if not isinstance(value, list) or len(value) != n:
            raise self.error(where, f"{field} = {_show(value)} must be a list of {n} numbers ({meaning})")
        for v in value:
            if not _is_number(v) or not math.isfinite(float(v)):
                raise self.error(where, f"{field} = {_show(value)} must be a list of {n} finite "
                                        f"numbers ({meaning})")
        return tuple(float(v) for v in value)

    def vector_checked(self, value, where, field, n, meaning, *, positive=False, nonnegative=False):
        vec = self.vector(value, where, field, n, meaning)
        if positive and any(v <= 0 for v in vec):
            raise self.error(where, f"{field} = {_show(value)}: every value must be greater than 0 "
                                    f"({meaning})")
        if nonnegative and any(v < 0 for v in vec):
            raise self.error(where, f"{field} = {_show(value)}: no value may be negative ({meaning})")
        return vec

    def point(self, value, where, field):
        return self.vector(value, where, field, 2, "[x, y] in meters")

    def polygon(self, value, where):
        if isinstance(value, list) and len(value) > MAX_CORNERS:
            raise self.error(where, f"{len(value):,} corners; a room's outline has at most {MAX_CORNERS:,}")
        if not isinstance(value, list) or not all(isinstance(p, list) for p in value):
            raise self.error(where, f"{_show(value)} must be a list of [x, y] corners in meters")
        pts = [self.point(p, where, f"vertex {k}") for k, p in enumerate(value)]
        if len(pts) > 3 and pts[0] == pts[-1]:
            pts = pts[:-1]
        if len(pts) < 3:
            raise self.error(where, f"{_show(value)} has {len(pts)} vertices; a floor needs at least 3 "
                                    "corners, e.g. [[0, 0], [4, 0], [4, 3], [0, 3]]")
        return np.array(pts, dtype=np.float64)

    def stiffness(self, table, where):
        k = table.get("stiffness")
        if k is not None:
            k = self.number(k, where, "stiffness", unit="")
            if not 0.0 <= k <= 1.0:
                raise self.error(where, f"stiffness = {_show(table['stiffness'])} must lie in [0, 1]")
        s = table.get("schedule")
        if s is not None:
            s = self.string(s, where, "schedule", SCHEDULES)
        return k, s


# ----------------------------------------------------------------------- room


def _read_openings(r, room, key, fields):
    value = room.get(key, [])
    if not isinstance(value, list):
        raise r.error(f"room.{key}", f"expected a list of tables, got {_show(value)}")
    if len(value) > MAX_OPENINGS:
        raise r.error(f"room.{key}", f"{len(value):,} entries; a room has at most {MAX_OPENINGS}")
    out = []
    for n, d in enumerate(value):
        where = f"room.{key}[{n}]"
        r.table(d, where, fields, ("at",))
        at = r.point(d["at"], where, "at")
        if key == "doors":
            out.append(Opening(
                at_m=at,
                width_m=r.number(d.get("width", 0.9), where, "width", positive=True),
                clearance_m=(None if "clearance" not in d
                             else r.number(d["clearance"], where, "clearance", positive=True)),
                height_m=r.number(d.get("height", 2.1), where, "height", positive=True),
                where=where,
            ))
        else:
            out.append(Opening(
                at_m=at,
                width_m=r.number(d.get("width", 1.2), where, "width", positive=True),
                clearance_m=r.number(d.get("clearance", 0.4), where, "clearance", positive=True),
                height_m=r.number(d.get("height", 1.2), where, "height", positive=True),
                sill_m=r.number(d.get("sill", 0.9), where, "sill", nonnegative=True),
                where=where,
            ))
    return tuple(out)


def _distance_to_walls(polygon_m, point):
    return float(edge_distances(np.asarray(point, dtype=np.float64)[None], polygon_m).min())


# ------------------------------------------------------------------ furniture


def _entry_name(where, table):
    """``items[3] (id "sofa")`` when the entry has a usable id, else ``items[3]``."""
    if isinstance(table, dict) and isinstance(table.get("id"), str):
        return f'{where} (id "{table["id"]}")'
    return where


def _read_groups(r, tables, where_prefix=""):
    groups = []
    for n, g in enumerate(tables):
        where = _entry_name(f"{where_prefix}groups[{n}]", g)
        r.table(g, where, GROUP_FIELDS, ("id",))
        gid = r.string(g["id"], where, "id")
        rigid = r.boolean(g.get("rigid", False), where, "rigid")
        curve = None
        if "curve" in g:
            if rigid:
                raise r.error(where, "curve needs a non-rigid group (set rigid = false)")
            curve = _read_curve(r, g["curve"], f"{where}.curve")
        fixed = r.boolean(g.get("fixed", False), where, "fixed")
        at = None if "at" not in g else r.point(g["at"], where, "at")
        if fixed and at is None:
            raise r.error(where, "fixed = true needs a position: add at = [x, y]")
        yaw = None
        if "yaw_deg" in g:
            yaw = math.radians(r.number(g["yaw_deg"], where, "yaw_deg", unit="degrees"))
        if fixed and yaw is None:
            yaw = 0.0
        groups.append(Group(
            id=gid, rigid=rigid,
            parent=None if "group" not in g else r.string(g["group"], where, "group"),
            offset_m=(0.0, 0.0) if "offset" not in g else r.point(g["offset"], where, "offset"),
            at_m=at, yaw_rad=yaw, fixed=fixed, curve=curve, where=where,
        ))
    return groups


def _read_curve(r, c, where):
    r.table(c, where, CURVE_FIELDS)
    if ("arc" in c) == ("segment" in c):
        raise r.error(where, "give exactly one of arc = { center, radius, start_deg, end_deg } "
                             "or segment = [[x0, y0], [x1, y1]]")
    segment = arc = None
    if "segment" in c:
        s = c["segment"]
        if not isinstance(s, list) or len(s) != 2:
            raise r.error(where, f"segment = {_show(s)} must be two points [[x0, y0], [x1, y1]]")
        segment = (r.point(s[0], where, "segment"), r.point(s[1], where, "segment"))
        if segment[0] == segment[1]:
            raise r.error(where, f"segment = {_show(s)} has zero length")
    else:
        a = r.table(c["arc"], f"{where}.arc", ARC_FIELDS, ARC_FIELDS)
        w = f"{where}.arc"
        arc = (r.point(a["center"], w, "center"),
               r.number(a["radius"], w, "radius", positive=True),
               math.radians(r.number(a["start_deg"], w, "start_deg", unit="degrees")),
               math.radians(r.number(a["end_deg"], w, "end_deg", unit="degrees")))
    k, s = r.stiffness(c, where)
    return Curve(
        segment_m=segment, arc=arc,
        spacing_m=r.number(c.get("spacing", 0.0), where, "spacing", nonnegative=True),
        anchor_fixed=r.boolean(c.get("anchor_fixed", False), where, "anchor_fixed"),
        stiffness=k, schedule=s,
    )


def _per_copy(r, value, where, field, count, read):
    """A field that may hold one value for all copies or a list of ``count`` values."""
    if count > 1 and isinstance(value, list) and value and isinstance(value[0], list):
        if len(value) != count:
            raise r.error(where, f"{field} has {len(value)} entries but count = {count}; give one "
                                 "value for all copies or exactly one per copy")
        return [read(v) for v in value]
    if count > 1 and field == "yaw_deg" and isinstance(value, list):
        if len(value) != count:
            raise r.error(where, f"yaw_deg has {len(value)} entries but count = {count}")
        return [read(v) for v in value]
    one = read(value)
    return [one] * count


def _read_items(r, tables, groups_by_id, where_prefix=""):
    """Items after count expansion, and id -> expanded ids."""
    items, aliases = [], {}
    for n, t in enumerate(tables):
        where = _entry_name(f"{where_prefix}items[{n}]", t)
        r.table(t, where, ITEM_FIELDS, ("id",))
        iid = r.string(t["id"], where, "id")
        if not iid or iid == "*":
            raise r.error(where, f"id = {_show(iid)} is not a usable name")
        size = None
        if "size" in t:
            size = r.vector_checked(t["size"], where, "size", 3, "width, depth, height in meters",
                                    positive=True)
        kind_name = t.get("kind", "item")
        kind_name = r.string(kind_name, where, "kind")
        in_catalog = kind_name in catalog.CATALOG
        if in_catalog:
            kind = catalog.CATALOG[kind_name]
        elif size is None:
            if "kind" not in t:
                raise r.error(where, "needs a kind from the catalog (`layout kinds`) or an explicit "
                                     "size = [width, depth, height]")
            catalog.kind_or_error(kind_name, f"{r.file}: {where}")
        else:
            kind = Kind(kind_name, size, label=kind_name)
        if size is not None:
            kind = dataclasses.replace(kind, size_m=size)
        if "access" in t:
            kind = dataclasses.replace(kind, access_m=r.vector_checked(
                t["access"], where, "access", 4, "back, left, front, right clearance in meters",
                nonnegative=True))
        if "collides" in t:
            kind = dataclasses.replace(kind, collides=r.boolean(t["collides"], where, "collides"))
        count = r.integer(t.get("count", 1), where, "count", minimum=1, maximum=MAX_COUNT)
        group = None
        if "group" in t:
            group = r.string(t["group"], where, "group")
            if group not in groups_by_id:
                raise r.error(where, f"group = {_show(group)} is not a [[groups]] id; "
                                     + _known_hint(group, list(groups_by_id), "groups"))
        rigid = group is not None and groups_by_id[group].rigid
        if "offset" in t and not rigid:
            raise r.error(where, f"offset = {_show(t['offset'])} only applies to members of a rigid "
                                 "group; use at = [x, y] for a start position")
        if "at" in t and rigid:
            raise r.error(where, f"at = {_show(t['at'])}: members of rigid group {group!r} are placed "
                                 "by offset = [x, y] in the group's frame")
        fixed = r.boolean(t.get("fixed", False), where, "fixed")
        if fixed and "at" not in t:
            raise r.error(where, "fixed = true needs a position: add at = [x, y]")
        offsets = _per_copy(r, t.get("offset", [0.0, 0.0]), where, "offset", count,
                            lambda v: r.point(v, where, "offset"))
        ats = _per_copy(r, t.get("at"), where, "at", count,
                        lambda v: None if v is None else r.point(v, where, "at"))
        yaws = _per_copy(r, t.get("yaw_deg"), where, "yaw_deg", count,
                         lambda v: None if v is None else math.radians(r.number(v, where, "yaw_deg",
                                                                                unit="degrees")))
        if count > 1 and fixed and len(set(ats)) < count:
            raise r.error(where, f"fixed copies need one position each: at = a list of {count} points")
        if count > 1 and rigid and len(set(offsets)) < count:
            raise r.error(where, f"copies in rigid group {group!r} need one offset each: offset = a list "
                                 f"of {count} points")
        elevation = r.number(t.get("elevation", 0.0), where, "elevation", nonnegative=True)
        rules = r.boolean(t.get("rules", True), where, "rules")
        ids = [iid] if count == 1 else [f"{iid}_{k + 1}" for k in range(count)]
        if len(items) + count > MAX_ENTRIES:
            raise r.error(where, f"more than {MAX_ENTRIES:,} items in all (counting each copy); a room holds "
                                 "far fewer")
        aliases[iid] = ids
        for k, cid in enumerate(ids):
            items.append(Item(
                id=cid, kind=kind, in_catalog=in_catalog, group=group, offset_m=offsets[k],
                yaw_rad=0.0 if fixed and yaws[k] is None else yaws[k], at_m=ats[k], fixed=fixed,
                elevation_m=elevation, rules=rules, where=where,
            ))
    return items, aliases


def _known_hint(name, known, what="ids"):
    close = difflib.get_close_matches(str(name), known, n=2)
    shown = ", ".join(known[:8]) + (", …" if len(known) > 8 else "")
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return f"{hint}known {what}: {shown or '(none)'}"


def _check_names(r, groups, items, aliases):
    """Unique ids across groups and items; group parents exist; no cycles."""
    seen = {}
    for entry in list(groups) + list(items):
        if entry.id in seen:
            raise r.error(entry.where, f"duplicate id {entry.id!r} (also used by {seen[entry.id]})")
        seen[entry.id] = entry.where
    for base, ids in aliases.items():
        if len(ids) > 1 and base in seen:
            where = next(i.where for i in items if i.id == ids[0])
            raise r.error(where, f"id {base!r} with count is also used by {seen[base]}")
    by_id = {g.id: g for g in groups}
    for g in groups:
        if g.parent is not None and g.parent not in by_id:
            raise r.error(g.where, f"group = {_show(g.parent)} is not a [[groups]] id; "
                                   + _known_hint(g.parent, list(by_id), "groups"))
        if g.parent is not None and by_id[g.parent].rigid:
            if not g.rigid:
                raise r.error(g.where, f"a non-rigid group cannot sit inside rigid group {g.parent!r}")
            if g.at_m is not None:
                raise r.error(g.where, f"at: groups inside rigid group {g.parent!r} are placed by offset")
        elif g.offset_m != (0.0, 0.0):
            raise r.error(g.where, "offset only applies inside a rigid parent group")
        chain, p = [g.id], g.parent
        while p is not None:
            if p in chain:
                raise r.error(g.where, f"groups nest in a cycle: {' -> '.join(chain + [p])}")
            if len(chain) > MAX_GROUP_DEPTH:
                raise r.error(g.where, f"groups nest more than {MAX_GROUP_DEPTH} deep ({' -> '.join(chain[:4])} "
                                       "-> ...); a room's groups nest a few deep")
            chain.append(p)
            p = by_id[p].parent
    for g in groups:
        if g.curve is not None and not any(i.group == g.id for i in items) and not any(
                h.parent == g.id for h in groups):
            raise r.error(g.where, "has a curve but no members (items with group = "
                                   f"{_show(g.id)})")


def _companion_groups(groups, items):
    """Put a nightstand/office chair and its bed/desk, or the pieces of a conversation
    group and their sofa, in a shared group when neither has one, so the chair may stand
    in the desk's clearance, the coffee table in the sofa's (see catalog.pairings)."""
    records = [RuleItem(n, it.kind, it.group, it.rules) for n, it in enumerate(items) if it.in_catalog]
    partner = catalog.pairings(records)
    taken = {g.id for g in groups} | {i.id for i in items}
    new_group = {}
    items = list(items)
    groups = list(groups)
    for n, p in partner.items():
        member, host = items[n], items[p.index]
        if member.group is not None or (host.group is not None and host.id not in new_group):
            continue
        gid = new_group.get(host.id)
        if gid is None:
            gid, k = f"{host.id}_set", 2
            while gid in taken:
                gid, k = f"{host.id}_set{k}", k + 1
            taken.add(gid)
            new_group[host.id] = gid
            groups.append(Group(id=gid, rigid=False, parent=None, offset_m=(0.0, 0.0), at_m=None,
                                yaw_rad=None, fixed=False, curve=None,
                                where=f"group {gid!r} (made for {host.id!r})", automatic=True))
            items[p.index] = dataclasses.replace(host, group=gid)
        items[n] = dataclasses.replace(member, group=gid)
    return groups, items


# ----------------------------------------------------------------- constraints


class _Names:
    """Resolves ids in constraints to expanded item/group ids."""

    def __init__(self, r, groups, items, aliases):
        self.r = r
        self.groups = {g.id for g in groups}
        self.items = {i.id: i for i in items}
        self.aliases = dict(aliases)
        self.known = [g.id for g in groups if not g.automatic] + list(aliases)

    def many(self, value, where, field, *, groups=True):
        """A member list (or one id); counted ids expand to all copies."""
        values = value if isinstance(value, list) else [value]
        out = []
        for v in values:
            out.extend(self._one_or_all(v, where, field, groups))
        if not out:
            raise self.r.error(where, f"{field} = {_show(value)} names no item")
        if len(set(out)) != len(out):
            raise self.r.error(where, f"{field} = {_show(value)} names an item twice")
        return tuple(out)

    def one(self, value, where, field, *, groups=True):
        ids = self._one_or_all(value, where, field, groups)
        if len(ids) != 1:
            raise self.r.error(where, f"{field} = {_show(value)} names {len(ids)} items "
                                      f"({ids[0]} … {ids[-1]}); name one, e.g. {_show(ids[0])}")
        return ids[0]

    def _one_or_all(self, v, where, field, groups):
        if not isinstance(v, str):
            raise self.r.error(where, f"{field} = {_show(v)} is not an id (a string)")
        if v in self.groups:
            if not groups:
                raise self.r.error(where, f"{field} = {_show(v)} is a group; this constraint takes items")
            return [v]
        if v in self.aliases:
            return list(self.aliases[v])
        if v in self.items:
            return [v]
        raise self.r.error(where, f"{field} = {_show(v)} names no item or group; "
                                  + _known_hint(v, self.known))


def _read_constraints(r, tables, names, where_prefix=""):
    out = []
    for n, c in enumerate(tables):
        where = f"{where_prefix}constraints[{n}]"
        if not isinstance(c, dict):
            raise r.error(where, f"expected a table, got {_show(c)}")
        if "type" not in c:
            raise r.error(where, f"missing field 'type' (one of {', '.join(CONSTRAINT_FIELDS)})")
        ctype = r.string(c["type"], where, "type", tuple(CONSTRAINT_FIELDS))
        where = f'{where} (type "{ctype}")'
        required, optional = CONSTRAINT_FIELDS[ctype]
        allowed = list(COMMON_FIELDS) + [f for spec in required for f in spec.split("|")] + list(optional)
        r.table(c, where, allowed, required)
        k, s = r.stiffness(c, where)
        out.append(Constraint(ctype, _constraint_args(r, ctype, c, names, where), k, s, where))
    return out


def _constraint_args(r, ctype, c, names, where):
    deg = lambda f: math.radians(r.number(c.get(f, 0.0), where, f, unit="degrees"))  # noqa: E731
    mode = lambda: r.string(c.get("mode", "eq"), where, "mode", MODES)  # noqa: E731
    if ctype == "distance":
        return dict(a=names.many(c["a"], where, "a"), b=names.one(c["b"], where, "b"),
                    distance=r.number(c["distance"], where, "distance", nonnegative=True), mode=mode())
    if ctype == "focal_distance":
        return dict(focal=names.one(c["focal"], where, "focal"),
                    members=names.many(c["members"], where, "members"),
                    distance=r.number(c["distance"], where, "distance", nonnegative=True), mode=mode())
    if ctype == "lane":
        origin = names.one(c["origin"], where, "origin")
        members = c.get("members", "*")
        if members == "*":
            members = tuple(i for i in names.items if i != origin)
        else:
            members = names.many(members, where, "members")
        return dict(origin=origin, members=members, angle=deg("angle_deg"),
                    length=r.number(c["length"], where, "length", positive=True),
                    half_width=r.number(c["half_width"], where, "half_width", nonnegative=True),
                    start=r.point(c.get("start", [0.0, 0.0]), where, "start"))
    if ctype == "heat":
        return dict(members=names.many(c["members"], where, "members"),
                    target=r.point(c["target"], where, "target"),
                    frame=None if "frame" not in c else names.one(c["frame"], where, "frame"))
    if ctype == "symmetry":
        return dict(focal=names.one(c["focal"], where, "focal"),
                    members=names.many(c["members"], where, "members"), angle=deg("angle_deg"))
    if ctype == "balance":
        members = None if "members" not in c else names.many(c["members"], where, "members")
        return dict(members=members)
    if ctype in ("wall", "wall_orientation", "against_wall"):
        if "item" in c and "items" in c:
            raise r.error(where, "give item or items, not both")
        field = "item" if "item" in c else "items"
        ids = names.many(c[field], where, field, groups=ctype != "against_wall")
        if ctype == "wall":
            dist = None if "distance" not in c else r.number(c["distance"], where, "distance",
                                                             nonnegative=True)
            grouped = [i for i in ids if i in names.groups]
            if dist is None and grouped:
                raise r.error(where, f"{grouped[0]!r} is a group: give distance (of its center from "
                                     "the wall)")
            return dict(items=ids, distance=dist, mode=mode())
        if ctype == "wall_orientation":
            return dict(items=ids, angle=deg("angle_deg"))
        return dict(items=ids, gap=r.number(c.get("gap", 0.0), where, "gap", nonnegative=True))
    if ctype in ("face", "parallel"):
        args = dict(a=names.many(c["a"], where, "a"), b=names.one(c["b"], where, "b"),
                    angle=deg("angle_deg"))
        if ctype == "face":
            args["mutual"] = r.boolean(c.get("mutual", False), where, "mutual")
        return args
    # stack
    if "items" in c:
        if "base" in c or "top" in c:
            raise r.error(where, "give base and top, or items = [bottom, …, top], not both")
        chain = names.many(c["items"], where, "items", groups=False)
        if len(chain) < 2:
            raise r.error(where, f"items = {_show(c['items'])} needs at least two items, bottom first")
    else:
        if "top" not in c:
            raise r.error(where, "missing field 'top' (or use items = [bottom, …, top])")
        chain = (names.one(c["base"], where, "base", groups=False),
                 names.one(c["top"], where, "top", groups=False))
        if chain[0] == chain[1]:
            raise r.error(where, f"base and top are both {chain[0]!r}")
    return dict(chain=chain)


# ------------------------------------------------------------------- loading


def load_spec(path) -> Spec:
    """Read and check a spec file.

    Parameters
    ----------
    path : str or os.PathLike
        A TOML file in the format of this module's docstring.

    Returns
    -------
    Spec

    Raises
    ------
    LayoutError
        For a missing or unreadable file, a TOML syntax error (with its line and
        column) or any invalid entry; the message starts with the file path.
    """
    path = Path(path)
    if (problem := path_problem(path, missing="no such file", folder="is a directory, not a spec file")) is not None:
        raise LayoutError(f"{path}: {problem}")
    if path.stat().st_size > MAX_SPEC_BYTES:
        raise LayoutError(f"{path}: is {path.stat().st_size:,} bytes; a spec is a short TOML text (at most "
                          f"{MAX_SPEC_BYTES >> 10} KB)")
    try:
        data = path.read_bytes()
    except OSError as error:
        raise LayoutError(f"{path}: cannot be read ({error.strerror or error})") from None
    return spec_from_bytes(data, path)


def spec_from_bytes(data: bytes, where) -> Spec:
    """Check a spec file's contents (an upload, say), as :func:`load_spec` does.

    Parameters
    ----------
    data : bytes
        The TOML file, UTF-8.
    where : str or os.PathLike
        Names the spec in error messages and becomes ``Spec.path``.

    Raises
    ------
    LayoutError
        For text that is not UTF-8, a TOML syntax error (with its line and column) or any
        invalid entry; the message starts with ``where``.
    """
    try:
        doc = tomllib.loads(bytes(data).decode("utf-8"))
    except UnicodeDecodeError as e:
        raise LayoutError(f"{where}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except tomllib.TOMLDecodeError as e:
        raise LayoutError(f"{where}: invalid TOML: {e}") from None
    except RecursionError:
        raise LayoutError(f"{where}: invalid TOML: arrays or tables nested thousands deep; a spec nests "
                          "three deep at most (a polygon's points)") from None
    return _parse(_Reader(where), Path(where), doc)


def spec_from_dict(doc, where="<spec>") -> Spec:
    """Check a spec given as a dict, shaped like a spec file's TOML (see the module
    docstring): specs made in code, e.g. a room preset on a measured floor.

    Parameters
    ----------
    doc : dict
        ``{"room": {...}, "items": [...], ...}`` with lists (not arrays) for points, as
        :func:`tomllib.load` would give. Not modified.
    where : str
        Names the spec in error messages and becomes ``Spec.path`` (e.g.
        ``"--room bedroom"``).

    Returns
    -------
    Spec
        With a ``room.preset`` and a ``room.polygon``: furnished for that floor's area.

    Raises
    ------
    LayoutError
        For any invalid entry; the message starts with ``where``.
    """
    if not isinstance(doc, dict):
        raise LayoutError(f"{where}: expected a table (a dict of sections), got {_show(doc)}")
    return _parse(_Reader(where), Path(where), doc)


def _parse(r, path, doc):
    unknown = [k for k in doc if k not in TOP_LEVEL]
    if unknown:
        close = difflib.get_close_matches(unknown[0], TOP_LEVEL, n=1)
        hint = f"did you mean [{close[0]}]? " if close else ""
        raise r.error(unknown[0], f"unknown section or key {unknown[0]!r}; {hint}allowed: "
                                  f"{', '.join(TOP_LEVEL)}")
    if "room" not in doc:
        raise LayoutError(f"{path}: missing [room] section (polygon, height, doors, windows)")
    room = r.table(doc["room"], "room", ROOM_FIELDS)
    height = r.number(room.get("height", 2.5), "room", "height", positive=True)
    polygon = None
    open_edges = room.get("open_edges", [])
    if not isinstance(open_edges, list):
        raise r.error("room", f"open_edges = {_show(open_edges)} must be a list of edge numbers, e.g. [2]")
    open_edges = [r.integer(e, "room", "open_edges", minimum=0) for e in open_edges]
    if open_edges and "polygon" not in room:
        raise r.error("room", "open_edges needs a polygon: edge k runs from polygon corner k to k + 1")
    if "polygon" in room:
        polygon = r.polygon(room["polygon"], "room.polygon")
        with r.context(None):
            # The builder knows what a usable floor is (simple, non-degenerate), and
            # renumbers the open edges when it turns the corners counter-clockwise.
            b = LayoutBuilder(polygon, height, open_edges=open_edges)
            polygon, open_edges = b.polygon_m, [int(e) for e in np.flatnonzero(~b.edge_wall)]
    preset = None
    if "preset" in room:
        from . import presets

        preset = r.string(room["preset"], "room", "preset", tuple(presets.PRESETS))
        for key in ("items", "groups"):
            if doc.get(key):
                raise r.error(key, f"room.preset = {_show(preset)} furnishes the room itself; remove "
                                   f"either the preset or the [[{key}]] entries")
    doors = _read_openings(r, room, "doors", DOOR_FIELDS)
    windows = _read_openings(r, room, "windows", WINDOW_FIELDS)
    if polygon is not None:
        for o in doors + windows:
            _check_on_wall(r, polygon, o)

    camera = _read_camera(r, doc["camera"]) if "camera" in doc else None
    settings = r.table(doc.get("solver", {}), "solver", tuple(SOLVER_FIELDS))
    kwargs = {}
    for key, typ in SOLVER_FIELDS.items():
        if key in settings:
            v = settings[key]
            if typ is int:
                kwargs[key] = r.integer(v, "solver", key, minimum=1)
            elif typ is float:
                kwargs[key] = r.number(v, "solver", key, unit="")
            else:
                kwargs[key] = r.string(v, "solver", key)
    try:
        solver = Solver(**kwargs)
    except LayoutError as e:
        raise LayoutError(f"{path}: {e}") from None

    group_tables = r.array_of_tables(doc, "groups")
    item_tables = r.array_of_tables(doc, "items")
    constraint_tables = r.array_of_tables(doc, "constraints")
    if preset is None and not item_tables:
        raise LayoutError(f"{path}: no [[items]]; add some, or set room.preset "
                          f"(one of: {', '.join(_preset_names())})")
    spec = Spec(path=path, polygon_m=polygon, height_m=height, preset=preset, doors=doors,
                windows=windows, solver=solver, groups=(), items=(), constraints=(),
                constraint_tables=tuple(constraint_tables), open_edges=tuple(open_edges), camera=camera)
    if preset is not None:
        if polygon is None:
            return spec  # furnished by build(), once the floor is known
        g_tables, i_tables, c_tables = _preset_tables(spec, polygon)
        groups, items, constraints = _furnish(r, g_tables, i_tables, constraint_tables, c_tables,
                                              f"preset {preset!r}: ")
    else:
        groups, items, constraints = _furnish(r, group_tables, item_tables, constraint_tables)
    return dataclasses.replace(spec, groups=tuple(groups), items=tuple(items),
                               constraints=tuple(constraints))


def _read_camera(r, value):
    from .camera import Camera

    t = r.table(value, "camera", ("K", "camera_from_floor", "size_px"), ("K", "camera_from_floor", "size_px"))

    def matrix(field, rows, meaning):
        if not isinstance(t[field], list) or len(t[field]) != rows:
            raise r.error("camera", f"{field} = {_show(t[field])} must be {rows} rows of {rows} numbers ({meaning})")
        return [r.vector(row, "camera", field, rows, meaning) for row in t[field]]

    K = matrix("K", 3, "the intrinsics, pixels")
    T = matrix("camera_from_floor", 4, "floor meters to camera, OpenCV axes")
    if not isinstance(t["size_px"], list) or len(t["size_px"]) != 2:
        raise r.error("camera", f"size_px = {_show(t['size_px'])} must be [width, height] in pixels")
    size = tuple(r.integer(v, "camera", "size_px", minimum=2) for v in t["size_px"])
    try:
        return Camera(K, T, size)
    except LayoutError as e:
        raise r.error("camera", str(e)) from None


def _preset_names():
    from . import presets

    return tuple(presets.PRESETS)


def _preset_tables(spec, polygon_m):
    """Preset groups, items and constraints for a floor."""
    from . import presets

    parts = presets.preset_items(spec.preset, abs(polygon_area(polygon_m)))
    return parts.get("groups", []), parts["items"], parts.get("constraints", [])


def _furnish(r, group_tables, item_tables, constraint_tables, preset_constraints=(), prefix=""):
    groups = _read_groups(r, group_tables, prefix)
    by_id = {g.id: g for g in groups}
    items, aliases = _read_items(r, item_tables, by_id, prefix)
    _check_names(r, groups, items, aliases)
    groups, items = _companion_groups(groups, items)
    names = _Names(r, groups, items, aliases)
    constraints = _read_constraints(r, list(preset_constraints), names, prefix)
    constraints += _read_constraints(r, constraint_tables, names)
    return groups, items, constraints


def _check_on_wall(r, polygon_m, o):
    d = _distance_to_walls(polygon_m, o.at_m)
    if d > DOOR_SNAP_M:
        raise r.error(o.where, f"at = {_show(list(o.at_m))} is {d:.2f} m from the nearest wall; put it "
                               f"on a wall (within {DOOR_SNAP_M} m)")


# -------------------------------------------------------------------- building


def build(spec: Spec, *, polygon_m=None):
    """The model and solver of a spec.

    Parameters
    ----------
    spec : Spec
        From :func:`load_spec`.
    polygon_m : (m, 2) array_like, optional
        Floor polygon in meters replacing the spec's (e.g. measured from a photo);
        a preset is then chosen for this floor's area. Doors and windows of the spec
        snap to its nearest walls.

    Returns
    -------
    model : Model
    solver : Solver

    Raises
    ------
    LayoutError
        When the floor is missing or invalid, the items do not fit it, or a door is
        far from every wall.
    """
    r = _Reader(spec.path)
    height = spec.height_m
    if polygon_m is None:
        if spec.polygon_m is None:
            raise LayoutError(f"{spec.path}: room.polygon is missing and no floor polygon was given")
        where, polygon = "room.polygon", spec.polygon_m
    else:
        where = "floor polygon (polygon_m)"
        poly = np.array(polygon_m, dtype=np.float64, copy=True)
        with r.context(where):
            polygon = LayoutBuilder(poly, height).polygon_m
    with r.context(None if polygon_m is None else where):
        b = LayoutBuilder(polygon, height, open_edges=spec.open_edges if polygon_m is None else ())
    if spec.camera is not None:
        b.set_camera(spec.camera)
    groups, items, constraints = spec.groups, spec.items, spec.constraints
    if spec.preset is not None and (polygon_m is not None or not items):
        g_tables, i_tables, c_tables = _preset_tables(spec, b.polygon_m)
        groups, items, constraints = _furnish(r, g_tables, i_tables, spec.constraint_tables, c_tables,
                                              f"preset {spec.preset!r}: ")

    for o in spec.doors:
        _check_on_wall(r, b.polygon_m, o)
        with r.context(o.where):
            b.add_door(o.at_m, *o.zone_m, o.height_m)
    for o in spec.windows:
        _check_on_wall(r, b.polygon_m, o)
        with r.context(o.where):
            width, depth = o.zone_m
            b.add_window(o.at_m, width, o.sill_m, o.height_m, depth)

    index = {}
    pending = list(groups)
    while pending:  # parents before children (cycles were refused when loading)
        g = next(g for g in pending if g.parent is None or g.parent in index)
        pending.remove(g)
        with r.context(g.where):
            index[g.id] = b.add_group(
                g.id, rigid=g.rigid, group=None if g.parent is None else index[g.parent],
                offset_m=g.offset_m, yaw_rad=g.yaw_rad, position_m=g.at_m, fixed=g.fixed)
    for it in items:
        k = it.kind
        with r.context(it.where):
            index[it.id] = b.add_item(
                it.id, k.size_m, kind=k.name, access_m=k.access_m, collides=k.collides,
                group=None if it.group is None else index[it.group], offset_m=it.offset_m,
                yaw_rad=it.yaw_rad, position_m=it.at_m, fixed=it.fixed, elevation_m=it.elevation_m)
    for g in groups:
        if g.curve is None:
            continue
        c = g.curve
        members = [index[h.id] for h in groups if h.parent == g.id] + [
            index[i.id] for i in items if i.group == g.id]
        with r.context(f"{g.where}.curve"):
            b.curve(index[g.id], members, segment_m=c.segment_m, arc=c.arc, spacing_m=c.spacing_m,
                    anchor_fixed=c.anchor_fixed, k0=c.stiffness, schedule=c.schedule)

    rigid = {g.id for g in groups if g.rigid}
    records = [RuleItem(index[i.id], i.kind, i.group, i.rules, i.group in rigid)
               for i in items if i.in_catalog]
    with r.context("default rules"):
        applied = catalog.apply_default_rules(b, records)
    sizes = {i.id: i.kind.size_m for i in items}
    # Balance moves what stands on its own; what a rule places at its partner follows it.
    followers = {a.index for a in applied if a.name in catalog.PLACED_AT_PARTNER}
    for c in constraints:
        with r.context(c.where):
            _add_constraint(b, c, index, sizes, followers)
    try:
        model = b.finalize()
    except LayoutError as e:
        raise LayoutError(f"{spec.path}: {e}") from None
    return model, spec.solver


def _add_constraint(b, c, index, sizes, followers):
    a = c.args
    kw = dict(k0=c.stiffness, schedule=c.schedule)
    t = c.type
    if t == "distance":
        for i in a["a"]:
            b.distance(index[i], index[a["b"]], a["distance"], mode=a["mode"], **kw)
    elif t == "focal_distance":
        b.focal_distance(index[a["focal"]], [index[m] for m in a["members"]], a["distance"],
                         mode=a["mode"], **kw)
    elif t == "lane":
        b.lane(index[a["origin"]], [index[m] for m in a["members"]], angle_rad=a["angle"],
               length_m=a["length"], half_width_m=a["half_width"], start_m=a["start"], **kw)
    elif t == "heat":
        b.heat([index[m] for m in a["members"]], a["target"],
               frame=None if a["frame"] is None else index[a["frame"]], **kw)
    elif t == "symmetry":
        b.symmetry(index[a["focal"]], [index[m] for m in a["members"]], angle_rad=a["angle"], **kw)
    elif t == "balance":
        if a["members"] is None:
            b.balance(exclude=followers, **kw)
        else:
            b.balance([index[m] for m in a["members"]], **kw)
    elif t == "wall":
        for i in a["items"]:
            b.wall_distance(index[i], a["distance"], mode=a["mode"], **kw)
    elif t == "wall_orientation":
        for i in a["items"]:
            b.wall_orientation(index[i], a["angle"], **kw)
    elif t == "against_wall":
        for i in a["items"]:
            b.wall_distance(index[i], 0.5 * sizes[i][1] + a["gap"], **kw)
            b.wall_orientation(index[i], 0.0, **kw)
    elif t in ("face", "parallel"):
        for i in a["a"]:
            if t == "face":
                b.face(index[i], index[a["b"]], angle_rad=a["angle"], mutual=a["mutual"], **kw)
            else:
                b.parallel(index[i], index[a["b"]], angle_rad=a["angle"], **kw)
    elif t == "stack":
        chain = a["chain"]
        for lo, hi in zip(chain, chain[1:]):
            b.stack(index[lo], index[hi], **kw)


# ------------------------------------------------------------------- a layout as written


def read_layout(path):
    """A layout as ``layout solve`` or ``stage furnish`` wrote it (``layout_K.json``): the
    spec of its room with every item fixed where it stands, and the
    :class:`~layout.solver.Layout` of that, to render, check or plot it again.

    Returns
    -------
    spec : Spec
    layout : Layout

    Raises
    ------
    LayoutError
        For a file that is missing, not such JSON, or a room or item that will not do;
        the message starts with the file path.
    """
    path = Path(path)
    if (problem := path_problem(path, missing="no such file")) is not None:
        raise LayoutError(f"{path}: {problem}")
    if path.stat().st_size > MAX_LAYOUT_BYTES:
        raise LayoutError(f"{path}: is {path.stat().st_size:,} bytes, more than a layout_K.json holds "
                          f"({MAX_LAYOUT_BYTES >> 20} MB at most)")
    try:
        doc = json.loads(path.read_bytes().decode("utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as error:
        raise LayoutError(f"{path}: not the JSON of a layout_K.json ({str(error)[:100]})") from None
    return layout_from_dict(doc, path)


def layout_from_dict(doc, where="<layout>"):
    """:func:`read_layout` of a layout's ``to_dict()`` (the JSON, parsed)."""
    from .solver import Layout, energy_terms, initial_state

    spec = spec_of_layout(doc, where)
    model, _ = build(spec)
    state = initial_state(model, np.random.default_rng(0))
    seed = doc.get("seed")
    layout = Layout.from_state(model, state.position_m, state.yaw_rad, energy_terms(model, state), np.zeros(0), 0,
                               0, seed if isinstance(seed, int) and not isinstance(seed, bool) else None, 0.0)
    # The rules it was solved under are not in the file: its energy is the one it was solved at.
    energy = doc.get("energy")
    if _is_number(energy) and math.isfinite(energy) and energy >= 0:
        terms = doc.get("energy_by_kind")
        layout = dataclasses.replace(layout, energy=float(energy),
                                     energy_by_kind=terms if isinstance(terms, dict) else {})
    return spec, layout


def spec_of_layout(doc, where="<layout>") -> Spec:
    """The spec of a layout's ``to_dict()``: its room, every item fixed where it stands.
    Checks the layout as :func:`read_layout` does, without building it."""
    r = _Reader(where)
    if not isinstance(doc, dict) or not isinstance(doc.get("room"), dict) or not isinstance(doc.get("items"), list):
        raise LayoutError(f"{where}: not a layout_K.json (expected an object with room and items)")
    room = r.table(doc["room"], "room", ("polygon_m", "open_edges", "height_m", "doors_m", "windows_m"),
                   ("polygon_m",))
    doors = room.get("doors_m") or []
    if not isinstance(doors, list) or len(doors) > MAX_OPENINGS:
        raise r.error("room", f"doors_m must be a list of at most {MAX_OPENINGS} [[x, y], [x, y]] segments")
    spec_doors = []
    for k, d in enumerate(doors):
        a, b = (r.point(p, f"room.doors_m[{k}]", "end") for p in (d if isinstance(d, list) and len(d) == 2 else [0]))
        spec_doors.append({"at": [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2], "width": math.dist(a, b)})
    items = []
    if len(doc["items"]) > MAX_ENTRIES:
        raise r.error("items", f"{len(doc['items']):,} entries; at most {MAX_ENTRIES:,}")
    for n, it in enumerate(doc["items"]):
        where_item = f"items[{n}]"
        r.table(it, where_item, ("id", "kind", "position_m", "yaw_rad", "size_m", "group"),
                ("id", "kind", "position_m", "yaw_rad", "size_m"))
        x, y, z = r.vector(it["position_m"], where_item, "position_m", 3, "[x, y, z] meters")
        size = r.vector_checked(it["size_m"], where_item, "size_m", 3, "width, depth, height", positive=True)
        yaw = r.number(it["yaw_rad"], where_item, "yaw_rad", unit="radians")
        items.append({"id": r.string(it["id"], where_item, "id"), "kind": r.string(it["kind"], where_item, "kind"),
                      "size": list(size), "at": [x, y], "yaw_deg": math.degrees(yaw), "fixed": True,
                      "elevation": max(0.0, round(z - size[2] / 2, 9)), "rules": False})
    if not items:
        raise r.error("items", "no items: nothing to lay out")
    return spec_from_dict({"room": {"polygon": room["polygon_m"], "height": room.get("height_m", 2.5),
                                    "open_edges": room.get("open_edges", []), "doors": spec_doors},
                           "items": items}, where=where)
