"""Furniture meshes for every catalog kind: procedural builders, and users' own models.

Every kind of :data:`layout.catalog.CATALOG` has a builder that makes a piece of furniture
of any size from parts (legs, frames, cushions, drawers, bevelled slabs, turned profiles),
in one of several styles, with materials drawn from a palette and varied in colour, all
chosen by a seeded generator: the same seed gives the same piece. A user's GLB or OBJ
stands in for a kind through :func:`load_asset`.

Frames. A builder works in a *builder frame*: x across the width (to the item's right), y
along the depth with the front at +y, z up from the floor. The result, a
:class:`Furniture`, is in the layout's *item frame* (:mod:`layout.geometry`): x forward
(the front faces +x), y to the item's left, z up, the footprint centered on the origin and
the base at z = 0. Its bounding box is exactly the item's size: width along y, depth along
x, height along z (a final fit scales the assembled parts onto the box; at the catalog
sizes the builders already come within ``RENDER.furniture.fit_slack_m`` of it, and round things
become ovals when an item's width and depth differ).
:func:`world_from_item` places it in the floor frame (z up, floor at z = 0) by the item's
position and yaw.

Colours are linear RGB (what a renderer multiplies with light); palettes are written in
sRGB and converted with the 2.2 power of :mod:`augment.render.gl`'s renderer.
"""
from __future__ import annotations

import contextvars
import math
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import trimesh

from layout.catalog import CATALOG
from layout.fileio import path_problem

from ..errors import FurnishError
from .settings import RENDER
from .rugs import PATTERNS, rug_pattern
from .styles import STYLES, WEAVES
from .surfaces import surface, surface_name

# --------------------------------------------------------------------------------------
# Materials
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Material:
    """A PBR metallic-roughness material.

    Attributes
    ----------
    name : str
    color_rgb : (3,) tuple of float
        Base colour, linear RGB in [0, 1].
    roughness, metallic : float
    emissive_rgb : (3,) tuple of float
        Light it gives off (screens, marquees), linear RGB.
    texture_key : str
        Identifies ``texture`` (a user asset's base-colour image); "" when there is none.
    texture : (h, w, 3) uint8 or None
        sRGB base-colour texture, multiplied by ``color_rgb``.
    surface : str
        Its surface detail (:func:`augment.render.surfaces.surface`: grain, weave, ...),
        laid on the parts' ``uv`` (meters); "" for none.
    """

    name: str
    color_rgb: tuple
    roughness: float = 0.7
    metallic: float = 0.0
    emissive_rgb: tuple = (0.0, 0.0, 0.0)
    texture_key: str = ""
    texture: np.ndarray | None = field(default=None, compare=False, hash=False, repr=False)
    surface: str = ""


def _linear(srgb255) -> np.ndarray:
    return (np.asarray(srgb255, dtype=np.float64) / 255.0) ** 2.2


def _mat(rng, name, srgb255, roughness=0.7, metallic=0.0, spread=0.06, emissive=None, surface=None) -> Material:
    """A material of colour ``srgb255`` varied by about ``spread`` in brightness and tint;
    its surface by default the one its name says (:func:`surface_name`)."""
    base = _linear(srgb255)
    gain = math.exp(rng.normal(0.0, spread * 2.0))
    tint = np.exp(rng.normal(0.0, spread * 0.5, 3))
    color = np.clip(base * gain * tint, 0.002, 0.92)
    r = float(np.clip(roughness + rng.normal(0.0, 0.04), 0.05, 1.0))
    em = (0.0, 0.0, 0.0) if emissive is None else tuple(float(v) for v in emissive)
    return Material(name, tuple(float(v) for v in color), r, float(metallic), em,
                    surface=surface_name(name) if surface is None else surface)


# The gaps between drawer and door fronts: narrow and deep, so dark whatever the wood.
_RECESS = Material("recess", tuple(float(v) for v in _linear((30, 27, 25))), 0.95)

# Palettes: (name, sRGB 0-255, roughness, metallic).
WOODS = (("light oak", (196, 158, 112), 0.55), ("oak", (170, 128, 82), 0.55), ("walnut", (112, 74, 46), 0.5),
         ("dark walnut", (78, 52, 36), 0.5), ("pine", (214, 178, 128), 0.6), ("teak", (150, 98, 58), 0.5),
         ("ash", (214, 196, 165), 0.6))
PAINTS = (("white paint", (236, 234, 229), 0.45), ("black paint", (34, 34, 35), 0.45),
          ("grey paint", (150, 151, 150), 0.45), ("sage paint", (150, 165, 140), 0.5),
          ("navy paint", (48, 62, 92), 0.45), ("cream paint", (228, 220, 198), 0.45))
FABRICS = (("light grey fabric", (182, 181, 178)), ("charcoal fabric", (72, 74, 78)), ("beige fabric", (204, 188, 160)),
           ("navy fabric", (46, 60, 96)), ("olive fabric", (112, 116, 72)), ("terracotta fabric", (178, 96, 70)),
           ("mustard fabric", (200, 150, 52)), ("dusty pink fabric", (200, 152, 146)),
           ("bottle green fabric", (42, 86, 66)), ("cream fabric", (226, 218, 200)),
           ("blue grey fabric", (110, 126, 142)))
LEATHERS = (("cognac leather", (152, 86, 46)), ("brown leather", (84, 52, 34)), ("black leather", (34, 31, 30)))
METALS = (("black steel", (38, 38, 40), 0.45, 0.6), ("brushed steel", (186, 186, 188), 0.35, 0.9),
          ("brass", (196, 156, 84), 0.3, 0.9), ("white steel", (226, 226, 222), 0.4, 0.3))
BEDDING = (("white linen", (236, 234, 228)), ("grey linen", (170, 170, 168)), ("linen", (206, 194, 172)),
           ("blue linen", (120, 140, 168)), ("sage linen", (150, 164, 138)), ("rust linen", (176, 108, 80)))
GREENS = ((56, 98, 44), (44, 84, 40), (84, 120, 54), (36, 72, 42), (70, 104, 60))
POTS = (("terracotta", (176, 98, 66), 0.8), ("white ceramic", (232, 230, 224), 0.3), ("concrete", (158, 156, 150), 0.9),
        ("black ceramic", (40, 40, 42), 0.35), ("woven basket", (176, 146, 100), 0.9))
BOOK_COLORS = ((150, 40, 40), (40, 70, 120), (30, 30, 30), (220, 210, 190), (60, 110, 80), (200, 150, 60),
               (120, 60, 100), (230, 230, 225), (90, 90, 95), (170, 90, 50))


def _pick(rng, options):
    return options[int(rng.integers(len(options)))]


# The style a piece is being built in (build_furniture sets it; None: any material).
_STYLE: contextvars.ContextVar = contextvars.ContextVar("style", default=None)


def _styled(palette: str, options):
    """``options`` (a palette, entries named first) narrowed to the current style's."""
    style = _STYLE.get()
    names = () if style is None else getattr(style, palette)
    kept = tuple(o for o in options if o[0] in names)
    return kept or tuple(options)


def _wood(rng):
    name, rgb, rough = _pick(rng, _styled("woods", WOODS))
    return _mat(rng, name, rgb, rough)


def _paint(rng):
    name, rgb, rough = _pick(rng, _styled("paints", PAINTS))
    return _mat(rng, name, rgb, rough, spread=0.03)


def _fabric(rng):
    name, rgb = _pick(rng, _styled("fabrics", FABRICS))
    style = _STYLE.get()
    return _mat(rng, name, rgb, 0.92, surface=_pick(rng, WEAVES if style is None else style.weaves))


def _leather(rng):
    name, rgb = _pick(rng, _styled("leathers", LEATHERS))
    return _mat(rng, name, rgb, 0.5)


def _metal(rng, names=None):
    options = [m for m in METALS if names is None or m[0] in names]
    name, rgb, rough, metal = _pick(rng, _styled("metals", options))
    return _mat(rng, name, rgb, rough, metal, spread=0.03)


def _upholstery(rng):
    style = _STYLE.get()
    return _leather(rng) if rng.random() < (0.2 if style is None else style.leather_share) else _fabric(rng)


def _finish(rng):
    """Wood or paint, for carcasses."""
    style = _STYLE.get()
    return _wood(rng) if rng.random() < (0.6 if style is None else style.wood_share) else _paint(rng)


# --------------------------------------------------------------------------------------
# Parts and primitives (builder frame: x right, y front, z up)
# --------------------------------------------------------------------------------------

@dataclass
class Part:
    """One piece of a furniture mesh: triangles of one material.

    Attributes
    ----------
    vertices : (n, 3) float64
        Meters.
    normals : (n, 3) float64
        Unit vertex normals (flat parts repeat vertices per face).
    faces : (m, 3) int64
        Counter-clockwise seen from outside.
    material : Material
    uv : (n, 2) float64 or None
        Texture coordinates: a user asset's own, or for the builders' parts meters along
        the surface (u along the part's length, where a wood's grain runs).
    convex : bool
        The part is convex: its shadow is the hull of its projected vertices.
    casts_shadow : bool
        False for small details inside the silhouette (knobs, books on a shelf), which
        the floor shadows can leave out.
    cavity : (n,) float64 or None
        Share of the room's light each vertex gets where the part's own shape hides
        some of it (deep in a fold of cloth): occlusion finer than the renderer's. None: 1.
    outline : (k, 3) float64 or None
        A few points whose convex hull stands in for a convex part where only its outline
        counts (the floor's shadows): a cushion's or cloth's support points. None: its vertices.
    """

    vertices: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    material: Material
    uv: np.ndarray | None = None
    convex: bool = True
    casts_shadow: bool = True
    cavity: np.ndarray | None = None
    outline: np.ndarray | None = None

    def transformed(self, matrix: np.ndarray) -> "Part":
        """The part moved by a 4x4 affine ``matrix`` (normals by its inverse transpose)."""
        m = np.asarray(matrix, dtype=np.float64)
        v = self.vertices @ m[:3, :3].T + m[:3, 3]
        n = self.normals @ np.linalg.inv(m[:3, :3])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        faces = self.faces if np.linalg.det(m[:3, :3]) > 0 else self.faces[:, ::-1]
        outline = None if self.outline is None else self.outline @ m[:3, :3].T + m[:3, 3]
        return replace(self, vertices=v, normals=n, faces=faces, outline=outline)

    def light_share(self) -> np.ndarray:
        """(n,) :attr:`cavity`, 1 for every vertex where it is None."""
        return np.ones(len(self.vertices)) if self.cavity is None else self.cavity


def _oriented(vertices, normals, faces):
    """Flip the triangles whose winding disagrees with their vertex normals."""
    tri = vertices[faces]
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    facing = np.einsum("ij,ij->i", cross, normals[faces].sum(axis=1))
    faces = faces.copy()
    faces[facing < 0] = faces[facing < 0][:, ::-1]
    return faces


def _rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def _rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _move(x, y, z):
    m = np.eye(4)
    m[:3, 3] = x, y, z
    return m


def _about(point, matrix):
    """``matrix`` applied about ``point`` instead of the origin."""
    return _move(*point) @ matrix @ _move(*(-np.asarray(point, dtype=np.float64)))


