"""Photo in, furnished photos out: Stager end to end (thesis Algorithm 4, Appendix C).

:func:`furnish` runs every stage on one photo of an empty room with the board lying on
its floor and returns everything in memory (:class:`FurnishResult`);
:func:`write_outputs` writes it to a folder, all files or none. ``stage furnish`` is the
command line over the two.

Stages, in order (``FurnishResult.timings_s`` has one entry per stage):

1. ``calibrate``: the camera from the board (:func:`augment.calibrate.calibrate_file`;
   focal length from ``camera``, else EXIF, else the board). The floor frame is the
   board's: origin at its center, z up, meters.
2. ``segment``: the floor mask (:func:`augment.segment.segment_floor`), or the user's
   own (``floor_mask``, :func:`augment.segment.read_floor_mask`).
3. ``floor``: the visible floor's polygon in meters (:func:`augment.floor.floor_polygon`).
4. ``height``: the wall height (:func:`augment.height.measure_height`; 2.5 m assumed
   when nothing trustworthy is in view, with a warning).
5. ``furniture``: the furniture set from a room preset or a spec file, on the measured
   floor and height (:func:`fit_spec`): what cannot fit is dropped, with a warning.
6. ``layout``: ``suggestions`` layouts (:class:`layout.solver.Solver`, suggestion K
   from seed ``seed + K - 1``), each checked (:func:`layout.report.evaluate`). When one
   has overlapping items or items off the floor, the least important remaining item is
   dropped and all are solved again: no suggestion is an impossible layout.
7. ``render``: each layout rendered into the photo (:func:`augment.render.render_staged`,
   one GL context for all), the light estimated once.
8. ``scene``: each suggestion as a glTF scene: the measured floor, walls of the
   measured height along the polygon's ``"boundary"`` edges, the furniture.
9. ``overlays``: calibration, floor and height drawn over the photo, and the contact
   sheet of the staged photos.
10. ``plans``: each suggestion's plan and JSON, and the energy plot
    (:func:`layout.report.output_files`). They are drawn on a second thread from the end
    of ``layout`` on; this stage is only the wait for them after ``overlays``.

Files written by :func:`write_outputs` (K = 1 … N):

=========================== =========================================================
``staged_K.jpg``            the photo furnished with suggestion K (JPEG quality 92)
``staged_all.jpg``          contact sheet: all suggestions side by side, numbered
``staged_K_layer.png``      with ``layers=True``: what suggestion K adds (RGBA)
``layout_K.json``           suggestion K (see ``layout solve``): room, items, energy, metrics
``plan_K.png``              its top-down plan on the measured floor
``energy.png``              energy per solver iteration of every suggestion
``scene_K.glb``             glTF 2.0 scene (y up, meters): floor, walls, furniture
``overlay_calibration.png`` board corners, floor axes, 1 m grid, horizon
``overlay_floor.png``       the floor mask and polygon (edges coloured by kind), plan
``overlay_height.png``      the vertical edges the wall height was measured from
``report.json``             everything measured and decided (:func:`report_dict`)
=========================== =========================================================

Errors, each one message saying what and what would work: :class:`~augment.calibrate.
CalibrationError` (unreadable photo, no board), :class:`~augment.segment.
SegmentationError` (floor model), :class:`~layout.errors.LayoutError` (spec file,
unknown room preset), :class:`FurnishError` (no floor, a floor too small for any
furniture, an output folder that cannot be written).

Image convention: arrays are (row, col); points are (x, y) pixels. Colours are RGB uint8.
"""
from __future__ import annotations

import dataclasses
import importlib
import math
import platform
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from layout import report as layout_report
from layout.builder import LayoutBuilder
from layout.errors import LayoutError
from layout.fileio import replaced_input, staged_folder
from layout.geometry import edge_distances, polygon_area, triangulate_polygon
from layout.presets import DEFAULT_ROOM, PRESETS

from . import __version__
from .errors import FurnishError
from .imageio import encode_image

DEFAULT_SUGGESTIONS = 4


@dataclass(frozen=True)
class Tolerances:
    """What :func:`fit_spec` and the outputs decide by, in one place."""

    wall_margin_m: float = 0.05      # the layout's floor is the measured one shrunk by this (the outline
                                     # strays up to augment.floor.SIMPLIFY_M beyond the mask; baseboards)
    max_fill: float = 0.5            # summed footprint of floor-standing items: at most this share of the floor
    seed_tries: int = 3              # seeds tried per suggestion before an item is dropped
    min_difference_m: float = 0.3    # a suggestion this close to an earlier one (diversity) is a twin
    fit_cell_m: float = 0.02         # raster cell of the "does this footprint fit the floor" test
    fit_angles: int = 36             # orientations tried, over 180 degrees
    sheet_tile_px: int = 640         # width of one photo on the contact sheet
    sheet_gap_px: int = 8


TOL = Tolerances()

