"""A picture of a calibration, drawn over its photo, to see at a glance whether it is right.

:func:`calibration_overlay` draws, on a copy of the photo:

* the detected board corners, colored row by row and joined in the detector's order, the
  first corner ringed in white (where the board frame starts); a ChArUco board shows the
  corners it was seen by, and the caption says how many of all;
* the outline of the printed squares where the calibration puts them;
* a 1 m grid on the floor (``DRAW.calibration.grid_half_span_m`` around the board), only
  where the floor is in front of the camera and below the horizon, bent by the lens
  distortion like the photo's own straight lines;
* the floor axes at the board's origin: x red, y green (along the floor), z blue (up),
  each ``DRAW.calibration.axis_m`` long;
* the horizon (the floor's vanishing line) dashed, when it crosses the frame;
* a caption box in the corner farthest from the board: where the focal length came from
  and how sure it is, the camera's height, the board's reprojection RMS.

A right calibration shows the grid lying flat on the floor, parallel to the board's
edges, converging on the horizon where the floor meets the far wall, and the blue axis
standing upright like the room's vertical edges.

Conventions: images are RGB ``(h, w, 3)`` uint8 arrays; colors are RGB
(:mod:`augment.draw.settings`).
"""
from __future__ import annotations

import cv2
import numpy as np
from PIL import Image, ImageDraw

from ..camera.calibration import Calibration
from ..camera.detect import corner_spacing_px
from .fonts import overlay_font
from .settings import DRAW

_SHIFT = 4                    # fixed-point bits for subpixel drawing
_ONE = 1 << _SHIFT


def _fixed(points: np.ndarray) -> np.ndarray:
    """Pixel coordinates (k, 2) as int32 fixed point for OpenCV's ``shift`` argument."""
    return np.round(np.asarray(points, dtype=np.float64) * _ONE).astype(np.int32)


