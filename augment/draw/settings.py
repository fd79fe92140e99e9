"""The draw stage's styles, one section per picture: colours (RGB), line widths, spans.

Code reads them at call time (``DRAW.floor.door_color`` inside a function), so a caller,
or a test with ``monkeypatch.setattr(DRAW.sheet, "gap_px", 4)``, can change one.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class CalibrationOverlaySettings:
    """The calibration overlay (:mod:`augment.draw.calibration`)."""

    grid_step_m: float = 1.0  # the floor grid's spacing: meters read at a glance
    grid_half_span_m: float = 6.0  # the grid reaches this far from the board each way: a room's size
    grid_sample_m: float = 0.01  # grid lines are sampled this densely before projection (the lens bends them)
    axis_m: float = 0.5  # length of each floor axis
    min_depth_m: float = 0.05  # floor points nearer the camera plane than this are not drawn
    inset_below_spacing_px: int = 14  # boards with corners closer than this get a magnified inset
    inset_width: float = 0.3  # the inset's width, of the image's width
    style_long_px: float = 1280.0  # the widths below are for a photo this long; they scale with the photo
    grid_width_px: float = 1.5  # grid lines
    axis_width_px: float = 4.0  # floor axes
    thin_width_px: float = 1.0  # the squares' outline, the horizon, the corners' path
    halo_width_px: float = 1.5  # the dark halo each side of a line, so it shows on any floor
    dash_px: float = 18.0  # the horizon's dashes
    dash_gap_px: float = 11.0  # ... and the gaps between them
    grid_rgb: tuple[int, int, int] = (255, 255, 255)  # the floor grid
    grid_fade_m: tuple[float, float] = (3.0, 9.0)  # the grid fades between these floor distances from the camera
    grid_opacity: tuple[float, float] = (0.65, 0.22)  # ... from this opacity near to this far: the far grid is dense
    axis_rgb: dict = field(default_factory=lambda: {  # x red, y green, z blue, as every 3-D tool draws them
        "x": (235, 45, 45), "y": (40, 205, 60), "z": (50, 110, 255)})
    horizon_rgb: tuple[int, int, int] = (255, 175, 0)  # the floor's vanishing line
    squares_rgb: tuple[int, int, int] = (0, 225, 255)  # the printed squares' outline
    first_corner_rgb: tuple[int, int, int] = (255, 40, 220)  # where the board frame starts
    caption_box_rgba: tuple[int, int, int, int] = (0, 0, 0, 160)  # behind the caption: readable on any photo
    text_rgb: tuple[int, int, int] = (255, 255, 255)  # captions and labels


@dataclass
class FloorOverlaySettings:
    """The floor overlay (:mod:`augment.draw.floor`)."""

    px_per_line_width: int = 500  # a pixel of line width per this many pixels of the photo's longer side (2 at least)
    edge_colors: dict = field(default_factory=lambda: {  # the polygon's edges by kind: wall, photo's edge, distance
        "boundary": (255, 210, 0), "image": (0, 200, 255), "far": (170, 170, 170)})
    tint: np.ndarray = field(default_factory=lambda: np.array([40, 220, 90], np.float32))  # (3,) the floor's green tint
    disputed_color: tuple[int, int, int] = (255, 40, 200)  # magenta: apart from the tint and every edge colour
    click_colors: dict = field(default_factory=lambda: {  # the user's "not floor" (0) and "floor" (1) marks
        0: (230, 30, 30), 1: (0, 150, 40)})
    door_color: tuple[int, int, int] = (30, 90, 230)  # doors the user marked, as the web page marks them
    window_color: tuple[int, int, int] = (130, 60, 255)  # windows found in the photo: violet, apart from the rest


@dataclass
class HeightOverlaySettings:
    """The wall-height overlay (:mod:`augment.draw.height`)."""

    px_per_line_width: int = 320  # a pixel of line width per this many pixels of the photo's longer side (2 at least)
    edge_rgb: tuple[int, int, int] = (60, 220, 90)  # inlier vertical edges
    ceiling_rgb: tuple[int, int, int] = (40, 200, 255)  # inlier wall--ceiling lines (from their base to their top)
    other_rgb: tuple[int, int, int] = (170, 170, 170)  # measured but not used
    bound_rgb: tuple[int, int, int] = (255, 190, 40)  # the edge whose top bounds the walls from below (a door's)
    fallback_rgb: tuple[int, int, int] = (255, 120, 60)  # caption accent when the fallback was used
    caption_box_rgba: tuple[int, int, int, int] = (0, 0, 0, 170)  # behind the caption: readable on any photo
    text_rgb: tuple[int, int, int] = (255, 255, 255)  # captions and labels


@dataclass
class SheetSettings:
    """The contact sheet of the staged photos (:mod:`augment.draw.sheet`)."""

    tile_px: int = 640  # width of one photo on the sheet
    gap_px: int = 8  # white space between and around the photos


@dataclass
class DrawSettings:
    """Every style of the draw stage, by picture."""

    calibration: CalibrationOverlaySettings = field(default_factory=CalibrationOverlaySettings)
    floor: FloorOverlaySettings = field(default_factory=FloorOverlaySettings)
    height: HeightOverlaySettings = field(default_factory=HeightOverlaySettings)
    sheet: SheetSettings = field(default_factory=SheetSettings)
    # The calibration and height overlays are for checking by eye: drawn over a larger photo,
    # they are shrunk to this on its long side (at 12 MP, 10 MB of PNG and 0.5 s to encode).
    overlay_long_px: int = 2048


DRAW = DrawSettings()
