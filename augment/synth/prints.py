"""Boards as users print them, pasted onto floors: the test set of the board's erasure.

Real prints differ from the sheet Stager assumes: off-white or cream paper, a printer's
margin or none (the sheet trimmed to the squares), ``stage board``'s ruler and caption or
another pattern altogether (OpenCV's plain chessboard), lying half in a shadow, on carpet,
planks or tiles. :func:`pasted_board` draws such a print on a synthetic floor seen by a
camera, and the same floor without it (the truth), through the same light, blur, noise
and JPEG. The floor is a plane seen through one homography, so a photo takes tens of
milliseconds: hundreds of cases where the full photographer would make dozens.
:func:`paste_print` lays the same print on a real photo taken without one, where its
camera (:func:`level_camera`) would have seen it; :func:`paste_planned` at a plan as
``samples/real/rooms.json`` gives one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ..camera.board import Board
from ..photo.io import encode_image
from .textures import floor_texture

PAPERS = {"white": (0.94, 0.94, 0.93), "off-white": (0.90, 0.89, 0.85), "cream": (0.93, 0.88, 0.74)}
MARGINS = ("sheet", "none")  # the A3 sheet as printed, or trimmed to the squares
FLOORS = ("carpet", "wood", "tiles", "laminate", "concrete")
PATTERNS = ("stager", "charuco", "opencv")


@dataclass(frozen=True)
class PastedBoard:
    """One case: the photo with the print, the same without it, and how it was made.

    Attributes
    ----------
    photo, truth : (h, w, 3) uint8
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64
        Floor frame = the board's (origin at its centre, x along its rows, z up).
    board : Board
    floor_mask : (h, w) bool
        Where the photo shows the floor drawn (beyond it, a plain wall colour).
    sheet_px : (4, 2) float64
        The printed sheet's corners in the photo.
    case : dict
        ``paper``, ``margin``, ``marks``, ``pattern``, ``floor``, ``shadow``, ``blur_px``,
        ``noise``, ``jpeg``.
    """

    photo: np.ndarray
    truth: np.ndarray
    K: np.ndarray
    camera_from_floor: np.ndarray
    board: Board
    floor_mask: np.ndarray
    sheet_px: np.ndarray
    case: dict


def _camera(rng, size_px):
    """A phone held at chest height looking down at the floor, the board 1.6-2.6 m ahead."""
    w, h = size_px
    f = float(rng.uniform(0.75, 1.0)) * w
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])
    height = float(rng.uniform(1.2, 1.6))
    pitch = np.radians(rng.uniform(35, 55))  # below the horizontal
    ahead = height / np.tan(pitch) * float(rng.uniform(0.9, 1.1))
    yaw = float(rng.uniform(0, 2 * np.pi))  # the board's rotation under the camera
    eye = np.array([-ahead * np.cos(yaw), -ahead * np.sin(yaw), height])
    forward = np.array([np.cos(yaw) * np.cos(pitch), np.sin(yaw) * np.cos(pitch), -np.sin(pitch)])
    right = np.cross(forward, [0, 0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    R = np.stack([right, down, forward])
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, -R @ eye
    return K, pose


def _sheet(board: Board, margin: str, marks: bool, px_per_mm: float) -> np.ndarray:
    """The print as ink on paper, (h, w) float32 in [0, 1] (1 = paper), floor-frame rows
    (row 0 at board -y). With ``marks``: a 100 mm ruler under the squares and a line of
    caption above them, as ``stage board`` prints."""
    px_per_square = int(round(board.square_mm * px_per_mm))
    sheet = board.image(px_per_square) if margin == "sheet" else board.printed_image(px_per_square)
    if margin != "sheet" and board.kind == "charuco":
        sheet = sheet[::-1]
    sheet = sheet.astype(np.float32) / 255.0
    if marks and margin == "sheet":
        img = Image.fromarray((sheet * 255).astype(np.uint8))
        draw = ImageDraw.Draw(img)
        h, w = sheet.shape
        pad_y = (h - (board.rows + 1) * px_per_square) // 2
        x0 = (w - (board.cols + 1) * px_per_square) // 2
        y = h - pad_y // 2
        length = 100 * px_per_mm
        draw.line([(x0, y), (x0 + length, y)], fill=0, width=max(1, round(0.5 * px_per_mm)))
        for k in range(11):
            tick = (3 if k % 5 else 5) * px_per_mm
            x = x0 + k * length / 10
            draw.line([(x, y - tick), (x, y)], fill=0, width=max(1, round(0.3 * px_per_mm)))
        font = ImageFont.load_default(size=max(8, round(4 * px_per_mm)))
        draw.text((x0, pad_y // 2 - 2 * px_per_mm), f"stage furnish --board {board.cols}x{board.rows} "
                  f"--square {board.square_mm:g}   measure the ruler: 100 mm", fill=0, font=font)
        sheet = np.asarray(img, np.float32) / 255.0
    return sheet


def pasted_board(rng: np.random.Generator, size_px=(1280, 960), *, paper: str | None = None,
                 margin: str | None = None, marks: bool | None = None, pattern: str | None = None,
                 floor: str | None = None, shadow: bool | None = None) -> PastedBoard:
    """A print on a floor, photographed; every choice left None is drawn from ``rng``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The only randomness: the same state, the same case.
    size_px : (w, h)
    paper : str
        A key of :data:`PAPERS`.
    margin : str
        One of :data:`MARGINS`.
    marks : bool
        The ruler and caption in the margin (only with ``margin="sheet"``).
    pattern : str
        ``"stager"`` (``stage board``'s default chessboard on A3), ``"charuco"`` (its
        ChArUco board) or ``"opencv"`` (OpenCV's 9x6 chessboard, 25 mm squares).
    floor : str
        One of :data:`FLOORS`.
    shadow : bool
        A shadow's edge across the sheet (a piece of furniture or a window frame's).
    """
    pick = lambda value, options: value if value is not None else options[int(rng.integers(len(options)))]  # noqa: E731
    paper, margin, floor = pick(paper, list(PAPERS)), pick(margin, MARGINS), pick(floor, FLOORS)
    pattern = pick(pattern, PATTERNS)
    marks = bool(rng.random() < 0.5) if marks is None else marks
    shadow = bool(rng.random() < 0.5) if shadow is None else shadow
    marks = marks and margin == "sheet"
    board = {"stager": Board(), "charuco": Board(kind="charuco"), "opencv": Board(9, 6, square_mm=25.0)}[pattern]
    w, h = size_px
    K, pose = _camera(rng, size_px)

    # Each photo pixel (2x supersampled) traced to the floor: the floor plane's homography.
    texture, tile_m = floor_texture(floor, rng, 512)
    image_from_floor = K @ np.column_stack([pose[:3, 0], pose[:3, 1], pose[:3, 3]])
    S = np.array([[2.0, 0, 0.5], [0, 2.0, 0.5], [0, 0, 1]])  # photo pixel centres -> supersampled
    floor_from_big = np.linalg.inv(S @ image_from_floor)
    yy, xx = np.mgrid[0:2 * h, 0:2 * w].astype(np.float32)
    q = floor_from_big.astype(np.float32)
    z = q[2, 0] * xx + q[2, 1] * yy + q[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        X = (q[0, 0] * xx + q[0, 1] * yy + q[0, 2]) / z
        Y = (q[1, 0] * xx + q[1, 1] * yy + q[1, 2]) / z
    eye = -pose[:3, :3].T @ pose[:3, 3]
    seen = (z < 0) == (q[2, 2] < 0)  # rays that meet the floor in front of the camera ...
    seen &= np.hypot(X - eye[0], Y - eye[1]) < 8.0  # ... within 8 m (a wall stands beyond)
    X, Y = np.where(seen, X, 0.0).astype(np.float32), np.where(seen, Y, 0.0).astype(np.float32)
    scale = texture.shape[0] / tile_m
    linear_texture = (texture.astype(np.float32) / 255.0) ** 2.2  # light adds up in linear
    floor_rgb = cv2.remap(linear_texture, np.mod(X * np.float32(scale), texture.shape[1]),
                          np.mod(Y * np.float32(scale), texture.shape[0]), cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_WRAP)

    # The print, linear: paper colour times ink (ink reflects 6 % of what the paper does).
    px_per_mm = 2.0
    ink = _sheet(board, margin, marks, px_per_mm)
    sh, sw = ink.shape
    half = np.array([sw, sh]) / (2000.0 * px_per_mm)
    sheet_m = np.array([[-half[0], -half[1]], [half[0], -half[1]], [half[0], half[1]], [-half[0], half[1]]])
    col = ((X + half[0]) * 1000 * px_per_mm + 1.0).astype(np.float32)
    row = ((Y + half[1]) * 1000 * px_per_mm + 1.0).astype(np.float32)
    on_ink = cv2.remap(np.pad(ink, 1, constant_values=-1.0), col, row, cv2.INTER_LINEAR,
                       borderMode=cv2.BORDER_CONSTANT, borderValue=-1.0)
    paper_rgb = (np.asarray(PAPERS[paper], np.float32) * float(rng.uniform(0.95, 1.02))) ** 2.2
    cover = np.clip(on_ink + 1.0, 0.0, 1.0)[..., None]  # 0 off the sheet, 1 on it (the pad blends its edge)
    printed = (0.06 + 0.94 * np.clip(on_ink, 0.0, 1.0))[..., None] * paper_rgb
    board_rgb = cover * printed + (1 - cover) * floor_rgb

    # Light: a lamp's slow falloff, and maybe a shadow's soft edge across the sheet.
    lamp = rng.uniform(-2, 2, 2)
    light = 0.6 + 0.4 * np.exp(-((X - lamp[0]) ** 2 + (Y - lamp[1]) ** 2) / (2 * rng.uniform(1.5, 3.0) ** 2))
    if shadow:
        angle, offset = rng.uniform(0, np.pi), rng.uniform(-0.08, 0.08)
        d = np.cos(angle) * X + np.sin(angle) * Y - offset
        light *= 1.0 - rng.uniform(0.35, 0.55) / (1.0 + np.exp(d / rng.uniform(0.005, 0.02)))
    light = np.where(seen, light, 0.0).astype(np.float32)[..., None]
    wall = (np.array([200, 196, 190], np.float32) / 255.0) ** 2.2

    def photograph(view):
        linear = cv2.resize(view * light, (w, h), interpolation=cv2.INTER_AREA)
        linear += (1.0 - cv2.resize(seen.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA))[..., None] * wall
        return 255.0 * np.clip(linear, 0, 1) ** (1 / 2.2)

    floor_mask = cv2.resize(seen.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA) > 0.999
    blur = float(rng.uniform(0.5, 1.2))
    noise = float(rng.uniform(0.5, 4.0))
    quality = int(rng.integers(75, 96))
    grain = rng.standard_normal((h, w, 3)).astype(np.float32) * noise

    def camera(img):
        img = cv2.GaussianBlur(img, (0, 0), blur) + grain
        data = encode_image(np.clip(img + 0.5, 0, 255).astype(np.uint8), ".jpg", quality)
        return cv2.cvtColor(cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)

    photo, truth = camera(photograph(board_rgb)), camera(photograph(floor_rgb))
    corners = np.column_stack([sheet_m, np.zeros(4)])
    cam = corners @ pose[:3, :3].T + pose[:3, 3]
    sheet_px = (cam @ K.T)[:, :2] / (cam @ K.T)[:, 2:]
    case = {"paper": paper, "margin": margin, "marks": marks, "pattern": pattern, "floor": floor, "shadow": shadow,
            "blur_px": round(blur, 2), "noise": round(noise, 2), "jpeg": quality}
    return PastedBoard(photo, truth, K, pose, board, floor_mask, sheet_px, case)


# What an erased print may leave, against the floor that was there (levels of 255):
LIGHT_MAX = 4.0  # mean difference of the light on the sheet (blurred over a third of the sheet's size)
CONTRAST_RANGE = (0.6, 1.5)  # the floor's local contrast (7 px windows) on the sheet, as a share of the truth's
SEAM_MAX = 1.6  # edges along the sheet's outline, as a share of the truth's there
SPOT_LEVELS = 20.0  # a spot: this much brighter than its 7 px surround, half this than the floor's brightest


def erasure_scores(case: PastedBoard, erased: np.ndarray) -> dict:
    """How well the erased photo hides the print, against the floor that was under it.

    The fill copies floor from elsewhere, so it cannot match the truth pixel by pixel
    (a tile joint or a plank seam lands elsewhere); what is compared is what the eye
    catches: the light, the texture's contrast, an outline, bright specks.

    Returns
    -------
    dict
        ``light``: mean difference (levels) of erased and truth, both blurred over a third
        of the sheet's size, on the sheet; ``contrast``: mean local std (7 px windows) on
        the sheet, erased over truth; ``seam``: mean edge strength along the sheet's
        outline (2 px either side), erased over truth; ``spots``: specks of 3 px or more, on
        or within 6 px of the sheet, brighter by :data:`SPOT_LEVELS` than the median of
        their 7 px surround and by half that than the floor's brightest (99.9th percentile
        within half the sheet's size): paper left, as dots or a ring, not a light grout
        line copied; ``ok``: all four within their limits.
    """
    h, w = erased.shape[:2]
    sheet = np.zeros((h, w), np.uint8)
    cv2.fillConvexPoly(sheet, np.round(case.sheet_px * 16).astype(np.int32), 1, cv2.LINE_AA, 4)
    region = sheet > 0
    near = cv2.dilate(sheet, np.ones((13, 13), np.uint8)) > 0
    size_px = math.sqrt(region.sum())
    e, t = erased.astype(np.float32), case.truth.astype(np.float32)
    ge, gt = (cv2.cvtColor(a, cv2.COLOR_RGB2GRAY) for a in (e, t))
    sigma = max(2.0, size_px / 3)
    light = float(np.abs(cv2.GaussianBlur(e, (0, 0), sigma) - cv2.GaussianBlur(t, (0, 0), sigma)).mean(axis=2)[region]
                  .mean())

    def local_std(grey):
        mean = cv2.blur(grey, (7, 7))
        return np.sqrt(np.maximum(cv2.blur(grey * grey, (7, 7)) - mean * mean, 0))

    contrast = float(local_std(ge)[region].mean() / max(1e-6, local_std(gt)[region].mean()))
    outline = cv2.morphologyEx(sheet, cv2.MORPH_GRADIENT, np.ones((5, 5), np.uint8)) > 0

    def edges(grey):
        g = cv2.GaussianBlur(grey, (0, 0), 1.0)
        return np.hypot(cv2.Sobel(g, cv2.CV_32F, 1, 0), cv2.Sobel(g, cv2.CV_32F, 0, 1))

    seam = float(edges(ge)[outline].mean() / max(1e-6, edges(gt)[outline].mean()))

    speck = ge - cv2.medianBlur(np.clip(ge, 0, 255).astype(np.uint8), 7).astype(np.float32)
    around = (cv2.dilate(sheet, np.ones((2 * round(size_px / 2) + 1,) * 2, np.uint8)) > 0) & case.floor_mask
    floor_top = float(np.percentile(gt[around], 99.9))
    bright = (speck > SPOT_LEVELS) & (ge > floor_top + SPOT_LEVELS / 2) & near
    count, _, stats, _ = cv2.connectedComponentsWithStats(bright.astype(np.uint8))
    spots = int((stats[1:, cv2.CC_STAT_AREA] >= 3).sum())
    ok = (light <= LIGHT_MAX and CONTRAST_RANGE[0] <= contrast <= CONTRAST_RANGE[1] and seam <= SEAM_MAX
          and spots == 0)
    return {"light": light, "contrast": contrast, "seam": seam, "spots": spots, "ok": bool(ok)}


def level_camera(focal_px: float, size_px, pitch_rad: float, height_m: float, board_px, yaw_rad: float):
    """The pose of a board lying on the floor under pixel ``board_px``, seen by a camera
    ``height_m`` above the floor, tipped down ``pitch_rad`` from level, without roll: how a
    real photo taken without a board gets one where its own camera would have seen it.

    Parameters
    ----------
    focal_px : float
        The photo's focal length, pixels; its principal point is the centre.
    size_px : (w, h)
    pitch_rad, height_m : float
        The camera's tilt below the horizontal and height above the floor (from the
        photo's vanishing points and a door's height, say).
    board_px : (2,) float
        The board's centre in the photo, pixels; below the horizon.
    yaw_rad : float
        The board's rows turned this far from the camera's right, about the vertical.

    Returns
    -------
    K : (3, 3) float64
    camera_from_floor : (4, 4) float64
        Floor frame = the board's (origin at its centre, x along its rows, z up).
    """
    w, h = size_px
    K = np.array([[focal_px, 0, (w - 1) / 2], [0, focal_px, (h - 1) / 2], [0, 0, 1.0]])
    up = np.array([0.0, -np.cos(pitch_rad), -np.sin(pitch_rad)])  # camera frame: x right, y down, z ahead
    ray = np.linalg.solve(K, [board_px[0], board_px[1], 1.0])
    if up @ ray >= 0:
        raise ValueError(f"board_px {tuple(board_px)} is not below the horizon")
    centre = -height_m / (up @ ray) * ray
    ahead = np.array([0.0, 0.0, 1.0]) - up[2] * up
    ahead /= np.linalg.norm(ahead)
    x = np.cos(yaw_rad) * np.array([1.0, 0.0, 0.0]) + np.sin(yaw_rad) * ahead
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(up, x), up])
    pose[:3, 3] = centre
    return K, pose


def paste_print(photo: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray, *, board: Board | None = None,
                paper: str = "white", marks: bool = True, paper_over_floor: float = 3.0,
                seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``stage board``'s print laid on the floor of a real photo: the sheet seen through the
    photo's camera, lit by the floor's own light there, with the photo's blur and grain.

    The paper is matte: its brightness is ``paper_over_floor`` times the floor's around it
    (blurred over the sheet's size), the ratio of their albedos (about 3 on light wood, 6
    on dark), held below white.

    Parameters
    ----------
    photo : (h, w, 3) uint8
        RGB. Not modified.
    K, camera_from_floor : from :func:`level_camera`
    board : Board, optional
        Default: ``stage board``'s A3 chessboard.
    paper : str
        A key of :data:`PAPERS`.
    marks : bool
        The ruler and caption in the margin.
    paper_over_floor : float
        The paper's brightness over the floor's around it.
    seed : int
        The grain's.

    Returns
    -------
    image : (h, w, 3) uint8
        The photo with the print.
    sheet_px : (4, 2) float64
        The sheet's corners in the photo.
    """
    board = board or Board()
    h, w = photo.shape[:2]
    px_per_mm = 2.0
    ink = _sheet(board, "sheet", marks, px_per_mm)
    sh, sw = ink.shape
    floor_from_sheet = np.array([[1 / (1000 * px_per_mm), 0, -sw / (2000 * px_per_mm)],
                                 [0, 1 / (1000 * px_per_mm), -sh / (2000 * px_per_mm)], [0, 0, 1.0]])
    pose = camera_from_floor
    image_from_sheet = K @ np.column_stack([pose[:3, 0], pose[:3, 1], pose[:3, 3]]) @ floor_from_sheet
    corners = np.array([[0, 0], [sw, 0], [sw, sh], [0, sh]], np.float64)
    sheet_px = cv2.perspectiveTransform(corners.reshape(-1, 1, 2), image_from_sheet).reshape(-1, 2)
    # Drawn at twice the photo's size and averaged down (the squares' edges antialiased),
    # the sheet blurred first by half the sheet pixels that fall in one drawn pixel.
    size_px = float(np.sqrt(cv2.contourArea(sheet_px.astype(np.float32))))
    per_px = np.sqrt(sw * sh) / max(2 * size_px, 1.0)
    src = cv2.GaussianBlur(ink, (0, 0), 0.5 * per_px) if per_px > 1 else ink
    big_from_padded = (np.array([[2.0, 0, 0.5], [0, 2.0, 0.5], [0, 0, 1]]) @ image_from_sheet
                       @ np.array([[1.0, 0, -1], [0, 1, -1], [0, 0, 1]]))
    on_ink = cv2.warpPerspective(np.pad(src, 1, constant_values=-1.0), big_from_padded, (2 * w, 2 * h),
                                 flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=-1.0)
    cover = cv2.resize(np.clip(on_ink + 1.0, 0.0, 1.0), (w, h), interpolation=cv2.INTER_AREA)[..., None]
    reflect = cv2.resize(0.06 + 0.94 * np.clip(on_ink, 0.0, 1.0), (w, h), interpolation=cv2.INTER_AREA)[..., None]

    linear = (photo.astype(np.float32) / 255.0) ** 2.2
    around = cv2.GaussianBlur(linear, (0, 0), max(2.0, size_px / 2))
    light = around.mean(axis=2, keepdims=True) * paper_over_floor
    paper_rgb = np.asarray(PAPERS[paper], np.float32) ** 2.2
    printed = np.minimum(reflect * paper_rgb * light, 0.93)
    out = cover * printed + (1 - cover) * linear
    out = 255.0 * np.clip(out, 0, 1) ** (1 / 2.2)
    grain = np.random.default_rng(seed).standard_normal(out.shape).astype(np.float32) * 1.5
    soft = cv2.GaussianBlur(out, (0, 0), 0.6) + grain
    out = cover * soft + (1 - cover) * photo.astype(np.float32)
    return np.clip(out + 0.5, 0, 255).astype(np.uint8), sheet_px


def paste_planned(photo: np.ndarray, plan: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`paste_print` where ``plan`` (an entry of ``samples/real/rooms.json``) puts it:
    its ``focal_px``, ``pitch_deg``, ``height_m``, ``board_px``, ``board_yaw_deg`` and
    ``paper_over_floor``. Returns the photo with the print, ``K``, ``camera_from_floor``
    and the sheet's corners in the photo (4, 2)."""
    K, pose = level_camera(plan["focal_px"], photo.shape[1::-1], np.radians(plan["pitch_deg"]), plan["height_m"],
                           plan["board_px"], np.radians(plan["board_yaw_deg"]))
    image, sheet_px = paste_print(photo, K, pose, paper_over_floor=plan["paper_over_floor"])
    return image, K, pose, sheet_px
