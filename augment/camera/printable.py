"""The printable board: a one-page PDF of the checkerboard at exact scale.

The user prints it, lays it on the floor and photographs the room; the calibration then
trusts that a square on paper is ``square_mm`` wide. So the page is drawn in millimeters
(the figure is the paper, one axes spans it with limits in mm) and the margin carries a
100 mm ruler that tells at a glance whether the printer rescaled the page ("fit to page"
is a common default), plus a caption with the command-line flags matching the print.

Page layout. The squares are centered on the landscape sheet, top-left square black, as
in :meth:`augment.camera.board.Board.printed_image`; a ChArUco board's markers sit in the white
squares, drawn bit by bit. The ruler and the caption go into the margins around
the squares, never closer than :data:`PRINTER_MARGIN_MM` to the paper edge (most printers
cannot print there) nor than :data:`QUIET_ZONE_MM` to the squares (the corner detector
needs white around the outer squares). They are placed automatically: the ruler under the
squares and the caption above when those margins are deep enough, otherwise both turned a
quarter and set in the side margins.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_pdf import FigureCanvasPdf
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.patches import PathPatch
from matplotlib.path import Path as MplPath
from matplotlib.textpath import TextToPath

from layout.fileio import atomic_path

from .board import (CHARUCO_BITS_PER_SQUARE, CHARUCO_DICTIONARY, CHARUCO_MARKER_BITS, DEFAULT_INNER_CORNERS,
                    MIN_SQUARE_MM, PAPER_MM, Board)

DEFAULT_SQUARE_BY_PAPER_MM = {"A3": 45.0, "A4": 30.0}

PRINTER_MARGIN_MM = 8.0
"""Nothing, squares included, is drawn closer than this to the paper edge: most office
printers leave 3-6 mm blank, 8 mm covers them with room to spare."""

QUIET_ZONE_MM = 4.0
"""White kept between the outer squares and the ruler or caption."""

RULER_MM = 100
MM_PER_INCH = 25.4
PT_PER_INCH = 72.0

_FONT_FAMILY = "DejaVu Sans"  # ships with matplotlib: the measured text is the printed text
_RULER_FONT_PT = 7.0
_CAPTION_FONTS_PT = (8.0, 7.0)  # 7 pt is the smallest still comfortable to read on paper
_LINE_SPACING = 1.25
_TICK_MM = {10: 5.0, 5: 3.5, 1: 2.0}  # tick length by the divisor of the mm value
_TICK_LABEL_GAP_MM = 1.0
_TICK_WIDTH_MM = 0.2
_ITEM_GAP_MM = 2.0
# Rasterizing renderers hint text to pixels and report boxes up to ~0.2 mm larger than
# the font's own metrics; texts keep this much extra room on every side.
_TEXT_SLACK_MM = 0.5


def _pt_to_mm(pt: float) -> float:
    return pt * MM_PER_INCH / PT_PER_INCH


def _paper_mm(paper: str) -> tuple[str, tuple[float, float]]:
    key = str(paper).upper()
    if key not in PAPER_MM:
        raise ValueError(f"paper {paper!r}: unknown; choose one of {', '.join(sorted(PAPER_MM))}")
    return key, PAPER_MM[key]


def board_for_paper(paper: str, cols: int | None = None, rows: int | None = None,
                    square_mm: float | None = None, kind: str = "chessboard") -> Board:
    """The board printed on ``paper``, checked to fit.

    Parameters
    ----------
    paper : str
        ``"A3"`` or ``"A4"`` (case-insensitive), used landscape.
    cols, rows : int, optional
        Inner corners per row and per column; default 7 x 5.
    square_mm : float, optional
        Side of one square, millimeters; default the paper's entry in
        :data:`DEFAULT_SQUARE_BY_PAPER_MM` (45 mm on A3, 30 mm on A4).
    kind : str
        ``"chessboard"`` or ``"charuco"`` (see :class:`augment.camera.board.Board`).

    Returns
    -------
    Board
        With ``sheet_mm`` the paper's landscape size.

    Raises
    ------
    ValueError
        When the paper is unknown, the squares are under :data:`MIN_SQUARE_MM`, or they
        do not fit inside the :data:`PRINTER_MARGIN_MM` margins with room left for the
        ruler and caption; the message names the paper, the board and the sizes, and
        suggests the largest square in whole millimeters that fits.
    """
    paper, sheet_mm = _paper_mm(paper)
    cols = DEFAULT_INNER_CORNERS[0] if cols is None else int(cols)
    rows = DEFAULT_INNER_CORNERS[1] if rows is None else int(rows)
    square_mm = DEFAULT_SQUARE_BY_PAPER_MM[paper] if square_mm is None else float(square_mm)
    # A board on its own default sheet always fits, so this checks only the counts and
    # the square size, leaving the paper to the message below.
    _check_fits(Board(cols, rows, square_mm, kind=kind), paper)
    if not square_mm >= MIN_SQUARE_MM:
        raise ValueError(f"squares of {square_mm:g} mm are too small to print and to see across a room; use "
                         f"{MIN_SQUARE_MM:g} mm or more (the default on {paper} is "
                         f"{DEFAULT_SQUARE_BY_PAPER_MM[paper]:g})")
    return Board(cols, rows, square_mm, sheet_mm, kind)


def _check_fits(board: Board, paper: str) -> None:
    """Raise the ValueError of :func:`board_for_paper` when ``board`` does not fit."""
    paper, sheet_mm = _paper_mm(paper)
    if _plan(board, paper) is not None:
        return
    squares_mm = ((board.cols + 1) * board.square_mm, (board.rows + 1) * board.square_mm)
    inside_mm = tuple(s - 2 * PRINTER_MARGIN_MM for s in sheet_mm)
    # Whole millimeters are what a user types; the bound below is where the squares alone
    # touch the printer margins, and the ruler and caption may need a little less.
    largest = math.floor(min(inside_mm[0] / (board.cols + 1), inside_mm[1] / (board.rows + 1)))
    while largest >= 1 and _plan(Board(board.cols, board.rows, float(largest), kind=board.kind), paper) is None:
        largest -= 1
    if largest >= 1:
        advice = (f"use squares of {largest} mm or less (--square {largest}), "
                  f"fewer corners, or larger paper")
    else:
        advice = "use fewer corners or larger paper"
    raise ValueError(
        f"board {board.cols}x{board.rows} with {board.square_mm:g} mm squares does not fit on "
        f"{paper}: its squares need {squares_mm[0]:g} x {squares_mm[1]:g} mm, the "
        f"{sheet_mm[0]:g} x {sheet_mm[1]:g} mm sheet has {inside_mm[0]:g} x {inside_mm[1]:g} mm "
        f"inside its {PRINTER_MARGIN_MM:g} mm printer margins, and the ruler and caption need "
        f"room beside the squares; {advice}"
    )


# --------------------------------------------------------------------------- layout


@dataclass(frozen=True)
class _Band:
    """A free strip of margin between the squares and the printer margin.

    Local coordinates: ``u`` along the reading direction, ``v`` towards the top of the
    text (so turned text reads upwards); the strip is ``[0, length_mm] x [0, depth_mm]``.
    """

    name: str
    origin_mm: tuple[float, float]
    u_dir: tuple[float, float]
    v_dir: tuple[float, float]
    length_mm: float
    depth_mm: float
    edge_at_v0: bool  # whether the paper edge is on the v = 0 side
    rotation_deg: float

    def to_page(self, u_mm: float, v_mm: float) -> tuple[float, float]:
        return (self.origin_mm[0] + u_mm * self.u_dir[0] + v_mm * self.v_dir[0],
                self.origin_mm[1] + u_mm * self.u_dir[1] + v_mm * self.v_dir[1])


def _bands(sheet_mm, squares_mm) -> dict[str, _Band]:
    w, h = sheet_mm
    mx = (w - squares_mm[0]) / 2
    my = (h - squares_mm[1]) / 2
    p, q = PRINTER_MARGIN_MM, QUIET_ZONE_MM
    across_x = (1.0, 0.0), (0.0, 1.0)
    upwards = (0.0, 1.0), (-1.0, 0.0)
    return {
        "bottom": _Band("bottom", (p, p), *across_x, w - 2 * p, my - p - q, True, 0.0),
        "top": _Band("top", (p, h - my + q), *across_x, w - 2 * p, my - p - q, False, 0.0),
        "left": _Band("left", (mx - q, p), *upwards, h - 2 * p, mx - p - q, False, 90.0),
        "right": _Band("right", (w - p, p), *upwards, h - 2 * p, mx - p - q, True, 90.0),
    }


# The ruler reads best under the squares and the caption above them; a side margin comes
# next, with the caption in the opposite one so neither crowds the other.
_PREFERENCES = {
    "bottom": ("top", "bottom", "left", "right"),
    "left": ("right", "left", "top", "bottom"),
    "right": ("left", "right", "top", "bottom"),
    "top": ("bottom", "top", "left", "right"),
}

_TEXT_TO_PATH = TextToPath()


def _text_mm(text: str, size_pt: float) -> tuple[float, float, float]:
    """Width, ascent and descent of ``text`` set in the page font, millimeters.

    Ascent and descent are at least those of "lp", as matplotlib lays out a line, so the
    box is the one matplotlib reports for the drawn text.
    """
    prop = FontProperties(family=_FONT_FAMILY, size=size_pt)
    w, h, d = _TEXT_TO_PATH.get_text_width_height_descent(text, prop, ismath=False)
    _, h_lp, d_lp = _TEXT_TO_PATH.get_text_width_height_descent("lp", prop, ismath=False)
    return _pt_to_mm(w), _pt_to_mm(max(h - d, h_lp - d_lp)), _pt_to_mm(max(d, d_lp))


@dataclass(frozen=True)
class _Item:
    kind: str  # "ruler" or "caption"
    length_mm: float
    depth_mm: float
    lines: tuple[str, ...] = ()
    size_pt: float = _RULER_FONT_PT


def _ruler_item() -> _Item:
    w0 = _text_mm("0", _RULER_FONT_PT)[0]
    w100 = _text_mm(str(RULER_MM), _RULER_FONT_PT)[0]
    w_unit = _text_mm("mm", _RULER_FONT_PT)[0]
    digit_ascent = _text_mm("0123456789", _RULER_FONT_PT)[1]
    length = 2 * _TEXT_SLACK_MM + w0 / 2 + RULER_MM + w100 / 2 + _TICK_LABEL_GAP_MM + w_unit
    depth = max(_TICK_MM.values()) + _TICK_LABEL_GAP_MM + digit_ascent + _TEXT_SLACK_MM
    return _Item("ruler", length, depth)


def caption_lines(board: Board, paper: str) -> tuple[str, str]:
    """The two lines of the caption: what the sheet is and how to print it, then the flags.

    A ChArUco board names its marker dictionary, which a detector must be given.

    Parameters
    ----------
    board : Board
    paper : str

    Returns
    -------
    tuple of str
    """
    what = "board" if board.kind == "chessboard" else "ChArUco board"
    markers = "" if board.kind == "chessboard" else f" (markers {CHARUCO_DICTIONARY})"
    description = (f"Stager {what} {board.cols}x{board.rows} inner corners{markers}, {board.square_mm:g} mm "
                   f"squares, {paper} - print at 100 % (actual size); check the ruler: {RULER_MM} mm")
    flags = f"command-line flags: --board {board.spec} --square {board.square_mm:g}"
    return description, flags


def _caption_items(board: Board, paper: str):
    description, flags = caption_lines(board, paper)
    for size_pt in _CAPTION_FONTS_PT:
        for lines in ((f"{description}; {flags}",), (description, flags)):
            metrics = [_text_mm(line, size_pt) for line in lines]
            ascent = metrics[0][1]
            descent = metrics[-1][2]
            depth = ascent + (len(lines) - 1) * _pt_to_mm(_LINE_SPACING * size_pt) + descent
            yield _Item("caption", max(m[0] for m in metrics) + 2 * _TEXT_SLACK_MM,
                        depth + 2 * _TEXT_SLACK_MM, lines, size_pt)


@dataclass(frozen=True)
class _Placed:
    item: _Item
    band: _Band
    u0_mm: float
    v0_mm: float

    def page_box_mm(self) -> tuple[float, float, float, float]:
        corners = [self.band.to_page(u, v)
                   for u in (self.u0_mm, self.u0_mm + self.item.length_mm)
                   for v in (self.v0_mm, self.v0_mm + self.item.depth_mm)]
        xs, ys = zip(*corners)
        return min(xs), min(ys), max(xs), max(ys)


def _stack(items: list[_Item], band: _Band) -> list[_Placed] | None:
    """Items stacked from the paper edge inwards, centered along the band, or None."""
    depth = sum(i.depth_mm for i in items) + _ITEM_GAP_MM * (len(items) - 1)
    if depth > band.depth_mm or max(i.length_mm for i in items) > band.length_mm:
        return None
    placed = []
    # Hugging the paper edge keeps the white around the squares as wide as possible.
    v = 0.0 if band.edge_at_v0 else band.depth_mm
    for item in items:
        if not band.edge_at_v0:
            v -= item.depth_mm
        placed.append(_Placed(item, band, (band.length_mm - item.length_mm) / 2, v))
        v = v + item.depth_mm + _ITEM_GAP_MM if band.edge_at_v0 else v - _ITEM_GAP_MM
    return placed


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _plan(board: Board, paper: str) -> list[_Placed] | None:
    """Where the ruler and the caption go, or None when the board does not fit."""
    sheet_mm = PAPER_MM[paper]
    squares_mm = ((board.cols + 1) * board.square_mm, (board.rows + 1) * board.square_mm)
    if any(s + 2 * PRINTER_MARGIN_MM > p for s, p in zip(squares_mm, sheet_mm)):
        return None
    bands = _bands(sheet_mm, squares_mm)
    ruler = _ruler_item()
    captions = list(_caption_items(Board(board.cols, board.rows, board.square_mm, sheet_mm, board.kind), paper))
    for ruler_band, caption_bands in _PREFERENCES.items():
        for caption_band in caption_bands:
            for caption in captions:
                if ruler_band == caption_band:
                    placed = _stack([ruler, caption], bands[ruler_band])
                else:
                    a = _stack([ruler], bands[ruler_band])
                    b = _stack([caption], bands[caption_band])
                    placed = None if a is None or b is None else a + b
                    # Perpendicular bands share the sheet's corners.
                    if placed and _overlap(placed[0].page_box_mm(), placed[1].page_box_mm()):
                        placed = None
                if placed:
                    return placed
    return None


# --------------------------------------------------------------------------- drawing


def _no_simplify(path: MplPath) -> MplPath:
    # Long line-only paths are simplified by default, which may merge or drop ticks.
    path.should_simplify = False
    return path


def _squares_path(board: Board, sheet_mm) -> MplPath:
    s = board.square_mm
    x0 = (sheet_mm[0] - (board.cols + 1) * s) / 2
    y_top = (sheet_mm[1] + (board.rows + 1) * s) / 2
    vertices, codes = [], []
    for j in range(board.rows + 1):
        for i in range(board.cols + 1):
            if (i + j) % 2:
                continue
            x, y = x0 + i * s, y_top - (j + 1) * s
            vertices += [(x, y), (x + s, y), (x + s, y + s), (x, y + s), (x, y)]
            codes += [MplPath.MOVETO, MplPath.LINETO, MplPath.LINETO, MplPath.LINETO,
                      MplPath.CLOSEPOLY]
    return _no_simplify(MplPath(vertices, codes))


def _markers_path(board: Board, sheet_mm) -> MplPath:
    """The black bits of the ChArUco markers, one rectangle per run of black bits in a row
    of a marker, 1/8 of a square each (as :meth:`Board.printed_image` draws them)."""
    s = board.square_mm
    bit = s / CHARUCO_BITS_PER_SQUARE
    margin = (CHARUCO_BITS_PER_SQUARE - CHARUCO_MARKER_BITS) / 2 * bit
    x0 = (sheet_mm[0] - (board.cols + 1) * s) / 2
    y_top = (sheet_mm[1] + (board.rows + 1) * s) / 2
    vertices, codes = [], []
    for _, i, j, bits in board.markers():
        left, top = x0 + i * s + margin, y_top - j * s - margin
        for r, row in enumerate(bits):
            padded = np.concatenate([[False], row, [False]]).astype(np.int8)
            edges = np.flatnonzero(np.diff(padded))
            for a, b in zip(edges[::2], edges[1::2]):
                x, y = left + a * bit, top - (r + 1) * bit
                w = (b - a) * bit
                vertices += [(x, y), (x + w, y), (x + w, y + bit), (x, y + bit), (x, y)]
                codes += [MplPath.MOVETO, MplPath.LINETO, MplPath.LINETO, MplPath.LINETO, MplPath.CLOSEPOLY]
    return _no_simplify(MplPath(vertices, codes))


def _draw_ruler(ax, placed: _Placed) -> None:
    band = placed.band
    u_zero = placed.u0_mm + _TEXT_SLACK_MM + _text_mm("0", _RULER_FONT_PT)[0] / 2
    v_base = placed.v0_mm
    vertices, codes = [], []
    for mm in range(RULER_MM + 1):
        tick_mm = next(length for divisor, length in _TICK_MM.items() if mm % divisor == 0)
        vertices += [band.to_page(u_zero + mm, v_base), band.to_page(u_zero + mm, v_base + tick_mm)]
        codes += [MplPath.MOVETO, MplPath.LINETO]
    ax.add_patch(PathPatch(
        _no_simplify(MplPath(vertices, codes)), fill=False, edgecolor="black",
        linewidth=_TICK_WIDTH_MM * PT_PER_INCH / MM_PER_INCH, capstyle="butt",
        snap=False, clip_on=False, gid="ruler-ticks"))
    v_label = v_base + max(_TICK_MM.values()) + _TICK_LABEL_GAP_MM
    style = dict(fontsize=_RULER_FONT_PT, family=_FONT_FAMILY, rotation=band.rotation_deg,
                 rotation_mode="anchor", va="baseline", clip_on=False)
    for mm in range(0, RULER_MM + 1, 10):
        ax.text(*band.to_page(u_zero + mm, v_label), str(mm), ha="center", **style)
    u_unit = u_zero + RULER_MM + _text_mm(str(RULER_MM), _RULER_FONT_PT)[0] / 2 + _TICK_LABEL_GAP_MM
    ax.text(*band.to_page(u_unit, v_label), "mm", ha="left", **style)


def _draw_caption(ax, placed: _Placed) -> None:
    band, item = placed.band, placed.item
    u_mid = placed.u0_mm + item.length_mm / 2
    baseline = (placed.v0_mm + item.depth_mm - _TEXT_SLACK_MM
                - _text_mm(item.lines[0], item.size_pt)[1])
    for line in item.lines:
        ax.text(*band.to_page(u_mid, baseline), line, fontsize=item.size_pt, family=_FONT_FAMILY,
                rotation=band.rotation_deg, rotation_mode="anchor", ha="center", va="baseline",
                clip_on=False)
        baseline -= _pt_to_mm(_LINE_SPACING * item.size_pt)


def board_figure(board: Board, paper: str) -> Figure:
    """The printable page as a matplotlib figure the size of the paper.

    The single axes spans the figure with limits in millimeters, so data coordinates are
    millimeters on paper (origin at the bottom-left corner of the sheet).

    Parameters
    ----------
    board : Board
    paper : str
        ``"A3"`` or ``"A4"``; sets the page, whatever ``board.sheet_mm`` says.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        When the board does not fit on the paper (see :func:`board_for_paper`).
    """
    paper, sheet_mm = _paper_mm(paper)
    _check_fits(board, paper)
    plan = _plan(board, paper)
    fig = Figure(figsize=(sheet_mm[0] / MM_PER_INCH, sheet_mm[1] / MM_PER_INCH), facecolor="white")
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0.0, sheet_mm[0])
    ax.set_ylim(0.0, sheet_mm[1])
    ax.set_axis_off()
    # Snapping moves edges to pixel boundaries, which would distort raster previews of the
    # page; the PDF is unaffected either way.
    ax.add_patch(PathPatch(_squares_path(board, sheet_mm), facecolor="black", edgecolor="none",
                           linewidth=0.0, snap=False, clip_on=False, gid="squares"))
    if board.kind == "charuco":
        ax.add_patch(PathPatch(_markers_path(board, sheet_mm), facecolor="black", edgecolor="none",
                               linewidth=0.0, snap=False, clip_on=False, gid="markers"))
    for placed in plan:
        (_draw_ruler if placed.item.kind == "ruler" else _draw_caption)(ax, placed)
    return fig


def write_board_pdf(path, board: Board, paper: str) -> Path:
    """Write the board as a one-page PDF at exact scale, atomically.

    One millimeter in the file is one millimeter on the paper when printed at actual size;
    the page is the landscape sheet of ``paper``.

    Parameters
    ----------
    path : str or Path
        The PDF to write; its folder must exist.
    board : Board
    paper : str
        ``"A3"`` or ``"A4"``.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    FileNotFoundError
        When the folder of ``path`` does not exist.
    ValueError
        When the board does not fit on the paper.
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise FileNotFoundError(f"cannot write {path}: folder {path.parent} does not exist")
    paper, _ = _paper_mm(paper)
    fig = board_figure(board, paper)
    title = f"Stager board {board.spec}, {board.square_mm:g} mm squares, {paper}"
    with atomic_path(path) as tmp:
        # No creation date: the same board gives the same bytes.
        FigureCanvasPdf(fig).print_pdf(str(tmp), metadata={
            "Title": title, "Creator": "Stager", "CreationDate": None})
    return path


__all__ = ["DEFAULT_SQUARE_BY_PAPER_MM", "PRINTER_MARGIN_MM", "QUIET_ZONE_MM", "board_figure",
           "board_for_paper", "caption_lines", "write_board_pdf"]

