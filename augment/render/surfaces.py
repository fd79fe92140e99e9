"""Surface detail of furniture materials: wood grain, weaves, leather, brushed metal, stone.

A surface is a seamless texture of a *detail multiplier* at real scale (``tile_m`` meters
per repeat; u runs along a part's length, which is where a wood's grain goes). A piece's
colour comes from its palette with a small random spread, so one texture per surface
serves every piece: the renderer multiplies the colour, divided by ``mean_rgb``, by the
texture. The light is per vertex (:mod:`augment.render.staged`), so relief is baked in as
cavity darkening: the crevices of a weave, leather's pores and creases, oak's pores.
Textures are made procedurally from seeded noise (:mod:`augment.render.noise`), never
downloaded, and kept on disk (:func:`cache_dir`) so a fresh process does not remake them.
"""
from __future__ import annotations

import functools
import hashlib
import math
import os
import tempfile
import zlib
from pathlib import Path
from dataclasses import dataclass

import numpy as np

from .noise import WOOD_SHADE_GAIN_RGB, periodic_noise, wood_grain

SIZE_PX = 512
GAMMA = 2.2  # the renderer's: textures are stored as detail ** (1 / GAMMA)


@dataclass(frozen=True)
class Surface:
    """One surface's texture.

    Attributes
    ----------
    name : str
    image : (SIZE_PX, SIZE_PX, 3) uint8
        The detail multiplier ``d`` (linear, at most 1) stored as ``255 d ** (1 / 2.2)``,
        periodic in both axes.
    tile_m : float
        Meters one repeat covers, along u and v.
    mean_rgb : (3,) tuple of float
        Mean of ``d`` per channel (linear).
    """

    name: str
    image: np.ndarray
    tile_m: float
    mean_rgb: tuple


# Wood species: figure (latewood line contrast) and streak (pore contrast), as the
# synthetic floors' planks.
_WOODS = {"oak": (0.30, 0.20), "light oak": (0.25, 0.16), "walnut": (0.30, 0.22), "dark walnut": (0.24, 0.20),
          "pine": (0.35, 0.18), "teak": (0.20, 0.18), "ash": (0.32, 0.18), "weathered": (0.35, 0.30)}

def surface_name(material_name: str) -> str:
    """The surface a palette material shows, from its name ("" for none): e.g. "light oak"
    -> "wood:light oak", "brushed steel" -> "metal:brushed". Fabrics are chosen by the
    builder (:data:`WEAVES`), not here."""
    name = material_name.lower()
    for species in sorted(_WOODS, key=len, reverse=True):
        if species in name:
            return f"wood:{species}"
    rules = (("wood", "wood:oak"), ("platform", "wood:oak"), ("rattan", "basket"), ("basket", "basket"),
             ("leather", "leather"), ("velvet", "velvet"), ("felt", "felt"), ("wool", "rug"),
             ("linen", "linen"), ("canvas", "linen"), ("mattress", "weave"), ("skirt", "velvet"), ("shade", "linen"),
             ("mesh", "weave"),
             ("soundbar", "weave"), ("fabric", "weave"), ("brushed", "metal:brushed"),
             ("brass", "metal:brushed"), ("alumin", "metal:brushed"), ("silver", "metal:brushed"),
             ("steel", "metal:powder"), ("marble", "marble"), ("concrete", "concrete"),
             ("terracotta", "terracotta"), ("ceramic", "ceramic"), ("porcelain", "ceramic"),
             ("glaze", "ceramic"), ("stoneware", "ceramic"), ("leaves", "leaf"), ("paint", "paint"),
             ("laminate", "paint"), ("enamel", "paint"), ("resin", "paint"), ("plastic", "paint"))
    return next((surface for word, surface in rules if word in name), "")


def cache_dir() -> Path:
    """Where made textures are kept: ``$STAGER_CACHE_DIR``, else ``$XDG_CACHE_HOME/stager``,
    else ``~/.cache/stager``; a folder per version of the generators, so an edit never
    reads stale textures."""
    root = os.environ.get("STAGER_CACHE_DIR")
    if not root:
        root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "stager"
    return Path(root) / f"surfaces-{_version()}"


