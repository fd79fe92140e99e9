"""Random empty rooms: floor polygons, wall height, doors, windows and sparse clutter.

World frame: meters, floor at z = 0, z up; polygons counter-clockwise in (x, y).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.path import Path as _MplPath

# Baseboard heights drawn, low and high, meters: most rooms' boards (real ones reach 0.2).
BASEBOARD_M = (0.05, 0.12)

ROOM_SIDE_M = (2.5, 8.0)
WALL_HEIGHT_M = (2.3, 3.5)
_CORNER_GAP_M = 0.15  # openings keep this far from a wall's ends (room for the frame)


@dataclass(frozen=True)
class Opening:
    """A door or window: a rectangle cut from wall ``wall`` (edge wall -> wall+1).

    ``start_m``/``end_m`` run along the wall from its first vertex; ``bottom_m``/``top_m``
    are heights above the floor.
    """

    kind: str
    wall: int
    start_m: float
    end_m: float
    bottom_m: float
    top_m: float

    def segment_m(self, polygon_m: np.ndarray) -> np.ndarray:
        """The opening's two floor-plan end points, (2, 2) meters."""
        a, b = wall_ends(polygon_m, self.wall)
        u = (b - a) / np.linalg.norm(b - a)
        return np.array([a + u * self.start_m, a + u * self.end_m])


@dataclass(frozen=True)
class Clutter:
    """A box standing on the floor: a carton or a radiator. ``yaw_rad`` turns its width
    axis from +x."""

    kind: str
    center_m: tuple[float, float]
    size_m: tuple[float, float, float]
    yaw_rad: float

    def footprint_m(self) -> np.ndarray:
        """The four floor corners, (4, 2) meters, counter-clockwise."""
        w, d, _ = self.size_m
        c, s = np.cos(self.yaw_rad), np.sin(self.yaw_rad)
        local = np.array([[-w, -d], [w, -d], [w, d], [-w, d]]) / 2
        return local @ np.array([[c, s], [-s, c]]) + np.asarray(self.center_m)


@dataclass(frozen=True)
class Room:
    polygon_m: np.ndarray
    height_m: float
    openings: tuple[Opening, ...]
    clutter: tuple[Clutter, ...] = ()


def wall_ends(polygon_m: np.ndarray, wall: int) -> tuple[np.ndarray, np.ndarray]:
    return polygon_m[wall], polygon_m[(wall + 1) % len(polygon_m)]


def inward_normal(polygon_m: np.ndarray, wall: int) -> np.ndarray:
    """Unit normal of a wall pointing into the room (left of a counter-clockwise edge)."""
    a, b = wall_ends(polygon_m, wall)
    t = (b - a) / np.linalg.norm(b - a)
    return np.array([-t[1], t[0]])


