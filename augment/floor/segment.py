"""Where the floor is: the floor model's mask refined by GrabCut, and the user's corrections.

Thesis Appendix C.3.1: a segmentation network's floor class seeds GrabCut (the network:
:mod:`augment.floor.model`). GrabCut refines the model's edges against the photo's colours;
the board (it lies on the floor) and the horizon (nothing above it is floor) pin it down.
Without a model, GrabCut alone starts from the calibration's geometry. Where the model
and the refined mask disagree is measured and, when large, said (:func:`disputed_floor`);
a user's own mask can stand in for all of it (:func:`read_floor_mask`).

Images are RGB ``(rows, cols, 3)`` uint8; masks are ``(rows, cols)`` bool; points are
``(x, y)`` pixels.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np

from layout.fileio import path_problem

from ..errors import SegmentationError
from ..photo.io import decode_grey, decode_problem, header, pixels_problem, read_user_file
from .model import FloorModel, check_image, shrink_area, shrink_to, working_scale
from .settings import FLOOR
from .skirting import board_clicks, trim_skirting
from .upright import Upright
from .wall_foot import reach_wall_foot

# ----------------------------------------------------------------------------- geometry seeds

def below_horizon(shape: tuple[int, int], horizon: np.ndarray, margin_px: float = 0.0) -> np.ndarray:
    """Pixels on the floor side of the horizon line ``a x + b y + c = 0`` by ``margin_px``."""
    rows, cols = shape
    y, x = np.mgrid[0:rows, 0:cols]
    a, b, c = horizon
    return a * x + b * y + c > margin_px


def board_polygon_px(calibration, grow: float = 1.0) -> np.ndarray:
    """The board's paper outline in pixels, (4, 2), optionally grown about its center."""
    outline = calibration.board.outline_m() * grow
    return calibration.pixels_from_floor(outline)


def floor_distance_m(shape: tuple[int, int], calibration) -> np.ndarray:
    """Horizontal distance (rows, cols) from the camera to each pixel's floor point; inf
    at and above the horizon, and beyond the lens model's reach
    (:meth:`~augment.camera.calibration.Calibration.lens_maps`)."""
    rows, cols = shape
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float64)
    pts = np.column_stack([x.ravel(), y.ravel()])
    cam = np.linalg.inv(calibration.camera_from_floor)[:2, 3]
    floor = calibration.floor_from_pixels(pts)
    d = np.hypot(floor[:, 0] - cam[0], floor[:, 1] - cam[1])
    d[~calibration.lens_maps(pts)] = np.inf
    d = d.reshape(rows, cols)
    d[~below_horizon(shape, calibration.horizon, 1.0)] = np.inf
    return d


def floor_footprint_m2(points_px: np.ndarray, calibration) -> np.ndarray:
    """Floor area (m^2) a pixel at each of ``points_px`` (n, 2) covers, through the floor
    homography: its local area scale. Meaningless at and above the horizon."""
    pts = np.asarray(points_px, dtype=np.float64).reshape(-1, 2)
    H = np.linalg.inv(calibration.image_from_floor)
    w = pts @ H[2, :2] + H[2, 2]
    # |det J| of the projective map (x, y) -> floor at a point is det(H) / w^3.
    return np.abs(np.linalg.det(H) / np.where(np.abs(w) > 1e-12, w, np.inf) ** 3)


def _believed_footprint_m2(shape: tuple[int, int], calibration, distance_m: np.ndarray | None = None) -> np.ndarray:
    """Each pixel's floor area (m^2, :func:`floor_footprint_m2`), (rows, cols), zero beyond
    ``FLOOR.segment.max_floor_distance_m`` (``distance_m``: :func:`floor_distance_m`, when known)."""
    rows, cols = shape
    y, x = np.mgrid[0:rows, 0:cols]
    footprint = floor_footprint_m2(np.column_stack([x.ravel(), y.ravel()]), calibration).reshape(rows, cols)
    if distance_m is None:
        distance_m = floor_distance_m(shape, calibration)
    return footprint * (distance_m <= FLOOR.segment.max_floor_distance_m)


def border_pixels(image: np.ndarray) -> np.ndarray:
    """The values of ``image`` (rows, cols) along the photo's four edges, (2 rows + 2 cols,)."""
    return np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])


def floor_parts(mask: np.ndarray, calibration=None, probability: np.ndarray | None = None,
                distance_m: np.ndarray | None = None,
                reach_edge: bool = True) -> tuple[np.ndarray, int, list[int]]:
    """The floor's connected regions: the main one and the parts cut off from it.

    A carton or a wall corner standing at the photo's edge cuts the visible floor in two;
    both are floor, and they meet beyond the edge. Such a part is kept when it reaches
    the photo's edge and is substantial both on the floor (``FLOOR.segment.min_part_m2``
    or more within ``FLOOR.segment.max_floor_distance_m``) and in the photo
    (``FLOOR.segment.min_part_share`` of the main region's pixels or more: a far sliver,
    such as a strip of skirting board the trim cut loose, spans many square meters in a
    few pixels), and, when a model's probabilities are
    given, the model calls it floor on average: GrabCut's leaks into the foot of a near
    wall or a carton's side also reach the photo's edge.

    Parameters
    ----------
    mask : (rows, cols) bool or uint8
    calibration : Calibration or None
        At the mask's size (:meth:`Calibration.scaled`). Without it only the main region
        is the floor.
    probability : (rows, cols) float or None
        The model's floor probability at the mask's size.
    distance_m : (rows, cols) float or None
        :func:`floor_distance_m` of the mask's size, when the caller has it already.
    reach_edge : bool
        Keep only parts that reach the photo's edge (default). False keeps substantial
        parts anywhere: for a mask already cleaned up, where a part cut off inside the
        photo is floor someone kept on purpose (a click behind a carton, a painted mask).

    Returns
    -------
    labels : (rows, cols) int32
        8-connected regions, 0 = not floor.
    main : int
        The region under the board, else the largest; 0 when the mask is empty.
    parts : list of int
        The other regions kept, largest first.
    """
    n, labels, stats, _ = cv2.connectedComponentsWithStats(np.asarray(mask, np.uint8), connectivity=8)
    if n <= 1:
        return labels, 0, []
    main = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if calibration is None:
        return labels, main, []
    x, y = calibration.pixels_from_floor(np.zeros((1, 2)))[0].round().astype(int)
    if 0 <= y < labels.shape[0] and 0 <= x < labels.shape[1] and labels[y, x] > 0:
        main = int(labels[y, x])
    if n == 2:
        return labels, main, []
    keep = _substantial(labels, stats[:, cv2.CC_STAT_AREA], stats[main, cv2.CC_STAT_AREA], calibration, distance_m)
    if reach_edge:
        edge = np.zeros(n, bool)
        edge[border_pixels(labels)] = True
        keep &= edge
    if probability is not None:
        count = np.maximum(stats[:, cv2.CC_STAT_AREA], 1)
        keep &= np.bincount(labels.ravel(), np.asarray(probability, np.float64).ravel(), minlength=n) / count >= 0.5
    keep[[0, main]] = False
    parts = np.flatnonzero(keep)
    return labels, main, [int(k) for k in parts[np.argsort(-stats[parts, cv2.CC_STAT_AREA])]]


