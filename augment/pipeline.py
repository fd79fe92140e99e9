"""Photo in, furnished photos out: Stager end to end (thesis Algorithm 4, Appendix C).

Orchestration only: each stage lives in its own subpackage, and this module runs them in
order. :func:`measure` takes a photo of an empty room with the board lying on its floor
to a :class:`Measurement` (``stage measure``); :func:`furnish` goes on to furnished
photos, everything in memory (:class:`FurnishResult`); :func:`write_outputs` writes it to
a folder, all files or none. ``stage furnish`` is the command line over the last two.

Stages, in order (``timings_s`` has one entry per stage):

1. ``calibrate``: the camera from the board (:func:`augment.camera.calibrate.calibrate_file`;
   focal length from ``camera``, else EXIF, else the board). The floor frame is the
   board's: origin at its center, z up, meters.
2. ``segment``: the floor mask (:func:`augment.floor.segment.segment_floor`), or the
   user's own (``floor_mask``, :func:`augment.floor.segment.read_floor_mask`).
3. ``floor``: the visible floor's polygon in meters (:func:`augment.floor.polygon.floor_polygon`).
4. ``height``: the wall height (:func:`augment.room.height.measure_height`; 2.5 m
   assumed when nothing trustworthy is in view, with a warning).
5. ``furniture``: the furniture from a room preset or a spec file, on the measured floor
   and height (:func:`augment.room.fit.furniture_for_floor`): what cannot fit is dropped.
6. ``layout``: ``suggestions`` layouts (:func:`augment.room.fit.solve_suggestions`:
   suggestion K from seed ``seed + K - 1``, never one with overlaps or items off the floor).
7. ``render``: each layout rendered into the photo (:func:`augment.render.staged.render_staged`,
   one GL context for all) with the board erased (:func:`augment.render.erase.erase_board`);
   the erasure, the light and the camera's look are worked out once, on a second thread
   while ``furniture`` and ``layout`` run; this stage waits for them.
8. ``scene``: each suggestion as a glTF scene (:func:`augment.render.gltf.scene_glb`).
9. ``overlays``: calibration, floor and height drawn over the photo, and the contact
   sheet of the staged photos (:mod:`augment.draw`).
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
``energy.png``              energy per solver iteration of every suggestion (not of ``--layout``)
``scene_K.glb``             glTF 2.0 scene (y up, meters): floor, walls, furniture
``overlay_calibration.png`` board corners, floor axes, 1 m grid, horizon
``overlay_floor.png``       the floor mask and polygon (edges coloured by kind), plan
``overlay_height.png``      the vertical edges the wall height was measured from
``report.json``             everything measured and decided (:func:`report_dict`)
=========================== =========================================================

Errors: bad input raises a :class:`~augment.errors.StagerError` whose message says what
and what would work (an unreadable photo, no board, no floor, a floor too small for any
furniture, a bad spec, an output folder that cannot be written).

Image convention: arrays are (row, col); points are (x, y) pixels. Colours are RGB uint8.
"""
from __future__ import annotations

import importlib
import math
import os
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
from layout.fileio import folder_problem, replaced_input, staged_folder
from layout.metrics import area_outside
from layout.spec import read_layout

from . import __version__
from .camera.calibrate import calibrate_file
from .draw.calibration import calibration_overlay
from .draw.floor import floor_overlay
from .draw.height import height_overlay
from .draw.settings import DRAW
from .draw.sheet import contact_sheet
from .errors import FurnishError
from .floor.model import load_floor_model
from .floor.polygon import floor_polygon
from .floor.segment import read_floor_mask, segment_floor
from .photo.io import encode_image, read_photo
from .render.erase import erase_board, layer_over_photo
from .render.styles import STYLES
from .room.fit import (broken_rules, corner_specs, dropped_summary, furniture_for_floor, furniture_source,
                       rule_count, solve_suggestions)
from .room.openings import find_openings
from .room.height import measure_height

DEFAULT_SUGGESTIONS = 4


