"""What a phone does to a rendered image: exposure, white balance, vignetting, blur,
sensor noise, JPEG. None of it moves a pixel, so the ground truth stays exact."""
from __future__ import annotations

import cv2
import numpy as np

from .scene import kelvin_rgb


# sRGB-ish gamma 2.2 to linear, for every 8-bit value.
_TO_LINEAR = ((np.arange(256, dtype=np.float32) / 255.0) ** 2.2).astype(np.float32)


def degrade(rng: np.random.Generator, image: np.ndarray) -> tuple[np.ndarray, dict]:
    """Apply random photographic degradations.

    Parameters
    ----------
    image : (h, w, 3) uint8
        sRGB render. Not modified.

    Returns
    -------
    photo : (h, w, 3) uint8
    params : dict
        What was applied, JSON-ready; ``jpeg_quality`` is for the writer.
    """
    h, w = image.shape[:2]
    linear = _TO_LINEAR[image]
    exposure_ev = float(np.clip(rng.normal(0.0, 0.3), -0.7, 0.7))
    # Auto white balance that missed: the illuminant it assumed vs 6500 K, plus a green tint.
    assumed_k = float(rng.uniform(4800, 8500))
    gains = kelvin_rgb(6500) / kelvin_rgb(assumed_k)
    gains = gains / gains[1] * np.array([1.0, 1.0 + rng.normal(0, 0.02), 1.0])
    vignetting = float(rng.uniform(0.0, 0.35))
    x2 = ((np.arange(w, dtype=np.float32) - (w - 1) / 2) ** 2)[None, :]
    y2 = ((np.arange(h, dtype=np.float32) - (h - 1) / 2) ** 2)[:, None]
    scale = np.float32(2.0 ** exposure_ev) * (1.0 - np.float32(vignetting / ((w / 2) ** 2 + (h / 2) ** 2)) * (x2 + y2))
    linear *= scale[..., None]
    linear *= gains.astype(np.float32)
    out = cv2.pow(np.clip(linear, 0, 1, out=linear), 1 / 2.2)

    blur_sigma_px = float(rng.uniform(0.0, 1.0)) * max(1.0, max(h, w) / 1000)
    if blur_sigma_px > 0.3:
        out = cv2.GaussianBlur(out, (0, 0), blur_sigma_px)
    # Sensor noise: a read-noise floor plus shot noise growing with the signal.
    read_std = float(rng.uniform(0.002, 0.012))
    shot_k = float(rng.uniform(0.0, 0.03))
    std = np.sqrt(read_std ** 2 + shot_k ** 2 * out)
    out = out + std * rng.standard_normal(out.shape, dtype=np.float32)
    photo = np.clip(out * 255 + 0.5, 0, 255).astype(np.uint8)
    params = {
        "exposure_ev": round(exposure_ev, 4),
        "white_balance_gains": np.round(gains, 4).tolist(),
        "vignetting": round(vignetting, 4),
        "blur_sigma_px": round(blur_sigma_px, 4) if blur_sigma_px > 0.3 else 0.0,
        "read_noise": round(read_std, 5),
        "shot_noise": round(shot_k, 5),
        "jpeg_quality": int(rng.integers(70, 96)),
    }
    return photo, params


def save_as_phone(path, image: np.ndarray, focal_px: float, quality: int) -> None:
    """Save a sample's photo as a phone would: JPEG at ``quality`` with the 35 mm
    equivalent focal length in EXIF (what ``stage`` reads the focal length from).

    Parameters
    ----------
    image : (h, w, 3) uint8
        RGB. Not modified.
    focal_px : float
        The render's focal length, pixels.
    """
    from PIL import Image

    from ..photo.exif import focal_35mm

    exif = Image.Exif()
    exif.get_ifd(0x8769)[0xA405] = focal_35mm(focal_px, image.shape[1::-1])
    Image.fromarray(image).save(path, quality=int(quality), exif=exif)
