import numpy as np
import pytest

from augment.render.noise import periodic_noise
from augment.synth import textures
from augment.synth.textures import (
    FLOOR_KINDS,
    ceiling_texture,
    floor_texture,
    wall_texture,
)

SIZE_PX = 256


def make(kind, seed, size_px=SIZE_PX):
    rng = np.random.default_rng(seed)
    if kind == "wall":
        return wall_texture(rng, size_px)
    if kind == "ceiling":
        return ceiling_texture(rng, size_px)
    return floor_texture(kind, rng, size_px)


def seam_ratio(image, axis, block=4):
    """Jump across the wrap-around seam over the largest such jump inside the image.

    ``axis=1`` looks at the seam between the last and the first column, ``axis=0`` at
    the one between the last and the first row. The image is averaged over blocks of
    ``block`` pixels along the seam, and the jump at a boundary is the mean difference
    between the ``block`` lines just before and just after it: pixel noise, which makes
    every pair of neighbouring lines differ, averages out, while a broken pattern does
    not. A periodic image has its seam jump among the interior ones (ratio about 1 or
    less); a non-periodic one stands out (a ramp scores ``size / block - 1``).
    """
    g = np.asarray(image, dtype=np.float64)
    if g.ndim == 3:
        g = g.mean(axis=2)
    if axis == 0:
        g = g.T
    n = g.shape[0] // block * block
    g = g[:n].reshape(n // block, block, -1).mean(axis=1)
    # Column sums of `block` consecutive columns, circularly: means[:, j] covers
    # columns j .. j + block - 1 (mod width).
    padded = np.concatenate([g, g[:, :block]], axis=1)
    csum = np.concatenate([np.zeros((g.shape[0], 1)), np.cumsum(padded, axis=1)], axis=1)
    means = (csum[:, block:block + g.shape[1]] - csum[:, :g.shape[1]]) / block
    # Jump at boundary j (between columns j - 1 and j): means[j] - means[j - block].
    jumps = np.abs(means - np.roll(means, block, axis=1)).mean(axis=0)
    width = g.shape[1]
    interior = jumps[block:width - block + 1]
    return jumps[0] / interior.max()


def line_score(profile, n_lines):
    """How clearly thin lines stand out at ``round(k * len / n_lines)`` in a 1-D profile.

    A circular running median over 9 samples keeps steps between tiles of different tone
    but drops lines one or two pixels wide; the score is the weakest line's residual over
    the largest residual away from every line.
    """
    size = len(profile)
    base = np.median(np.stack([np.roll(profile, k) for k in range(-4, 5)]), axis=0)
    residual = np.abs(profile - base)
    lines = np.round(np.arange(n_lines) * size / n_lines).astype(int) % size
    near = np.zeros(size, dtype=bool)
    for p in lines:
        near[np.arange(p - 2, p + 3) % size] = True
    weakest = min(residual[np.arange(p - 1, p + 2) % size].max() for p in lines)
    return weakest / residual[~near].max()


@pytest.mark.parametrize("kind", FLOOR_KINDS)
def test_floor_texture_shape_dtype_and_physical_size(kind):
    for seed in range(3):
        image, tile_m = make(kind, seed)
        assert image.shape == (SIZE_PX, SIZE_PX, 3)
        assert image.dtype == np.uint8
        assert isinstance(tile_m, float)
        assert 0.5 <= tile_m <= 2.5
        # Not a flat color, not blown out.
        assert image.std() > 1.0
        assert 20 < image.mean() < 245


def test_wall_and_ceiling_shape_dtype_and_physical_size():
    for seed in range(4):
        wall, wall_m = make("wall", seed)
        assert wall.shape == (SIZE_PX, SIZE_PX, 3) and wall.dtype == np.uint8
        assert 1.0 <= wall_m <= 2.0
    ceiling, ceiling_m = ceiling_texture(np.random.default_rng(0))
    assert ceiling.shape == (128, 128, 3) and ceiling.dtype == np.uint8
    assert 1.0 <= ceiling_m <= 2.0
    # Near white with very subtle noise.
    assert ceiling.mean() > 215
    assert ceiling.astype(float).mean(axis=2).std() < 4.0


def test_plank_rows_have_real_widths():
    for kind, (lo, hi) in (("wood", (0.12, 0.22)), ("laminate", (0.15, 0.25))):
        for seed in range(5):
            _, tile_m = make(kind, seed)
            # Some whole number of plank rows of an allowed width fills the repeat.
            assert any(lo <= tile_m / n <= hi for n in range(3, 20)), (kind, seed, tile_m)


@pytest.mark.parametrize("kind", FLOOR_KINDS + ("wall", "ceiling"))
def test_textures_are_seamless(kind):
    for seed in range(3):
        image, _ = make(kind, seed)
        assert seam_ratio(image, axis=1) < 2.0, (kind, seed)
        assert seam_ratio(image, axis=0) < 2.0, (kind, seed)


def test_seam_measure_catches_non_periodic_images():
    ramp = np.tile(np.linspace(0.0, 255.0, SIZE_PX), (SIZE_PX, 1))
    assert seam_ratio(ramp, axis=1) == pytest.approx(SIZE_PX / 4 - 1)
    assert seam_ratio(ramp.T, axis=0) == pytest.approx(SIZE_PX / 4 - 1)
    # A crop of periodic noise is an ordinary non-periodic texture.
    crop = periodic_noise(np.random.default_rng(0), 2 * SIZE_PX, 16.0)[:SIZE_PX, :SIZE_PX]
    assert seam_ratio(crop, axis=1) > 3
    assert seam_ratio(crop, axis=0) > 3
    whole = periodic_noise(np.random.default_rng(0), SIZE_PX, 16.0)
    assert seam_ratio(whole, axis=1) < 2.0
    assert seam_ratio(whole, axis=0) < 2.0


@pytest.mark.parametrize("kind", FLOOR_KINDS + ("wall", "ceiling"))
def test_same_seed_same_image_other_seed_other_image(kind):
    a, a_m = make(kind, 7)
    b, b_m = make(kind, 7)
    c, _ = make(kind, 8)
    assert np.array_equal(a, b) and a_m == b_m
    assert not np.array_equal(a, c)


def test_periodic_noise_statistics_and_shape():
    rng = np.random.default_rng(1)
    for scale_px in (0.5, 3.0, 12.0, (1.0, 30.0)):
        draws = [periodic_noise(rng, 128, scale_px, octaves=2) for _ in range(10)]
        for noise in draws:
            assert noise.shape == (128, 128) and noise.dtype == np.float32
            assert noise.flags.c_contiguous
            assert abs(float(noise.mean())) < 1e-3
            assert np.abs(noise).max() < 2.0
            assert seam_ratio(noise, axis=1) < 2.0 and seam_ratio(noise, axis=0) < 2.0
        # Standard deviation 1/3 in expectation; one draw of coarse noise varies more.
        rms = np.sqrt(np.mean([noise.var() for noise in draws]))
        assert rms == pytest.approx(1.0 / 3.0, rel=0.1)
    # Anisotropic scales give streaks along x: neighbours along a row agree more.
    streaks = periodic_noise(rng, 128, (1.0, 30.0))
    along = np.abs(np.diff(streaks, axis=1)).mean()
    across = np.abs(np.diff(streaks, axis=0)).mean()
    assert along < 0.2 * across


def test_tile_grid_geometry():
    layout = textures._TileLayout(nx=4, ny=8, pitch_x_m=0.4, pitch_y_m=0.2, grout_m=0.004,
                                  row_shift=0.5)
    size_px = 256
    ids, grout, _ = textures._tile_grid(size_px, layout)
    assert len(np.unique(ids)) == layout.nx * layout.ny
    px_per_m = size_px / layout.tile_m
    # Each horizontal grout line covers its width in pixels, centred on k * pitch.
    rows = grout.min(axis=1)
    for k in range(layout.ny):
        centre = k * size_px / layout.ny
        window = np.arange(int(centre) - 3, int(centre) + 4)
        cover = rows[window % size_px]
        assert cover.sum() == pytest.approx(layout.grout_m * px_per_m, abs=1e-4)
        assert np.sum(cover * window) / cover.sum() == pytest.approx(centre, abs=0.05)
    # Half-bond: odd rows shift their vertical joints by half a tile.
    pitch_x_px = size_px / layout.nx
    even_row, odd_row = 16, 16 + size_px // layout.ny
    assert grout[even_row, 0] > 0.5 and grout[odd_row, 0] == 0.0
    assert grout[odd_row, int(pitch_x_px / 2)] > 0.5


@pytest.mark.parametrize("seed", range(4))
def test_grout_lines_at_the_tile_period(seed):
    size_px = 512
    layout = textures._sample_tile_layout(np.random.default_rng(seed))
    image, tile_m = make("tiles", seed, size_px)
    assert tile_m == pytest.approx(layout.tile_m)
    # Whole tiles per repeat, of real sizes.
    assert 0.15 <= layout.pitch_y_m - layout.grout_m <= 0.6
    assert 0.002 <= layout.grout_m <= 0.005
    gray = image.astype(float).mean(axis=2)
    # Medians along the lines ignore marble veins that cross them.
    assert line_score(np.median(gray, axis=1), layout.ny) > 2.0
    if layout.row_shift == 0:
        assert line_score(np.median(gray, axis=0), layout.nx) > 2.0


def test_grout_lines_in_a_running_bond():
    layout = textures._TileLayout(nx=3, ny=6, pitch_x_m=0.4, pitch_y_m=0.2, grout_m=0.004,
                                  row_shift=0.5)
    image, tile_m = textures._render_tiles(np.random.default_rng(0), 512, layout)
    assert tile_m == pytest.approx(1.2)
    gray = image.astype(float).mean(axis=2)
    assert line_score(np.median(gray, axis=1), layout.ny) > 2.0
    # Vertical joints alternate between the two kinds of rows.
    even = np.median(gray[10:70], axis=0)
    odd = np.median(gray[95:155], axis=0)
    assert line_score(even, layout.nx) > 2.0
    assert line_score(np.roll(odd, -int(512 / 6)), layout.nx) > 2.0


def test_bad_kind_raises_with_name_and_valid_kinds():
    with pytest.raises(ValueError, match="parquet") as excinfo:
        floor_texture("parquet", np.random.default_rng(0))
    for kind in FLOOR_KINDS:
        assert kind in str(excinfo.value)


def test_tiny_size_rejected():
    with pytest.raises(ValueError, match="size_px"):
        floor_texture("wood", np.random.default_rng(0), 8)