@dataclass
class Measurement:
    """The room measured from one photo: what :func:`measure` found.

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
    timings_s : dict of str -> float
        Seconds per stage.
    warnings : list of str
    """

    photo: Path
    image: np.ndarray
    calibration: object
    segmentation: object
    floor: object
    height: object
    timings_s: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)


@dataclass(kw_only=True)
class FurnishResult(Measurement):
    """Everything :func:`furnish` made, in memory: the :class:`Measurement` (its
    ``timings_s`` then cover every stage, and ``total``), and:

    Attributes
    ----------
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
    overlay_png : dict of str -> bytes
        The same as PNG files (encoded while the photos were rendered).
    scenes_glb : list of bytes
        One glTF binary per suggestion.
    layout_files : dict of str -> bytes
        ``layout_K.json``, ``plan_K.png`` and ``energy.png``
        (:func:`layout.report.output_files`).
    assets : dict of str -> str
        The user's models by kind (``assets`` of :func:`furnish`), as given.
    styles : list of str
        Each suggestion's style (:data:`augment.render.styles.STYLES`).
    layers : list of (h, w, 4) uint8
        With ``layers=True``: what each suggestion adds to the photo (furniture and
        shadows, and the floor over the board) as straight-alpha RGBA; laid over the photo
        it gives the staged image.
    erased : ErasedBoard or None
        The board's sheet filled with floor (:func:`augment.render.erase.erase_board`), the
        photo the furniture was rendered into; None with ``keep_board``.
    look : PhotoLook or None
        The photo's noise and sharpness given to the furniture
        (:func:`augment.render.look.estimate_look`); None when nothing was rendered.
    lighting : Lighting or None
        The light the furniture was rendered in (:func:`augment.render.staged.estimate_lighting`).
    windows : list of FoundWindow
        The windows found in the photo (:func:`augment.room.openings.find_openings`; none
        with ``auto_doors=False``): their panes took no shadows.
    report : dict
        What ``report.json`` holds (:func:`report_dict`).
    """

    room_height_m: float
    source: str
    spec: object
    dropped: list
    layouts: list
    reports: list
    staged: list
    contact_sheet: np.ndarray
    overlays: dict
    overlay_png: dict
    scenes_glb: list
    layout_files: dict
    assets: dict = field(default_factory=dict)
    styles: list = field(default_factory=list)
    layers: list = field(default_factory=list)
    erased: object = None
    look: object = None
    lighting: object = None
    windows: list = field(default_factory=list)
    report: dict = field(default_factory=dict)


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

# --------------------------------------------------------------------------------------
# The glTF scene
# --------------------------------------------------------------------------------------

# --------------------------------------------------------------------------------------
# measure
# --------------------------------------------------------------------------------------

