"""Surface detail of the furniture (augment.render.surfaces): every surface tiles, keeps its
material's colour on average, shows its detail at the size it has in the world, and is
laid on every builder part at real scale."""
from __future__ import annotations

import numpy as np
import pytest

from augment.render import surfaces
from augment.render.furniture import (BUILDERS, Material, Part, PlacedItem, _rounded_box_mesh, build_furniture,
                                      tv_on_stand_m)
from augment.render.gl import Renderer
from augment.render.look import CLEAN
from augment.render.staged import render_staged
from augment.render.styles import STYLES, WEAVES
from augment.render.surfaces import SIZE_PX, surface, surface_name
from layout.catalog import CATALOG
from tests.augment.test_render import LIGHT, _hull_mask, _project, _truth_calibration

NAMES = [f"wood:{w}" for w in surfaces._WOODS] + list(surfaces._MAKERS)[1:]
NAMES = [n if n != "metal" else "metal:brushed" for n in NAMES] + ["metal:powder"]


def _linear(surf):
    return (surf.image / 255.0) ** surfaces.GAMMA


@pytest.mark.parametrize("name", NAMES)
def test_every_surface_tiles_and_keeps_the_colour_on_average(name):
    surf = surface(name)
    d = _linear(surf)
    assert surf.image.shape == (SIZE_PX, SIZE_PX, 3) and surf.image.dtype == np.uint8
    np.testing.assert_allclose(surf.mean_rgb, d.mean(axis=(0, 1)), rtol=1e-9)
    assert 0.5 < min(surf.mean_rgb) and max(surf.mean_rgb) <= 1.0
    # The step across the repeat's edges is no larger than the largest between two columns
    # (rows) inside it: a weave's thread boundaries are such steps, a seam would be larger.
    luma = d.mean(axis=2)
    for grid in (luma, luma.T):
        inside = np.abs(np.diff(grid, axis=1)).mean(axis=0)
        assert np.abs(grid[:, 0] - grid[:, -1]).mean() <= 1.05 * inside.max() + 1e-4
    assert luma.std() > 0.004, "a surface with no detail"
    family, _, variant = name.partition(":")
    np.testing.assert_array_equal(surfaces._make(name, family, variant), surf.image)  # the same every time


def test_textures_are_kept_on_disk_whole_and_remade_when_damaged(tmp_path, monkeypatch):
    monkeypatch.setenv("STAGER_CACHE_DIR", str(tmp_path))
    surface.cache_clear()
    try:
        made = surface("linen")
        (path,) = surfaces.cache_dir().glob("*.npy")
        assert path.name == "linen.npy" and not list(surfaces.cache_dir().glob("*.tmp"))
        surface.cache_clear()
        np.testing.assert_array_equal(surface("linen").image, made.image)  # read back
        path.write_bytes(path.read_bytes()[:1000])  # a write cut short by a crash elsewhere
        surface.cache_clear()
        np.testing.assert_array_equal(surface("linen").image, made.image)
        assert path.stat().st_size > 700_000  # remade whole
        monkeypatch.setenv("STAGER_CACHE_DIR", str(path))  # a file where the folder should be
        surface.cache_clear()
        np.testing.assert_array_equal(surface("linen").image, made.image)
    finally:
        surface.cache_clear()


def _peak_period_mm(profile, surf):
    """The period, in mm, of the strongest frequency of a 1-D profile across the repeat."""
    spectrum = np.abs(np.fft.rfft(profile - profile.mean()))
    k = int(spectrum[1:].argmax()) + 1
    return 1000.0 * surf.tile_m / k


def test_details_have_their_size_in_the_world():
    """A weave's threads are 1.1 mm apart (over and under: 2.2 mm repeats) and oak's
    growth rings 5-14 mm, wherever the texture is drawn: known from their construction."""
    weave = surface("weave")
    period = _peak_period_mm(_linear(weave).mean(axis=(0, 2)), weave)
    assert period == pytest.approx(1.1, rel=0.08) or period == pytest.approx(2.2, rel=0.08), period
    oak = surface("wood:oak")
    across_grain = _linear(oak).mean(axis=2)[:, :]  # rings run along u (columns): vary along v
    spectrum = np.abs(np.fft.rfft(across_grain - across_grain.mean(axis=0), axis=0)).mean(axis=1)
    k = int(spectrum[3:].argmax()) + 3
    assert 5.0 <= 1000.0 * oak.tile_m / k <= 14.0