def _runs(mask: np.ndarray) -> list[slice]:
    """Slices of the consecutive True stretches of a 1-d boolean array (2 points or more)."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2]) if b - a >= 2]


class _Lens:
    """Where drawing is trustworthy, and the distortion applied to undistorted pixels.

    A distortion polynomial fit inside the frame folds back on itself some way outside
    it, throwing far-away points into the picture; points are kept only inside the
    undistorted frame (grown by a margin) and within the radius where the radial
    distortion still increases monotonically.
    """

    def __init__(self, calibration: Calibration, margin: float = 0.15):
        self.K = calibration.intrinsics.K
        self.K_inv = np.linalg.inv(self.K)
        self.dist = np.asarray(calibration.intrinsics.distortion, dtype=np.float64).ravel()
        w, h = calibration.size_px
        self.size = (w, h)
        t = np.linspace(0, 1, 33)
        border = np.vstack([np.column_stack([t * (w - 1), np.zeros_like(t)]),
                            np.column_stack([t * (w - 1), np.full_like(t, h - 1)]),
                            np.column_stack([np.zeros_like(t), t * (h - 1)]),
                            np.column_stack([np.full_like(t, w - 1), t * (h - 1)])])
        if np.any(self.dist):
            border = cv2.undistortPoints(border.reshape(-1, 1, 2), self.K, self.dist, P=self.K).reshape(-1, 2)
        lo, hi = border.min(axis=0), border.max(axis=0)
        grow = margin * (hi - lo)
        self.box = (lo - grow, hi + grow)
        self.max_radius = self._monotonic_radius()

    def _monotonic_radius(self) -> float:
        k = np.zeros(8)
        k[:len(self.dist)] = self.dist[:8]
        k1, k2, k3 = k[0], k[1], k[4]
        k4, k5, k6 = k[5], k[6], k[7]
        r = np.linspace(0, 5, 5001)[1:]
        r2 = r * r
        num = 1 + k1 * r2 + k2 * r2 ** 2 + k3 * r2 ** 3
        den = 1 + k4 * r2 + k5 * r2 ** 2 + k6 * r2 ** 3
        rd = r * num / den
        bad = np.flatnonzero((np.diff(rd) <= 0) | (den[1:] <= 0))
        return float(r[bad[0]]) if len(bad) else np.inf

    def keep(self, undistorted_px: np.ndarray) -> np.ndarray:
        """Which undistorted pixels (k, 2) can be drawn."""
        lo, hi = self.box
        inside = np.all((undistorted_px >= lo) & (undistorted_px <= hi), axis=1)
        homog = np.column_stack([undistorted_px, np.ones(len(undistorted_px))]) @ self.K_inv.T
        return inside & (np.hypot(homog[:, 0], homog[:, 1]) < self.max_radius)

    def distort(self, undistorted_px: np.ndarray) -> np.ndarray:
        """Photo pixels (k, 2) of undistorted pixels (k, 2)."""
        if not np.any(self.dist) or len(undistorted_px) == 0:
            return np.asarray(undistorted_px, dtype=np.float64)
        rays = np.column_stack([undistorted_px, np.ones(len(undistorted_px))]) @ self.K_inv.T
        px, _ = cv2.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), self.K, self.dist)
        return px.reshape(-1, 2)


class _Style:
    """Line widths, radii and font sizes scaled to the image."""

    def __init__(self, size_px):
        settings = DRAW.calibration
        w, h = size_px
        self.s = max(w, h) / settings.style_long_px
        self.grid = max(1, round(settings.grid_width_px * self.s))
        self.axis = max(2, round(settings.axis_width_px * self.s))
        self.thin = max(1, round(settings.thin_width_px * self.s))
        self.halo = max(1, round(settings.halo_width_px * self.s))
        self.font_px = max(11, round(0.022 * min(w, h) * max(1.0, w / h) ** 0.5))
        self.label_px = max(10, round(0.9 * self.font_px))
        self.dash = settings.dash_px * self.s
        self.gap = settings.dash_gap_px * self.s


def _polyline(image, points, color, thickness, closed=False):
    cv2.polylines(image, [_fixed(points).reshape(-1, 1, 2)], closed, color, thickness, cv2.LINE_AA, _SHIFT)


def _camera_depth(calibration: Calibration, points_m: np.ndarray) -> np.ndarray:
    p = np.asarray(points_m, dtype=np.float64)
    if p.shape[-1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    return p @ calibration.camera_from_floor[2, :3] + calibration.camera_from_floor[2, 3]


def _floor_curves(calibration: Calibration, lens: _Lens, lines_m: list[np.ndarray],
                  with_points: bool = False) -> list:
    """Visible pieces, in photo pixels, of floor polylines (each (k, 2) meters, densely
    sampled); with ``with_points``, pairs (pixels, floor points) instead."""
    if not lines_m:
        return []
    counts = [len(line) for line in lines_m]
    points = np.vstack(lines_m)
    h = np.column_stack([points, np.ones(len(points))]) @ calibration.image_from_floor.T
    w = h[:, 2]
    safe = np.where(np.abs(w) > 1e-12, w, 1e-12)
    undistorted = h[:, :2] / safe[:, None]
    a, b, c = calibration.horizon
    keep = ((_camera_depth(calibration, points) > DRAW.calibration.min_depth_m)
            & (a * undistorted[:, 0] + b * undistorted[:, 1] + c > 0)
            & lens.keep(undistorted))
    # Only the kept points go through the lens model (the others may be anywhere).
    pixels = np.full_like(undistorted, np.nan)
    if keep.any():
        pixels[keep] = calibration.pixels_from_floor(points[keep])
    curves, start = [], 0
    for n in counts:
        for run in _runs(keep[start:start + n]):
            piece = pixels[start:start + n][run]
            curves.append((piece, points[start:start + n][run]) if with_points else piece)
        start += n
    return curves


def _grid_lines_m() -> list[np.ndarray]:
    settings = DRAW.calibration
    half, step = settings.grid_half_span_m, settings.grid_step_m
    ticks = np.arange(-half, half + 1e-9, step)
    along = np.linspace(-half, half, int(round(2 * half / settings.grid_sample_m)) + 1)
    lines = [np.column_stack([np.full_like(along, v), along]) for v in ticks]
    lines += [np.column_stack([along, np.full_like(along, v)]) for v in ticks]
    return lines


def _grid_opacity(calibration: Calibration, size_px) -> np.ndarray:
    """Per-pixel opacity (h, w, 1) of the grid: it fades with the floor distance from the
    camera, since far lines mostly cross walls. Computed coarsely, without distortion."""
    w, h = size_px
    step = 8
    u, v = np.meshgrid(np.arange(0, w + step, step, dtype=np.float64),
                       np.arange(0, h + step, step, dtype=np.float64))
    rays = np.stack([u, v, np.ones_like(u)], axis=-1) @ np.linalg.inv(calibration.image_from_floor).T
    wz = rays[..., 2]
    a, b, c = calibration.horizon
    ok = a * u + b * v + c > 0  # below the horizon: the ray meets the floor in front
    floor = rays[..., :2] / np.where(np.abs(wz) > 1e-12, wz, 1e-12)[..., None]
    foot = calibration.world_from_camera[:2, 3]
    d = np.where(ok, np.hypot(*(floor - foot).transpose(2, 0, 1)), np.inf)
    lo, hi, (a_near, a_far) = *DRAW.calibration.grid_fade_m, DRAW.calibration.grid_opacity
    alpha = a_near + (a_far - a_near) * np.clip((d - lo) / (hi - lo), 0, 1)
    alpha = cv2.resize(alpha.astype(np.float32), None, fx=step, fy=step, interpolation=cv2.INTER_LINEAR)
    return alpha[:h, :w, None]


def _draw_grid(out, calibration, lens, style):
    layer = out.copy()
    curves = _floor_curves(calibration, lens, _grid_lines_m())
    if not curves:
        return
    for curve in curves:
        _polyline(layer, curve, (0, 0, 0), style.grid + 2 * style.halo)
    for curve in curves:
        _polyline(layer, curve, DRAW.calibration.grid_rgb, style.grid)
    # Blend only where lines were drawn: a 12 MP photo has few such pixels.
    rows, cols = np.nonzero(np.any(layer != out, axis=2))
    alpha = _grid_opacity(calibration, calibration.size_px)[rows, cols]
    out[rows, cols] = np.round(out[rows, cols] * (1 - alpha) + layer[rows, cols] * alpha).astype(np.uint8)


def _squares_outline_m(calibration: Calibration) -> np.ndarray:
    """The outer edge of the printed squares, densely sampled (k, 2) meters, closed.

    The squares, not the sheet: their size is known exactly, the paper's is not."""
    board = calibration.board
    hx, hy = (board.cols + 1) * board.square_m / 2, (board.rows + 1) * board.square_m / 2
    corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy], [-hx, -hy]])
    return np.vstack([np.linspace(p, q, 50, endpoint=False) for p, q in zip(corners[:-1], corners[1:])]
                     + [corners[:1]])