def _face_grid(coords_b, coords_d):
    nb, nd = len(coords_b), len(coords_d)
    idx = np.arange(nb * nd).reshape(nb, nd)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def _rounded_box_mesh(lo, hi, radius, segments, steps=1):
    """A box from ``lo`` to ``hi`` with its edges rounded by ``radius`` (``segments`` facets
    per 45 degrees; radius 0 gives a sharp box; each flat side cut in ``steps`` x ``steps``
    quads). Exact extents, analytic normals; each side's texture coordinates (meters) run
    along its longer edge first."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    center, half = (lo + hi) / 2, (hi - lo) / 2
    r = float(min(radius, 0.999 * half.min()))
    if r < RENDER.furniture.bevel_min_m:  # too small to see: a sharp box, 12 triangles
        r = 0.0
    inner = half - max(r, 0.0)
    if r <= 1e-6:
        segments = 0
    t = np.tan(np.linspace(0.0, np.pi / 4, segments + 1)[1:]) if segments else np.zeros(0)
    verts, norms, faces, uvs = [], [], [], []
    count = 0
    for a in range(3):
        b, d = (a + 1) % 3, (a + 2) % 3
        along, across = (b, d) if half[b] >= half[d] else (d, b)
        cb = np.concatenate([-inner[b] - r * t[::-1], np.linspace(-inner[b], inner[b], steps + 1), inner[b] + r * t])
        cd = np.concatenate([-inner[d] - r * t[::-1], np.linspace(-inner[d], inner[d], steps + 1), inner[d] + r * t])
        for sign in (-1.0, 1.0):
            gb, gd = np.meshgrid(cb, cd, indexing="ij")
            p = np.zeros(gb.shape + (3,))
            p[..., a] = sign * (inner[a] + max(r, 0.0))
            p[..., b], p[..., d] = gb, gd
            p = p.reshape(-1, 3)
            core = np.clip(p, -inner, inner)
            out = p - core
            length = np.linalg.norm(out, axis=1, keepdims=True)
            n = out / np.maximum(length, 1e-12)
            pos = core + n * r if r > 1e-6 else p
            if r <= 1e-6:
                n = np.zeros_like(p)
                n[:, a] = sign
            verts.append(pos + center)
            norms.append(n)
            faces.append(_face_grid(cb, cd) + count)
            uvs.append(pos[:, [along, across]] + half[[along, across]])
            count += len(p)
    v, n, f = np.concatenate(verts), np.concatenate(norms), np.concatenate(faces)
    # Drop the zero-area triangles of the flat middle strips when the box is sharp.
    tri = v[f]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    f = f[area > 1e-14]
    return v, n, _oriented(v, n, f), np.concatenate(uvs)


def _crowned_core(lo, hi, radius, crown_m):
    """How :func:`_crowned_box_mesh` shapes the box ``lo``-``hi``: the crown it takes (3,)
    (at most a quarter of each side), its rims' radius, and the half sides (3,) of the core
    whose edges the rims round (the rims' centre lines)."""
    crown = np.minimum(np.asarray(crown_m, dtype=np.float64), 0.25 * (hi - lo))
    half = (hi - lo) / 2 - crown
    r = min(radius, 0.999 * float(half.min()))
    return crown, r, half - r


def _crowned_box_mesh(lo, hi, radius, crown_m, steps=8):
    """A stuffed cushion filling the box ``lo``-``hi``: a rounded box whose flat sides
    bulge out by ``crown_m`` (3,) (the sides across x, y, z) at their middle, falling to
    nothing at their rims, so that its seams sit inside and its faces catch the light
    unevenly. Exact extents; normals follow the bulge."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    crown, r, inner = _crowned_core(lo, hi, radius, crown_m)
    v, n, f, uv = _rounded_box_mesh(lo + crown, hi - crown, radius, 2, steps)
    center = (lo + hi) / 2
    inner = np.maximum(inner, 1e-9)
    c = np.clip((v - center) / inner, -1.0, 1.0)
    bend = n.copy()
    for a in range(3):
        b, d = (a + 1) % 3, (a + 2) % 3
        bump = crown[a] * (1 - c[:, b] ** 2) * (1 - c[:, d] ** 2)
        v[:, a] += bump * n[:, a]
        # The bulge's slope tilts the normal (weighted by how squarely the side faces a).
        w = n[:, a] ** 2
        bend[:, b] -= w * crown[a] * (-2 * c[:, b] / inner[b]) * (1 - c[:, d] ** 2) * (np.abs(c[:, b]) < 1)
        bend[:, d] -= w * crown[a] * (-2 * c[:, d] / inner[d]) * (1 - c[:, b] ** 2) * (np.abs(c[:, d]) < 1)
    bend /= np.linalg.norm(bend, axis=1, keepdims=True)
    return v, bend, _oriented(v, bend, f), uv


def _wave(rng, count=4, shortest_m=0.12, longest_m=0.4):
    """A smooth random wave of ``count`` sines (wavelengths between the two, meters):
    f(s) in [-1, 1] along a length s (meters)."""
    lam = rng.uniform(shortest_m, longest_m, count)
    phase = rng.uniform(0, 2 * np.pi, count)
    amp = rng.uniform(0.5, 1.0, count)

    def wave(s):
        s = np.asarray(s, dtype=np.float64)[..., None]
        return (amp * np.sin(2 * np.pi * s / lam + phase)).sum(-1) / amp.sum()
    return wave


class Folds:
    """Where cloth hanging down a bed's sides folds: a wave along each side (left, right,
    head, foot, by where the cloth hangs in the item's frame), so that layers of bedding
    made with one fold the same way and the upper never dips into the lower. The cloth
    folds in by up to ``depth_m`` below the height ``rim_z`` (the mattress's edge),
    fully from ``full_m`` below it on."""

    def __init__(self, rng, depth_m: float, rim_z: float, full_m: float = 0.16):
        self.depth_m, self.rim_z, self.full_m = float(depth_m), float(rim_z), float(full_m)
        self.valley_dark = 0.3  # light lost at the bottom of the deepest fold (a soft fold hides a third of it)
        self._in = [_wave(rng, 3, 0.25, 0.6) for _ in range(4)]
        self._hem = [_wave(rng) for _ in range(4)]

    def at(self, x, y, z, ux, uy):
        """How far the cloth folds in (n,) and its hem's rise (n,), at rest points
        (x, y, z), the horizontal way out (ux, uy)."""
        weights = (np.maximum(-ux, 0) ** 2, np.maximum(ux, 0) ** 2, np.maximum(-uy, 0) ** 2, np.maximum(uy, 0) ** 2)
        along = (y, y, x, x)
        grow = self.depth_m * np.clip((self.rim_z - z) / self.full_m, 0.0, 1.0) ** 1.5
        inward = grow * sum(w * (1 - f(s)) / 2 for w, f, s in zip(weights, self._in, along))
        rise = 0.15 * grow * sum(w * f(s) for w, f, s in zip(weights, self._hem, along))
        return inward, rise


# 42 directions evenly spread, and the 26 of a box's faces, edges and corners (the builders'
# parts are boxes at heart: their silhouettes' corners lie along those).
_BOX_WAYS = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1) if x or y or z], float)
_SUPPORT_WAYS = np.vstack([trimesh.creation.icosphere(subdivisions=1).vertices,
                           _BOX_WAYS / np.linalg.norm(_BOX_WAYS, axis=1, keepdims=True)])


def _support_points(points) -> np.ndarray:
    """The points (k <= 68, 3) of ``points`` (n, 3) furthest along 68 directions: their
    hull is the points' own within a few percent from any side, and stays so under any
    affine map (extreme points stay extreme)."""
    return np.asarray(points)[np.unique(np.argmax(np.asarray(points) @ _SUPPORT_WAYS.T, axis=0))]


def _grid_normals(P, outward):
    """Unit normals (rows, cols, 3) of a grid of points, from its two directions, on the
    side ``outward`` (rows, cols, 3) points to on the whole (up where they degenerate: a
    corner's rim)."""
    n = np.cross(np.gradient(P, axis=0), np.gradient(P, axis=1))
    n *= np.sign(float((n * outward).sum()) or 1.0)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.where(length > 1e-12, n / np.maximum(length, 1e-12), (0.0, 0.0, 1.0))


def _perimeter(lo, hi, step_m, corner_steps):
    """A rectangle's outline as points (n, 2) and outward directions (n, 2), once round
    counter-clockwise from its (lo, lo) corner; at each corner the direction turns
    through 90 degrees in ``corner_steps`` steps. Sides are cut every ``step_m`` or finer."""
    corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    outward = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    points, ways = [], []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        count = max(1, int(np.ceil(np.linalg.norm(b - a) / step_m)))
        t = np.linspace(0.0, 1.0, count + 1)[:-1]
        points.append(a + t[:, None] * (b - a))
        ways.append(np.repeat(outward[k][None], count, axis=0))
        turn = np.linspace(0.0, np.pi / 2, corner_steps + 1)[:-1]  # at b, from this side's way to the next's
        c0 = math.atan2(outward[k][1], outward[k][0])
        points.append(np.repeat(b[None], corner_steps, axis=0))
        ways.append(np.column_stack([np.cos(c0 + turn), np.sin(c0 + turn)]))
    return np.concatenate(points), np.concatenate(ways)


def _draped_mesh(lo_xy, hi_xy, z_top, radius, hang_m, folds: Folds | None = None, puff_m=0.0, rng=None,
                 step_m=0.02, top_step_m=0.05):
    """Cloth covering the rectangle ``lo_xy``-``hi_xy`` at height ``z_top`` and hanging down
    its four sides (a duvet, a sheet, a throw): over the rim by a roll of ``radius``, then
    straight down by ``hang_m`` (left, right, head (low y), foot (high y)); rounded around
    the corners. Its top puffs up by ``puff_m`` toward the middle (unevenly, by ``rng``)
    and the hanging cloth folds as ``folds`` says. (n, 3) vertices, normals, faces and
    texture coordinates (meters along the cloth), and (n,) the light left deep in the
    folds (:attr:`Part.cavity`).

    Two grids: the top, coarse (``top_step_m``), and the skirt round it, fine along the
    rim (``step_m``: layers of bedding sampled apart must not cross in a fold), reaching
    a little onto the top so that no gap opens between them."""
    lo, hi = np.asarray(lo_xy, dtype=np.float64), np.asarray(hi_xy, dtype=np.float64)
    r = float(radius)
    arc = r * np.pi / 2
    reach = arc + np.asarray(hang_m, dtype=np.float64)  # cloth past the top's rim, per side
    core_lo, core_hi = lo + r, hi - r
    size = np.maximum(core_hi - core_lo, 1e-9)
    uneven = (lambda x, y: 1.0) if rng is None else (
        lambda x, y, w=_wave(rng, 3, 0.3, 0.8): 1 + 0.25 * w(x + 0.7 * y))

    def rise(x, y):
        u, w = 2 * (x - core_lo[0]) / size[0] - 1, 2 * (y - core_lo[1]) / size[1] - 1
        return puff_m * (1 - u ** 4) * (1 - w ** 4) * uneven(x, y)

    # The top.
    xs = np.linspace(core_lo[0], core_hi[0], max(2, int(np.ceil(size[0] / top_step_m)) + 1))
    ys = np.linspace(core_lo[1], core_hi[1], max(2, int(np.ceil(size[1] / top_step_m)) + 1))
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    top = np.stack([X, Y, z_top + rise(X, Y)], axis=-1)
    # The skirt: along the rim, and out from it (from a little inside, under the top's edge).
    rim, way = _perimeter(core_lo, core_hi, step_m, max(4, int(np.ceil(reach.max() * np.pi / 2 / step_m))))
    ex = np.where(way[:, 0] < 0, reach[0], reach[1])
    ey = np.where(way[:, 1] < 0, reach[2], reach[3])
    e = np.hypot(way[:, 0] * ex, way[:, 1] * ey)  # how far the cloth runs on past the rim this way
    inside = min(step_m, 0.5 * float(size.min()))
    t = np.concatenate([[-inside], np.linspace(0.0, 1.0, max(3, int(np.ceil(e.max() / step_m))) + 1)])
    d = np.maximum(t[None, :], 0.0) * e[:, None]
    theta = np.minimum(d, arc) / max(r, 1e-9)
    straight = (np.abs(way).max(axis=1) > 1 - 1e-9)[:, None]  # round a corner the strip under the top stays put
    out = r * np.sin(theta) + np.minimum(t[None, :], 0.0) * straight
    drop = r * (1 - np.cos(theta)) + np.maximum(d - arc, 0.0)
    cx, cy = np.broadcast_to(rim[:, :1], d.shape), np.broadcast_to(rim[:, 1:], d.shape)
    ux, uy = np.broadcast_to(way[:, :1], d.shape), np.broadcast_to(way[:, 1:], d.shape)
    inward, hem = (np.zeros(d.shape), 0.0) if folds is None else folds.at(cx, cy, z_top - drop, ux, uy)
    along = ux * (out - inward), uy * (out - inward)
    lift = np.where(t[None, :] < 0, rise(cx + along[0], cy + along[1]) - 1e-4, 0.0)  # the strip under the top
    skirt = np.stack([cx + along[0], cy + along[1], z_top + lift - drop + hem], axis=-1)
    skirt = np.concatenate([skirt, skirt[:1]])  # closed round
    ring_uv = np.concatenate([rim, rim[:1]])[:, None, :] + np.concatenate([way, way[:1]])[:, None, :] * (
        np.concatenate([d, d[:1]]) + np.minimum(t, 0.0)[None, :] * np.concatenate([straight, straight[:1]]))[..., None]
    up = np.array([0.0, 0.0, 1.0])
    away = np.concatenate([way, way[:1]])
    grids = [(top, up, _face_grid(xs, ys), np.column_stack([X.ravel(), Y.ravel()]), np.ones(top.shape[:2])),
             (skirt, np.column_stack([away, np.ones(len(away))])[:, None, :], _face_grid(np.arange(len(skirt)), t),
              ring_uv.reshape(-1, 2),
              1.0 - (0.0 if folds is None else folds.valley_dark / folds.depth_m)
              * np.concatenate([inward, inward[:1]]))]
    vs, ns, fs, uvs, cav = [], [], [], [], []
    count = 0
    for k, (P, outward, faces, uv, c) in enumerate(grids):
        n = _grid_normals(P, np.broadcast_to(outward, P.shape))
        if k == 1:  # the strip under the top and the rim face up (round a corner they are single points)
            n[:, :2] = (0.0, 0.0, 1.0)
        vs.append(P.reshape(-1, 3))
        ns.append(n.reshape(-1, 3))
        fs.append(_oriented(vs[-1], ns[-1], faces) + count)
        uvs.append(uv)
        cav.append(np.ravel(c))
        count += len(vs[-1])
    v = np.concatenate(vs)
    return v, np.concatenate(ns), np.concatenate(fs), np.concatenate(uvs), np.concatenate(cav)


def _lathe_mesh(profile, sections, arc=(0.0, 2 * np.pi), smooth_deg=35.0):
    """Revolve a profile of (radius, z) points about the z axis. Consecutive profile edges
    meeting at less than ``smooth_deg`` share a normal (curved), else the edge is sharp.
    Texture coordinates (meters): on the sides u along the axis (a turned leg's grain), v
    around it at the widest radius, the seam's vertices doubled so that v does not wrap;
    tops and steps as seen from above."""
    prof = np.asarray(profile, dtype=np.float64)
    seg_dir = np.diff(prof, axis=0)
    seg_len = np.linalg.norm(seg_dir, axis=1)
    keep = seg_len > 1e-9
    starts, ends, seg_dir = prof[:-1][keep], prof[1:][keep], seg_dir[keep] / seg_len[keep, None]
    seg_n = np.stack([seg_dir[:, 1], -seg_dir[:, 0]], axis=1)  # outward (right of travel)
    phi = np.linspace(arc[0], arc[1], sections + 1)
    cos_p, sin_p = np.cos(phi), np.sin(phi)
    around = phi * max(float(np.abs(prof[:, 0]).max()), 1e-3)
    cos_limit = math.cos(math.radians(smooth_deg))
    verts, norms, faces, uvs = [], [], [], []
    count = 0
    for k in range(len(starts)):
        ends_n = []
        for j, nb in ((k - 1, 0), (k + 1, 1)):
            n = seg_n[k]
            if 0 <= j < len(starts) and float(seg_n[j] @ seg_n[k]) > cos_limit:
                n = seg_n[j] + seg_n[k]
                n = n / np.linalg.norm(n)
            ends_n.append(n)
        ring = []
        for (r, z), (nr, nz) in ((starts[k], ends_n[0]), (ends[k], ends_n[1])):
            p = np.column_stack([r * cos_p, r * sin_p, np.full_like(phi, z)])
            n = np.column_stack([nr * cos_p, nr * sin_p, np.full_like(phi, nz)])
            ring.append((p, n))
        m = len(phi)
        verts += [ring[0][0], ring[1][0]]
        norms += [ring[0][1], ring[1][1]]
        if abs(ends[k][1] - starts[k][1]) >= abs(ends[k][0] - starts[k][0]):  # a side: along the axis, around
            uvs += [np.column_stack([np.full(m, z), around]) for z in (starts[k][1], ends[k][1])]
        else:  # a top or a step: seen from above
            uvs += [ring[0][0][:, :2], ring[1][0][:, :2]]
        i = np.arange(m - 1)
        j = i + 1
        a, b, c, d = i + count, j + count, j + m + count, i + m + count
        quads = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
        faces.append(quads)
        count += 2 * m
    v, n, f = np.concatenate(verts), np.concatenate(norms), np.concatenate(faces)
    tri = v[f]
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    f = f[area > 1e-14]
    return v, n, _oriented(v, n, f), np.concatenate(uvs)


def _planar_uv(v, n):
    """Texture coordinates (meters) of vertices projected along their normal's main axis:
    for meshes whose faces do not share vertices across such axes."""
    axis = np.abs(n).argmax(axis=1)
    first, second = np.array([1, 2, 0])[axis], np.array([2, 0, 1])[axis]
    rows = np.arange(len(v))
    return np.column_stack([v[rows, first], v[rows, second]])


def _hull_mesh(points):
    hull = trimesh.convex.convex_hull(np.asarray(points, dtype=np.float64))
    v = hull.vertices[hull.faces].reshape(-1, 3)
    n = np.repeat(hull.face_normals, 3, axis=0)
    f = np.arange(len(v)).reshape(-1, 3)
    return v, n, f, _planar_uv(v, n)


_ICO = trimesh.creation.icosphere(subdivisions=2)


def _leaf_outlines(bases, directions, lengths, widths, bends, twists, steps: int):
    """Leaves' outlines, (n, steps + 1, 3) each: midrib, left and right edge from the
    stalk to the tip (an ellipse-like outline, folded along the midrib by ``bends``
    radians, drooping with its length, turned by ``twists`` about it); with the leaves'
    unit directions and across-vectors, (n, 3). ``bases``, ``directions`` (n, 3), the
    rest (n,)."""
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    side = np.cross(d, [0, 0, 1.0])
    side[np.linalg.norm(side, axis=1) < 1e-6] = (1.0, 0.0, 0.0)
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    up = np.cross(side, d)
    c, s = np.cos(np.asarray(twists, dtype=np.float64))[:, None], np.sin(np.asarray(twists, dtype=np.float64))[:, None]
    side, up = c * side + s * up, -s * side + c * up
    ts = np.linspace(0.0, 1.0, steps + 1)
    length = np.asarray(lengths, dtype=np.float64).reshape(-1, 1)
    half = (np.asarray(widths, dtype=np.float64).reshape(-1, 1) / 2 * np.sin(np.pi * ts) ** 0.8)[..., None]
    mid = (np.asarray(bases, dtype=np.float64).reshape(-1, 1, 3) + (ts * length)[..., None] * d[:, None]
           + (-0.25 * length * ts ** 2)[..., None] * np.array([0, 0, 1.0]))
    fold = np.sin(np.asarray(bends, dtype=np.float64)).reshape(-1, 1, 1)
    left = mid - half * side[:, None] + (half * fold) * up[:, None]
    right = mid + half * side[:, None] + (half * fold) * up[:, None]
    return mid, left, right, d, side


class _Shop:
    """Collects the parts of one piece of furniture, in the builder frame."""

    def __init__(self):
        self.parts: list[Part] = []

    def _add(self, v, n, f, uv, mat, convex=True, shadow=True, matrix=None, cavity=None, outline=None) -> Part:
        # Each part starts its surface elsewhere, so that neighbours' grain does not line up.
        phase = abs(math.sin(float(v.mean(axis=0) @ (12.9898, 78.233, 37.719))))
        start = np.modf(phase * np.array([43758.55, 24634.63]))[0]
        part = Part(v, n, f, mat, uv + 3.0 * start, convex, shadow, cavity, outline)
        if matrix is not None:
            part = part.transformed(matrix)
        self.parts.append(part)
        return part

    def box(self, lo, hi, mat, round_m=0.0, segments=1, shadow=True, matrix=None) -> Part:
        """Axis-aligned box from corner ``lo`` to ``hi``, edges rounded by ``round_m``."""
        return self._add(*_rounded_box_mesh(lo, hi, round_m, segments), mat, True, shadow, matrix)

    def cushion(self, lo, hi, mat, round_m=0.04, crown_m=(0.01, 0.01, 0.015), matrix=None) -> Part:
        """A stuffed cushion filling the box ``lo``-``hi``, its sides bulging by ``crown_m``."""
        mesh = _crowned_box_mesh(lo, hi, round_m, crown_m)
        return self._add(*mesh, mat, True, True, matrix, outline=_support_points(mesh[0]))

    def drape(self, lo_xy, hi_xy, z_top, mat, rng, radius=0.04, hang_m=(0.1, 0.1, 0.1, 0.1), folds=None,
              puff_m=0.0) -> Part:
        """Cloth over a rectangle, hanging down its sides (:func:`_draped_mesh`)."""
        *mesh, cavity = _draped_mesh(lo_xy, hi_xy, z_top, radius, hang_m, folds, puff_m, rng)
        return self._add(*mesh, mat, cavity=cavity, outline=_support_points(mesh[0]))

    def lathe(self, x, y, profile, mat, sections=24, arc=(0.0, 2 * np.pi), convex=True, shadow=True,
              matrix=None) -> Part:
        """A turned part: ``profile`` (radius, z) pairs revolved about the vertical through (x, y)."""
        m = _move(x, y, 0.0) if matrix is None else matrix @ _move(x, y, 0.0)
        return self._add(*_lathe_mesh(profile, sections, arc), mat, convex, shadow, m)

    def cylinder(self, x, y, z0, z1, radius, mat, sections=16, radius_top=None, shadow=True) -> Part:
        rt = radius if radius_top is None else radius_top
        return self.lathe(x, y, [(0, z0), (radius, z0), (rt, z1), (0, z1)], mat, sections, shadow=shadow)

    def rod(self, p0, p1, radius, mat, sections=10, radius_end=None, shadow=True) -> Part:
        """A cylinder from point ``p0`` to ``p1`` (tapering to ``radius_end``)."""
        p0, p1 = np.asarray(p0, dtype=np.float64), np.asarray(p1, dtype=np.float64)
        axis = p1 - p0
        length = float(np.linalg.norm(axis))
        re = radius if radius_end is None else radius_end
        mesh = _lathe_mesh([(0, 0), (radius, 0), (re, length), (0, length)], sections)
        R = np.eye(4)
        R[:3, :3] = trimesh.geometry.align_vectors([0, 0, 1.0], axis / length)[:3, :3]
        return self._add(*mesh, mat, True, shadow, _move(*p0) @ R)

    def ellipsoid(self, center, radii, mat, shadow=True, matrix=None) -> Part:
        radii = np.asarray(radii, dtype=np.float64)
        v = _ICO.vertices * radii
        n = _ICO.vertices / radii
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        m = _move(*center) if matrix is None else matrix @ _move(*center)
        flat = np.argsort(radii)[::-1][:2]  # seen from its flattest side, as a cushion is
        return self._add(v, n, _oriented(v, n, _ICO.faces.copy()), v[:, flat], mat, True, shadow, m)

    def reach(self, first, axis, target, side=1, last=None):
        """Stretch parts ``first:last`` along ``axis`` about their far bound until their
        upper (``side`` = 1) or lower (-1) bound lies on ``target``: a leaning cushion or a
        tuft of leaves made to touch the item's box."""
        group = self.parts[first:last]
        v = np.concatenate([p.vertices[:, axis] for p in group])
        lo, hi = float(v.min()), float(v.max())
        pivot, scale = (lo, (target - lo) / (hi - lo)) if side > 0 else (hi, (hi - target) / (hi - lo))
        m = np.eye(4)
        m[axis, axis] = scale
        m[axis, 3] = pivot * (1 - scale)
        stop = len(self.parts) if last is None else last
        self.parts[first:stop] = [p.transformed(m) for p in group]

    def hull(self, points, mat, shadow=True) -> Part:
        return self._add(*_hull_mesh(points), mat, True, shadow)

    def leaves(self, bases, directions, lengths, widths, mat, bends, twists, segments=4) -> Part:
        """Many small leaves at once, as :meth:`leaf` draws one (``bases``, ``directions``
        (n, 3); the rest (n,)), coarser (``segments`` steps along each) and in one part
        that casts no shadow: a bush's hundreds of leaves as one mesh."""
        mid, left, right, d, side = _leaf_outlines(bases, directions, lengths, widths, bends, twists, segments)
        # Points per leaf: the midrib's, then the left edge's, then the right's; both sides
        # share them, the back's normals turned round.
        k = segments + 1
        pts = np.concatenate([mid, left, right], axis=1)  # (n, 3k, 3)
        i = np.arange(segments)
        L, M, Rt = i + k, i, i + 2 * k
        template = np.concatenate([np.stack([M, L, L + 1], 1), np.stack([M, L + 1, M + 1], 1),
                                   np.stack([M, M + 1, Rt + 1], 1), np.stack([M, Rt + 1, Rt], 1)])
        tri = pts[:, template]  # (n, t, 3, 3)
        fn = np.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0])
        normals = np.zeros_like(pts)
        for corner in range(3):
            np.add.at(normals, (slice(None), template[:, corner]), fn)
        normals /= np.maximum(np.linalg.norm(normals, axis=2, keepdims=True), 1e-12)
        count = len(d)
        faces = (template[None] + (3 * k * np.arange(count))[:, None, None]).reshape(-1, 3)
        v = pts.reshape(-1, 3)
        rel = pts - np.asarray(bases, dtype=np.float64)[:, None]
        uv = np.stack([(rel * d[:, None]).sum(2), (rel * side[:, None]).sum(2)], axis=2).reshape(-1, 2)
        back = len(v)
        return self._add(np.concatenate([v, v]), np.concatenate([normals.reshape(-1, 3), -normals.reshape(-1, 3)]),
                         np.concatenate([faces, faces[:, ::-1] + back]), np.concatenate([uv, uv]), mat, False, False)

    def leaf(self, base, direction, length, width, mat, bend=0.0, twist=0.0, shadow=True) -> Part:
        """A flat leaf (both sides) from ``base`` along ``direction``: an ellipse-like outline
        folded along its midrib by ``bend`` (radians) and drooping with its length."""
        mid, left, right, d, side = (a[0] for a in _leaf_outlines(base, direction, [length], [width], [bend],
                                                                   [twist], 6))
        pts = np.concatenate([mid, left[1:-1], right[1:-1]])
        k = len(mid)
        L = lambda i: k + i - 1  # noqa: E731  (left[i], i in 1..k-2)
        R = lambda i: k + (k - 2) + i - 1  # noqa: E731
        tris = []
        for i in range(k - 1):
            li = L(i) if 1 <= i <= k - 2 else i
            ri = R(i) if 1 <= i <= k - 2 else i
            lj = L(i + 1) if 1 <= i + 1 <= k - 2 else i + 1
            rj = R(i + 1) if 1 <= i + 1 <= k - 2 else i + 1
            tris += [[i, li, lj], [i, lj, i + 1], [i, i + 1, rj], [i, rj, ri]]
        f = np.array([t for t in tris if len(set(t)) == 3])
        tri = pts[f]
        fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        fn /= np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-12)
        # Both sides, flat-shaded per face so light falls correctly on each.
        v = np.concatenate([tri.reshape(-1, 3), tri[:, ::-1].reshape(-1, 3)])
        n = np.concatenate([np.repeat(fn, 3, axis=0), np.repeat(-fn, 3, axis=0)])
        faces = np.arange(len(v)).reshape(-1, 3)
        uv = np.column_stack([(v - base) @ d, (v - base) @ side])  # along the leaf, across it
        return self._add(v, n, faces, uv, mat, False, shadow)