def _substantial(labels: np.ndarray, pixels: np.ndarray, reference_px: int, calibration,
                 distance_m: np.ndarray | None = None) -> np.ndarray:
    """(n,) bool: which of the regions ``labels`` numbers (``pixels`` (n,) each) are
    substantial, on the floor (``FLOOR.segment.min_part_m2``) and in the photo
    (``FLOOR.segment.min_part_share`` of ``reference_px``); ``calibration`` at the labels' size."""
    footprint = _believed_footprint_m2(labels.shape, calibration, distance_m).ravel()
    area = np.bincount(labels.ravel(), footprint, minlength=len(pixels))
    return (area >= FLOOR.segment.min_part_m2) & (pixels >= FLOOR.segment.min_part_share * reference_px)


# ----------------------------------------------------------------------------- segmentation

@dataclass(frozen=True)
class Segmentation:
    """A floor mask and how it was found.

    Attributes
    ----------
    mask : (rows, cols) bool
        True on the floor (the board counts as floor), at the photo's size.
    probability : (r, c) float32 or None
        The model's floor probability at the working size (long side
        ``FLOOR.segment.grabcut_long_px``), when a model ran.
    method : str
        ``"onnx+grabcut"``, ``"onnx"`` or ``"grabcut"``.
    warnings : tuple of str
    skirting_m : float or None
        Height of the skirting board trimmed from the mask's top edge
        (:func:`augment.floor.skirting.trim_skirting`), when one was.
    disputed : (r, c) bool or None
        Where the mask and the model disagree, at the probability's size
        (:func:`disputed_floor`), when a model ran and the photo is calibrated.
    disputed_m2, disputed_share : float or None
        Its floor area, and its share of the mask's floor area.
    clicks : (n, 3) float
        The user's corrections it was made with (x, y px, 1 floor or 0 not floor), in
        order; none, (0, 3), by default.
    doubt_px : (x, y) int or None
        When the floor is :attr:`uncertain`: the middle of the disputed patch with the
        most floor area, in photo pixels, where a look (and maybe a click) is best spent.
        Otherwise, when the skirting trim may have left a board
        (:func:`augment.floor.skirting.trim_skirting`): a point on that board, where a "not
        floor" click trims it.
    """

    mask: np.ndarray
    probability: np.ndarray | None
    method: str
    warnings: tuple[str, ...] = field(default=())
    skirting_m: float | None = None
    disputed: np.ndarray | None = None
    disputed_m2: float | None = None
    disputed_share: float | None = None
    clicks: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    doubt_px: tuple[int, int] | None = None

    def to_json(self) -> dict:
        """How the floor was found, as every report gives it."""
        return {"method": self.method, "floor_fraction": float(self.mask.mean()), "skirting_m": self.skirting_m,
                "disputed_m2": self.disputed_m2, "disputed_share": self.disputed_share,
                "clicks": self.clicks_json(), "doubt": self.doubt_json()}

    def clicks_json(self) -> list[dict]:
        """The clicks as the reports list them."""
        return [{"x_px": float(x), "y_px": float(y), "floor": bool(f)} for x, y, f in self.clicks]

    @property
    def floor_clicks_px(self) -> np.ndarray:
        """(k, 2) float: the clicks that said floor, (x, y) px, for
        :func:`augment.floor.polygon.floor_polygon`'s ``keep_px``."""
        return self.clicks[self.clicks[:, 2] > 0, :2]

    @property
    def uncertain(self) -> bool:
        """Whether the disputed share is large enough to warn of (``FLOOR.segment.disputed_share_warn``)."""
        return self.disputed_share is not None and self.disputed_share > FLOOR.segment.disputed_share_warn

    def doubt_json(self) -> dict | None:
        """:attr:`doubt_px` as the reports give it, with what the mask says there."""
        if self.doubt_px is None:
            return None
        x, y = self.doubt_px
        return {"x_px": x, "y_px": y, "floor": bool(self.mask[y, x])}

    @property
    def doubted(self) -> np.ndarray | None:
        """The disputed region when the floor is uncertain (what the floor overlay hatches),
        else None."""
        return self.disputed if self.uncertain else None


def _grabcut(image_small, trimap, iterations):
    mask = trimap.copy()
    if not (np.any((mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD))
            and np.any((mask == cv2.GC_BGD) | (mask == cv2.GC_PR_BGD))):
        return (mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)
    bgd, fgd = np.zeros((1, 65), np.float64), np.zeros((1, 65), np.float64)
    bgr = np.ascontiguousarray(image_small[..., ::-1])
    # GrabCut seeds its colour clustering from OpenCV's global generator: seed it, so one
    # photo gives one mask on every call.
    cv2.setRNGSeed(0)
    cv2.grabCut(bgr, mask, None, bgd, fgd, iterations, cv2.GC_INIT_WITH_MASK)
    return (mask == cv2.GC_FGD) | (mask == cv2.GC_PR_FGD)


def _seed_geometry(trimap, shape_small, scale, calibration):
    """Pin what the calibration knows: around the board is floor, above the horizon is not."""
    if calibration is None:
        return
    trimap[~below_horizon(shape_small, calibration.scaled(scale).horizon, 0.0)] = cv2.GC_BGD
    board = (board_polygon_px(calibration, grow=FLOOR.segment.board_margin) * scale).round().astype(np.int32)
    cv2.fillPoly(trimap, [board], int(cv2.GC_FGD))