def _draw_squares_outline(out, calibration, lens, style):
    for curve in _floor_curves(calibration, lens, [_squares_outline_m(calibration)]):
        _polyline(out, curve, DRAW.calibration.squares_rgb, style.thin)


def _horizon_px(calibration: Calibration, lens: _Lens) -> np.ndarray | None:
    """The horizon as a dense polyline in photo pixels, or None when it is off the frame."""
    a, b, c = calibration.horizon
    lo, hi = lens.box
    center = (lo + hi) / 2
    foot = center - (np.dot([a, b], center) + c) * np.array([a, b])  # nearest line point to the center
    direction = np.array([-b, a])
    half = float(np.hypot(*(hi - lo)))
    n = int(max(200, 2 * half))
    t = np.linspace(-half, half, n)
    undistorted = foot + t[:, None] * direction
    keep = lens.keep(undistorted)
    if keep.sum() < 2:
        return None
    runs = _runs(keep)
    longest = max(runs, key=lambda r: r.stop - r.start)
    px = lens.distort(undistorted[longest])
    w, h = lens.size
    near = 0.03 * max(w, h)
    inside = ((px[:, 0] > -near) & (px[:, 0] < w - 1 + near) & (px[:, 1] > -near) & (px[:, 1] < h - 1 + near))
    if not inside.any():
        return None
    if px[-1, 0] < px[0, 0]:  # left to right, for the label
        px = px[::-1]
    return px