def contains(polygon_m: np.ndarray, points_m: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
    """Whether each point lies inside the polygon at least ``margin_m`` from every wall.

    Parameters
    ----------
    polygon_m : (n, 2) float
    points_m : (k, 2) float

    Returns
    -------
    inside : (k,) bool
    """
    points_m = np.atleast_2d(np.asarray(points_m, dtype=np.float64))
    inside = _MplPath(polygon_m).contains_points(points_m)
    if margin_m > 0:
        inside &= distance_to_walls(polygon_m, points_m) >= margin_m
    return inside


def distance_to_walls(polygon_m: np.ndarray, points_m: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest wall segment, (k,) meters."""
    a = polygon_m[None, :, :]
    ab = np.roll(polygon_m, -1, axis=0)[None] - a
    ap = points_m[:, None, :] - a
    t = np.clip((ap * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    return np.linalg.norm(ap - t[..., None] * ab, axis=-1).min(axis=1)


def random_polygon(rng: np.random.Generator) -> np.ndarray:
    """A rectangle, L- or U-shaped floor (probabilities 0.5, 0.3, 0.2), counter-clockwise,
    its bounding box 2.5-8 m a side, corner at the origin. Returns (n, 2) meters."""
    w, d = rng.uniform(*ROOM_SIDE_M, size=2)
    shape = rng.choice(["rect", "L", "U"], p=[0.5, 0.3, 0.2])
    if shape == "L":
        nw, nd = w * rng.uniform(0.3, 0.55), d * rng.uniform(0.3, 0.55)
        poly = np.array([[0, 0], [w, 0], [w, d - nd], [w - nw, d - nd], [w - nw, d], [0, d]])
    elif shape == "U" and w >= 3.5:
        # A notch in the middle of the far wall, leaving two arms at least 1 m wide.
        nw = rng.uniform(0.25 * w, min(0.45 * w, w - 2.2))
        x0 = rng.uniform(1.0, w - 1.0 - nw)
        nd = d * rng.uniform(0.25, 0.5)
        poly = np.array([[0, 0], [w, 0], [w, d], [x0 + nw, d], [x0 + nw, d - nd],
                         [x0, d - nd], [x0, d], [0, d]])
    else:
        poly = np.array([[0, 0], [w, 0], [w, d], [0, d]])
    # Turning the plan by a quarter keeps it axis-aligned but varies which side has the notch.
    quarter = rng.integers(4)
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    for _ in range(quarter):
        poly = poly @ rot.T
    return poly - poly.min(axis=0)


def _place_openings(rng, polygon_m, height_m):
    """Doors (0.8-1.0 m wide, 2.0-2.1 m tall, at most min(height - 0.15)) and windows
    (0.6-2.0 m wide, sill 0.5-1.0 m) on distinct stretches of the walls."""
    n = len(polygon_m)
    lengths = np.linalg.norm(np.roll(polygon_m, -1, axis=0) - polygon_m, axis=1)
    taken: dict[int, list[tuple[float, float]]] = {i: [] for i in range(n)}
    openings = []

    def try_place(kind, width_m, bottom_m, top_m):
        for _ in range(20):
            wall = int(rng.choice(n, p=lengths / lengths.sum()))
            free = lengths[wall] - 2 * _CORNER_GAP_M - width_m
            if free <= 0:
                continue
            start = _CORNER_GAP_M + rng.uniform(0, free)
            end = start + width_m
            if any(start < e + 0.3 and s < end + 0.3 for s, e in taken[wall]):
                continue
            taken[wall].append((start, end))
            openings.append(Opening(kind, wall, float(start), float(end), float(bottom_m), float(top_m)))
            return

    for _ in range(rng.choice([1, 1, 2])):
        top = min(rng.uniform(2.0, 2.1), height_m - 0.15)
        try_place("door", rng.uniform(0.8, 1.0), 0.0, top)
    for _ in range(rng.choice([0, 1, 1, 2, 2, 3])):
        sill = rng.uniform(0.5, 1.0)
        top = min(sill + rng.uniform(0.9, 1.6), height_m - 0.2)
        try_place("window", rng.uniform(0.6, 2.0), sill, top)
    return tuple(openings)


def random_room(rng: np.random.Generator) -> Room:
    """A random empty room without clutter (see :func:`add_clutter`)."""
    polygon_m = random_polygon(rng)
    height_m = float(rng.uniform(*WALL_HEIGHT_M))
    return Room(polygon_m, height_m, _place_openings(rng, polygon_m, height_m))


def _overlaps(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two convex polygons (k, 2) overlap (separating axis test)."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        for nx, ny in np.column_stack([-edges[:, 1], edges[:, 0]]):
            pa, pb = a @ (nx, ny), b @ (nx, ny)
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    return True


def _door_zones(room: Room) -> list[np.ndarray]:
    """Door swing zones, which stay clear: a square of the door's width in front of it."""
    poly = room.polygon_m
    zones = []
    for o in room.openings:
        if o.kind == "door":
            a, b = o.segment_m(poly)
            n = inward_normal(poly, o.wall)
            zones.append(np.array([a, b, b + n * (o.end_m - o.start_m), a + n * (o.end_m - o.start_m)]))
    return zones


def _fits(poly: np.ndarray, c: Clutter, blocked: list[np.ndarray], items: list[Clutter]) -> bool:
    """Whether ``c`` stands on the floor clear of ``blocked`` regions and ``items``."""
    foot = c.footprint_m()
    return bool(contains(poly, foot, margin_m=0.005).all()) and not any(
        _overlaps(foot, k) for k in blocked + [i.footprint_m() for i in items])


def add_clutter(rng: np.random.Generator, room: Room, keep_out: list[np.ndarray],
                max_items: int = 3) -> Room:
    """Add a radiator under some windows and up to ``max_items`` cartons.

    Parameters
    ----------
    keep_out : list of (k, 2) convex polygons
        Floor regions clutter must not touch (the board, the camera's sight lines to it).
    """
    poly = room.polygon_m
    items: list[Clutter] = []
    blocked = list(keep_out) + _door_zones(room)

    def fits(c: Clutter) -> bool:
        return _fits(poly, c, blocked, items)

    for o in room.openings:
        if o.kind == "window" and o.bottom_m > 0.65 and rng.random() < 0.4:
            a, b = o.segment_m(poly)
            n = inward_normal(poly, o.wall)
            width = min(o.end_m - o.start_m, rng.uniform(0.6, 1.4))
            depth = rng.uniform(0.08, 0.12)
            center = (a + b) / 2 + n * (0.04 + depth / 2)
            t = b - a
            c = Clutter("radiator", tuple(center), (width, depth, o.bottom_m - rng.uniform(0.08, 0.2)),
                        float(np.arctan2(t[1], t[0])))
            if fits(c):
                items.append(c)
    if rng.random() < 0.5:
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        for _ in range(rng.integers(1, max_items + 1)):
            for _ in range(20):
                size = rng.uniform([0.25, 0.25, 0.2], [0.7, 0.6, 0.6])
                c = Clutter("box", tuple(rng.uniform(lo, hi)), tuple(size), float(rng.uniform(0, np.pi)))
                if fits(c):
                    items.append(c)
                    break
    return Room(room.polygon_m, room.height_m, room.openings, tuple(items))


# Catalog kinds that furnish a room (rugs stay out: they are floor to a layout).
FURNITURE_KINDS = ("sofa", "armchair", "coffee_table", "tv_stand", "bookcase", "dining_table", "chair", "desk",
                   "office_chair", "bed", "nightstand", "wardrobe", "dresser", "plant", "floor_lamp", "side_table")


def add_furniture(rng: np.random.Generator, room: Room, keep_out: list[np.ndarray], max_items: int = 6) -> Room:
    """Add 1 to ``max_items`` pieces of furniture (catalog kinds at their sizes, give or
    take 15 %), most with their backs to a wall, the rest anywhere, clear of the board's
    sight lines, the door swings and each other. They are ``Clutter`` whose ``kind`` is
    a catalog kind; the scene builds them with :mod:`augment.render.furniture`."""
    from layout.catalog import CATALOG

    poly = room.polygon_m
    items = list(room.clutter)
    blocked = list(keep_out) + _door_zones(room)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    for _ in range(rng.integers(1, max_items + 1)):
        kind = FURNITURE_KINDS[rng.integers(len(FURNITURE_KINDS))]
        for _ in range(20):
            size = tuple(float(v) for v in np.asarray(CATALOG[kind].size_m) * rng.uniform(0.85, 1.15, 3))
            if rng.random() < 0.6:
                wall = int(rng.integers(len(poly)))
                a, b = wall_ends(poly, wall)
                n = inward_normal(poly, wall)
                center = a + rng.uniform(0.1, 0.9) * (b - a) + n * (size[1] / 2 + 0.03)
                facing = float(np.arctan2(n[1], n[0]))
            else:
                center = rng.uniform(lo, hi)
                facing = float(rng.uniform(-np.pi, np.pi))
            # Clutter turns its width axis; the front faces a quarter turn on.
            c = Clutter(kind, tuple(float(v) for v in center), size, facing - np.pi / 2)
            if _fits(poly, c, blocked, items):
                items.append(c)
                break
    return Room(room.polygon_m, room.height_m, room.openings, tuple(items))

