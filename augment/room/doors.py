"""Doors on the measured floor: the walls' open edges, and the doors the user marked in
the photo turned into the layout's doors, whose swing zones stay free of furniture."""
from __future__ import annotations

import numpy as np

from layout.geometry import edge_distances

from ..errors import FurnishError
from .settings import ROOM


def open_edges(polygon_m: np.ndarray, floor) -> list[int]:
    """Edges of ``polygon_m`` (the layout's floor, counter-clockwise) that are not walls:
    those whose midpoint is nearest an edge of the measured floor that the photo's edge
    or the distance cut off (``FloorPolygon.edge_kind`` other than ``"boundary"``).

    Parameters
    ----------
    polygon_m : (m, 2) float64
        The floor the layouts are made on (the measured one, shrunk by the wall margin).
    floor : FloorPolygon

    Returns
    -------
    list of int
        Edge numbers k (corner k to k + 1).
    """
    mid = 0.5 * (polygon_m + np.roll(polygon_m, -1, axis=0))
    nearest = edge_distances(mid, floor.polygon_m).argmin(axis=1)
    return [k for k, e in enumerate(nearest) if floor.edge_kind[e] != "boundary"]


# Doors kept clear in one photo: more than a room shows.
MAX_DOORS = 10


def doors_on_floor(doors_px, calibration, polygon_m: np.ndarray, open_edges_=()) -> tuple:
    """The doors the user marked in the photo, as the layout's doors: their swing zones,
    as deep as the door is wide, are kept free of furniture.

    Parameters
    ----------
    doors_px : (n, 4) array_like
        Per door the photo pixels x1, y1, x2, y2 of the feet of its two sides, where
        they meet the floor (upright, as the floor overlay shows the photo).
    calibration : Calibration
    polygon_m : (m, 2) float64
        The layout's floor, counter-clockwise.
    open_edges_ : iterable of int
        Its edges that are not walls (:func:`open_edges`).

    Returns
    -------
    tuple of layout.spec.Opening
        Each at the middle of its feet moved onto the nearest wall, as wide as they are
        apart, also where the outline draws that wall in shorter steps
        (:func:`layout.geometry.stepped_wall`).

    Raises
    ------
    FurnishError
        A door outside the photo, above the horizon, of an unlikely width or not at a
        wall of the floor found; the message says what to give instead.
    """
    from layout.spec import Opening

    fit = ROOM.fit
    poly = np.asarray(polygon_m, dtype=np.float64)
    walls = sorted(set(range(len(poly))) - {int(k) for k in open_edges_})
    cols, rows = calibration.size_px
    doors = []
    marked = np.asarray(doors_px, dtype=np.float64).reshape(-1, 4)
    if len(marked) > MAX_DOORS:
        raise FurnishError(f"{len(marked)} doors: at most {MAX_DOORS} are kept clear in one photo")
    for d in marked:
        name = "door " + ",".join(f"{v:g}" for v in d)
        feet_px = d.reshape(2, 2)
        if not ((feet_px >= 0).all() and (feet_px[:, 0] < cols).all() and (feet_px[:, 1] < rows).all()):
            raise FurnishError(f"{name}: outside the photo ({cols} x {rows} px); give the photo pixels X1,Y1,X2,Y2 "
                               "of the feet of the door's two sides, as the floor overlay shows the photo")
        feet = calibration.floor_from_pixels(feet_px)
        depth = (calibration.camera_from_floor @ np.column_stack([feet, np.zeros(2), np.ones(2)]).T)[2]
        if not (np.isfinite(feet).all() and (depth > 0).all()):
            raise FurnishError(f"{name}: above the horizon, so not on the floor; give the feet of the door's two "
                               "sides, where they meet the floor")
        width = float(np.linalg.norm(feet[1] - feet[0]))
        lo, hi = fit.door_width_m
        if not lo <= width <= hi:
            raise FurnishError(f"{name}: its two feet are {width:.2f} m apart on the floor, and a door is {lo:g}-"
                               f"{hi:g} m wide; give the feet of its two sides, where they meet the floor")
        middle = feet.mean(axis=0)
        distance = edge_distances(middle[None], poly)[0]
        k = min(walls, key=lambda e: distance[e]) if walls else None
        if k is None or distance[k] > fit.door_from_wall_m:
            where = "the floor found has no wall in view" if k is None else \
                f"it is {distance[k]:.2f} m from the nearest wall of the floor found"
            raise FurnishError(f"{name}: {where}; a door is marked at a wall, by the feet of its two sides "
                               "(the floor overlay shows the walls found)")
        a, b = poly[k], poly[(k + 1) % len(poly)]
        t = float(np.clip(np.dot(middle - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0))
        doors.append(Opening(at_m=tuple(float(v) for v in a + t * (b - a)), width_m=round(width, 4),
                             clearance_m=None, height_m=2.1, where=name))
    return tuple(doors)
