"""The printed board: its geometry in its own frame and its printable image.

Two kinds. A plain checkerboard (``"chessboard"``, the default) must be seen whole. A
ChArUco board (``"charuco"``) is the same checkerboard with an ArUco marker of the fixed
dictionary :data:`CHARUCO_DICTIONARY` printed in each white square (OpenCV's
``cv2.aruco.CharucoBoard``), so every inner corner it shows is known by its number: a
board partly hidden by a chair leg or cut by the frame still calibrates.

Board frame: origin at the center of the squares, x along a row of inner corners
(``cols`` of them), y along a column (``rows``), z out of the printed face; meters. Inner
corner ``k = j * cols + i`` lies at ``((i - (cols - 1) / 2) * s, (j - (rows - 1) / 2) * s, 0)``.
Seen from above, the board face up, x points right and y up: the printed page's top edge
is at +y, so corner row ``j`` is printed row ``rows - 1 - j`` counted from the top
(:meth:`Board.corner_ids` turns OpenCV's ChArUco corner numbers into these).

Defaults. The standard board has 7x5 inner corners (8 x 6 squares). With 45 mm squares it
fills an A3 sheet (360 x 270 mm of squares on 420 x 297 mm paper, margins 30 and
13.5 mm); 50 mm squares would need 300 mm across the sheet's 297 mm. On A4 the squares
are 30 mm. The synthetic photographer and every ``stage`` command share these defaults.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from typing import NamedTuple

import numpy as np

PAPER_MM = {"A4": (297.0, 210.0), "A3": (420.0, 297.0)}
DEFAULT_INNER_CORNERS = (7, 5)
DEFAULT_PAPER = "A3"
DEFAULT_SQUARE_MM = {"A3": 45.0, "A4": 30.0}[DEFAULT_PAPER]
# Smaller squares are a few pixels in a room photo, and a ChArUco marker's bits in them
# are a few printer dots.
MIN_SQUARE_MM = 5.0
# Limits no printed board reaches: more inner corners a side, or larger squares.
MAX_INNER_CORNERS = 100
MAX_SQUARE_MM = 1000.0
BOARD_KINDS = ("chessboard", "charuco")
# ChArUco: 4x4-bit markers are the easiest to read when small; 50 of them cover boards up
# to 100 squares (the default 8 x 6 squares use 24). The marker, its black border
# included (6 bits), fills 3/4 of its square: one bit of white on each side.
CHARUCO_DICTIONARY = "DICT_4X4_50"
CHARUCO_MARKER_BITS = 6
CHARUCO_BITS_PER_SQUARE = 8


@lru_cache(maxsize=8)
def _dictionary():
    import cv2

    return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, CHARUCO_DICTIONARY))


@lru_cache(maxsize=8)
def charuco_board(cols: int, rows: int):
    """OpenCV's ``CharucoBoard`` of ``cols`` x ``rows`` inner corners, in square units
    (the pattern does not depend on the square size)."""
    import cv2

    return cv2.aruco.CharucoBoard((cols + 1, rows + 1), 1.0, CHARUCO_MARKER_BITS / CHARUCO_BITS_PER_SQUARE,
                                  _dictionary())


def _short(number) -> str:
    """A number as a message names it: a long one by its first digits and its length."""
    text = number if isinstance(number, str) else str(number)
    return text if len(text) <= 12 else f"{text[:6]}…({len(text)} digits)"


@dataclass(frozen=True)
class Board:
    """A board of ``cols`` x ``rows`` inner corners printed on a sheet.

    Parameters
    ----------
    cols, rows : int
        Inner corners per row and per column (squares are one more each way).
    square_mm : float
        Side of one square, millimeters.
    sheet_mm : (width, height), optional
        The paper, landscape, squares centered on it. Default: the A3 sheet for the
        default board, otherwise the squares with a one-square white margin.
    kind : str
        ``"chessboard"`` (default) or ``"charuco"`` (markers of
        :data:`CHARUCO_DICTIONARY` in the white squares).
    """

    cols: int = DEFAULT_INNER_CORNERS[0]
    rows: int = DEFAULT_INNER_CORNERS[1]
    square_mm: float = DEFAULT_SQUARE_MM
    sheet_mm: tuple[float, float] | None = None
    kind: str = "chessboard"

    def __post_init__(self):
        if self.kind not in BOARD_KINDS:
            raise ValueError(f"board kind {self.kind!r}: choose one of {', '.join(BOARD_KINDS)}")
        if int(self.cols) < 2 or int(self.rows) < 2:
            raise ValueError(
                f"board {self.cols}x{self.rows}: needs at least 2x2 inner corners "
                "(count the corners where four squares meet, not the squares)"
            )
        if int(self.cols) > MAX_INNER_CORNERS or int(self.rows) > MAX_INNER_CORNERS:
            raise ValueError(f"board {_short(self.cols)}x{_short(self.rows)}: at most {MAX_INNER_CORNERS} inner "
                             "corners a side; count the corners where four squares meet, e.g. 7x5")
        if not 0 < self.square_mm <= MAX_SQUARE_MM:
            raise ValueError(f"board square size {self.square_mm:g} mm: must be positive and at most "
                             f"{MAX_SQUARE_MM:g}, e.g. {DEFAULT_SQUARE_MM:g}")
        if self.kind == "charuco":
            available = _dictionary().bytesList.shape[0]
            if self.marker_count > available:
                raise ValueError(
                    f"ChArUco board {self.cols}x{self.rows} needs {self.marker_count} markers, one per white "
                    f"square, but {CHARUCO_DICTIONARY} has {available}; use fewer corners, e.g. charuco:9x6")
        squares_mm = ((self.cols + 1) * self.square_mm, (self.rows + 1) * self.square_mm)
        if self.sheet_mm is None:
            default = (self.cols, self.rows, self.square_mm) == (*DEFAULT_INNER_CORNERS, DEFAULT_SQUARE_MM)
            sheet = PAPER_MM[DEFAULT_PAPER] if default else tuple(s + 2 * self.square_mm for s in squares_mm)
            object.__setattr__(self, "sheet_mm", tuple(float(v) for v in sheet))
        if self.sheet_mm[0] < squares_mm[0] or self.sheet_mm[1] < squares_mm[1]:
            raise ValueError(
                f"board {self.cols}x{self.rows} with {self.square_mm:g} mm squares needs "
                f"{squares_mm[0]:g} x {squares_mm[1]:g} mm, more than the {self.sheet_mm[0]:g} x "
                f"{self.sheet_mm[1]:g} mm sheet; use smaller squares or larger paper"
            )

    @property
    def square_m(self) -> float:
        return self.square_mm / 1000.0

    @property
    def size_m(self) -> tuple[float, float]:
        """The sheet's width and height (x, y), meters."""
        return self.sheet_mm[0] / 1000.0, self.sheet_mm[1] / 1000.0

    @property
    def corner_count(self) -> int:
        return self.cols * self.rows

    @property
    def marker_count(self) -> int:
        """ChArUco markers: one per white square (the top-left square is black)."""
        return (self.cols + 1) * (self.rows + 1) // 2

    @property
    def spec(self) -> str:
        """The board as the ``--board`` flag writes it: ``7x5`` or ``charuco:7x5``."""
        size = f"{self.cols}x{self.rows}"
        return size if self.kind == "chessboard" else f"{self.kind}:{size}"

    def describe(self) -> str:
        """``"7x5 checkerboard"`` or ``"7x5 ChArUco board (DICT_4X4_50)"``, for messages."""
        if self.kind == "chessboard":
            return f"{self.cols}x{self.rows} checkerboard"
        return f"{self.cols}x{self.rows} ChArUco board ({CHARUCO_DICTIONARY})"

    def corners_m(self) -> np.ndarray:
        """Inner corners in the board frame, (cols * rows, 3) float64, row by row."""
        i, j = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        x = (i.ravel() - (self.cols - 1) / 2) * self.square_m
        y = (j.ravel() - (self.rows - 1) / 2) * self.square_m
        return np.column_stack([x, y, np.zeros_like(x)])

    def corner_ids(self, charuco_ids) -> np.ndarray:
        """Board corner numbers ``k`` (n,) int64 of OpenCV's ChArUco corner ids (n,), which
        count printed rows from the top of the page."""
        c = np.asarray(charuco_ids, dtype=np.int64).ravel()
        return (self.rows - 1 - c // self.cols) * self.cols + c % self.cols

    def outline_m(self) -> np.ndarray:
        """The sheet's four corners in the board frame, (4, 3), counter-clockwise."""
        w, h = self.size_m
        return np.array([[-w / 2, -h / 2, 0], [w / 2, -h / 2, 0],
                         [w / 2, h / 2, 0], [-w / 2, h / 2, 0]])

    def markers(self) -> list[tuple[int, int, int, np.ndarray]]:
        """The ChArUco markers as printed: ``(marker id, square column, square row from the
        top of the page, bits)`` with ``bits`` (6, 6) bool, True black, row 0 the marker's
        top; empty for a checkerboard. The marker fills the middle 6/8 of its square."""
        if self.kind != "charuco":
            return []
        import cv2

        out = []
        white = [(i, j) for j in range(self.rows + 1) for i in range(self.cols + 1) if (i + j) % 2 == 1]
        for marker_id, (i, j) in zip(charuco_board(self.cols, self.rows).getIds().ravel(), white):
            bits = cv2.aruco.generateImageMarker(_dictionary(), int(marker_id), CHARUCO_MARKER_BITS, borderBits=1)
            out.append((int(marker_id), i, j, bits == 0))
        return out

    def printed_image(self, px_per_square: int = 32) -> np.ndarray:
        """The squares (and markers) as printed, without the paper margin: (h, w) uint8,
        row 0 the top of the page, the top-left square black.

        Marker bits (1/8 of a square) are exact when ``px_per_square`` is a multiple of 8,
        otherwise their edges are rounded to whole pixels; square edges are always exact."""
        a = np.arange(self.cols + 1)
        b = np.arange(self.rows + 1)
        squares = ((a[None, :] + b[:, None]) % 2).astype(np.uint8) * 255
        page = np.kron(squares, np.ones((px_per_square, px_per_square), np.uint8))
        if self.kind == "charuco":
            # Pixel k of a square lies in bit floor(k * 8 / px) of its 8 bit widths.
            bit = (np.arange(px_per_square) * CHARUCO_BITS_PER_SQUARE) // px_per_square
            margin = (CHARUCO_BITS_PER_SQUARE - CHARUCO_MARKER_BITS) // 2
            inside = (bit >= margin) & (bit < margin + CHARUCO_MARKER_BITS)
            cell = np.clip(bit - margin, 0, CHARUCO_MARKER_BITS - 1)
            for _, i, j, bits in self.markers():
                square = np.where(bits[cell[:, None], cell[None, :]], 0, 255).astype(np.uint8)
                square[~(inside[:, None] & inside[None, :])] = 255
                page[j * px_per_square:(j + 1) * px_per_square, i * px_per_square:(i + 1) * px_per_square] = square
        return page

    def image(self, px_per_square: int = 32) -> np.ndarray:
        """The sheet as a grayscale image in board coordinates, (h, w) uint8; row 0 is
        board -y (the texture the synthetic photographer lays on the floor).

        For a ChArUco board this is :meth:`printed_image` upside down (row order reversed),
        so that seen from above the markers read as printed. The plain checkerboard keeps
        the array Stager has always rendered, top-left square black: seen from above it
        is the print mirrored, which for a checkerboard at most swaps the colors, something
        no detector tells apart, and earlier synthetic photos stay the same.

        Square edges fall on pixel edges and the margins are equal on opposite sides, so a
        texture made of it keeps the corners exact; the sheet may come out up to half a
        pixel per side smaller or larger than ``size_m``.
        """
        pattern = self.printed_image(px_per_square)
        if self.kind == "charuco":
            pattern = pattern[::-1]
        px_per_mm = px_per_square / self.square_mm
        pad_x = int(round((self.sheet_mm[0] / 2 - (self.cols + 1) * self.square_mm / 2) * px_per_mm))
        pad_y = int(round((self.sheet_mm[1] / 2 - (self.rows + 1) * self.square_mm / 2) * px_per_mm))
        return np.pad(pattern, ((pad_y, pad_y), (pad_x, pad_x)), constant_values=255)


class BoardSpec(NamedTuple):
    """A ``--board`` value: inner corners per row and per column, and the board's kind."""

    cols: int
    rows: int
    kind: str = "chessboard"


DEFAULT_BOARD = BoardSpec(*DEFAULT_INNER_CORNERS)
_KIND_NAMES = {"chessboard": "chessboard", "checkerboard": "chessboard", "charuco": "charuco"}


def parse_board(text: str) -> BoardSpec:
    """``"7x5"`` -> ``BoardSpec(7, 5, "chessboard")``, ``"charuco:7x5"`` ->
    ``BoardSpec(7, 5, "charuco")``: inner corners per row and per column.

    Raises
    ------
    ValueError
        Text that is not such a board; the message says how to write one.
    """
    match = re.fullmatch(r"\s*(?:([A-Za-z]+)\s*:\s*)?(\d+)\s*[xX]\s*(\d+)\s*", text)
    counting = ("it counts inner corners, where four squares meet, not squares: "
                "a board of 8 x 6 squares is --board 7x5")
    if match is None:
        raise ValueError(
            f"{text!r} is not COLSxROWS like 7x5 (a checkerboard) or charuco:7x5 (a ChArUco board); {counting}")
    kind = _KIND_NAMES.get((match[1] or "chessboard").lower())
    if kind is None:
        raise ValueError(
            f"{text!r}: unknown board kind {match[1]!r}; write COLSxROWS for a checkerboard or "
            f"charuco:COLSxROWS for a ChArUco board ({', '.join(BOARD_KINDS)})")
    if max(len(match[2]), len(match[3])) > 6:
        raise ValueError(f"{_short(match[2])}x{_short(match[3])}: at most {MAX_INNER_CORNERS} inner corners a "
                         f"side; {counting}")
    cols, rows = int(match[2]), int(match[3])
    if cols < 2 or rows < 2:
        raise ValueError(f"{text!r}: needs at least 2x2 inner corners; {counting}")
    if cols > MAX_INNER_CORNERS or rows > MAX_INNER_CORNERS:
        raise ValueError(f"{_short(cols)}x{_short(rows)}: at most {MAX_INNER_CORNERS} inner corners a side; "
                         f"{counting}")
    return BoardSpec(cols, rows, kind)