def _dashes(px: np.ndarray, dash: float, gap: float) -> list[np.ndarray]:
    seg = np.hypot(*np.diff(px, axis=0).T)
    along = np.concatenate([[0.0], np.cumsum(seg)])
    on = (along % (dash + gap)) < dash
    return [px[r] for r in _runs(on)]


def _draw_horizon(out, calibration, lens, style) -> np.ndarray | None:
    """Draw the horizon dashed; returns its polyline (photo pixels) or None when off the frame."""
    px = _horizon_px(calibration, lens)
    if px is None:
        return None
    for piece in _dashes(px, style.dash, style.gap):
        _polyline(out, piece, (0, 0, 0), style.thin + 2 * style.halo)
        _polyline(out, piece, DRAW.calibration.horizon_rgb, style.thin + 1)
    return px


def _horizon_label(px, size_px, style, boxes):
    """Where to write "horizon": above the line, as far right as it stays clear of ``boxes``."""
    w, h = size_px
    text_w, text_h = 4.2 * style.label_px, 1.2 * style.label_px
    gap = 0.6 * style.label_px
    for x, y in px[::-1]:
        right = min(x, w - 1 - gap)
        rect = (right - text_w, y - gap - text_h, right, y - gap)
        if rect[0] < gap or rect[1] < 0 or rect[3] > h:
            continue
        if all(rect[2] < b[0] or rect[0] > b[2] or rect[3] < b[1] or rect[1] > b[3] for b in boxes):
            return (right, y - gap), "horizon", DRAW.calibration.horizon_rgb, "rb"
    return None


def _draw_axes(out, calibration, style, labels):
    settings = DRAW.calibration
    t = np.linspace(0, settings.axis_m, 26)[:, None]
    zero = np.zeros_like(t)
    axes = {"x": np.hstack([t, zero, zero]), "y": np.hstack([zero, t, zero]), "z": np.hstack([zero, zero, t])}
    w, h = calibration.size_px
    origin_px = None
    for name in ("z", "x", "y"):  # z first: the floor axes are drawn over its foot
        pts = axes[name]
        if np.any(_camera_depth(calibration, pts) <= settings.min_depth_m):
            continue
        px = calibration.pixels_from_floor(pts)
        if not np.all(np.isfinite(px)) or np.abs(px).max() > 4 * max(w, h):
            continue
        origin_px = px[0]
        _polyline(out, px, (0, 0, 0), style.axis + 2 * style.halo)
        rgb = settings.axis_rgb[name]
        _polyline(out, px, rgb, style.axis)
        tip, back = px[-1], px[-4]
        d = tip - back
        norm = float(np.hypot(*d))
        if norm > 1e-6:
            d /= norm
            size = 3.5 * style.axis
            base = tip - d * size
            normal = np.array([-d[1], d[0]])
            head = np.array([tip + d * 0.3 * size, base + normal * 0.5 * size, base - normal * 0.5 * size])
            cv2.fillConvexPoly(out, _fixed(head), rgb, cv2.LINE_AA, _SHIFT)
            labels.append((tuple(tip + d * (size + 0.6 * style.label_px)), name, rgb, "mm"))
    if origin_px is not None:
        cv2.circle(out, tuple(_fixed(origin_px)), round(1.2 * style.axis * _ONE), (255, 255, 255), -1,
                   cv2.LINE_AA, _SHIFT)