def _hide_board(small, calibration, scale):
    """The board's black and white squares would teach GrabCut's floor colour model that
    black and white are floor; paint the floor's colours over it first."""
    if calibration is None:
        return small
    mask = np.zeros(small.shape[:2], np.uint8)
    board = (board_polygon_px(calibration, grow=1.1) * scale).round().astype(np.int32)
    cv2.fillPoly(mask, [board], 255)
    if not mask.any():
        return small
    return cv2.inpaint(small, mask, 3, cv2.INPAINT_TELEA)


# Corrections per photo: more is a job for a floor mask (each click runs a region fill).
MAX_CLICKS = 100


def _check_clicks(clicks, shape: tuple[int, int]) -> np.ndarray:
    """Clicks as an (n, 3) float array of x, y photo pixels and 1 (floor) or 0, each
    inside the photo."""
    if clicks is None or np.size(clicks) == 0:
        return np.zeros((0, 3))
    arr = np.asarray(clicks, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise SegmentationError(f"clicks of shape {arr.shape}: give rows of x, y, and 1 for floor or 0 for "
                                "not floor")
    if len(arr) > MAX_CLICKS:
        raise SegmentationError(f"{len(arr)} clicks: at most {MAX_CLICKS}; for larger corrections give a floor mask")
    rows, cols = shape
    for x, y, floor in arr:
        name = "floor at" if floor else "not floor at"
        if not (np.isfinite(x) and np.isfinite(y) and 0 <= x < cols and 0 <= y < rows):
            raise SegmentationError(f"{name} {x:g},{y:g}: outside the photo ({cols} x {rows} px); give "
                                    "x,y in the photo's pixels, 0,0 at its top left, as the floor overlay shows")
    return arr


def _click_region(lab: np.ndarray, edges: np.ndarray, col: int, row: int,
                  floor_m: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """What a click on the working pixel ``(col, row)`` says: the region of the clicked colour
    (``lab``, the working image blurred a little, in Lab) reached from it without crossing
    ``edges`` (a magic wand) and within reach of it; and the wider reach
    ``FLOOR.segment.click_reach`` within which the model is not sure. ``floor_m`` (rows,
    cols, 2), the floor point of each pixel (NaN above the horizon), measures the reach
    on the floor when the click is below the horizon."""
    rows, cols = lab.shape[:2]
    # Edges stop the fill where a wall of the floor's colour meets it; the click itself
    # may sit on one (a plank joint), so its neighbourhood is cleared.
    edges = edges.copy()
    edges[max(0, row - 2):row + 3, max(0, col - 2):col + 3] = 0

    def disc(share):
        out = np.zeros((rows, cols), np.uint8)
        cv2.circle(out, (col, row), max(2, round(share * max(rows, cols))), 1, -1)
        return out > 0

    # Walls of the floor's colour often meet it without an edge, and a click on a thin
    # strip of floor lands on that line: the reach keeps such a leak small. Measured on
    # the floor it is, far away, a wide, flat ellipse: along a far wall rather than up it.
    if floor_m is not None and not np.isnan(floor_m[row, col, 0]):
        with np.errstate(invalid="ignore"):
            from_click_m = np.hypot(*(floor_m - floor_m[row, col]).transpose(2, 0, 1))
            on_floor = from_click_m < FLOOR.segment.click_region_reach_m
        near = disc(FLOOR.segment.click_region_max_reach) & on_floor
    else:
        near = disc(FLOOR.segment.click_region_reach)
    fill = np.ones((rows + 2, cols + 2), np.uint8)
    fill[1:-1, 1:-1] = (edges > 0) | ~near
    tol = (FLOOR.segment.click_tolerance,) * 3
    cv2.floodFill(lab, fill, (col, row), 0, tol, tol,
                  4 | cv2.FLOODFILL_FIXED_RANGE | cv2.FLOODFILL_MASK_ONLY | (2 << 8))
    return fill[1:-1, 1:-1] == 2, disc(FLOOR.segment.click_reach)


def _click_regions(small, scale, calibration, clicks):
    """What the user's clicks say, at the working size: the regions marked floor and not
    floor (a later click overriding an earlier one where they overlap), and where the
    model is not to be taken as sure: within each click's reach. Clicks the geometry
    contradicts are refused: floor above the horizon, the board not floor."""
    shape = small.shape[:2]
    floor = np.zeros(shape, bool)
    other = np.zeros(shape, bool)
    near = np.zeros(shape, bool)
    if not len(clicks):
        return floor, other, near
    below = board = floor_m = None
    if calibration is not None:
        working = calibration.scaled(scale)
        below = below_horizon(shape, working.horizon, 0.0)
        board = np.zeros(shape, np.uint8)
        cv2.fillPoly(board, [(board_polygon_px(calibration) * scale).round().astype(np.int32)], 1)
        board = board > 0
        ys, xs = np.nonzero(below)
        floor_m = np.full((*shape, 2), np.nan)
        floor_m[ys, xs] = working.floor_from_pixels(np.column_stack([xs + 0.5, ys + 0.5]))
    # The colours and edges the clicks' regions are found in, once for all of them.
    lab = cv2.cvtColor(cv2.medianBlur(small, 5), cv2.COLOR_RGB2LAB)
    grey = cv2.cvtColor(cv2.GaussianBlur(small, (3, 3), 0), cv2.COLOR_RGB2GRAY)
    edges = cv2.dilate(cv2.Canny(grey, *FLOOR.segment.click_canny), np.ones((2, 2), np.uint8))
    for x, y, is_floor, x_given, y_given in clicks:
        # One working pixel for the click, both for its refusal and its region.
        col, row = min(shape[1] - 1, round(x * scale)), min(shape[0] - 1, round(y * scale))
        if is_floor and below is not None and not below[row, col]:
            raise SegmentationError(f"floor at {x_given:g},{y_given:g}: above the horizon the board gives, where no "
                                    "floor can be; click floor below the far walls' feet")
        if not is_floor and board is not None and board[row, col]:
            raise SegmentationError(f"not floor at {x_given:g},{y_given:g}: on the board, which lies on the floor; "
                                    "click the thing wrongly taken for floor")
        region, reach = _click_region(lab, edges, col, row, floor_m)
        near |= reach
        if is_floor:
            floor |= region
            other &= ~region
        else:
            other |= region
            floor &= ~region
    # The geometry outranks a click's region: the board is floor, above the horizon is not.
    if calibration is not None:
        floor &= below
        other &= ~board
        near &= below & ~board
    return floor, other, near


def _apply_clicks(trimap, floor, other, near):
    """Pin the clicked regions in GrabCut's start; near a click the model's sure labels
    become probable, so GrabCut can carry the clicked colour past them."""
    trimap[near & (trimap == cv2.GC_BGD)] = cv2.GC_PR_BGD
    trimap[near & (trimap == cv2.GC_FGD)] = cv2.GC_PR_FGD
    trimap[floor] = cv2.GC_FGD
    trimap[other] = cv2.GC_BGD


def segment_floor(image: np.ndarray, model: FloorModel | None = None, calibration=None,
                  method: str = "onnx", refine: bool = True, skirting: bool = True,
                  clicks=None) -> Segmentation:
    """Find the floor in a photo.

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        RGB photo (grey (rows, cols) is accepted). Not modified.
    model : FloorModel, optional
        Needed for ``method="onnx"``.
    calibration : Calibration, optional
        From :func:`augment.camera.calibrate.calibrate_photo`; its board and horizon seed GrabCut,
        and its horizon says which way is up: the model and the skirting trim see a room
        that the photo shows turned (``Calibration.upright_turns``) turned upright.
    method : {"onnx", "grabcut"}
        ``"grabcut"`` runs GrabCut alone, seeded from the calibration's geometry.
    refine : bool
        Refine the model's mask with GrabCut (``"onnx"`` only).
    skirting : bool
        Trim the skirting boards from the refined mask, or where it shows none, move its
        edge up to the floor line where it stops short (needs ``calibration``).
    clicks : (n, 3) array_like of float, optional
        The user's corrections, in order: photo pixels ``x, y`` and 1 where the floor
        is, 0 where something was wrongly taken for floor. Each marks the region of its
        colour around it (reached without crossing an edge) for GrabCut, a later click
        winning where two regions overlap, and lets GrabCut overrule the model within
        ``FLOOR.segment.click_reach`` of it; a region clicked as floor is kept even when
        cut off from the rest, and within a floor click's reach the skirting trim cuts
        nothing; a "not floor" click on the strip at a wall's foot makes that wall's strip
        a skirting board for the trim, and marks no colour region (which of them are, a
        first pass without the "not floor" clicks tells:
        :func:`augment.floor.skirting.board_clicks`).

    Returns
    -------
    Segmentation

    Raises
    ------
    SegmentationError
        Bad image, or a click outside the photo, floor above the horizon, or the board
        marked not floor.
    """
    image = check_image(image)
    if method not in ("onnx", "grabcut"):
        raise SegmentationError(f"method {method!r}: use onnx or grabcut")
    if method == "onnx" and model is None:
        raise SegmentationError("method onnx needs a model; give --model PATH or use --method grabcut")
    if method == "grabcut" and calibration is None:
        raise SegmentationError("method grabcut needs the board's calibration (the board seeds the floor, "
                                "the horizon bounds it); photograph the board on the floor, or use a model")
    rows, cols = image.shape[:2]
    clicks = _check_clicks(clicks, (rows, cols))
    up = Upright.of(calibration, (cols, rows))
    # Each click as the upright view shows it, and as the user gave it (for messages).
    found = _find(up.image(image), model, up.calibration, method, refine, skirting,
                  np.column_stack([up.points(clicks), clicks[:, :2]]))
    mask = up.back(found.mask)
    disputed = up.back(found.disputed)
    board_doubt = up.point_back(found.board_doubt_px)
    warnings = () if found.any_floor else ("no floor found",)
    seg = Segmentation(mask, up.back(found.probability), found.method, warnings, found.skirting_m, disputed,
                       found.disputed_m2, found.disputed_share, clicks)
    if seg.uncertain:
        x, y = up.point_back(_largest_patch_px(found.disputed, up.calibration, found.mask.shape))
        # Where the model calls much floor that the mask leaves out, the patches in doubt
        # can outgrow the floor found.
        share = (f"{100 * seg.disputed_share:.0f} % of the floor found" if seg.disputed_share <= 1 else
                 f"{seg.disputed_share:.1f} times the floor found")
        seg = replace(seg, doubt_px=(x, y), warnings=seg.warnings + (
            f"the floor found is uncertain: the floor model and GrabCut disagree on {seg.disputed_m2:.1f} m\u00b2 "
            f"({share}, hatched magenta in the floor overlay); the largest patch in "
            f"doubt is around {x},{y} (ringed there), now {'floor' if mask[y, x] else 'not floor'}: check it, and "
            "correct the floor where it is wrong",))
    elif board_doubt is not None and mask[board_doubt[1], board_doubt[0]]:
        x, y = board_doubt
        seg = replace(seg, doubt_px=(x, y), warnings=seg.warnings + (
            f"a skirting board may be left in the floor along the wall around {x},{y} (ringed in the floor "
            "overlay; most often a board of the floor's own colour): if the photo shows one there, mark it not "
            "floor there to trim it along that wall",))
    return seg


class _Found(NamedTuple):
    """What :func:`_find` found, in the upright view."""

    mask: np.ndarray
    probability: np.ndarray | None
    method: str
    skirting_m: float | None
    disputed: np.ndarray | None
    disputed_m2: float | None
    disputed_share: float | None
    board_doubt_px: tuple[int, int] | None
    any_floor: bool


def _find(image, model, calibration, method, refine, skirting, clicks) -> _Found:
    """:func:`segment_floor` on the photo turned upright (:mod:`augment.floor.upright`).
    ``clicks`` (n, 5): x, y in this view, 1 floor or 0 not, and x, y as the user gave them."""
    rows, cols = image.shape[:2]
    trims = skirting and calibration is not None and (method == "grabcut" or refine)
    scale = working_scale((rows, cols), FLOOR.segment.grabcut_long_px)
    size_small = (max(1, round(cols * scale)), max(1, round(rows * scale)))
    work = shrink_to(image, FLOOR.model.preshrink_long_px)
    small = _hide_board(shrink_area(work, size_small), calibration, scale)
    probability = model.floor_probability(work, size_small) if method == "onnx" else None

    def found(wand):
        return _refined(small, scale, probability, calibration, method, refine, wand)

    wand, board_marks = clicks, clicks[:0]
    floor_clicks = clicks[clicks[:, 2] > 0]
    first = None
    if trims and len(floor_clicks) < len(clicks):
        # A "not floor" click on the strip at a wall's foot marks a skirting board, which
        # the trim cuts along the wall. Its colour region is left out: on a board of the
        # floor's colour the board's lower edge is too faint to stop it, and it would carve
        # a patch out of the floor below. Which clicks those are, the floor found without
        # the "not floor" clicks tells.
        first = found(floor_clicks)
        other = np.flatnonzero(clicks[:, 2] == 0)
        on_board = np.zeros(len(clicks), bool)
        on_board[other] = board_clicks(image, _full_size(first[0], (cols, rows)), calibration, clicks[other, :2])
        wand, board_marks = clicks[~on_board], clicks[on_board]
    # When every "not floor" click is on a board, the floor clicks alone mark regions,
    # and the first pass is the floor.
    mask_small, name, clicked_floor, clicked_other, clicked_near, vetoed = (
        first if first is not None and len(wand) == len(floor_clicks) else found(wand))
    mask = _full_size(mask_small, (cols, rows))
    skirting_m = board_doubt = None
    board_cut = np.zeros((rows, cols), bool)
    vetoed = _full_size(vetoed, (cols, rows)) if vetoed.any() else None
    if trims and mask.any():
        # The refined mask's top edge sits on the skirting boards; the floor ends below.
        # Where it holds none, its edge may instead stop short of the floor line.
        trimmed, skirting_m, board_doubt = trim_skirting(image, mask, calibration,
                                                         board_at=clicks[clicks[:, 2] == 0, :3], extend=True)
        # A strip the trim took for a board is floor within reach of a floor click there:
        # the user's word is the last.
        reach = np.zeros((rows, cols), np.uint8)
        for x, y in clicks[clicks[:, 2] > 0, :2]:
            cv2.circle(reach, (round(x), round(y)), round(FLOOR.segment.click_reach * max(rows, cols)), 1, -1)
        board_cut = _cut_clicked(mask & ~trimmed, board_marks)
        # A far strip dropped whole (a second floor, a band of sun) goes on to the wall's foot,
        # and a thing against the wall stops there: what the model vetoes is no edge of either.
        mask = reach_wall_foot(image, trimmed if vetoed is None else trimmed & ~vetoed, calibration) | (
            mask & (reach > 0))
        if board_doubt is not None and reach[board_doubt[1], board_doubt[0]]:
            board_doubt = None
    # After the trim: taken out before, they would leave a skirting board's strip in
    # pieces, which the trim no longer knows for a board.
    if vetoed is not None:
        mask &= ~vetoed
    if len(wand):
        other = cv2.resize(clicked_other.astype(np.float32), (cols, rows), interpolation=cv2.INTER_LINEAR) > 0.5
        mask &= ~other
    disputed = (None, None, None)
    if probability is not None and calibration is not None and mask.any():
        # A board the user clicked was cut where the model calls it floor: settled too.
        settled = clicked_near | (shrink_area(board_cut.view(np.uint8), size_small) > 0 if board_cut.any()
                                  else False)
        disputed = disputed_floor(mask, probability, calibration, settled=settled)
    return _Found(mask, probability, name, skirting_m, *disputed, board_doubt, bool(mask_small.any()))


def _full_size(mask_small: np.ndarray, size_px: tuple[int, int]) -> np.ndarray:
    """The working size's mask at ``size_px = (width, height)``. Linear interpolation of the
    0/1 mask, cut at one half: edges come out straight rather than staircased at the
    working pixel size."""
    return cv2.resize(np.asarray(mask_small, bool).view(np.uint8) * np.uint8(255), size_px,
                      interpolation=cv2.INTER_LINEAR) > 127


def _refined(small, scale, probability, calibration, method, refine, clicks):
    """The floor at the working size for these clicks: the model's mask refined by
    GrabCut (or taken as it is, or GrabCut alone), cleaned; with the clicks' regions and
    reach (:func:`_click_regions`), the method's name and what the model vetoes of
    GrabCut's additions (:func:`_vetoed`, taken out after the skirting trim)."""
    shape_small = small.shape[:2]
    clicked_floor, clicked_other, clicked_near = _click_regions(small, scale, calibration, clicks)
    vetoed = np.zeros(shape_small, bool)
    if method == "onnx" and refine:
        trimap = np.where(probability > 0.5, cv2.GC_PR_FGD, cv2.GC_PR_BGD).astype(np.uint8)
        # Only well inside a confident region is the model taken as given: its edges
        # are a few input pixels soft, and they are what GrabCut is for.
        band = 5
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * band + 1, 2 * band + 1))
        trimap[cv2.erode((probability > FLOOR.segment.sure_floor).astype(np.uint8), kernel) > 0] = cv2.GC_FGD
        trimap[cv2.erode((probability < FLOOR.segment.sure_other).astype(np.uint8), kernel) > 0] = cv2.GC_BGD
        _seed_geometry(trimap, shape_small, scale, calibration)
        _apply_clicks(trimap, clicked_floor, clicked_other, clicked_near)
        small_mask = _grabcut(small, trimap, FLOOR.segment.grabcut_iterations)
        small_mask = _restore_dropped(small_mask, probability, calibration, scale, clicked_other | clicked_near)
        # The board's floor is pinned: what stands on it is the erasure's to find.
        vetoed = _vetoed(small_mask, probability, clicked_floor | clicked_near | (trimap == cv2.GC_FGD))
        name = "onnx+grabcut"
    elif method == "onnx":
        small_mask = probability > 0.5
        if calibration is not None:
            trimap = np.where(small_mask, cv2.GC_FGD, cv2.GC_BGD).astype(np.uint8)
            _seed_geometry(trimap, shape_small, scale, calibration)
            small_mask = trimap == cv2.GC_FGD
        small_mask = (small_mask | clicked_floor) & ~clicked_other
        name = "onnx"
    else:
        trimap = _geometry_trimap(shape_small, scale, calibration)
        _apply_clicks(trimap, clicked_floor, clicked_other, clicked_near)
        small_mask = _grabcut(small, trimap, 5)
        name = "grabcut"
    mask_small = _clean(small_mask, calibration, scale, probability, clicked_floor) & ~clicked_other
    return mask_small, name, clicked_floor, clicked_other, clicked_near, vetoed


