"""The printed checkerboard: its geometry in its own frame and its printable image.

Board frame: origin at the board's center, x along a row of inner corners (``cols`` of
them), y along a column (``rows``), z out of the printed face; meters. Inner corner
``k = j * cols + i`` lies at ``((i - (cols - 1) / 2) * s, (j - (rows - 1) / 2) * s, 0)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# CLI defaults: 7x5 inner corners (8 x 6 squares) of 50 mm with a one-square white margin
# prints at 50 x 40 cm, large enough to detect across a room in a phone photo.
DEFAULT_INNER_CORNERS = (7, 5)
DEFAULT_SQUARE_MM = 50.0


@dataclass(frozen=True)
class Board:
    """A checkerboard of ``cols`` x ``rows`` inner corners.

    Parameters
    ----------
    cols, rows : int
        Inner corners per row and per column (squares are one more each way).
    square_mm : float
        Side of one square, millimeters.
    margin_mm : float, optional
        White margin around the squares; defaults to one square.
    """

    cols: int = DEFAULT_INNER_CORNERS[0]
    rows: int = DEFAULT_INNER_CORNERS[1]
    square_mm: float = DEFAULT_SQUARE_MM
    margin_mm: float | None = None

    def __post_init__(self):
        if int(self.cols) < 2 or int(self.rows) < 2:
            raise ValueError(
                f"board {self.cols}x{self.rows}: needs at least 2x2 inner corners "
                "(count the corners where four squares meet, not the squares)"
            )
        if not self.square_mm > 0:
            raise ValueError(f"board square size {self.square_mm} mm: must be positive, e.g. 50")
        if self.margin_mm is None:
            object.__setattr__(self, "margin_mm", float(self.square_mm))
        if self.margin_mm < 0:
            raise ValueError(f"board margin {self.margin_mm} mm: must be zero or positive")

    @property
    def square_m(self) -> float:
        return self.square_mm / 1000.0

    @property
    def size_m(self) -> tuple[float, float]:
        """Printed sheet width and height (x, y), margin included, meters."""
        margin_m = self.margin_mm / 1000.0
        return ((self.cols + 1) * self.square_m + 2 * margin_m,
                (self.rows + 1) * self.square_m + 2 * margin_m)

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
        """The printable sheet as a grayscale image, (h, w) uint8; row 0 is board -y.

        Square edges fall on pixel edges, so a texture made of it keeps the corners exact.
        """
        margin_px = int(round(self.margin_mm / self.square_mm * px_per_square))
        a = np.arange(self.cols + 1)
        b = np.arange(self.rows + 1)
        squares = ((a[None, :] + b[:, None]) % 2).astype(np.uint8) * 255
        pattern = np.kron(squares, np.ones((px_per_square, px_per_square), np.uint8))
        return np.pad(pattern, margin_px, constant_values=255)