FLOOR_RGBA = (196, 170, 132, 255)    # the glTF scene's floor and walls
WALL_RGBA = (232, 229, 222, 255)
# glTF is y up; the floor frame is z up: (x, y, z) -> (x, z, -y).
GLTF_FROM_FLOOR = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]])


@dataclass
class FurnishResult:
    """Everything :func:`furnish` made, in memory.

    Attributes
    ----------
    photo : Path
    image : (h, w, 3) uint8
        The photo as read (RGB).
    calibration : Calibration
    segmentation : Segmentation
    floor : FloorPolygon
        The visible floor, meters, floor frame.
    height : HeightResult
    room_height_m : float
        The wall height the layouts were made for.
    source : str
        ``"preset living_room"`` or ``"spec PATH"``.
    spec : layout.spec.Spec
        The furniture actually laid out (the measured floor, fitted items).
    dropped : list of dict
        Items left out, ``{"id", "kind", "reason"}``, in the order they were dropped.
    layouts : list of Layout
        Suggestion K is ``layouts[K - 1]``.
    reports : list of dict
        :func:`layout.report.evaluate` of each layout.
    staged : list of (h, w, 3) uint8
        The photo furnished with each layout.
    contact_sheet : (H, W, 3) uint8
    overlays : dict of str -> (h', w', 3) uint8
        ``overlay_calibration.png``, ``overlay_floor.png``, ``overlay_height.png``.
    scenes_glb : list of bytes
        One glTF binary per suggestion.
    layout_files : dict of str -> bytes
        ``layout_K.json``, ``plan_K.png`` and ``energy.png``
        (:func:`layout.report.output_files`).
    assets : dict of str -> str
        The user's models by kind (``assets`` of :func:`furnish`), as given.
    layers : list of (h, w, 4) uint8
        With ``layers=True``: what each suggestion adds to the photo (furniture and
        shadows, and the floor over the board) as straight-alpha RGBA; laid over the photo
        it gives the staged image.
    erased : ErasedBoard or None
        The board's sheet filled with floor (:func:`augment.erase.erase_board`), the
        photo the furniture was rendered into; None with ``keep_board``.
    report : dict
        What ``report.json`` holds (:func:`report_dict`).
    timings_s : dict of str -> float
        Seconds per stage, and ``total``.
    warnings : list of str
    """

    photo: Path
    image: np.ndarray
    calibration: object
    segmentation: object
    floor: object
    height: object
    room_height_m: float
    source: str
    spec: object
    dropped: list
    layouts: list
    reports: list
    staged: list
    contact_sheet: np.ndarray
    overlays: dict
    scenes_glb: list
    layout_files: dict
    assets: dict = field(default_factory=dict)
    layers: list = field(default_factory=list)
    erased: object = None
    report: dict = field(default_factory=dict)
    timings_s: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)


# --------------------------------------------------------------------------------------
# Progress
# --------------------------------------------------------------------------------------

class _Progress:
    """One tqdm bar over the steps of a run, named after the current stage (stderr);
    nothing at all when disabled."""

    def __init__(self, enabled: bool, total: int):
        self.bar = None
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=total, file=sys.stderr, unit="step", leave=False,
                            bar_format="{desc:<24} {bar} {n_fmt}/{total_fmt} [{elapsed}]")

    def stage(self, name: str) -> None:
        if self.bar is not None:
            self.bar.set_description_str(name)

    def step(self, n: int = 1) -> None:
        if self.bar is not None:
            self.bar.update(n)

    def grow(self, n: int) -> None:
        """``n`` more steps than planned (a layout solved again)."""
        if self.bar is not None:
            self.bar.total += n
            self.bar.refresh()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


class _Clock:
    """Seconds per stage: ``with clock("layout"): ...`` adds to ``timings["layout"]``."""

    def __init__(self, progress: _Progress):
        self.timings = {}
        self.progress = progress

    @contextmanager
    def __call__(self, name: str):
        self.progress.stage(name)
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.timings[name] = self.timings.get(name, 0.0) + time.perf_counter() - t0


# --------------------------------------------------------------------------------------
# Furniture for the measured floor
# --------------------------------------------------------------------------------------

def _rect_fits(polygon_m: np.ndarray, width_m: float, depth_m: float, tol: Tolerances = TOL) -> bool:
    """Whether a ``width_m`` x ``depth_m`` rectangle fits inside the polygon at some
    position and orientation (rasterized at ``tol.fit_cell_m``; 180 / ``fit_angles``
    degree steps)."""
    cell = tol.fit_cell_m
    kw, kd = max(1, math.ceil(width_m / cell)), max(1, math.ceil(depth_m / cell))
    for theta in np.linspace(0.0, np.pi, tol.fit_angles, endpoint=False):
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


