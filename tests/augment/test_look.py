"""The photo's camera on the furniture: noise and edge spread measured and given."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from augment.render.furniture import PlacedItem
from augment.render.gl import Renderer
from augment.render.look import (CLEAN, PhotoLook, apply_look, blur_like_photo, edge_sigma, estimate_blur,
                                 estimate_look, estimate_noise)
from augment.render.staged import render_staged
from tests.augment.test_render import _truth_calibration


def _scene(rng, h=480, w=640):
    """A photo-like image: smooth shading, hard edges, fine texture on a third of it and a
    clipped window, so only some blocks are flat."""
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    base = 90 + 60 * (x / w) + 30 * np.sin(y / 70.0)
    base[:, w // 3: w // 2] += 50  # a door frame: two hard edges
    base[h // 2:, : w // 3] += 25 * rng.standard_normal((h - h // 2, w // 3))  # carpet
    img = np.repeat(base[..., None], 3, axis=2) * np.array([1.0, 0.95, 0.85])
    img[: h // 5, 2 * w // 3:] = 255.0  # a blown-out window
    return img


@pytest.mark.parametrize("sigma", [(1.5, 3.0, 5.0), (0.0, 0.0, 0.0)])
def test_noise_per_channel_from_the_flattest_parts(rng, sigma):
    img = _scene(rng)
    noisy = np.clip(np.round(img + rng.standard_normal(img.shape) * np.array(sigma)), 0, 255).astype(np.uint8)
    before = noisy.copy()
    got = estimate_noise(noisy)
    np.testing.assert_array_equal(noisy, before)
    if max(sigma) == 0:
        # Rounding to whole levels leaves 1/sqrt(12) level of noise, which the operator sees.
        assert max(got) < 0.35
    else:
        np.testing.assert_allclose(got, np.sqrt(np.square(sigma) + 1 / 12), rtol=0.08)


def test_noise_rejects_what_is_not_a_photo():
    with pytest.raises(ValueError, match=r"\(h, w, 3\) uint8"):
        estimate_noise(np.zeros((10, 10), np.uint8))
    assert estimate_noise(np.full((64, 64, 3), 255, np.uint8)) == (0.0, 0.0, 0.0)  # all clipped


def test_a_blurred_step_is_measured():
    d = np.arange(-8, 8.01, 0.25)
    for s in (0.6, 1.0, 2.5):
        profile = 40 + 160 * 0.5 * (1 + np.vectorize(math.erf)(d / (s * np.sqrt(2))))
        sigma, contrast = edge_sigma(profile, 0.25)
        assert sigma == pytest.approx(s, rel=0.02) and contrast == pytest.approx(160, rel=0.02)
    assert edge_sigma(np.full(40, 100.0)) is None  # no step
    assert edge_sigma(np.r_[np.zeros(20), 200 * np.ones(10), np.zeros(10)]) is None  # a bar, not a step


def _board_photo(calibration, blur_px, size_px, supersample=4):
    """The board (paper margin and all) drawn into a grey floor through the calibration's
    exact homography, at 4x and shrunk (edges within a pixel's width), then blurred."""
    board = calibration.board
    w, h = size_px
    sheet = board.image(px_per_square=60)
    sh, sw = sheet.shape[:2]
    half_w, half_h = board.size_m[0] / 2, board.size_m[1] / 2
    # Sheet pixel (column, row) -> floor (x, y): the sheet's first row at +y.
    floor_from_sheet = np.array([[2 * half_w / sw, 0, -half_w], [0, -2 * half_h / sh, half_h], [0, 0, 1]])
    S = np.diag([supersample, supersample, 1.0])
    H = S @ calibration.image_from_floor @ floor_from_sheet
    big = cv2.warpPerspective(sheet if sheet.ndim == 3 else cv2.cvtColor(sheet, cv2.COLOR_GRAY2RGB), H,
                              (w * supersample, h * supersample), flags=cv2.INTER_AREA,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=(120, 110, 100))
    small = cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA)
    return cv2.GaussianBlur(small, (0, 0), blur_px) if blur_px > 0 else small


def test_blur_from_the_boards_printed_edges():
    """A board drawn exactly through the truth camera, then blurred by known Gaussians: the
    spreads measured add in quadrature to that of the sharp drawing (which is under
    0.7 px: a pixel's box, and the profiles' interpolation)."""
    _, _, calibration = _truth_calibration("room_2")
    sharp, edges = estimate_blur(_board_photo(calibration, 0.0, calibration.size_px), calibration)
    assert edges >= 12 and 0.3 < sharp < 0.7
    for blur_px in (1.0, 2.0):
        sigma, edges = estimate_blur(_board_photo(calibration, blur_px, calibration.size_px), calibration)
        assert edges >= 12
        assert sigma == pytest.approx(np.hypot(blur_px, sharp), rel=0.08)