def measure(photo, board, *, camera=None, model=None, floor_mask=None, clicks=None, height_m=None,
            clock: _Clock | None = None) -> Measurement:
    """Measure the room in a photo: the camera, the floor and the wall height.

    Parameters
    ----------
    photo : path-like
        The photo, the board lying flat on the floor. Not modified.
    board : Board
        The printed board (:class:`augment.camera.board.Board`).
    camera : path-like, optional
        A camera profile from ``stage calibrate``.
    model : path-like or FloorModel, optional
        Floor model (default :data:`augment.floor.model.DEFAULT_MODEL`).
    floor_mask : path-like, optional
        The user's own floor mask (white = floor), used as it is instead of finding the
        floor. No model is loaded.
    clicks : (n, 3) array_like, optional
        The user's corrections of the floor found (x, y photo pixels, 1 floor or 0 not
        floor; :func:`augment.floor.segment.segment_floor`). Not with ``floor_mask``.
    height_m : float, optional
        The wall height the user knows, used when the photo does not show it (the ceiling
        out of view; :func:`augment.room.height.measure_height`).
    clock : optional
        Times the stages (``calibrate``, ``segment``, ``floor``, ``height``) and steps a
        progress bar after each; a silent one when None.

    Returns
    -------
    Measurement

    Raises
    ------
    StagerError
        Bad input; the message says what would work.
    """
    photo = Path(photo)
    if floor_mask is not None and clicks is not None and np.size(clicks):
        raise FurnishError("clicks correct the floor Stager finds, and a floor mask is used as it is; paint "
                           "the correction into the mask, or give no mask")
    floor_model = load_floor_model(model) if floor_mask is None else None
    clock = _Clock(_Progress(False, 0)) if clock is None else clock
    with clock("calibrate"):
        image = read_photo(photo)
        calibration = calibrate_file(photo, board, profile=camera, image=image)
    clock.progress.step()
    with clock("segment"):
        if floor_mask is None:
            seg = segment_floor(image, floor_model, calibration, clicks=clicks)
        else:
            seg = read_floor_mask(floor_mask, (image.shape[1], image.shape[0]), calibration)
    clock.progress.step()
    warnings = list(calibration.warnings) + list(seg.warnings)
    with clock("floor"):
        if not seg.mask.any():
            raise FurnishError(f"photo {photo}: no floor found; the floor must show around the board")
        try:
            floor = floor_polygon(seg.mask, calibration, seg.floor_clicks_px)
        except ValueError as error:
            if floor_mask is not None:
                raise FurnishError(f"floor mask {floor_mask}: no floor outline ({error}); paint the floor around "
                                   "the board white, in a patch, not a line") from None
            raise FurnishError(f"photo {photo}: no floor outline ({error}); the floor must show around "
                               "the board") from None
    clock.progress.step()
    with clock("height"):
        height = measure_height(image, calibration, floor_mask=seg.mask, given_m=height_m)
        if height.fallback:
            warnings.append(f"wall height not measured: {height.reason}")
    clock.progress.step()
    return Measurement(photo, image, calibration, seg, floor, height, dict(clock.timings), warnings)


def overlays(m: Measurement, doors=None, windows_px=()) -> dict:
    """The three overlays of a measurement, ``{file name: (h, w, 3) uint8}``; ``doors``
    are the ones the user marked or, without, those found in the photo; ``windows_px``
    the corners of the windows found (:class:`augment.room.openings.FoundWindow`). Over a
    photo larger than ``DRAW.overlay_long_px`` on its long side, the calibration's and the
    height's are shrunk to that; the floor's stays the photo's size: clicks that correct
    the floor are given in its pixels."""
    seg = m.segmentation
    scale = min(1.0, DRAW.overlay_long_px / max(m.image.shape[:2]))

    def shrunk(p):
        size = (round(p.shape[1] * scale), round(p.shape[0] * scale))
        return p if scale == 1.0 else cv2.resize(p, size, interpolation=cv2.INTER_AREA)

    return {"overlay_calibration.png": shrunk(calibration_overlay(m.image, m.calibration)),
            "overlay_floor.png": floor_overlay(m.image, seg.mask, m.floor, m.calibration, seg.doubted, seg.clicks,
                                               seg.doubt_px, doors, windows_px),
            "overlay_height.png": shrunk(height_overlay(m.image, m.calibration, m.height))}


# --------------------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------------------

