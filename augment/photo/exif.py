"""What a photo's EXIF says: its orientation and the lens's focal length."""
from __future__ import annotations

import numpy as np

from .io import pillow_open

# 35 mm film's diagonal: "35 mm equivalent" focal lengths are scaled by diagonals.
_FILM_DIAGONAL_MM = float(np.hypot(36.0, 24.0))


def _exif(path) -> tuple[dict, dict]:
    """The EXIF tags of an image file (HEIC too): its main directory and its Exif
    sub-directory, both empty when it has none or cannot be opened."""
    try:
        with pillow_open(path) as im:
            exif = im.getexif()
            return dict(exif), dict(exif.get_ifd(0x8769))
    except (OSError, ValueError):
        return {}, {}


def exif_focal_px(path, size_px: tuple[int, int]) -> float | None:
    """Focal length in pixels from the EXIF 35 mm equivalent focal length, or None."""
    main, sub = _exif(path)
    f35 = sub.get(0xA405) or main.get(0xA405)
    if not f35:
        return None
    return float(f35) / _FILM_DIAGONAL_MM * float(np.hypot(*size_px))


def focal_35mm(focal_px: float, size_px: tuple[int, int]) -> int:
    """The EXIF 35 mm equivalent focal length (whole mm) of a focal length in pixels: the
    inverse of :func:`exif_focal_px`."""
    return int(round(focal_px * _FILM_DIAGONAL_MM / float(np.hypot(*size_px))))


def exif_orientation(path) -> int | None:
    """The EXIF orientation tag of an image file (1-8), or None."""
    value = _exif(path)[0].get(0x0112)
    return int(value) if value else None
