"""Datasets of synthetic photos: one GL context per worker process, a contact sheet.

The worker functions live here, not in ``__main__``, because spawned processes import
them by module name.
"""
from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from .truth import overlay

_worker = {}


def init_worker(options: dict) -> None:
    # Each process owns one GL context; it is made here, after the fork/spawn.
    from ..render.gl import Renderer

    _worker["renderer"] = Renderer()
    _worker["options"] = options


def render_one(index: int) -> tuple[int, dict]:
    from . import render_sample, write_sample

    o = _worker["options"]
    sample = render_sample([o["seed"], index], _worker["renderer"], size_px=o["size"], board=o["board"],
                           clutter=o["clutter"], furnished=o.get("furnished", 0.0),
                           baseboard_m=o["baseboard_m"], trim_like_floor=o.get("trim_like_floor", 0.0),
                           trim_dark=o.get("trim_dark", 0.0), low_sun=o.get("low_sun", 0.0),
                           two_floors=o.get("two_floors", 0.0), far_floor=o.get("far_floor", 0.0))
    paths = write_sample(sample, o["out"], f"{index:05d}")
    return index, {k: str(v) for k, v in paths.items()}


def contact_sheet(images: list[np.ndarray], columns: int = 4, cell_px: tuple[int, int] = (320, 240)) -> np.ndarray:
    """Tile images (any sizes and orientations) into a grid, each fitted into its cell.

    Returns
    -------
    sheet : (rows * cell_h + gaps, columns * cell_w + gaps, 3) uint8
    """
    cw, ch = cell_px
    gap = 6
    rows = -(-len(images) // columns)
    sheet = np.full((rows * (ch + gap) + gap, columns * (cw + gap) + gap, 3), 255, np.uint8)
    for k, image in enumerate(images):
        h, w = image.shape[:2]
        scale = min(cw / w, ch / h)
        small = cv2.resize(image, (max(1, round(w * scale)), max(1, round(h * scale))), interpolation=cv2.INTER_AREA)
        r, c = divmod(k, columns)
        y = gap + r * (ch + gap) + (ch - small.shape[0]) // 2
        x = gap + c * (cw + gap) + (cw - small.shape[1]) // 2
        sheet[y:y + small.shape[0], x:x + small.shape[1]] = small
    return sheet


def truth_view(folder, stem: str) -> np.ndarray:
    """A written sample's photo with its floor mask tinted and board corners marked (BGR)."""
    folder = Path(folder)
    truth = json.loads((folder / f"{stem}.json").read_text())
    photo = cv2.imread(str(folder / truth["image"]))
    mask = cv2.imread(str(folder / truth["floor_mask"]), cv2.IMREAD_GRAYSCALE) > 127
    corners = np.array(truth["board"]["corners_px"])[np.array(truth["board"]["corners_visible"])]
    return overlay(photo[..., ::-1], mask, corners)[..., ::-1]
