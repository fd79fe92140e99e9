"""The photo turned so that the room stands upright in it, and back: the one place the
floor stage turns anything.

A photo whose orientation was lost, or taken with the phone held sideways, shows the
room turned by a quarter or a half (``Calibration.upright_turns``). The floor model
learned rooms upright and the skirting trim reads each column up from the floor to the
wall, so the floor is found on the photo turned upright, and what was found is turned
back to the photo's pixels.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera.calibration import Calibration, turn_points


@dataclass(frozen=True)
class Upright:
    """The turn from a photo to its upright view.

    Attributes
    ----------
    turns : int
        Quarter turns, as ``np.rot90(photo, turns)``; 0 when the room stands upright, or
        when no calibration says which way is up.
    size_px : (width, height)
        The photo's size.
    calibration : Calibration or None
        The calibration of the upright view.
    """

    turns: int
    size_px: tuple[int, int]
    calibration: Calibration | None

    @classmethod
    def of(cls, calibration: Calibration | None, size_px: tuple[int, int]) -> "Upright":
        turns = 0 if calibration is None else calibration.upright_turns
        return cls(turns, (int(size_px[0]), int(size_px[1])),
                   None if calibration is None else calibration.turned(turns))

    @property
    def upright_size_px(self) -> tuple[int, int]:
        w, h = self.size_px
        return (h, w) if self.turns % 2 else (w, h)

    def image(self, array: np.ndarray | None) -> np.ndarray | None:
        """An array of the photo (rows, cols, ...), or of a resized copy, as the upright
        view shows it."""
        if array is None or not self.turns:
            return array
        return np.ascontiguousarray(np.rot90(array, self.turns))

    def back(self, array: np.ndarray | None) -> np.ndarray | None:
        """An array of the upright view as the photo shows it."""
        if array is None or not self.turns:
            return array
        return np.ascontiguousarray(np.rot90(array, -self.turns))

    def points(self, points: np.ndarray) -> np.ndarray:
        """Photo pixels (n, 2 + k): their x, y where the upright view shows them, the
        other columns as they are."""
        pts = np.array(points, dtype=np.float64, ndmin=2)
        if self.turns and len(pts):
            pts[:, :2] = turn_points(pts[:, :2], self.turns, self.size_px)
        return pts

    def point_back(self, point_px: tuple[int, int] | None) -> tuple[int, int] | None:
        """A whole pixel ``(x, y)`` of the upright view, in the photo."""
        if point_px is None or not self.turns:
            return point_px
        x, y = turn_points([point_px], -self.turns, self.upright_size_px)[0]
        return int(round(x)), int(round(y))
