"""The board erased from the photo (augment.render.erase), against the same render drawn
without the board: the floor that lies under it."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from augment.camera.board import Board
from augment.camera.calibrate import calibrate_photo, exif_intrinsics
from augment.render.erase import ErasedBoard, erase_board, layer_over_photo
from augment.render.gl import Renderer
from augment.synth import render_sample
from augment.synth.prints import erasure_scores, pasted_board

SIZE = (640, 480)


def _render(seed, size=SIZE, **options):
    """A render and the same render without the board (its floor): the sample and the
    truth's image."""
    with Renderer() as renderer:
        photo = render_sample(seed, renderer, size_px=size, **options)
        truth = render_sample(seed, renderer, size_px=size, board_drawn=False, **options)
    return photo, truth.image


def _calibrated(image, photo, board):
    """``image`` (the render ``photo`` or a crop of it) calibrated from ``board`` with the
    render's true focal length."""
    return calibrate_photo(image, board, intrinsics=exif_intrinsics(photo.truth["K"][0][0], image.shape[1::-1]))


def _pair(seed, board=None):
    photo, truth = _render(seed, board=board)
    return photo, truth, _calibrated(photo.image, photo, Board())


def _changed(image, truth, levels=8):
    """Where the board (or its paper) shows: the photo more than ``levels`` off its truth."""
    return np.abs(image.astype(int) - truth.astype(int)).max(axis=2) > levels


@pytest.fixture(scope="module")
def charuco():
    """A ChArUco board on a light wood floor of its paper's colour (seed [7500, 0])."""
    board = Board(kind="charuco")
    return (board, *_render([7500, 0], (960, 720), board=board))


def _blur(image, sigma):
    return cv2.GaussianBlur(image.astype(np.float32), (0, 0), sigma)


@pytest.mark.parametrize("seed", [[7400, 6], [7400, 9]])  # a tiled floor, a planked one
def test_the_floor_under_the_board_comes_back(seed):
    photo, truth, cal = _pair(seed)
    given = photo.image.copy()
    erased = erase_board(photo.image, cal, photo.floor_mask)
    alpha = erased.full_alpha()
    assert np.array_equal(photo.image, given)  # the input is not modified
    board = _changed(photo.image, truth)
    assert board.sum() > 2000
    # Every pixel the board changed is filled ...
    assert not (board & (alpha < 0.5)).any()
    # ... close to the floor under it (the photo itself is 50-110 levels off there) ...
    error = np.abs(erased.image.astype(np.float32) - truth).mean(axis=2)[board].mean()
    assert error < 12, error
    light = np.abs(_blur(erased.image, 4) - _blur(truth, 4)).mean(axis=2)[board].mean()
    assert light < 7, light
    # ... and as detailed as the floor: a smooth fill (OpenCV's Telea) keeps 0.17-0.18 of
    # its fine detail, Stager's copy 0.82-0.95.
    detail = lambda im: np.abs(im.astype(np.float32) - _blur(im, 2))  # noqa: E731
    assert detail(erased.image)[board].std() / detail(truth)[board].std() > 0.5
    # Nothing else changes.
    untouched = alpha == 0
    assert np.array_equal(erased.image[untouched], photo.image[untouched])
    assert untouched.mean() > 0.9
    assert len(erased.source_m) == 1 and erased.covered == 0


def test_paper_larger_than_the_board_assumes_is_erased_too():
    """A board printed on 500 x 380 mm paper, Stager told the default (A3, 420 x 297): the
    sheet grows to the paper seen."""
    photo, truth, cal = _pair([7200, 0], Board(sheet_mm=(500.0, 380.0)))
    erased = erase_board(photo.image, cal, photo.floor_mask)
    alpha = erased.full_alpha()
    paper = _changed(photo.image, truth, 20)
    assert not (paper & (alpha < 0.5)).any()
    np.testing.assert_allclose(erased.sheet_m.max(axis=0), [0.25, 0.19], atol=0.01)