def _warm_solver():
    """One tiny layout solved: a fresh process loads the solver's compiled kernels from
    numba's cache (about a second), here while the main thread's OpenCV and onnxruntime
    find the board and the floor without the GIL."""
    from layout.builder import LayoutBuilder
    from layout.solver import Solver

    builder = LayoutBuilder([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    builder.add_item("warm", (0.5, 0.5, 0.5))
    Solver().solve(builder.finalize(), seed=0)


def _photo_light(m: Measurement, keep_board: bool, ceiling_m: float):
    """The board erased (None with ``keep_board``), the light and the camera's look: all
    from the photo as taken (the board's white squares give the light, its edges the
    sharpness), none from the layouts."""
    from .render.staged import estimate_lighting, estimate_look
    erased = None if keep_board else erase_board(m.image, m.calibration, m.segmentation.mask)
    lighting = estimate_lighting(m.image, m.calibration, m.segmentation.mask, floor_polygon=m.floor,
                                 ceiling_m=ceiling_m)
    return erased, lighting, estimate_look(m.image, m.calibration)


def _scenes(floor, room_height_m: float, layouts, styles, seed: int, assets) -> list[bytes]:
    """Each layout's 3-D scene (GLB), its furniture as rendered."""
    from .render.gltf import scene_glb
    cache = {}
    return [scene_glb(floor, room_height_m, lay, seed=_seed(lay, seed), cache=cache, assets=assets, style=style_name)
            for lay, style_name in zip(layouts, styles)]


def _drawn_overlays(m: Measurement, doors, windows_px) -> tuple[dict, dict]:
    """:func:`overlays`, and the same as PNG files."""
    pictures = overlays(m, doors, windows_px)
    return pictures, {name: encode_image(picture, ".png") for name, picture in pictures.items()}


def versions() -> dict:
    """Versions of Stager, Python and the libraries that shape the results."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"stager": __version__, "python": platform.python_version(), "numpy": np.__version__,
           "opencv": cv2.__version__}
    # By import name; pyrender's maintained fork is distributed as pyrender2.
    for name, distribution in (("onnxruntime", "onnxruntime"), ("pyrender", "pyrender2"), ("trimesh", "trimesh"),
                               ("numba", "numba")):
        try:
            out[name] = version(distribution)
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


def floor_report(m: Measurement) -> dict:
    """The floor as the reports give it: how it was found, and its polygon."""
    return {**m.segmentation.to_json(), **m.floor.to_json()}


def measure_report(m: Measurement) -> dict:
    """What ``stage measure`` writes to ``report.json``."""
    t = m.timings_s
    return _jsonable({"photo": str(m.photo), "stager_version": __version__, "calibration": m.calibration.to_json(),
                      "floor": floor_report(m), "height": m.height.to_json(),
                      "timings": {"calibrate_s": round(t["calibrate"], 3),
                                  "segment_s": round(t["segment"] + t["floor"], 3),
                                  "height_s": round(t["height"], 3)},
                      "warnings": list(m.warnings)})


REPORT_KEYS = ("photo", "size_px", "versions", "calibration", "board", "camera_look", "light", "floor", "height",
               "furniture", "suggestions", "files", "timings_s", "warnings")


def report_dict(result: FurnishResult) -> dict:
    """What ``report.json`` holds (keys :data:`REPORT_KEYS`): the calibration (its
    ``source`` and ``rms_px`` first), the floor (area, polygon, edge kinds, caveat), the
    wall height (with confidence, and ``used_m``), the furniture (source, items laid
    out, items dropped and why), per suggestion its energy, overlaps, area off the floor,
    walkability, how deep the worst item stands in another's clearance and the rules it
    breaks (:func:`augment.room.fit.broken_rules`), seconds per
    stage, the photo's noise and sharpness given to the furniture (``camera_look``), the
    light it was rendered in (``light``) and
    the library versions."""
    cal, height = result.calibration, result.height
    n = len(result.layouts)
    suggestions = []
    for k, (lay, rep) in enumerate(zip(result.layouts, result.reports), start=1):
        suggestions.append({
            "k": k, "seed": lay.seed, "style": result.styles[k - 1] if result.styles else None,
            "energy": float(lay.energy), "iterations": int(lay.iterations),
            "items": len(lay.items), "overlaps": rep["overlaps"]["count"],
            "overlap_area_m2": rep["overlaps"]["area_m2"], "outside_m2": rep["outside_m2"],
            "traversable": rep["traversable"], "unreachable": rep["unreachable"],
            "clearance_intrusion_m": rep["clearances"]["deepest_m"],
            **({"camera": rep["camera"]} if "camera" in rep else {}),
            "rules": {"judged": rule_count(lay), "broken": broken_rules(lay)},
            "furniture": [lay.model.names[i] for i in lay.items],
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
        "camera_look": None if result.look is None else result.look.to_json(),
        "light": None if result.lighting is None else result.lighting.to_json(),
        "floor": floor_report(result),
        "height": {**height.to_json(), "used_m": result.room_height_m},
        "furniture": {"source": result.source, "floor_polygon_m": np.round(result.spec.polygon_m, 4),
                      "height_m": result.room_height_m, "items": [i.id for i in result.spec.items],
                      "kinds": [i.kind.name for i in result.spec.items], "dropped": result.dropped,
                      "doors": [{"at_m": list(o.at_m), "width_m": o.width_m, "margin_m": o.margin_m, "marked": o.where}
                                for o in result.spec.doors],
                      "windows": [{"at_m": list(o.at_m), "width_m": o.width_m, "sill_m": o.sill_m,
                                   "height_m": o.height_m} for o in result.spec.windows],
                      "assets": dict(result.assets)},
        "suggestions": suggestions,
        "files": {"contact_sheet": "staged_all.jpg", "report": "report.json",
                  "energy": "energy.png" if "energy.png" in result.layout_files else None,
                  "overlays": list(result.overlays), "per_suggestion": n},
        "timings_s": {k: round(v, 4) for k, v in result.timings_s.items()},
        "warnings": list(result.warnings),
    })


# --------------------------------------------------------------------------------------
# furnish
# --------------------------------------------------------------------------------------

def off_floor_m2(layout, polygon_m) -> float:
    """How much of a layout's furniture footprint lies off the floor ``polygon_m``, m²."""
    return float(area_outside(np.asarray(polygon_m, dtype=np.float64), layout.corners_m()).sum())


def _seed(layout, seed: int) -> int:
    """The seed a suggestion was solved from, which also picks its designs."""
    return seed if layout.seed is None else int(layout.seed)


def suggestion_styles(style: str | None, seed: int, suggestions: int) -> list[str]:
    """Each suggestion's style: ``style`` for all, or by default a different one for each,
    in :data:`augment.render.styles.STYLES`' order from the seed's on."""
    names = list(STYLES)
    if style is None:
        return [names[(seed + k) % len(names)] for k in range(suggestions)]
    if style not in STYLES:
        raise FurnishError(f"style {style!r}: choose one of {', '.join(names)}")
    return [style] * suggestions


def furnish(photo, board, *, room: str | None = None, spec=None, suggestions: int = DEFAULT_SUGGESTIONS,
            seed: int = 0, style: str | None = None, layout=None, camera=None, model=None, floor_mask=None,
            clicks=None, doors=None, auto_doors: bool = True, assets: dict | None = None, layers: bool = False,
            keep_board: bool = False, height_m=None, progress: bool = False, reporter=None,
            renderer=None) -> FurnishResult:
    """Furnish a photo of an empty room: every stage, results in memory.

    Parameters
    ----------
    photo : path-like
        The photo, the board lying flat on the floor. Not modified.
    board : Board
        The printed board (:class:`augment.camera.board.Board`).
    room : str, optional
        A room preset (:data:`layout.presets.PRESETS`); default ``"living_room"``.
    spec : path-like, optional
        A spec file (:mod:`layout.spec`) instead of a preset: its items, groups and
        constraints on the measured floor.
    suggestions : int
        Layouts to make; suggestion K is solved from seed ``seed + K - 1``, which also
        picks its furniture's designs.
    seed : int
        The first suggestion's seed.
    style : str, optional
        Every suggestion in this style (:data:`augment.render.styles.STYLES`); by default
        suggestion K takes the K-th style from the seed's on, so each looks different.
    layout : path-like, optional
        A layout made before for this photo (``layout_K.json``), rendered again as it
        stands, with its own designs, instead of solving: one suggestion, e.g. in another
        ``style``.
    camera : path-like, optional
        A camera profile from ``stage calibrate``.
    model : path-like or FloorModel, optional
        Floor model (default :data:`augment.floor.model.DEFAULT_MODEL`).
    floor_mask : path-like, optional
        The user's own floor mask (white = floor; :func:`augment.floor.segment.read_floor_mask`),
        used as it is instead of finding the floor: the mask ``stage segment`` wrote,
        corrected by hand where it went wrong. No model is loaded.
    clicks : (n, 3) array_like, optional
        The user's corrections of the floor found (x, y photo pixels, 1 floor or 0 not
        floor; :func:`augment.floor.segment.segment_floor`). Not with ``floor_mask``.
    doors : (n, 4) array_like, optional
        Doors to keep clear: per door the photo pixels x1, y1, x2, y2 of the feet of its
        two sides (:func:`doors_on_floor`). Each swing zone, as deep as the door is
        wide, stays free of furniture.
    auto_doors : bool
        Find the windows in the photo, and without ``doors`` the doors
        (:func:`augment.room.openings.find_openings`): doors are kept clear the same way,
        windows free of tall furniture, and a window's pane takes no shadow.
    assets : dict, optional
        Kind -> the user's model of that kind, rendered and put in the scenes instead of
        Stager's own, stretched onto each item's box: a GLB, glTF or OBJ path (y up,
        front toward +z) or parts from :func:`augment.render.furniture.load_asset`.
    layers : bool
        Also keep each suggestion's RGBA layer (``FurnishResult.layers``; written as
        ``staged_K_layer.png``), to composite by hand.
    keep_board : bool
        Leave the board in the staged photos. By default its sheet is filled with the
        floor around it (:func:`augment.render.erase.erase_board`) before the furniture is
        rendered in; the overlays always show the photo as it is.
    height_m : float, optional
        The wall height, used when the photo does not show it (:func:`measure`).
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
    if isinstance(suggestions, bool) or not isinstance(suggestions, (int, np.integer)) or suggestions < 1:
        raise ValueError(f"suggestions = {suggestions!r}: must be a whole number, at least 1")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed = {seed!r}: must be a whole number, at least 0")
    photo = Path(photo)
    t_start = time.perf_counter()
    # Everything that can be checked without the photo is, first.
    if layout is not None:
        # A layout made before (layout_K.json), rendered again as it stands: one suggestion.
        if room is not None or spec is not None:
            raise FurnishError(f"layout {layout}: it holds its own furniture; give no room preset or spec with it")
        source_name = f"layout {layout}"
        fixed_spec, fixed_layout = read_layout(layout)
        suggestions = 1
        # Its own seed picks the designs and default style it was first rendered with.
        styles = suggestion_styles(style, seed if fixed_layout.seed is None else fixed_layout.seed, 1)
    else:
        source_name, source = furniture_source(room, spec)
        styles = suggestion_styles(style, seed, suggestions)
    if assets:  # checked before any work; without them, trimesh is imported on the second thread
        from .render.furniture import load_assets
        user_models = load_assets(assets)
    else:
        user_models = {}
    steps = 6 + 3 * suggestions
    bar = _Progress(progress, steps) if reporter is None else reporter(steps)
    clock = _Clock(bar)
    # A second thread takes work that would otherwise wait for the GIL-free stretches of
    # this one: loading the solver's kernels and importing the renderer (pyrender and
    # trimesh, a second or more each) while OpenCV and onnxruntime find the board and the
    # floor; erasing the board and reading
    # the light off the photo while the layouts are solved; drawing the plans (matplotlib)
    # and building the 3-D scenes while GL and NumPy render the suggestions.
    background = ThreadPoolExecutor(max_workers=1, thread_name_prefix="furnish")
    if layout is None:  # a layout rendered again solves nothing
        background.submit(_warm_solver)
    background.submit(importlib.import_module, "augment.render.gltf")
    background.submit(importlib.import_module, "layout.plot")  # matplotlib, for the plans
    try:
        m = measure(photo, board, camera=camera, model=model, floor_mask=floor_mask, clicks=clicks,
                    height_m=height_m, clock=clock)
        room_height = float(m.height.height_m)
        photo_light = background.submit(_photo_light, m, keep_board, room_height)
        warnings = list(m.warnings)
        if m.floor.caveat:
            warnings.append(f"furniture is placed on the floor in view only ({m.floor.caveat})")
        # The doors kept clear: the user's, else those found in the photo (drawn on the overlay too).
        marked = doors is not None and len(doors) > 0
        with clock("furniture"):
            # Found for a layout rendered again too: a window's pane takes no shadow.
            found = find_openings(m.image, m.calibration, m.floor) if auto_doors else None
        found_windows = [] if found is None else found.windows
        found_px = [f.feet_px.ravel() for f in found.doors] if found is not None and not marked else []
        if layout is not None:
            fitted, layouts, dropped = fixed_spec, [fixed_layout], []
            reports = [layout_report.evaluate(fixed_layout)]
            if (off := off_floor_m2(fixed_layout, m.floor.polygon_m)) > 0.05:
                warnings.append(f"layout {layout}: {off:.2f} m\u00b2 of its furniture stands off the floor "
                                "measured in this photo: was it made for this photo?")
            bar.step(1 + suggestions)
        else:
            with clock("furniture"):
                fitted, dropped = furniture_for_floor(source, m.floor, room_height, photo, doors=doors,
                                                      found_doors=found_px, found_windows=found_windows,
                                                      calibration=m.calibration, asset_kinds=user_models,
                                                      warnings=warnings)
            bar.step()
            with clock("layout"):
                corners = corner_specs(source, fitted, m.calibration)
                fitted, layouts, reports = solve_suggestions(fitted, suggestions, seed, m.floor.area_m2, dropped,
                                                             bar, warnings, corners)
                # Rendered as layout_K.json holds them, so `--layout` renders the very same photo.
                layouts = [lay.as_written() for lay in layouts]
        if dropped:
            # A corner set's piece of the same id as the room's counts once, as in the summary.
            n = len({d['id'] for d in dropped})
            warnings.append(f"left out {n} item{' that does' if n == 1 else 's that do'} not fit the measured floor: "
                            + dropped_summary(dropped))
        # A plan's title names no folder (the web app's files are its own).
        titled = source_name if layout is None else f"layout {Path(layout).name}"
        layout_files = background.submit(layout_report.output_files, layouts, reports,
                                         title=f"{photo.stem}, {titled}: ")
        # Drawn and encoded while the main thread renders: they need nothing from the render.
        pictures = background.submit(_drawn_overlays, m, doors if marked else found_px,
                                     [w.corners_px for w in found_windows])
        # The 3-D scenes need nothing from the render either.
        scenes = background.submit(_scenes, m.floor, room_height, layouts, styles, seed, user_models)
        with clock("render"):
            from .render import staged as render
            own = renderer is None
            gl = render.Renderer() if own else renderer
            try:
                erased, lighting, camera_look = photo_light.result()
                if erased is not None and erased.warning:
                    warnings.append(erased.warning)
                base = m.image if erased is None else erased.image
                staged, staged_layers = [], []
                for lay, style_name in zip(layouts, styles):
                    done = render.render_staged(base, m.calibration, lay, gl, floor_mask=m.segmentation.mask,
                                                floor_polygon=m.floor, lighting=lighting, look=camera_look,
                                                seed=_seed(lay, seed), style=style_name, assets=user_models,
                                                layer=layers, windows_px=[w.corners_px for w in found_windows])
                    staged.append(done.image)
                    if layers:
                        staged_layers.append(done.layer if erased is None else
                                             layer_over_photo(done.layer, erased, m.image))
                    bar.step()
            finally:
                if own:
                    gl.close()
        with clock("scene"):  # the wait for the scenes beyond the render
            scenes = scenes.result()
            bar.step(len(scenes))
        with clock("overlays"):  # the contact sheet, and the wait for the overlays
            sheet = contact_sheet(staged)
            pictures, overlay_png = pictures.result()
        bar.step()
        with clock("plans"):  # only the wait for the plans beyond the stages above
            layout_files = layout_files.result()
    finally:
        # On an error nothing waits for the import or the plans still running.
        background.shutdown(wait=False, cancel_futures=True)
        bar.close()
    timings = dict(clock.timings, total=time.perf_counter() - t_start)
    result = FurnishResult(photo=photo, image=m.image, calibration=m.calibration, segmentation=m.segmentation,
                           floor=m.floor, height=m.height, timings_s=timings, warnings=warnings,
                           room_height_m=room_height, source=source_name, spec=fitted, dropped=dropped,
                           layouts=layouts, reports=reports, staged=staged, contact_sheet=sheet, overlays=pictures,
                           overlay_png=overlay_png,
                           scenes_glb=scenes, layout_files=layout_files, styles=styles[:len(layouts)],
                           assets={k: str(v) if isinstance(v, (str, Path)) else "parts" for k, v in
                                   (assets or {}).items()}, layers=staged_layers, erased=erased,
                           look=camera_look, lighting=lighting, windows=found_windows)
    result.report = report_dict(result)
    return result


# --------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------

# What each suggestion K writes: ``layout solve``'s files, the staged photo, its layer
# (with ``--layers``) and the 3-D scene.
SUGGESTION_FILES = (*layout_report.SUGGESTION_FILES, "staged_{k}.jpg", "staged_{k}_layer.png", "scene_{k}.glb")


def output_files(result: FurnishResult) -> dict[str, bytes]:
    """Every output file of ``result``, encoded: name -> bytes (what :func:`write_outputs`
    writes; a batch worker hands these to the driver that writes the folder)."""
    import json

    images = {f"staged_{k}.jpg": img for k, img in enumerate(result.staged, start=1)}
    images.update({f"staged_{k}_layer.png": rgba for k, rgba in enumerate(result.layers, start=1)})
    images["staged_all.jpg"] = result.contact_sheet
    # OpenCV encodes without the GIL: the images of a 12 MP photo take a second on one core.
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1, thread_name_prefix="encode") as pool:
        encoded = {name: pool.submit(encode_image, img, Path(name).suffix) for name, img in images.items()}
        files = {name: encoded[name].result() for name in images}
    for name, data in result.layout_files.items():
        files[name] = data.encode() if isinstance(data, str) else data
    for k, glb in enumerate(result.scenes_glb, start=1):
        files[f"scene_{k}.glb"] = glb
    files.update(result.overlay_png)
    files["report.json"] = (json.dumps(result.report, indent=2, allow_nan=False) + "\n").encode()
    return files


def write_outputs(result: FurnishResult, out_dir, inputs=()) -> list[Path]:
    """Write every output file of ``result`` into ``out_dir``, all or none
    (:func:`write_files` of :func:`output_files`)."""
    return write_files(output_files(result), out_dir, inputs)


def write_files(files: dict, out_dir, inputs=()) -> list[Path]:
    """Write ``files`` (name -> bytes, :func:`output_files`) into ``out_dir``, all or none.

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
    if (problem := folder_problem(out)) is not None:
        raise FurnishError(f"output folder {out}: {problem}")
    try:
        stale = layout_report.earlier_suggestion_files(out, SUGGESTION_FILES, inputs)
        with staged_folder(out, stale=stale) as staging:
            for name, data in files.items():
                (staging / name).write_bytes(data)
            names = list(files)
            if (clash := replaced_input([out / name for name in names], inputs)) is not None:
                raise FurnishError(f"output folder {out}: {clash[0].name} there is the input {clash[1]}, which "
                                   "Stager never overwrites; nothing was changed in it; write the outputs to "
                                   "another folder")
    except OSError as error:
        raise FurnishError(f"output folder {out}: cannot write there ({error.strerror or error}); "
                           "nothing was changed in it; choose a folder you can write to") from None
    return [out / name for name in names]