def inset_polygon(polygon_m, margin_m: float, cell_m: float = 0.01) -> np.ndarray | None:
    """The polygon shrunk by ``margin_m`` on every side (rasterized at ``cell_m``, the
    largest piece left, straightened within a cell), counter-clockwise; None when
    nothing is left.

    Parameters
    ----------
    polygon_m : (n, 2) float64
    margin_m, cell_m : float

    Returns
    -------
    (m, 2) float64 or None
    """
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


def fit_spec(spec, polygon_m, height_m: float, tol: Tolerances = TOL):
    """Fit a spec's furniture to a measured floor.

    The room becomes ``polygon_m`` and ``height_m`` (the spec's doors and windows, in
    another frame, are dropped); items that cannot be placed are dropped: taller than
    the room, a footprint (a rigid group's: all its members) that
    does not fit inside the floor at any angle, and, in the spec's order, those that
    would take the summed footprint of floor-standing items over ``tol.max_fill`` of the
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
        if not _rect_fits(poly, w, d, tol):
            drop(unit, f"its footprint {w:.2f} x {d:.2f} m fits the {area:.1f} m\u00b2 floor at no angle")
    stacked = _stacked_tops(spec.constraints)
    budget, used = tol.max_fill * area, 0.0
    for unit in _units(spec):
        fp = sum(i.kind.size_m[0] * i.kind.size_m[1] for i in unit if _blocks_floor(i, stacked))
        if used + fp > budget + 1e-9:
            drop(unit, f"no room left: {used + fp:.2f} m\u00b2 of furniture would cover more than "
                       f"{100 * tol.max_fill:.0f} % of the {area:.1f} m\u00b2 floor")
        else:
            used += fp
    return spec, [{"id": i, "kind": kinds[i], "reason": r} for i, r in reasons.items()]


def _furniture_source(room: str | None, spec):
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


# Furniture area inside a marked door's swing zone that still leaves the door usable.
DOOR_GRAZE_M2 = 0.005
# A door's feet this far apart: a narrow cupboard door to a wide double door.
DOOR_WIDTH_M = (0.5, 2.5)
# The middle of a door's feet this near a wall of the layout's floor (which lies the wall
# margin inside the measured one, itself a few centimeters off at worst).
DOOR_FROM_WALL_M = 0.5


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
        apart.

    Raises
    ------
    FurnishError
        A door outside the photo, above the horizon, of an unlikely width or not at a
        wall of the floor found; the message says what to give instead.
    """
    from layout.spec import Opening

    poly = np.asarray(polygon_m, dtype=np.float64)
    walls = sorted(set(range(len(poly))) - {int(k) for k in open_edges_})
    cols, rows = calibration.size_px
    doors = []
    for d in np.asarray(doors_px, dtype=np.float64).reshape(-1, 4):
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
        lo, hi = DOOR_WIDTH_M
        if not lo <= width <= hi:
            raise FurnishError(f"{name}: its two feet are {width:.2f} m apart on the floor, and a door is {lo:g}-"
                               f"{hi:g} m wide; give the feet of its two sides, where they meet the floor")
        middle = feet.mean(axis=0)
        distance = edge_distances(middle[None], poly)[0]
        k = min(walls, key=lambda e: distance[e]) if walls else None
        if k is None or distance[k] > DOOR_FROM_WALL_M:
            where = "the floor found has no wall in view" if k is None else \
                f"it is {distance[k]:.2f} m from the nearest wall of the floor found"
            raise FurnishError(f"{name}: {where}; a door is marked at a wall, by the feet of its two sides "
                               "(the floor overlay shows the walls found)")
        a, b = poly[k], poly[(k + 1) % len(poly)]
        t = float(np.clip(np.dot(middle - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0))
        doors.append(Opening(at_m=tuple(float(v) for v in a + t * (b - a)), width_m=round(width, 4),
                             clearance_m=None, height_m=2.1, where=name))
    return tuple(doors)


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


def _too_small(area_m2: float, dropped: list) -> FurnishError:
    what = dropped_summary(dropped)
    return FurnishError(f"floor too small for any furniture: the photo shows {area_m2:.2f} m\u00b2 of floor"
                        + (f" ({what})" if what else "")
                        + ". Show more of the floor: step back, turn toward the room, or hold the camera higher")


def _layout_floor(floor, height_m: float, photo: Path, tol: Tolerances) -> np.ndarray:
    """The floor the layouts are made on: the measured polygon shrunk by the wall margin
    (the measured one itself when shrinking leaves no usable polygon)."""
    for poly in (inset_polygon(floor.polygon_m, tol.wall_margin_m), floor.polygon_m):
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
            and all(a <= DOOR_GRAZE_M2 for a in rep["door_clearance_m2"]))


