"""Woven patterns of rugs: a base-colour image the size of the rug, made from its colours.

A rug is seen whole, so its pattern is one image across it rather than a repeating
surface: a medallion rug (a border band of small diamonds between guard lines, a central
lozenge, corner spandrels), a trellis (a lattice of diamonds over the field) or a kilim
(rows of stepped diamonds). Edges are woven: they step from knot to knot (``knot_m``),
as a pile rug's motifs do. The rug's pile (:func:`augment.render.surfaces.surface`
``"rug"``) is woven in, so one image carries both.
"""
from __future__ import annotations

import functools

import cv2
import numpy as np

from .surfaces import GAMMA, surface

PATTERNS = ("medallion", "trellis", "kilim")


def _knotted(coord_m, knot_m):
    """Coordinates (about the rug's middle) snapped to the knot grid, alike either side
    of the middle: motifs' edges step as woven ones do, and stay symmetric."""
    return np.sign(coord_m) * (np.floor(np.abs(coord_m) / knot_m) + 0.5) * knot_m


def rug_pattern(pattern: str, colours_srgb, size_m, rng: np.random.Generator, mm_per_px: float = 4.0,
                knot_m: float = 0.012) -> np.ndarray:
    """The pattern of a rug, (rows, cols, 3) uint8 sRGB: columns across its width, rows
    along its depth.

    Parameters
    ----------
    pattern : str
        One of :data:`PATTERNS`.
    colours_srgb : (3, 3) array_like
        Field, ground of the motifs and accent, sRGB 0-255.
    size_m : (2,) float
        Width and depth of the rug, meters.
    rng : numpy.random.Generator
        Varies the motifs' size and count.
    mm_per_px : float
        The image's resolution.
    knot_m : float
        The steps of the motifs' edges.
    """
    label = rug_labels(pattern, size_m, rng, mm_per_px, knot_m)
    rows, cols = label.shape
    # The pile woven in: its detail (linear multiplier, mean about 0.8) divided by its mean
    # so the colours stay the rug's on average. Encoded (power 1 / 2.2) a product is the
    # product of the encoded factors: no powers per pixel.
    detail = _pile(round(surface("rug").tile_m * 1000 / mm_per_px))
    detail = np.tile(detail, (rows // len(detail) + 1, cols // len(detail) + 1, 1))[:rows, :cols]
    colour = np.asarray(colours_srgb, dtype=np.float32).reshape(3, 3)[label]
    return np.clip(colour * detail + 0.5, 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=4)
def _pile(tile_px: int) -> np.ndarray:
    """The rug surface's detail at ``tile_px`` a repeat, encoded and over its mean's
    encoding: (tile_px, tile_px, 3) float32 factors for encoded colours."""
    pile = surface("rug")
    detail = cv2.resize(pile.image, (max(2, tile_px),) * 2, interpolation=cv2.INTER_AREA).astype(np.float32)
    return detail / 255.0 / np.asarray(pile.mean_rgb, dtype=np.float32) ** (1 / GAMMA)


def rug_labels(pattern: str, size_m, rng: np.random.Generator, mm_per_px: float = 4.0,
               knot_m: float = 0.012) -> np.ndarray:
    """Which colour each pixel of :func:`rug_pattern` takes, (rows, cols) int: 0 the
    field, 1 the ground of the motifs, 2 the accent."""
    if pattern not in PATTERNS:
        raise ValueError(f"rug pattern {pattern!r}: choose one of {', '.join(PATTERNS)}")
    W, D = (float(v) for v in size_m)
    cols, rows = max(8, round(W * 1000 / mm_per_px)), max(8, round(D * 1000 / mm_per_px))
    x = _knotted((np.arange(cols) - (cols - 1) / 2) * (W / cols), knot_m)[None, :]  # exactly mirrored about 0
    y = _knotted((np.arange(rows) - (rows - 1) / 2) * (D / rows), knot_m)[:, None]
    ax, ay = np.abs(x), np.abs(y)
    label = np.zeros((rows, cols), np.int64)  # 0 field, 1 ground, 2 accent
    short = min(W, D)
    band = rng.uniform(0.08, 0.12) * short  # the border's width
    inner = np.minimum(W / 2 - ax, D / 2 - ay)  # distance in from the rug's edge
    if pattern == "medallion":
        in_band = (inner > 0.02) & (inner < 0.02 + band)
        label[in_band] = 1
        guard = knot_m * 1.5
        label[(np.abs(inner - 0.02) < guard / 2) | (np.abs(inner - 0.02 - band) < guard / 2)] = 2
        # Small diamonds along the band's middle.
        pitch = rng.uniform(0.07, 0.1)
        mid = inner - 0.02 - band / 2
        along = np.where(W / 2 - ax < D / 2 - ay, y, x)
        local = np.abs((along + pitch / 2) % pitch - pitch / 2)
        label[in_band & (local / (0.3 * pitch) + np.abs(mid) / (0.3 * band) < 1)] = 2
        # The field: a lozenge in the middle, an accent lozenge within, corner spandrels.
        fw, fd = W / 2 - 0.02 - band, D / 2 - 0.02 - band
        size = rng.uniform(0.45, 0.6)
        lozenge = ax / (size * fw) + ay / (size * fd)
        label[lozenge < 1] = 1
        label[(lozenge > 0.93) & (lozenge < 1)] = 2
        label[lozenge < 0.45] = 2
        label[lozenge < 0.25] = 0
        corner = ((fw - ax) / (0.35 * fw)) ** 2 + ((fd - ay) / (0.35 * fd)) ** 2
        label[(inner >= 0.02 + band) & (corner < 1)] = 1
        label[(inner >= 0.02 + band) & (corner > 0.85) & (corner < 1)] = 2
    elif pattern == "trellis":
        pitch = rng.uniform(0.22, 0.32)
        line = 0.018
        u, v = (x + y) / pitch, (x - y) / pitch
        on = (np.abs(u - np.round(u)) * pitch < line / 2) | (np.abs(v - np.round(v)) * pitch < line / 2)
        label[on] = 2
        label[(inner > 0.03) & (inner < 0.03 + knot_m * 2)] = 2
    else:  # kilim: rows of stepped diamonds across the rug, alternating ground and accent
        count = int(rng.integers(4, 7))
        h = D / count
        row = np.floor((y + D / 2) / h)
        local_y = (y + D / 2) - (row + 0.5) * h
        n_across = max(2, round(W / h))
        w = W / n_across
        local_x = np.abs((x + W / 2) % w - w / 2)
        diamond = local_x / (0.42 * w) + np.abs(local_y) / (0.42 * h)
        label[diamond < 1] = np.where(row % 2 == 0, 1, 2).repeat(cols, axis=1)[diamond < 1]
        label[diamond < 0.45] = 0
        label[(inner > 0.0) & (inner < 0.02 + knot_m)] = 1
    return label