def _restore_dropped(mask: np.ndarray, probability: np.ndarray, calibration, scale: float,
                     clicked: np.ndarray) -> np.ndarray:
    """Give back the regions the model calls floor that GrabCut dropped whole.

    GrabCut's colour model of the floor is learnt from the floor it is sure of, around
    the board: a second floor material past a threshold (tiles beyond carpet, planks in
    an alcove) fits it badly and is dropped, though the model calls it floor. GrabCut is
    for the model's soft edges, a few working pixels; a region of
    ``FLOOR.segment.restore_min_m2`` or more on the floor and not a far speck in the photo
    (``FLOOR.segment.min_part_share`` of the mask's pixels: a carton's top far off spans
    that much floor in a few hundred pixels) unless the floor kept goes on right below it
    (a far strip along a wall, :func:`_floor_below_share`), thicker than an edge
    (``FLOOR.segment.restore_edge_px``), below the horizon and touching the floor kept,
    is the model's call to make. Where the user clicked (``clicked``: a "not floor" region
    and every click's reach) GrabCut, told by the click, has the last word."""
    if calibration is None:
        return mask
    small_cal = calibration.scaled(scale)
    dropped = (probability > 0.5) & ~mask & ~clicked
    dropped &= below_horizon(mask.shape, small_cal.horizon, 1.0)
    n, labels, region = _edge_regions(dropped)
    if n <= 1:
        return mask
    footprint = _believed_footprint_m2(mask.shape, small_cal)
    area = np.bincount(region.ravel(), footprint.ravel(), minlength=n)
    near = cv2.dilate(mask.astype(np.uint8), _edge_kernel(), iterations=2) > 0
    touching = np.zeros(n, bool)
    touching[np.unique(labels[near & (labels > 0)])] = True
    pixels = np.bincount(region.ravel(), minlength=n)
    keep = touching & (area >= FLOOR.segment.restore_min_m2)
    keep &= (pixels >= FLOOR.segment.min_part_share * np.count_nonzero(mask)) | (
        _floor_below_share(region, mask, n, small_cal) >= FLOOR.segment.restore_below_share)
    keep[0] = False
    if not keep.any():
        return mask
    return mask | np.isin(region, np.flatnonzero(keep))


