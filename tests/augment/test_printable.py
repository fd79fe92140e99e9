"""The printable board: fit checks, and the geometry actually written into the PDF.

Scale is checked on the PDF itself, not on the figure that produced it: the file is
written uncompressed, the page's content stream is parsed (path operators under the
current transformation matrix) and its coordinates, in points, converted to millimeters.
"""
import math
import re

import matplotlib
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from augment.camera import printable
from augment.camera.board import PAPER_MM, Board
from augment.camera.printable import (DEFAULT_SQUARE_BY_PAPER_MM, PRINTER_MARGIN_MM, QUIET_ZONE_MM, board_figure,
                                      board_for_paper, write_board_pdf)

MM_PER_PT = 25.4 / 72.0

# Default boards on both papers (ruler and caption in the side margins) and one small
# board whose deep top and bottom margins take the ruler under the squares.
CASES = [("A3", None, None, None), ("A4", None, None, None), ("A3", 5, 3, 40.0)]


# --------------------------------------------------------------------------- PDF parsing

_TOKEN = re.compile(
    rb"\((?:\\.|[^\\()])*\)"  # string
    rb"|<[0-9A-Fa-f\s]*>"  # hex string
    rb"|[\[\]]"
    rb"|/[^\s/\[\]()<>]+"  # name
    rb"|[-+]?(?:\d+\.?\d*|\.\d+)"  # number
    rb"|[A-Za-z'\"*]+"  # operator
)
_PAINT = {b"f", b"F", b"f*", b"S", b"s", b"B", b"B*", b"b", b"b*", b"n"}


def page_content(pdf: bytes) -> bytes:
    """The content stream of the single page of an uncompressed PDF."""
    assert pdf.count(b"/Type /Page ") == 1, "expected exactly one page"
    page = re.search(rb"/Type /Page .*?/Contents (\d+) 0 R", pdf, re.S)
    number = page.group(1)
    stream = re.search(rb"(?:^|\n)" + number + rb" 0 obj\s*<<(.*?)>>\s*stream\r?\n(.*?)endstream",
                       pdf, re.S)
    assert b"/Filter" not in stream.group(1), "content stream is compressed"
    return stream.group(2)


def painted_paths(content: bytes):
    """Every painted path: (operator, fill gray, stroke gray, subpaths of (n, 2) mm arrays).

    Only what the tests draw is understood: m/l/h/re path construction, gray or RGB
    colors, q/Q/cm; text blocks are skipped.
    """
    ctm = np.eye(3)
    stack = []
    fill, stroke = 0.0, 0.0
    operands, subpaths, current = [], [], []
    in_text = False
    paths = []

    def to_page(x, y):
        return (np.array([x, y, 1.0]) @ ctm)[:2]

    for token in _TOKEN.findall(content):
        if not re.fullmatch(rb"[A-Za-z'\"*]+", token):
            operands.append(token)
            continue
        op, args = token, operands
        operands = []
        if in_text:
            in_text = op != b"ET"
            continue
        nums = [float(a) for a in args if re.fullmatch(rb"[-+]?(?:\d+\.?\d*|\.\d+)", a)]
        if op == b"BT":
            in_text = True
        elif op == b"q":
            stack.append((ctm.copy(), fill, stroke))
        elif op == b"Q":
            ctm, fill, stroke = stack.pop()
        elif op == b"cm":
            a, b, c, d, e, f = nums
            ctm = np.array([[a, b, 0], [c, d, 0], [e, f, 1]]) @ ctm
        elif op in (b"g", b"rg"):
            fill = float(np.mean(nums))
        elif op in (b"G", b"RG"):
            stroke = float(np.mean(nums))
        elif op == b"m":
            if current:
                subpaths.append(current)
            current = [to_page(*nums)]
        elif op == b"l":
            current.append(to_page(*nums))
        elif op == b"re":
            x, y, w, h = nums
            if current:
                subpaths.append(current)
            subpaths.append([to_page(x, y), to_page(x + w, y), to_page(x + w, y + h), to_page(x, y + h)])
            current = []
        elif op == b"h":
            if current:
                subpaths.append(current)
            current = []
        elif op in _PAINT:
            if current:
                subpaths.append(current)
            if op != b"n":  # n ends a clipping path, which paints nothing
                paths.append((op, fill, stroke, [np.array(p) * MM_PER_PT for p in subpaths]))
            subpaths, current = [], []
    return paths


def written(tmp_path, paper, cols=None, rows=None, square_mm=None):
    board = board_for_paper(paper, cols, rows, square_mm)
    with matplotlib.rc_context({"pdf.compression": 0}):
        pdf = write_board_pdf(tmp_path / "board.pdf", board, paper).read_bytes()
    return board, pdf


