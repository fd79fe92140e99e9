"""A picture of a wall-height measurement, drawn over its photo.

:func:`height_overlay` draws, on a copy of the photo:

* every measured candidate: vertical edges and wall--ceiling lines that stood on the floor,
  the ones the estimate was taken from thick (edges green, wall--ceiling lines cyan), the
  others thin and grey, each from its base (a dot, where it meets the floor) to its top
  (a tick); the inliers labeled with their height; when the height was not measured, the
  edge whose top bounds it from below (``at_least_m``: a door's casing) thick in amber,
  labeled "at least";
* a caption box in a corner clear of the measured edges (top left when it can): the wall
  height and its confidence, or the fallback and why.

Conventions: images are RGB ``(h, w, 3)`` uint8 arrays; colors are RGB
(:mod:`augment.draw.settings`). Points in a :class:`~augment.room.height.HeightResult` are
undistorted pixels; they are bent by the lens distortion before drawing, like the photo's
own lines.
"""
from __future__ import annotations

import cv2
import numpy as np
from PIL import Image, ImageDraw

from ..camera.calibration import Calibration
from ..room.height import HeightResult
from .fonts import overlay_font
from .settings import DRAW


def _distorted(points: np.ndarray, calibration: Calibration) -> np.ndarray:
    """Undistorted pixels (k, 2) to the photo's (distorted) pixels."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    intr = calibration.intrinsics
    if len(points) == 0 or not np.any(intr.distortion):
        return points
    rays = np.column_stack([points, np.ones(len(points))]) @ np.linalg.inv(intr.K).T
    px, _ = cv2.projectPoints(rays.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), intr.K, intr.distortion)
    return px.reshape(-1, 2)


def height_overlay(image: np.ndarray, calibration: Calibration, result: HeightResult) -> np.ndarray:
    """Draw a height measurement over its photo.

    Parameters
    ----------
    image : (h, w, 3) or (h, w) uint8
        The photo (RGB or gray). Not modified.
    calibration : Calibration
        The photo's calibration (for the lens distortion); ``size_px`` must match.
    result : HeightResult
        From :func:`augment.room.height.measure_height`.

    Returns
    -------
    overlay : (h, w, 3) uint8
        A new RGB image.
    """
    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim not in (2, 3):
        raise ValueError(f"image of shape {image.shape} and dtype {image.dtype}: expected (h, w[, 3]) uint8")
    out = cv2.cvtColor(image, cv2.COLOR_GRAY2RGB) if image.ndim == 2 else np.array(image[..., :3], copy=True)
    h, w = out.shape[:2]
    if (w, h) != tuple(calibration.size_px):
        raise ValueError(f"image of {w}x{h} px but the calibration is for "
                         f"{calibration.size_px[0]}x{calibration.size_px[1]} px")
    settings = DRAW.height
    side = max(h, w)
    thick = max(2, round(side / settings.px_per_line_width))
    bases = _distorted(result.bases_px, calibration)
    tops = _distorted(result.tops_px, calibration)
    # The bound is the top of one whole edge: its height, copied, equals at_least_m exactly.
    bound = np.zeros(len(bases), bool) if result.at_least_m is None else \
        (result.kinds == "edge") & (result.heights_m == result.at_least_m)
    shown = result.inliers | bound
    order = np.argsort(shown, kind="stable")          # inliers and the bound drawn last, on top
    for i in order:
        if not (np.all(np.isfinite(bases[i])) and np.all(np.isfinite(tops[i]))):
            continue
        inlier = bool(shown[i])
        color = (settings.bound_rgb if bound[i] else settings.ceiling_rgb if result.kinds[i] == "ceiling"
                 else settings.edge_rgb if inlier else settings.other_rgb)
        b, t = tuple(np.round(bases[i]).astype(int)), tuple(np.round(tops[i]).astype(int))
        cv2.line(out, b, t, color, thick if inlier else max(1, thick // 2), cv2.LINE_AA)
        cv2.circle(out, b, thick * (2 if inlier else 1) + 1, color, -1, cv2.LINE_AA)
        tick = np.array([[-1.0, 0.0], [1.0, 0.0]]) * thick * 4 + tops[i]
        cv2.line(out, tuple(np.round(tick[0]).astype(int)), tuple(np.round(tick[1]).astype(int)), color,
                 max(1, thick // 2 + 1), cv2.LINE_AA)

    canvas = Image.fromarray(out)
    draw = ImageDraw.Draw(canvas, "RGBA")
    label_font = overlay_font(max(12, round(side / 55)))
    for i in np.flatnonzero(shown):
        if np.all(np.isfinite(tops[i])) and np.isfinite(result.heights_m[i]):
            x = min(max(tops[i][0] + thick * 5, 0), w - 1)
            y = min(max(tops[i][1] - label_font.size / 2, 0), h - 1)
            label = f"at least {result.heights_m[i]:.2f} m" if bound[i] else f"{result.heights_m[i]:.2f} m"
            draw.text((x, y), label, font=label_font, fill=settings.text_rgb,
                      stroke_width=max(1, thick // 2), stroke_fill=(0, 0, 0))
    title = (f"wall height {result.height_m:.2f} m (fallback)" if result.fallback
             else f"wall height {result.height_m:.2f} m, confidence {result.confidence:.2f}")
    lines = [title] + _wrap(result.reason, 70)
    font = overlay_font(max(12, round(side / 45)))
    pad = round(font.size * 0.5)
    box_w = pad * 2 + max(draw.textlength(s, font=font) for s in lines)
    box_h = pad * 2 + len(lines) * round(font.size * 1.25)
    x0, y0 = _caption_corner(w, h, box_w, box_h, pad, np.vstack([bases[shown], tops[shown]]))
    draw.rectangle((x0, y0, x0 + box_w, y0 + box_h), fill=settings.caption_box_rgba)
    for k, text in enumerate(lines):
        fill = (settings.fallback_rgb if result.fallback else settings.text_rgb) if k == 0 else settings.text_rgb
        draw.text((x0 + pad, y0 + pad + k * round(font.size * 1.25)), text, font=font, fill=fill)
    return np.asarray(canvas).copy()


def _caption_corner(w: int, h: int, box_w: float, box_h: float, pad: int, keep_clear: np.ndarray
                    ) -> tuple[float, float]:
    """The corner for the caption box farthest from the points it must not hide (top left
    when none are near)."""
    corners = [(pad, pad), (w - pad - box_w, pad), (pad, h - pad - box_h), (w - pad - box_w, h - pad - box_h)]
    points = keep_clear[np.all(np.isfinite(keep_clear), axis=1)]
    if len(points) == 0:
        return corners[0]

    def clearance(corner):
        x0, y0 = corner
        dx = np.maximum(np.maximum(x0 - points[:, 0], points[:, 0] - (x0 + box_w)), 0)
        dy = np.maximum(np.maximum(y0 - points[:, 1], points[:, 1] - (y0 + box_h)), 0)
        return float(np.min(np.hypot(dx, dy)))

    scores = [clearance(c) for c in corners]
    best = int(np.argmax(scores))
    return corners[0] if scores[0] >= min(scores[best], 4 * pad) else corners[best]


def _wrap(text: str, width: int) -> list[str]:
    words, lines, line = text.split(), [], ""
    for word in words:
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return lines + ([line] if line else [])