def test_a_charuco_board_on_a_floor_of_its_papers_colour(charuco):
    """The paper's colour is the floor's here (light wood): the sheet stays as printed
    (A3) rather than growing over floor that only looks like paper."""
    board, photo, truth = charuco
    cal = _calibrated(photo.image, photo, board)
    erased = erase_board(photo.image, cal, photo.floor_mask)
    alpha = erased.full_alpha()
    assert not (_changed(photo.image, truth) & (alpha < 0.5)).any()
    np.testing.assert_allclose(erased.sheet_m.max(axis=0), [0.214, 0.1525], atol=1e-3)


def test_a_board_cut_off_at_the_photos_edge(charuco):
    """The photo cut through a ChArUco board: what shows is erased, and the part beyond
    the edge is not taken for a thing lying on the board."""
    board, photo, truth = charuco
    cut = int(np.median(np.array(photo.truth["board"]["corners_px"])[:, 0])) + 20
    image = np.ascontiguousarray(photo.image[:, :cut])
    erased = erase_board(image, _calibrated(image, photo, board))
    printed = _changed(image, truth[:, :cut])
    assert printed.sum() > 3000
    assert not (printed & (erased.full_alpha() < 0.5)).any()
    assert erased.covered == 0


def test_a_carton_over_part_of_the_board_stays():
    """A ChArUco board a third under a carton: the print that shows is erased; the
    carton, which the floor mask calls floor there (the board's surroundings are seeded
    as floor), mostly stays (all of it was painted over before the print's pattern was
    checked; 35 % of its pixels over the sheet are now)."""
    board = Board(kind="charuco")
    photo, truth = _render([7600, 1], (960, 720), board=board, board_hidden=0.3)
    cal = _calibrated(photo.image, photo, board)
    erased = erase_board(photo.image, cal)
    alpha = erased.full_alpha()
    assert not (_changed(photo.image, truth) & (alpha < 0.5)).any()
    sheet = np.zeros(alpha.shape, np.uint8)
    cv2.fillPoly(sheet, [np.round(cal.pixels_from_floor(erased.sheet_m)).astype(np.int32)], 1)
    carton = (sheet > 0) & ~photo.floor_mask
    assert carton.sum() > 3000
    assert (carton & (alpha > 0.5)).sum() / carton.sum() < 0.4
    assert 0.15 < erased.covered < 0.35


def test_the_layer_joins_the_fill_under_it():
    """Hand-computed: photo P = 40, fill F = 200 at alpha 0.5 (erased E = 120); a layer of
    colour 50 at alpha 0.5 over E gives 85. Over P the joined layer must give 85 too:
    alpha 0.75, colour (0.5 * 50 + 0.5 * 0.5 * 200) / 0.75 = 100."""
    photo = np.full((2, 3, 3), 40, np.uint8)
    erased = ErasedBoard(np.full((2, 3, 3), 120, np.uint8), (0, 0, 3, 2), np.full((2, 3), 0.5, np.float32),
                         np.zeros((4, 2)), np.zeros((0, 2)))
    layer = np.dstack([np.full((2, 3, 3), 50, np.uint8), np.full((2, 3), 128, np.uint8)])
    joined = layer_over_photo(layer, erased, photo)
    np.testing.assert_allclose(joined[..., 3], 0.75 * 255, atol=1.0)
    np.testing.assert_allclose(joined[..., :3], 100, atol=1.0)
    # Where neither the layer nor the fill is, the layer stays empty.
    none = layer_over_photo(np.zeros((2, 3, 4), np.uint8),
                            ErasedBoard(photo, (1, 0, 3, 2), np.zeros((2, 2), np.float32), np.zeros((4, 2)),
                                        np.zeros((0, 2))),
                            photo)
    assert not none[..., 3].any()


def test_wrong_inputs_are_refused():
    photo, _, cal = _pair([7400, 9])
    with pytest.raises(ValueError, match="calibration is of a 640x480 photo"):
        erase_board(photo.image[:400], cal)
    with pytest.raises(ValueError, match="floor_mask must be"):
        erase_board(photo.image, cal, photo.floor_mask[:10])
    with pytest.raises(ValueError, match="uint8"):
        erase_board(photo.image.astype(np.float32), cal)


