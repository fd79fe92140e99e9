"""The board erased from the photo: the floor it lies on filled in, for the staged images.

A staged photo should show the room, not the printed checkerboard that measured it. The
sheet is filled on a top-down view of the floor around it (the calibration's floor plane,
looked at square-on), where the floor's texture has one scale and one orientation:

1. **Where.** The sheet the board was printed on (``Board.sheet_mm``), grown side by side
   while the next line beyond it is still the paper's colour (a board printed on larger
   paper than Stager assumes), at most one square; less what stands on it (a carton
   over part of a ChArUco board), found where the photo does not follow the print's
   pattern.
2. **Light.** A shadow's straight edge across the sheet (a window frame's, in the sun) is
   found where the floor on both sides of the sheet steps in brightness along one line;
   it is taken out of the view and put back on the fill, sharp as the photo shows it.
   The floor's slow changes of light and colour (shade, the falloff of a lamp) are filled
   smoothly from the sheet's rim (OpenCV's Telea inpainting, then blurred).
3. **Texture.** What remains of the floor (grain, carpet, blotches, tile joints) is
   copied from the place beside the sheet whose rim matches the sheet's rim best (masked
   template matching, the squared differences relative to the two rims' energy, so that
   a flat place does not win), among places the photo shows about as sharp as the sheet
   (from farther back, the copy is a soft smudge): a tiled or planked floor lines up
   its joints, a carpet keeps its grain. The place is found on a small view, then refined at full size; the
   copy runs on over the rim it was matched on, fading out, so it has no edge. What the
   copy's light still misses of the floor's at the rim (a glossy floor's sheen, a lighter
   plank running on), a few levels at most, is carried smoothly across the sheet.

The view is then mapped back into the photo and blended over the sheet's pixels with a
soft edge. Measured against renders of the same room without the board: see
``benchmarks/erase.py`` and the README.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..floor.segment import below_horizon
from .settings import RENDER


@dataclass(frozen=True)
class ErasedBoard:
    """The photo with the board's sheet filled with floor.

    Attributes
    ----------
    image : (h, w, 3) uint8
        The photo, the sheet's pixels replaced.
    box_px : (4,) int
        ``(x0, y0, x1, y1)``: the part of the photo the fill may touch (end exclusive);
        the photo is unchanged outside it.
    alpha : (y1 - y0, x1 - x0) float32
        In the box, how much of each pixel is the fill (0 off the sheet, 1 on it, soft at
        its edge): ``image = alpha * fill + (1 - alpha) * photo``
        (:meth:`full_alpha` gives it at the photo's size).
    sheet_m : (4, 2) float64
        The sheet as erased, floor meters (the printed sheet grown to the paper found,
        plus the edge margin).
    covered : float
        The share of the sheet that something standing on it covers (0-1): left as it
        is, though its edges over the paper may be painted over.
    source_m : (k, 2) float64
        Where the texture was taken from: per part of the sheet, the offset, floor
        meters, to the floor copied. One part, or where no place beside the whole sheet
        is all floor (near a wall, or the photo's edge), halves and quarters of it; none
        where even those find no place (the fill is smooth there).
    """

    image: np.ndarray
    box_px: tuple
    alpha: np.ndarray
    sheet_m: np.ndarray
    source_m: np.ndarray
    covered: float = 0.0

    @property
    def warning(self) -> str | None:
        """What to tell the user when something stands on much of the board."""
        if self.covered <= RENDER.erase.covered_warn:
            return None
        return (f"something stands on {100 * self.covered:.0f} % of the board: it is kept in the staged photos, "
                "but where it overhangs the paper it may be painted over with floor; --keep-board leaves the "
                "board as it is")

    def full_alpha(self) -> np.ndarray:
        """(h, w) float32: :attr:`alpha` at the photo's size (0 outside the box)."""
        out = np.zeros(self.image.shape[:2], np.float32)
        x0, y0, x1, y1 = self.box_px
        out[y0:y1, x0:x1] = self.alpha
        return out


def erase_board(image: np.ndarray, calibration, floor_mask: np.ndarray | None = None) -> ErasedBoard:
    """The photo with the calibration board's sheet filled with the floor around it.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo the board was found in (RGB), not modified.
    calibration : Calibration
        Of this photo (:func:`augment.camera.calibrate.calibrate_photo`): the board's pose and
        the floor plane.
    floor_mask : (h, w) bool, optional
        The floor found (:func:`augment.floor.segment.segment_floor`): texture is taken from
        floor only, and only floor pixels are replaced (a thing standing on the board
        stays). Without it, every pixel below the horizon counts as floor.

    Returns
    -------
    ErasedBoard

    Raises
    ------
    ValueError
        When ``image`` is not (h, w, 3) uint8 of the calibration's size, or ``floor_mask``
        not (h, w).
    """
    image = np.asarray(image)
    h, w = image.shape[:2]
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise ValueError(f"image must be (h, w, 3) uint8, got shape {image.shape} dtype {image.dtype}")
    if (w, h) != tuple(calibration.size_px):
        raise ValueError(f"image is {w}x{h} but the calibration is of a "
                         f"{calibration.size_px[0]}x{calibration.size_px[1]} photo")
    if floor_mask is not None:
        floor_mask = np.ascontiguousarray(floor_mask, dtype=bool)
        if floor_mask.shape != (h, w):
            raise ValueError(f"floor_mask must be ({h}, {w}) like the image, got {floor_mask.shape}")

    settings = RENDER.erase
    board = calibration.board
    half = np.array(board.size_m) / 2
    sheet = np.array([-half, half]) + [[-settings.edge_margin_m], [settings.edge_margin_m]]
    context = settings.context_share * 2 * float(half.max())
    origin = -half - context
    extent = 2 * (half + context)
    ppm = min(_density_px_per_m(calibration, half), settings.max_px_per_m)
    short_m = float(np.min(sheet[1] - sheet[0]))
    scale = min(1.0, settings.search_sheet_px / (short_m * ppm))

    # The whole neighbourhood, small: where the paper ends, the light, and where the
    # texture best matches.
    small = _TopDown(calibration, origin, ppm * scale)
    cols, rows = (int(np.ceil(v * small.ppm)) for v in extent)
    small_rgb, small_valid = small.sample(image, floor_mask, (0, 0, cols, rows), shrink=True)
    lab = cv2.cvtColor(small_rgb, cv2.COLOR_RGB2LAB).astype(np.float32)
    printed, on, squares = _printed(small, (rows, cols), board, lab[..., 0], small_valid)
    colours = _print_colours(lab, small_valid, printed, on)
    sheet = _grow_to_paper(small, lab, small_valid, sheet, board, colours)
    short_m = float(np.min(sheet[1] - sheet[0]))
    hole = small.rectangle(sheet, (0, 0, cols, rows))
    # What stands on the sheet stays, and is no floor to copy from.
    foreign = _foreign(lab, small_valid, hole, printed, squares, board.square_m * small.ppm, colours)
    covered = float(foreign.sum()) / max(1, int(hole.sum()))
    small_valid = small_valid & ~foreign
    hole &= ~foreign
    bad = hole | ~small_valid
    # A shadow's straight edges across the sheet are taken out first and put back on the
    # fill: smoothing would blur them, and the copied texture would bring another place's.
    usable = small_valid & ~(cv2.dilate(hole.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
    shade = []
    for _ in range(settings.shadow_max_edges):
        edge = _shadow_edge(small, small_rgb, usable, hole)
        if edge is None:
            break
        shade.append(edge)
        small_rgb = _lifted(small_rgb, [edge.factor(small, (0, 0, cols, rows))])
    # Light is what varies slowly; the floor's own blotches and planks are texture, copied whole.
    sigma = max(1.0, settings.light_sigma_share * short_m * small.ppm)
    smooth = cv2.inpaint(small_rgb, bad.astype(np.uint8) * 255, 3, cv2.INPAINT_TELEA)
    light = cv2.GaussianBlur(smooth.astype(np.float32), (0, 0), sigma)
    ring = max(2, round(settings.rim_share * short_m * small.ppm))
    parts = _sources(small, small_rgb.astype(np.float32) - light, sheet, bad, ring,
                     _photo_density(small, (rows, cols)))

    # The sheet at full size, and the places its texture comes from.
    full = _TopDown(calibration, origin, ppm)
    ring = max(2, round(settings.rim_share * short_m * ppm))
    (c0, r0), (c1, r1) = np.floor(full.view_px(sheet)).astype(int) + [[-ring], [ring + 1]]
    box = (c0, r0, c1, r1)
    rgb, valid = full.sample(image, floor_mask, box)
    shade_box = [edge.factor(full, box) for edge in shade]
    rgb = _lifted(rgb, shade_box)
    standing = _upsample(foreign.astype(np.float32), scale, box) > 0.5
    hole_full = full.rectangle(sheet, box) & ~standing
    valid &= ~standing
    light_full = _upsample(light, scale, box)
    texture = rgb.astype(np.float32) - light_full
    copied = np.zeros_like(light_full)
    have = np.zeros(hole_full.shape, bool)
    kernel = np.ones((2 * ring + 1,) * 2, np.uint8)
    reach = int(np.ceil(1 / scale)) + 2
    offsets = []
    crop_rows, crop_cols = hole_full.shape
    for part_m, found in parts:
        part = full.rectangle(part_m, box)
        dx, dy = (round(v / scale) for v in found)
        source = (c0 + dx - reach, r0 + dy - reach, c1 + dx + reach, r1 + dy + reach)
        src_rgb, src_valid = full.sample(image, floor_mask, source)
        src_rgb = _lifted(src_rgb, [edge.factor(full, source) for edge in shade])
        src_texture = src_rgb.astype(np.float32) - _upsample(light, scale, source)
        refined = _best_offset(texture, part, hole_full | ~valid, ring, search=(src_texture, ~src_valid, reach))
        if refined is None:
            continue
        ox, oy = refined
        # The part and its rim, where no part before it copied.
        take = (cv2.dilate(part.astype(np.uint8), kernel) > 0) & ~have
        copied[take] = src_texture[reach + oy:reach + oy + crop_rows, reach + ox:reach + ox + crop_cols][take]
        have |= take
        offsets.append((dx + ox, dy + oy))
    fill = light_full + copied
    # The copy's light seldom meets the floor's exactly at the rim (a glossy floor's sheen, a
    # lighter plank running on): what it misses there, smoothed along the rim and within
    # ``settings.rim_fix_levels``, is carried smoothly across the sheet.
    # (Worked out where the rim is 4 pixels wide: it is smooth.)
    outside = cv2.distanceTransform((~hole_full).astype(np.uint8), cv2.DIST_L2, 3)
    rim = ~hole_full & valid & (outside <= ring)
    shrink = min(1.0, 4.0 / ring)
    size = (max(2, round(rim.shape[1] * shrink)), max(2, round(rim.shape[0] * shrink)))
    on_rim = cv2.resize(rim.astype(np.float32), size, interpolation=cv2.INTER_AREA)
    missed = cv2.resize(np.where(rim[..., None], rgb.astype(np.float32) - fill, 0.0).astype(np.float32), size,
                        interpolation=cv2.INTER_AREA)
    share = cv2.GaussianBlur(on_rim, (0, 0), ring * shrink)
    missed = cv2.GaussianBlur(missed, (0, 0), ring * shrink) / np.maximum(share, 1e-6)[..., None]
    known = (on_rim > 0.5) & (share > 0.05)
    missed = np.clip(np.where(known[..., None], missed, 0.0), -settings.rim_fix_levels, settings.rim_fix_levels)
    carried = _push_pull(missed.astype(np.float32), known.astype(np.float32))
    fill = fill + cv2.resize(carried, rim.shape[::-1], interpolation=cv2.INTER_LINEAR)
    # How much of the fill each pixel takes: all of the sheet, and where a texture was
    # copied, a ramp over the rim it was matched on, so that the copy has no edge.
    weight = np.where(hole_full, 1.0, np.where(have, np.clip(1.0 - outside / (ring + 1), 0.0, 1.0), 0.0))
    weight = np.where(standing, 0.0, weight).astype(np.float32)
    for factor in shade_box:
        fill = fill * factor
    filled = np.clip(fill + 0.5, 0, 255).astype(np.uint8)

    # Back into the photo: the sheet's pixels, with the print's blurred edge, and the ramp.
    corners_m = np.array([[sheet[0, 0], sheet[0, 1]], [sheet[1, 0], sheet[0, 1]],
                          [sheet[1, 0], sheet[1, 1]], [sheet[0, 0], sheet[1, 1]]])
    region = _photo_region(calibration, corners_m, (ring + 1) / ppm, (h, w))
    result = image.copy()
    if region is None:
        return ErasedBoard(result, (0, 0, 0, 0), np.zeros((0, 0), np.float32), corners_m, np.zeros((0, 2)), covered)
    x0, y0, x1, y1, inside = region
    map_x, map_y = (m.astype(np.float32) for m in full.view_px_of_photo(x0, y0, x1, y1))
    map_x -= c0
    map_y -= r0
    back = cv2.remap(filled, map_x, map_y, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
    ramp = cv2.remap(weight, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    grown = cv2.dilate(inside.astype(np.uint8), np.ones((2 * settings.edge_grow_px + 1,) * 2, np.uint8))
    a = np.maximum(cv2.GaussianBlur(grown.astype(np.float32), (0, 0), settings.feather_px), ramp)
    if foreign.any():
        a *= 1.0 - _small_at(foreign.astype(np.float32), scale, map_x + c0, map_y + r0, cv2.BORDER_CONSTANT)
    # Only floor: what stands on the board stays; nothing above the horizon, where a
    # pixel maps to a point behind the camera.
    ha, hb, hc = calibration.horizon
    a *= below_horizon((y1 - y0, x1 - x0), (ha, hb, hc + ha * x0 + hb * y0))
    if floor_mask is not None:
        a *= floor_mask[y0:y1, x0:x1]
    blend = a[..., None] * back.astype(np.float32) + (1 - a[..., None]) * image[y0:y1, x0:x1]
    result[y0:y1, x0:x1] = np.clip(blend + 0.5, 0, 255).astype(np.uint8)
    return ErasedBoard(result, (x0, y0, x1, y1), a, corners_m, np.asarray(offsets, np.float64).reshape(-1, 2) / ppm,
                       covered)


class _TopDown:
    """The floor seen square-on at ``ppm`` pixels per meter: view pixel (c, r) is the floor
    point ``origin_m + ((c, r) + 0.5) / ppm``. Boxes are ``(c0, r0, c1, r1)``, view pixels,
    end exclusive, anywhere on the floor plane."""

    def __init__(self, calibration, origin_m, ppm):
        self.calibration = calibration
        self.origin_m = np.asarray(origin_m, np.float64)
        self.ppm = float(ppm)

    def view_px(self, points_m):
        return (np.asarray(points_m, np.float64) - self.origin_m) * self.ppm - 0.5

    def sample(self, image, floor_mask, box, shrink=False):
        """The photo seen in ``box``: (rows, cols, 3) uint8 and where it shows floor
        (bool: in the frame, before the camera, within the lens model, on ``floor_mask``
        when given).
        ``shrink``: from the photo shrunk by the power of two nearest the view's scale,
        so that a small view does not alias."""
        c0, r0, c1, r1 = box
        map_x, map_y = self._photo_maps(c0, r0, c1 - c0, r1 - r0)
        h, w = image.shape[:2]
        seen = (map_x >= 0) & (map_x <= w - 1) & (map_y >= 0) & (map_y <= h - 1)
        source, factor = image, 1
        if shrink:
            photo_ppm = _density_px_per_m(self.calibration, np.zeros(2))
            while photo_ppm / (2 * factor) >= self.ppm and min(h, w) // (2 * factor) >= 16:
                factor *= 2
            if factor > 1:
                source = cv2.resize(image, (w // factor, h // factor), interpolation=cv2.INTER_AREA)
        sx = (map_x + 0.5) / factor - 0.5
        sy = (map_y + 0.5) / factor - 0.5
        rgb = cv2.remap(source, sx, sy, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
        if floor_mask is None:
            return rgb, seen
        on_floor = cv2.remap(floor_mask.view(np.uint8), map_x, map_y, cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT)
        return rgb, seen & (on_floor > 0)

    def _photo_maps(self, c0, r0, cols, rows):
        """Photo pixel of each view pixel of the box (float32, far outside the photo where
        it does not show the point: behind the camera or beyond the lens model),
        computed on a coarse grid and interpolated."""
        step = RENDER.erase.map_step_px
        gx, gy = np.meshgrid(np.arange(c0, c0 + cols + step, step, dtype=np.float64),
                             np.arange(r0, r0 + rows + step, step, dtype=np.float64))
        floor = self.origin_m + (np.column_stack([gx.ravel(), gy.ravel()]) + 0.5) / self.ppm
        cal = self.calibration
        depth = floor @ cal.camera_from_floor[2, :2] + cal.camera_from_floor[2, 3]
        px = cal.pixels_from_floor(floor)
        ok = (depth > 1e-3) & np.all(np.isfinite(px), axis=1)
        ok[ok] &= cal.lens_maps(px[ok])
        return [_from_grid(np.where(ok, px[:, k], -1e4).reshape(gx.shape), rows, cols) for k in range(2)]

    def rectangle(self, sheet_m, box) -> np.ndarray:
        """(rows, cols) bool: the box's pixels inside ``sheet_m`` ((2, 2) low, high corner)."""
        c0, r0, c1, r1 = box
        (a0, b0), (a1, b1) = self.view_px(sheet_m)
        c = np.arange(c0, c1)
        r = np.arange(r0, r1)
        return ((r >= np.floor(b0)) & (r <= np.ceil(b1)))[:, None] & ((c >= np.floor(a0)) & (c <= np.ceil(a1)))[None]

    def view_px_of_photo(self, x0, y0, x1, y1):
        """Maps (float32, (y1 - y0, x1 - x0)) from the photo's box to view pixels."""
        step = RENDER.erase.map_step_px
        gx, gy = np.meshgrid(np.arange(x0, x1 + step, step, dtype=np.float64),
                             np.arange(y0, y1 + step, step, dtype=np.float64))
        v = self.view_px(self.calibration.floor_from_pixels(np.column_stack([gx.ravel(), gy.ravel()])))
        return [_from_grid(v[:, k].reshape(gx.shape), y1 - y0, x1 - x0) for k in range(2)]


@dataclass(frozen=True)
class _ShadowEdge:
    """A shadow's straight soft edge on the floor: each channel of the photo is
    ``exp(step[k] * s)`` times what it would be without it, ``s = 1 / (1 + exp(-t))`` and
    ``t = (normal_m . p - offset_m) / width_m`` at floor point ``p``; the darker side is 1."""

    normal_m: np.ndarray
    offset_m: float
    width_m: float
    step: np.ndarray

    def factor(self, view: _TopDown, box) -> np.ndarray:
        """(rows, cols, 3) float32: the shadow's factor at the view's box."""
        c0, r0, c1, r1 = box
        d = (view.origin_m @ self.normal_m + ((np.arange(c0, c1) + 0.5) / view.ppm)[None] * self.normal_m[0]
             + ((np.arange(r0, r1) + 0.5) / view.ppm)[:, None] * self.normal_m[1])
        s = 1.0 / (1.0 + np.exp(-np.clip((d - self.offset_m) / self.width_m, -50, 50)))
        return np.exp(s[..., None] * self.step - np.minimum(self.step, 0.0)).astype(np.float32)


def _lifted(rgb: np.ndarray, factors) -> np.ndarray:
    """``rgb`` (uint8) with each shadow edge's factor of ``factors`` (:meth:`_ShadowEdge.factor`
    at its box) taken out in turn, as they were found: the lit side brought down to the
    shaded side's light (a factor is at least 1, so nothing clips)."""
    for factor in factors:
        rgb = np.clip(rgb / factor + 0.5, 0, 255).astype(np.uint8)
    return rgb


def _shadow_edge(view: _TopDown, rgb: np.ndarray, usable: np.ndarray, hole: np.ndarray) -> _ShadowEdge | None:
    """The shadow's edge that crosses the sheet (``hole``, view pixels) in a straight line,
    found on the floor around it (``usable``) of the view's ``rgb``, or None.

    Along a candidate line the floor is cut into pieces; in each, the log brightness of a
    strip on one side is compared with the strip on the other. A shadow's edge darkens one
    side all along (a seam between planks of different colours flips sign from plank to
    plank, a tile's joint darkens neither side): of every direction and every place through
    the sheet, the line kept is the one whose pieces agree on the strongest step. Its
    softness and height per channel are then fitted to the median profile across it. A
    plank's lighter run that does agree all along is taken too: carried straight across
    the sheet, it is what the planks most likely do there."""
    settings = RENDER.erase
    hy, hx = np.nonzero(hole)
    short = min(hx.max() - hx.min(), hy.max() - hy.min()) + 1 if len(hx) else 0
    if short < 8:
        return None
    strip = max(3, round(settings.shadow_strip_share * short))
    piece = max(6, round(settings.shadow_piece_share * short))
    # The floor within a sheet's width around it. Closed (grey morphology): a joint's or a
    # seam's dark line is gone, a step stays.
    near = np.zeros_like(usable)
    near[max(0, hy.min() - short):hy.max() + short + 1, max(0, hx.min() - short):hx.max() + short + 1] = True
    near &= usable
    closed = cv2.morphologyEx(rgb, cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))

    def floor(stride):
        """Every ``stride``-th pixel's column, row, log brightness, and log of each channel."""
        ys, xs = np.nonzero(near[::stride, ::stride])
        logs = np.log(closed[ys * stride, xs * stride].astype(np.float64) + 4.0)
        return xs * stride, ys * stride, logs @ [0.299, 0.587, 0.114], logs

    def score(theta, xs, ys, lum, stride):
        """How strongly the pieces along the line at ``theta`` agree on a step: the best
        place through the sheet, (the step's median where they agree, else 0; the place)."""
        cos, sin = np.cos(theta), np.sin(theta)
        d, t = xs * cos + ys * sin, ys * cos - xs * sin
        d0 = d.min()
        db, tb = (d - d0).astype(int), ((t - t.min()) / piece).astype(int)
        nd = db.max() + 1
        shape = (tb.max() + 1, nd)
        total = np.pad(np.cumsum(np.bincount(tb * nd + db, lum, shape[0] * nd).reshape(shape), 1), ((0, 0), (1, 0)))
        count = np.pad(np.cumsum(np.bincount(tb * nd + db, None, shape[0] * nd).reshape(shape), 1), ((0, 0), (1, 0)))
        dh = hx * cos + hy * sin - d0
        places = np.arange(max(strip, int(dh.min())), min(nd - strip, int(np.ceil(dh.max()))) + 1)
        if len(places) == 0:
            return 0.0, 0.0
        hi_n = count[:, places + strip] - count[:, places]
        lo_n = count[:, places] - count[:, places - strip]
        hi = (total[:, places + strip] - total[:, places]) / np.maximum(hi_n, 1)
        lo = (total[:, places] - total[:, places - strip]) / np.maximum(lo_n, 1)
        step = np.where(np.minimum(hi_n, lo_n) >= strip * piece / (4 * stride ** 2), hi - lo, np.nan)
        seen = np.isfinite(step)
        n = seen.sum(0)
        ranked = np.sort(step, 0)  # nan last
        middle = [np.take_along_axis(ranked, np.maximum(k, 0)[None], 0)[0] for k in ((n - 1) // 2, n // 2)]
        median = np.where(n >= 4, (middle[0] + middle[1]) / 2, 0.0)
        agree = np.sum(seen & (step * median[None] >= 0.5 * median[None] ** 2), 0) / np.maximum(n, 1)
        value = np.abs(median) * (agree >= settings.shadow_agree)
        k = int(np.argmax(value))
        return float(value[k]), float(places[k] + d0)

    # Every direction on a coarse sample, then the best one's neighbourhood on a finer one.
    coarse = floor(4)
    xs, ys, lum, logs = floor(2)
    if len(xs) < 200:
        return None
    theta = max(np.deg2rad(np.arange(0.0, 180.0, 3.0)), key=lambda a: score(a, *coarse[:3], 4)[0])
    found = max((score(a, xs, ys, lum, 2) + (a,) for a in theta + np.deg2rad(np.arange(-2.0, 2.5, 0.5))),
                key=lambda v: v[0])
    if found[0] < settings.shadow_min_step:
        return None
    _, place, theta = found
    # The profile across the line: per piece, the log brightness about its mean, then the
    # median over pieces; fitted by a level, a slope and a soft step.
    cos, sin = np.cos(theta), np.sin(theta)
    d, t = xs * cos + ys * sin - place, ys * cos - xs * sin
    reach = 3 * strip
    inside = np.abs(d) < reach
    if inside.sum() < 50:
        return None
    db = (d[inside] + reach).astype(int)
    tb = ((t[inside] - t.min()) / piece).astype(int)
    nd = 2 * reach
    key = tb * nd + db
    rows = tb.max() + 1
    count = np.bincount(key, None, rows * nd).reshape(rows, nd)
    whole = (count[:, :reach].sum(1) > strip * piece / 8) & (count[:, reach:].sum(1) > strip * piece / 8)
    if whole.sum() < 4:
        return None
    profiles = []
    for channel in np.column_stack([lum, logs])[inside].T:
        mean = np.bincount(key, channel, rows * nd).reshape(rows, nd) / np.where(count > 0, count, np.nan)
        mean = mean[whole] - np.nanmean(mean[whole], 1, keepdims=True)
        profile = np.full(nd, np.nan)
        some = np.isfinite(mean).any(0)
        profile[some] = np.nanmedian(mean[:, some], 0)
        profiles.append(profile)
    profiles = np.array(profiles)
    x = np.arange(nd) - reach + 0.5
    known = np.all(np.isfinite(profiles), 0)
    best = None
    for shift in np.arange(-strip / 2, strip / 2 + 0.1, 0.5):
        for width in (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0):
            soft = 1.0 / (1.0 + np.exp(-np.clip((x - shift) / width, -50, 50)))
            model = np.column_stack([np.ones(nd), x, soft])[known]
            coef = np.linalg.lstsq(model, profiles[:, known].T, rcond=None)[0]
            res = float(np.sum((profiles[0, known] - model @ coef[:, 0]) ** 2))
            if best is None or res < best[0]:
                best = (res, shift, width, coef[2])
    _, shift, width, height = best
    # A step: strong, within the strips, and the profile's shape (a joint's dark line is no step).
    across = profiles[0, known]
    explained = 1.0 - best[0] / max(float(np.sum((across - across.mean()) ** 2)), 1e-12)
    if abs(height[0]) < settings.shadow_min_step or abs(shift) >= strip / 2 or explained < settings.shadow_fit:
        return None
    normal = np.array([cos, sin])
    offset_m = view.origin_m @ normal + (place + shift + 0.5 * normal.sum()) / view.ppm
    return _ShadowEdge(normal, float(offset_m), width / view.ppm, height[1:].astype(np.float32))


def _push_pull(values: np.ndarray, known: np.ndarray) -> np.ndarray:
    """``values`` (rows, cols, 3) where ``known`` (rows, cols, 0 or 1) is 1, carried smoothly
    over the rest: averaged down a pyramid (pull), then each level's gaps filled from the
    level above (push)."""
    levels = [(values * known[..., None], known)]
    while min(levels[-1][1].shape) > 4:
        total, weight = levels[-1]
        levels.append((cv2.pyrDown(total), cv2.pyrDown(weight)))
    total, weight = levels[-1]
    out = total / np.maximum(weight, 1e-6)[..., None]
    for total, weight in reversed(levels[:-1]):
        up = cv2.pyrUp(out, dstsize=(weight.shape[1], weight.shape[0]))
        sure = np.clip(4.0 * weight, 0.0, 1.0)[..., None]
        out = sure * total / np.maximum(weight, 1e-6)[..., None] + (1.0 - sure) * up
    return out


def _from_grid(grid: np.ndarray, rows: int, cols: int) -> np.ndarray:
    """(rows, cols) float32: values given every ``RENDER.erase.map_step_px`` pixels from
    the first (``grid``, one more row and column than needed), interpolated between."""
    step = RENDER.erase.map_step_px
    size = (grid.shape[1] - 1) * step + 1, (grid.shape[0] - 1) * step + 1
    return cv2.resize(grid.astype(np.float32), size, interpolation=cv2.INTER_LINEAR)[:rows, :cols]


def _upsample(small: np.ndarray, scale: float, box) -> np.ndarray:
    """The small view's ``small`` (at ``scale`` of the full view) at the full view's box."""
    c0, r0, c1, r1 = box
    gx, gy = np.meshgrid(np.arange(c0, c1, dtype=np.float32), np.arange(r0, r1, dtype=np.float32))
    return _small_at(small, scale, gx, gy, cv2.BORDER_REPLICATE)


def _small_at(small: np.ndarray, scale: float, x, y, border) -> np.ndarray:
    """The small view's ``small`` read at full-view pixels ``x``, ``y`` (float arrays)."""
    return cv2.remap(small, ((x + 0.5) * scale - 0.5).astype(np.float32), ((y + 0.5) * scale - 0.5).astype(np.float32),
                     cv2.INTER_LINEAR, borderMode=border)


def _floor_jacobians(calibration, points_m: np.ndarray) -> np.ndarray:
    """(n, 2, 2): photo pixels per meter of floor at floor points (n, 2), by a millimeter's
    finite difference: column 0 along x, column 1 along y."""
    p = np.asarray(points_m, dtype=np.float64)
    d = 1e-3
    px = [calibration.pixels_from_floor(p + off) for off in ((0, 0), (d, 0), (0, d))]
    return np.stack([px[1] - px[0], px[2] - px[0]], axis=-1) / d


def _density_px_per_m(calibration, half_m) -> float:
    """The photo's sharpest pixels per meter on the floor at the corners of the rectangle
    ``+-half_m`` around the board's center."""
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half_m
    return max(1.0, float(np.linalg.svd(_floor_jacobians(calibration, corners), compute_uv=False)[:, 0].max()))


def _photo_density(view: _TopDown, shape) -> np.ndarray:
    """(rows, cols) float: per pixel of ``view``, how many photo pixels cover a square
    meter of floor there (the floor homography's Jacobian determinant), from a grid of
    every eighth pixel."""
    rows, cols = shape
    gy, gx = np.mgrid[0:rows + 8:8, 0:cols + 8:8].astype(np.float64)
    J = _floor_jacobians(view.calibration, view.origin_m + (np.column_stack([gx.ravel(), gy.ravel()]) + 0.5) / view.ppm)
    det = np.abs(np.linalg.det(J)).reshape(gy.shape).astype(np.float32)
    return cv2.resize(det, (gx.shape[1] * 8, gy.shape[0] * 8), interpolation=cv2.INTER_LINEAR)[:rows, :cols]


def _printed(view: _TopDown, shape, board, lightness, valid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The print as :meth:`Board.image` lays it on the floor, in the view: (rows, cols)
    float32 grey levels, where the sheet is and where its squares are (bool each).
    A print without the margin (or on smaller paper) shows floor where the margin would
    be: only the squares are sure to be printed.

    A chessboard's pose is known up to a half turn, and a chessboard seen from above is
    its print mirrored; either can swap its squares' colours but never the white margin.
    The squares are swapped when the photo's ``lightness`` over them (where ``valid``)
    runs against them."""
    rows, cols = shape
    k = max(4, int(np.ceil(board.square_m * view.ppm)))
    sheet = board.image(px_per_square=k).astype(np.float32)
    # Image pixel (u, v) is the board point ((u + 0.5) / px_per_m - w / 2, ...): an affine
    # map into the view.
    px_per_m = k / board.square_m
    size = np.array(sheet.shape[::-1]) / px_per_m
    scale = view.ppm / px_per_m
    offset = (-size / 2 - view.origin_m) * view.ppm + 0.5 * scale - 0.5
    warp = np.array([[scale, 0.0, offset[0]], [0.0, scale, offset[1]]])
    # Beyond the sheet as white as its margin: no edge of the print where none is printed.
    printed = cv2.warpAffine(sheet, warp, (cols, rows), flags=cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=255)
    on = cv2.warpAffine(np.ones(sheet.shape, np.uint8), warp, (cols, rows), flags=cv2.INTER_NEAREST) > 0
    pad_y, pad_x = ((n - (m + 1) * k) // 2 for n, m in zip(sheet.shape, (board.rows, board.cols)))
    squares = np.zeros(sheet.shape, np.uint8)
    squares[pad_y:sheet.shape[0] - pad_y, pad_x:sheet.shape[1] - pad_x] = 1
    squares = cv2.warpAffine(squares, warp, (cols, rows), flags=cv2.INTER_NEAREST) > 0
    seen = squares & valid
    if seen.sum() > 20 and np.corrcoef(lightness[seen], printed[seen])[0, 1] < 0:
        printed = np.where(squares, 255.0 - printed, printed).astype(np.float32)
    return printed, on, squares


def _print_colours(lab, valid, printed, on):
    """The paper's and the ink's colour (Lab), and how far from either a pixel of the
    print may be: medians over the insides of the print's white and black (the photo
    blurs their edges), so that a thing covering part of the board (a ChArUco board may
    be partly hidden) does not count while it covers less than half. None when too
    little of the print shows."""
    kernel = np.ones((5, 5), np.uint8)
    white = (cv2.erode((printed > 200).astype(np.uint8), kernel) > 0) & on & valid
    black = (cv2.erode((printed < 55).astype(np.uint8), kernel) > 0) & on & valid
    if white.sum() < 20 or black.sum() < 20:
        return None
    paper, ink = np.median(lab[white], axis=0), np.median(lab[black], axis=0)
    spread = max(float(np.median(np.linalg.norm(lab[white] - paper, axis=1))),
                 float(np.median(np.linalg.norm(lab[black] - ink, axis=1))))
    return paper, ink, max(12.0, 3.0 * 1.4826 * spread)


def _foreign(lab, valid, hole, printed, squares, square_px, colours) -> np.ndarray:
    """(rows, cols) bool: what stands on the sheet (a carton over part of a ChArUco
    board). Where the print's ``squares`` are, the photo follows their pattern (shade
    darkens black and white alike) and a thing on them does not: the local correlation
    of the lightness with the print, over a square's window and its pixels on the squares
    only (past them a print without its margin shows floor), is low. Such a patch, a quarter square across
    or more, then takes in the sheet's pixels of its colour joined to it (the thing over
    the margin)."""
    if not squares.any():
        return np.zeros(hole.shape, bool)
    window = (max(3, int(round(square_px)) | 1),) * 2
    box = lambda im: cv2.boxFilter(im, cv2.CV_32F, window)  # noqa: E731
    # Means over each window's pixels on the squares only.
    w = squares.astype(np.float32)
    share = box(w)
    mean = lambda im: box(im * w) / np.maximum(share, 1e-6)  # noqa: E731
    light = lab[..., 0]
    mo, mp = mean(light), mean(printed)
    cov = mean(light * printed) - mo * mp
    var_o = np.maximum(mean(light * light) - mo * mo, 0)
    var_p = np.maximum(mean(printed * printed) - mp * mp, 0)
    # Only windows the photo shows (a board cut off at the photo's edge), a quarter on the squares.
    patterned = (var_p > 0.5 * float(np.percentile(var_p[squares], 90))) & (box(valid.astype(np.float32)) > 0.9) \
        & (share > 0.25)
    ncc = cov / np.sqrt(var_o * var_p + 1e-6)
    core = (ncc < 0.3) & patterned & hole & valid
    size = max(3, int(round(square_px / 4)) | 1)
    core = cv2.morphologyEx(core.astype(np.uint8), cv2.MORPH_OPEN, np.ones((size, size), np.uint8)) > 0
    if core.sum() < square_px ** 2 / 4:
        return np.zeros(hole.shape, bool)
    colour = np.median(lab[core], axis=0)
    spread = max(8.0, 3.0 * 1.4826 * float(np.median(np.linalg.norm(lab[core] - colour, axis=1))))
    alike = (np.linalg.norm(lab - colour, axis=2) < spread) & hole & valid
    if colours is not None:
        # Not the paper: a thing the paper's colour cannot be told from the margin.
        paper, _, tolerance = colours
        to_paper = np.linalg.norm(lab - paper, axis=2)
        alike &= ~((to_paper < tolerance) | (to_paper < np.linalg.norm(lab - colour, axis=2)))
    alike |= core
    n, labels = cv2.connectedComponents(alike.astype(np.uint8), connectivity=8)
    joined = np.unique(labels[core])
    thing = np.isin(labels, joined[joined > 0]).astype(np.uint8)
    # Whole: its own marks and the print's blurred edges under its rim are not floor either.
    thing = cv2.morphologyEx(thing, cv2.MORPH_CLOSE, np.ones((2 * size + 1,) * 2, np.uint8))
    outside = thing == 0
    n, labels = cv2.connectedComponents(outside.astype(np.uint8), connectivity=4)
    rim = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    holes = outside & ~np.isin(labels, rim)
    return ((thing > 0) | holes) & hole


def _grow_to_paper(view: _TopDown, lab, valid, sheet_m: np.ndarray, board, colours) -> np.ndarray:
    """``sheet_m`` ((2, 2) low, high corner) grown side by side while the next line of the
    view (``lab``, the box from the view's origin) beyond it is mostly the paper's colour
    (``colours``, :func:`_print_colours`), at most ``RENDER.erase.paper_growth_squares``
    squares; not at all where the floor beyond is the paper's colour."""
    rows, cols = valid.shape
    box = (0, 0, cols, rows)
    if colours is None:
        return sheet_m
    paper, _, tolerance = colours
    like_paper = (np.linalg.norm(lab - paper, axis=2) < tolerance) & valid
    growth = RENDER.erase.paper_growth_squares
    reach = int(growth * board.square_m * view.ppm)
    # A floor the paper's colour tells nothing: the sheet stays as printed.
    far = board.square_m * (growth + 0.5)
    ring = view.rectangle(sheet_m + [[-2 * far], [2 * far]], box) & ~view.rectangle(sheet_m + [[-far], [far]], box)
    if (ring & valid).sum() >= 20 and np.linalg.norm(np.median(lab[ring & valid], axis=0) - paper) < tolerance:
        return sheet_m
    grown = sheet_m.copy()
    (c0, r0), (c1, r1) = np.round(view.view_px(sheet_m)).astype(int)
    c0, c1 = np.clip([c0, c1], 0, cols - 1)
    r0, r1 = np.clip([r0, r1], 0, rows - 1)
    for start, axis, sign in ((c0, 0, -1), (c1, 0, 1), (r0, 1, -1), (r1, 1, 1)):
        n = 0
        for k in range(1, reach + 1):
            at = start + sign * k
            if not 0 <= at < (cols, rows)[axis]:
                break
            line = like_paper[r0:r1 + 1, at] if axis == 0 else like_paper[at, c0:c1 + 1]
            seen = valid[r0:r1 + 1, at] if axis == 0 else valid[at, c0:c1 + 1]
            if seen.sum() < 0.5 * len(seen) or line.sum() < RENDER.erase.paper_line_share * seen.sum():
                break
            n = k
        grown[0 if sign < 0 else 1, axis] += sign * n / view.ppm
    return grown


def _sources(view: _TopDown, texture, sheet_m, bad, ring, density, depth=0) -> list:
    """Parts of the sheet ``sheet_m`` ((2, 2) low, high corner, meters) with the offset
    (view pixels) of the place their texture is copied from (:func:`_best_offset`): the
    whole sheet, or where no place is all floor, its halves across the longer side, and
    theirs (to ``RENDER.erase.max_splits`` deep). Parts that find none are left out.
    ``density``: :func:`_photo_density` of the view (:func:`_best_offset` prefers places
    as sharp as the part)."""
    rows, cols = bad.shape
    part = view.rectangle(sheet_m, (0, 0, cols, rows))
    found = _best_offset(texture, part, bad, ring, density=density)
    if found is not None:
        return [(sheet_m, found)]
    if depth >= RENDER.erase.max_splits:
        return []
    axis = int(np.argmax(sheet_m[1] - sheet_m[0]))
    middle = 0.5 * (sheet_m[0, axis] + sheet_m[1, axis])
    low, high = sheet_m.copy(), sheet_m.copy()
    low[1, axis] = high[0, axis] = middle
    return (_sources(view, texture, low, bad, ring, density, depth + 1)
            + _sources(view, texture, high, bad, ring, density, depth + 1))


def _best_offset(texture, hole, bad, ring, search=None, density=None):
    """(dx, dy) minimizing the masked sum of squared differences between the rim of
    ``hole`` in ``texture`` and the rim of the place (dx, dy) away, over places whose
    hole and rim hold nothing ``bad``; None when there is no such place. ``search =
    (texture, bad, reach)``: look there instead, a box ``reach`` larger all round than
    ``texture`` and displaced from it; the offset is then relative to that
    displacement. ``density`` (like ``bad``, photo pixels per square meter; not with
    ``search``): a place whose middle the photo shows coarser than
    ``RENDER.erase.source_sharpness`` of the hole's is taken only when there is no other
    (its texture, copied nearer the camera, would be a soft smudge)."""
    rows, cols = hole.shape
    ys, xs = np.nonzero(hole)
    if not len(ys):
        return None
    y0, y1 = max(0, ys.min() - ring), min(rows, ys.max() + 1 + ring)
    x0, x1 = max(0, xs.min() - ring), min(cols, xs.max() + 1 + ring)
    kernel = np.ones((2 * ring + 1,) * 2, np.uint8)
    near = cv2.dilate(hole.astype(np.uint8), kernel) > 0
    rim = near & ~bad
    if not rim.any():
        return None
    templ = np.ascontiguousarray(texture[y0:y1, x0:x1])
    weight = np.repeat(rim[y0:y1, x0:x1, None], 3, axis=2).astype(np.float32)
    need = near[y0:y1, x0:x1].astype(np.float32)
    if search is None:
        image, bad_image, base_x, base_y = texture, bad, x0, y0
    else:
        image, bad_image, reach = search
        image = image[y0:y1 + 2 * reach, x0:x1 + 2 * reach]
        bad_image = bad_image[y0:y1 + 2 * reach, x0:x1 + 2 * reach]
        base_x = base_y = reach
    if image.shape[0] < templ.shape[0] or image.shape[1] < templ.shape[1]:
        return None
    image = np.ascontiguousarray(image)
    ssd = cv2.matchTemplate(image, templ, cv2.TM_SQDIFF, mask=weight)
    # Relative to the two rims' energy: a plain SSD would prefer a flat place, whose
    # difference to any texture is only that texture.
    energy = float(np.sum(weight * templ * templ)) + cv2.matchTemplate(image * image, weight, cv2.TM_CCORR)
    ssd = ssd / np.maximum(energy, 1e-6)
    blocked = cv2.matchTemplate(bad_image.astype(np.float32), need, cv2.TM_CCORR)
    ssd[blocked > 0.5] = np.inf
    if not np.isfinite(ssd).any():
        return None
    if density is not None:
        my, mx = (ys.min() + ys.max()) // 2, (xs.min() + xs.max()) // 2
        coarse = density[my - y0:my - y0 + ssd.shape[0], mx - x0:mx - x0 + ssd.shape[1]] < (
            RENDER.erase.source_sharpness * density[my, mx])
        fine = np.where(coarse, np.inf, ssd)
        ssd = fine if np.isfinite(fine).any() else ssd
    py, px = np.unravel_index(int(np.argmin(ssd)), ssd.shape)
    return int(px - base_x), int(py - base_y)


def _photo_region(calibration, corners_m, around_m, shape):
    """The photo's box around the sheet ``corners_m`` (4, 2) grown by ``around_m`` (x0, y0,
    x1, y1) and, in it, the sheet's pixels (bool); None when the sheet is out of the photo."""
    h, w = shape
    t = np.linspace(0, 1, 16, endpoint=False)[:, None]

    def outline_px(corners):
        # Densified, so that lens distortion bends the edges.
        dense = np.concatenate([a + t * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0))])
        return calibration.pixels_from_floor(dense)

    outer = outline_px(corners_m + np.sign(corners_m - corners_m.mean(axis=0)) * around_m)
    pad = RENDER.erase.edge_grow_px + 3 * int(np.ceil(RENDER.erase.feather_px)) + 1
    x0, y0 = np.floor(outer.min(axis=0)).astype(int) - pad
    x1, y1 = np.ceil(outer.max(axis=0)).astype(int) + pad + 1
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(w, x1), min(h, y1)
    if x1 <= x0 or y1 <= y0:
        return None
    inside = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.fillPoly(inside, [np.round((outline_px(corners_m) - [x0, y0]) * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
    return x0, y0, x1, y1, inside > 0


def layer_over_photo(layer: np.ndarray, erased: ErasedBoard, photo: np.ndarray) -> np.ndarray:
    """A straight-alpha RGBA layer made over ``erased.image``, as a layer over ``photo``
    (the photo before the board was erased): the fill under the layer joins it, so that
    laid over the photo it gives what it gave over the erased photo.

    Parameters
    ----------
    layer : (h, w, 4) uint8
        Over the erased photo: ``c a + (1 - a) E``.
    erased : ErasedBoard
        ``E = alpha F + (1 - alpha) P`` with the fill F.
    photo : (h, w, 3) uint8
        P.

    Returns
    -------
    (h, w, 4) uint8
        Alpha ``a + (1 - a) alpha``, colour ``(a c + (1 - a) alpha F) / that``.
    """
    out = layer.copy()
    x0, y0, x1, y1 = erased.box_px
    part = layer[y0:y1, x0:x1]
    a = part[..., 3].astype(np.float32) / 255.0
    b = erased.alpha
    total = a + (1.0 - a) * b
    # alpha F, from the erased photo and the photo: no division by a small alpha.
    fill = erased.image[y0:y1, x0:x1].astype(np.float32) - (1.0 - b)[..., None] * photo[y0:y1, x0:x1]
    colour = (a[..., None] * part[..., :3].astype(np.float32) + (1.0 - a)[..., None] * fill) \
        / np.maximum(total, 1e-4)[..., None]
    colour = np.where(total[..., None] > 0, colour, part[..., :3].astype(np.float32))
    out[y0:y1, x0:x1] = (np.dstack([np.clip(colour, 0, 255), np.clip(total * 255.0, 0, 255)]) + 0.5).astype(np.uint8)
    return out