def test_no_board_no_blur(rng):
    look = estimate_look(np.clip(_scene(rng), 0, 255).astype(np.uint8))
    assert look.blur_px == 0.0 and look.edges == 0
    _, _, calibration = _truth_calibration("room_2")
    grey = np.full((calibration.size_px[1], calibration.size_px[0], 3), 128, np.uint8)
    assert estimate_blur(grey, calibration) == (0.0, 0)  # the board is not in this photo


def test_the_look_given_to_a_layer():
    rgba = np.zeros((120, 160, 4), np.uint8)
    rgba[20:100, 40:120] = (100, 60, 30, 255)  # opaque, premultiplied
    before = rgba.copy()
    look = PhotoLook((2.0, 4.0, 6.0), 2.0, 20)
    out = apply_look(rgba, look, render_blur_px=0.5, seed=3)
    np.testing.assert_array_equal(rgba, before)
    np.testing.assert_array_equal(out, apply_look(rgba, look, 0.5, seed=3))  # the same seed, the same photo
    inside = out[40:80, 60:100, :3].reshape(-1, 3).astype(np.float64)
    np.testing.assert_allclose(inside.std(axis=0), [2.0, 4.0, 6.0], rtol=0.12)
    np.testing.assert_allclose(inside.mean(axis=0), [100, 60, 30], atol=0.5)
    assert (out[:5, :5] == 0).all()  # nothing where nothing was rendered
    # The silhouette: spread sqrt(2^2 - 0.5^2) more, premultiplied colour follows alpha.
    sigma, _ = edge_sigma(out[60, 25:56, 3].astype(np.float64))
    assert sigma == pytest.approx(np.sqrt(4 - 0.25), rel=0.1)
    edge = out[60, 30:50].astype(np.float64)
    np.testing.assert_allclose(edge[:, 0], edge[:, 3] * 100 / 255, atol=4 + 3 * 2.0)
    np.testing.assert_array_equal(apply_look(rgba, CLEAN, 0.5), rgba)


def test_a_plane_that_goes_with_the_layer_is_blurred_as_the_layer():
    """The mark of floor-level furniture (rugs), render-sharp (sigma 0.8), comes out with the
    photo's edge spread (2.5): sqrt(0.8^2 + extra^2) = 2.5; not at all for a sharp photo."""
    step = np.zeros((40, 80), np.uint8)
    step[:, 40:] = 255
    step = cv2.GaussianBlur(step, (0, 0), 0.8)
    before = step.copy()
    out = blur_like_photo(step, PhotoLook((1.0, 1.0, 1.0), 2.5, 20), render_blur_px=0.8)
    np.testing.assert_array_equal(step, before)
    sigma, _ = edge_sigma(out[20, 20:61].astype(np.float64))
    assert sigma == pytest.approx(2.5, rel=0.1)
    np.testing.assert_array_equal(blur_like_photo(step, CLEAN, 0.8), step)


def test_staged_furniture_gets_the_photos_noise_and_sharpness():
    """A sample photo blurred and made noisy: the furniture rendered into it carries the
    same noise as its floor, and edges as soft as the board's; with CLEAN it stays clean."""
    image, mask, calibration = _truth_calibration("room_2")
    rng = np.random.default_rng(7)
    photo = np.clip(cv2.GaussianBlur(image, (0, 0), 1.2) + rng.normal(0, 4, image.shape), 0, 255).astype(np.uint8)
    look = estimate_look(photo, calibration)
    assert np.allclose(look.noise_rgb, 4.0, rtol=0.1) and look.edges >= 12
    items = [PlacedItem("coffee_table", (0.0, 0.9, 0.225), 0.3, (1.1, 0.6, 0.45), "table")]
    kernel = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)

    def roughness(img, where):
        return float(np.median(np.abs(cv2.filter2D(img[..., 1].astype(np.float32), -1, kernel))[where]))

    with Renderer() as renderer:
        got = {name: render_staged(photo, calibration, items, renderer, floor_mask=mask, look=lk, seed=1)
               for name, lk in (("clean", CLEAN), ("look", look), ("default", None))}
    top = cv2.erode((got["clean"].alpha >= 0.999).astype(np.uint8), np.ones((7, 7), np.uint8)) > 0
    assert top.sum() > 2000
    floor = mask & (got["clean"].alpha == 0) & (got["clean"].gain > 0.999)
    photo_rough = roughness(photo, floor)
    assert roughness(got["clean"].image, top) < 0.3 * photo_rough
    assert roughness(got["look"].image, top) == pytest.approx(photo_rough, rel=0.25)
    np.testing.assert_array_equal(got["default"].image, got["look"].image)  # estimated from the photo by default