# --------------------------------------------------------------------------------------
# Shared assemblies
# --------------------------------------------------------------------------------------

def _legs(shop, xs, ys, z0, z1, mat, style, thick, splay=0.0):
    """Four (or more) legs at the grid ``xs`` x ``ys``: ``square``, ``round``, ``tapered``
    (round, narrowing to the floor, splayed outward by ``splay`` meters) or ``hairpin``."""
    for x in xs:
        for y in ys:
            if style == "square":
                shop.box((x - thick / 2, y - thick / 2, z0), (x + thick / 2, y + thick / 2, z1), mat, 0.003)
            elif style == "round":
                shop.cylinder(x, y, z0, z1, thick / 2, mat, 12)
            elif style == "tapered":
                sx, sy = np.sign(x) * splay, np.sign(y) * splay
                shop.rod((x + sx, y + sy, z0), (x, y, z1), thick * 0.3, mat, 10, radius_end=thick / 2)
            elif style == "hairpin":  # a bent rod: two legs meeting at the foot
                r = 0.006
                dy = min(0.08, abs(ys[0] - ys[-1]) * 0.15 + 0.03)
                inward = -np.sign(y) if y else 1.0
                foot = (x + np.sign(x) * splay, y + inward * dy, z0)
                for off in (0.0, 2 * dy):
                    shop.rod(foot, (x, y + inward * off, z1), r, mat, 6)
            else:
                raise ValueError(f"leg style {style!r}")


def _table(shop, rng, W, D, H, top_mat, leg_mat, style, top_t=None, round_top=False, shelf=False, apron=True):
    """A table: top slab (rectangular or round) and a base of ``style``."""
    top_t = top_t or float(np.clip(0.035 * (H / 0.75) + 0.01, 0.02, 0.05))
    zt = H - top_t
    if round_top:
        r = min(W, D) / 2
        edge = min(0.008, top_t / 3)
        shop.lathe(0, 0, [(0, zt), (r - edge, zt), (r, zt + edge), (r, H - edge), (r - edge, H), (0, H)], top_mat, 48)
    else:
        shop.box((-W / 2, -D / 2, zt), (W / 2, D / 2, H), top_mat, min(0.006, top_t / 3))
    inset = 0.06 if not round_top else min(W, D) * 0.22
    lw = float(np.clip(0.05 * (H / 0.75), 0.03, 0.07))
    if style == "pedestal":
        rb = min(W, D) * (0.3 if round_top else 0.25)
        shop.lathe(0, 0, [(0, 0), (rb, 0), (rb, 0.02), (rb * 0.35, 0.06), (0.04, 0.12), (0.035, zt * 0.7),
                          (0.05, zt - 0.02), (0.12 if round_top else 0.08, zt), (0, zt)], leg_mat, 32)
        return
    if style == "trestle":
        for s in (-1, 1):
            x = s * (W / 2 - max(0.12, W * 0.12))
            shop.box((x - lw / 2, -D / 2 + 0.08, 0), (x + lw / 2, D / 2 - 0.08, 0.05), leg_mat, 0.004)
            shop.box((x - lw / 2, -lw, 0.05), (x + lw / 2, lw, zt), leg_mat, 0.004)
            shop.box((x - lw / 2, -D / 2 + 0.12, zt - 0.05), (x + lw / 2, D / 2 - 0.12, zt), leg_mat, 0.004)
        shop.box((-W / 2 + 0.15, -0.02, zt * 0.35), (W / 2 - 0.15, 0.02, zt * 0.35 + 0.06), leg_mat, 0.004)
        return
    if style == "frame":  # metal sled frames at the ends
        t = 0.02
        for s in (-1, 1):
            x = s * (W / 2 - 0.05)
            for y in (-D / 2 + 0.04, D / 2 - 0.04):
                shop.box((x - t / 2, y - t / 2, 0), (x + t / 2, y + t / 2, zt), leg_mat, 0.002)
            shop.box((x - t / 2, -D / 2 + 0.04, 0), (x + t / 2, D / 2 - 0.04, t), leg_mat, 0.002)
            shop.box((x - t / 2, -D / 2 + 0.04, zt - t), (x + t / 2, D / 2 - 0.04, zt), leg_mat, 0.002)
        if shelf:
            shop.box((-W / 2 + 0.05, -D / 2 + 0.04, 0.12), (W / 2 - 0.05, D / 2 - 0.04, 0.14), top_mat, 0.002)
        return
    if round_top:
        c = (min(W, D) / 2 - inset) / math.sqrt(2)
        xs, ys = (-c, c), (-c, c)
    else:
        xs, ys = (-W / 2 + inset, W / 2 - inset), (-D / 2 + inset, D / 2 - inset)
    splay = 0.03 if style in ("tapered", "hairpin") else 0.0
    if style in ("tapered", "hairpin"):
        xs = tuple(x - np.sign(x) * splay for x in xs)
        ys = tuple(y - np.sign(y) * splay * 0.5 for y in ys)
    _legs(shop, xs, ys, 0.0, zt, leg_mat, style, lw, splay)
    if apron and style in ("square", "round") and not round_top:
        ah = min(0.08, zt * 0.15)
        a = 0.02
        shop.box((xs[0], ys[0] - a / 2 + lw / 2 - 0.01, zt - ah), (xs[1], ys[0] + a / 2, zt), top_mat)
        shop.box((xs[0], ys[1] - a / 2, zt - ah), (xs[1], ys[1] + a / 2 - lw / 2 + 0.01, zt), top_mat)
        shop.box((xs[0] - a / 2, ys[0], zt - ah), (xs[0] + a / 2, ys[1], zt), top_mat)
        shop.box((xs[1] - a / 2, ys[0], zt - ah), (xs[1] + a / 2, ys[1], zt), top_mat)
    if shelf:
        zs = zt * 0.3
        shop.box((xs[0], ys[0], zs), (xs[1], ys[1], zs + 0.018), top_mat, 0.003)


def _base(shop, rng, W, D, z_top, mat, style):
    """What a cabinet stands on: a recessed ``plinth``, ``legs`` (tapered) or ``feet``."""
    if style == "plinth":
        shop.box((-W / 2 + 0.03, -D / 2 + 0.03, 0), (W / 2 - 0.03, D / 2 - 0.05, z_top), mat)
    elif style == "legs":
        inset = 0.05
        _legs(shop, (-W / 2 + inset, W / 2 - inset), (-D / 2 + inset, D / 2 - inset), 0.0, z_top + 0.005,
              mat, "tapered", 0.035, 0.015)
    else:
        for x in (-W / 2 + 0.04, W / 2 - 0.04):
            for y in (-D / 2 + 0.04, D / 2 - 0.06):
                shop.cylinder(x, y, 0, z_top + 0.005, 0.025, mat, 12)


def _shell(shop, lo, hi, mat, opening, t=0.018):
    """A cabinet body from ``lo`` to ``hi`` with an open compartment ``opening`` =
    (x0, x1, z0, z1, depth) in its front face: the boards around it and a back recessed by
    ``depth``, in a darker shade of ``mat`` inside (the compartment gets less light)."""
    (X0, Y0, Z0), (X1, Y1, Z1) = lo, hi
    x0, x1, z0, z1, depth = opening
    inside = replace(mat, name=mat.name + " inside", color_rgb=tuple(0.55 * c for c in mat.color_rgb))
    yb = Y1 - depth
    shop.box((X0, Y0, Z0), (X1, yb, Z1), mat, 0.004)  # behind the compartment
    for a, b in (((X0, yb, Z0), (X1, Y1, z0)), ((X0, yb, z1), (X1, Y1, Z1)),
                 ((X0, yb, z0), (x0, Y1, z1)), ((x1, yb, z0), (X1, Y1, z1))):
        if all(bb - aa > 1e-4 for aa, bb in zip(a, b)):
            shop.box(a, b, mat)
    shop.box((x0, yb - 0.002, z0), (x1, yb + 0.001, z1), inside, shadow=False)


def _fronts(shop, x0, x1, z0, z1, y_face, mat, handle_mat, rows, cols, handle, gap=0.004, proud=0.012,
            vertical=False):
    """Drawer or door fronts on the face ``y = y_face`` between x0..x1, z0..z1, with handles,
    and a dark recess behind them that shows in the gaps."""
    ws, hs = (x1 - x0) / cols, (z1 - z0) / rows
    shop.box((x0, y_face - 0.001, z0), (x1, y_face + 0.001, z1), _RECESS, shadow=False)
    for i in range(cols):
        for j in range(rows):
            a, b = x0 + i * ws + gap / 2, x0 + (i + 1) * ws - gap / 2
            c, d = z0 + j * hs + gap / 2, z0 + (j + 1) * hs - gap / 2
            shop.box((a, y_face - 0.002, c), (b, y_face + proud, d), mat, 0.002)
            if handle == "none":
                continue
            yh = y_face + proud
            if vertical:
                hx = b - 0.04 if i % 2 == 0 else a + 0.04
                hz = (c + d) / 2
                if handle == "knob":
                    shop.ellipsoid((hx, yh + 0.012, hz), (0.014, 0.012, 0.014), handle_mat, shadow=False)
                else:
                    L = min(0.3, (d - c) * 0.35)
                    shop.box((hx - 0.006, yh, hz - L / 2), (hx + 0.006, yh + 0.025, hz + L / 2), handle_mat, 0.004,
                             shadow=False)
            else:
                hx, hz = (a + b) / 2, c + (d - c) * 0.6 if rows > 1 else (c + d) / 2
                if handle == "knob":
                    for kx in ((hx,) if (b - a) < 0.6 else (a + (b - a) * 0.25, b - (b - a) * 0.25)):
                        shop.ellipsoid((kx, yh + 0.012, hz), (0.014, 0.012, 0.014), handle_mat, shadow=False)
                else:
                    L = min(0.18, (b - a) * 0.4)
                    shop.box((hx - L / 2, yh, hz - 0.006), (hx + L / 2, yh + 0.022, hz + 0.006), handle_mat, 0.004,
                             shadow=False)


