"""The photo's camera on the furniture: its noise and its sharpness.

A render is cleaner and sharper than any photo: no sensor noise, edges antialiased over
a fraction of a pixel. Pasted as it is, furniture reads as pasted. :func:`estimate_look`
measures what the photo's camera did (the noise left after demosaicing and JPEG in the
photo's flattest parts; the edge spread of the board's printed squares, whose edges are
known to be sharp), and :func:`apply_look` does the same to the rendered layer.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numba import njit, prange
from scipy.optimize import curve_fit
from scipy.special import ndtr

from .settings import RENDER, LookSettings

# Immerkær's operator: the difference of two Laplacians, blind to planes and ramps; for
# white noise of std s the mean of its absolute response is s * 6 / sqrt(pi / 2).
_NOISE_KERNEL = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)
_NOISE_SCALE = math.sqrt(math.pi / 2.0) / 6.0


@dataclass(frozen=True)
class PhotoLook:
    """How the photo's camera recorded the scene.

    Attributes
    ----------
    noise_rgb : (3,) tuple of float
        Standard deviation of the photo's pixel noise per channel, 8-bit levels, as it
        shows in the flattest parts of the photo (after demosaicing and JPEG).
    blur_px : float
        Gaussian sigma of the photo's edge spread, photo pixels (the board's printed
        edges); 0 when unknown.
    edges : int
        How many profiles across the board's printed edges gave the blur (0: none).
    """

    noise_rgb: tuple
    blur_px: float
    edges: int

    def to_json(self) -> dict:
        return {"noise_rgb": [round(v, 2) for v in self.noise_rgb], "blur_px": round(self.blur_px, 2),
                "edges": self.edges}


CLEAN = PhotoLook((0.0, 0.0, 0.0), 0.0, 0)


def estimate_noise(image: np.ndarray, settings: LookSettings | None = None) -> tuple:
    """Per-channel noise std (8-bit levels) of an RGB photo.

    The photo is cut into blocks (``settings.noise_block_px`` square); the share of them
    with the least structure (the gradient of the photo shrunk 4x, which noise hardly
    moves) are the flattest parts (walls, ceiling, plain floor). Their mean response to a
    noise operator that planes and ramps do not excite is the noise. Blocks with clipped
    pixels are left out: clipping hides the noise.

    Parameters
    ----------
    image : (h, w, 3) uint8
        Not modified.
    settings : LookSettings, optional
        Default ``RENDER.look``.

    Returns
    -------
    (3,) tuple of float
    """
    settings = RENDER.look if settings is None else settings
    block_px = settings.noise_block_px
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
        raise ValueError(f"image must be (h, w, 3) uint8, got shape {image.shape} dtype {image.dtype}")
    rows, cols = image.shape[0] // block_px, image.shape[1] // block_px
    if rows * cols == 0:
        return (0.0, 0.0, 0.0)
    tiles = image[:rows * block_px, :cols * block_px].reshape(rows, block_px, cols, block_px, 3).swapaxes(1, 2)
    low, high = settings.unclipped_levels
    unclipped = cv2.inRange(image[:rows * block_px, :cols * block_px], (low,) * 3, (high,) * 3)
    clipped = cv2.resize(unclipped, (cols, rows), interpolation=cv2.INTER_AREA) < 255
    if clipped.all():
        return (0.0, 0.0, 0.0)
    # Structure per block at a quarter of the block's resolution: smooth, and fast on 12 MP.
    grey = cv2.resize(cv2.cvtColor(image[:rows * block_px, :cols * block_px], cv2.COLOR_RGB2GRAY), (cols * 4, rows * 4),
                      interpolation=cv2.INTER_AREA).astype(np.float32)
    gradient = np.hypot(cv2.Sobel(grey, cv2.CV_32F, 1, 0), cv2.Sobel(grey, cv2.CV_32F, 0, 1))
    structure = cv2.resize(gradient, (cols, rows), interpolation=cv2.INTER_AREA)
    structure[clipped] = np.inf
    order = np.argsort(structure, axis=None)[:max(1, int(settings.noise_flat_share * (~clipped).sum()))]
    a = tiles[np.unravel_index(order, (rows, cols))].astype(np.float32)  # (n, B, B, 3)
    k = _NOISE_KERNEL
    response = sum(k[i, j] * a[:, i:block_px - 2 + i, j:block_px - 2 + j] for i in range(3) for j in range(3))
    return tuple(float(v) * _NOISE_SCALE for v in np.abs(response).mean(axis=(0, 1, 2)))


def _edge(d, low, high, centre, sigma):
    return low + (high - low) * ndtr((d - centre) / sigma)


def edge_sigma(profile: np.ndarray, step_px: float = 1.0, settings: LookSettings | None = None):
    """Gaussian sigma (pixels) of a dark-to-bright step sampled every ``step_px`` along
    ``profile`` (n,), and its contrast (levels); None when it is no clean step."""
    settings = RENDER.look if settings is None else settings
    profile = np.asarray(profile, np.float64)
    d = np.arange(len(profile)) * step_px
    low, high = float(np.median(profile[:3])), float(np.median(profile[-3:]))
    if high - low < settings.edge_min_contrast:
        return None
    try:
        (lo, hi, c, s), _ = curve_fit(_edge, d, profile, p0=(low, high, d.mean(), 1.0),
                                      bounds=((-50, 0, d[2], 0.05), (300, 350, d[-3], 0.25 * d[-1])))
    except (RuntimeError, ValueError):
        return None
    residual = float(np.sqrt(np.mean((_edge(d, lo, hi, c, s) - profile) ** 2)))
    if residual > settings.edge_max_residual * (hi - lo):
        return None
    return float(s), float(hi - lo)


def estimate_blur(image: np.ndarray, calibration, settings: LookSettings | None = None) -> tuple[float, int]:
    """The photo's edge spread (Gaussian sigma, pixels) from the board's outer squares.

    The black squares along the edge of the printed pattern meet white paper (or the
    floor) in a straight, sharp edge; two profiles across each, perpendicular in the
    photo, are fitted with a blurred step. Returns the median sigma and how many
    profiles gave a clean step ((0.0, 0) when fewer than ``settings.edge_min_count`` did).
    """
    settings = RENDER.look if settings is None else settings
    step_px = settings.edge_step_px
    board = calibration.board
    s = board.square_m
    half = np.array([(board.cols + 1) * s / 2, (board.rows + 1) * s / 2])
    K = np.asarray(calibration.intrinsics.K, np.float64)
    dist = np.asarray(calibration.intrinsics.distortion, np.float64).ravel()
    pose = np.asarray(calibration.camera_from_floor, np.float64)
    rvec = cv2.Rodrigues(pose[:3, :3])[0]

    def project(points):
        px, _ = cv2.projectPoints(np.asarray(points, np.float64).reshape(-1, 1, 3), rvec, pose[:3, 3], K, dist)
        return px.reshape(-1, 2)

    grey = cv2.cvtColor(np.asarray(image), cv2.COLOR_RGB2GRAY).astype(np.float32)
    h, w = grey.shape
    sigmas = []
    # Each side of the pattern: (axis along the edge, outward sign).
    for along, sign in ((0, -1), (0, 1), (1, -1), (1, 1)):
        across = 1 - along
        count = (board.cols if along == 0 else board.rows) + 1
        for k in range(count):
            for t in (0.35, 0.65):
                p = np.zeros(3)
                p[along] = -half[along] + (k + t) * s
                p[across] = sign * half[across]
                inside, outside = p.copy(), p.copy()
                inside[across] -= sign * 0.35 * s
                outside[across] += sign * 0.25 * s  # the A3 sheet's narrow margin is 0.3 square
                a, b, c = project([inside, p, outside])
                normal = c - a
                length = float(np.linalg.norm(normal))
                if length < settings.edge_min_span_px:
                    continue  # squares too small in the photo to see their edge
                normal /= length
                n_in, n_out = float(np.dot(b - a, normal)), float(np.dot(c - b, normal))
                d = np.arange(-n_in, n_out, step_px)
                pts = b[None, :] + d[:, None] * normal[None, :]
                if (pts < 1).any() or (pts[:, 0] > w - 2).any() or (pts[:, 1] > h - 2).any():
                    continue
                profile = cv2.remap(grey, pts[:, 0].astype(np.float32)[None, :], pts[:, 1].astype(np.float32)[None, :],
                                    cv2.INTER_LINEAR)[0]
                fit = edge_sigma(profile, step_px, settings)
                if fit is not None:
                    sigmas.append(fit[0])
    if len(sigmas) < settings.edge_min_count:
        return 0.0, 0
    return float(np.median(sigmas)), len(sigmas)


def estimate_look(image: np.ndarray, calibration=None) -> PhotoLook:
    """The photo's noise (:func:`estimate_noise`) and, with a calibration whose board is
    in it, its sharpness (:func:`estimate_blur`).

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo as taken, board and all (not modified).
    calibration : Calibration, optional
    """
    noise = estimate_noise(image)
    blur, edges = (0.0, 0) if calibration is None else estimate_blur(image, calibration)
    return PhotoLook(noise, blur, edges)


def apply_look(rgba: np.ndarray, look: PhotoLook, render_blur_px: float, seed: int = 0,
               settings: LookSettings | None = None) -> np.ndarray:
    """The rendered layer recorded as the photo's camera would have: blurred up to the
    photo's edge spread, and the photo's noise added where the furniture covers.

    Parameters
    ----------
    rgba : (h, w, 4) uint8
        Premultiplied render at photo resolution (not modified). Blurring it premultiplied
        softens the silhouette against the photo as a lens does.
    look : PhotoLook
    render_blur_px : float
        The render's own edge spread (Gaussian sigma, photo pixels).
    seed : int
        Of the noise: the same seed gives the same staged photo.
    settings : LookSettings, optional
        Default ``RENDER.look``.

    Returns
    -------
    (h, w, 4) uint8
    """
    settings = RENDER.look if settings is None else settings
    out = blur_like_photo(rgba, look, render_blur_px, settings)
    if max(look.noise_rgb) > settings.min_noise_levels:
        rng = np.random.default_rng(seed)
        n = settings.noise_tile_px
        tile = rng.standard_normal((n, n, 3), dtype=np.float32) * np.asarray(look.noise_rgb, np.float32)
        _add_noise(out, tile, int(rng.integers(n)), int(rng.integers(n)))
    return out


def blur_like_photo(image: np.ndarray, look: PhotoLook, render_blur_px: float,
                    settings: LookSettings | None = None) -> np.ndarray:
    """A copy of a render-sized ``image`` (h, w) or (h, w, c) blurred from the render's edge
    spread (``render_blur_px``, photo pixels) up to the photo's: what :func:`apply_look`
    does to the layer, for planes that go with it."""
    settings = RENDER.look if settings is None else settings
    extra = math.sqrt(max(look.blur_px ** 2 - render_blur_px ** 2, 0.0))
    return cv2.GaussianBlur(image, (0, 0), extra) if extra > settings.min_extra_blur_px else image.copy()


@njit(cache=True, parallel=True)
def _add_noise(rgba, tile, dy, dx):
    """Add ``tile`` (repeated, shifted by dy, dx) times alpha to premultiplied ``rgba`` in
    place, clipped to [0, alpha]."""
    h, w = rgba.shape[:2]
    t = tile.shape[0]
    for y in prange(h):
        ty = (y + dy) % t
        for x in range(w):
            a = rgba[y, x, 3]
            if a == 0:
                continue
            tx = (x + dx) % t
            for c in range(3):
                v = rgba[y, x, c] + tile[ty, tx, c] * (a / 255.0)
                rgba[y, x, c] = np.uint8(min(max(v, 0.0), float(a)) + 0.5)