def _draw_corners(out, calibration, style, transform=None, spacing=None, light=False):
    """Corners colored by board row, joined along their rows and from each row's end to the
    next row's start (the order a checkerboard detector lists them), the board's first
    corner (or the first one seen) ringed.

    ``transform`` maps photo pixels to ``out``'s (for the inset); ``light`` draws small
    dots only (the inset shows the detail)."""
    board = calibration.board
    corners = np.asarray(calibration.corners_px, dtype=np.float64).reshape(-1, 2)
    ids = np.asarray(calibration.corner_ids)
    if transform is not None:
        corners = transform(corners)
    grid = np.full((board.rows * board.cols, 2), np.nan)
    grid[ids] = corners
    grid = grid.reshape(board.rows, board.cols, 2)
    if spacing is None:
        spacing = _corner_spacing_px(calibration)
    radius = float(np.clip(0.25 * spacing, 1.5, 6 * style.s))
    # Row colors as in OpenCV's drawChessboardCorners: the order reads at a glance.
    hues = np.linspace(0, 150, board.rows, endpoint=False).astype(np.uint8)
    colors = cv2.cvtColor(np.stack([hues, np.full_like(hues, 255), np.full_like(hues, 255)], axis=1)[None],
                          cv2.COLOR_HSV2RGB)[0]
    thin = max(1, style.thin)
    # Polylines through neighbors both seen: a hidden corner breaks its row.
    path = grid.reshape(-1, 2)
    pieces = [path[r] for r in _runs(np.all(np.isfinite(path), axis=1))]
    if not light:
        for piece in pieces:
            _polyline(out, piece, (0, 0, 0), thin + 2)
    for j in range(board.rows):
        color = tuple(int(v) for v in colors[j])
        row = grid[j][np.all(np.isfinite(grid[j]), axis=1)]
        if light:
            for p in row:
                cv2.circle(out, tuple(_fixed(p)), round(1.2 * _ONE), color, -1, cv2.LINE_AA, _SHIFT)
            continue
        for r in _runs(np.all(np.isfinite(grid[j]), axis=1)):
            _polyline(out, grid[j][r], color, thin)
        if j + 1 < board.rows and np.all(np.isfinite([grid[j, -1], grid[j + 1, 0]])):
            _polyline(out, np.array([grid[j, -1], grid[j + 1, 0]]), color, thin)  # the jump to the next row
        for p in row:
            cv2.circle(out, tuple(_fixed(p)), round(radius * _ONE), (0, 0, 0), thin + 2, cv2.LINE_AA, _SHIFT)
            cv2.circle(out, tuple(_fixed(p)), round(radius * _ONE), color, thin, cv2.LINE_AA, _SHIFT)
    first = tuple(_fixed(corners[np.argmin(ids)]))
    big = max(radius * 1.6, 3.0 if light else 4.0)
    cv2.circle(out, first, round(big * _ONE), (0, 0, 0), thin + 3, cv2.LINE_AA, _SHIFT)
    cv2.circle(out, first, round(big * _ONE), (255, 255, 255), thin + 1, cv2.LINE_AA, _SHIFT)
    cv2.circle(out, first, round(0.55 * big * _ONE), DRAW.calibration.first_corner_rgb, -1, cv2.LINE_AA, _SHIFT)


def _caption_lines(calibration: Calibration, horizon: bool) -> list[list[tuple[str, tuple]]]:
    i = calibration.intrinsics
    board = calibration.board
    settings = DRAW.calibration
    white, axis_rgb = settings.text_rgb, settings.axis_rgb
    count = len(calibration.corner_ids)
    seen = f"{count} of {board.corner_count} corners, " if count < board.corner_count else ""
    return [
        [(f"focal {i.K[0, 0]:.0f} px \u00b1 {100 * i.focal_uncertainty:.1f} % ({i.source})", white)],
        [(f"camera {calibration.camera_height_m:.2f} m above the floor", white)],
        [(f"board {board.spec}, {board.square_mm:g} mm: " + seen + f"RMS {calibration.rms_px:.2f} px", white)],
        [(f"grid {settings.grid_step_m:g} m, axes {settings.axis_m:g} m: ", white), ("x ", axis_rgb["x"]),
         ("y ", axis_rgb["y"]), ("z", axis_rgb["z"])] + ([("  horizon", settings.horizon_rgb)] if horizon else []),
    ]


def _place(size_px, box_wh, margin, avoid) -> tuple[int, int]:
    """Top-left of a box in the first image corner (top-left, top-right, bottom-left,
    bottom-right) where it stays clear of the rectangles ``avoid`` (x0, y0, x1, y1), else
    where it overlaps them least."""
    w, h = size_px
    bw, bh = box_wh
    best, best_overlap = None, None
    for x, y in ((margin, margin), (w - margin - bw, margin), (margin, h - margin - bh),
                 (w - margin - bw, h - margin - bh)):
        overlap = 0.0
        for x0, y0, x1, y1 in avoid:
            overlap += max(0.0, min(x + bw, x1) - max(x, x0)) * max(0.0, min(y + bh, y1) - max(y, y0))
        if best is None or overlap < best_overlap:
            best, best_overlap = (int(x), int(y)), overlap
        if overlap == 0:
            break
    return best


