"""A picture of the floor found, drawn over its photo: the mask tinted, the polygon's
edges coloured by what bounds them, the user's clicks and doors, and a plan of the
floor in meters beside it."""
from __future__ import annotations

import cv2
import numpy as np
from PIL import Image, ImageDraw

from ..floor.polygon import FloorPolygon
from .fonts import overlay_font
from .settings import DRAW


def floor_overlay(image: np.ndarray, mask: np.ndarray, polygon: FloorPolygon | None = None,
                  calibration=None, disputed: np.ndarray | None = None, clicks=None,
                  doubt_px: tuple[int, int] | None = None, doors_px=None, windows_px=()) -> np.ndarray:
    """The photo with the floor tinted, its outline, and a plan of the polygon.

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        RGB photo. Not modified.
    mask : (rows, cols) bool
    polygon, calibration : optional
        When given, the straightened polygon is drawn back onto the photo (edges coloured
        by kind: yellow boundary, blue photo edge, grey far) and a top-down plan with a
        1 m grid, the board, the camera (red) and the area is set beside the photo.
    disputed : (r, c) bool, optional
        Where the floor is in doubt (``Segmentation.disputed``, any size of the photo's
        shape): hatched in magenta, so the eye goes where a correction may be needed.
    clicks : (n, 3), optional
        The user's corrections (x, y px, 1 floor or 0 not floor): a green dot for floor,
        a red one with a white cross for not floor.
    doubt_px : (x, y), optional
        The patch in doubt to look at first (``Segmentation.doubt_px``): ringed in magenta.
    doors_px : (n, 4), optional
        Doors the user marked to keep clear (x1, y1, x2, y2: the feet of each door's two
        sides): a blue bar between the feet.
    windows_px : sequence of (4, 2), optional
        Windows found in the photo: the sill's two ends, then the top's, px; outlined.

    Returns
    -------
    (rows, cols, 3) uint8, or (rows, cols + rows, 3) with the plan beside it.
    """
    settings = DRAW.floor
    out = np.asarray(image, dtype=np.uint8).copy()
    mask = np.asarray(mask, dtype=bool)
    # Whole-image uint8 passes: floats per floor pixel would take gigabytes on a large photo.
    tinted = cv2.addWeighted(out, 0.55, np.broadcast_to(np.uint8(settings.tint), out.shape).copy(), 0.45, 0.0)
    np.copyto(out, tinted, where=mask[..., None])
    del tinted
    rows, cols = mask.shape
    thick = max(2, round(max(rows, cols) / settings.px_per_line_width))
    edge = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
    out[edge] = (20, 120, 40)
    if disputed is not None:
        doubt = cv2.resize(np.asarray(disputed, np.uint8) * np.uint8(255), (cols, rows),
                           interpolation=cv2.INTER_LINEAR) > 127
        y, x = np.nonzero(doubt)
        hatch = (x + y) // (2 * thick) % 3 == 0
        out[y[hatch], x[hatch]] = settings.disputed_color
    if polygon is not None and calibration is not None:
        n = len(polygon.polygon_m)
        for i in range(n):
            a, b = polygon.polygon_m[i], polygon.polygon_m[(i + 1) % n]
            pts = calibration.pixels_from_floor(np.linspace(a, b, 24)).round().astype(np.int32)
            cv2.polylines(out, [pts], False, settings.edge_colors[polygon.edge_kind[i]], thick, cv2.LINE_AA)
    radius = 4 * thick
    if doubt_px is not None:
        center = (int(doubt_px[0]), int(doubt_px[1]))
        cv2.circle(out, center, 3 * radius, (255, 255, 255), 3 * thick, cv2.LINE_AA)
        cv2.circle(out, center, 3 * radius, settings.disputed_color, thick, cv2.LINE_AA)
    for corners in windows_px:
        outline = np.asarray(corners, np.float64)[[0, 1, 3, 2]].round().astype(np.int32)
        cv2.polylines(out, [outline], True, (255, 255, 255), 3 * thick, cv2.LINE_AA)
        cv2.polylines(out, [outline], True, settings.window_color, thick, cv2.LINE_AA)
    # The user's clicks and doors on top of everything: they are what the user looks for.
    for x1, y1, x2, y2 in np.asarray(doors_px if doors_px is not None else np.zeros((0, 4)), np.float64).reshape(-1, 4):
        feet = (int(round(x1)), int(round(y1))), (int(round(x2)), int(round(y2)))
        cv2.line(out, *feet, (255, 255, 255), 3 * thick, cv2.LINE_AA)
        cv2.line(out, *feet, settings.door_color, thick, cv2.LINE_AA)
        for foot in feet:
            cv2.circle(out, foot, radius // 2 + thick, (255, 255, 255), -1, cv2.LINE_AA)
            cv2.circle(out, foot, radius // 2, settings.door_color, -1, cv2.LINE_AA)
    for x, y, is_floor in np.asarray(clicks if clicks is not None else np.zeros((0, 3)), np.float64).reshape(-1, 3):
        center = (int(round(x)), int(round(y)))
        cv2.circle(out, center, radius + thick, (255, 255, 255), -1, cv2.LINE_AA)
        cv2.circle(out, center, radius, settings.click_colors[int(bool(is_floor))], -1, cv2.LINE_AA)
        if not is_floor:
            d = round(0.6 * radius)
            for sign in (1, -1):
                cv2.line(out, (center[0] - d, center[1] - sign * d), (center[0] + d, center[1] + sign * d),
                         (255, 255, 255), thick, cv2.LINE_AA)
    if polygon is None or calibration is None:
        return out
    return np.hstack([out, _plan(rows, polygon, calibration)])


def _plan(side: int, polygon: FloorPolygon, calibration) -> np.ndarray:
    """Top-down plan, turned so the camera looks up the panel, as the photo does."""
    band = side // 10  # room for the captions above and below the plan
    world_from_camera = np.linalg.inv(calibration.camera_from_floor)
    cam = world_from_camera[:2, 3]
    forward = world_from_camera[:2, 2]
    forward = forward / max(np.linalg.norm(forward), 1e-9)
    # Rows of R are the panel's right and up directions in floor coordinates.
    R = np.array([[forward[1], -forward[0]], forward])
    pts = np.vstack([polygon.polygon_m, cam[None]]) @ R.T
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    px_per_m = (side - 2 * band) / max(float((hi - lo).max()), 1.0)
    center = (lo + hi) / 2

    def to_px(p):
        q = (np.asarray(p, dtype=np.float64).reshape(-1, 2) @ R.T - center) * px_per_m
        return np.column_stack([side / 2 + q[:, 0], side / 2 - q[:, 1]]).round().astype(np.int32)

    panel = np.full((side, side, 3), 250, np.uint8)
    reach = np.abs(np.vstack([polygon.polygon_m, cam[None]])).max() + side / px_per_m
    for g in np.arange(-np.ceil(reach), np.ceil(reach) + 1):
        for a, b in (((g, -reach), (g, reach)), ((-reach, g), (reach, g))):
            p, q = to_px([a, b])
            cv2.line(panel, tuple(map(int, p)), tuple(map(int, q)), (225, 225, 225), 1)
    poly_px = to_px(polygon.polygon_m)
    cv2.fillPoly(panel, [poly_px], (200, 240, 205))
    weight = max(1, side // 400)
    for i in range(len(poly_px)):
        cv2.line(panel, tuple(map(int, poly_px[i])), tuple(map(int, poly_px[(i + 1) % len(poly_px)])),
                 tuple(int(c * 0.8) for c in DRAW.floor.edge_colors[polygon.edge_kind[i]]), 1 + weight, cv2.LINE_AA)
    cv2.fillPoly(panel, [to_px(calibration.board.outline_m()[:, :2])], (60, 60, 60))
    c = to_px(cam)[0]
    cv2.circle(panel, (int(c[0]), int(c[1])), 3 + 2 * weight, (200, 30, 30), -1, cv2.LINE_AA)
    cv2.rectangle(panel, (0, 0), (side - 1, side - 1), (80, 80, 80), 1)
    canvas = Image.fromarray(panel)
    draw = ImageDraw.Draw(canvas)
    draw.text((band // 3, band // 3), "plan (camera red, looking up), grid 1 m",
              font=overlay_font(max(10, round(band * 0.3))), fill=(90, 90, 90))
    draw.text((band // 3, side - band // 3), f"{polygon.area_m2:.1f} m\u00b2 visible floor",
              font=overlay_font(max(12, round(band * 0.45))), fill=(30, 30, 30), anchor="ls")
    return np.asarray(canvas).copy()