def _cushion(shop, lo, hi, mat, round_m=0.04, matrix=None, piping_m=0.004):
    """A stuffed cushion: it bulges most across its thinnest side, as a pillow does, and
    piping (a cord ``piping_m`` thick, 0 for none) runs round its two big faces where their
    panels meet the sides: along the middle of the rounded rims and round the corners."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    size = hi - lo
    a = int(size.argmin())
    crown = 0.07 * size.min() * np.ones(3)
    crown[a] = 0.2 * size.min()
    part = shop.cushion(lo, hi, mat, round_m, crown, matrix)
    if piping_m <= 0:
        return part
    _, r, inner = _crowned_core(lo, hi, round_m, crown)
    if r < RENDER.furniture.bevel_min_m or inner.min() <= 0:
        return part
    center = (lo + hi) / 2
    b, d = (k for k in range(3) if k != a)
    # Round a big face: 45 degrees down its rims, each corner an eighth of a sphere's seam.
    turn = np.linspace(0.0, np.pi / 2, 4)
    loop = []
    for sb, sd, start in ((1, 1, 0.0), (-1, 1, np.pi / 2), (-1, -1, np.pi), (1, -1, 1.5 * np.pi)):
        phi = start + turn
        point = np.zeros((len(phi), 3))
        point[:, b] = sb * inner[b] + r / math.sqrt(2) * np.cos(phi)
        point[:, d] = sd * inner[d] + r / math.sqrt(2) * np.sin(phi)
        loop.append(point)
    loop = np.concatenate(loop) + center
    up = np.eye(3)[a]
    for sa in (-1.0, 1.0):
        loop[:, a] = center[a] + sa * (inner[a] + r / math.sqrt(2))
        shop._add(*_loop_tube_mesh(loop, piping_m / 2, up), mat, False, False, matrix)
    return part


def _loop_tube_mesh(points, radius, up, sections=6):
    """A tube of ``radius`` round the closed loop ``points`` (k, 3), lying in a plane across
    the unit vector ``up``: one ring of ``sections`` vertices at each point, swept without
    twist. (n, 3) vertices, normals, faces, uv (meters along and around)."""
    points = np.asarray(points, dtype=np.float64)
    k = len(points)
    tangent = np.roll(points, -1, axis=0) - np.roll(points, 1, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
    u = np.cross(tangent, up)
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-12)
    v = np.cross(tangent, u)
    angle = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    ring = np.cos(angle)[None, :, None] * u[:, None] + np.sin(angle)[None, :, None] * v[:, None]  # (k, s, 3)
    vs = (points[:, None] + radius * ring).reshape(-1, 3)
    ns = ring.reshape(-1, 3)
    i, j = np.meshgrid(np.arange(k), np.arange(sections), indexing="ij")
    a, b = i * sections + j, i * sections + (j + 1) % sections
    c, d = ((i + 1) % k) * sections + (j + 1) % sections, ((i + 1) % k) * sections + j
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    uv = np.stack([np.repeat(along, sections), np.tile(radius * angle, k)], axis=1)
    return vs, ns, _oriented(vs, ns, faces), uv


# --------------------------------------------------------------------------------------
# Builders, one per kind: (shop, rng, W, D, H) -> style name
# --------------------------------------------------------------------------------------

def _bed(shop, rng, W, D, H, pillows=None):
    style = _pick(rng, ("upholstered", "wood", "metal"))
    frame = (_fabric(rng) if style == "upholstered" else _wood(rng) if style == "wood"
             else _metal(rng, ("black steel", "white steel")))
    sheet = _mat(rng, *_pick(rng, _styled("bedding", BEDDING)), 0.95)
    duvet = _mat(rng, *_pick(rng, _styled("bedding", BEDDING)), 0.95)
    mattress = _mat(rng, "mattress", (232, 230, 224), 0.9, spread=0.02)
    # A mattress at sitting height, plump pillows leaning on the headboard, which rises to H;
    # a bed without its headboard (H 0.5 m) is all bed.
    mattress_top = min(0.55, H - min(0.18, 0.36 * H))
    tm = min(0.22, 0.45 * mattress_top)
    frame_top = mattress_top - tm + 0.05
    head_t = 0.07 if style != "metal" else 0.03
    leg_h = 0.1 if style != "upholstered" else 0.03
    y_head = -D / 2 + head_t
    if style == "upholstered":
        shop.box((-W / 2, y_head - 0.01, leg_h), (W / 2, D / 2, frame_top), frame, 0.03, 2)
        shop.box((-W / 2, -D / 2, leg_h), (W / 2, y_head + 0.02, H), frame, 0.03, 3)
        for x in (-W / 2 + 0.08, W / 2 - 0.08):
            for y in (-D / 2 + 0.08, D / 2 - 0.08):
                shop.cylinder(x, y, 0, leg_h + 0.005, 0.025, _metal(rng, ("black steel",)), 10)
    elif style == "wood":
        rail = 0.03
        shop.box((-W / 2, y_head, leg_h + 0.06), (W / 2, D / 2, frame_top), frame, 0.005)
        for x in (-W / 2 + 0.05, W / 2 - 0.05):
            for y in (y_head + 0.05, D / 2 - 0.05):
                shop.box((x - 0.035, y - 0.035, 0), (x + 0.035, y + 0.035, leg_h + 0.07), frame, 0.004)
        shop.box((-W / 2, -D / 2, leg_h), (W / 2, y_head + rail, H), frame, 0.006)
    else:
        t = 0.018
        shop.box((-W / 2, y_head, frame_top - 0.12), (W / 2, D / 2, frame_top - 0.09), frame, 0.003)
        for x in (-W / 2 + t, W / 2 - t):
            shop.rod((x, -D / 2 + t, 0), (x, -D / 2 + t, H), t, frame, 8)
            shop.rod((x, D / 2 - t, 0), (x, D / 2 - t, frame_top - 0.09), t, frame, 8)
        for z in (H - t, frame_top + 0.02):
            shop.rod((-W / 2 + t, -D / 2 + t, z), (W / 2 - t, -D / 2 + t, z), t * 0.8, frame, 8)
        n_bars = max(3, int(W / 0.14))
        for x in np.linspace(-W / 2 + t, W / 2 - t, n_bars + 2)[1:-1]:
            shop.rod((x, -D / 2 + t, frame_top + 0.02), (x, -D / 2 + t, H - t), 0.007, frame, 6)
        shop.box((-W / 2 + t, y_head, frame_top - 0.09), (W / 2 - t, D / 2, frame_top - 0.05), frame, 0.002)
        frame_top = frame_top - 0.05
    ins = 0.02 if style != "metal" else 0.015
    folds = Folds(rng, 0.04, mattress_top - 0.01)  # the bedding folds in this far: the mattress stands back
    m_in = ins + folds.depth_m
    shop.box((-W / 2 + m_in, y_head + ins, frame_top - 0.05), (W / 2 - m_in, D / 2 - m_in, mattress_top), mattress,
             0.05, 2)
    # A lofty duvet over most of the mattress, rolling over its sides and hanging in folds
    # down to the frame, turned down at the head.
    loft = 0.08  # the duvet's top above the mattress's
    r = r_duvet = 0.075
    fold_y = y_head + 0.37 + r
    # Duvet, turned-down sheet and throw overlap: their sides stand 8 mm apart, never
    # in one plane (coplanar faces flicker between the two colours) nor crossing in a fold;
    # the sheet, higher, rolls over the duvet's edges (from beyond its head's) by as much
    # larger a radius, so that it follows them rather than standing off them like a lid.
    edge = ins * 0.9  # how far the bedding hangs over the mattress
    x_out, y_out = W / 2 - ins + edge, D / 2 - ins + edge
    hang = max(0.05, mattress_top + loft - r - (frame_top + 0.008))
    shop.drape((-x_out + 0.008, fold_y - r), (x_out - 0.008, y_out - 0.008), mattress_top + loft, duvet, rng,
               r, (hang, hang, 0.0, hang), folds, puff_m=0.025)
    r = r_duvet + 0.02
    shop.drape((-x_out, fold_y - r_duvet - 0.01), (x_out, fold_y + 0.2), mattress_top + loft + 0.02, sheet, rng, r,
               (0.065, 0.065, 0.02, 0.0), folds, puff_m=0.01)
    n = pillows or (2 if W > 1.2 else 1)
    pw = (W - 2 * ins - 0.08 - (n - 1) * 0.04) / n
    # Pillows propped against a headboard that rises well above them (resting on the
    # mattress at the front, their back end raised), else lying flat under the box's top.
    thick, deep = min(0.16, H - mattress_top - 0.02), 0.38
    propped = H - mattress_top >= 0.36
    y_front = y_head + 0.01 + deep
    tilt = (_move(0, -0.04, 0) @ _about((0, y_front, mattress_top - 0.01), _rot_x(math.radians(-25))) if propped
            else None)
    for i in range(n):
        x0 = -W / 2 + ins + 0.04 + i * (pw + 0.04)
        shop.cushion((x0, y_front - deep, mattress_top - 0.01), (x0 + pw, y_front, mattress_top - 0.01 + thick),
                     sheet, 0.03, (0.015, 0.03, 0.3 * thick), tilt)
    if rng.random() < 0.5:
        throw = _mat(rng, *_pick(rng, _styled("bedding", BEDDING) + _styled("fabrics", FABRICS)), 0.95)
        # Folded across the foot on the duvet's flat top, short of its rolled edges (round
        # the corners of a cloth draped over them the duvet would show through).
        x_top, y_top = x_out - 0.008 - r_duvet, y_out - 0.008 - r_duvet
        shop.drape((-x_top, D / 2 - 0.5), (x_top, y_top), mattress_top + loft + 0.035, throw, rng, 0.02,
                   (0.02,) * 4, None, puff_m=0.003)
    return style


def _single_bed(shop, rng, W, D, H):
    return _bed(shop, rng, W, D, H, pillows=1)


def _nightstand(shop, rng, W, D, H):
    style = _pick(rng, ("drawers", "open shelf", "legs"))
    body = _finish(rng)
    front = body if rng.random() < 0.6 else _finish(rng)
    handle = _metal(rng, ("brass", "black steel", "brushed steel"))
    proud = 0.012
    base_h = 0.12 if style == "legs" else 0.02
    y_face = D / 2 - proud - 0.025  # knobs stand 25 mm proud of the drawer fronts
    _base(shop, rng, W, y_face + D / 2, base_h, body, "legs" if style == "legs" else "plinth")
    shop.parts[-1] = shop.parts[-1].transformed(_move(0, (y_face - D / 2) / 2, 0))
    if style == "open shelf":
        zm = base_h + (H - base_h) * 0.45
        _shell(shop, (-W / 2, -D / 2, base_h), (W / 2, y_face, H), body,
               (-W / 2 + 0.018, W / 2 - 0.018, base_h + 0.018, zm - 0.009, D * 0.75))
        _books(shop, rng, -W / 2 + 0.03, W / 2 - 0.03, base_h + 0.018, zm - 0.02, y_face - D * 0.75, y_face - 0.02)
        _fronts(shop, -W / 2 + 0.01, W / 2 - 0.01, zm, H - 0.02, y_face, front, handle, 1, 1, "knob")
    else:
        shop.box((-W / 2, -D / 2, base_h), (W / 2, y_face, H), body, 0.004)
        rows = 2 if style == "drawers" else 1
        _fronts(shop, -W / 2 + 0.01, W / 2 - 0.01, base_h + 0.02, H - 0.02, y_face, front, handle, rows, 1,
                "knob" if rng.random() < 0.5 else "bar")
    return style


def _wardrobe(shop, rng, W, D, H):
    style = _pick(rng, ("modern", "bar handles", "classic"))
    body = _paint(rng) if style == "modern" else _finish(rng)
    handle = _metal(rng, ("brushed steel", "black steel", "brass"))
    proud, hd = 0.018, 0.03
    y_face = D / 2 - proud - hd
    base_h = 0.08 if style != "classic" else 0.12
    _base(shop, rng, W, y_face + D / 2, base_h, body, "plinth" if style != "classic" else "feet")
    shop.parts[-1] = shop.parts[-1].transformed(_move(0, (y_face - D / 2) / 2, 0))
    top = H - (0.05 if style == "classic" else 0.0)
    shop.box((-W / 2 + 0.005, -D / 2, base_h), (W / 2 - 0.005, y_face, top), body, 0.004)
    if style == "classic":
        shop.box((-W / 2, -D / 2, top), (W / 2, y_face + proud + 0.02, H), body, 0.01)
    doors = 2 if W < 1.5 else 3
    _fronts(shop, -W / 2 + 0.01, W / 2 - 0.01, base_h + 0.01, top - 0.01, y_face, body, handle, 1, doors,
            "none" if style == "modern" else "bar" if style == "bar handles" else "knob", gap=0.004,
            proud=proud, vertical=True)
    if style == "modern":  # routed grip grooves instead of handles
        ws = (W - 0.02) / doors
        dark = _mat(rng, "groove", (40, 38, 36), 0.8)
        for i in range(doors):
            x = -W / 2 + 0.01 + (i + 0.5) * ws + (0.3 * ws if i % 2 == 0 else -0.3 * ws)
            shop.box((x - 0.012, y_face + proud - 0.001, base_h + 0.9), (x + 0.012, y_face + proud + 0.001,
                     base_h + 1.2), dark, shadow=False)
    # Handles stick out of the doors: the box's front is theirs.
    return style


def _dresser(shop, rng, W, D, H):
    style = _pick(rng, ("legs", "plinth", "sideboard"))
    body = _finish(rng)
    front = body if rng.random() < 0.5 else _finish(rng)
    handle = _metal(rng, ("brass", "black steel", "brushed steel"))
    proud, hd = 0.014, 0.022
    top_t = 0.025
    y_face = D / 2 - proud - hd
    base_h = 0.16 if style in ("legs", "sideboard") else 0.07
    _base(shop, rng, W - 0.04, y_face + D / 2 - 0.04, base_h, body if style != "legs" else _wood(rng),
          "legs" if style != "plinth" else "plinth")
    shop.parts[-1] = shop.parts[-1].transformed(_move(0, (y_face - D / 2) / 2, 0))
    shop.box((-W / 2 + 0.01, -D / 2, base_h), (W / 2 - 0.01, y_face, H - top_t), body, 0.003)
    shop.box((-W / 2, -D / 2, H - top_t), (W / 2, y_face + proud + 0.01, H), body, 0.005)
    kind = "knob" if rng.random() < 0.4 else "bar"
    if style == "sideboard":
        _fronts(shop, -W / 2 + 0.02, W / 2 - 0.02, base_h + 0.01, H - top_t - 0.01, y_face, front, handle, 1,
                2 if W < 1.3 else 3, kind, proud=proud, vertical=True)
    else:
        cols = 2 if W >= 0.9 and rng.random() < 0.6 else 1
        _fronts(shop, -W / 2 + 0.02, W / 2 - 0.02, base_h + 0.01, H - top_t - 0.01, y_face, front, handle, 3, cols,
                kind, proud=proud)
    return style


def _sofa(shop, rng, W, D, H, seats=None):
    style = _pick(rng, ("modern", "rounded", "mid-century"))
    cover = _upholstery(rng)
    accent = _fabric(rng)
    leg_mat = _wood(rng) if style == "mid-century" else _metal(rng, ("black steel", "brushed steel", "brass"))
    leg_h = {"modern": 0.06, "rounded": 0.04, "mid-century": 0.16}[style]
    arm_w = float(np.clip(W * (0.09 if style == "mid-century" else 0.11), 0.07, 0.22))
    arm_h = min(H * (0.66 if style != "mid-century" else 0.7), 0.66)
    seat_h = min(0.45, H * 0.52)
    back_t = float(np.clip(D * 0.18, 0.12, 0.2))
    cushion_t = 0.13
    rr = {"modern": 0.02, "rounded": 0.08, "mid-century": 0.025}[style]
    z_base = leg_h
    # Frame: base between the arms, back, arms.
    shop.box((-W / 2 + arm_w - 0.01, -D / 2 + back_t - 0.02, z_base), (W / 2 - arm_w + 0.01, D / 2 - 0.01,
             seat_h - cushion_t + 0.01), cover, 0.02, 2)
    shop.box((-W / 2 + 0.005, -D / 2, z_base), (W / 2 - 0.005, -D / 2 + back_t, H - 0.17), cover, min(rr, 0.04), 2)
    for s in (-1, 1):
        x0, x1 = (-W / 2, -W / 2 + arm_w) if s < 0 else (W / 2 - arm_w, W / 2)
        shop.box((x0, -D / 2, z_base), (x1, D / 2, arm_h), cover, rr, 3)
    # Seat cushions
    n = seats or (3 if W >= 1.9 else 2 if W >= 1.2 else 1)
    inner = W - 2 * arm_w
    cw = inner / n
    for i in range(n):
        x0 = -W / 2 + arm_w + i * cw + 0.004
        _cushion(shop, (x0, -D / 2 + back_t - 0.02, seat_h - cushion_t), (x0 + cw - 0.008, D / 2, seat_h), cover, 0.045)
    # Back cushions, leaning back
    nb = n if n <= 3 else 2
    bw = inner / nb
    lean = _about((0, -D / 2 + back_t, seat_h), _rot_x(math.radians(12)))
    first = len(shop.parts)
    for i in range(nb):
        x0 = -W / 2 + arm_w + i * bw + 0.004
        _cushion(shop, (x0, -D / 2 + back_t - 0.01, seat_h - 0.01), (x0 + bw - 0.008, -D / 2 + back_t + 0.17,
                 H - 0.035), cover, 0.06, lean)
    shop.reach(first, 2, H)
    shop.reach(first, 1, -D / 2 + 0.01, side=-1)
    # Throw pillows in the corners
    if n >= 2 and rng.random() < 0.7:
        for s in (-1, 1):
            x = s * (W / 2 - arm_w - 0.24)
            turn = _about((x, -D / 2 + back_t + 0.25, seat_h), _rot_z(s * 0.25) @ _rot_x(math.radians(20)))
            _cushion(shop, (x - 0.2, -D / 2 + back_t + 0.17, seat_h), (x + 0.2, -D / 2 + back_t + 0.31, seat_h + 0.38),
                     accent, 0.06, turn)
    xs = (-W / 2 + 0.06, W / 2 - 0.06)
    if W > 1.6:
        xs = (-W / 2 + 0.06, 0.0, W / 2 - 0.06)
    for x in xs:
        for y in (-D / 2 + 0.06, D / 2 - 0.08):
            if style == "mid-century":
                shop.rod((x + np.sign(x) * 0.02, y + np.sign(y) * 0.02, 0), (x, y, leg_h + 0.01), 0.012, leg_mat, 10,
                         radius_end=0.02)
            elif style == "modern":
                shop.box((x - 0.02, y - 0.02, 0), (x + 0.02, y + 0.02, leg_h + 0.01), leg_mat, 0.003)
            else:
                shop.cylinder(x, y, 0, leg_h + 0.01, 0.025, leg_mat, 12)
    return style


def _armchair(shop, rng, W, D, H):
    return _sofa(shop, rng, W, D, H, seats=1)


def _coffee_table(shop, rng, W, D, H):
    style = _pick(rng, ("wood", "marble", "shelf", "hairpin"))
    if style == "marble":
        top = _mat(rng, "marble", (228, 226, 222), 0.15, spread=0.02)
        _table(shop, rng, W, D, H, top, _metal(rng, ("black steel", "brass")), "frame", top_t=0.025, apron=False)
    elif style == "shelf":
        wood = _wood(rng)
        _table(shop, rng, W, D, H, wood, wood, "square", top_t=0.03, shelf=True, apron=False)
    elif style == "hairpin":
        _table(shop, rng, W, D, H, _wood(rng), _metal(rng, ("black steel",)), "hairpin", top_t=0.035, apron=False)
    else:
        wood = _wood(rng)
        _table(shop, rng, W, D, H, wood, wood, "tapered", top_t=0.04, apron=False)
    return style


def _side_table(shop, rng, W, D, H):
    style = _pick(rng, ("pedestal", "square", "drum"))
    if style == "pedestal":
        top = _finish(rng)
        _table(shop, rng, W, D, H, top, _metal(rng, ("black steel", "brass", "white steel")), "pedestal",
               top_t=0.025, round_top=True)
    elif style == "square":
        wood = _wood(rng)
        _table(shop, rng, W, D, H, wood, wood, "square", top_t=0.025, shelf=True, apron=False)
    else:
        body = _mat(rng, *_pick(rng, (("rattan", (180, 140, 90)), ("ceramic", (220, 215, 205)),
                                      ("terrazzo", (200, 195, 185)), ("green glaze", (70, 110, 90)))), 0.5)
        r = min(W, D) / 2
        shop.lathe(0, 0, [(0, 0), (r * 0.92, 0), (r, 0.04), (r * 0.82, H * 0.5), (r, H - 0.03), (r * 0.97, H), (0, H)],
                   body, 40)
    return style


# A TV stand's box holds the TV standing on it; below this height it is the stand alone.
TV_MIN_BOX_M = 0.9
TV_FEET_M = 0.05  # the gap the TV's feet leave between the stand and the panel


def tv_on_stand_m(W, H) -> tuple[float, float, float]:
    """``(stand height, panel width, panel height)`` of the TV on a stand whose box is
    ``W`` wide and ``H`` tall (panel 0 when the box is too low for a TV): a 16:9 panel
    four fifths of the stand's width, on a stand 0.35-0.6 m high."""
    if H < TV_MIN_BOX_M:
        return H, 0.0, 0.0
    panel_w = min(0.82 * W, 1.65)
    stand = float(np.clip(H - TV_FEET_M - (panel_w * 9 / 16 + 0.03), 0.35, 0.6))
    panel_h = H - TV_FEET_M - stand
    return stand, min(panel_w, (panel_h - 0.03) * 16 / 9), panel_h


def _tv(shop, rng, y_back, z_base, feet_m, panel_w, panel_h):
    """A flat TV, off, on a pedestal standing at ``z_base``, its panel ``feet_m`` higher:
    a dark frame and a glossy screen facing the front."""
    frame = _mat(rng, "black plastic", (26, 26, 28), 0.45, spread=0.01)
    screen = _mat(rng, "screen", (6, 7, 9), 0.08, spread=0.0, surface="")
    y0, y1 = y_back, y_back + 0.035
    z = z_base + feet_m
    shop.box((-0.12, y0 - 0.05, z_base), (0.12, y1 + 0.06, z_base + 0.01), frame, 0.004)
    shop.box((-0.03, y0 + 0.005, z_base), (0.03, y1 - 0.01, z + 0.1), frame)
    shop.box((-panel_w / 2, y0, z), (panel_w / 2, y1, z + panel_h), frame, 0.004)
    shop.box((-panel_w / 2 + 0.01, y1 - 0.001, z + 0.02), (panel_w / 2 - 0.01, y1 + 0.002, z + panel_h - 0.01),
             screen, shadow=False)


def _tv_stand(shop, rng, W, D, H):
    style = _pick(rng, ("doors", "open", "soundbar"))
    body = _finish(rng)
    handle = _metal(rng, ("black steel", "brushed steel", "brass"))
    H, panel_w, panel_h = tv_on_stand_m(W, H)
    top = H - (0.07 if style == "soundbar" else 0.0)
    base_h = 0.12 if rng.random() < 0.5 else 0.04
    _base(shop, rng, W, D - 0.02, base_h, _wood(rng) if base_h > 0.1 else body, "legs" if base_h > 0.1 else "plinth")
    shop.parts[-1] = shop.parts[-1].transformed(_move(0, -0.01, 0))
    handles = style != "open" and rng.random() < 0.5
    y_face = D / 2 - 0.012 - (0.025 if handles else 0.0)
    if style == "open":
        _shell(shop, (-W / 2, -D / 2, base_h), (W / 2, y_face, top), body,
               (-W / 2 + 0.018, -W / 6 - 0.009, base_h + 0.018, top - 0.018, D * 0.8))
        # An open compartment holds things, or it reads as a dark hole.
        _books(shop, rng, -W / 2 + 0.03, -W / 6 - 0.02, base_h + 0.018, top - 0.03, y_face - D * 0.8, y_face - 0.02)
        _fronts(shop, -W / 6, W / 2 - 0.01, base_h + 0.01, top - 0.01, y_face, body, handle, 1, 2, "none",
                proud=0.012, vertical=True)
    else:
        shop.box((-W / 2, -D / 2, base_h), (W / 2, y_face, top), body, 0.004)
        _fronts(shop, -W / 2 + 0.01, W / 2 - 0.01, base_h + 0.01, top - 0.01, y_face, body, handle, 1,
                3 if W > 1.2 else 2, "bar" if handles else "none", proud=0.012, vertical=True)
    if style == "soundbar":
        black = _mat(rng, "soundbar", (30, 30, 32), 0.6, spread=0.01)
        shop.box((-min(0.45, W * 0.3), -0.05, top), (min(0.45, W * 0.3), 0.04, top + 0.07), black, 0.02, 2)
        pot = _mat(rng, *_pick(rng, _styled("pots", POTS)))
        shop.lathe(W / 2 - 0.14, 0.0 if not panel_w else D / 2 - 0.1,
                   [(0, top), (0.05, top), (0.06, top + 0.06), (0.055, top + 0.065), (0, top + 0.065)],
                   pot, 20, shadow=False)
    if panel_w:
        _tv(shop, rng, -D / 2 + 0.06, top, H - top + TV_FEET_M, panel_w, panel_h)
    return style


def _bookcase(shop, rng, W, D, H):
    style = _pick(rng, ("closed", "open frame", "ladder"))
    body = _finish(rng)
    t = 0.022
    shelves = max(3, int(round(H / 0.36)))
    if style == "open frame":
        metal = _metal(rng, ("black steel", "brass"))
        for x in (-W / 2 + 0.01, W / 2 - 0.01):
            for y in (-D / 2 + 0.01, D / 2 - 0.01):
                shop.box((x - 0.01, y - 0.01, 0), (x + 0.01, y + 0.01, H), metal, 0.002)
        zs = np.linspace(0.05, H - t, shelves + 1)
        for z in zs:
            shop.box((-W / 2, -D / 2, z), (W / 2, D / 2, z + t), body, 0.003)
        gaps = [(z + t, z2) for z, z2 in zip(zs[:-1], zs[1:])]
        x_in = (-W / 2 + 0.025, W / 2 - 0.025)
    elif style == "ladder":  # leaning-look: shelves deepening toward the floor
        for x in (-W / 2, W / 2 - t):
            shop.hull([[x, -D / 2, 0], [x + t, -D / 2, 0], [x, D / 2, 0], [x + t, D / 2, 0],
                       [x, -D / 2, H], [x + t, -D / 2, H], [x, -D / 2 + 0.12, H], [x + t, -D / 2 + 0.12, H]], body)
        zs = np.linspace(0.04, H - t - 0.02, shelves + 1)
        gaps = []
        for k, z in enumerate(zs):
            depth = D - (D - 0.14) * (z / H)
            shop.box((-W / 2 + t, -D / 2, z), (W / 2 - t, -D / 2 + depth - 0.01, z + t), body, 0.003)
            if k < len(zs) - 1:
                gaps.append((z + t, zs[k + 1]))
        x_in = (-W / 2 + t, W / 2 - t)
    else:
        shop.box((-W / 2, -D / 2, 0), (-W / 2 + t, D / 2, H), body, 0.003)
        shop.box((W / 2 - t, -D / 2, 0), (W / 2, D / 2, H), body, 0.003)
        shop.box((-W / 2 + t, -D / 2, H - t), (W / 2 - t, D / 2, H), body, 0.003)
        shop.box((-W / 2 + t, -D / 2, 0), (W / 2 - t, D / 2 - 0.02, 0.07), body, 0.003)
        shop.box((-W / 2 + t, -D / 2, 0.07), (W / 2 - t, -D / 2 + 0.01, H - t), body)
        zs = np.linspace(0.07, H - t, shelves + 1)
        for z in zs[1:-1]:
            shop.box((-W / 2 + t, -D / 2 + 0.01, z - t / 2), (W / 2 - t, D / 2 - 0.005, z + t / 2), body, 0.002)
        gaps = [(z + (t / 2 if k else 0), z2 - t / 2) for k, (z, z2) in enumerate(zip(zs[:-1], zs[1:]))]
        x_in = (-W / 2 + t, W / 2 - t)
    for g0, g1 in gaps:
        _books(shop, rng, x_in[0] + 0.01, x_in[1] - 0.01, g0, g1, -D / 2 + 0.02, D / 2 - 0.03)
    return style