def black_squares_mm(paths):
    """Bounding boxes (x0, y0, x1, y1) of the black filled subpaths, mm."""
    boxes = [np.r_[p.min(0), p.max(0)] for op, fill, _, subs in paths
             if op in (b"f", b"f*", b"F") and fill == 0.0 for p in subs]
    return np.array(boxes)


def ruler_ticks_mm(paths):
    """The stroked two-point segments, (n, 2, 2) mm."""
    segments = [p for op, _, _, subs in paths if op in (b"S", b"s") for p in subs if len(p) == 2]
    return np.array(segments)


# --------------------------------------------------------------------------- fitting


@pytest.mark.parametrize("paper", ["A3", "A4"])
def test_defaults_per_paper(paper):
    board = board_for_paper(paper)
    assert (board.cols, board.rows) == (7, 5)
    assert board.square_mm == DEFAULT_SQUARE_BY_PAPER_MM[paper] == {"A3": 45.0, "A4": 30.0}[paper]
    assert board.sheet_mm == PAPER_MM[paper]
    assert board_for_paper(paper.lower()) == board


def test_explicit_board_is_kept():
    assert board_for_paper("A3", 5, 3, 40) == Board(5, 3, 40.0, PAPER_MM["A3"])


@pytest.mark.parametrize("paper, square_mm, largest_mm", [("A3", 50, 46), ("A4", 33, 32)])
def test_refuses_board_too_large_and_suggests_one_that_fits(paper, square_mm, largest_mm):
    with pytest.raises(ValueError) as info:
        board_for_paper(paper, square_mm=square_mm)
    message = str(info.value)
    sheet = PAPER_MM[paper]
    for part in (paper, "7x5", f"{square_mm} mm", f"{8 * square_mm} x {6 * square_mm} mm",
                 f"{sheet[0]:g} x {sheet[1]:g} mm", f"--square {largest_mm}"):
        assert part in message
    # The suggestion is the largest whole millimeter that fits: it does, one more does not.
    assert board_for_paper(paper, square_mm=largest_mm).square_mm == largest_mm
    with pytest.raises(ValueError):
        board_for_paper(paper, square_mm=largest_mm + 1)


def test_refuses_squares_inside_printer_margin():
    # 6 x 49 = 294 mm fits the 297 mm sheet but not inside two 8 mm printer margins.
    with pytest.raises(ValueError, match="8 mm printer margins"):
        board_for_paper("A3", square_mm=49)


def test_refuses_unknown_paper_and_bad_board():
    with pytest.raises(ValueError, match="Letter.*A3, A4"):
        board_for_paper("Letter")
    with pytest.raises(ValueError, match="inner corners"):
        board_for_paper("A3", cols=1)
    with pytest.raises(ValueError, match="positive"):
        board_for_paper("A3", square_mm=0)
    # 0.01 mm squares made a PDF no printer can print and no photo can show.
    with pytest.raises(ValueError, match="squares of 0.01 mm are too small .* 5 mm or more"):
        board_for_paper("A4", square_mm=0.01)
    assert board_for_paper("A4", square_mm=5).square_mm == 5


def test_write_refuses_board_that_does_not_fit(tmp_path):
    with pytest.raises(ValueError, match="does not fit on A4"):
        write_board_pdf(tmp_path / "board.pdf", Board(), "A4")  # the A3 default board
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- the PDF


@pytest.mark.parametrize("paper", ["A3", "A4"])
def test_page_is_the_landscape_paper(tmp_path, paper):
    board, pdf = written(tmp_path, paper)
    assert pdf.startswith(b"%PDF")
    box = re.findall(rb"/MediaBox\s*\[\s*([-\d.\s]+)\]", pdf)
    assert len(box) == 1
    x0, y0, x1, y1 = (float(v) for v in box[0].split())
    expected_pt = {"A3": (1190.55, 841.89), "A4": (841.89, 595.28)}[paper]
    assert (x0, y0) == (0.0, 0.0)
    assert x1 == pytest.approx(expected_pt[0], abs=0.1)
    assert y1 == pytest.approx(expected_pt[1], abs=0.1)