@functools.lru_cache(maxsize=1)
def _version() -> str:
    code = b"".join(Path(__file__).with_name(f).read_bytes() for f in ("surfaces.py", "noise.py"))
    return hashlib.sha256(code + np.__version__.encode()).hexdigest()[:12]


@functools.lru_cache(maxsize=None)
def surface(name: str) -> Surface:
    """The texture of surface ``name`` (:func:`surface_name`): from the disk cache, or
    made (about 50 ms) and kept there when the cache folder is writable.

    Raises
    ------
    ValueError
        For a name no generator makes.
    """
    family, _, variant = name.partition(":")
    maker = _MAKERS.get(family)
    if maker is None or (family == "wood" and variant not in _WOODS):
        raise ValueError(f"surface {name!r}: no such surface")
    path = cache_dir() / f"{name.replace(':', '-').replace(' ', '_')}.npy"
    try:
        image = np.load(path, allow_pickle=False)
        if image.shape != (SIZE_PX, SIZE_PX, 3) or image.dtype != np.uint8:
            raise ValueError("not a texture")
    except (OSError, ValueError):
        image = _make(name, family, variant)
        _keep(path, image)
    linear = (np.arange(256) / 255.0) ** GAMMA
    mean = tuple(float(v) for v in linear[image].mean(axis=(0, 1)))
    image.setflags(write=False)
    return Surface(name, image, _TILES_M[family], mean)