class _Caption:
    """The caption's lines, font and box size (placed later)."""

    def __init__(self, calibration: Calibration, style: _Style, horizon: bool):
        self.font = overlay_font(style.font_px)
        self.lines = _caption_lines(calibration, horizon)
        self.line_h = round(1.35 * style.font_px)
        self.pad = round(0.6 * style.font_px)
        measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
        width = max(sum(measure.textlength(text, font=self.font) for text, _ in line) for line in self.lines)
        self.size = (round(width) + 2 * self.pad,
                     self.line_h * len(self.lines) + 2 * self.pad - round(0.35 * style.font_px))
        self.origin = (0, 0)

    @property
    def rect(self):
        return (*self.origin, self.origin[0] + self.size[0], self.origin[1] + self.size[1])

    def draw(self, base: Image.Image, draw: ImageDraw.ImageDraw) -> Image.Image:
        box = Image.new("RGBA", base.size, (0, 0, 0, 0))
        ImageDraw.Draw(box).rounded_rectangle(self.rect, radius=self.pad, fill=DRAW.calibration.caption_box_rgba)
        base = Image.alpha_composite(base, box)
        for k, line in enumerate(self.lines):
            x = self.origin[0] + self.pad
            y = self.origin[1] + self.pad + k * self.line_h
            for text, color in line:
                draw.text((x, y), text, font=self.font, fill=(*color, 255), anchor="la")
                x += draw.textlength(text, font=self.font)
        return base


def _board_rect_px(calibration: Calibration, lens: _Lens) -> tuple[float, float, float, float]:
    """Bounding rectangle of the board's corners and squares, photo pixels."""
    points = [np.asarray(calibration.corners_px, dtype=np.float64).reshape(-1, 2)]
    points += _floor_curves(calibration, lens, [_squares_outline_m(calibration)])
    p = np.vstack(points)
    return (*p.min(axis=0), *p.max(axis=0))


def _corner_spacing_px(calibration: Calibration) -> float:
    return corner_spacing_px(calibration.corners_px, calibration.corner_ids, calibration.board)


def _inset(photo, calibration, lens, style, board_rect, width_px):
    """A magnified view of the board from the untouched photo, corners drawn at that scale.

    The inset is ``width_px`` wide and as tall as the board needs (between 0.3 and 0.7 of
    its width). Returns the inset (RGB) and its zoom factor."""
    x0, y0, x1, y1 = _grow(board_rect, 0.08, 4.0)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    bw, bh = x1 - x0, y1 - y0
    zoom = width_px / bw
    height_px = int(np.clip(bh * zoom, 0.3 * width_px, 0.7 * width_px))
    zoom = min(zoom, height_px / bh)
    # The inset's pixel u shows photo x = left + (u + 0.5) / zoom - 0.5.
    left, top = cx - width_px / zoom / 2, cy - height_px / zoom / 2
    M = np.array([[1 / zoom, 0, left + 0.5 / zoom - 0.5], [0, 1 / zoom, top + 0.5 / zoom - 0.5]])
    view = cv2.warpAffine(photo, M, (int(width_px), height_px), flags=cv2.INTER_CUBIC | cv2.WARP_INVERSE_MAP,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(40, 40, 40))

    def to_inset(p):
        return (np.asarray(p, dtype=np.float64) + 0.5 - [left, top]) * zoom - 0.5

    thin = max(1, round(style.thin * 1.5))
    for curve in _floor_curves(calibration, lens, [_squares_outline_m(calibration)]):
        _polyline(view, to_inset(curve), DRAW.calibration.squares_rgb, thin)
    _draw_corners(view, calibration, style, transform=to_inset, spacing=_corner_spacing_px(calibration) * zoom)
    return view, zoom