def _erased_print(seed, **choices):
    """A pasted print (:func:`pasted_board`, 1280x960), calibrated with its true focal length
    and erased on its floor: the case and the erased photo."""
    case = pasted_board(np.random.default_rng(seed), (1280, 960), **choices)
    cal = calibrate_photo(case.photo, case.board, intrinsics=exif_intrinsics(case.K[0, 0], (1280, 960)))
    return case, erase_board(case.photo, cal, case.floor_mask).image


def _print_case(seed, **choices):
    case, erased = _erased_print(seed, **choices)
    return case, erasure_scores(case, erased)


def test_opencvs_chessboard_on_cream_paper_leaves_no_dots():
    """OpenCV's 9x6 board: its pose is known up to a half turn, which swaps its squares'
    colours but not its margin's. Taken for a thing lying on the print, the margin beside
    each white square was once kept: a ring of paper dots."""
    case, scores = _print_case(9306, paper="cream", margin="sheet", marks=False, pattern="opencv", floor="carpet",
                               shadow=False)
    assert scores["spots"] == 0 and scores["ok"], scores


@pytest.mark.parametrize("choices", [
    dict(paper="off-white", margin="none", pattern="stager", floor="tiles", shadow=True),
    dict(paper="white", margin="sheet", marks=True, pattern="charuco", floor="laminate", shadow=False),
])
def test_prints_as_users_make_them_leave_no_trace(choices):
    """Trimmed to the squares under a shadow's edge on tiles; the ruler and caption on
    planks: the light, contrast and outline of the floor, no bright specks."""
    case, scores = _print_case(9400, **choices)
    assert scores["ok"], (case.case, scores)


@pytest.mark.parametrize("seed", [[9310, 11], [9310, 17]])
def test_a_charuco_print_without_its_margin_is_erased(seed):
    """ChArUco boards printed without the margin on dark planks (the second under a
    shadow's edge): where the margin would be the photo shows floor, which the print's
    pattern checked against the margin took for a thing lying on the board, so 84 % and
    58 % of the sheet were kept. Now nothing is said to stand on them, and they leave no
    trace."""
    case, scores = _print_case(seed)
    assert case.case["pattern"] == "charuco" and case.case["margin"] == "none"
    assert scores["ok"], (case.case, scores)


def test_the_texture_is_copied_from_floor_the_photo_shows_as_sharp():
    """room_2's carpet: the places beside the sheet that match its rim best lie farther
    from the camera, where the photo shows the carpet at half the sheet's pixels per
    square meter: copied there, the fill was a soft smudge (its fine detail 0.54 of the
    carpet's around it). Now its fine detail is 0.8-1.25 of the carpet's."""
    from pathlib import Path

    from augment.pipeline import measure

    m = measure(Path(__file__).resolve().parents[2] / "samples" / "photos" / "room_2.jpg", Board())
    erased = erase_board(m.image, m.calibration, m.segmentation.mask)
    alpha = erased.full_alpha()
    grey = cv2.cvtColor(erased.image, cv2.COLOR_RGB2GRAY).astype(np.float32)
    detail = np.abs(grey - cv2.GaussianBlur(grey, (0, 0), 1.5))
    sheet = alpha > 0.99
    around = (cv2.dilate(sheet.astype(np.uint8), np.ones((61, 61), np.uint8)) > 0) & (alpha < 0.01)
    assert 0.8 <= detail[sheet].mean() / detail[around].mean() <= 1.25