def _solve(spec, suggestions: int, seed: int, area_m2: float, dropped: list, progress: _Progress,
           tol: Tolerances):
    """Solve ``suggestions`` layouts, suggestion K from seed ``seed + K - 1``; one that
    collides, leaves the floor or repeats an earlier suggestion (closer than
    ``tol.min_difference_m``, :func:`layout.diversity`) is solved again from seed
    ``seed + K - 1 + N``, then ``+ 2N`` (``tol.seed_tries`` in all). A twin is kept when
    no try gives anything else (a floor may allow only so many arrangements). When a
    suggestion has no clean layout, the least important unit (the spec's last) is
    dropped and all are solved again."""
    from layout import diversity
    from layout.spec import build

    while True:
        model, solver = build(spec)
        layouts, reports, failed = [], [], None
        for k in range(suggestions):
            twin = None
            for t in range(tol.seed_tries):
                lay = solver.solve(model, seed=seed + k + t * suggestions)
                rep = layout_report.evaluate(lay)
                if not _clean(rep):
                    continue
                if all(diversity([old, lay]) >= tol.min_difference_m for old in layouts):
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
            raise _too_small(area_m2, dropped)
        spec, gone = _drop(spec, [i.id for i in units[-1]])
        dropped.extend({"id": i, "kind": kinds[i], "reason": reason} for i in sorted(gone))
        progress.grow(suggestions)


# --------------------------------------------------------------------------------------
# The glTF scene
# --------------------------------------------------------------------------------------

def _floor_mesh(polygon_m: np.ndarray):
    import trimesh

    poly = np.asarray(polygon_m, dtype=np.float64)
    vertices = np.column_stack([poly, np.zeros(len(poly))])
    return trimesh.Trimesh(vertices, triangulate_polygon(poly), face_colors=FLOOR_RGBA, process=False)


def _wall_mesh(walls_m: np.ndarray, height_m: float):
    """Quads of ``height_m`` on the (k, 2, 2) wall segments of a counter-clockwise floor,
    facing into the room, or None."""
    import trimesh

    if len(walls_m) == 0:
        return None
    v, f = [], []
    for (x0, y0), (x1, y1) in walls_m:
        n = len(v)
        v += [(x0, y0, 0.0), (x1, y1, 0.0), (x1, y1, height_m), (x0, y0, height_m)]
        f += [(n, n + 2, n + 1), (n, n + 3, n + 2)]
    return trimesh.Trimesh(np.array(v), np.array(f), face_colors=WALL_RGBA, process=False)


