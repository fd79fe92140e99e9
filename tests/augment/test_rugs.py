"""Woven rug patterns: their layout, their colours, and the rug they cover."""
from __future__ import annotations

import numpy as np
import pytest

from augment.render.furniture import build_furniture, part_texture
from augment.render.rugs import PATTERNS, rug_labels, rug_pattern
from augment.render.surfaces import GAMMA

COLOURS = ((170, 96, 70), (50, 62, 92), (222, 212, 190))  # rust field, navy ground, cream accent


@pytest.mark.parametrize("pattern", ["medallion", "trellis"])
def test_medallion_and_trellis_rugs_mirror_about_both_axes(pattern):
    labels = rug_labels(pattern, (2.4, 1.7), np.random.default_rng(3))
    assert labels.shape == (425, 600)  # 4 mm a pixel
    assert np.array_equal(labels, labels[::-1]) and np.array_equal(labels, labels[:, ::-1])
    assert np.mean(labels == 2) > 0.05 and np.mean(labels == 0) > 0.3  # motifs over a field


def test_a_medallion_has_its_border_band_its_lozenge_and_the_field_between():
    labels = rug_labels("medallion", (2.0, 1.4), np.random.default_rng(0))
    rows, cols = labels.shape
    assert labels[rows // 2, cols // 2] == 0  # the lozenge's heart is the field's colour
    assert labels[rows // 2, cols // 2 + 40] in (1, 2)  # 16 cm out: inside the lozenge
    assert labels[rows // 2, 3] == 0  # the outer 2 cm rim
    assert np.mean(labels[rows // 2, 8:20] >= 1) > 0.9  # the border band from 3 cm in
    column = labels[:, cols // 2]
    assert np.any(column[rows // 2 - 120:rows // 2 - 60] == 0)  # field between the band and the lozenge


def test_kilim_rows_alternate_ground_and_accent_diamonds():
    labels = rug_labels("kilim", (2.0, 1.5), np.random.default_rng(2))
    rows, cols = labels.shape
    inner = labels[10:-10, 10:-10]
    row_colour = [np.bincount(r[r > 0], minlength=3)[1:].argmax() for r in inner[::5]]
    changes = np.count_nonzero(np.diff(row_colour))
    assert changes >= 3  # at least four rows of diamonds, each of one colour


@pytest.mark.parametrize("pattern", PATTERNS)
def test_the_woven_pile_keeps_each_colour_on_average(pattern):
    """The pile's detail is divided by its mean: over each colour's pixels the linear
    colour is the yarn's within 6 %."""
    rng_labels, rng_image = np.random.default_rng(4), np.random.default_rng(4)
    labels = rug_labels(pattern, (2.4, 1.7), rng_labels)
    image = rug_pattern(pattern, COLOURS, (2.4, 1.7), rng_image)
    linear = (image / 255.0) ** GAMMA
    for k in np.unique(labels):
        want = (np.asarray(COLOURS[k]) / 255.0) ** GAMMA
        got = linear[labels == k].mean(axis=0)
        assert np.allclose(got, want, rtol=0.06), (pattern, k, got, want)


def test_a_patterned_rug_is_one_woven_image_laid_once_across_it():
    for seed in range(40):
        rug = build_furniture("rug", (1.6, 2.3, 0.012), style_seed=seed)
        if rug.style in PATTERNS:
            break
    else:
        pytest.fail("no patterned rug in 40 seeds")
    (part,) = rug.parts
    key, image, uv, scale = part_texture(part)
    assert key.startswith("rug ") and scale is None and image.shape == (575, 400, 3)  # depth x width at 4 mm
    assert np.allclose(uv.min(axis=0), 0.0) and np.allclose(uv.max(axis=0), 1.0)
    # Flat-coloured exports (scene.glb) show the rug's mean colour, not white.
    assert np.allclose(part.material.color_rgb, ((image / 255.0) ** 2.2).mean(axis=(0, 1)), rtol=1e-6)
    assert max(part.material.color_rgb) < 0.9
    assert not part.casts_shadow
    with pytest.raises(ValueError, match="choose one of medallion"):
        rug_labels("paisley", (2.0, 1.5), np.random.default_rng(0))