def test_a_place_the_photo_shows_coarser_is_copied_only_when_no_other_is():
    """A rim copied exactly 20 px right of a hole, and with noise 20 px left: the exact
    copy is taken, unless the photo shows its middle at half the hole's pixels per square
    meter; with every place but the hole so coarse, it is taken again."""
    from augment.render.erase import _best_offset

    rng = np.random.default_rng(3)
    texture = rng.normal(0, 20, (60, 100, 3)).astype(np.float32)
    hole = np.zeros((60, 100), bool)
    hole[25:35, 45:55] = True
    texture[19:41, 59:81] = texture[19:41, 39:61]  # the rim and hole, 20 px right
    texture[19:41, 19:41] = texture[19:41, 39:61] + rng.normal(0, 4, (22, 22, 3))  # 20 px left, noisier
    bad = hole.copy()
    assert _best_offset(texture, hole, bad, 4) == (20, 0)
    density = np.ones(hole.shape, np.float32)
    density[:, 60:] = 0.5
    assert _best_offset(texture, hole, bad, 4, density=density) == (-20, 0)
    assert _best_offset(texture, hole, bad, 4, density=np.where(hole, 1.0, 0.5).astype(np.float32)) == (20, 0)


def test_a_print_on_a_real_floor_leaves_no_trace():
    """samples/real/bedroom_closets.jpg (Curtis Adams / Pexels, Pexels License): a real
    laminate floor, the print pasted where the photo's camera would have seen it; the
    erased sheet against the photo taken without it."""
    from pathlib import Path

    from augment.photo.io import read_photo
    from augment.synth.prints import PastedBoard, level_camera, paste_print

    truth = read_photo(Path(__file__).resolve().parents[2] / "samples" / "real" / "bedroom_closets.jpg")
    K, pose = level_camera(1002.9, (1600, 1200), np.radians(6.61), 1.12, (760.0, 1040.0), np.radians(20))
    photo, sheet_px = paste_print(truth, K, pose, paper_over_floor=3.2)
    cal = calibrate_photo(photo, Board(), intrinsics=exif_intrinsics(1002.9, (1600, 1200)))
    floor = np.zeros(photo.shape[:2], bool)
    floor[700:] = True  # below the walls' feet: all floor there
    case = PastedBoard(photo, truth, K, pose, Board(), floor, sheet_px, {})
    scores = erasure_scores(case, erase_board(photo, cal, floor).image)
    assert scores["ok"] and scores["light"] <= 2.5, scores


def test_what_the_rim_knows_is_carried_smoothly_across_the_gap():
    """Push-pull: known pixels keep their values, a constant is carried exactly, and a
    ramp known on a ring is filled within its range, without steps (by hand: the gap's
    values lie between the ring's, and neighbours differ by less than the ramp's range
    over a tenth of the gap)."""
    from augment.render.erase import _push_pull

    rows, cols = np.mgrid[0:96, 0:128]
    known = ((np.abs(rows - 48) > 30) | (np.abs(cols - 64) > 40)).astype(np.float32)
    flat = np.full((96, 128, 3), 7.0, np.float32)
    np.testing.assert_allclose(_push_pull(flat * known[..., None], known), 7.0, atol=1e-4)
    ramp = np.repeat((cols / 127.0 * 10.0)[..., None], 3, axis=2).astype(np.float32)
    out = _push_pull(ramp * known[..., None], known)
    np.testing.assert_allclose(out[known > 0], ramp[known > 0], atol=1e-4)
    gap = known == 0
    assert out[gap].min() >= ramp[gap].min() - 2.0 and out[gap].max() <= ramp[gap].max() + 2.0
    assert np.abs(np.diff(out[..., 0], axis=1)).max() < 1.0 and np.abs(np.diff(out[..., 0], axis=0)).max() < 1.0


class _FlatView:
    """A top-down view whose pixel (c, r) is the floor point ((c, r) + 0.5) / ppm."""

    origin_m = np.zeros(2)
    ppm = 100.0