def _floor_below_share(region: np.ndarray, mask: np.ndarray, n: int, calibration) -> np.ndarray:
    """(n,) share of each region's lower edge (labels ``region`` (rows, cols), 1..n-1: its
    pixels whose neighbour below is not in it) with floor of ``mask`` below it, the photo
    upright, no farther on the floor than ``FLOOR.segment.restore_gap_m`` (``calibration``
    at the mask's size). A strip of floor GrabCut cut off the far edge goes on into the
    floor toward the camera, past a threshold bar at most; a carton's top sits on the
    carton's face, which spans more floor than that as seen from the camera."""
    below = np.zeros_like(region)
    below[:-1] = region[1:]
    ys, xs = np.nonzero((region > 0) & (below != region))
    hit = np.full(len(ys), -1)
    for step in range(1, FLOOR.segment.restore_gap_px + 1):
        look = (hit < 0) & (ys + step < mask.shape[0])
        look[look] = mask[ys[look] + step, xs[look]]
        hit[look] = ys[look] + step
    near = hit >= 0
    if near.any():
        ends = [calibration.floor_from_pixels(np.column_stack([xs[near], y[near]]).astype(np.float64))
                for y in (ys, hit)]
        near[near] = np.hypot(*(ends[1] - ends[0]).T) <= FLOOR.segment.restore_gap_m
    labels = region[ys, xs]
    return np.bincount(labels[near], minlength=n) / np.maximum(np.bincount(labels, minlength=n), 1)