def _keep(path: Path, image: np.ndarray) -> None:
    """Write ``image`` to ``path`` whole or not at all (a temporary file renamed); a cache
    that cannot be written is no error."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(fd, "wb") as f:
            np.save(f, image, allow_pickle=False)
        os.replace(tmp, path)
    except OSError:
        Path(tmp).unlink(missing_ok=True)


def _make(name, family, variant) -> np.ndarray:
    maker, tile_m, gain = _MAKERS[family], _TILES_M[family], (1.0, 1.0, 1.0)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    px_per_mm = SIZE_PX / (1000.0 * tile_m)
    shade = maker(rng, px_per_mm, variant) if family in ("wood", "metal") else maker(rng, px_per_mm)
    if isinstance(shade, tuple):
        shade, gain = shade
    detail = np.exp(shade[..., None] * np.asarray(gain, np.float32))
    # At most 1 (the renderer's vertex colours cannot brighten), the brightest 0.2 % clipped.
    detail /= np.float32(np.percentile(detail.max(axis=2), 99.8))
    np.minimum(detail, 1.0, out=detail)
    return np.round(255.0 * detail ** (1.0 / GAMMA)).astype(np.uint8)


# --------------------------------------------------------------------------- generators
# Each returns the log-brightness (SIZE_PX, SIZE_PX) float32 of the surface, or that and
# per-channel gains (darker also warmer, or greener).


def _noise(rng, scale_px, std=1.0):
    """Periodic noise of unit standard deviation (about) times ``std``."""
    return periodic_noise(rng, SIZE_PX, scale_px) * np.float32(3.0 * std)


def _threads(count):
    """Per pixel along an axis: thread index and position across the thread (0-1), for
    ``count`` threads a repeat."""
    x = (np.arange(SIZE_PX, dtype=np.float32) + 0.5) * (count / SIZE_PX)
    index = np.floor(x).astype(np.int64)
    return index, x - index


def _weave_shade(rng, px_per_mm, pitch_mm, contrast, tone_sd, twill=False):
    """A woven cloth: threads of ``pitch_mm`` over and under each other, rounded (darker
    at their edges by ``contrast``), each thread its own tone."""
    count = max(4, 4 * round(SIZE_PX / (4 * pitch_mm * px_per_mm)))  # over-under repeats every 2 or 4 threads
    iu, fu = _threads(count)
    iv, fv = _threads(count)
    over = ((iu[None, :] + iv[:, None]) % 4 < 2) if twill else ((iu[None, :] + iv[:, None]) % 2 == 0)
    across_u = (4.0 * (fu - 0.5) ** 2)[None, :]  # 0 at a thread's middle, 1 at its edges
    across_v = (4.0 * (fv - 0.5) ** 2)[:, None]
    tone_u = rng.normal(0.0, tone_sd, count).astype(np.float32)[iu][None, :]
    tone_v = rng.normal(0.0, tone_sd, count).astype(np.float32)[iv][:, None]
    return np.where(over, tone_u - contrast * across_u, tone_v - contrast * across_v).astype(np.float32)


def _wood(rng, px_per_mm, species):
    figure, streak = _WOODS[species]
    return wood_grain(rng, SIZE_PX, px_per_mm, figure, streak), WOOD_SHADE_GAIN_RGB


def _weave(rng, px_per_mm):
    """Upholstery flat weave: fine threads, a heathered yarn."""
    shade = _weave_shade(rng, px_per_mm, 1.1, 0.22, 0.05)
    return shade + _noise(rng, 4.0 * px_per_mm, 0.035) + _noise(rng, 25.0 * px_per_mm, 0.02)


def _linen(rng, px_per_mm):
    """Linen: irregular threads with slubs (thick runs) along them."""
    shade = _weave_shade(rng, px_per_mm, 0.9, 0.2, 0.06)
    shade += _noise(rng, (0.6 * px_per_mm, 12.0 * px_per_mm), 0.06)
    shade += _noise(rng, (12.0 * px_per_mm, 0.6 * px_per_mm), 0.06)
    return shade + _noise(rng, 30.0 * px_per_mm, 0.02)


def _boucle(rng, px_per_mm):
    """Bouclé: a pile of small loops with dark gaps between them."""
    loops = _noise(rng, 0.9 * px_per_mm)
    shade = -0.28 * np.clip(-loops, 0.0, 2.5) + 0.06 * np.clip(loops, 0.0, 2.0)
    return shade + _noise(rng, 6.0 * px_per_mm, 0.04)


def _velvet(rng, px_per_mm):
    """Velvet: pile crushed in soft patches that catch the light differently."""
    return _noise(rng, 30.0 * px_per_mm, 0.045) + _noise(rng, 8.0 * px_per_mm, 0.02) + _noise(rng, px_per_mm, 0.02)


def _wool(rng, px_per_mm):
    """Wool tweed: a coarse twill with flecks of lighter and darker fibre."""
    shade = _weave_shade(rng, px_per_mm, 1.8, 0.25, 0.06, twill=True)
    flecks = _noise(rng, 0.8 * px_per_mm)
    shade += 0.12 * np.clip(flecks - 1.8, 0.0, None) - 0.12 * np.clip(-flecks - 1.8, 0.0, None)
    return shade + _noise(rng, 10.0 * px_per_mm, 0.03)


def _felt(rng, px_per_mm):
    return _noise(rng, 1.0 * px_per_mm, 0.03) + _noise(rng, 20.0 * px_per_mm, 0.03)


def _rug(rng, px_per_mm):
    """Rug pile: tufts and the wear of feet."""
    tufts = _noise(rng, 1.5 * px_per_mm)
    return -0.08 * np.abs(tufts) + _noise(rng, 15.0 * px_per_mm, 0.05)


def _leather(rng, px_per_mm):
    """Leather: a pebbled grain, wandering creases, a patina of wear."""
    pebble = _noise(rng, 0.7 * px_per_mm)
    shade = -0.10 * np.clip(-pebble, 0.0, 2.5)
    for scale in ((3.0 * px_per_mm, 30.0 * px_per_mm), (30.0 * px_per_mm, 3.0 * px_per_mm)):
        line = _noise(rng, scale)
        shade -= 0.09 * np.exp(-(line / 0.25) ** 2)  # soft lines where the noise crosses zero
    return shade + _noise(rng, 40.0 * px_per_mm, 0.07), (0.9, 1.0, 1.12)


def _metal(rng, px_per_mm, finish):
    if finish == "brushed":  # streaks along u
        return _noise(rng, (0.5 * px_per_mm, 80.0 * px_per_mm), 0.06) + _noise(rng, 30.0 * px_per_mm, 0.02)
    return _noise(rng, 0.5 * px_per_mm, 0.035) + _noise(rng, 25.0 * px_per_mm, 0.02)  # powder coat


def _paint(rng, px_per_mm):
    """Paint and lacquer: almost flat, a faint mottle of the brush or spray."""
    return _noise(rng, 40.0 * px_per_mm, 0.015) + _noise(rng, 1.5 * px_per_mm, 0.01)


def _ceramic(rng, px_per_mm):
    """Glaze pooling unevenly, a few dark specks of the clay."""
    specks = _noise(rng, 0.6 * px_per_mm)
    return _noise(rng, 15.0 * px_per_mm, 0.04) - 0.25 * np.clip(specks - 2.4, 0.0, None)


def _terracotta(rng, px_per_mm):
    return _noise(rng, 12.0 * px_per_mm, 0.09) + _noise(rng, 0.8 * px_per_mm, 0.05), (0.9, 1.0, 1.15)


def _concrete(rng, px_per_mm):
    pores = _noise(rng, 0.9 * px_per_mm)
    return _noise(rng, 20.0 * px_per_mm, 0.07) + _noise(rng, 2.0 * px_per_mm, 0.03) \
        - 0.3 * np.clip(-pores - 2.2, 0.0, None)


def _marble(rng, px_per_mm):
    """Marble: a cloudy ground crossed by thin veins that run roughly along u, wandering."""
    t = np.arange(SIZE_PX, dtype=np.float32) / np.float32(SIZE_PX)
    phase = 2.0 * t[:, None] + 0.3 * _noise(rng, 150.0 * px_per_mm) + 0.06 * _noise(rng, 25.0 * px_per_mm)
    veins = np.exp(-(np.sin(np.pi * phase) / 0.05) ** 2) + 0.4 * np.exp(-(np.sin(np.pi * (phase + 0.37)) / 0.03) ** 2)
    return _noise(rng, 25.0 * px_per_mm, 0.02) - 0.4 * veins.astype(np.float32), (1.0, 1.0, 0.97)


def _basket(rng, px_per_mm):
    """Rattan or a woven basket: broad strands over and under."""
    return _weave_shade(rng, px_per_mm, 9.0, 0.45, 0.08) + _noise(rng, (0.7 * px_per_mm, 9 * px_per_mm), 0.06)


def _leaf(rng, px_per_mm):
    """Leaves: parallel side veins, lighter, and blotches of deeper green."""
    t = np.arange(SIZE_PX, dtype=np.float32) / np.float32(SIZE_PX)
    count = max(2, round(SIZE_PX / (9.0 * px_per_mm)))
    # Chevrons from a midrib along u (at v = 0.5): periodic, as |v - 0.5| is at v = 0 and 1.
    veins = np.cos(2 * math.pi * (count * t[None, :] + count // 2 * np.abs(t[:, None] - 0.5))) ** 16
    shade = 0.10 * veins + _noise(rng, 6.0 * px_per_mm, 0.09)
    return shade.astype(np.float32), (1.1, 1.0, 1.2)


_MAKERS = {"wood": _wood, "weave": _weave, "linen": _linen, "boucle": _boucle, "velvet": _velvet, "wool": _wool,
           "felt": _felt, "rug": _rug, "leather": _leather, "metal": _metal, "paint": _paint, "ceramic": _ceramic,
           "terracotta": _terracotta, "concrete": _concrete, "marble": _marble, "basket": _basket, "leaf": _leaf}
# One repeat: long enough that it is not seen repeating on a sofa or a table top, short
# enough that the finest detail (a thread, a pore) is a texel or two.
_TILES_M = {"wood": 0.6, "weave": 0.25, "linen": 0.25, "boucle": 0.3, "velvet": 0.6, "wool": 0.3, "felt": 0.5,
            "rug": 0.4, "leather": 0.5, "metal": 0.4, "paint": 1.0, "ceramic": 0.3, "terracotta": 0.4,
            "concrete": 0.5, "marble": 0.8, "basket": 0.4, "leaf": 0.15}
