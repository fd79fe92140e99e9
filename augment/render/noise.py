"""Seamless procedural noise for textures: band-limited, periodic in both axes.

Textures are sampled with REPEAT wrap, so every field here tiles: white noise is smoothed
with wrap-around filtering on a grid coarse enough for its scale and upsampled with cubic
interpolation (at 512 px a pass over the image costs more than the noise itself).
Image-sized temporaries live in per-thread scratch buffers (:data:`SCRATCH`) because at
512 px fresh ones cost as much in page faults as the arithmetic. Randomness comes only
from the ``rng`` passed in. Used by the furniture's surfaces
(:mod:`augment.render.surfaces`) and the synthetic photographer's floors and walls.
"""
from __future__ import annotations

import math
import threading

import cv2
import numpy as np

# Noise is generated on a grid `step` times coarser than the output, with `step` as
# large as the smoothing scale allows: the Gaussian must still span this many grid
# samples, so that almost nothing is left near the grid's Nyquist frequency and the
# upsampling adds no visible structure of its own.
_MIN_GRID_SIGMA = 1.25
# ... and the grid keeps at least this many samples per axis.
_MIN_GRID_SAMPLES = 8
# Wrapped samples kept around every noise grid: enough for cubic interpolation when a
# coarse grid is refined onto a finer one that keeps the same margin.
_GRID_MARGIN = 4

class _Scratch(threading.local):
    """Work buffers reused from call to call, one set per thread.

    From 512 px up, every image-sized temporary is larger than glibc's mmap threshold,
    so a fresh one comes back from the kernel page by page, and the page faults cost
    as much as the arithmetic. A buffer is asked for by tag and stays valid until the
    same tag is asked for again. Generators run one at a time in a thread, so they
    share tags: ``noise0``..``noise2`` (each with the sub-tags of
    :func:`noise_mix`), ``plane0``.., ``ids`` and ``rgb0``..``rgb2``; only the returned
    images are freshly allocated. Each tag keeps its largest buffer: about 25 MB per
    thread after 512 px textures.
    """

    def __init__(self):
        self._flat = {}

    def array(self, tag, shape, dtype=np.float32):
        size = shape[0] * shape[1]
        key = (tag, np.dtype(dtype))
        flat = self._flat.get(key)
        if flat is None or flat.size < size:
            flat = self._flat[key] = np.empty(size, dtype)
        # The leading part of the flat buffer is C-contiguous in any 2-D shape.
        return flat[:size].reshape(shape)


SCRATCH = _Scratch()


def _grid_step(size_px, sigma_px):
    """Largest divisor of ``size_px`` usable as the coarse-grid spacing for ``sigma_px``."""
    limit = min(sigma_px / _MIN_GRID_SIGMA, size_px / _MIN_GRID_SAMPLES)
    for step in range(int(limit), 1, -1):
        if size_px % step == 0:
            return step
    return 1


def _wrapped_square_sum(kernel, period):
    """Sum of squares of a centred kernel wrapped onto ``period`` samples."""
    if len(kernel) <= period:
        return float(kernel @ kernel)
    radius = len(kernel) // 2
    wrapped = np.bincount((np.arange(len(kernel)) - radius) % period, kernel, period)
    return float(wrapped @ wrapped)