def _edge_kernel() -> np.ndarray:
    """The disc that peels GrabCut's edge corrections (``FLOOR.segment.restore_edge_px``
    either side) off a region."""
    edge = FLOOR.segment.restore_edge_px
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * edge + 1, 2 * edge + 1))


def _edge_regions(region: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """``region`` (rows, cols) bool split into its parts thicker than
    ``FLOOR.segment.restore_edge_px`` either side: (count + 1, the cores' labels, the
    labels grown back over each part's full extent, whose area counts: a far strip of
    tiles loses a third of itself to the erosion), 0 for the thin edge strips GrabCut is
    for and the rest."""
    kernel = _edge_kernel()
    n, labels = cv2.connectedComponents(cv2.erode(region.astype(np.uint8), kernel), connectivity=8)
    return n, labels, np.where(region, cv2.dilate(labels.astype(np.float32), kernel).astype(np.int32), 0)


def _vetoed(mask: np.ndarray, probability: np.ndarray, settled: np.ndarray) -> np.ndarray:
    """The floor GrabCut added where the model is sure there is none: (rows, cols) bool.

    A carton's face or a wall's foot of the floor's colour fits GrabCut's colour model
    of the floor, and it takes them in whole, though the model gives them a few percent.
    Floor in shade that the model doubts gets 0.1-0.4 from it; what GrabCut adds at the
    model's soft edge is thinner than an edge (``FLOOR.segment.restore_edge_px``). A
    region thicker than that is the model's call where it gives below ``FLOOR.segment.veto_p``
    (pixel by pixel: a region often holds both, a carton's face and the floor in its
    shadow). Where the floor is settled (``settled``: a floor click's region and reach,
    where GrabCut was told; the board and its margin, floor for sure) it stays."""
    _, _, region = _edge_regions(mask & (probability <= 0.5) & ~settled)
    return (region > 0) & (probability < FLOOR.segment.veto_p)


def _cut_clicked(cut: np.ndarray, marks: np.ndarray) -> np.ndarray:
    """The parts of ``cut`` (rows, cols) bool, what the skirting trim took, that hold a
    board click of ``marks`` (n, 2+): the nearest cut pixels at or above it in its column,
    as the trim cut down from the mask's top edge (the room upright)."""
    out = np.zeros(cut.shape, bool)
    if not len(marks) or not cut.any():
        return out
    _, labels = cv2.connectedComponents(cut.astype(np.uint8), connectivity=8)
    for x, y in np.asarray(marks, np.float64)[:, :2]:
        column = labels[:min(cut.shape[0] - 1, round(y)) + 1, min(cut.shape[1] - 1, round(x))]
        hit = column[column > 0]
        if len(hit):
            out |= labels == hit[-1]
    return out


def _largest_patch_px(region: np.ndarray, calibration, shape: tuple[int, int]) -> tuple[int, int]:
    """The middle (farthest from its edge) of ``region``'s patch with the most floor area,
    in photo pixels (``shape`` is the photo's (rows, cols))."""
    r, c = region.shape
    n, labels = cv2.connectedComponents(region.astype(np.uint8), connectivity=8)
    footprint = _believed_footprint_m2((r, c), calibration.scaled(c / shape[1]))
    area = np.bincount(labels.ravel(), footprint.ravel(), minlength=n)
    area[0] = -1
    x, y = patch_middle(labels == int(np.argmax(area)))
    return (min(shape[1] - 1, int((x + 0.5) * shape[1] / c)), min(shape[0] - 1, int((y + 0.5) * shape[0] / r)))


def patch_middle(patch: np.ndarray) -> tuple[int, int]:
    """``(x, y)`` of the pixel of ``patch`` ((rows, cols) bool) farthest from its edge.

    The photo's edge counts as the patch's, so a patch cut off there has its middle
    inside it. Distances are OpenCV's 5 x 5 approximation of Euclidean, whose deepest
    pixel is within a few percent of the true deepest's depth (closer than the 3 x 3
    mask's)."""
    depth = cv2.distanceTransform(np.pad(patch, 1).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_5)[1:-1, 1:-1]
    y, x = np.unravel_index(int(np.argmax(depth)), depth.shape)
    return int(x), int(y)


def disputed_floor(mask: np.ndarray, probability: np.ndarray, calibration,
                   settled: np.ndarray | None = None) -> tuple[np.ndarray, float, float]:
    """Where the final mask and the model (its probability cut at one half) disagree:
    what GrabCut and the skirting trim added or took away, and its floor area.

    It tells floors likely to be off: a disputed share above
    ``FLOOR.segment.disputed_share_warn`` flags some of the polygons far from the true
    area, and few of the rest (docs/floor.md).

    Parameters
    ----------
    mask : (rows, cols) bool
        The floor mask at the photo's size.
    probability : (r, c) float
        The model's floor probability at a smaller working size.
    calibration : Calibration
        At the photo's size.
    settled : (r, c) bool, optional
        What the user's clicks decided (at the probability's size): not in dispute.

    Returns
    -------
    region : (r, c) bool
        Where the two disagree, at the probability's size.
    disputed_m2 : float
        Its floor area (m^2, within ``FLOOR.segment.max_floor_distance_m``).
    share : float
        ``disputed_m2`` over the mask's floor area (m^2, same limit).
    """
    r, c = probability.shape
    small = shrink_area(np.asarray(mask, bool).view(np.uint8), (c, r)) > 0  # a mean of 0/1 rounded: over one half
    footprint = _believed_footprint_m2((r, c), calibration.scaled(c / mask.shape[1]))
    region = small != (probability > 0.5)
    if settled is not None:
        region &= ~settled
    disputed_m2 = float(footprint[region].sum())
    floor_m2 = float(footprint[small].sum())
    return region, disputed_m2, disputed_m2 / max(floor_m2, 1e-9)


def read_floor_mask(path, size_px: tuple[int, int], calibration=None) -> Segmentation:
    """A floor mask the user made or corrected, in place of :func:`segment_floor`.

    White (grey level above 127) is floor, as in the mask ``stage segment`` writes; any
    format Stager reads photos in, grey or colour; with an alpha channel, transparent is
    not floor. A mask of another size but the photo's shape (one painted on a smaller
    copy) is scaled to the photo.

    Parameters
    ----------
    path : path-like
        The mask file. Not modified.
    size_px : (width, height)
        The photo's size, upright as Stager reads it.
    calibration : Calibration, optional
        The photo's. When given, the board must lie on the floor of the mask: a mask
        with the board outside is more likely inverted or of another photo than meant.

    Returns
    -------
    Segmentation
        ``method`` ``"user mask"``, no probabilities.

    Raises
    ------
    SegmentationError
        The file is missing or unreadable, its size does not fit the photo, it shows no
        floor, or the board is not on its floor.
    """
    path = Path(path)
    if path_problem(path) is not None and path_problem(path).startswith("does not exist"):
        raise SegmentationError(f"floor mask {path}: no such file; give the mask `stage segment` wrote "
                                "(white = floor), corrected in any image editor")
    data, problem = read_user_file(path)
    if problem is not None:
        raise SegmentationError(f"floor mask {path}: {problem}")
    if (head := header(data)) is not None and (problem := pixels_problem(*head[1])) is not None:
        raise SegmentationError(f"floor mask {path} {problem}")
    lightness = decode_grey(data)
    if lightness is None:
        raise SegmentationError(f"floor mask {path} {decode_problem(data)} (a mask: PNG, white = floor)")
    sample = lightness[::4, ::4]  # plenty to tell a mask from a photo
    grey = float(((sample > 32) & (sample < 223)).mean())
    if grey > FLOOR.segment.max_mask_grey:
        # Thresholded at 127, a photo (the room's own, given by mistake, or one with the
        # floor painted over) would make its bright parts floor.
        raise SegmentationError(f"floor mask {path}: {grey:.0%} of its pixels are neither near black nor near "
                                "white, so it looks like a photo, not a mask; give a black-and-white mask "
                                "(white = floor), e.g. the floor.png of `stage segment` corrected")
    cols, rows = int(size_px[0]), int(size_px[1])
    height, width = lightness.shape
    if (width, height) != (cols, rows):
        if abs((width / height) / (cols / rows) - 1) > FLOOR.segment.mask_aspect_tolerance:
            turned = (" (turned a quarter: save it upright, as the photo shows)"
                      if (width, height) == (rows, cols) else "")
            raise SegmentationError(f"floor mask {path}: size {width} x {height} px does not fit the photo's "
                                    f"{cols} x {rows}{turned}; paint the mask on the photo or a copy scaled "
                                    "evenly, e.g. the floor.png of `stage segment`")
        lightness = cv2.resize(lightness, (cols, rows), interpolation=cv2.INTER_LINEAR)
    mask = lightness > 127
    warnings = ()
    if not mask.any():
        raise SegmentationError(f"floor mask {path}: no floor in it (no pixel lighter than grey 127); "
                                "paint the floor white on black")
    if calibration is not None:
        x, y = calibration.pixels_from_floor(np.zeros((1, 2)))[0]
        col, row = int(round(x)), int(round(y))
        if 0 <= row < rows and 0 <= col < cols and not mask[row, col]:
            raise SegmentationError(f"floor mask {path}: the board's center (pixel {col}, {row}) is not floor "
                                    "in it; white must be floor (is the mask inverted, or of another photo?)")
        # A brush spilling over the top of a far wall leaves a little white above the
        # horizon, left out with a word; a mask white over walls and ceiling (all white, or
        # another photo's) is refused: its floor would run through the walls to the
        # polygon's distance limit.
        below = below_horizon((rows, cols), calibration.horizon, 0.0)
        sky = float((mask & ~below).sum() / mask.sum())
        if sky > FLOOR.segment.max_mask_sky:
            raise SegmentationError(f"floor mask {path}: {sky:.0%} of its white lies above the horizon (the "
                                    "camera's eye level, which the board gives: dashed in the calibration "
                                    "overlay), where no floor can show, so it marks walls or the ceiling as "
                                    "floor; paint only the floor white")
        mask &= below
        if sky > FLOOR.segment.mask_sky_warn:
            warnings = (f"floor mask {path}: {sky:.1%} of its white lies above the horizon, where no floor can "
                        "show (a wall's top, painted over?); left out",)
    return Segmentation(mask, None, "user mask", warnings)


def _geometry_trimap(shape_small, scale, calibration) -> np.ndarray:
    """GrabCut's start without a model: floor no farther from the camera than the board
    is probably floor (people lay the board on open floor, in front of what they shoot),
    floor beyond any room's reach is not, the board is, above the horizon is not. (The
    board's distance as the limit fits the floor better than a larger one, or the board
    alone as the seed.)"""
    distance = floor_distance_m(shape_small, calibration.scaled(scale))
    board_distance_m = float(np.hypot(*np.linalg.inv(calibration.camera_from_floor)[:2, 3]))
    trimap = np.full(shape_small, cv2.GC_PR_BGD, np.uint8)
    trimap[distance < board_distance_m] = cv2.GC_PR_FGD
    trimap[distance > FLOOR.segment.max_floor_distance_m] = cv2.GC_BGD
    _seed_geometry(trimap, shape_small, scale, calibration)
    return trimap


def _bridged(mask: np.ndarray, calibration) -> np.ndarray:
    """``mask`` (rows, cols) uint8 with the substantial floor regions either side of a line
    thinner than ``FLOOR.segment.bridge_px`` joined, the line with them: two floors meeting
    at a threshold bar that GrabCut left out are one floor. Slivers (a line along a
    skirting board's top) are not joined: the clean-up judges them on their own."""
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    if n <= 2:
        return mask
    pixels = stats[:, cv2.CC_STAT_AREA]
    big = _substantial(labels, pixels, pixels[1:].max(), calibration)
    big[0] = False
    if big.sum() < 2:
        return mask
    width = FLOOR.segment.bridge_px
    regions = np.isin(labels, np.flatnonzero(big)).astype(np.uint8)
    return mask | cv2.morphologyEx(regions, cv2.MORPH_CLOSE,
                                   cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (width, width)))