def _books(shop, rng, x0, x1, z0, z1, y0, y1):
    """Books standing on a shelf from x0 to x1, with gaps, a stack or an ornament."""
    gap_h = z1 - z0
    x = x0 + rng.uniform(0, 0.05)
    while x < x1 - 0.03:
        r = rng.random()
        if r < 0.12:  # empty stretch
            x += rng.uniform(0.05, 0.15)
            continue
        if r < 0.2 and x1 - x > 0.2:  # a lying stack
            z = z0
            for _ in range(int(rng.integers(2, 5))):
                t = rng.uniform(0.02, 0.04)
                c = _mat(rng, "book", _pick(rng, BOOK_COLORS), 0.6)
                shop.box((x, y0 + 0.01, z), (x + rng.uniform(0.15, 0.2), min(y1, y0 + 0.2), z + t), c, 0.002,
                         shadow=False)
                z += t
            x += 0.22
            continue
        if r < 0.26 and x1 - x > 0.12:
            pot = _mat(rng, *_pick(rng, _styled("pots", POTS)))
            h = min(gap_h * 0.7, 0.2)
            shop.lathe(x + 0.05, (y0 + y1) / 2, [(0, z0), (0.035, z0), (0.05, z0 + h * 0.5), (0.02, z0 + h),
                                                (0, z0 + h)], pot, 16, shadow=False)
            x += 0.12
            continue
        for _ in range(int(rng.integers(3, 9))):
            t = rng.uniform(0.018, 0.05)
            if x + t > x1:
                break
            h = min(gap_h - 0.01, rng.uniform(0.6, 0.95) * gap_h)
            d = min(y1 - y0, rng.uniform(0.14, 0.24))
            c = _mat(rng, "book", _pick(rng, BOOK_COLORS), 0.6)
            shop.box((x, y1 - d, z0), (x + t, y1, z0 + h), c, 0.002, shadow=False)
            x += t + 0.001
        x += rng.uniform(0.0, 0.04)


def _pot(shop, rng, r, h, mat):
    """A plant pot of radius ``r`` and height ``h`` standing at the origin, with soil."""
    lip = 0.012
    shop.lathe(0, 0, [(0, 0), (r * 0.72, 0), (r * 0.78, 0.01), (r - lip, h - 0.03), (r, h - 0.03), (r, h),
                      (r - lip, h), (r - lip - 0.005, h - 0.02), (0, h - 0.02)], mat, 32)
    soil = _mat(rng, "soil", (62, 46, 36), 0.95)
    shop.lathe(0, 0, [(0, h - 0.035), (r - lip - 0.004, h - 0.035), (r - lip - 0.004, h - 0.025), (0, h - 0.025)],
               soil, 24, shadow=False)


def _plant(shop, rng, W, D, H):
    style = _pick(rng, ("bush", "fiddle leaf", "snake plant"))
    pot_mat = _mat(rng, *_pick(rng, _styled("pots", POTS)))
    green = _mat(rng, "leaves", _pick(rng, GREENS), 0.6, spread=0.08)
    r = min(W, D) / 2
    pot_r = r * (0.62 if style != "snake plant" else 0.7)
    pot_h = min(0.42, H * (0.32 if style != "snake plant" else 0.3))
    _pot(shop, rng, pot_r, pot_h, pot_mat)
    top = pot_h - 0.03
    first = len(shop.parts)
    if style == "bush":
        stem = _mat(rng, "stem", (90, 70, 50), 0.8)
        shop.rod((0, 0, top), (0, 0, H * 0.55), 0.015, stem, 8)
        other = _mat(rng, "leaves", _pick(rng, GREENS), 0.65, spread=0.08)
        # The canopy's shaded inside: clumps that cast the shadows, under leaves that
        # break their outline (the leaves cast none: hundreds of casters would cost more
        # than the clumps' shadows differ).
        inside = _mat(rng, "leaves", tuple(int(0.55 * c) for c in _pick(rng, GREENS)), 0.8, spread=0.05)
        clumps = []
        for _ in range(int(rng.integers(9, 15))):
            a = rng.uniform(0, 2 * np.pi)
            rad = rng.uniform(0.0, r * 0.55)
            size = rng.uniform(0.09, 0.14) * (r / 0.2)
            clumps.append(((rad * math.cos(a), rad * math.sin(a), rng.uniform(top + (H - top) * 0.35, H - 0.1)),
                           (size, size, size * 0.85)))
        clumps += [((0, 0, H - 0.1), (r * 0.5, r * 0.5, 0.1)), ((r * 0.45, 0, H * 0.7), (r * 0.5, r * 0.45, 0.12)),
                   ((-r * 0.45, 0, H * 0.72), (r * 0.5, r * 0.45, 0.12))]
        leaf = 0.085 * (r / 0.2)
        bases, dirs = [], []
        for c, radii in clumps:
            # Leaves root at the clump's surface and beyond: a clump shows only in gaps.
            shop.ellipsoid(c, 0.6 * np.asarray(radii), inside)
            k = int(np.clip(np.prod(radii) ** (1 / 3) / leaf * 28, 20, 60))
            u = rng.normal(size=(k, 3)) + (0, 0, 0.4)
            u /= np.linalg.norm(u, axis=1, keepdims=True)
            bases.append(np.asarray(c) + u * np.asarray(radii) * rng.uniform(0.6, 1.0, (k, 1)))
            dirs.append(u + (0, 0, 0.3))
        bases, dirs = np.concatenate(bases), np.concatenate(dirs)
        which = np.arange(len(bases)) % 3 == 0
        for pick, mat in ((~which, green), (which, other)):
            m = int(pick.sum())
            shop.leaves(bases[pick], dirs[pick], leaf * rng.uniform(0.8, 1.25, m), leaf * rng.uniform(0.45, 0.6, m),
                        mat, rng.uniform(0.2, 0.5, m), rng.normal(0, 0.5, m))
    elif style == "fiddle leaf":
        stem = _mat(rng, "stem", (100, 80, 55), 0.8)
        n_stems = int(rng.integers(3, 6))
        for s in range(n_stems):
            a = rng.uniform(0, 2 * np.pi)
            tip = np.array([math.cos(a) * r * 0.35, math.sin(a) * r * 0.35, rng.uniform(0.75, 0.95) * H])
            shop.rod((0, 0, top), tip, 0.008, stem, 6)
            for k in range(int(rng.integers(5, 9))):
                t = rng.uniform(0.25, 1.0)
                p = np.array([0, 0, top]) + t * (tip - [0, 0, top])
                b = rng.uniform(0, 2 * np.pi)
                out = np.array([math.cos(b), math.sin(b), rng.uniform(0.2, 0.9)])
                shop.leaf(p, out, rng.uniform(0.14, 0.22) * (r / 0.2), rng.uniform(0.09, 0.13) * (r / 0.2), green,
                          bend=rng.uniform(0.1, 0.4), twist=rng.normal(0, 0.3))
    else:
        dark = _mat(rng, "leaves", (40, 80, 44), 0.5, spread=0.08)
        for k in range(int(rng.integers(9, 15))):
            a = rng.uniform(0, 2 * np.pi)
            off = rng.uniform(0, pot_r * 0.6)
            base = np.array([off * math.cos(a), off * math.sin(a), top])
            lean = rng.uniform(0.05, 0.25)
            d = np.array([lean * math.cos(a), lean * math.sin(a), 1.0])
            shop.leaf(base, d, rng.uniform(0.6, 1.0) * (H - top), rng.uniform(0.05, 0.08), dark if k % 2 else green,
                      bend=rng.uniform(0.2, 0.5), twist=rng.uniform(-1, 1))
    # The foliage fills the item's box: as tall as the item, as wide as its footprint.
    shop.reach(first, 2, H)
    for axis, half in ((0, W / 2), (1, D / 2)):
        shop.reach(first, axis, half)
        shop.reach(first, axis, -half, side=-1)
    return style


def _floor_lamp(shop, rng, W, D, H):
    style = _pick(rng, ("drum", "cone", "tripod"))
    metal = _metal(rng, ("black steel", "brass", "brushed steel", "white steel"))
    shade = _mat(rng, *_pick(rng, (("linen shade", (232, 224, 206)), ("white shade", (240, 238, 232)),
                                   ("grey shade", (150, 150, 150)), ("black shade", (40, 40, 40)))), 0.9,
                 emissive=(0.02, 0.018, 0.012))
    r = min(W, D) / 2
    shade_h = 0.3 if style != "cone" else 0.22
    z_shade = H - shade_h
    if style == "tripod":
        wood = _wood(rng)
        for k in range(3):
            a = k * 2 * np.pi / 3 + np.pi / 2
            shop.rod((r * 0.95 * math.cos(a), r * 0.95 * math.sin(a), 0), (0, 0, z_shade * 0.75), 0.013, wood, 8)
        shop.rod((0, 0, z_shade * 0.7), (0, 0, z_shade + 0.05), 0.009, metal, 8)
    else:
        shop.lathe(0, 0, [(0, 0), (r * 0.75, 0), (r * 0.75, 0.015), (r * 0.6, 0.03), (0, 0.03)], metal, 32)
        shop.rod((0, 0, 0.03), (0, 0, z_shade + 0.06), 0.011, metal, 10)
    if style == "cone":
        prof = [(r * 0.98, z_shade), (r * 0.45, H), (r * 0.43, H), (r * 0.95, z_shade)]
    else:
        prof = [(r, z_shade), (r * 0.9, H), (r * 0.88, H), (r * 0.98, z_shade)]
    shop.lathe(0, 0, prof, shade, 36)
    # The shade is open: a lid of shadow inside keeps it from looking hollow from above.
    inner = _mat(rng, "shade inside", (120, 110, 95), 0.9, emissive=(0.06, 0.05, 0.035))
    shop.lathe(0, 0, [(0, H - 0.04), (prof[1][0] * 0.98, H - 0.04), (prof[1][0] * 0.98, H - 0.035), (0, H - 0.035)],
               inner, 24, shadow=False)
    return style


RUG_WOOLS = (("cream wool", (222, 212, 190)), ("grey wool", (150, 150, 148)), ("charcoal wool", (70, 70, 72)),
             ("rust wool", (170, 96, 70)), ("navy wool", (50, 62, 92)), ("sand wool", (196, 176, 140)),
             ("sage wool", (150, 162, 136)), ("blush wool", (204, 164, 150)))


def _rug(shop, rng, W, D, H):
    # No half-and-half rug: under furniture its dark half reads as a hard shadow.
    chosen = _STYLE.get()
    style = _pick(rng, chosen.rug_patterns if chosen is not None and chosen.rug_patterns
                  else ("border", "stripes", "plain") + PATTERNS)
    wools = _styled("rugs", RUG_WOOLS)
    if style in PATTERNS:  # one woven image across the whole rug
        field_, ground = (wools[i][1] for i in rng.choice(len(wools), 2, replace=False))
        light = ([c for _, c in wools if sum(c) > 500 and c not in (field_, ground)]
                 or [c for _, c in RUG_WOOLS if sum(c) > 500 and c not in (field_, ground)])
        accent = light[int(rng.integers(len(light)))]
        image = rug_pattern(style, (field_, ground, accent), (W, D), rng)
        image.setflags(write=False)
        # Its colour (the image's mean) is what flat-coloured exports (scene.glb) show.
        mean = tuple(float(c) for c in _linear(image).mean(axis=(0, 1)))
        woven = Material(f"{style} rug", mean, 0.98, texture=image,
                         texture_key=f"rug {zlib.crc32(image.tobytes()):08x}")
        part = shop.box((-W / 2, -D / 2, 0), (W / 2, D / 2, H), woven, min(0.003, H / 3), shadow=False)
        part.uv = np.column_stack([(part.vertices[:, 0] + W / 2) / W, (part.vertices[:, 1] + D / 2) / D])
        return style
    field_ = _mat(rng, *_pick(rng, wools), 0.98)
    other = _mat(rng, *_pick(rng, wools), 0.98)
    zb = H * 0.7
    shop.box((-W / 2, -D / 2, 0), (W / 2, D / 2, zb), field_ if style != "border" else other, min(0.003, zb / 3))
    if style == "border":
        b = min(W, D) * 0.08
        shop.box((-W / 2 + b, -D / 2 + b, zb - 0.001), (W / 2 - b, D / 2 - b, H), field_)
        shop.box((-W / 2 + b * 1.4, -D / 2 + b * 1.4, H - 0.0005), (W / 2 - b * 1.4, D / 2 - b * 1.4, H), field_)
    elif style == "stripes":
        n = int(rng.integers(3, 7))
        for k in range(n):
            y = -D / 2 + (k + 0.5) * D / n
            shop.box((-W / 2 + 0.02, y - D / n * 0.18, zb - 0.001), (W / 2 - 0.02, y + D / n * 0.18, H), other)
    else:
        shop.box((-W / 2 + 0.01, -D / 2 + 0.01, zb - 0.001), (W / 2 - 0.01, D / 2 - 0.01, H), field_)
    for part in shop.parts:
        part.casts_shadow = False
    return style


def _coat_rack(shop, rng, W, D, H):
    style = _pick(rng, ("four feet", "round base"))
    wood = _wood(rng) if rng.random() < 0.6 else _metal(rng, ("black steel",))
    hook = _metal(rng, ("black steel", "brass", "brushed steel"))
    r = min(W, D) / 2
    if style == "four feet":
        for k in range(4):
            a = k * np.pi / 2
            shop.rod((r * 0.97 * math.cos(a), r * 0.97 * math.sin(a), 0), (0, 0, H * 0.35), 0.014, wood, 8)
        shop.rod((0, 0, H * 0.3), (0, 0, H - 0.03), 0.016, wood, 10)
    else:
        shop.lathe(0, 0, [(0, 0), (r, 0), (r, 0.02), (r * 0.75, 0.04), (0, 0.04)], hook, 40)
        shop.rod((0, 0, 0.04), (0, 0, H - 0.03), 0.016, wood, 10)
    shop.ellipsoid((0, 0, H - 0.025), (0.025, 0.025, 0.025), wood)
    for k in range(6):
        a = k * np.pi / 3 + np.pi / 6
        z = H - 0.12 - (k % 2) * 0.12
        tip = (0.16 * math.cos(a), 0.16 * math.sin(a), z + 0.07)
        shop.rod((0, 0, z), tip, 0.006, hook, 6)
        shop.ellipsoid(tip, (0.012, 0.012, 0.012), hook, shadow=False)
    return style


def _dining_table(shop, rng, W, D, H):
    style = _pick(rng, ("square", "trestle", "tapered", "frame"))
    top = _wood(rng) if rng.random() < 0.75 else _paint(rng)
    legs = top if style in ("square", "trestle", "tapered") and rng.random() < 0.7 else (
        _metal(rng, ("black steel",)) if style == "frame" else _wood(rng))
    _table(shop, rng, W, D, H, top, legs, style, top_t=0.04)
    return style


def _round_table(shop, rng, W, D, H):
    style = _pick(rng, ("pedestal", "round"))
    top = _wood(rng) if rng.random() < 0.6 else _mat(rng, "marble", (228, 226, 222), 0.15, spread=0.02)
    _table(shop, rng, W, D, H, top, _wood(rng) if style == "round" else _metal(rng, ("black steel", "white steel")),
           style, top_t=0.035, round_top=True)
    return style


def _chair(shop, rng, W, D, H):
    style = _pick(rng, ("slat", "upholstered", "metal"))
    wood = _wood(rng)
    seat_h = min(0.46, H * 0.5)
    st = 0.03
    back_lean = math.radians(8)
    if style == "metal":
        frame = _metal(rng, ("black steel", "white steel", "brushed steel"))
        shell = _wood(rng) if rng.random() < 0.5 else _paint(rng)
        r = 0.011
        for x in (-W / 2 + r + 0.01, W / 2 - r - 0.01):
            shop.rod((x, D / 2 - r - 0.01, 0), (x, D / 2 - 0.06, seat_h - st), r, frame, 8)
            shop.rod((x, -D / 2 + r + 0.03, 0), (x, -D / 2 + 0.08, seat_h - st), r, frame, 8)
            shop.rod((x, -D / 2 + 0.06, seat_h - st), (x, -D / 2 + r, H - 0.02), r, frame, 8)
        shop.box((-W / 2, -D / 2 + 0.04, seat_h - st), (W / 2, D / 2, seat_h), shell, 0.01, 2)
        shop.box((-W / 2 + 0.01, -D / 2, H - 0.22), (W / 2 - 0.01, -D / 2 + 0.025, H), shell, 0.01, 2)
        return style
    lw = 0.035
    # Back legs rise into the back posts, leaning back.
    for x in (-W / 2 + lw / 2, W / 2 - lw / 2):
        shop.box((x - lw / 2, D / 2 - lw, 0), (x + lw / 2, D / 2, seat_h - st), wood, 0.004)
        shop.hull([[x - lw / 2, -D / 2 + 0.03, 0], [x + lw / 2, -D / 2 + 0.03, 0],
                   [x - lw / 2, -D / 2 + 0.03 + lw, 0], [x + lw / 2, -D / 2 + 0.03 + lw, 0],
                   [x - lw / 2, -D / 2 + 0.04, seat_h], [x + lw / 2, -D / 2 + 0.04, seat_h],
                   [x - lw / 2, -D / 2 + 0.04 + lw, seat_h], [x + lw / 2, -D / 2 + 0.04 + lw, seat_h],
                   [x - lw / 2, -D / 2, H], [x + lw / 2, -D / 2, H], [x - lw / 2, -D / 2 + lw, H],
                   [x + lw / 2, -D / 2 + lw, H]], wood)
    # Stretchers
    for y in (D / 2 - lw / 2, -D / 2 + 0.04 + lw / 2):
        shop.box((-W / 2 + lw, y - 0.01, 0.18), (W / 2 - lw, y + 0.01, 0.21), wood)
    if style == "upholstered":
        cover = _upholstery(rng)
        shop.box((-W / 2 + 0.005, -D / 2 + 0.04, seat_h - st - 0.04), (W / 2 - 0.005, D / 2, seat_h - st + 0.01),
                 wood, 0.004)
        _cushion(shop, (-W / 2 + 0.01, -D / 2 + 0.05, seat_h - st), (W / 2 - 0.01, D / 2 - 0.005, seat_h + 0.02),
                 cover, 0.02)
        lean = _about((0, -D / 2 + 0.04 + lw, seat_h), _rot_x(back_lean))
        _cushion(shop, (-W / 2 + lw, -D / 2 + 0.04 + lw * 0.4, seat_h + 0.12), (W / 2 - lw, -D / 2 + 0.04 + lw * 1.6,
                 H - 0.03), cover, 0.02, lean)
    else:
        shop.box((-W / 2 + 0.005, -D / 2 + 0.04, seat_h - st), (W / 2 - 0.005, D / 2, seat_h), wood, 0.006)
        lean = _about((0, -D / 2 + 0.04 + lw / 2, seat_h), _rot_x(back_lean))
        shop.box((-W / 2 + lw, -D / 2 + 0.04 + lw * 0.2, H - 0.12), (W / 2 - lw, -D / 2 + 0.04 + lw * 0.8, H - 0.02),
                 wood, 0.004, matrix=lean)
        n = int(rng.integers(3, 6))
        for x in np.linspace(-W / 2 + lw + 0.04, W / 2 - lw - 0.04, n):
            shop.box((x - 0.01, -D / 2 + 0.04 + lw * 0.35, seat_h + 0.05), (x + 0.01, -D / 2 + 0.04 + lw * 0.65,
                     H - 0.11), wood, matrix=lean)
    return style