def _noise_grid(rng, size_px, step_y, step_x, sigma_y_px, sigma_x_px, std, tag):
    """White noise on a ``step``-coarser periodic grid, smoothed and normalized.

    Returns the grid with ``_GRID_MARGIN`` wrapped samples on every side (a view into
    the scratch buffer ``tag``), zero mean and standard deviation ``std``.
    """
    rows, cols = size_px // step_y, size_px // step_x
    # Beyond a quarter of the period a periodic field has nothing left to show but its
    # first harmonic, and normalizing what is left would only amplify rounding noise.
    sy, sx = min(sigma_y_px / step_y, rows / 4.0), min(sigma_x_px / step_x, cols / 4.0)
    ry, rx = math.ceil(3.0 * sy), math.ceil(3.0 * sx)
    py, px = ry + _GRID_MARGIN, rx + _GRID_MARGIN
    # uint8 draws are the fastest NumPy offers; 256 levels are plenty for white noise
    # that is smoothed afterwards.
    white = rng.integers(0, 256, (rows, cols), dtype=np.uint8)
    # Wrap padding makes the blur a circular convolution on the interior, and the
    # margin repeats the grid: this is what makes the noise periodic.
    if py <= rows and px <= cols:
        padded = cv2.copyMakeBorder(
            white, py, py, px, px, cv2.BORDER_WRAP,
            dst=SCRATCH.array(tag + ".pad", (rows + 2 * py, cols + 2 * px), np.uint8))
    else:
        padded = np.pad(white, ((py, py), (px, px)), mode="wrap")
    ky = cv2.getGaussianKernel(2 * ry + 1, sy, cv2.CV_64F)
    kx = cv2.getGaussianKernel(2 * rx + 1, sx, cv2.CV_64F)
    # Normalize exactly instead of measuring. The blur is a circular convolution with
    # the kernels wrapped onto the grid; it keeps the grid mean, which is removed (a
    # constant is no texture), and the rest of the output has variance
    # var(white) * (sum(wrapped ky**2) * sum(wrapped kx**2) - 1 / cells).
    sum_y, sum_x = _wrapped_square_sum(ky[:, 0], rows), _wrapped_square_sum(kx[:, 0], cols)
    variance = (256.0 ** 2 - 1.0) / 12.0 * (sum_y * sum_x - 1.0 / (rows * cols))
    scale = std / math.sqrt(variance) if variance > 1e-9 * sum_y * sum_x else 0.0
    # One pass converts, blurs, scales and removes the mean.
    blurred = cv2.sepFilter2D(padded, cv2.CV_32F, kx * scale, ky,
                              dst=SCRATCH.array(tag, padded.shape),
                              delta=-cv2.mean(white)[0] * scale)
    return blurred[ry:ry + rows + 2 * _GRID_MARGIN, rx:rx + cols + 2 * _GRID_MARGIN]


def _reach(factor, out_margin, cubic):
    """Input margin that resizing by ``factor`` reads to fill ``out_margin`` of output.

    OpenCV maps output sample ``j`` to input ``(j + 0.5) / factor - 0.5`` and reads
    taps ``floor - 1 .. floor + 2`` (cubic) or ``floor .. floor + 1`` (linear).
    """
    if factor == 1:
        return out_margin
    low = math.floor((0.5 - out_margin) / factor - 0.5)
    high = math.floor((out_margin - 0.5) / factor - 0.5)
    return max(-low + (1 if cubic else 0), high + (3 if cubic else 2))


def _resize_grid(grid, margin, factor, out_margin, cubic, tag):
    """Resize a periodic grid with wrapped margins by integer factors, keeping it aligned.

    Parameters are per axis ``(y, x)``. The input is cropped to what the kernel reads,
    and the output to ``out_margin`` samples around the refined grid, so that output
    sample ``out_margin`` is the refined grid's sample 0.
    """
    (my, mx), (fy, fx), (oy, ox) = margin, factor, out_margin
    rows, cols = grid.shape[0] - 2 * my, grid.shape[1] - 2 * mx
    ky, kx = _reach(fy, oy, cubic), _reach(fx, ox, cubic)
    src = grid[my - ky:my + rows + ky, mx - kx:mx + cols + kx]
    if fy > 1 or fx > 1:
        shape = (src.shape[0] * fy, src.shape[1] * fx)
        src = cv2.resize(src, shape[::-1], dst=SCRATCH.array(tag, shape),
                         interpolation=cv2.INTER_CUBIC if cubic else cv2.INTER_LINEAR)
    # Input sample k lands on refined coordinate k * factor - reach * factor.
    y0, x0 = ky * fy - oy, kx * fx - ox
    return src[y0:y0 + rows * fy + 2 * oy, x0:x0 + cols * fx + 2 * ox]


def _cubic_factor(factor):
    """Share of an upsampling factor done with cubic interpolation.

    Cubic upsampling by large factors is slow in OpenCV, so it goes to at most four
    times the grid, where the signal is smooth enough for linear interpolation to
    finish the job without visible kinks.
    """
    for f in (4, 3, 2):
        if factor % f == 0:
            return f
    return factor