def _clean(mask: np.ndarray, calibration, scale, probability=None, clicked=None) -> np.ndarray:
    """Keep the floor's region under the board (else the largest) with the floors it meets
    across a thin line (:func:`_bridged`), the parts cut off
    from it at the photo's edge (:func:`floor_parts`) and the parts the user clicked as
    floor (``clicked``), close pinholes, drop specks and thin spurs far from the model's
    floor (``FLOOR.segment.spur_width_px``, ``FLOOR.segment.spur_reach_px``; floor the user
    clicked counts as the model's)."""
    mask = mask.astype(np.uint8)
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    if probability is not None:
        # GrabCut follows colour: a line of the floor's colour that touches the floor (a
        # window's shadow on a wall, the edge of a door) is taken in with it, a thin spur
        # reaching far from anything the model calls floor. Floor GrabCut rightly finds
        # past the model is near it (the foot of a wall) or a region, not a line.
        known = probability > 0.5 if clicked is None else (probability > 0.5) | clicked
        far = cv2.distanceTransform((~known).astype(np.uint8), cv2.DIST_L2, 5) > FLOOR.segment.spur_reach_px
        width = FLOOR.segment.spur_width_px
        disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (width, width))
        mask[far & (cv2.morphologyEx(mask, cv2.MORPH_OPEN, disc) == 0)] = 0
    if calibration is not None:
        mask = _bridged(mask, calibration.scaled(scale))
    labels, main, parts = floor_parts(mask, None if calibration is None else calibration.scaled(scale),
                                      probability)
    if probability is None:
        # GrabCut alone has only colour to go on: a part it cut off is not trusted.
        parts = []
    if clicked is not None:
        parts = [*parts, *np.unique(labels[clicked & (labels > 0)]).tolist()]
    if main == 0:
        return np.zeros(mask.shape, bool)
    out = np.isin(labels, [main, *parts])
    # Pinholes (texture, a knot in the wood) are not things standing on the floor.
    holes = ~out
    n, hl, hs, _ = cv2.connectedComponentsWithStats(holes.astype(np.uint8), connectivity=4)
    tiny = max(4, int(1e-4 * mask.size))
    small_holes = np.flatnonzero(hs[:, cv2.CC_STAT_AREA] < tiny)
    out |= np.isin(hl, small_holes[small_holes > 0])
    return out