def _desk(shop, rng, W, D, H):
    style = _pick(rng, ("pedestal", "trestle", "hairpin", "frame"))
    top = _wood(rng) if rng.random() < 0.7 else _paint(rng)
    metal = _metal(rng, ("black steel", "white steel"))
    if style == "pedestal":
        _table(shop, rng, W, D, H, top, top, "square", top_t=0.03, apron=False)
        body = top if rng.random() < 0.5 else _paint(rng)
        shop.parts = [p for p in shop.parts if p.vertices[:, 0].max() < W / 2 - 0.25 or p.vertices[:, 2].min() > 0.7]
        shop.box((W / 2 - 0.42, -D / 2 + 0.02, 0.0), (W / 2, D / 2 - 0.04, H - 0.03), body, 0.004)
        _fronts(shop, W / 2 - 0.41, W / 2 - 0.01, 0.03, H - 0.04, D / 2 - 0.04, body, metal, 3, 1,
                "bar" if rng.random() < 0.5 else "knob", proud=0.012)
        shop.box((-W / 2 + 0.06 - 0.025, -D / 2 + 0.05, 0.35), (W / 2 - 0.42, -D / 2 + 0.068, H - 0.03), top)
    elif style == "trestle":
        _table(shop, rng, W, D, H, top, _wood(rng), "trestle", top_t=0.03)
    elif style == "hairpin":
        _table(shop, rng, W, D, H, top, metal, "hairpin", top_t=0.03, apron=False)
    else:
        _table(shop, rng, W, D, H, top, metal, "frame", top_t=0.025, apron=False)
        shop.box((-W / 2 + 0.06, -D / 2 + 0.04, H - 0.3), (W / 2 - 0.06, -D / 2 + 0.055, H - 0.03), metal, 0.002)
    return style


def _office_chair(shop, rng, W, D, H):
    style = _pick(rng, ("task", "mesh", "executive"))
    cover = _leather(rng) if style == "executive" else _fabric(rng)
    plastic = _mat(rng, "plastic", _pick(rng, ((30, 30, 32), (60, 60, 62), (200, 200, 198))), 0.5, spread=0.02)
    chrome = _metal(rng, ("brushed steel", "black steel"))
    seat_h = min(0.48, H * 0.47)
    R = min(W, D) / 2
    base_r = R * 0.95
    for k in range(5):
        a = np.pi / 2 + k * 2 * np.pi / 5
        tip = (base_r * 0.88 * math.cos(a), base_r * 0.88 * math.sin(a))
        shop.hull([[0.03 * math.cos(a + 1.2), 0.03 * math.sin(a + 1.2), 0.07],
                   [0.03 * math.cos(a - 1.2), 0.03 * math.sin(a - 1.2), 0.07],
                   [tip[0] + 0.02 * math.cos(a + 1.57), tip[1] + 0.02 * math.sin(a + 1.57), 0.06],
                   [tip[0] - 0.02 * math.cos(a + 1.57), tip[1] - 0.02 * math.sin(a + 1.57), 0.06],
                   [0.03 * math.cos(a + 1.2), 0.03 * math.sin(a + 1.2), 0.11],
                   [0.03 * math.cos(a - 1.2), 0.03 * math.sin(a - 1.2), 0.11],
                   [tip[0], tip[1], 0.085]], chrome)
        cx, cy = base_r * 0.9 * math.cos(a), base_r * 0.9 * math.sin(a)
        wheel = _rounded_box_mesh((-0.015, -0.03, 0), (0.015, 0.03, 0.055), 0.027, 2)
        shop._add(*wheel, plastic, matrix=_move(cx, cy, 0) @ _rot_z(a + np.pi / 2))
    shop.cylinder(0, 0, 0.07, 0.14, 0.05, plastic, 20, radius_top=0.035)
    shop.cylinder(0, 0, 0.14, seat_h - 0.08, 0.022, chrome, 16)
    shop.box((-0.12, -0.12, seat_h - 0.1), (0.12, 0.12, seat_h - 0.07), plastic, 0.01)
    sw = W * (0.78 if style != "executive" else 0.82)
    _cushion(shop, (-sw / 2, -D / 2 + 0.08, seat_h - 0.08), (sw / 2, D / 2, seat_h), cover, 0.035)
    back_w = sw * 0.95
    lean = _about((0, -D / 2 + 0.1, seat_h), _rot_x(math.radians(8)))
    first = len(shop.parts)
    shop.box((-0.03, -D / 2 + 0.1, seat_h - 0.1), (0.03, -D / 2 + 0.13, seat_h + 0.15), plastic, 0.01, matrix=lean)
    back_mat = cover if style != "mesh" else _mat(rng, "mesh", (45, 45, 48), 0.8)
    _cushion(shop, (-back_w / 2, -D / 2 + 0.08, seat_h + 0.08), (back_w / 2, -D / 2 + 0.15, H - 0.02), back_mat,
             0.05 if style != "mesh" else 0.03, lean)
    shop.reach(len(shop.parts) - 1, 2, H)
    shop.reach(first, 1, -D / 2, side=-1)
    if style != "mesh" or rng.random() < 0.5:
        for s in (-1, 1):
            x = s * (W / 2 - 0.025)
            shop.box((x - 0.012, -0.05, seat_h - 0.06), (x + 0.012, 0.0, seat_h + 0.18), plastic, 0.008)
            shop.box((x - 0.025, -0.17, seat_h + 0.18), (x + 0.025, 0.1, seat_h + 0.21), plastic, 0.012, 2)
    return style


def _stage(shop, rng, W, D, H):
    style = _pick(rng, ("black skirt", "wood"))
    deck = _mat(rng, *_pick(rng, (("stage black", (40, 40, 42)), ("stage wood", (150, 110, 70)),
                                  ("stage grey", (90, 90, 92)))), 0.6)
    skirt = _mat(rng, "stage skirt", (30, 30, 32), 0.98) if style == "black skirt" else _wood(rng)
    n = max(2, int(round(H / 0.18)) - 1)  # steps below the deck
    tread = 0.28
    yf = D / 2 - n * tread  # the deck's front; the steps stand in front of it
    shop.box((-W / 2, -D / 2, H - 0.04), (W / 2, yf, H), deck, 0.006)
    shop.box((-W / 2 + 0.01, -D / 2 + 0.01, 0), (W / 2 - 0.01, yf - 0.01, H - 0.04), skirt)
    if style == "black skirt":  # pleats: thin vertical ribs
        for x in np.arange(-W / 2 + 0.08, W / 2 - 0.05, 0.16):
            shop.box((x - 0.03, yf - 0.012, 0.01), (x + 0.03, yf - 0.004, H - 0.045), skirt, 0.01, shadow=False)
    else:
        for x in np.arange(-W / 2 + 0.6, W / 2 - 0.3, 0.6):
            shop.box((x - 0.004, yf - 0.012, 0), (x + 0.004, yf - 0.004, H - 0.04), deck, shadow=False)
    sw = min(1.2, W * 0.4)
    for k in range(n):
        z = (k + 1) * H / (n + 1)
        shop.box((-sw / 2, yf - 0.02, 0), (sw / 2, D / 2 - k * tread, z), deck, 0.004)
    return style


def _seat(shop, rng, W, D, H):
    style = _pick(rng, ("red velvet", "blue", "charcoal"))
    cover = _mat(rng, *{"red velvet": ("red velvet", (140, 30, 36)), "blue": ("blue velvet", (40, 60, 120)),
                        "charcoal": ("charcoal fabric", (60, 60, 64))}[style], 0.95)
    side = _mat(rng, *_pick(rng, (("black plastic", (30, 30, 32)), ("dark wood", (80, 52, 34)))), 0.5)
    seat_h = min(0.45, H * 0.5)
    aw = 0.05
    for s in (-1, 1):
        x0, x1 = (-W / 2, -W / 2 + aw) if s < 0 else (W / 2 - aw, W / 2)
        shop.box((x0, -D / 2 + 0.05, 0), (x1, D / 2 - 0.1, seat_h + 0.2), side, 0.015, 2)
        shop.box((x0 - 0.0, -D / 2 + 0.02, seat_h + 0.18), (x1, D / 2, seat_h + 0.23), side, 0.02, 2)
    _cushion(shop, (-W / 2 + aw + 0.005, -D / 2 + 0.12, seat_h - 0.1), (W / 2 - aw - 0.005, D / 2 - 0.05, seat_h),
             cover, 0.04, _about((0, -D / 2 + 0.12, seat_h), _rot_x(math.radians(4))))
    lean = _about((0, -D / 2 + 0.05, seat_h - 0.05), _rot_x(math.radians(10)))
    first = len(shop.parts)
    _cushion(shop, (-W / 2 + aw + 0.005, -D / 2 + 0.06, seat_h - 0.05), (W / 2 - aw - 0.005, -D / 2 + 0.17, H - 0.01),
             cover, 0.05, lean)
    shop.reach(len(shop.parts) - 1, 2, H)
    shop.box((-W / 2 + aw, -D / 2 + 0.0, seat_h - 0.05), (W / 2 - aw, -D / 2 + 0.06, H - 0.04), side, 0.01,
             matrix=lean)
    shop.reach(first, 1, -D / 2, side=-1)
    return style


def _pool_table(shop, rng, W, D, H):
    style = _pick(rng, ("classic", "modern"))
    wood = _wood(rng) if style == "classic" else _paint(rng)
    felt = _mat(rng, *_pick(rng, (("green felt", (30, 110, 62)), ("blue felt", (40, 84, 128)),
                                  ("red felt", (130, 36, 40)), ("grey felt", (110, 112, 116)))), 0.95)
    black = _mat(rng, "pocket", (20, 20, 20), 0.8)
    rail = 0.12
    z_bed = H - 0.05
    shop.box((-W / 2 + 0.1, -D / 2 + 0.1, H - 0.32), (W / 2 - 0.1, D / 2 - 0.1, z_bed - 0.02), wood, 0.01)
    shop.box((-W / 2 + rail, -D / 2 + rail, z_bed - 0.03), (W / 2 - rail, D / 2 - rail, z_bed), felt)
    for s in (-1, 1):  # long rails (along x) and short rails (along y)
        shop.box((-W / 2, s * D / 2 - (rail if s > 0 else 0), H - 0.14), (W / 2, s * D / 2 + (0 if s > 0 else rail), H),
                 wood, 0.012)
        shop.box((s * W / 2 - (rail if s > 0 else 0), -D / 2 + rail, H - 0.14), (s * W / 2 + (0 if s > 0 else rail),
                 D / 2 - rail, H), wood, 0.012)
        shop.box((-W / 2 + rail, s * (D / 2 - rail) - (0.04 if s > 0 else 0), z_bed - 0.01),
                 (W / 2 - rail, s * (D / 2 - rail) + (0 if s > 0 else 0.04), z_bed + 0.035), felt, 0.01)
        shop.box((s * (W / 2 - rail) - (0.04 if s > 0 else 0), -D / 2 + rail, z_bed - 0.01),
                 (s * (W / 2 - rail) + (0 if s > 0 else 0.04), D / 2 - rail, z_bed + 0.035), felt, 0.01)
    for x in (-W / 2 + rail * 0.7, 0.0, W / 2 - rail * 0.7):
        for y in (-D / 2 + rail * 0.7, D / 2 - rail * 0.7):
            shop.cylinder(x, y, H - 0.005, H + 0.0, 0.045, black, 16, shadow=False)
    if style == "classic":
        for x in (-W / 2 + 0.25, W / 2 - 0.25):
            for y in (-D / 2 + 0.22, D / 2 - 0.22):
                shop.lathe(x, y, [(0, 0), (0.09, 0), (0.09, 0.05), (0.06, 0.08), (0.08, 0.2), (0.06, H - 0.32),
                                  (0, H - 0.32)], wood, 20)
    else:
        for x in (-W / 2 + 0.3, W / 2 - 0.3):
            shop.box((x - 0.06, -D / 2 + 0.2, 0), (x + 0.06, D / 2 - 0.2, H - 0.32), wood, 0.01)
    # Balls in a triangle and the cue ball.
    colors = ((220, 180, 40), (40, 60, 150), (170, 30, 30), (90, 40, 110), (220, 110, 30), (30, 110, 60),
              (120, 40, 30), (20, 20, 20), (240, 236, 220))
    br = 0.028
    k = 0
    for row in range(4):
        for j in range(row + 1):
            x = W / 4 + row * br * 1.75
            y = (j - row / 2) * br * 2.02
            shop.ellipsoid((x, y, z_bed + br), (br, br, br), _mat(rng, "ball", colors[k % 8], 0.2, spread=0.01),
                           shadow=False)
            k += 1
    shop.ellipsoid((-W / 4, 0.0, z_bed + br), (br, br, br), _mat(rng, "cue ball", colors[8], 0.2, spread=0.01),
                   shadow=False)
    return style


def _game_table(shop, rng, W, D, H):
    style = _pick(rng, ("felt", "chess"))
    wood = _wood(rng)
    rim = 0.07
    _table(shop, rng, W, D, H - 0.006, wood, wood, "square" if rng.random() < 0.6 else "tapered", top_t=0.03)
    for lo, hi in (((-W / 2, -D / 2), (W / 2, -D / 2 + rim)), ((-W / 2, D / 2 - rim), (W / 2, D / 2)),
                   ((-W / 2, -D / 2 + rim), (-W / 2 + rim, D / 2 - rim)),
                   ((W / 2 - rim, -D / 2 + rim), (W / 2, D / 2 - rim))):
        shop.box((lo[0], lo[1], H - 0.012), (hi[0], hi[1], H), wood, 0.005)
    if style == "felt":
        felt = _mat(rng, *_pick(rng, (("green felt", (30, 110, 62)), ("blue felt", (40, 84, 128)),
                                      ("red felt", (130, 36, 40)))), 0.95)
        shop.box((-W / 2 + rim, -D / 2 + rim, H - 0.012), (W / 2 - rim, D / 2 - rim, H - 0.004), felt)
    else:
        shop.box((-W / 2 + rim, -D / 2 + rim, H - 0.012), (W / 2 - rim, D / 2 - rim, H - 0.006), wood)
        light = _mat(rng, "light square", (226, 206, 170), 0.5)
        dark = _mat(rng, "dark square", (80, 52, 34), 0.5)
        s = min(W, D) * 0.5 / 8
        for i in range(8):
            for j in range(8):
                x0, y0 = -4 * s + i * s, -4 * s + j * s
                shop.box((x0, y0, H - 0.006), (x0 + s, y0 + s, H - 0.003), light if (i + j) % 2 else dark,
                         shadow=False)
    return style


def _arcade_cabinet(shop, rng, W, D, H):
    style = _pick(rng, ("black", "red", "blue", "wood"))
    body = _mat(rng, *{"black": ("black laminate", (30, 30, 32)), "red": ("red laminate", (150, 30, 30)),
                       "blue": ("blue laminate", (30, 50, 130)), "wood": ("wood laminate", (120, 80, 50))}[style], 0.4)
    trim = _mat(rng, "trim", (20, 20, 22), 0.4)
    screen = _mat(rng, "screen", (10, 12, 20), 0.1, emissive=(0.05, 0.12, 0.22))
    marquee = _mat(rng, "marquee", (240, 200, 120), 0.4, emissive=(0.5, 0.35, 0.15))
    yb, yf = -D / 2, D / 2
    side = lambda ys_zs: [[x, y, z] for x in (-W / 2, W / 2) for y, z in ys_zs]  # noqa: E731
    shop.hull(side([(yb, 0), (yf - 0.12, 0), (yf - 0.12, 0.88), (yb, 0.88)]), body)
    shop.hull(side([(yb, 0.86), (yf - 0.12, 0.86), (yf, 0.95), (yf, 1.0), (yf - 0.3, 1.02), (yb, 1.02)]), body)
    shop.hull(side([(yb, 1.0), (yf - 0.3, 1.0), (yf - 0.38, 1.5), (yb, 1.5)]), body)
    shop.hull(side([(yb, 1.48), (yf - 0.38, 1.48), (yf - 0.28, H - 0.25), (yf - 0.2, H), (yb, H)]), body)
    # Screen on the sloped face, marquee above, controls on the panel.
    p0, p1 = np.array([yf - 0.3, 1.0]), np.array([yf - 0.38, 1.5])
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    n = np.array([u[1], -u[0]])
    c = (p0 + p1) / 2 + n * 0.004
    q = [c + u * 0.2 + n * 0.0, c - u * 0.2, c - u * 0.2 + n * 0.006, c + u * 0.2 + n * 0.006]
    shop.hull([[x, y, z] for x in (-W / 2 + 0.08, W / 2 - 0.08) for y, z in q], screen)
    m0, m1 = np.array([yf - 0.28, H - 0.25]), np.array([yf - 0.2, H])
    um = (m1 - m0) / np.linalg.norm(m1 - m0)
    nm = np.array([um[1], -um[0]])
    q = [m0 + um * 0.03 + nm * 0.002, m1 - um * 0.03 + nm * 0.002, m1 - um * 0.03 + nm * 0.008,
         m0 + um * 0.03 + nm * 0.008]
    shop.hull([[x, y, z] for x in (-W / 2 + 0.04, W / 2 - 0.04) for y, z in q], marquee)
    zp = 0.99
    for x in (-W / 4, W / 4):
        shop.rod((x, yf - 0.15, zp), (x, yf - 0.15, zp + 0.07), 0.006, trim, 6)
        shop.ellipsoid((x, yf - 0.15, zp + 0.075), (0.017, 0.017, 0.017), _mat(rng, "ball top", (180, 30, 30), 0.3),
                       shadow=False)
        for k in range(3):
            shop.cylinder(x + 0.06 + k * 0.035, yf - 0.12, zp - 0.005, zp + 0.012, 0.012,
                          _mat(rng, "button", _pick(rng, ((200, 40, 40), (40, 160, 60), (230, 200, 40), (40, 90, 200))),
                               0.3), 12, shadow=False)
    shop.box((-0.12, yf - 0.125, 0.3), (0.12, yf - 0.115, 0.55), trim, 0.004, shadow=False)
    return style


def _picnic_table(shop, rng, W, D, H):
    style = _pick(rng, ("a-frame", "straight"))
    wood = _mat(rng, *_pick(rng, (("weathered wood", (150, 140, 125)), ("pine", (200, 160, 110)),
                                  ("stained wood", (120, 80, 50)), ("green paint", (60, 100, 70)))), 0.8)
    t = 0.04
    n = max(3, int(round(D / 0.15)))
    pw = (D - (n - 1) * 0.008) / n
    for k in range(n):
        y0 = -D / 2 + k * (pw + 0.008)
        shop.box((-W / 2, y0, H - t), (W / 2, y0 + pw, H), wood, 0.004)
    for s in (-1, 1):
        x = s * (W / 2 - 0.25)
        shop.box((x - 0.03, -D / 2 + 0.03, H - t - 0.08), (x + 0.03, D / 2 - 0.03, H - t), wood, 0.004)
        if style == "a-frame":
            for sy in (-1, 1):
                shop.hull([[x - 0.03, sy * (D / 2 - 0.05), 0], [x + 0.03, sy * (D / 2 - 0.05), 0],
                           [x - 0.03, sy * (D / 2 - 0.14), 0], [x + 0.03, sy * (D / 2 - 0.14), 0],
                           [x - 0.03, sy * 0.02, H - t - 0.08], [x + 0.03, sy * 0.02, H - t - 0.08],
                           [x - 0.03, sy * 0.11, H - t - 0.08], [x + 0.03, sy * 0.11, H - t - 0.08]], wood)
        else:
            for sy in (-1, 1):
                y = sy * (D / 2 - 0.1)
                shop.box((x - 0.035, y - 0.035, 0), (x + 0.035, y + 0.035, H - t - 0.08), wood, 0.004)
    shop.box((-W / 2 + 0.25, -0.03, 0.25), (W / 2 - 0.25, 0.03, 0.3), wood, 0.004)
    return style


