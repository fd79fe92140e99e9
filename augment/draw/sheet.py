"""The contact sheet: the staged photos side by side, numbered."""
from __future__ import annotations

import math

import cv2
import numpy as np

from .fonts import overlay_font
from .settings import DRAW


def contact_sheet(images: list, labels: list | None = None, tile_px: int | None = None,
                  gap_px: int | None = None) -> np.ndarray:
    """The images side by side (two per row from four on), each scaled to
    ``tile_px`` wide and numbered from 1 (or labelled) in its top-left corner.

    Parameters
    ----------
    images : list of (h, w, 3) uint8
        Of one size.
    labels : list of str, optional
    tile_px, gap_px : int, optional
        Default ``DRAW.sheet.tile_px`` and ``DRAW.sheet.gap_px`` (:mod:`augment.draw.settings`).

    Returns
    -------
    (H, W, 3) uint8
    """
    from PIL import Image, ImageDraw

    tile_px = DRAW.sheet.tile_px if tile_px is None else tile_px
    gap_px = DRAW.sheet.gap_px if gap_px is None else gap_px
    n = len(images)
    if n == 0:
        raise ValueError("contact sheet of no images")
    cols = n if n <= 3 else math.ceil(math.sqrt(n))
    rows = math.ceil(n / cols)
    h, w = images[0].shape[:2]
    tw = min(tile_px, w)
    th = round(h * tw / w)
    gap = gap_px
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