@pytest.mark.parametrize("paper, cols, rows, square_mm", CASES)
def test_squares_are_written_at_exact_scale_and_centered(tmp_path, paper, cols, rows, square_mm):
    board, pdf = written(tmp_path, paper, cols, rows, square_mm)
    s = board.square_mm
    sheet_w, sheet_h = PAPER_MM[paper]
    boxes = black_squares_mm(painted_paths(page_content(pdf)))

    assert len(boxes) == math.ceil((board.cols + 1) * (board.rows + 1) / 2)
    np.testing.assert_allclose(boxes[:, 2] - boxes[:, 0], s, atol=0.05)
    np.testing.assert_allclose(boxes[:, 3] - boxes[:, 1], s, atol=0.05)

    x0, y0 = boxes[:, :2].min(0)
    x1, y1 = boxes[:, 2:].max(0)
    assert x1 - x0 == pytest.approx((board.cols + 1) * s, abs=0.05)
    assert y1 - y0 == pytest.approx((board.rows + 1) * s, abs=0.05)
    assert (x0 + x1) / 2 == pytest.approx(sheet_w / 2, abs=0.1)
    assert (y0 + y1) / 2 == pytest.approx(sheet_h / 2, abs=0.1)

    # A checkerboard with its top-left square black: column i, row j (from the top) black
    # exactly when i + j is even.
    i = np.rint((boxes[:, 0] - x0) / s).astype(int)
    j = np.rint((y1 - boxes[:, 3]) / s).astype(int)
    assert sorted(zip(i, j)) == sorted((a, b) for a in range(board.cols + 1)
                                       for b in range(board.rows + 1) if (a + b) % 2 == 0)
    assert (0, 0) in set(zip(i, j))


@pytest.mark.parametrize("paper, cols, rows, square_mm", CASES)
def test_ruler_has_101_ticks_one_mm_apart_in_the_margin(tmp_path, paper, cols, rows, square_mm):
    board, pdf = written(tmp_path, paper, cols, rows, square_mm)
    paths = painted_paths(page_content(pdf))
    ticks = ruler_ticks_mm(paths)
    assert ticks.shape == (101, 2, 2)

    direction = ticks[:, 1] - ticks[:, 0]
    across = 0 if np.allclose(direction[:, 1], 0, atol=1e-6) else 1  # axis the ticks span
    assert np.allclose(direction[:, 1 - across], 0, atol=1e-6), "ticks must be parallel"
    positions = np.sort(ticks[:, 0, 1 - across])
    np.testing.assert_allclose(np.diff(positions), 1.0, atol=0.01)
    assert positions[-1] - positions[0] == pytest.approx(100.0, abs=0.05)

    lengths = np.abs(direction[np.argsort(ticks[:, 0, 1 - across]), across])
    assert np.all(lengths[::10] > lengths.max() - 1e-6)  # long ticks at 0, 10, ..., 100
    assert np.all(np.delete(lengths, np.s_[::10]) < lengths.max())

    # Inside the printable area and clear of the squares.
    sheet_w, sheet_h = PAPER_MM[paper]
    points = ticks.reshape(-1, 2)
    assert points[:, 0].min() >= PRINTER_MARGIN_MM - 1e-6
    assert points[:, 1].min() >= PRINTER_MARGIN_MM - 1e-6
    assert points[:, 0].max() <= sheet_w - PRINTER_MARGIN_MM + 1e-6
    assert points[:, 1].max() <= sheet_h - PRINTER_MARGIN_MM + 1e-6
    squares = black_squares_mm(paths)
    sq0 = squares[:, :2].min(0) - QUIET_ZONE_MM
    sq1 = squares[:, 2:].max(0) + QUIET_ZONE_MM
    inside = np.all((points > sq0) & (points < sq1), axis=1)
    assert not inside.any()
    if (board.cols, board.rows) == (5, 3):
        assert across == 1 and points[:, 1].max() < sq0[1], "deep margins: ruler under the squares"
    else:
        assert across == 0, "shallow top and bottom margins: ruler in a side margin"


@pytest.mark.parametrize("paper, cols, rows, square_mm", CASES)
def test_texts_are_readable_and_clear_of_squares_and_paper_edge(paper, cols, rows, square_mm):
    board = board_for_paper(paper, cols, rows, square_mm)
    fig = board_figure(board, paper)
    renderer = FigureCanvasAgg(fig).get_renderer()
    mm_per_px = 25.4 / fig.dpi
    sheet_w, sheet_h = PAPER_MM[paper]
    ax = fig.axes[0]
    assert ax.get_xlim() == (0.0, sheet_w) and ax.get_ylim() == (0.0, sheet_h)
    s = board.square_mm
    sq0 = np.array([sheet_w - (board.cols + 1) * s, sheet_h - (board.rows + 1) * s]) / 2
    sq1 = np.array([sheet_w, sheet_h]) - sq0

    texts = ax.texts
    assert {t.get_text() for t in texts} >= {str(v) for v in range(0, 101, 10)}
    caption = " ".join(t.get_text() for t in texts)
    assert f"--board {board.cols}x{board.rows} --square {s:g}" in caption
    assert f"Stager board {board.cols}x{board.rows} inner corners, {s:g} mm squares, {paper}" in caption
    assert "print at 100 %" in caption
    for text in texts:
        assert text.get_fontsize() >= 7
        box = text.get_window_extent(renderer)
        lo = np.array([box.x0, box.y0]) * mm_per_px
        hi = np.array([box.x1, box.y1]) * mm_per_px
        assert lo.min() >= PRINTER_MARGIN_MM - 0.01, text.get_text()
        assert hi[0] <= sheet_w - PRINTER_MARGIN_MM + 0.01 and hi[1] <= sheet_h - PRINTER_MARGIN_MM + 0.01
        overlaps = np.all(lo < sq1 + QUIET_ZONE_MM - 0.01) and np.all(hi > sq0 - QUIET_ZONE_MM + 0.01)
        assert not overlaps, text.get_text()