def _refine(grid, factor, out_margin, tag):
    """Upsample a grid with ``_GRID_MARGIN`` margins by integer ``factor`` (y, x)."""
    a = tuple(_cubic_factor(f) for f in factor)
    b = tuple(f // c for f, c in zip(factor, a))
    m = (_GRID_MARGIN, _GRID_MARGIN)
    if b == (1, 1):
        return _resize_grid(grid, m, a, (out_margin, out_margin), True, tag)
    # The linear stage reads at most one sample beyond what it fills, plus the margin.
    mid = tuple(_reach(f, out_margin, cubic=False) for f in b)
    coarse = _resize_grid(grid, m, a, mid, True, tag + ".cubic")
    return _resize_grid(coarse, mid, b, (out_margin, out_margin), False, tag)


def noise_mix(rng, size_px, layers, tag):
    """Sum of independent periodic noise layers, as one (size_px, size_px) float32 array.

    ``layers`` holds ``((sigma_y_px, sigma_x_px), std)`` pairs. Layers are summed on
    their coarse grids, coarsest first, each refined onto the next finer grid, so that
    only one resize reaches full resolution: at full size every pass over the image
    costs more than the noise itself. The result lives in the scratch buffers ``tag``.
    """
    plans = []
    for (sigma_y_px, sigma_x_px), std in layers:
        if not (sigma_y_px > 0 and sigma_x_px > 0):
            raise ValueError(f"noise scales must be > 0, got {(sigma_y_px, sigma_x_px)}")
        plans.append((_grid_step(size_px, sigma_y_px), _grid_step(size_px, sigma_x_px),
                      sigma_y_px, sigma_x_px, std))
    plans.sort(key=lambda p: -p[0] * p[1])
    total = acc = None
    acc_step = (1, 1)
    for i, (step_y, step_x, sigma_y_px, sigma_x_px, std) in enumerate(plans):
        # Two grid buffers in turn: the previous grid is read while the next is made.
        grid = _noise_grid(rng, size_px, step_y, step_x, sigma_y_px, sigma_x_px, std,
                           f"{tag}.grid{i % 2}")
        if acc is not None and acc_step[0] % step_y == 0 and acc_step[1] % step_x == 0:
            factor = (acc_step[0] // step_y, acc_step[1] // step_x)
            np.add(grid, _refine(acc, factor, _GRID_MARGIN, tag + ".refine"), out=grid)
        elif acc is not None:
            # Grids that do not nest (sizes with few divisors) meet at full resolution.
            full = _refine(acc, acc_step, 0, tag + ".full")
            if total is None:
                total = SCRATCH.array(tag + ".total", full.shape)
                np.copyto(total, full)
            else:
                total += full
        acc, acc_step = grid, (step_y, step_x)
    full = _refine(acc, acc_step, 0, tag + ".full")
    if total is None:
        return full
    total += full
    return total


def periodic_noise(rng, size_px, scale_px, *, octaves=1, persistence=0.5):
    """Seamless band-limited noise: white noise smoothed by a periodic Gaussian.

    Parameters
    ----------
    rng : numpy.random.Generator
        Only source of randomness.
    size_px : int
        Side of the square output in pixels.
    scale_px : float or (float, float)
        Standard deviation in pixels of the Gaussian that smooths the white noise, i.e.
        the correlation length; blobs are roughly ``2 * scale_px`` across. A pair gives
        ``(rows, columns)`` scales for anisotropic noise, e.g. ``(1, 40)`` for streaks
        that run along the image x axis.
    octaves : int, optional
        Number of layers in the fractal sum; layer ``i`` has scale ``scale_px / 2**i``.
    persistence : float, optional
        Amplitude ratio between consecutive layers.

    Returns
    -------
    (size_px, size_px) float32
        Zero mean and standard deviation about 1/3 (in expectation), so values lie in
        [-1, 1] apart from rare tails. Periodic: row 0 continues row -1, column 0
        continues column -1. Scales near the image size leave only the lowest harmonics
        that fit the period.
    """
    size_px = int(size_px)
    if size_px < 1:
        raise ValueError(f"size_px must be >= 1, got {size_px}")
    scale_y_px, scale_x_px = (scale_px, scale_px) if np.isscalar(scale_px) else scale_px
    if octaves < 1:
        raise ValueError(f"octaves must be >= 1, got {octaves}")
    amplitudes = persistence ** np.arange(octaves)
    # The layers are independent, so their variances add.
    amplitudes = amplitudes / (3.0 * math.sqrt(float((amplitudes ** 2).sum())))
    layers = [((scale_y_px / 2 ** i, scale_x_px / 2 ** i), float(a))
              for i, a in enumerate(amplitudes)]
    # A copy: the mix lives in scratch buffers that the next call overwrites.
    return np.array(noise_mix(rng, size_px, layers, "noise0"), dtype=np.float32)


def octave_layers(scale_px, std, octaves, persistence=0.5):
    """Layers for :func:`noise_mix`: a fractal sum with total standard deviation ``std``."""
    scale_y_px, scale_x_px = (scale_px, scale_px) if np.isscalar(scale_px) else scale_px
    amplitudes = persistence ** np.arange(octaves)
    amplitudes = amplitudes * (std / math.sqrt(float((amplitudes ** 2).sum())))
    return [((scale_y_px / 2 ** i, scale_x_px / 2 ** i), float(a))
            for i, a in enumerate(amplitudes)]


def fine_scale(scale_px):
    """Scale for pixel-level noise: below half a pixel the Gaussian is only a delta."""
    return max(0.5, scale_px)


# Darker wood is more saturated and warmer than lighter wood of the same board, so the
# grain shading hits blue hardest and red least.
WOOD_SHADE_GAIN_RGB = (0.85, 1.0, 1.2)


def wood_grain(rng, size_px, px_per_mm, figure, streak):
    """Periodic relative shade of a board surface, grain along x.

    Latewood lines are the level sets of ``y / spacing + warp(x, y)``; a strong, slowly
    varying warp bends them into the elongated loops (cathedrals) of flat-sawn boards.
    """
    # Pores and fibres: long thin streaks. Tone drifts slowly along a board, faster
    # across it.
    shade = noise_mix(rng, size_px, octave_layers(
        (fine_scale(rng.uniform(0.7, 1.4) * px_per_mm), rng.uniform(60.0, 140.0) * px_per_mm),
        streak / 3.0, 2, persistence=0.7) + octave_layers(
        (rng.uniform(20.0, 50.0) * px_per_mm, rng.uniform(150.0, 300.0) * px_per_mm),
        0.1 / 3.0, 2), "noise0")
    warp = noise_mix(rng, size_px, octave_layers(
        (rng.uniform(15.0, 35.0) * px_per_mm, rng.uniform(200.0, 450.0) * px_per_mm),
        1.0 / 3.0, 2), "noise1")
    # Where the warp is strong the lines loop into cathedrals (flat-sawn), where it is
    # weak they run straight (rift-sawn): let its strength wander so planks differ.
    strength = noise_mix(rng, size_px, [((rng.uniform(150.0, 300.0) * px_per_mm,) * 2,
                                          1.0 / 3.0)], "noise2")
    np.abs(strength, out=strength)
    strength *= np.float32(2.0 * math.pi * rng.uniform(2.0, 7.0))
    strength += np.float32(2.0 * math.pi * rng.uniform(0.3, 1.0))
    # A whole number of rings per repeat keeps the y term periodic.
    rings = max(1, round(size_px / (rng.uniform(5.0, 14.0) * px_per_mm)))
    y = np.arange(size_px, dtype=np.float32) * np.float32(2.0 * math.pi * rings / size_px)
    line = np.multiply(warp, strength, out=warp)
    line += y[:, None]
    np.cos(line, out=line)
    line += np.float32(1.0)
    line *= np.float32(0.5)
    line *= line
    line *= line
    # E[((1 + cos) / 2)^4] = 35/128: subtracting it keeps the mean tone at the base color.
    line -= np.float32(35.0 / 128.0)
    line *= np.float32(-figure)
    shade += line
    return shade