def _bench(shop, rng, W, D, H):
    style = _pick(rng, ("slats", "slab", "metal"))
    wood = _wood(rng) if style != "slats" else _mat(rng, *_pick(rng, (("weathered wood", (150, 140, 125)),
                                                                       ("teak", (150, 98, 58)))), 0.7)
    t = 0.04 if style != "slab" else 0.06
    if style == "slats":
        n = 3
        pw = (D - 0.02 * (n - 1)) / n
        for k in range(n):
            y0 = -D / 2 + k * (pw + 0.02)
            shop.box((-W / 2, y0, H - t), (W / 2, y0 + pw, H), wood, 0.005)
    else:
        shop.box((-W / 2, -D / 2, H - t), (W / 2, D / 2, H), wood, 0.008)
    leg = wood if style == "slab" else _metal(rng, ("black steel", "brushed steel"))
    for s in (-1, 1):
        x = s * (W / 2 - 0.15)
        if style == "slab":
            shop.box((x - 0.03, -D / 2 + 0.03, 0), (x + 0.03, D / 2 - 0.03, H - t), leg, 0.004)
        else:
            tt = 0.02
            for y in (-D / 2 + 0.03, D / 2 - 0.03):
                shop.box((x - tt / 2, y - tt / 2, 0), (x + tt / 2, y + tt / 2, H - t), leg, 0.002)
            shop.box((x - tt / 2, -D / 2 + 0.03, H - t - tt), (x + tt / 2, D / 2 - 0.03, H - t), leg, 0.002)
            shop.box((x - tt / 2, -D / 2 + 0.03, 0), (x + tt / 2, D / 2 - 0.03, tt), leg, 0.002)
    return style


def _grill(shop, rng, W, D, H):
    style = _pick(rng, ("cart", "cabinet"))
    body = _mat(rng, *_pick(rng, (("black enamel", (30, 30, 32)), ("steel", (170, 170, 172)),
                                  ("red enamel", (140, 30, 30)))), 0.35, metallic=0.4)
    steel = _metal(rng, ("brushed steel", "black steel"))
    black = _mat(rng, "black", (24, 24, 24), 0.6)
    bw = min(W * 0.58, 0.75)
    lid_r = (D - 0.06) / 2
    z_box = H - lid_r
    yc = -D / 2 + lid_r
    shop.box((-bw / 2, -D / 2, z_box - 0.22), (bw / 2, yc + lid_r, z_box), body, 0.01)
    shop.lathe(0, 0, [(0, -bw / 2), (lid_r, -bw / 2), (lid_r, bw / 2), (0, bw / 2)], body, 24, arc=(0, np.pi),
               matrix=_move(0, yc, z_box) @ _rot_y(np.pi / 2) @ _rot_z(np.pi / 2))
    # Handle across the lid front.
    yh = D / 2 - 0.012
    shop.rod((-bw * 0.35, yh, z_box + lid_r * 0.75), (bw * 0.35, yh, z_box + lid_r * 0.75), 0.012, steel, 8)
    for x in (-bw * 0.35, bw * 0.35):
        shop.rod((x, yc + lid_r * 0.75, z_box + lid_r * 0.6), (x, yh, z_box + lid_r * 0.75), 0.008, steel, 6)
    for s in (-1, 1):
        shop.box((s * bw / 2, -D / 2 + 0.06, z_box - 0.03) if s > 0 else (-W / 2, -D / 2 + 0.06, z_box - 0.03),
                 (W / 2, D / 2 - 0.08, z_box) if s > 0 else (-bw / 2, D / 2 - 0.08, z_box), steel, 0.005)
    if style == "cabinet":
        shop.box((-bw / 2, -D / 2 + 0.06, 0.08), (bw / 2, D / 2 - 0.1, z_box - 0.22), body, 0.008)
        _fronts(shop, -bw / 2 + 0.01, bw / 2 - 0.01, 0.1, z_box - 0.24, D / 2 - 0.1, body, steel, 1, 2, "bar",
                proud=0.01, vertical=True)
        for x in (-bw / 2 + 0.05, bw / 2 - 0.05):
            for y in (-D / 2 + 0.1, D / 2 - 0.15):
                shop.cylinder(x, y, 0, 0.08, 0.03, black, 12)
    else:
        for x in (-bw / 2 + 0.02, bw / 2 - 0.02):
            for y in (-D / 2 + 0.08, D / 2 - 0.1):
                shop.box((x - 0.015, y - 0.015, 0.06 if x < 0 else 0.0), (x + 0.015, y + 0.015, z_box - 0.2), steel,
                         0.003)
        shop.box((-bw / 2 + 0.02, -D / 2 + 0.08, 0.18), (bw / 2 - 0.02, D / 2 - 0.1, 0.2), steel, 0.003)
        for y in (-D / 2 + 0.08, D / 2 - 0.1):
            shop.lathe(0, 0, [(0, -0.02), (0.07, -0.02), (0.07, 0.02), (0, 0.02)], black, 18,
                       matrix=_move(-bw / 2 + 0.02, y, 0.07) @ _rot_y(np.pi / 2))
    return style


def _trash_can(shop, rng, W, D, H):
    style = _pick(rng, ("round", "square"))
    body = _mat(rng, *_pick(rng, (("green plastic", (50, 100, 60)), ("grey plastic", (110, 112, 114)),
                                  ("steel", (180, 180, 182)), ("black plastic", (40, 40, 42)))), 0.5)
    r = min(W, D) / 2
    if style == "round":
        shop.lathe(0, 0, [(0, 0), (r * 0.85, 0), (r * 0.95, H - 0.12), (r, H - 0.1), (r, H - 0.07), (r * 0.9, H - 0.02),
                          (r * 0.3, H), (0, H)], body, 36)
    else:
        shop.box((-W / 2 + 0.03, -D / 2 + 0.03, 0), (W / 2 - 0.03, D / 2 - 0.03, H - 0.08), body, 0.04, 2)
        shop.box((-W / 2, -D / 2, H - 0.09), (W / 2, D / 2, H - 0.02), body, 0.02, 2)
        shop.box((-W / 2 + 0.1, -0.05, H - 0.03), (W / 2 - 0.1, 0.05, H), body, 0.015, 2)
    return style


def _carousel(shop, rng, W, D, H):
    style = _pick(rng, ("red", "blue"))
    a_col, b_col = {"red": ((180, 40, 40), (240, 236, 226)), "blue": ((40, 70, 150), (240, 220, 140))}[style]
    stripe_a, stripe_b = _mat(rng, "canopy", a_col, 0.6), _mat(rng, "canopy", b_col, 0.6)
    wood = _mat(rng, "platform", (150, 100, 60), 0.6)
    gold = _metal(rng, ("brass",))
    R = min(W, D) / 2
    shop.lathe(0, 0, [(0, 0), (R, 0), (R, 0.3), (0, 0.3)], wood, 64)
    shop.lathe(0, 0, [(0, 0.3), (0.35, 0.3), (0.3, 3.0), (0, 3.0)], _mat(rng, "column", b_col, 0.5), 24)
    z_roof = H * 0.72
    n = 16
    for k in range(n):
        arc = (k * 2 * np.pi / n, (k + 1) * 2 * np.pi / n)
        m = stripe_a if k % 2 else stripe_b
        shop.lathe(0, 0, [(0, z_roof - 0.35), (R, z_roof - 0.35), (R, z_roof), (R * 0.98, z_roof), (0.05, H - 0.05),
                          (0, H - 0.05)],
                   m, 4, arc=arc)
    shop.ellipsoid((0, 0, H - 0.08), (0.08, 0.08, 0.08), gold)
    horse_cols = ((240, 236, 226), (90, 60, 40), (40, 40, 40), (200, 170, 120))
    for k in range(12):
        a = k * 2 * np.pi / 12
        x, y = 2.3 * math.cos(a), 2.3 * math.sin(a)
        shop.rod((x, y, 0.3), (x, y, z_roof - 0.35), 0.02, gold, 8)
        hm = _mat(rng, "horse", horse_cols[k % 4], 0.4)
        z = 1.15 + 0.25 * math.sin(3 * a)
        heading = a + np.pi / 2
        M = _move(x, y, z) @ _rot_z(heading)
        shop.ellipsoid((0, 0, 0), (0.45, 0.14, 0.17), hm, matrix=M)
        shop.ellipsoid((0.38, 0, 0.22), (0.1, 0.07, 0.22), hm, matrix=M @ _about((0.38, 0, 0.22), _rot_y(0.5)))
        shop.ellipsoid((0.5, 0, 0.4), (0.14, 0.06, 0.07), hm, matrix=M)
        for lx in (-0.3, 0.3):
            for ly in (-0.07, 0.07):
                shop._add(*_lathe_mesh([(0, 0), (0.025, 0), (0.02, 0.35), (0, 0.35)], 6), hm,
                          matrix=M @ _move(lx, ly, -0.45) @ _about((0, 0, 0.35), _rot_y(0.4 if lx > 0 else -0.4)))
    return style


def _lounge_chair(shop, rng, W, D, H):
    style = _pick(rng, ("cushion", "slats"))
    frame = _mat(rng, *_pick(rng, (("teak", (150, 98, 58)), ("white resin", (230, 230, 226)),
                                   ("grey aluminium", (150, 152, 155)))), 0.5)
    z_bed = H * 0.55
    t = 0.04
    for x in (-W / 2 + t / 2, W / 2 - t / 2):
        shop.box((x - t / 2, -D / 2 + 0.05, z_bed - 0.08), (x + t / 2, D / 2, z_bed), frame, 0.006)
        for y in (-D / 2 + 0.15, D / 2 - 0.08):
            shop.box((x - t / 2, y - 0.025, 0), (x + t / 2, y + 0.025, z_bed - 0.02), frame, 0.005)
    back_len = min(0.65, D * 0.35)
    rise = float(np.clip((H - z_bed - 0.04) / back_len, 0.05, 0.9))
    lean = _about((0, -D / 2 + back_len, z_bed), _rot_x(-math.asin(rise)))
    first = len(shop.parts)
    if style == "cushion":
        pad = _fabric(rng)
        _cushion(shop, (-W / 2 + 0.02, -D / 2 + back_len, z_bed - 0.02), (W / 2 - 0.02, D / 2 - 0.01, z_bed + 0.06),
                 pad, 0.03)
        _cushion(shop, (-W / 2 + 0.02, -D / 2 + 0.0, z_bed - 0.02), (W / 2 - 0.02, -D / 2 + back_len, z_bed + 0.06),
                 pad, 0.03, lean)
    else:
        n = int((D - back_len) / 0.09)
        for k in range(n):
            y = -D / 2 + back_len + 0.01 + k * 0.09
            shop.box((-W / 2 + t, y, z_bed - 0.02), (W / 2 - t, y + 0.07, z_bed), frame, 0.004)
        for k in range(int(back_len / 0.09)):
            y = -D / 2 + 0.01 + k * 0.09
            shop.box((-W / 2 + t, y, z_bed - 0.02), (W / 2 - t, y + 0.07, z_bed), frame, 0.004, matrix=lean)
    shop.reach(first, 2, H)
    shop.reach(first, 1, -D / 2, side=-1)
    return style


def _parasol(shop, rng, W, D, H):
    style = _pick(rng, ("cross base", "round base"))
    cloth = _mat(rng, *_pick(rng, (("canvas", (226, 218, 196)), ("navy canvas", (46, 60, 96)),
                                   ("terracotta canvas", (178, 96, 70)), ("green canvas", (70, 110, 80)))), 0.9)
    pole = _mat(rng, *_pick(rng, (("wood pole", (150, 110, 70)), ("aluminium", (190, 190, 192)))), 0.5)
    r = min(W, D) / 2
    base = _mat(rng, "base", (60, 60, 62), 0.6)
    if style == "cross base":
        shop.box((-r, -0.04, 0), (r, 0.04, 0.06), base, 0.008)
        shop.box((-0.04, -r, 0), (0.04, r, 0.06), base, 0.008)
    else:
        shop.lathe(0, 0, [(0, 0), (r, 0), (r, 0.05), (r * 0.8, 0.08), (0, 0.08)], base, 40)
    shop.rod((0, 0, 0.05), (0, 0, H - 0.03), 0.02, pole, 10)
    z0 = H * 0.5
    shop.lathe(0, 0, [(0, z0), (0.03, z0), (0.1, z0 + 0.25), (0.09, H - 0.25), (0.035, H - 0.12), (0, H - 0.12)],
               cloth, 16)
    shop.ellipsoid((0, 0, H - 0.03), (0.03, 0.03, 0.03), pole)
    return style


def _book(shop, rng, W, D, H):
    cover = _mat(rng, "cover", _pick(rng, BOOK_COLORS), 0.6)
    pages = _mat(rng, "pages", (236, 230, 214), 0.9)
    c = min(0.0025, H / 6)
    shop.box((-W / 2, -D / 2, 0), (W / 2, D / 2, c), cover, 0.001)
    shop.box((-W / 2, -D / 2, H - c), (W / 2, D / 2, H), cover, 0.001)
    shop.box((-W / 2, -D / 2, 0), (-W / 2 + c, D / 2, H), cover, 0.001)
    shop.box((-W / 2 + c, -D / 2 + 0.003, c), (W / 2 - 0.003, D / 2 - 0.003, H - c), pages)
    return "hardcover"


def _laptop(shop, rng, W, D, H):
    shell = _mat(rng, *_pick(rng, (("silver", (190, 192, 196)), ("space grey", (90, 92, 96)))), 0.35, metallic=0.6)
    dark = _mat(rng, "seam", (30, 30, 32), 0.5)
    shop.box((-W / 2, -D / 2, 0), (W / 2, D / 2, H * 0.5), shell, min(0.008, H / 3), 2)
    shop.box((-W / 2 + 0.003, -D / 2 + 0.003, H * 0.5 - 0.0005), (W / 2 - 0.003, D / 2 - 0.003, H * 0.55), dark)
    shop.box((-W / 2, -D / 2, H * 0.55), (W / 2, D / 2, H), shell, min(0.008, H / 3), 2)
    return "closed"


def _mug(shop, rng, W, D, H):
    mat = _mat(rng, *_pick(rng, (("white ceramic", (236, 234, 228)), ("blue glaze", (60, 90, 140)),
                                 ("black glaze", (40, 40, 42)), ("terracotta glaze", (176, 96, 70)))), 0.25)
    r = min(W, D) / 2 * 0.78
    shop.lathe(0, 0, [(0, 0), (r * 0.9, 0), (r, 0.006), (r, H), (r - 0.004, H), (r - 0.004, 0.01), (0, 0.01)], mat, 28,
               convex=False)
    coffee = _mat(rng, "coffee", (50, 30, 20), 0.1)
    shop.lathe(0, 0, [(0, H - 0.02), (r - 0.004, H - 0.02), (r - 0.004, H - 0.019), (0, H - 0.019)], coffee, 20,
               shadow=False)
    # The handle, on the diagonal so it fits the square footprint.
    a = math.radians(-45)
    reach = min(W, D) / 2 * math.sqrt(2) * 0.92
    hr = 0.006
    pts = []
    for t in np.linspace(0, np.pi, 9):
        rad = r - 0.002 + (reach - hr - r) * math.sin(t)
        pts.append((rad * math.cos(a), rad * math.sin(a), H * 0.25 + (H * 0.5) * (1 - math.cos(t)) / 2 + 0.0))
    for p0, p1 in zip(pts[:-1], pts[1:]):
        shop.rod(p0, p1, hr, mat, 8)
    return "mug"


def _plate(shop, rng, W, D, H):
    mat = _mat(rng, *_pick(rng, (("white porcelain", (240, 238, 234)), ("stoneware", (150, 140, 128)),
                                 ("blue rim", (200, 210, 225)))), 0.2)
    r = min(W, D) / 2
    shop.lathe(0, 0, [(0, 0.0), (r * 0.55, 0.0), (r * 0.6, 0.006), (r * 0.62, H * 0.35), (r * 0.97, H), (r, H),
                      (r, H * 0.9), (r * 0.62, H * 0.5), (0, H * 0.45)], mat, 40)
    return "plate"


def _pencil(shop, rng, W, D, H):
    paint = _mat(rng, *_pick(rng, (("yellow paint", (230, 180, 40)), ("red paint", (180, 40, 40)),
                                   ("green paint", (40, 110, 60)), ("black paint", (30, 30, 30)))), 0.4)
    wood = _mat(rng, "pencil wood", (214, 176, 130), 0.7)
    lead = _mat(rng, "graphite", (50, 50, 52), 0.4)
    eraser = _mat(rng, "eraser", (220, 130, 130), 0.8)
    band = _metal(rng, ("brushed steel", "brass"))
    r = min(W, H) / 2
    L = D
    M = _move(0, -L / 2, r) @ _rot_x(-np.pi / 2)  # z of the lathe runs along +y
    shop.lathe(0, 0, [(0, 0), (r * 0.95, 0), (r * 0.95, 0.012)], eraser, 12, matrix=M)
    shop.lathe(0, 0, [(r * 0.95, 0.012), (r, 0.012), (r, 0.025), (r * 0.95, 0.025)], band, 12, matrix=M)
    shop.lathe(0, 0, [(r * 0.95, 0.025), (r, 0.025), (r, L - 0.022), (0, L - 0.022)], paint, 6, matrix=M)
    shop.lathe(0, 0, [(r, L - 0.022), (r * 0.3, L - 0.004), (0, L - 0.004)], wood, 12, matrix=M)
    shop.lathe(0, 0, [(r * 0.3, L - 0.004), (0, L), (0, L)], lead, 8, matrix=M)
    return "pencil"


def _binder(shop, rng, W, D, H):
    cover = _mat(rng, *_pick(rng, (("blue binder", (40, 70, 140)), ("black binder", (30, 30, 32)),
                                   ("red binder", (160, 40, 40)), ("white binder", (230, 230, 226)))), 0.4)
    label = _mat(rng, "label", (240, 238, 230), 0.8)
    paper = _mat(rng, "paper", (240, 238, 232), 0.9)
    t = 0.003
    shop.box((-W / 2, -D / 2, 0), (-W / 2 + t, D / 2, H), cover)
    shop.box((W / 2 - t, -D / 2, 0), (W / 2, D / 2, H), cover)
    shop.box((-W / 2, D / 2 - t, 0), (W / 2, D / 2 - 0.001, H), cover, 0.001)
    shop.box((-W / 2 + t, -D / 2 + 0.01, 0.01), (W / 2 - t, D / 2 - t, H - 0.01), paper)
    shop.box((-W / 2 + 0.008, D / 2 - 0.0015, H * 0.45), (W / 2 - 0.008, D / 2, H * 0.85), label, shadow=False)
    return "binder"


