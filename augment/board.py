"""The printed checkerboard: its geometry in its own frame and its printable image.

Board frame: origin at the center of the squares, x along a row of inner corners
(``cols`` of them), y along a column (``rows``), z out of the printed face; meters. Inner
corner ``k = j * cols + i`` lies at ``((i - (cols - 1) / 2) * s, (j - (rows - 1) / 2) * s, 0)``.

Defaults. The standard board has 7x5 inner corners (8 x 6 squares). With 45 mm squares it
fills an A3 sheet (360 x 270 mm of squares on 420 x 297 mm paper, margins 30 and
13.5 mm); 50 mm squares would need 300 mm across the sheet's 297 mm. On A4 the squares
are 30 mm. The synthetic photographer and every ``stage`` command share these defaults.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PAPER_MM = {"A4": (297.0, 210.0), "A3": (420.0, 297.0)}
DEFAULT_INNER_CORNERS = (7, 5)
DEFAULT_PAPER = "A3"
DEFAULT_SQUARE_MM = {"A3": 45.0, "A4": 30.0}[DEFAULT_PAPER]


@dataclass(frozen=True)
class Board:
    """A checkerboard of ``cols`` x ``rows`` inner corners printed on a sheet.

    Parameters
    ----------
    cols, rows : int
        Inner corners per row and per column (squares are one more each way).
    square_mm : float
        Side of one square, millimeters.
    sheet_mm : (width, height), optional
        The paper, landscape, squares centered on it. Default: the A3 sheet for the
        default board, otherwise the squares with a one-square white margin.
    """

    cols: int = DEFAULT_INNER_CORNERS[0]
    rows: int = DEFAULT_INNER_CORNERS[1]
    square_mm: float = DEFAULT_SQUARE_MM
    sheet_mm: tuple[float, float] | None = None

    def __post_init__(self):
        if int(self.cols) < 2 or int(self.rows) < 2:
            raise ValueError(
                f"board {self.cols}x{self.rows}: needs at least 2x2 inner corners "
                "(count the corners where four squares meet, not the squares)"
            )
        if not self.square_mm > 0:
            raise ValueError(f"board square size {self.square_mm} mm: must be positive, e.g. {DEFAULT_SQUARE_MM:g}")
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

    def corners_m(self) -> np.ndarray:
        """Inner corners in the board frame, (cols * rows, 3) float64, row by row."""
        i, j = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        x = (i.ravel() - (self.cols - 1) / 2) * self.square_m
        y = (j.ravel() - (self.rows - 1) / 2) * self.square_m
        return np.column_stack([x, y, np.zeros_like(x)])

    def outline_m(self) -> np.ndarray:
        """The sheet's four corners in the board frame, (4, 3), counter-clockwise."""
        w, h = self.size_m
        return np.array([[-w / 2, -h / 2, 0], [w / 2, -h / 2, 0],
                         [w / 2, h / 2, 0], [-w / 2, h / 2, 0]])

    def image(self, px_per_square: int = 32) -> np.ndarray:
        """The sheet as a grayscale image, (h, w) uint8; row 0 is board -y.

        Square edges fall on pixel edges and the margins are equal on opposite sides, so a
        texture made of it keeps the corners exact; the sheet may come out up to half a
        pixel per side smaller or larger than ``size_m``.
        """
        a = np.arange(self.cols + 1)
        b = np.arange(self.rows + 1)
        squares = ((a[None, :] + b[:, None]) % 2).astype(np.uint8) * 255
        pattern = np.kron(squares, np.ones((px_per_square, px_per_square), np.uint8))
        px_per_mm = px_per_square / self.square_mm
        pad_x = int(round((self.sheet_mm[0] / 2 - (self.cols + 1) * self.square_mm / 2) * px_per_mm))
        pad_y = int(round((self.sheet_mm[1] / 2 - (self.rows + 1) * self.square_mm / 2) * px_per_mm))
        return np.pad(pattern, ((pad_y, pad_y), (pad_x, pad_x)), constant_values=255)
