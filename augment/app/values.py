"""The checks of values that both ``stage`` flags and a batch manifest's fields take."""
from __future__ import annotations

import argparse

from ..camera.board import DEFAULT_SQUARE_MM, MIN_SQUARE_MM


def _number(text: str) -> float:
    """``text`` as a float; NaN (which no range admits) when it is none."""
    try:
        return float(text)
    except ValueError:
        return float("nan")


def square_mm(text: str) -> float:
    value = _number(text)
    if not MIN_SQUARE_MM <= value < 1000:
        # 1e-300 mm ran on, to "the board is seen almost face-on".
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected the side of one printed square in millimeters, {MIN_SQUARE_MM:g} to 1000, e.g. "
            f"{DEFAULT_SQUARE_MM:g}")
    return value


def whole(text: str, lo: int, hi: int, example: str = "") -> int:
    try:
        value = int(text)
    except ValueError:
        value = lo - 1
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number from {lo} to {hi}{example}")
    return value


def count(text: str) -> int:
    return whole(text, 1, 100)


# Wall heights a user may give: a low attic room to a loft's double height.
HEIGHT_RANGE_M = (1.8, 6.0)


def height_m(text: str) -> float:
    value = _number(text)
    lo, hi = HEIGHT_RANGE_M
    if not lo <= value <= hi:
        raise argparse.ArgumentTypeError(f"{text!r}: expected the wall height in meters, {lo:g} to {hi:g}, e.g. 2.6")
    return value
