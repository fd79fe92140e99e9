"""Images to file bytes: one encoder for every picture Stager writes.

Images are RGB ``(h, w, 3)``, RGBA ``(h, w, 4)`` or grey ``(h, w)`` uint8 arrays.
"""
from __future__ import annotations

import cv2
import numpy as np

JPEG_QUALITY = 92  # staged photos: no visible loss, about a third of the PNG's size


def encode_image(image: np.ndarray, ext: str, quality: int = JPEG_QUALITY) -> bytes:
    """The bytes of a ``.jpg`` (at ``quality``) or ``.png`` file of ``image``."""
    a = np.asarray(image)
    if a.dtype != np.uint8 or not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise ValueError(f"image must be (h, w), (h, w, 3) or (h, w, 4) uint8, got shape {a.shape} dtype {a.dtype}")
    if a.ndim == 3:
        a = cv2.cvtColor(a, cv2.COLOR_RGBA2BGRA if a.shape[2] == 4 else cv2.COLOR_RGB2BGR)
    params = [cv2.IMWRITE_JPEG_QUALITY, int(quality)] if ext == ".jpg" else []
    ok, data = cv2.imencode(ext, a, params)
    if not ok:
        raise RuntimeError(f"OpenCV could not encode an image as {ext}")
    return data.tobytes()
