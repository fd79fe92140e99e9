"""Procedural, seamlessly tiling textures for synthetic empty-room renders.

The renderer samples these images with REPEAT wrap, so every image here is periodic in
both axes: its left edge continues its right edge and its top edge continues its bottom
edge. Periodicity comes from construction, never from blending seams afterwards: noise is
white noise smoothed with wrap-around filtering, and plank and tile layouts place their
joints so that the pattern wraps consistently.

Each generator also returns ``tile_m``, the physical width in meters that one repeat of
the image covers, so that planks and tiles come out at believable real sizes. Feature
sizes are drawn in meters or millimeters and converted to pixels with
``px_per_m = size_px / tile_m``.

Images are ``(size_px, size_px, 3)`` uint8 in sRGB, channel order RGB (convert before
``cv2.imwrite``). Randomness comes only from the ``rng`` passed in: the same generator
state gives the same image.

The textures are made per rendered image, so they are written for speed: noise is
generated on a grid coarse enough for its scale and upsampled with cubic interpolation,
per-plank and per-tile values are looked up with ``cv2.LUT`` on uint8 id maps, color is
kept as three planes because NumPy broadcasting over a trailing axis of length 3 is an
order of magnitude slower than plane-wise arithmetic, and image-sized temporaries live
in per-thread scratch buffers (:class:`_Scratch`) because at 512 px fresh ones cost as
much in page faults as the arithmetic does. The functions are thread-safe.
"""
from __future__ import annotations

import colorsys
import math
import threading
from dataclasses import dataclass

import cv2
import numpy as np

FLOOR_KINDS = ("wood", "tiles", "carpet", "concrete", "laminate")

# Plank and tile layouts need a few pixels per plank or tile to mean anything.
_MIN_SIZE_PX = 16

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

# Darker wood is more saturated and warmer than lighter wood of the same board, so the
# grain shading hits blue hardest and red least.
_WOOD_SHADE_GAIN_RGB = (0.85, 1.0, 1.2)

# name, base sRGB, plank-to-plank tone sd (log), figure contrast, streak contrast,
# probability of knots.
_WOOD_SPECIES = (
    ("oak", (182, 138, 92), 0.08, 0.30, 0.20, 0.5),
    ("light oak", (206, 172, 128), 0.07, 0.25, 0.16, 0.4),
    ("walnut", (108, 72, 48), 0.12, 0.30, 0.22, 0.3),
    ("maple", (222, 194, 150), 0.05, 0.12, 0.10, 0.1),
    ("cherry", (160, 94, 60), 0.08, 0.18, 0.15, 0.2),
    ("ash", (204, 184, 150), 0.07, 0.32, 0.18, 0.3),
    ("hickory", (188, 146, 104), 0.16, 0.28, 0.20, 0.6),
    ("grey-washed", (150, 144, 136), 0.08, 0.30, 0.20, 0.5),
    ("white-washed", (214, 205, 190), 0.05, 0.22, 0.12, 0.4),
    ("dark stained", (82, 56, 40), 0.10, 0.25, 0.20, 0.3),
    ("honey pine", (198, 150, 88), 0.09, 0.35, 0.18, 0.8),
    ("smoked oak", (126, 96, 70), 0.10, 0.28, 0.20, 0.5),
)

# name, tile sRGB choices, veined (marble), per-tile tone sd (log), mottle, speckle.
_TILE_STYLES = (
    ("ceramic", ((238, 236, 231), (232, 226, 214), (226, 214, 190), (214, 198, 170),
                 (198, 198, 194), (150, 150, 148), (92, 92, 94), (40, 40, 42)),
     False, 0.02, 0.03, 0.015),
    ("marble", ((234, 232, 228), (222, 208, 184), (38, 38, 40), (176, 176, 178)),
     True, 0.02, 0.04, 0.01),
    ("terracotta", ((178, 94, 58), (160, 80, 50), (192, 112, 72), (150, 92, 66)),
     False, 0.07, 0.10, 0.04),
    ("stone", ((124, 122, 118), (88, 88, 90), (162, 156, 146), (186, 178, 162)),
     False, 0.04, 0.10, 0.05),
)

_CARPET_COLORS = (
    (128, 126, 122), (160, 156, 148), (96, 96, 98), (188, 176, 156), (168, 150, 124),
    (120, 104, 86), (78, 92, 120), (104, 118, 140), (92, 108, 88), (126, 130, 104),
    (112, 84, 70), (70, 66, 64),
)