# --------------------------------------------------------------------------- writing


def test_write_is_atomic_and_leaves_no_temporary_files(tmp_path, monkeypatch):
    board = board_for_paper("A4")
    target = tmp_path / "board.pdf"
    assert write_board_pdf(target, board, "A4") == target
    assert [p.name for p in tmp_path.iterdir()] == ["board.pdf"]
    first = target.read_bytes()
    assert write_board_pdf(str(target), board, "A4") == target  # overwrite, same bytes
    assert target.read_bytes() == first
    assert [p.name for p in tmp_path.iterdir()] == ["board.pdf"]

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(printable.FigureCanvasPdf, "print_pdf", fail)
    with pytest.raises(OSError, match="disk full"):
        write_board_pdf(target, board_for_paper("A3"), "A3")
    assert [p.name for p in tmp_path.iterdir()] == ["board.pdf"]
    assert target.read_bytes() == first


def test_write_to_missing_folder_names_it(tmp_path):
    missing = tmp_path / "no" / "such"
    with pytest.raises(FileNotFoundError, match=re.escape(str(missing))):
        write_board_pdf(missing / "board.pdf", board_for_paper("A3"), "A3")
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- ChArUco


def test_charuco_markers_are_written_bit_by_bit_at_exact_scale(tmp_path):
    """The black areas of the ChArUco PDF, sampled at the middle of each 1/8-square bit
    cell, are the page OpenCV generates (Board.printed_image, checked against OpenCV in
    test_board); the squares stay where a checkerboard's are."""
    board = board_for_paper("A4", kind="charuco")
    with matplotlib.rc_context({"pdf.compression": 0}):
        pdf = write_board_pdf(tmp_path / "board.pdf", board, "A4").read_bytes()
    boxes = black_squares_mm(painted_paths(page_content(pdf)))
    s = board.square_mm
    sheet_w, sheet_h = PAPER_MM["A4"]
    x0 = (sheet_w - (board.cols + 1) * s) / 2
    y_top = (sheet_h + (board.rows + 1) * s) / 2
    cells = 8 * np.array([board.rows + 1, board.cols + 1])
    # Cell (r, c) center on the page, mm.
    cx = x0 + (np.arange(cells[1]) + 0.5) * s / 8
    cy = y_top - (np.arange(cells[0]) + 0.5) * s / 8
    inside = ((boxes[:, None, None, 0] < cx[None, None, :]) & (cx[None, None, :] < boxes[:, None, None, 2])
              & (boxes[:, None, None, 1] < cy[None, :, None]) & (cy[None, :, None] < boxes[:, None, None, 3]))
    black = inside.any(axis=0)
    np.testing.assert_array_equal(black, board.printed_image(8) == 0)
    # Nothing black outside the squares' area.
    assert boxes[:, 0].min() == pytest.approx(x0, abs=0.05) and boxes[:, 3].max() == pytest.approx(y_top, abs=0.05)


def test_charuco_caption_names_the_dictionary_and_the_flags():
    board = board_for_paper("A3", kind="charuco")
    description, flags = printable.caption_lines(board, "A3")
    assert "ChArUco" in description and "DICT_4X4_50" in description and "45 mm squares, A3" in description
    assert flags.endswith("--board charuco:7x5 --square 45")


def test_printed_charuco_page_is_detected_where_the_board_frame_says():
    """The page as a printer would put it on paper (rasterized at 60 dpi), read by the
    ChArUco detector: all 35 corners, each where Board.corners_m puts it on the sheet (board
    x to the right, y up the page, origin at the squares' center)."""
    from augment.camera.detect import detect_board

    board = board_for_paper("A4", kind="charuco")
    fig = board_figure(board, "A4")
    fig.set_dpi(60)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    page = np.asarray(canvas.buffer_rgba())[..., :3].copy()
    detection = detect_board(page, board)
    assert detection is not None and len(detection.ids) == board.corner_count
    px_per_mm = page.shape[1] / PAPER_MM["A4"][0]
    corners_mm = board.corners_m()[detection.ids, :2] * 1000
    expected = np.column_stack([PAPER_MM["A4"][0] / 2 + corners_mm[:, 0],
                                PAPER_MM["A4"][1] / 2 - corners_mm[:, 1]]) * px_per_mm - 0.5
    np.testing.assert_allclose(detection.corners_px, expected, atol=0.5)