def test_materials_name_their_surface():
    assert surface_name("light oak") == "wood:light oak" and surface_name("dark walnut") == "wood:dark walnut"
    assert surface_name("walnut") == "wood:walnut" and surface_name("weathered wood") == "wood:weathered"
    assert surface_name("brushed steel") == "metal:brushed" and surface_name("black steel") == "metal:powder"
    assert surface_name("cognac leather") == "leather" and surface_name("white linen") == "linen"
    assert surface_name("marble") == "marble" and surface_name("horse") == ""
    with pytest.raises(ValueError, match="no such surface"):
        surface("wood:balsa")
    # Upholstery takes its style's weaves.
    for style in STYLES.values():
        sofa = build_furniture("sofa", style=style.name, style_seed=3)
        fabrics = {p.material.surface for p in sofa.parts if "fabric" in p.material.name}
        assert fabrics <= set(style.weaves) <= set(WEAVES)


def test_every_part_is_mapped_at_real_scale():
    v, _, _, uv = _rounded_box_mesh((0, 0, 0), (1.2, 0.5, 0.3), 0.0, 1)
    top = v[:, 2] == 0.3
    np.testing.assert_allclose(np.ptp(uv[top], axis=0), (1.2, 0.5))  # along its length first
    for kind in BUILDERS:
        for part in build_furniture(kind, style_seed=1).parts:
            assert part.uv is not None and part.uv.shape == (len(part.vertices), 2) and np.isfinite(part.uv).all()
            # Neighbouring vertices are as far apart on the surface as in space (a mapping
            # at real scale; stretched at most where a round part is seen from its side).
            e = part.faces[:, :2]
            along = np.linalg.norm(np.diff(part.uv[e], axis=1)[:, 0], axis=1)
            apart = np.linalg.norm(np.diff(part.vertices[e], axis=1)[:, 0], axis=1)
            assert np.median(along[apart > 1e-4] / apart[apart > 1e-4]) < 1.6, (kind, part.material.name)


def test_a_textured_surface_shows_grain_and_keeps_its_colour():
    """The same grey box rendered plain and as oak (no camera noise): the oak's top shows
    grain (its pixels vary several times more) and keeps the grey on average (within 4 %)."""
    image, mask, calibration = _truth_calibration("room_1", 0.5)
    v, n, f, uv = _rounded_box_mesh((-0.5, -0.5, 0.0), (0.5, 0.5, 0.5), 0.0, 1)
    size, center = (0.8, 0.8, 0.5), (0.2, 0.9)
    top = _hull_mask(mask.shape, _project(calibration, [(center[0] + x, center[1] + y, 0.5) for x, y in
                                                        ((-0.3, -0.3), (0.3, -0.3), (0.3, 0.3), (-0.3, 0.3))]))
    looks = []
    with Renderer() as renderer:
        for name in ("", "wood:oak"):
            part = Part(v, n, f, Material("grey", (0.3, 0.3, 0.3), 0.8, surface=name), uv)
            item = PlacedItem("box", (*center, 0.25), 0.0, size, "box")
            staged = render_staged(image, calibration, [item], renderer, assets={"box": (part,)}, lighting=LIGHT,
                                   look=CLEAN)
            looks.append(staged.image[top].astype(np.float64))
    plain, oak = looks
    assert top.sum() > 500
    assert oak.std(axis=0).mean() > 3.0 * plain.std(axis=0).mean() + 2.0
    np.testing.assert_allclose(oak.mean(axis=0), plain.mean(axis=0), rtol=0.04)


