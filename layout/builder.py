"""Collects items, groups and constraints, then freezes them into a :class:`Model`.

Every ``add_*`` method validates its arguments and returns an index; errors are
:class:`~layout.errors.LayoutError` with a message naming the entry and the value.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from . import _codes as codes
from . import _kernels as K
from .errors import LayoutError
from .geometry import access_zones, box_corners, polygon_area, polygon_centroid, self_intersection, stepped_wall
from .model import Model

# Default initial stiffness per kind and schedule: soft constraints fade (DECAY),
# the wall constraints and hard ones stay (CONSTANT). Collision (GROW) and
# accessibility (CONSTANT) stiffness are solver settings.
DEFAULT_STIFFNESS = {
    "distance": (0.5, codes.DECAY),
    "lane": (0.5, codes.DECAY),
    "heat": (0.5, codes.DECAY),
    "symmetry": (0.5, codes.DECAY),
    "balance": (0.5, codes.DECAY),
    "wall_distance": (0.5, codes.CONSTANT),
    "wall_orientation": (0.5, codes.CONSTANT),
    "orientation": (0.5, codes.DECAY),
    "stack": (1.0, codes.CONSTANT),
    "curve": (0.5, codes.DECAY),
}
DOOR_HEIGHT_M = 2.1
# An opening wider than the edge it is nearest stands on a wall the outline draws in steps this deep.
STEPPED_WALL_M = 0.15
# Across the room's bounding box: walkability is checked on a 5 cm grid, 16 M cells at this.
MAX_ROOM_M = 200.0
# A room's outline: curved walls drawn in short pieces stay far below this.
MAX_CORNERS = 1000
# Any length or position: a few room sizes.
MAX_LENGTH_M = 1000.0


@functools.lru_cache(maxsize=8)
def _clearance(polygon_bytes: bytes, corners: int):
    """The floor's clearance grid (:func:`layout._kernels.clearance_grid`): its origin,
    cell (m) and cells. Every model of one photo's floor has the same (a photo's
    suggestions build a dozen)."""
    poly = np.frombuffer(polygon_bytes).reshape(corners, 2)
    # About 16k cells of at least 5 cm: one lookup then settles "far inside" for
    # most items, instead of a walk over every wall. More cells would only fall
    # out of the cache on a large floor (the solver asks twice per item and
    # iteration, in no spatial order).
    lo, hi = poly.min(0), poly.max(0)
    cell = max(0.05, float(np.sqrt(np.prod(hi - lo) / 16_000.0)))
    gx, gy = (np.ceil((hi - lo) / cell).astype(int) + 2)
    return lo - cell, cell, K.clearance_grid(np.ascontiguousarray(poly), lo - cell, cell, int(gx), int(gy))


def _finite(name, value, *, positive=False, nonnegative=False, shape=None, meters=True):
    arr = np.asarray(value, dtype=np.float64)
    if shape is not None and arr.shape != shape:
        raise LayoutError(f"{name}: expected {len(shape) and shape[0]} numbers, got {value!r}")
    if not np.all(np.isfinite(arr)):
        raise LayoutError(f"{name}: {value!r} is not a finite number")
    # Lengths past any room only overflow the energies (a lane 1e300 m long made them inf).
    if meters and np.any(np.abs(arr) > MAX_LENGTH_M):
        raise LayoutError(f"{name}: {value!r} is beyond any room; lengths are meters, at most {MAX_LENGTH_M:g}")
    if positive and np.any(arr <= 0):
        raise LayoutError(f"{name}: {value!r} must be greater than 0")
    if nonnegative and np.any(arr < 0):
        raise LayoutError(f"{name}: {value!r} must not be negative")
    return arr


class LayoutBuilder:
    """Builder of a layout problem.

    Parameters
    ----------
    floor_polygon_m : (m, 2) array_like
        Floor outline in meters (any orientation; stored counter-clockwise). Must be a
        simple polygon with at least 3 vertices.
    wall_height_m : float
        Room height; items taller than this are refused.
    open_edges : iterable of int, optional
        Edges (k = from vertex k to k + 1, in the order given) that are not walls, such
        as where a photo cuts the floor off: items stay inside them, but nothing is put
        against them, turned to them or slid along them.
    """

    def __init__(self, floor_polygon_m, wall_height_m=2.5, open_edges=()):
        poly = np.asarray(floor_polygon_m, dtype=np.float64)
        if poly.ndim != 2 or poly.shape[1] != 2:
            raise LayoutError(f"room.polygon: expected a list of [x, y] points, got shape {poly.shape}")
        if len(poly) > 3 and np.allclose(poly[0], poly[-1]):
            poly = poly[:-1]
        if len(poly) < 3:
            raise LayoutError(f"room.polygon: needs at least 3 vertices, got {len(poly)}")
        if len(poly) > MAX_CORNERS:
            raise LayoutError(f"room.polygon: {len(poly):,} corners; a room's outline has at most {MAX_CORNERS:,}")
        if not np.all(np.isfinite(poly)):
            raise LayoutError("room.polygon: contains a value that is not a finite number")
        same = np.flatnonzero(np.all(poly == np.roll(poly, -1, axis=0), axis=1))
        if len(same):
            k = int(same[0])
            raise LayoutError(f"room.polygon: corners {k} and {(k + 1) % len(poly)} are the same point "
                              f"{poly[k].tolist()}; list each corner once")
        extent = float((poly.max(axis=0) - poly.min(axis=0)).max())
        if extent > MAX_ROOM_M:
            raise LayoutError(f"room.polygon: {extent:.4g} m across; a room, hall or yard is at most {MAX_ROOM_M:g} m "
                              "(corners are in meters, not millimeters)")
        hit = self_intersection(poly)
        if hit is not None:
            a, b = hit
            raise LayoutError(
                f"room.polygon: edges {a}->{(a + 1) % len(poly)} and {b}->{(b + 1) % len(poly)} "
                "intersect; list the corners in order around the room"
            )
        area = polygon_area(poly)
        if abs(area) < 1e-9:
            raise LayoutError("room.polygon: has zero area")
        m = len(poly)
        wall = np.ones(m, bool)
        for k in open_edges:
            if not (isinstance(k, (int, np.integer)) and 0 <= int(k) < m):
                raise LayoutError(f"room.open_edges: {k!r} is not an edge number 0-{m - 1} of the "
                                  f"{m}-corner polygon (edge k runs from corner k to corner k + 1)")
            wall[int(k)] = False
        self.polygon_m = poly if area > 0 else poly[::-1].copy()
        # Reversing the corners turns edge k into edge m - 2 - k.
        self.edge_wall = wall if area > 0 else wall[(m - 2 - np.arange(m)) % m]
        self.wall_height_m = float(_finite("room.height", wall_height_m, positive=True))
        self._p = []  # particle records (dicts)
        self._c = {k: [] for k in DEFAULT_STIFFNESS}
        self._doors = []
        self._windows = []
        self._camera = None
        self._camera_rules = None

    # ------------------------------------------------------------------ particles

    def _index(self, what, i):
        if isinstance(i, (int, np.integer)) and 0 <= int(i) < len(self._p):
            return int(i)
        raise LayoutError(f"{what}: no item or group with index {i!r}")

    def add_item(
        self,
        name,
        size_m,
        *,
        kind="item",
        access_m=(0.0, 0.0, 0.0, 0.0),
        collides=True,
        group=None,
        offset_m=(0.0, 0.0),
        yaw_rad=None,
        position_m=None,
        fixed=False,
        elevation_m=0.0,
    ):
        """Add a furniture item; returns its index.

        Parameters
        ----------
        size_m : (3,) width, depth, height in meters, all > 0.
        access_m : (4,) clearance depth behind, left, in front, right (0 = none).
        collides : False for floor coverings (rugs) that others may stand on.
        group : index of a group; in a rigid group ``offset_m`` and ``yaw_rad`` place
            the item in the group's frame.
        position_m, yaw_rad : a start pose in the floor frame (random when None); with
            ``fixed`` the item never moves (inverse mass 0).
        elevation_m : height of the item's underside above the floor.
        """
        size = _finite(f"item {name!r} size", size_m, positive=True, shape=(3,))
        if size[2] + elevation_m > self.wall_height_m + 1e-9:
            raise LayoutError(
                f"item {name!r}: height {size[2] + elevation_m:g} m exceeds the room height "
                f"{self.wall_height_m:g} m"
            )
        access = _finite(f"item {name!r} access", access_m, nonnegative=True, shape=(4,))
        rec = dict(
            name=str(name), kind=str(kind), role=codes.ITEM, size=size, access=access,
            collides=bool(collides), parent=-1, offset=np.zeros(3), yaw=np.nan,
            pos=np.full(3, np.nan), fixed=bool(fixed), elevation=float(elevation_m),
        )
        self._attach(rec, group, offset_m, yaw_rad, position_m)
        self._p.append(rec)
        return len(self._p) - 1

    def add_group(self, name, *, rigid=False, group=None, offset_m=(0.0, 0.0), yaw_rad=None,
                  position_m=None, fixed=False):
        """Add a group particle (members are added with ``group=`` this index).

        A rigid group moves as one body: corrections to any member move the group.
        A non-rigid group is a particle of its own; members move freely subject to
        the group's constraints (for instance :meth:`curve`).
        """
        rec = dict(
            name=str(name), kind="group", role=codes.GROUP, size=np.zeros(3), access=np.zeros(4),
            collides=False, parent=-1, offset=np.zeros(3), yaw=np.nan, pos=np.full(3, np.nan),
            fixed=bool(fixed), elevation=0.0, rigid=bool(rigid),
        )
        self._attach(rec, group, offset_m, yaw_rad, position_m)
        self._p.append(rec)
        return len(self._p) - 1

    def _attach(self, rec, group, offset_m, yaw_rad, position_m):
        if yaw_rad is not None:
            rec["yaw"] = float(_finite(f"{rec['name']} yaw", yaw_rad, meters=False))
        if position_m is not None:
            xy = _finite(f"{rec['name']} position", position_m, shape=(2,))
            rec["pos"][:2] = xy
        if group is None:
            return
        g = self._index(f"{rec['name']} group", group)
        if self._p[g]["role"] != codes.GROUP:
            raise LayoutError(f"{rec['name']}: group {self._p[g]['name']!r} is not a group")
        rec["parent"] = g
        if self._p[g]["rigid"]:
            rec["offset"][:2] = _finite(f"{rec['name']} offset", offset_m, shape=(2,))
            if rec["role"] == codes.GROUP and not rec["rigid"]:
                raise LayoutError(
                    f"group {rec['name']!r}: a non-rigid group cannot sit inside rigid group "
                    f"{self._p[g]['name']!r}"
                )

    def add_door(self, position_m, width_m=0.9, clearance_m=None, height_m=DOOR_HEIGHT_M):
        """Add a door on the wall nearest ``position_m``; its swing zone stays free."""
        return self._add_opening(self._doors, "door", position_m, width_m,
                                 width_m if clearance_m is None else clearance_m, 0.0, height_m)

    def add_window(self, position_m, width_m=1.2, sill_m=0.9, height_m=1.2, clearance_m=0.4):
        """Add a window: items taller than its sill keep ``clearance_m`` away from it."""
        return self._add_opening(self._windows, "window", position_m, width_m, clearance_m,
                                 sill_m, height_m)

    def _add_opening(self, bucket, what, position_m, width_m, clearance_m, bottom_m, height_m):
        label = f"{what} {len(bucket) + 1}"
        at = _finite(f"{label} at", position_m, shape=(2,))
        width = float(_finite(f"{label} width", width_m, positive=True))
        depth = float(_finite(f"{label} clearance", clearance_m, positive=True))
        height = float(_finite(f"{label} height", height_m, positive=True))
        poly = self.polygon_m
        best = None
        for e in range(len(poly)):
            a, b = poly[e], poly[(e + 1) % len(poly)]
            ev = b - a
            t = np.clip(np.dot(at - a, ev) / np.dot(ev, ev), 0, 1)
            d = np.linalg.norm(a + t * ev - at)
            if best is None or d < best[0]:
                best = (d, e, t)
        _, e, t = best
        a, b = poly[e], poly[(e + 1) % len(poly)]
        length = np.linalg.norm(b - a)
        if width <= length + 1e-9:
            u = (b - a) / length
            foot = a + u * np.clip(t * length, width / 2, length - width / 2)
            segment = np.stack([foot - u * width / 2, foot + u * width / 2])
        else:
            segment = stepped_wall(poly, at, width, STEPPED_WALL_M)
            if segment is None:
                raise LayoutError(f"{label}: width {width:g} m is wider than its wall ({length:.2f} m)")
            u = (segment[1] - segment[0]) / width
            foot = segment.mean(axis=0)
        normal = np.array([-u[1], u[0]])
        rec = dict(
            name=label, kind=what, role=codes.OBSTACLE, size=np.array([width, depth, height]),
            access=np.zeros(4), collides=True, parent=-1, offset=np.zeros(3),
            yaw=float(math.atan2(normal[1], normal[0])),
            pos=np.array([*(foot + normal * depth / 2), bottom_m + height / 2]),
            fixed=True, elevation=bottom_m,
        )
        self._p.append(rec)
        bucket.append((segment, len(self._p) - 1))
        return len(self._p) - 1

    def set_camera(self, camera, rules=None):
        """Lay out for a photo: every item's box stays in the space ``camera``
        (:class:`layout.camera.Camera`) shows, the foreground clear
        (:meth:`~layout.camera.Camera.frame_planes`), and the restarts judge what it
        hides and shows from behind (:func:`layout.camera.judge`)."""
        from .camera import CAMERA, Camera

        if not isinstance(camera, Camera):
            raise LayoutError(f"camera: expected a layout.camera.Camera, got {type(camera).__name__}")
        self._camera = camera
        self._camera_rules = CAMERA if rules is None else rules

    # ---------------------------------------------------------------- constraints

    def _stiff(self, kind, k0, schedule):
        dk, ds = DEFAULT_STIFFNESS[kind]
        k = dk if k0 is None else float(_finite(f"{kind} stiffness", k0, meters=False))
        if not 0.0 <= k <= 1.0:
            raise LayoutError(f"{kind}: stiffness {k0!r} must lie in [0, 1]")
        if schedule is None:
            return k, ds
        if schedule not in codes.SCHEDULE_NAMES:
            raise LayoutError(f"{kind}: schedule {schedule!r} is not one of {sorted(codes.SCHEDULE_NAMES)}")
        return k, codes.SCHEDULE_NAMES[schedule]

    def _mode(self, kind, mode):
        if mode not in codes.MODE_NAMES:
            raise LayoutError(f"{kind}: mode {mode!r} is not one of {sorted(codes.MODE_NAMES)}")
        return codes.MODE_NAMES[mode]

    def distance(self, i, j, distance_m, *, mode="eq", pin=(False, False), k0=None, schedule=None):
        """Pairwise distance between particle centers (Eq. 4); ``pin`` gives an end w = 0."""
        i, j = self._index("distance", i), self._index("distance", j)
        if i == j:
            raise LayoutError(f"distance: item {self._p[i]['name']!r} paired with itself")
        d = float(_finite("distance", distance_m, nonnegative=True))
        self._c["distance"].append((i, j, d, self._mode("distance", mode), *self._stiff("distance", k0, schedule),
                                    0.0 if pin[0] else 1.0, 0.0 if pin[1] else 1.0))
        return len(self._c["distance"]) - 1

    def focal_distance(self, focal, members, distance_m, *, mode="eq", pin_focal=True, k0=None, schedule=None):
        """Focal point distance (Sec. 3.3.2): a distance from the focal to each member."""
        return [self.distance(m, focal, distance_m, mode=mode, pin=(False, pin_focal), k0=k0, schedule=schedule)
                for m in members]

    def lane(self, origin, items, *, angle_rad, length_m, half_width_m, start_m=(0.0, 0.0),
             pin_origin=True, k0=None, schedule=None):
        """Traffic lane (Sec. 3.3.3): ``items`` keep ``half_width_m`` (plus their own
        extent) away from the vector that starts at ``start_m`` in the origin's frame
        and runs ``length_m`` at ``angle_rad`` from the origin's facing."""
        o = self._index("lane", origin)
        length = float(_finite("lane length", length_m, positive=True))
        hw = float(_finite("lane half width", half_width_m, nonnegative=True))
        start = _finite("lane start", start_m, shape=(2,))
        ang = float(_finite("lane angle", angle_rad, meters=False))
        k, s = self._stiff("lane", k0, schedule)
        for m in items:
            m = self._index("lane", m)
            if m != o:
                self._c["lane"].append((o, m, start, ang, length, hw, k, s, 0.0 if pin_origin else 1.0))

    def heat(self, members, target_m, *, frame=None, k0=None, schedule=None):
        """Heat point (Eq. 9): the members' center of mass goes to ``target_m``, given in
        the frame of particle ``frame`` (world when None)."""
        members = [self._index("heat", m) for m in members]
        if not members:
            raise LayoutError("heat: needs at least one member")
        fr = -1 if frame is None else self._index("heat frame", frame)
        self._c["heat"].append((members, _finite("heat target", target_m, shape=(2,)), fr,
                                *self._stiff("heat", k0, schedule)))

    def symmetry(self, focal, members, *, angle_rad=0.0, k0=None, schedule=None):
        """Focal point symmetry (Eq. 11): members' center of mass on the focal's axis."""
        members = [self._index("symmetry", m) for m in members]
        if not members:
            raise LayoutError("symmetry: needs at least one member")
        angle = float(_finite("symmetry angle", angle_rad, meters=False))
        self._c["symmetry"].append((members, self._index("symmetry focal", focal), angle,
                                    *self._stiff("symmetry", k0, schedule)))

    def balance(self, members=None, *, exclude=(), k0=None, schedule=None):
        """Visual balance (Eq. 12): footprint-weighted center to the room centroid; by
        default of every item that blocks the floor, grouped ones too (a non-rigid group's
        particle does not stand for where its members are; a rug lies where its host puts
        it), but those in ``exclude``."""
        if members is None:
            members = [i for i, r in enumerate(self._p)
                       if r["role"] == codes.ITEM and r["collides"] and i not in exclude]
        members = [self._index("balance", m) for m in members]
        if members:
            self._c["balance"].append((members, polygon_centroid(self.polygon_m), *self._stiff("balance", k0, schedule)))

    def wall_distance(self, i, distance_m=None, *, mode="eq", k0=None, schedule=None):
        """Distance of the center from the nearest wall (Eq. 13); default: back to wall."""
        i = self._index("wall", i)
        d = 0.5 * self._p[i]["size"][1] if distance_m is None else float(_finite("wall distance", distance_m, nonnegative=True))
        self._c["wall_distance"].append((i, d, self._mode("wall", mode), *self._stiff("wall_distance", k0, schedule)))

    def wall_orientation(self, i, angle_rad=0.0, *, k0=None, schedule=None):
        """Orientation to the nearest wall (Eq. 17): 0 faces into the room."""
        i = self._index("wall orientation", i)
        self._c["wall_orientation"].append((i, float(_finite("wall angle", angle_rad, meters=False)),
                                            *self._stiff("wall_orientation", k0, schedule)))

    def against_wall(self, i, gap_m=0.0):
        """Back against the nearest wall, facing the room (distance + orientation)."""
        self.wall_distance(i, 0.5 * self._p[self._index("wall", i)]["size"][1] + gap_m)
        self.wall_orientation(i, 0.0)

    def face(self, i, j, *, angle_rad=0.0, mutual=False, k0=None, schedule=None):
        """Pairwise orientation (Eq. 16): i's front points ``angle_rad`` off the direction
        to j (and j faces i too when ``mutual``)."""
        i, j = self._index("orientation", i), self._index("orientation", j)
        self._c["orientation"].append((i, j, float(angle_rad), 0.0 if mutual else np.nan, codes.FACE,
                                       *self._stiff("orientation", k0, schedule)))

    def parallel(self, i, j, *, angle_rad=0.0, k0=None, schedule=None):
        """Pairwise orientation: yaw_i − yaw_j = ``angle_rad`` modulo π (e.g. a coffee
        table parallel to the sofa)."""
        i, j = self._index("orientation", i), self._index("orientation", j)
        self._c["orientation"].append((i, j, float(angle_rad), np.nan, codes.PARALLEL,
                                       *self._stiff("orientation", k0, schedule)))

    def stack(self, base, top, *, k0=None, schedule=None):
        """Vertical stacking (Eqs. 18–19): ``top`` rests centered on ``base``."""
        b, t = self._index("stack", base), self._index("stack", top)
        if b == t:
            raise LayoutError(f"stack: item {self._p[b]['name']!r} stacked on itself")
        # What the base rests on, all the way down: the top must not be among it.
        below, todo = set(), [b]
        while todo:
            x = todo.pop()
            for base_x, top_x, *_ in self._c["stack"]:
                if top_x == x and base_x not in below:
                    below.add(base_x)
                    todo.append(base_x)
        if t in below:
            raise LayoutError(f"stack: {self._p[t]['name']!r} on {self._p[b]['name']!r}, which already rests on "
                              f"{self._p[t]['name']!r}: stacks cannot go round in a loop")
        self._c["stack"].append((b, t, *self._stiff("stack", k0, schedule)))

    def curve(self, group, members, *, segment_m=None, arc=None, spacing_m=0.0, anchor_fixed=False,
              k0=None, schedule=None):
        """Lay members of a non-rigid group along a curve in the group's frame.

        ``segment_m`` = ((ax, ay), (bx, by)); ``arc`` = (center (2,), radius_m,
        start_rad, end_rad). Neighbours in curve order keep ``spacing_m`` (0 = free).
        ``anchor_fixed`` gives the curve point infinite mass as in the paper; by default
        it shares the group's mass, so the group follows its members.
        """
        g = self._index("curve", group)
        if self._p[g]["role"] != codes.GROUP or self._p[g]["rigid"]:
            raise LayoutError(f"curve: {self._p[g]['name']!r} must be a non-rigid group")
        members = [self._index("curve", m) for m in members]
        if (segment_m is None) == (arc is None):
            raise LayoutError(f"curve of group {self._p[g]['name']!r}: give exactly one of segment or arc")
        if segment_m is not None:
            seg = _finite("curve segment", segment_m, shape=(2, 2))
            kind, params = codes.SEGMENT, [*seg[0], *seg[1], 0.0]
        else:
            center, radius, a0, a1 = arc
            c = _finite("arc center", center, shape=(2,))
            r = float(_finite("arc radius", radius, positive=True))
            params = [c[0], c[1], r, float(_finite("arc start", a0, meters=False)),
                      float(_finite("arc end", a1, meters=False))]
            kind = codes.ARC
        spacing = float(_finite("curve spacing", spacing_m, nonnegative=True))
        self._c["curve"].append((g, kind, params, members, spacing, bool(anchor_fixed), *self._stiff("curve", k0, schedule)))

    # ------------------------------------------------------------------- finalize

    def _check_fits(self):
        floor_area = polygon_area(self.polygon_m)
        stacked_tops = {c[1] for c in self._c["stack"]}
        items = [i for i, r in enumerate(self._p) if r["role"] == codes.ITEM]
        footprint = sum(
            self._p[i]["size"][0] * self._p[i]["size"][1]
            for i in items
            if self._p[i]["collides"] and i not in stacked_tops and self._p[i]["elevation"] == 0.0
        )
        if footprint > floor_area:
            raise LayoutError(
                f"items: their footprints add up to {footprint:.2f} m², more than the floor's "
                f"{floor_area:.2f} m²; remove items or use a larger room"
            )
        lo, hi = self.polygon_m.min(0), self.polygon_m.max(0)
        span = hi - lo
        for i in items:
            w, d = self._p[i]["size"][:2]
            # Necessary conditions only (a long item may still fit diagonally).
            if max(w, d) > math.hypot(*span) + 1e-9 or min(w, d) > min(span) + 1e-9:
                raise LayoutError(
                    f"item {self._p[i]['name']!r}: footprint {w:g} x {d:g} m does not fit the floor "
                    f"({span[0]:.2f} x {span[1]:.2f} m)"
                )

    def finalize(self) -> Model:
        """Freeze everything into a :class:`Model` of arrays."""
        self._check_fits()
        n = len(self._p)
        if not any(r["role"] == codes.ITEM for r in self._p):
            raise LayoutError("items: the layout has no items")
        p = self._p
        parent = np.array([r["parent"] for r in p], np.int32)
        role = np.array([r["role"] for r in p], np.int8)
        size = np.array([r["size"] for r in p], np.float64).reshape(n, 3)
        rigid = np.array([r.get("rigid", False) for r in p])
        # Body = the outermost rigid group an item is fixed in; offsets compose.
        body = np.arange(n, dtype=np.int32)
        offset = np.array([r["offset"] for r in p], np.float64).reshape(n, 3)
        # Pose of each particle in its parent's frame (rigid parents only).
        in_rigid = (parent >= 0) & rigid[np.maximum(parent, 0)]
        yaw_in_parent = np.where(in_rigid, np.nan_to_num(np.array([r["yaw"] for r in p], np.float64)), 0.0)
        offset_in_parent = offset[:, :2].copy()
        body_yaw = yaw_in_parent.copy()
        for i in range(n):
            b = i
            off = offset_in_parent[i].copy()
            yaw_acc = yaw_in_parent[i]
            while in_rigid[b]:
                g = parent[b]
                if in_rigid[g]:
                    c, s = math.cos(yaw_in_parent[g]), math.sin(yaw_in_parent[g])
                    off = offset_in_parent[g] + np.array([c * off[0] - s * off[1], s * off[0] + c * off[1]])
                    yaw_acc += yaw_in_parent[g]
                b = g
            body[i] = b
            if b != i:
                offset[i, :2] = off
                body_yaw[i] = yaw_acc
        # Masses: box volume; groups weigh what their members weigh.
        mass = np.prod(size, axis=1)
        for i in reversed(range(n)):
            if parent[i] >= 0:
                mass[parent[i]] += mass[i]
        mass = np.maximum(mass, 1e-9)
        fixed = np.array([r["fixed"] for r in p])
        inv_mass = np.where(fixed | (role == codes.OBSTACLE), 0.0, 1.0 / mass)
        for i in range(n):
            if body[i] != i:
                inv_mass[i] = inv_mass[body[i]]
        elevation = np.array([r["elevation"] for r in p])
        for i in range(n):
            if body[i] != i:
                offset[i, 2] = elevation[i] + 0.5 * size[i, 2]
        init_pos = np.array([r["pos"] for r in p], np.float64).reshape(n, 3)
        init_yaw = np.array([r["yaw"] for r in p], np.float64)
        for i in range(n):
            if role[i] == codes.ITEM and body[i] == i:
                init_pos[i, 2] = elevation[i] + 0.5 * size[i, 2]
            elif role[i] == codes.GROUP:
                init_pos[i, 2] = 0.0
            if body[i] != i:  # members are placed by their body
                init_pos[i] = np.nan
                init_yaw[i] = np.nan
        is_member = body != np.arange(n)
        mlist = np.flatnonzero(is_member)[np.argsort(body[is_member], kind="stable")].astype(np.int64)
        mstart = np.zeros(n + 1, np.int64)
        mstart[1:] = np.cumsum(np.bincount(body[is_member], minlength=n))
        # A rigid group held to a wall holds all its members there (Sec. 3.3.9's
        # wall-point projection then applies to each of them).
        wall_bound = np.zeros(n, bool)
        for c in self._c["wall_distance"]:
            wall_bound[body == body[c[0]]] = True
        poly = self.polygon_m
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        prev = poly - np.roll(poly, 1, axis=0)
        reflex = (prev[:, 0] * edges[:, 1] - prev[:, 1] * edges[:, 0]) < 0
        grid_origin, grid_cell, clearance = _clearance(poly.tobytes(), len(poly))
        # Group sizes (for pictures): bounding box of member footprints in group frame.
        for g in np.flatnonzero(role == codes.GROUP)[::-1]:
            members = np.flatnonzero(parent == g)
            if len(members) and rigid[g]:
                off = np.array([offset[m, :2] for m in members])
                yaws = np.array([0.0 if np.isnan(p[m]["yaw"]) else p[m]["yaw"] for m in members])
                corners = box_corners(off, yaws, size[members, 0], size[members, 1]).reshape(-1, 2)
                ext = corners.max(0) - corners.min(0)
                size[g] = [ext[1], ext[0], size[members, 2].max()]

        C = self._c

        def arr(kind, col, dtype=np.float64, width=None):
            rows = [r[col] for r in C[kind]]
            if width is None:
                return np.array(rows, dtype=dtype).reshape(len(rows))
            return np.array(rows, dtype=dtype).reshape(len(rows), width)

        def csr(kind, col):
            lists = [r[col] for r in C[kind]]
            start = np.zeros(len(lists) + 1, np.int64)
            start[1:] = np.cumsum([len(m) for m in lists])
            members = np.array([m for ls in lists for m in ls], np.int64)
            return start, members

        dist = C["distance"]
        heat_start, heat_members = csr("heat", 0)
        sym_start, sym_members = csr("symmetry", 0)
        bal_start, bal_members = csr("balance", 0)
        cur_start, cur_members = csr("curve", 3)
        doors = self._doors
        windows = self._windows
        access = np.array([r["access"] for r in p], np.float64).reshape(n, 4)
        return Model(
            names=tuple(r["name"] for r in p),
            kinds=tuple(r["kind"] for r in p),
            particle_role=role,
            particle_size_m=size,
            particle_mass=mass,
            particle_inv_mass=inv_mass,
            particle_body=body,
            particle_body_offset_m=offset * (body != np.arange(n))[:, None],
            particle_body_yaw_rad=np.where(body != np.arange(n), body_yaw, 0.0),
            particle_parent=parent,
            particle_collides=np.array([r["collides"] for r in p], bool),
            particle_bounded=(role == codes.ITEM),
            particle_wall_bound=wall_bound,
            particle_access_depth_m=access,
            particle_mstart=mstart,
            particle_mlist=mlist,
            particle_radius_m=0.5 * np.hypot(size[:, 0], size[:, 1]),
            particle_access_max_m=access.max(axis=1),
            particle_access_zone_m=access_zones(size, access),
            particle_init_position_m=init_pos,
            particle_init_yaw_rad=init_yaw,
            floor_polygon_m=poly.copy(),
            floor_edge_normal=normals,
            floor_reflex=reflex,
            floor_edge_wall=self.edge_wall.copy(),
            floor_clearance_m=clearance.copy(),  # the cache's own stays as made
            floor_grid_origin_m=grid_origin.copy(),
            floor_grid_cell_m=np.array([grid_cell]),
            floor_frame_planes=(np.zeros((0, 4)) if self._camera is None
                                else self._camera.frame_planes(self._camera_rules)),
            camera=self._camera,
            camera_rules=self._camera_rules,
            wall_height_m=self.wall_height_m,
            door_segments_m=np.array([d[0] for d in doors], np.float64).reshape(len(doors), 2, 2),
            door_particles=np.array([d[1] for d in doors], np.int32),
            window_segments_m=np.array([w[0] for w in windows], np.float64).reshape(len(windows), 2, 2),
            window_particles=np.array([w[1] for w in windows], np.int32),
            distance_pairs=np.array([r[:2] for r in dist], np.int64).reshape(len(dist), 2),
            distance_rest_m=arr("distance", 2),
            distance_mode=arr("distance", 3, np.int64),
            distance_k0=arr("distance", 4),
            distance_schedule=arr("distance", 5, np.int64),
            distance_w_scale=np.array([r[6:8] for r in dist], np.float64).reshape(len(dist), 2),
            lane_origin=arr("lane", 0, np.int64),
            lane_item=arr("lane", 1, np.int64),
            lane_start_m=arr("lane", 2, width=2),
            lane_angle_rad=arr("lane", 3),
            lane_length_m=arr("lane", 4),
            lane_half_width_m=arr("lane", 5),
            lane_k0=arr("lane", 6),
            lane_schedule=arr("lane", 7, np.int64),
            lane_w_scale=np.array([[1.0, r[8]] for r in C["lane"]], np.float64).reshape(len(C["lane"]), 2),
            heat_start=heat_start,
            heat_members=heat_members,
            heat_target_m=arr("heat", 1, width=2),
            heat_frame=arr("heat", 2, np.int64),
            heat_k0=arr("heat", 3),
            heat_schedule=arr("heat", 4, np.int64),
            symmetry_start=sym_start,
            symmetry_members=sym_members,
            symmetry_focal=arr("symmetry", 1, np.int64),
            symmetry_angle_rad=arr("symmetry", 2),
            symmetry_k0=arr("symmetry", 3),
            symmetry_schedule=arr("symmetry", 4, np.int64),
            balance_start=bal_start,
            balance_members=bal_members,
            balance_target_m=arr("balance", 1, width=2),
            balance_k0=arr("balance", 2),
            balance_schedule=arr("balance", 3, np.int64),
            wall_distance_item=arr("wall_distance", 0, np.int64),
            wall_distance_rest_m=arr("wall_distance", 1),
            wall_distance_mode=arr("wall_distance", 2, np.int64),
            wall_distance_k0=arr("wall_distance", 3),
            wall_distance_schedule=arr("wall_distance", 4, np.int64),
            wall_orientation_item=arr("wall_orientation", 0, np.int64),
            wall_orientation_angle_rad=arr("wall_orientation", 1),
            wall_orientation_k0=arr("wall_orientation", 2),
            wall_orientation_schedule=arr("wall_orientation", 3, np.int64),
            orientation_pairs=np.array([r[:2] for r in C["orientation"]], np.int64).reshape(len(C["orientation"]), 2),
            orientation_angle_rad=np.array([r[2:4] for r in C["orientation"]], np.float64).reshape(len(C["orientation"]), 2),
            orientation_mode=arr("orientation", 4, np.int64),
            orientation_k0=arr("orientation", 5),
            orientation_schedule=arr("orientation", 6, np.int64),
            stack_pairs=np.array([r[:2] for r in C["stack"]], np.int64).reshape(len(C["stack"]), 2),
            stack_k0=arr("stack", 2),
            stack_schedule=arr("stack", 3, np.int64),
            curve_group=arr("curve", 0, np.int64),
            curve_kind=arr("curve", 1, np.int64),
            curve_params=arr("curve", 2, width=5),
            curve_start=cur_start,
            curve_members=cur_members,
            curve_spacing_m=arr("curve", 4),
            curve_anchor_fixed=arr("curve", 5, bool),
            curve_k0=arr("curve", 6),
            curve_schedule=arr("curve", 7, np.int64),
        )