class _Scratch(threading.local):
    """Work buffers reused from call to call, one set per thread.

    From 512 px up, every image-sized temporary is larger than glibc's mmap threshold,
    so a fresh one comes back from the kernel page by page, and the page faults cost
    as much as the arithmetic. A buffer is asked for by tag and stays valid until the
    same tag is asked for again. Generators run one at a time in a thread, so they
    share tags: ``noise0``..``noise2`` (each with the sub-tags of
    :func:`_noise_mix`), ``plane0``.., ``ids`` and ``rgb0``..``rgb2``; only the returned
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


_SCRATCH = _Scratch()


def _check_size(size_px):
    if isinstance(size_px, bool) or not isinstance(size_px, (int, np.integer)):
        raise TypeError(f"size_px must be an int, got {type(size_px).__name__}")
    if size_px < _MIN_SIZE_PX:
        raise ValueError(f"size_px must be >= {_MIN_SIZE_PX}, got {size_px}")
    return int(size_px)


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
            dst=_SCRATCH.array(tag + ".pad", (rows + 2 * py, cols + 2 * px), np.uint8))
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
                              dst=_SCRATCH.array(tag, padded.shape),
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
        src = cv2.resize(src, shape[::-1], dst=_SCRATCH.array(tag, shape),
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


def _noise_mix(rng, size_px, layers, tag):
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
                total = _SCRATCH.array(tag + ".total", full.shape)
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
    return np.array(_noise_mix(rng, size_px, layers, "noise0"), dtype=np.float32)


def _octaves(scale_px, std, octaves, persistence=0.5):
    """Layers for :func:`_noise_mix`: a fractal sum with total standard deviation ``std``."""
    scale_y_px, scale_x_px = (scale_px, scale_px) if np.isscalar(scale_px) else scale_px
    amplitudes = persistence ** np.arange(octaves)
    amplitudes = amplitudes * (std / math.sqrt(float((amplitudes ** 2).sum())))
    return [((scale_y_px / 2 ** i, scale_x_px / 2 ** i), float(a))
            for i, a in enumerate(amplitudes)]


def _fine(scale_px):
    """Scale for pixel-level noise: below half a pixel the Gaussian is only a delta."""
    return max(0.5, scale_px)


def _lut(values):
    """256-entry float32 table for ``cv2.LUT`` on uint8 id maps."""
    table = np.zeros(256, np.float32)
    table[:len(values)] = values
    return table


def _shade_to_rgb8(shade, rgb):
    """uint8 RGB image ``rgb * shade``, rounded and saturated; ``shade`` must be >= 0.

    ``convertScaleAbs`` scales, rounds and saturates in one pass per channel; it takes
    absolute values, hence the sign requirement.
    """
    return cv2.merge([cv2.convertScaleAbs(shade, alpha=float(c),
                                          dst=_SCRATCH.array(f"rgb{i}", shade.shape, np.uint8))
                      for i, c in enumerate(rgb)])


# Direction in log-RGB along which natural materials vary in warmth: redder and less
# blue, or the reverse. Independent per-channel jitter would instead turn wood and stone
# green or pink.
_WARMTH_LOG_RGB = np.array([1.0, 0.15, -1.2])


def _jitter_rgb(rng, rgb, sd):
    """Random brightness (log sd ``sd``) and warmth (about ``sd / 2``) of an sRGB color."""
    log_gain = rng.normal(0.0, sd) + rng.normal(0.0, 0.5 * sd) * _WARMTH_LOG_RGB
    return np.asarray(rgb, np.float64) * np.exp(log_gain)


def _tones(rng, n, sd):
    """(n, 3) per-item RGB gains: brightness with log sd ``sd`` and a smaller warmth shift."""
    log_gain = rng.normal(0.0, sd, (n, 1)) + rng.normal(0.0, 0.3 * sd, (n, 1)) * _WARMTH_LOG_RGB
    return np.exp(log_gain)


def _luma(rgb):
    return 0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]


# --------------------------------------------------------------------------- planks


def _cyclic_gap(a, b, period):
    d = abs(a - b) % period
    return min(d, period - d)


def _plank_joints(rng, size_px, n_rows, *, min_stagger_px, laminate):
    """x positions (px) of the end joints in each plank row.

    A row's planks are the cyclic intervals between its joints, so whatever the joint
    positions, the row wraps onto itself and the layout is periodic in x.
    """
    # Keep the stagger rule satisfiable even for short repeats.
    min_stagger_px = min(min_stagger_px, size_px / 6.0)
    # Laminate planks all have the same length: one or two per repeat on every row.
    count = 1 if rng.random() < 0.7 else 2
    joints = []
    for r in range(n_rows):
        neighbours = [joints[r - 1]] if r > 0 else []
        if r == n_rows - 1 and r > 0:
            # The last row also touches the first one across the top/bottom wrap.
            neighbours.append(joints[0])
        if not laminate:
            count = 1 if rng.random() < 0.55 else 2
        for _ in range(30):
            first = float(rng.uniform(0.0, size_px))
            if count == 1:
                xs = [first]
            elif laminate:
                xs = [first, (first + size_px / 2.0) % size_px]
            else:
                xs = [first, (first + size_px * float(rng.uniform(0.35, 0.65))) % size_px]
            if all(_cyclic_gap(a, b, size_px) >= min_stagger_px
                   for n in neighbours for a in xs for b in n):
                break
        joints.append(sorted(int(x) for x in xs))
    return joints


def _wood_grain(rng, size_px, px_per_mm, figure, streak):
    """Periodic relative shade of a board surface, grain along x.

    Latewood lines are the level sets of ``y / spacing + warp(x, y)``; a strong, slowly
    varying warp bends them into the elongated loops (cathedrals) of flat-sawn boards.
    """
    # Pores and fibres: long thin streaks. Tone drifts slowly along a board, faster
    # across it.
    shade = _noise_mix(rng, size_px, _octaves(
        (_fine(rng.uniform(0.7, 1.4) * px_per_mm), rng.uniform(60.0, 140.0) * px_per_mm),
        streak / 3.0, 2, persistence=0.7) + _octaves(
        (rng.uniform(20.0, 50.0) * px_per_mm, rng.uniform(150.0, 300.0) * px_per_mm),
        0.1 / 3.0, 2), "noise0")
    warp = _noise_mix(rng, size_px, _octaves(
        (rng.uniform(15.0, 35.0) * px_per_mm, rng.uniform(200.0, 450.0) * px_per_mm),
        1.0 / 3.0, 2), "noise1")
    # Where the warp is strong the lines loop into cathedrals (flat-sawn), where it is
    # weak they run straight (rift-sawn): let its strength wander so planks differ.
    strength = _noise_mix(rng, size_px, [((rng.uniform(150.0, 300.0) * px_per_mm,) * 2,
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


def _add_knots(rng, shade, row_edges, px_per_mm, count):
    """Darken ``shade`` in place with ``count`` small elliptic knots, each inside a row."""
    size_px = shade.shape[0]
    for _ in range(count):
        r = int(rng.integers(len(row_edges) - 1))
        y0, y1 = row_edges[r], row_edges[r + 1]
        sy = min(rng.uniform(3.0, 7.0) * px_per_mm, (y1 - y0) / 6.0)
        if sy < 0.7:
            continue
        sx = sy * rng.uniform(1.3, 2.5)
        yc = rng.uniform(y0 + 2.5 * sy, y1 - 2.5 * sy)
        xc = rng.uniform(0.0, size_px)
        half_x = min(int(3 * sx) + 1, size_px // 2 - 1)
        ys = np.arange(max(y0, int(yc - 3 * sy)), min(y1, int(yc + 3 * sy) + 2))
        xs = np.arange(int(xc) - half_x, int(xc) + half_x + 1)
        dy = ((ys + 0.5 - yc) / sy)[:, None]
        dx = ((xs + 0.5 - xc) / sx)[None, :]
        d2 = dx * dx + dy * dy
        # A dark core with a slightly darker rim, like the ring around a real knot.
        knot = -0.45 * np.exp(-d2) - 0.15 * np.exp(-4.0 * (np.sqrt(d2) - 1.3) ** 2)
        shade[np.ix_(ys % size_px, xs % size_px)] += knot.astype(np.float32)


def _planks(rng, size_px, *, laminate):
    """Wood or laminate floor: staggered plank rows along x, see :func:`floor_texture`."""
    if laminate:
        width_m = rng.uniform(0.15, 0.25)
        n_rows = max(3, round(rng.uniform(1.1, 1.45) / width_m))
    else:
        width_m = rng.uniform(0.12, 0.22)
        n_rows = max(3, round(rng.uniform(0.9, 1.7) / width_m))
    tile_m = n_rows * width_m
    px_per_m = size_px / tile_m
    px_per_mm = px_per_m / 1000.0

    _, base_rgb, tone_sd, figure, streak, knot_p = _WOOD_SPECIES[
        rng.integers(len(_WOOD_SPECIES))]
    base = _jitter_rgb(rng, base_rgb, 0.05)
    if laminate:
        # Printed decor: planks differ little in tone and the grain is flatter.
        tone_sd, figure, streak = tone_sd * 0.35, figure * 0.8, streak * 0.7

    # Rows start a little below the top edge so that the seam falls inside a plank row;
    # on a row boundary it would show the same plank gap in every repeat. Row r covers
    # pixel rows row_edges[r] .. row_edges[r + 1] - 1, modulo size_px.
    shift = int(rng.integers(1, max(2, size_px // n_rows)))
    row_edges = shift + np.round(np.arange(n_rows + 1) * size_px / n_rows).astype(np.int64)
    joints = _plank_joints(rng, size_px, n_rows, laminate=laminate,
                           min_stagger_px=(0.3 if laminate else 0.15) * px_per_m)

    # Plank ids: one per cyclic interval between a row's joints.
    x = np.arange(size_px)
    id_rows = np.empty((n_rows, size_px), np.uint8)
    origin_x, origin_y = [], []
    n_planks = 0
    for r, xs in enumerate(joints):
        k = len(xs)
        seg = (np.searchsorted(xs, x, side="right") - 1) % k
        id_rows[r] = n_planks + seg
        origin_x.extend(xs)
        origin_y.extend([row_edges[r] % size_px] * k)
        n_planks += k
    ids = np.roll(np.repeat(id_rows, np.diff(row_edges), axis=0), shift, axis=0)
    origin_x, origin_y = np.array(origin_x), np.array(origin_y)

    # Every plank shows its own patch of one periodic grain field, so grain breaks at
    # the joints as it does between real boards. Laminate repeats a few printed decors,
    # each anchored at the plank's own corner, so equal prints look identical.
    if laminate:
        n_prints = int(rng.integers(3, 7))
        prints = rng.integers(0, size_px, (n_prints, 2))[rng.integers(n_prints, size=n_planks)]
        off_y = (prints[:, 0] - origin_y) % size_px
        off_x = (prints[:, 1] - origin_x) % size_px
    else:
        off_y = rng.integers(0, size_px, n_planks)
        off_x = rng.integers(0, size_px, n_planks)
    grain = _wood_grain(rng, size_px, px_per_mm, figure, streak)
    shape = (size_px, size_px)
    grid = np.arange(size_px, dtype=np.float32)
    map_x = cv2.LUT(ids, _lut(off_x), dst=_SCRATCH.array("plane0", shape))
    map_x += grid[None, :]
    map_y = cv2.LUT(ids, _lut(off_y), dst=_SCRATCH.array("plane1", shape))
    map_y += grid[:, None]
    shade = cv2.remap(grain, map_x, map_y, cv2.INTER_NEAREST, borderMode=cv2.BORDER_WRAP,
                      dst=_SCRATCH.array("plane2", shape))

    if not laminate and rng.random() < knot_p:
        _add_knots(rng, shade, row_edges, px_per_mm, int(rng.integers(1, 4)))

    # Gaps and bevels are sub-pixel at these resolutions: their strength is the share of
    # a pixel they darken.
    gap = float(np.clip(rng.uniform(0.8, 1.6) * px_per_mm, 0.12, 0.6))
    bevel = laminate or rng.random() < 0.4
    edges = map_x  # reuse the buffer
    edges.fill(1.0)
    for r in range(n_rows):
        y0, y1 = row_edges[r], row_edges[r + 1]
        edges[y0 % size_px, :] *= 1.0 - gap
        if bevel:
            # Light from one side: one bevel face catches it, the other is in shadow.
            edges[(y0 + 1) % size_px, :] *= 1.0 + 0.25 * gap
            edges[(y0 - 1) % size_px, :] *= 1.0 - 0.45 * gap
        inside = np.arange(y0 + 1, y1) % size_px
        for xj in joints[r]:
            edges[inside, xj] *= 1.0 - 0.8 * gap
            if bevel:
                edges[inside, xj - 1] *= 1.0 - 0.3 * gap

    # Per-plank tone and warmth: boards are cut from different trees. Each channel is
    # tone[id] * edges * (1 + gain_c * shade) = tone[id] * (edges + gain_c * shade * edges).
    gains = _tones(rng, n_planks, tone_sd)
    shade *= edges
    tone = map_y  # reuse the buffer
    factor = _SCRATCH.array("plane3", shape)
    channels = []
    for c in range(3):
        tone = cv2.LUT(ids, _lut(base[c] * gains[:, c]), dst=tone)
        factor = cv2.scaleAdd(shade, _WOOD_SHADE_GAIN_RGB[c], edges, dst=factor)
        factor = cv2.multiply(tone, factor, dst=factor)
        np.maximum(factor, 0.0, out=factor)
        channels.append(cv2.convertScaleAbs(
            factor, dst=_SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(tile_m)


# --------------------------------------------------------------------------- tiles


@dataclass(frozen=True)
class _TileLayout:
    """Grid of one repeat: ``nx`` tiles along x, ``ny`` rows, pitches include grout."""

    nx: int
    ny: int
    pitch_x_m: float
    pitch_y_m: float
    grout_m: float
    # Horizontal shift of row r is (r * row_shift mod 1) * pitch: 0, 1/2 or 1/3 bond.
    row_shift: float

    @property
    def tile_m(self):
        return self.nx * self.pitch_x_m


def _sample_tile_layout(rng):
    """Random tile grid whose repeat is square and holds a whole number of tiles."""
    grout_m = rng.uniform(0.002, 0.005)
    if rng.random() < 0.6:
        aspect = 1
        width_m = rng.choice([0.2, 0.25, 0.3, 0.33, 0.4, 0.45, 0.5, 0.6]) * rng.uniform(0.98, 1.02)
        width_m = min(width_m, 0.6)
        row_shift = 0.5 if rng.random() < 0.2 else 0.0
    else:
        aspect = int(rng.choice([2, 2, 3]))
        width_m = rng.uniform(0.15, 0.3) if aspect == 2 else rng.uniform(0.15, 0.2)
        row_shift = float(rng.choice([0.0, 0.5, 1.0 / 3.0] if aspect == 3 else [0.0, 0.5, 0.5]))
    pitch_y_m = width_m + grout_m
    # Long side L = aspect * W + (aspect - 1) * grout, as with rectified tiles sold for
    # mixing sizes; then `aspect` rows of pitch_y fill one tile pitch_x exactly, and a
    # repeat of nx tiles by aspect * nx rows is square.
    pitch_x_m = aspect * pitch_y_m
    nx = int(np.clip(round(rng.uniform(0.9, 1.8) / pitch_x_m), 1, 8))
    ny = aspect * nx
    if row_shift == 0.5 and ny % 2:
        # Half-bond rows alternate, so the repeat needs an even number of them.
        nx, ny = nx + 1, ny + aspect
    return _TileLayout(nx=nx, ny=ny, pitch_x_m=float(pitch_x_m), pitch_y_m=float(pitch_y_m),
                       grout_m=float(grout_m), row_shift=float(row_shift))


def _line_coverage(coord_px, pitch_px, width_px):
    """Share of each pixel covered by lines of ``width_px`` centred on multiples of pitch.

    ``coord_px`` holds pixel indices; the lines sit on pixel centres, and the coverage is
    the exact overlap of the unit pixel with the line (a box-filtered, anti-aliased line).
    Also returns the index of the cell (between lines) that each pixel falls in.
    """
    t = coord_px / pitch_px
    cell = np.floor(t)
    frac = t - cell
    d = np.minimum(frac, 1.0 - frac) * pitch_px
    half = 0.5 * width_px
    cov = np.clip(np.minimum(d + 0.5, half) - np.maximum(d - 0.5, -half), 0.0, 1.0)
    return cov.astype(np.float32), cell.astype(np.int64)


def _tile_grid(size_px, layout):
    """Tile ids, grout coverage and edge-band coverage of one repeat, all (size_px,)*2.

    Rows of a running bond differ only by their shift, and there are at most three
    shifts, so every profile along x is computed once per shift and rows copy theirs.
    The arrays are scratch buffers, valid until the next call.
    """
    px_per_m = size_px / layout.tile_m
    pitch_x_px, pitch_y_px = size_px / layout.nx, size_px / layout.ny
    grout_px = layout.grout_m * px_per_m
    # The rounded tile edge shades a band about a millimetre wider than the grout.
    edge_px = grout_px + 2.0 * max(0.7, px_per_m / 1000.0)

    y = np.arange(size_px, dtype=np.float64)
    cov_y, row = _line_coverage(y, pitch_y_px, grout_px)
    wide_y, _ = _line_coverage(y, pitch_y_px, edge_px)
    shifts = np.round((row * layout.row_shift) % 1.0 * 6.0).astype(np.int64)  # sixths
    kinds, kind_of_row = np.unique(shifts, return_inverse=True)
    cov_x = np.empty((len(kinds), size_px), np.float32)
    wide_x = np.empty_like(cov_x)
    col = np.empty((len(kinds), size_px), np.int64)
    for k, sixths in enumerate(kinds):
        x = y + sixths / 6.0 * pitch_x_px
        cov_x[k], col[k] = _line_coverage(x, pitch_x_px, grout_px)
        wide_x[k], _ = _line_coverage(x, pitch_x_px, edge_px)
    shape = (size_px, size_px)
    grout = np.take(cov_x, kind_of_row, axis=0, out=_SCRATCH.array("plane0", shape))
    np.maximum(grout, cov_y[:, None], out=grout)
    edge = np.take(wide_x, kind_of_row, axis=0, out=_SCRATCH.array("plane1", shape))
    np.maximum(edge, wide_y[:, None], out=edge)
    edge -= grout
    # uint8 arithmetic wraps at 256, which is the id space of cv2.LUT anyway.
    ids = np.take((col % layout.nx).astype(np.uint8), kind_of_row, axis=0,
                  out=_SCRATCH.array("ids", shape, np.uint8))
    ids += ((row % layout.ny) * layout.nx % 256).astype(np.uint8)[:, None]
    return ids, grout, edge


def _marble_veins(rng, size_px, px_per_mm, level, *, strength, thin, tag):
    """Opacity (size_px, size_px) float32 of one family of marble veins.

    Perlin's marble: veins are the lines where ``k . x / size_px + turbulence`` is an
    integer. With an integer wave vector ``k`` the phase wraps exactly at the image
    edges, so the veins stay periodic while running diagonally. ``level`` (a per-tile
    phase offset) gives every tile its own veins, as cut from different slabs.

    The result lives in the scratch buffer ``tag``; the noise scratch buffers
    ``noise1`` and ``noise2`` are overwritten.
    """
    spacing_m = rng.uniform(0.12, 0.3) if thin else rng.uniform(0.25, 0.6)
    waves = size_px / (spacing_m * 1000.0 * px_per_mm)
    angle = rng.uniform(0.0, math.pi)
    kx, ky = round(waves * math.cos(angle)), round(waves * math.sin(angle))
    if kx == 0 and ky == 0:
        kx = 1
    # Smooth turbulence: a rough one breaks the veins into specks. Its slope stays
    # below that of the linear term, or the level sets close into rings that look like
    # contour lines on a map.
    sigma_px = rng.uniform(50.0, 120.0) * px_per_mm
    slope = math.hypot(kx, ky) / size_px
    phase = _noise_mix(rng, size_px, _octaves(
        sigma_px, rng.uniform(0.3, 0.6) * sigma_px * slope, 3, persistence=0.4),
        "noise1")
    phase += (np.arange(size_px, dtype=np.float32) * np.float32(ky / size_px))[:, None]
    phase += (np.arange(size_px, dtype=np.float32) * np.float32(kx / size_px))[None, :]
    phase += level
    # Distance in pixels to the nearest vein centre line, over the local vein width,
    # which swells and thins along the vein.
    dist = np.round(phase, out=_SCRATCH.array(tag, phase.shape))
    np.subtract(phase, dist, out=dist)
    np.abs(dist, out=dist)
    width_px = max(1.5, (rng.uniform(0.5, 1.2) if thin else rng.uniform(1.0, 3.0)) * px_per_mm)
    width = _noise_mix(rng, size_px, [((0.5 * sigma_px,) * 2, 0.5 * width_px)], "noise2")
    width += np.float32(width_px)
    np.maximum(width, 0.6 * width_px, out=width)
    width *= np.float32(slope)
    dist /= width
    # A core (1 - d)^2 plus a faint halo 0.3 * (1 - d / 6), each clipped at zero.
    halo = np.multiply(dist, np.float32(-0.3 / 6.0), out=width)
    halo += np.float32(0.3)
    np.maximum(halo, 0.0, out=halo)
    core = np.subtract(np.float32(1.0), dist, out=dist)
    np.maximum(core, 0.0, out=core)
    core *= core
    core += halo
    core *= np.float32(strength)
    return core


def _render_tiles(rng, size_px, layout):
    """Tile floor on the grid ``layout``, in a random style, see :func:`floor_texture`."""
    px_per_mm = size_px / layout.tile_m / 1000.0
    ids, grout, edge = _tile_grid(size_px, layout)
    n_tiles = min(layout.nx * layout.ny, 256)

    _, colors, veins, tone_sd, mottle_amp, speckle_amp = _TILE_STYLES[
        rng.integers(len(_TILE_STYLES))]
    base = _jitter_rgb(rng, colors[rng.integers(len(colors))], 0.03)
    tile_luma = _luma(base)
    if rng.random() < 0.5:
        # Contrasting grout: a darker grey on light tiles, a lighter one on dark tiles.
        g = (tile_luma * rng.uniform(0.55, 0.75) if tile_luma > 140
             else min(225.0, tile_luma + rng.uniform(60.0, 110.0)))
        grout_rgb = _jitter_rgb(rng, (g, g * 0.99, g * 0.96), 0.02)
    elif tile_luma > 90:
        # "Matching" grout is still visibly darker: it is recessed and picks up dirt.
        grout_rgb = base * rng.uniform(0.68, 0.85)
    else:
        grout_rgb = base * rng.uniform(1.5, 1.9) + 8.0
    # Recessed joints receive less light than the tile faces.
    grout_rgb = grout_rgb * 0.92

    layers = _octaves(rng.uniform(8.0, 25.0) * px_per_mm, mottle_amp / 3.0, 3)
    layers.append(((_fine(0.6 * px_per_mm),) * 2, speckle_amp / 3.0))
    shade = _noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    edge *= np.float32(-0.12)
    shade += edge

    # Every channel is tile[id] * k_tile + vein_c * k_vein + grout_c * k_grout, with the
    # weights shared by the channels; the grout takes the tile's noise too, as sand.
    shape = (size_px, size_px)
    k_grout = cv2.multiply(grout, shade, dst=_SCRATCH.array("plane2", shape))
    inside = np.subtract(np.float32(1.0), grout, out=grout)
    k_tile = cv2.multiply(inside, shade, dst=edge)
    k_vein = None
    if veins:
        level = cv2.LUT(ids, _lut(rng.uniform(0.0, 1.0, n_tiles)),
                        dst=_SCRATCH.array("plane3", shape))
        vein = _marble_veins(rng, size_px, px_per_mm, level, strength=rng.uniform(0.5, 0.85),
                             thin=False, tag="plane4")
        vein += _marble_veins(rng, size_px, px_per_mm, level, strength=rng.uniform(0.12, 0.3),
                              thin=True, tag="plane5")
        np.minimum(vein, 1.0, out=vein)
        k_vein = cv2.multiply(vein, k_tile, dst=vein)
        k_tile = cv2.subtract(k_tile, k_vein, dst=k_tile)
        vein_rgb = (np.array([206.0, 204.0, 198.0]) if tile_luma < 90
                    else base * np.array([0.55, 0.57, 0.63]))

    gains = _tones(rng, n_tiles, tone_sd)
    tone = _SCRATCH.array("plane6", shape)
    out = _SCRATCH.array("plane7", shape)
    channels = []
    for c in range(3):
        tone = cv2.LUT(ids, _lut(base[c] * gains[:, c]), dst=tone)
        out = cv2.multiply(tone, k_tile, dst=out)
        out = cv2.scaleAdd(k_grout, float(grout_rgb[c]), out, dst=out)
        if k_vein is not None:
            out = cv2.scaleAdd(k_vein, float(vein_rgb[c]), out, dst=out)
        np.maximum(out, 0.0, out=out)
        channels.append(cv2.convertScaleAbs(out, dst=_SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(layout.tile_m)


# --------------------------------------------------------------------------- soft floors


def _carpet(rng, size_px):
    """Carpet: pixel-level pile noise, faint mottling, heathered flecks."""
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    base = _jitter_rgb(rng, _CARPET_COLORS[rng.integers(len(_CARPET_COLORS))], 0.06)
    # Tufts are 2-4 mm, about one pixel: the pile is near-white noise, tufts clump a
    # little, and wear and pile direction show as large faint blotches.
    layers = [((_fine(rng.uniform(0.5, 1.0) * px_per_mm),) * 2, rng.uniform(0.18, 0.32) / 3.0),
              ((rng.uniform(3.0, 6.0) * px_per_mm,) * 2, rng.uniform(0.08, 0.15) / 3.0)]
    layers += _octaves(rng.uniform(60.0, 150.0) * px_per_mm, rng.uniform(0.05, 0.12) / 3.0, 2)
    if rng.random() < 0.3:
        # Looped (berber) pile: short rows along x.
        layers.append(((_fine(px_per_mm), 5.0 * px_per_mm), rng.uniform(0.1, 0.2) / 3.0))
    shade = _noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    np.maximum(shade, 0.0, out=shade)

    # Heathered yarn: a share of fibres in a second color. Each channel is
    # base_c * shade + (fleck_c - base_c) * flecks * shade.
    fleck_rgb = base * np.exp(rng.normal(0.0, 0.1, 3)) * rng.choice([0.8, 1.2])
    flecks = _noise_mix(rng, size_px, [((_fine(0.7 * px_per_mm),) * 2, 4.0 / 3.0)],
                        "noise1")
    flecks -= np.float32(4.0 * rng.uniform(0.25, 0.5))
    np.clip(flecks, 0.0, 1.0, out=flecks)
    flecks *= shade
    flecks *= np.float32(rng.uniform(0.4, 0.9))
    shape = (size_px, size_px)
    out = _SCRATCH.array("plane0", shape)
    channels = []
    for c in range(3):
        out = cv2.addWeighted(shade, float(base[c]), flecks, float(fleck_rgb[c] - base[c]),
                              0.0, dst=out)
        channels.append(cv2.convertScaleAbs(out, dst=_SCRATCH.array(f"rgb{c}", shape, np.uint8)))
    return cv2.merge(channels), float(tile_m)


def _concrete(rng, size_px):
    """Concrete: grey fractal mottling, stains, pores and aggregate; sometimes polished."""
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    grey = rng.uniform(105.0, 195.0)
    tint = rng.normal(0.0, 0.025)
    base = np.array([grey * (1 + tint), grey, grey * (1 - 1.2 * tint)])
    polished = rng.random() < 0.35
    contrast = rng.uniform(0.07, 0.13) if polished else rng.uniform(0.1, 0.2)

    # Cement paste: fractal mottling with plenty of mid-scale detail (a flat spectrum
    # would read as clouds), plus a sandy grain.
    layers = _octaves(rng.uniform(20.0, 60.0) * px_per_mm, contrast / 3.0, 5, persistence=0.75)
    layers.append(((max(0.7, rng.uniform(1.0, 2.0) * px_per_mm),) * 2, rng.uniform(0.01, 0.025)))
    shade = _noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    # Stains: soft-edged patches where the large-scale noise is high.
    stains = _noise_mix(rng, size_px, _octaves(rng.uniform(80.0, 200.0) * px_per_mm,
                                               4.0 / 3.0, 2), "noise1")
    stains -= np.float32(4.0 * rng.uniform(0.1, 0.35))
    np.clip(stains, 0.0, 1.0, out=stains)
    stains *= np.float32(rng.uniform(0.04, 0.12))
    shade -= stains
    # Pores (dark) and exposed aggregate (light and dark) are the finest detail;
    # polishing exposes more aggregate.
    fine = _noise_mix(rng, size_px, [((_fine(rng.uniform(0.5, 1.0) * px_per_mm),) * 2,
                                      1.0 / 3.0)], "noise2")
    fine_amp = np.float32(rng.uniform(0.03, 0.07))
    spots = np.abs(fine, out=stains)
    spots -= np.float32(rng.uniform(0.55, 0.75))
    np.maximum(spots, 0.0, out=spots)
    spots *= np.float32(0.3 if polished else rng.uniform(0.4, 1.0))
    shade -= spots
    fine *= fine_amp
    shade += fine
    np.maximum(shade, 0.0, out=shade)
    return _shade_to_rgb8(shade, base), float(tile_m)


def floor_texture(kind, rng, size_px=512):
    """Seamless floor texture of the given kind.

    Parameters
    ----------
    kind : str
        One of :data:`FLOOR_KINDS`: ``"wood"``, ``"tiles"``, ``"carpet"``,
        ``"concrete"``, ``"laminate"``.
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters covered by one repeat of the image (both axes). Plank
        rows and tile grids fit a whole number of times into it: wood planks are
        0.12-0.22 m wide, laminate 0.15-0.25 m, tiles 0.15-0.6 m with 2-5 mm grout;
        carpet and concrete repeat every 1-2 m.

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`FLOOR_KINDS` or ``size_px`` is too small.
    """
    if kind not in FLOOR_KINDS:
        raise ValueError(f"unknown floor kind {kind!r}; valid kinds: {', '.join(FLOOR_KINDS)}")
    size_px = _check_size(size_px)
    if kind == "wood":
        return _planks(rng, size_px, laminate=False)
    if kind == "laminate":
        return _planks(rng, size_px, laminate=True)
    if kind == "tiles":
        return _render_tiles(rng, size_px, _sample_tile_layout(rng))
    if kind == "carpet":
        return _carpet(rng, size_px)
    return _concrete(rng, size_px)


# --------------------------------------------------------------------------- walls


def _hsv_rgb(h, s, v):
    return np.array(colorsys.hsv_to_rgb(h % 1.0, s, v)) * 255.0


def _wall_color(rng):
    u = rng.random()
    warm_or_cool = rng.uniform(0.07, 0.15) if rng.random() < 0.7 else rng.uniform(0.52, 0.62)
    if u < 0.32:  # white
        return _hsv_rgb(warm_or_cool, rng.uniform(0.0, 0.035), rng.uniform(0.93, 0.985))
    if u < 0.57:  # off-white, cream, greige
        return _hsv_rgb(warm_or_cool, rng.uniform(0.04, 0.11), rng.uniform(0.86, 0.95))
    if u < 0.72:  # light grey
        return _hsv_rgb(rng.random(), rng.uniform(0.0, 0.05), rng.uniform(0.70, 0.88))
    if u < 0.88:  # pastel tint
        return _hsv_rgb(rng.random(), rng.uniform(0.08, 0.22), rng.uniform(0.82, 0.95))
    # Accent walls: sage, navy, terracotta, mustard, teal, dusty pink, forest, charcoal.
    h, s, v = [(0.25, 0.25, 0.62), (0.61, 0.5, 0.38), (0.04, 0.5, 0.68), (0.12, 0.55, 0.78),
               (0.50, 0.45, 0.50), (0.97, 0.25, 0.78), (0.33, 0.4, 0.38),
               (0.58, 0.06, 0.32)][rng.integers(8)]
    return _hsv_rgb(h + rng.normal(0, 0.02), s * rng.uniform(0.8, 1.2), v * rng.uniform(0.9, 1.1))


def _paint(rng, size_px, rgb, fine_amp, low_amp, px_per_mm):
    """Flat color with fine stipple and soft mottling, relative amplitudes as given."""
    layers = [((_fine(rng.uniform(0.5, 1.5) * px_per_mm),) * 2, fine_amp / 3.0)]
    layers += _octaves(rng.uniform(40.0, 120.0) * px_per_mm, low_amp / 3.0, 4, persistence=0.6)
    shade = _noise_mix(rng, size_px, layers, "noise0")
    shade += np.float32(1.0)
    np.maximum(shade, 0.0, out=shade)
    return _shade_to_rgb8(shade, rgb)


def wall_texture(rng, size_px=256):
    """Seamless painted-wall texture.

    Mostly whites, off-whites, light greys and pastel tints, sometimes a stronger
    accent color; the surface is flat, orange-peel (fine roller stipple) or plaster
    (soft large-scale mottling), always subtle.

    Parameters
    ----------
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters of one repeat, 1-2 m.
    """
    size_px = _check_size(size_px)
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    rgb = _wall_color(rng)
    u = rng.random()
    if u < 0.3:  # flat: barely more than dither
        fine_amp, low_amp = rng.uniform(0.004, 0.01), rng.uniform(0.003, 0.008)
    elif u < 0.7:  # orange peel
        fine_amp, low_amp = rng.uniform(0.02, 0.05), rng.uniform(0.004, 0.012)
    else:  # plaster
        fine_amp, low_amp = rng.uniform(0.008, 0.02), rng.uniform(0.02, 0.06)
    return _paint(rng, size_px, rgb, fine_amp, low_amp, px_per_mm), float(tile_m)


def ceiling_texture(rng, size_px=128):
    """Seamless near-white ceiling texture with very subtle noise.

    Parameters
    ----------
    rng : numpy.random.Generator
        Only source of randomness; the same state gives the same image.
    size_px : int, optional
        Side of the square image in pixels (at least 16).

    Returns
    -------
    image : (size_px, size_px, 3) uint8
        sRGB, channel order RGB, periodic in both axes.
    tile_m : float
        Physical width in meters of one repeat, 1-2 m.
    """
    size_px = _check_size(size_px)
    tile_m = rng.uniform(1.0, 2.0)
    px_per_mm = size_px / tile_m / 1000.0
    hue = rng.uniform(0.07, 0.15) if rng.random() < 0.7 else rng.uniform(0.52, 0.62)
    rgb = _hsv_rgb(hue, rng.uniform(0.0, 0.03), rng.uniform(0.93, 0.985))
    image = _paint(rng, size_px, rgb, rng.uniform(0.006, 0.015), rng.uniform(0.004, 0.012),
                   px_per_mm)
    return image, float(tile_m)