def _matte(tree: dict) -> None:
    """glTF's default material is fully metallic, which PBR viewers show nearly black:
    every primitive without a material gets a matte, two-sided one that shows its
    vertex colours."""
    materials = tree.setdefault("materials", [])
    materials.append({"name": "matte", "doubleSided": True,
                      "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                                               "roughnessFactor": 0.85}})
    for mesh in tree.get("meshes", []):
        for primitive in mesh["primitives"]:
            primitive.setdefault("material", len(materials) - 1)


def scene_glb(floor, height_m: float, layout, seed: int = 0, cache: dict | None = None,
              assets: dict | None = None) -> bytes:
    """A suggestion as a binary glTF 2.0 scene (y up, meters, as Blender, three.js and
    Unity expect): the measured floor, walls of ``height_m`` along its ``"boundary"``
    edges, and the furniture (node names are the item ids).

    Parameters
    ----------
    floor : FloorPolygon or (n, 2) float64
        In the floor frame; for an array every edge gets a wall.
    height_m : float
    layout : Layout, layout dict or sequence of PlacedItem
    seed : int
        Furniture style seed, as given to :func:`augment.render.render_staged` (the
        scene shows the same pieces as the staged photo).
    cache : dict, optional
        Built furniture kept between calls (:func:`augment.furniture.furniture_for`).
    assets : dict, optional
        Kind -> the user's model, as for :func:`augment.render.render_staged`.
    """
    import trimesh

    from .furniture import furniture_for, placed_items, world_from_item
    from .render import wall_segments

    scene = trimesh.Scene()
    scene.add_geometry(_floor_mesh(getattr(floor, "polygon_m", floor)), node_name="floor", geom_name="floor",
                       transform=GLTF_FROM_FLOOR)
    walls = _wall_mesh(wall_segments(floor), float(height_m))
    if walls is not None:
        scene.add_geometry(walls, node_name="walls", geom_name="walls", transform=GLTF_FROM_FLOOR)
    items = list(layout) if isinstance(layout, (list, tuple)) else placed_items(layout)
    for k, item in enumerate(items):
        mesh = furniture_for(item, seed, assets, cache).to_trimesh(world_from_item(item))
        name = item.id or f"{item.kind}_{k + 1}"
        scene.add_geometry(mesh, node_name=name, geom_name=name, transform=GLTF_FROM_FLOOR)
    from trimesh.exchange.gltf import export_glb

    return export_glb(scene, include_normals=True, tree_postprocessor=_matte)


# --------------------------------------------------------------------------------------
# Contact sheet, report
# --------------------------------------------------------------------------------------

def contact_sheet(images: list, labels: list | None = None, tol: Tolerances = TOL) -> np.ndarray:
    """The images side by side (two per row from four on), each scaled to
    ``tol.sheet_tile_px`` wide and numbered from 1 (or labelled) in its top-left corner.

    Parameters
    ----------
    images : list of (h, w, 3) uint8
        Of one size.
    labels : list of str, optional

    Returns
    -------
    (H, W, 3) uint8
    """
    from PIL import Image, ImageDraw

    from .overlay import overlay_font

    n = len(images)
    if n == 0:
        raise ValueError("contact sheet of no images")
    cols = n if n <= 3 else math.ceil(math.sqrt(n))
    rows = math.ceil(n / cols)
    h, w = images[0].shape[:2]
    tw = min(tol.sheet_tile_px, w)
    th = round(h * tw / w)
    gap = tol.sheet_gap_px
    sheet = Image.new("RGB", (cols * tw + (cols + 1) * gap, rows * th + (rows + 1) * gap), (255, 255, 255))
    draw = ImageDraw.Draw(sheet, "RGBA")
    font = overlay_font(max(12, th // 14))
    for k, img in enumerate(images):
        x, y = gap + (k % cols) * (tw + gap), gap + (k // cols) * (th + gap)
        sheet.paste(Image.fromarray(cv2.resize(img, (tw, th), interpolation=cv2.INTER_AREA)), (x, y))
        text = labels[k] if labels else str(k + 1)
        box = draw.textbbox((0, 0), text, font=font)
        pad = max(4, th // 60)
        draw.rectangle((x, y, x + box[2] - box[0] + 2 * pad, y + box[3] - box[1] + 2 * pad), fill=(0, 0, 0, 150))
        draw.text((x + pad - box[0], y + pad - box[1]), text, font=font, fill=(255, 255, 255))
    return np.asarray(sheet)


def versions() -> dict:
    """Versions of Stager, Python and the libraries that shape the results."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"stager": __version__, "python": platform.python_version(), "numpy": np.__version__,
           "opencv": cv2.__version__}
    for name in ("onnxruntime", "pyrender", "trimesh", "numba"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def _jsonable(x):
    """Plain JSON values: NumPy scalars and arrays unwrapped, NaN and infinities as null."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


# Share of the board's sheet covered by a thing standing on it above which the erasure
# warns (a carton over part of a ChArUco board: 24-25 % of the sheet on three renders of
# seed 7600; 0 on the 22 plain boards of seed 7300).
COVERED_WARN = 0.02

REPORT_KEYS = ("photo", "size_px", "versions", "calibration", "board", "floor", "height", "furniture", "suggestions",
               "files", "timings_s", "warnings")


def report_dict(result: FurnishResult) -> dict:
    """What ``report.json`` holds (keys :data:`REPORT_KEYS`): the calibration (its
    ``source`` and ``rms_px`` first), the floor (area, polygon, edge kinds, caveat), the
    wall height (with confidence, and ``used_m``), the furniture (source, items laid
    out, items dropped and why), per suggestion its energy, overlaps, area off the floor,
    walkability and how deep the worst item stands in another's clearance, seconds per
    stage and the library versions."""
    cal, seg, floor, height = result.calibration, result.segmentation, result.floor, result.height
    n = len(result.layouts)
    suggestions = []
    for k, (lay, rep) in enumerate(zip(result.layouts, result.reports), start=1):
        suggestions.append({
            "k": k, "seed": lay.seed, "energy": float(lay.energy), "iterations": int(lay.iterations),
            "items": len(lay.items), "overlaps": rep["overlaps"]["count"],
            "overlap_area_m2": rep["overlaps"]["area_m2"], "outside_m2": rep["outside_m2"],
            "traversable": rep["traversable"], "unreachable": rep["unreachable"],
            "clearance_intrusion_m": rep["clearances"]["deepest_m"],
            "files": {"staged": f"staged_{k}.jpg", "layout": f"layout_{k}.json", "plan": f"plan_{k}.png",
                      "scene": f"scene_{k}.glb", **({"layer": f"staged_{k}_layer.png"} if result.layers else {})}})
    return _jsonable({
        "photo": str(result.photo),
        "size_px": list(cal.size_px),
        "versions": versions(),
        "calibration": {"source": cal.intrinsics.source, "rms_px": cal.rms_px,
                        "camera_height_m": cal.camera_height_m, **cal.to_json()},
        "board": {"erased": result.erased is not None,
                  **({} if result.erased is None else {
                      "sheet_m": np.round(result.erased.sheet_m, 4), "covered": round(result.erased.covered, 4),
                      "texture_from_m": np.round(result.erased.source_m, 4)})},
        "floor": {"method": seg.method, "floor_fraction": float(seg.mask.mean()), "skirting_m": seg.skirting_m,
                  "disputed_m2": seg.disputed_m2, "disputed_share": seg.disputed_share,
                  "clicks": seg.clicks_json(), "doubt": seg.doubt_json(), **floor.to_json()},
        "height": {**height.to_json(), "used_m": result.room_height_m},
        "furniture": {"source": result.source, "floor_polygon_m": np.round(result.spec.polygon_m, 4),
                      "height_m": result.room_height_m, "items": [i.id for i in result.spec.items],
                      "kinds": [i.kind.name for i in result.spec.items], "dropped": result.dropped,
                      "doors": [{"at_m": list(o.at_m), "width_m": o.width_m, "marked": o.where}
                                for o in result.spec.doors],
                      "assets": dict(result.assets)},
        "suggestions": suggestions,
        "files": {"contact_sheet": "staged_all.jpg", "energy": "energy.png", "report": "report.json",
                  "overlays": list(result.overlays), "per_suggestion": n},
        "timings_s": {k: round(v, 4) for k, v in result.timings_s.items()},
        "warnings": list(result.warnings),
    })


# --------------------------------------------------------------------------------------
# furnish
# --------------------------------------------------------------------------------------

def _load_assets(assets) -> dict:
    """Kind -> parts of each of the user's models (see ``assets`` of :func:`furnish`)."""
    if not assets:
        return {}
    from layout.catalog import CATALOG

    from .furniture import furniture_from_asset, load_asset

    loaded = {}
    for kind, source in dict(assets).items():
        if not isinstance(kind, str) or not kind.strip():
            raise FurnishError(f"asset kind {kind!r}: name a furniture kind (`layout kinds` lists them)")
        if not isinstance(source, (str, Path)):
            loaded[kind] = tuple(source)
            continue
        path = Path(source)
        if path.suffix.lower() not in (".glb", ".gltf", ".obj"):
            raise FurnishError(f"asset for {kind}: {path} is not a GLB, glTF or OBJ file")
        try:
            loaded[kind] = load_asset(path)
            if kind in CATALOG:  # refused now, not after the layouts are solved
                furniture_from_asset(kind, CATALOG[kind].size_m, loaded[kind])
        except ValueError as error:
            raise FurnishError(f"asset for {kind}: {error}") from None
    return loaded


def _load_model(model):
    from .segment import DEFAULT_MODEL, FloorModel

    if isinstance(model, FloorModel):
        return model
    return FloorModel(DEFAULT_MODEL if model is None else Path(model))


def furnish(photo, board, *, room: str | None = None, spec=None, suggestions: int = DEFAULT_SUGGESTIONS,
            seed: int = 0, camera=None, model=None, floor_mask=None, clicks=None, doors=None,
            assets: dict | None = None, layers: bool = False, keep_board: bool = False, progress: bool = False,
            reporter=None, renderer=None, tol: Tolerances = TOL) -> FurnishResult:
    """Furnish a photo of an empty room: every stage, results in memory.

    Parameters
    ----------
    photo : path-like
        The photo, the board lying flat on the floor. Not modified.
    board : Board
        The printed board (:class:`augment.board.Board`).
    room : str, optional
        A room preset (:data:`layout.presets.PRESETS`); default ``"living_room"``.
    spec : path-like, optional
        A spec file (:mod:`layout.spec`) instead of a preset: its items, groups and
        constraints on the measured floor.
    suggestions : int
        Layouts to make; suggestion K is solved from seed ``seed + K - 1``.
    seed : int
        Also picks the furniture's styles.
    camera : path-like, optional
        A camera profile from ``stage calibrate``.
    model : path-like or FloorModel, optional
        Floor model (default :data:`augment.segment.DEFAULT_MODEL`).
    floor_mask : path-like, optional
        The user's own floor mask (white = floor; :func:`augment.segment.read_floor_mask`),
        used as it is instead of finding the floor: the mask ``stage segment`` wrote,
        corrected by hand where it went wrong. No model is loaded.
    clicks : (n, 3) array_like, optional
        The user's corrections of the floor found (x, y photo pixels, 1 floor or 0 not
        floor; :func:`augment.segment.segment_floor`). Not with ``floor_mask``.
    doors : (n, 4) array_like, optional
        Doors to keep clear: per door the photo pixels x1, y1, x2, y2 of the feet of its
        two sides (:func:`doors_on_floor`). Each swing zone, as deep as the door is
        wide, stays free of furniture.
    assets : dict, optional
        Kind -> the user's model of that kind, rendered and put in the scenes instead of
        Stager's own, stretched onto each item's box: a GLB, glTF or OBJ path (y up,
        front toward +z) or parts from :func:`augment.furniture.load_asset`.
    layers : bool
        Also keep each suggestion's RGBA layer (``FurnishResult.layers``; written as
        ``staged_K_layer.png``), to composite by hand.
    keep_board : bool
        Leave the board in the staged photos. By default its sheet is filled with the
        floor around it (:func:`augment.erase.erase_board`) before the furniture is
        rendered in; the overlays always show the photo as it is.
    progress : bool
        A progress bar on stderr.
    reporter : callable, optional
        Instead of the bar: ``reporter(total_steps)`` makes an object with ``stage(name)``,
        ``step(n=1)``, ``grow(n)`` and ``close()`` that hears of the progress (the web
        app writes it to the job's folder).
    renderer : Renderer, optional
        A GL context to reuse (one is made and closed when None).

    Returns
    -------
    FurnishResult

    Raises
    ------
    CalibrationError, SegmentationError, LayoutError, FurnishError
        Bad input (see the module docstring); the message says what would work.
    """
    from .calibrate import calibrate_file, read_photo
    from .erase import erase_board, layer_over_photo
    from .floor import floor_overlay, floor_polygon
    from .height import measure_height
    from .overlay import calibration_overlay
    from .overlay_height import height_overlay
    from .segment import read_floor_mask, segment_floor

    if isinstance(suggestions, bool) or not isinstance(suggestions, (int, np.integer)) or suggestions < 1:
        raise ValueError(f"suggestions = {suggestions!r}: must be a whole number, at least 1")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}: must be a whole number, at least 0")
    photo = Path(photo)
    t_start = time.perf_counter()
    # Everything that can be checked without the photo is, first.
    source_name, source = _furniture_source(room, spec)
    if floor_mask is not None and clicks is not None and np.size(clicks):
        raise FurnishError("clicks correct the floor Stager finds, and a floor mask is used as it is; paint "
                           "the correction into the mask, or give no mask")
    floor_model = _load_model(model) if floor_mask is None else None
    user_models = _load_assets(assets)
    steps = 6 + 3 * suggestions
    bar = _Progress(progress, steps) if reporter is None else reporter(steps)
    clock = _Clock(bar)
    # A second thread takes work that would otherwise wait for the GIL-free stretches of
    # this one: importing the renderer (pyrender and trimesh, a second or more) while
    # OpenCV and onnxruntime find the board and the floor, and drawing the plans
    # (matplotlib) while GL and NumPy render the suggestions.
    background = ThreadPoolExecutor(max_workers=1, thread_name_prefix="furnish")
    render_module = background.submit(importlib.import_module, "augment.render")
    try:
        with clock("calibrate"):
            image = read_photo(photo)
            calibration = calibrate_file(photo, board, profile=camera)
        bar.step()
        with clock("segment"):
            if floor_mask is None:
                seg = segment_floor(image, floor_model, calibration, clicks=clicks)
            else:
                seg = read_floor_mask(floor_mask, (image.shape[1], image.shape[0]), calibration)
        bar.step()
        warnings = list(calibration.warnings) + list(seg.warnings)
        with clock("floor"):
            if not seg.mask.any():
                raise FurnishError(f"photo {photo}: no floor found; the floor must show around the board")
            try:
                floor = floor_polygon(seg.mask, calibration, seg.floor_clicks_px)
            except ValueError as error:
                raise FurnishError(f"photo {photo}: no floor outline ({error}); the floor must show around "
                                   "the board") from None
            if floor.caveat:
                warnings.append(f"furniture is placed on the floor in view only ({floor.caveat})")
        bar.step()
        with clock("height"):
            height = measure_height(image, calibration, floor_mask=seg.mask)
            if height.fallback:
                warnings.append(f"wall height not measured: {height.reason}")
        bar.step()
        room_height = float(height.height_m)
        with clock("furniture"):
            poly = _layout_floor(floor, room_height, photo, tol)
            edges = open_edges(poly, floor)
            spec = _spec_for_floor(source, poly, room_height, warnings, edges)
            fitted, dropped = fit_spec(spec, poly, room_height, tol)
            if doors is not None and len(doors):
                fitted = dataclasses.replace(fitted, doors=doors_on_floor(doors, calibration, poly, edges))
            if not fitted.items:
                raise _too_small(floor.area_m2, dropped)
            kinds = {i.kind.name for i in fitted.items}
            unused = sorted(set(user_models) - kinds)
            if unused:
                warnings.append(f"no item of kind {', '.join(unused)} to show your model(s) on; the furniture is "
                                + ", ".join(sorted(kinds)))
        bar.step()
        with clock("layout"):
            fitted, layouts, reports = _solve(fitted, suggestions, seed, floor.area_m2, dropped, bar, tol)
        if dropped:
            warnings.append(f"left out {len(dropped)} item(s) that do not fit the measured floor: "
                            + dropped_summary(dropped))
        layout_files = background.submit(layout_report.output_files, layouts, reports,
                                    title=f"{photo.stem}, {source_name}: ")
        with clock("render"):
            render = render_module.result()
            own = renderer is None
            gl = render.Renderer() if own else renderer
            try:
                erased = None if keep_board else erase_board(image, calibration, seg.mask)
                if erased is not None and erased.covered > COVERED_WARN:
                    warnings.append(f"something stands on {100 * erased.covered:.0f} % of the board: it is kept "
                                    "in the staged photos, but where it overhangs the paper it may be painted "
                                    "over with floor; --keep-board leaves the board as it is")
                base = image if erased is None else erased.image
                lighting = render.estimate_lighting(base, calibration, seg.mask)
                staged, staged_layers = [], []
                for lay in layouts:
                    done = render.render_staged(base, calibration, lay, gl, floor_mask=seg.mask,
                                                floor_polygon=floor, lighting=lighting, seed=seed,
                                                assets=user_models, layer=layers)
                    staged.append(done.image)
                    if layers:
                        staged_layers.append(done.layer if erased is None else
                                             layer_over_photo(done.layer, erased, image))
                    bar.step()
            finally:
                if own:
                    gl.close()
        with clock("scene"):
            cache = {}
            scenes = []
            for lay in layouts:
                scenes.append(scene_glb(floor, room_height, lay, seed=seed, cache=cache, assets=user_models))
                bar.step()
        with clock("overlays"):
            overlays = {"overlay_calibration.png": calibration_overlay(image, calibration),
                        "overlay_floor.png": floor_overlay(image, seg.mask, floor, calibration,
                                                           seg.doubted, seg.clicks, seg.doubt_px, doors),
                        "overlay_height.png": height_overlay(image, calibration, height)}
            sheet = contact_sheet(staged, tol=tol)
        bar.step()
        with clock("plans"):  # only what the plans take beyond the stages above
            layout_files = layout_files.result()
    finally:
        # On an error nothing waits for the import or the plans still running.
        background.shutdown(wait=False, cancel_futures=True)
        bar.close()
    timings = dict(clock.timings, total=time.perf_counter() - t_start)
    result = FurnishResult(photo, image, calibration, seg, floor, height, room_height, source_name, fitted,
                           dropped, layouts, reports, staged, sheet, overlays, scenes, layout_files,
                           assets={k: str(v) if isinstance(v, (str, Path)) else "parts" for k, v in
                                   (assets or {}).items()}, layers=staged_layers, erased=erased,
                           timings_s=timings, warnings=warnings)
    result.report = report_dict(result)
    return result


# --------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------

# What each suggestion K writes: ``layout solve``'s files, the staged photo, its layer
# (with ``--layers``) and the 3-D scene.
SUGGESTION_FILES = (*layout_report.SUGGESTION_FILES, "staged_{k}.jpg", "staged_{k}_layer.png", "scene_{k}.glb")


def _write_files(result: FurnishResult, folder: Path) -> list[str]:
    """Every output file into ``folder``; returns their names."""
    import json

    names = []

    def put(name, data):
        (folder / name).write_bytes(data.encode() if isinstance(data, str) else data)
        names.append(name)

    for k, img in enumerate(result.staged, start=1):
        put(f"staged_{k}.jpg", encode_image(img, ".jpg"))
    for k, rgba in enumerate(result.layers, start=1):
        put(f"staged_{k}_layer.png", encode_image(rgba, ".png"))
    put("staged_all.jpg", encode_image(result.contact_sheet, ".jpg"))
    for name, data in result.layout_files.items():
        put(name, data)
    for k, glb in enumerate(result.scenes_glb, start=1):
        put(f"scene_{k}.glb", glb)
    for name, img in result.overlays.items():
        put(name, encode_image(img, ".png"))
    put("report.json", json.dumps(result.report, indent=2, allow_nan=False) + "\n")
    return names


def write_outputs(result: FurnishResult, out_dir, inputs=()) -> list[Path]:
    """Write every output file of ``result`` into ``out_dir``, all or none.

    The files are made in a temporary folder beside ``out_dir`` and then moved in (a new
    ``out_dir`` is renamed into place whole), so a failure leaves ``out_dir`` as it was.
    Files there that this run does not write are left alone, and so are ``inputs`` (the
    run's input files, paths or None): none of the outputs may replace one. Only an
    earlier run's suggestions that this run does not write again (its ``staged_K.jpg``,
    ``staged_K_layer.png``, ``layout_K.json``, ``plan_K.png`` and ``scene_K.glb``, of a
    run with more suggestions or with ``--layers``) are taken away with the move, so
    that the folder holds this run's files and its report.

    Returns
    -------
    paths : list of Path
        The files written, in ``out_dir``.

    Raises
    ------
    FurnishError
        When ``out_dir`` is not a folder or cannot be written, or an output would replace
        one of ``inputs``.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise FurnishError(f"output folder {out}: exists and is not a folder")
    try:
        stale = layout_report.earlier_suggestion_files(out, SUGGESTION_FILES, inputs)
        with staged_folder(out, stale=stale) as staging:
            names = _write_files(result, staging)
            if (clash := replaced_input([out / name for name in names], inputs)) is not None:
                raise FurnishError(f"output folder {out}: {clash[0].name} there is the input {clash[1]}, which "
                                   "Stager never overwrites; nothing was changed in it; write the outputs to "
                                   "another folder")
    except OSError as error:
        raise FurnishError(f"output folder {out}: cannot write there ({error.strerror or error}); "
                           "nothing was changed in it; choose a folder you can write to") from None
    return [out / name for name in names]