def _photo_frame(shop, rng, W, D, H):
    frame = _finish(rng) if rng.random() < 0.7 else _metal(rng, ("brass", "black steel"))
    mount = _mat(rng, "mount", (236, 232, 222), 0.8)
    lean = _about((0, D / 2 - 0.01, 0), _rot_x(math.radians(12)))
    b = 0.018
    t = 0.015
    y0, y1 = D / 2 - t - 0.002, D / 2 - 0.002
    shop.box((-W / 2, y0, 0), (W / 2, y1, b), frame, 0.002, matrix=lean)
    top = H / math.cos(math.radians(12)) * 0.98  # the frame's height before it leans back
    shop.box((-W / 2, y0, top - b), (W / 2, y1, top), frame, 0.002, matrix=lean)
    for s in (-1, 1):
        x0 = -W / 2 if s < 0 else W / 2 - b
        shop.box((x0, y0, 0), (x0 + b, y1, top), frame, 0.002, matrix=lean)
    shop.box((-W / 2 + b, y0 + 0.004, b), (W / 2 - b, y1 - 0.004, top - b), mount, matrix=lean)
    # The picture: a little landscape of colour fields.
    sky = _mat(rng, "picture sky", _pick(rng, ((150, 180, 210), (230, 190, 150), (200, 210, 220))), 0.3)
    land = _mat(rng, "picture land", _pick(rng, ((80, 110, 70), (60, 80, 110), (170, 140, 100))), 0.3)
    px0, px1 = -W / 2 + b + 0.025, W / 2 - b - 0.025
    pz0, pz1 = b + 0.025, top - b - 0.025
    zm = pz0 + (pz1 - pz0) * rng.uniform(0.3, 0.6)
    shop.box((px0, y1 - 0.0045, pz0), (px1, y1 - 0.003, zm), land, matrix=lean, shadow=False)
    shop.box((px0, y1 - 0.0045, zm), (px1, y1 - 0.003, pz1), sky, matrix=lean, shadow=False)
    shop.box((-0.02, -D / 2, 0), (0.02, -D / 2 + 0.012, top * 0.65), frame, 0.002,
             matrix=_about((0, -D / 2, 0), _rot_x(-math.radians(17))))
    return "standing"


def _desk_lamp(shop, rng, W, D, H):
    metal = _metal(rng, ("black steel", "white steel", "brass", "brushed steel"))
    r = min(W, D) / 2
    shop.lathe(0, 0, [(0, 0), (r * 0.95, 0), (r * 0.95, 0.015), (r * 0.7, 0.025), (0, 0.025)], metal, 28)
    elbow = np.array([0.0, -r * 0.45, H * 0.55])
    shop.rod((0, -r * 0.2, 0.02), elbow, 0.007, metal, 8)
    head = np.array([0.0, r * 0.1, H - 0.06])
    shop.rod(elbow, head, 0.007, metal, 8)
    shop.ellipsoid(elbow, (0.012, 0.012, 0.012), metal)
    M = _move(*head) @ _rot_x(math.radians(35))
    shop.lathe(0, 0, [(0.012, 0.06), (0.02, 0.06), (0.06, -0.04), (0.056, -0.04)], metal, 20, matrix=M)
    shop.ellipsoid((0, 0.0, -0.02), (0.025, 0.025, 0.02), _mat(rng, "bulb", (250, 245, 230), 0.3,
                                                               emissive=(0.6, 0.55, 0.45)), matrix=M, shadow=False)
    return "anglepoise"


def _carton(shop, rng, W, D, H):
    """For kinds outside the catalog: a cardboard box of the item's size."""
    card = _mat(rng, "cardboard", (176, 136, 92), 0.9)
    tape = _mat(rng, "tape", (200, 170, 120), 0.4)
    shop.box((-W / 2, -D / 2, 0), (W / 2, D / 2, H), card, 0.004)
    shop.box((-0.03, -D / 2, H - 0.001), (0.03, D / 2, H), tape, shadow=False)
    return "carton"


BUILDERS = {
    "bed": _bed, "single_bed": _single_bed, "nightstand": _nightstand, "wardrobe": _wardrobe, "dresser": _dresser,
    "sofa": _sofa, "armchair": _armchair, "coffee_table": _coffee_table, "side_table": _side_table,
    "tv_stand": _tv_stand, "bookcase": _bookcase, "plant": _plant, "floor_lamp": _floor_lamp, "rug": _rug,
    "coat_rack": _coat_rack, "dining_table": _dining_table, "round_table": _round_table, "chair": _chair,
    "desk": _desk, "office_chair": _office_chair, "stage": _stage, "seat": _seat, "pool_table": _pool_table,
    "game_table": _game_table, "arcade_cabinet": _arcade_cabinet, "picnic_table": _picnic_table, "bench": _bench,
    "grill": _grill, "trash_can": _trash_can, "carousel": _carousel, "lounge_chair": _lounge_chair,
    "parasol": _parasol, "book": _book, "laptop": _laptop, "mug": _mug, "plate": _plate, "pencil": _pencil,
    "binder": _binder, "photo_frame": _photo_frame, "desk_lamp": _desk_lamp,
}


# --------------------------------------------------------------------------------------
# Furniture: the parts in the item frame, fitted to the item's box
# --------------------------------------------------------------------------------------

# Builder frame (x right, y front) to item frame (x front, y left): a -90 degree turn.
_ITEM_FROM_BUILDER = _rot_z(-np.pi / 2)


@dataclass(frozen=True)
class Furniture:
    """One piece of furniture in its item frame (x front, y left, z up; footprint centered
    on the origin, base at z = 0).

    Attributes
    ----------
    kind : str
    style : str
        Which of the kind's styles was built (or ``"asset"``).
    size_m : (3,) tuple of float
        Width (along y), depth (along x), height (z): the bounding box.
    parts : tuple of Part
    raw_bounds_m : (2, 3) ndarray
        The builder-frame bounds before the final fit (for checks).
    """

    kind: str
    style: str
    size_m: tuple
    parts: tuple
    raw_bounds_m: np.ndarray = field(compare=False, repr=False, default=None)

    @property
    def bounds_m(self) -> np.ndarray:
        """(2, 3) lower and upper corner of all parts, item frame."""
        v = np.concatenate([p.vertices for p in self.parts])
        return np.stack([v.min(axis=0), v.max(axis=0)])

    def to_trimesh(self, matrix=None) -> trimesh.Trimesh:
        """All parts as one ``trimesh.Trimesh`` with per-face colours (sRGB), optionally
        moved by a 4x4 ``matrix`` (e.g. :func:`world_from_item`)."""
        meshes = []
        for p in self.parts:
            part = p if matrix is None else p.transformed(matrix)
            rgb = np.clip(np.asarray(p.material.color_rgb) ** (1 / 2.2) * 255, 0, 255)
            colors = np.tile(np.append(rgb, 255).astype(np.uint8), (len(part.faces), 1))
            meshes.append(trimesh.Trimesh(part.vertices, part.faces, vertex_normals=part.normals,
                                          face_colors=colors, process=False))
        return trimesh.util.concatenate(meshes)


def _fit(parts, size_m, from_builder=True):
    """Move ``parts`` into the item frame and scale them onto the box of ``size_m``."""
    W, D, H = size_m
    v = np.concatenate([p.vertices for p in parts])
    lo, hi = v.min(axis=0), v.max(axis=0)
    target_lo = np.array([-W / 2, -D / 2, 0.0])
    target_hi = np.array([W / 2, D / 2, H])
    scale = (target_hi - target_lo) / np.maximum(hi - lo, 1e-9)
    fit = np.diag(np.append(scale, 1.0))
    fit[:3, 3] = target_lo - lo * scale
    m = (_ITEM_FROM_BUILDER if from_builder else np.eye(4)) @ fit
    return tuple(p.transformed(m) for p in parts), np.stack([lo, hi])


def _check_size(kind, size_m):
    size = tuple(float(v) for v in np.asarray(size_m, dtype=np.float64).reshape(-1))
    if len(size) != 3 or not all(np.isfinite(size)) or min(size) <= 0:
        raise ValueError(f"{kind}: size_m must be three positive lengths (width, depth, height), got {size_m!r}")
    return size


def build_furniture(kind: str, size_m=None, rng: np.random.Generator | None = None, style_seed=0,
                    style: str | None = None) -> Furniture:
    """Build a piece of furniture of catalog ``kind`` and size ``size_m``.

    Parameters
    ----------
    kind : str
        A catalog kind (:data:`layout.catalog.CATALOG`); any other name gets a cardboard box.
    size_m : (3,) float, optional
        Width, depth, height in meters; the catalog size when None.
    rng : numpy.random.Generator, optional
        Picks the style, materials and details; ``default_rng(style_seed)`` when None.
    style_seed : int
        Seed used when ``rng`` is None.
    style : str, optional
        A name of :data:`STYLES`: its materials only; any material when None.

    Returns
    -------
    Furniture
        In the item frame, its bounding box exactly ``size_m``.
    """
    if size_m is None:
        if kind not in CATALOG:
            raise ValueError(f"kind {kind!r} is not in the catalog: give its size_m")
        size_m = CATALOG[kind].size_m
    W, D, H = _check_size(kind, size_m)
    rng = np.random.default_rng(style_seed) if rng is None else rng
    if style is not None and style not in STYLES:
        raise ValueError(f"style {style!r}: choose one of {', '.join(STYLES)}")
    shop = _Shop()
    token = _STYLE.set(None if style is None else STYLES[style])
    try:
        style = BUILDERS.get(kind, _carton)(shop, rng, W, D, H)
    finally:
        _STYLE.reset(token)
    parts, raw = _fit(shop.parts, (W, D, H))
    return Furniture(kind, style, (W, D, H), parts, raw)


# --------------------------------------------------------------------------------------
# Users' models
# --------------------------------------------------------------------------------------

# Asset frames to the builder frame. glTF: y up, the model's front toward +z, so its
# right is -x. "z": z up, front toward -y (Blender's front view).
_ASSET_TO_BUILDER = {
    "y": np.array([[-1.0, 0, 0, 0], [0, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]),
    "z": np.array([[-1.0, 0, 0, 0], [0, -1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
}


def _visual_parts(mesh: trimesh.Trimesh, key: str) -> list[Part]:
    """Parts of one loaded mesh: one per material or per face colour."""
    normals = np.asarray(mesh.vertex_normals, dtype=np.float64)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.faces, dtype=np.int64)
    visual = mesh.visual
    if isinstance(visual, trimesh.visual.texture.TextureVisuals) and visual.material is not None:
        mat = visual.material
        if not isinstance(mat, trimesh.visual.material.PBRMaterial):
            mat = mat.to_pbr()
        factor = np.ones(4) if mat.baseColorFactor is None else np.asarray(mat.baseColorFactor, dtype=np.float64)
        if factor.max() > 1.0:
            factor = factor / 255.0
        texture, uv = None, None
        if mat.baseColorTexture is not None and visual.uv is not None:
            texture = np.asarray(mat.baseColorTexture.convert("RGB"))
            uv = np.asarray(visual.uv, dtype=np.float64)
        m = Material(f"{key} material", tuple(float(c) for c in factor[:3] ** 2.2),
                     float(mat.roughnessFactor if mat.roughnessFactor is not None else 0.7),
                     float(mat.metallicFactor if mat.metallicFactor is not None else 0.0),
                     texture_key=key if texture is not None else "", texture=texture)
        return [Part(v, normals, f, m, uv, convex=False)]
    colors = np.asarray(visual.face_colors, dtype=np.float64)[:, :3] / 255.0
    parts = []
    unique, inverse = np.unique(colors.round(3), axis=0, return_inverse=True)
    for k, c in enumerate(unique):
        m = Material(f"{key} colour {k}", tuple(float(x) for x in c ** 2.2), 0.7)
        parts.append(Part(v, normals, f[inverse.ravel() == k], m, None, convex=False))
    return parts


def load_asset(path, up: str = "y", yaw_deg: float = 0.0) -> tuple[Part, ...]:
    """Read a user's GLB, glTF or OBJ model as parts in the builder frame.

    Parameters
    ----------
    path : str or Path
    up : ``"y"`` or ``"z"``
        The file's up axis: ``"y"`` for glTF and most OBJ files (front toward +z),
        ``"z"`` for z-up exports (front toward -y).
    yaw_deg : float
        Extra turn about the vertical, for models whose front faces elsewhere.

    Raises
    ------
    ValueError
        When the file is missing, cannot be read or holds no triangles, or ``up`` is not
        ``"y"`` or ``"z"``.
    """
    path = Path(path)
    if up not in _ASSET_TO_BUILDER:
        raise ValueError(f"up={up!r} for {path}: use 'y' (glTF, most OBJ files) or 'z'")
    if (problem := path_problem(path)) is not None:
        raise ValueError(f"furniture model {path} {problem}")
    try:
        scene = trimesh.load(str(path), force="scene")
    except Exception as error:  # noqa: BLE001 - a malformed file makes trimesh raise anything
        raise ValueError(f"furniture model {path} could not be read as a 3-D model "
                         f"({type(error).__name__}: {error})") from None
    parts = []
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        geometry = scene.geometry[name]
        if not isinstance(geometry, trimesh.Trimesh) or len(geometry.faces) == 0:
            continue
        mesh = geometry.copy()
        mesh.apply_transform(transform)
        parts += _visual_parts(mesh, f"{path.name}:{name}")
    if not parts:
        raise ValueError(f"furniture model {path} holds no triangles")
    if not sum(trimesh.triangles.area(p.vertices[p.faces]).sum() for p in parts) > 0:
        raise ValueError(f"furniture model {path} has no surface: its triangles are points or lines")
    turn = _rot_z(math.radians(yaw_deg)) @ _ASSET_TO_BUILDER[up]
    return tuple(p.transformed(turn) for p in parts)


def furniture_from_asset(kind: str, size_m, parts) -> Furniture:
    """A user's model (parts from :func:`load_asset`) stretched onto the item's box.

    Raises
    ------
    ValueError
        When the model is flat along a side the box has (2 cm or more): a sheet cannot be
        stretched into a sofa; a flat model does for a rug.
    """
    size = _check_size(kind, size_m)
    v = np.concatenate([p.vertices for p in parts])
    extent = v.max(axis=0) - v.min(axis=0)
    for axis, name in enumerate(("wide", "deep", "tall")):
        if extent[axis] <= 1e-6 * extent.max() and size[axis] >= 0.02:
            raise ValueError(f"the model for {kind} is flat (0 m {name}) and cannot be stretched to the "
                             f"{size[axis]:.2f} m {name} a {kind} is: give a model with volume")
    fitted, raw = _fit(list(parts), size)
    return Furniture(kind, "asset", size, fitted, raw)


# --------------------------------------------------------------------------------------
# Placed items
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PlacedItem:
    """An item of a solved layout, in the floor frame.

    Attributes
    ----------
    kind : str
    position_m : (3,) tuple of float
        Center of the item's box (x, y on the floor, z = elevation + height / 2), as in
        ``layout_K.json``.
    yaw_rad : float
        Direction the front faces, ``(cos yaw, sin yaw)``.
    size_m : (3,) tuple of float
        Width, depth, height.
    id : str
    """

    kind: str
    position_m: tuple
    yaw_rad: float
    size_m: tuple
    id: str = ""

    @property
    def elevation_m(self) -> float:
        return float(self.position_m[2]) - float(self.size_m[2]) / 2


def placed_items(layout) -> list[PlacedItem]:
    """The items of a :class:`layout.solver.Layout` or of its ``to_dict()`` / JSON."""
    if isinstance(layout, dict):
        entries = layout.get("items", [])
        return [PlacedItem(str(e["kind"]), tuple(float(v) for v in e["position_m"]), float(e["yaw_rad"]),
                           tuple(float(v) for v in e["size_m"]), str(e.get("id", ""))) for e in entries]
    m = layout.model
    return [PlacedItem(str(m.kinds[i]), tuple(float(v) for v in layout.position_m[i]), float(layout.yaw_rad[i]),
                       tuple(float(v) for v in m.particle_size_m[i]), str(m.names[i])) for i in layout.items]


def world_from_item(item: PlacedItem) -> np.ndarray:
    """(4, 4) pose of the item frame in the floor frame: turned by yaw, base on its elevation."""
    x, y, _ = item.position_m
    return _move(x, y, item.elevation_m) @ _rot_z(item.yaw_rad)


# Kinds whose pieces in one room are each their own design; the pieces of any other kind
# match, as a stager buys a table's chairs or a pair of nightstands.
VARIED_KINDS = ("plant", "book", "binder", "mug", "photo_frame", "plate", "pencil")


def item_seed(item: PlacedItem, seed: int = 0) -> int:
    """A seed for an item's design, stable across suggestions: from ``seed`` and its kind
    (its id for :data:`VARIED_KINDS`)."""
    name = (item.id or item.kind) if item.kind in VARIED_KINDS else item.kind
    return int(zlib.crc32(f"{seed}:{name}".encode()))


def furniture_for(item: PlacedItem, seed: int = 0, assets: dict | None = None, cache: dict | None = None,
                  style: str | None = None) -> Furniture:
    """The furniture of ``item``: a user's model when ``assets`` maps its kind to one (a
    path, or parts from :func:`load_asset`), else the procedural builder seeded by
    :func:`item_seed`, in ``style`` (a name of :data:`STYLES`; any material when None).
    ``cache`` (a dict) keeps built pieces between calls (not those made from parts in memory)."""
    asset = (assets or {}).get(item.kind)
    if asset is not None and not isinstance(asset, (str, Path)):
        cache = None  # parts in memory: nothing to key them by
    key = (item.kind, tuple(round(v, 6) for v in item.size_m), item_seed(item, seed),
           None if asset is None else str(asset), style)
    if cache is not None and key in cache:
        return cache[key]
    if asset is not None:
        parts = load_asset(asset) if isinstance(asset, (str, Path)) else asset
        result = furniture_from_asset(item.kind, item.size_m, parts)
    else:
        result = build_furniture(item.kind, item.size_m, np.random.default_rng(key[2]), style=style)
    if cache is not None:
        cache[key] = result
    return result


def part_texture(part: Part):
    """How a part is textured: (key, image, uv, albedo scale). A user asset's own texture
    (its colour is in the image; scale None), or its material's surface detail at real
    scale (uv in tiles; the colour divided by the texture's mean, so the part keeps it);
    key "" and no image for an untextured part."""
    m = part.material
    if m.texture is not None:
        return m.texture_key, m.texture, part.uv, None
    if m.surface and part.uv is not None:
        detail = surface(m.surface)
        return f"surface {m.surface}", detail.image, part.uv / detail.tile_m, 1.0 / np.asarray(detail.mean_rgb)
    return "", None, None, np.ones(3)


def load_assets(assets) -> dict:
    """Kind -> parts of each of the user's models: a GLB, glTF or OBJ path per kind, or
    its parts already loaded (:func:`load_asset`); checked now, before any layout is solved."""
    if not assets:
        return {}
    loaded = {}
    for kind, source in dict(assets).items():
        if not isinstance(kind, str) or not kind.strip():
            raise FurnishError(f"asset kind {kind!r}: name a furniture kind (`layout kinds` lists them)")
        if not isinstance(source, (str, Path)):
            loaded[kind] = tuple(source)
            continue
        path = Path(source)
        if path.suffix.lower() not in (".glb", ".gltf", ".obj"):
            raise FurnishError(f"asset for {kind}: {path} is not a GLB, glTF or OBJ file")
        try:
            loaded[kind] = load_asset(path)
            if kind in CATALOG:  # refused now, not after the layouts are solved
                furniture_from_asset(kind, CATALOG[kind].size_m, loaded[kind])
        except ValueError as error:
            raise FurnishError(f"asset for {kind}: {error}") from None
    return loaded