def _floor_around_a_sheet(seed, light):
    """(200, 240, 3) uint8: grey noise (the floor's grain) times ``light`` (200, 240), with
    the sheet (rows 70-129, columns 80-159) and where the floor is usable around it."""
    rng = np.random.default_rng(seed)
    grain = 150.0 + cv2.GaussianBlur(rng.normal(0.0, 12.0, (200, 240)).astype(np.float32), (0, 0), 1.0) * 2.0
    rgb = np.clip(grain[..., None] * light[..., None] * [1.0, 0.95, 0.85], 0, 255).astype(np.uint8)
    hole = np.zeros((200, 240), bool)
    hole[70:130, 80:160] = True
    usable = ~(cv2.dilate(hole.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0)
    return rgb, usable, hole


def test_a_straight_shadow_edge_is_found_where_it_crosses_the_sheet():
    """A soft step to 70 % of the light along a line at 30 degrees through the sheet, on
    grain: its direction within a degree, its place within a pixel, its height log(0.7)
    within 0.05 per channel; lifted, the floor steps across the line by less than a tenth
    of what it did."""
    from augment.render.erase import _lifted, _shadow_edge

    rows, cols = np.mgrid[0:200, 0:240] + 0.5
    normal = np.array([np.cos(np.deg2rad(30.0)), np.sin(np.deg2rad(30.0))])
    across = cols * normal[0] + rows * normal[1] - (120 * normal[0] + 95 * normal[1])
    light = 1.0 - 0.3 / (1.0 + np.exp(-across / 2.0))
    rgb, usable, hole = _floor_around_a_sheet(3, light)
    edge = _shadow_edge(_FlatView(), rgb, usable, hole)
    assert edge is not None
    sign = np.sign(edge.normal_m @ normal)
    assert np.degrees(np.arccos(min(1.0, abs(edge.normal_m @ normal)))) < 1.0
    assert abs(sign * edge.offset_m * 100.0 - (120 * normal[0] + 95 * normal[1])) < 1.0
    np.testing.assert_allclose(sign * edge.step, np.log(0.7), atol=0.05)
    far = usable & (np.abs(across) > 8) & (np.abs(across) < 30)

    def step(image):
        image = image.astype(float).mean(axis=2)
        return np.log(image[far & (across > 0)].mean() / image[far & (across < 0)].mean())

    before, after = step(rgb), step(_lifted(rgb, [edge.factor(_FlatView(), (0, 0, 240, 200))]))
    assert before < -0.3 and abs(after) < 0.1 * abs(before), (before, after)


@pytest.mark.parametrize("floor", ["lamp", "tiles"])
def test_no_shadow_edge_is_found_where_the_floor_has_none(floor):
    """A lamp's slow falloff across the view, and tiles of random lightness (each joint
    steps up on some tiles and down on others): neither is a shadow's edge."""
    from augment.render.erase import _shadow_edge

    rows, cols = np.mgrid[0:200, 0:240]
    if floor == "lamp":
        light = 0.6 + 0.4 * cols / 240.0
    else:
        shades = np.random.default_rng(5).uniform(0.8, 1.2, (8, 9))
        light = shades[rows // 30, cols // 30] * np.where((rows % 30 < 2) | (cols % 30 < 2), 0.7, 1.0)
    assert _shadow_edge(_FlatView(), *_floor_around_a_sheet(4, light)) is None


def test_a_shadows_edge_across_the_print_runs_on_over_the_erased_sheet():
    """A shadow's edge across a print on concrete (held-out seed): the fill once smoothed
    the light across the sheet, the edge fading out in its middle (10 levels off on
    average, correlation 0.72 with the truth, both blurred 4 px). Now the edge runs on
    across the sheet: within 7.5 levels on average, correlation above 0.85."""
    case, erased = _erased_print([9420, 5], shadow=True)
    assert case.case["floor"] == "concrete"
    sheet = np.zeros(erased.shape[:2], np.uint8)
    cv2.fillConvexPoly(sheet, np.round(case.sheet_px).astype(np.int32), 1)
    sheet = cv2.erode(sheet, np.ones((5, 5), np.uint8)) > 0
    ours, truth = (_blur(cv2.cvtColor(im, cv2.COLOR_RGB2GRAY), 4)[sheet] for im in (erased, case.truth))
    error, match = np.abs(ours - truth).mean(), np.corrcoef(ours, truth)[0, 1]
    assert error < 7.5 and match > 0.85, (error, match)