def _first_hits(parts, origins, direction):
    """The material name of the first part each ray (one ``direction``) meets ("" for
    none): Moller-Trumbore against every triangle."""
    best = np.full(len(origins), np.inf)
    names = np.full(len(origins), "", dtype=object)
    for part in parts:
        tri = part.vertices[part.faces]  # (m, 3, 3)
        e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        p = np.cross(direction, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        if not ok.any():
            continue
        tri, e1, e2, p, det = tri[ok], e1[ok], e2[ok], p[ok], det[ok]
        s = origins[:, None, :] - tri[None, :, 0]  # (n, m, 3)
        u = np.einsum("nmk,mk->nm", s, p) / det
        q = np.cross(s, e1[None])
        v = (q @ direction) / det
        t = np.einsum("nmk,mk->nm", q, e2) / det
        hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        t = np.where(hit, t, np.inf).min(axis=1)
        closer = t < best
        best[closer] = t[closer]
        names[closer] = part.material.name
    return names


def test_open_compartments_hold_things_and_gaps_between_fronts_are_dark():
    """Seen square-on (a piece's front faces +x in its frame), a column of rays across a
    chest of three drawers meets the dark recess in the two gaps between them; a row of
    rays across a TV stand meets books in its open compartment."""
    front = np.array([-1.0, 0.0, 0.0])
    W, D, H = CATALOG["dresser"].size_m
    z = np.linspace(0.0, H, 2000)
    seen = 0
    for seed in range(12):
        furniture = build_furniture("dresser", style_seed=seed)
        if furniture.style == "sideboard":
            continue  # doors side by side: no gap across this column
        names = _first_hits(furniture.parts, np.column_stack([np.ones_like(z), np.full_like(z, -W / 4 + 0.013), z]),
                            front)
        runs = [k for k, (a, b) in enumerate(zip(names[:-1], names[1:])) if a != "recess" and b == "recess"]
        assert len(runs) >= 2, (seed, furniture.style)
        seen += 1
    assert seen >= 4
    W, D, H = CATALOG["tv_stand"].size_m
    for seed in range(20):
        furniture = build_furniture("tv_stand", style_seed=seed)
        if furniture.style != "open":
            continue
        y = np.linspace(-W / 2, W / 2, 300)
        stand_h = tv_on_stand_m(W, H)[0]
        names = _first_hits(furniture.parts, np.column_stack([np.ones_like(y), y, np.full_like(y, stand_h / 2)]),
                            front)
        assert (names == "book").mean() > 0.12, names  # the compartment is a third of the width
        break
    else:
        pytest.fail("no open TV stand in 20 seeds")


def test_a_tv_stand_carries_a_tv_when_its_box_is_tall_enough():
    """The catalog's TV stand (1.6 x 0.45 x 1.25 m) is a 0.43 m stand with a 16:9 panel
    1.31 m wide (0.82 of the stand) standing on it: rays from the front meet the screen
    over the panel's middle and the stand's carcass below it, and a ray above the panel
    meets nothing. A box lower than 0.9 m (a spec's bench) holds the stand alone."""
    front = np.array([-1.0, 0.0, 0.0])
    W, D, H = CATALOG["tv_stand"].size_m
    stand, panel_w, panel_h = tv_on_stand_m(W, H)
    assert panel_w == pytest.approx(0.82 * W) and stand == pytest.approx(H - 0.05 - (panel_w * 9 / 16 + 0.03))
    for seed in range(6):
        furniture = build_furniture("tv_stand", style_seed=seed)
        z_mid = stand + 0.05 + panel_h / 2
        y = np.linspace(-0.4 * panel_w, 0.4 * panel_w, 50)
        names = _first_hits(furniture.parts, np.column_stack([np.ones_like(y), y, np.full_like(y, z_mid)]), front)
        assert (names == "screen").all(), (seed, furniture.style, set(names))
        below = _first_hits(furniture.parts, np.array([[1.0, 0.0, 0.5 * stand]]), front)
        assert below[0] not in ("", "screen"), furniture.style
        beside = _first_hits(furniture.parts, np.array([[1.0, 0.48 * W, z_mid]]), front)
        assert beside[0] == "", furniture.style  # past the panel's side: the wall behind
    low = build_furniture("tv_stand", (1.2, 0.4, 0.55), style_seed=0)
    assert not any(p.material.name == "screen" for p in low.parts)