def calibration_overlay(image: np.ndarray, calibration: Calibration) -> np.ndarray:
    """The photo with its calibration drawn on it (see the module's docstring).

    Parameters
    ----------
    image : (h, w, 3) uint8
        The calibrated photo, RGB. Not modified.
    calibration : Calibration
        Of this photo: its ``size_px`` must be ``(w, h)``.

    Returns
    -------
    (h, w, 3) uint8
        A new RGB array.

    Raises
    ------
    ValueError
        When the image is not (h, w, 3) uint8 or not the calibrated size.
    """
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise ValueError(f"image of shape {image.shape} and type {image.dtype}: expected (h, w, 3) uint8 RGB")
    h, w = image.shape[:2]
    if (w, h) != tuple(calibration.size_px):
        raise ValueError(f"image is {w}x{h} px but the calibration is of a "
                         f"{calibration.size_px[0]}x{calibration.size_px[1]} photo")
    out = np.ascontiguousarray(image.copy())
    style = _Style((w, h))
    lens = _Lens(calibration)
    labels: list = []
    board_rect = _board_rect_px(calibration, lens)
    small = _corner_spacing_px(calibration) < DRAW.calibration.inset_below_spacing_px
    _draw_grid(out, calibration, lens, style)
    _draw_squares_outline(out, calibration, lens, style)
    horizon = _draw_horizon(out, calibration, lens, style)
    _draw_axes(out, calibration, style, labels)
    _draw_corners(out, calibration, style, light=small)

    margin = max(4, round(0.015 * min(w, h)))
    caption = _Caption(calibration, style, horizon is not None)
    grown = _grow(board_rect, 0.5)
    caption.origin = _place((w, h), caption.size, margin, [grown])
    if small:
        view, zoom = _inset(image, calibration, lens, style, board_rect, round(DRAW.calibration.inset_width * w))
        ih, iw = view.shape[:2]
        x, y = _place((w, h), (iw, ih), margin, [grown, _grow(caption.rect, 0.0, margin)])
        border = max(1, round(1.5 * style.s))
        cv2.rectangle(out, (x - border, y - border), (x + iw - 1 + border, y + ih - 1 + border),
                      (255, 255, 255), -1)
        out[y:y + ih, x:x + iw] = view
        inset_rect = (x, y, x + iw, y + ih)
        labels.append(((x + 0.5 * style.label_px, y + ih - 0.5 * style.label_px),
                       f"board \u00d7{zoom:.2g}", DRAW.calibration.text_rgb, "lb"))
    boxes = [_grow(caption.rect, 0.0, margin)] + ([_grow(inset_rect, 0.0, margin)] if small else [])
    if horizon is not None:
        label = _horizon_label(horizon, (w, h), style, boxes)
        if label is not None:
            labels.append(label)
    return _draw_text(out, caption, style, labels)


def _grow(rect, fraction, pixels=0.0):
    x0, y0, x1, y1 = rect
    gx, gy = fraction * (x1 - x0) + pixels, fraction * (y1 - y0) + pixels
    return (x0 - gx, y0 - gy, x1 + gx, y1 + gy)


def _draw_text(out: np.ndarray, caption: _Caption, style: _Style, labels) -> np.ndarray:
    """The caption box and the labels, drawn with PIL (antialiased TrueType text)."""
    h, w = out.shape[:2]
    label_font = overlay_font(style.label_px)
    base = Image.fromarray(out).convert("RGBA")
    layer = Image.new("RGBA", base.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(layer)
    stroke = max(1, round(style.label_px / 10))
    for (x, y), text, color, anchor in labels:
        if not (-w < x < 2 * w and -h < y < 2 * h):
            continue
        # Keep the label inside the frame.
        left, top, right, bottom = draw.textbbox((x, y), text, font=label_font, anchor=anchor, stroke_width=stroke)
        x += max(0, stroke - left) - max(0, right - (w - 1 - stroke))
        y += max(0, stroke - top) - max(0, bottom - (h - 1 - stroke))
        draw.text((x, y), text, font=label_font, fill=(*color, 255), anchor=anchor,
                  stroke_width=stroke, stroke_fill=(0, 0, 0, 255))
    base = caption.draw(base, draw)
    base = Image.alpha_composite(base, layer)
    return np.asarray(base.convert("RGB"))


__all__ = ["calibration_overlay"]
