"""Doors and windows found in the photo, so the layouts keep doors clear and tall
furniture off windows without the user marking them.

Every wall of the measured floor is a vertical plane through its foot line, so the
calibration maps the wall to the photo: :func:`find_openings` samples each wall in view
as a front-on strip (2 cm a sample) and takes the wall's own colour (its median
0.15-0.7 m up, below the windows' sills). Two readers find doors on it, and both are
kept where they do not overlap:

- the door model (``models/door_columns.onnx``, trained by ``models/train_doors.py`` on
  the synthetic photographer's rooms) gives each column a probability from its colours
  up to 2.4 m and its neighbours' within 1.2 m either side (a casing's two sides, a
  door's head); a run of likely columns as wide as a door is one;
- the rules: a run of columns, as wide as a door, whose colour differs from the wall's
  from the floor up as far as the photo shows, with a hard edge at a side, where a
  window (a sill above the floor) or a radiator (below 0.7 m) differs only in part of
  the height; or two vertical lines that far apart rising from the floor (a casing).

The feet of a run's two sides are the door, as a user would mark it
(:func:`augment.room.doors.doors_on_floor`). ``--door`` marks one that is missed.
Windows are read by rules on the same strip (:func:`_window_spans`): the wall's colour
near the floor, another colour from 1.0 to 1.8 m up, a vertical edge at a side and a
sill's line.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..floor.model import MODELS_DIR, shipped_session
from .settings import ROOM

DOOR_MODEL = MODELS_DIR / "door_columns.onnx"


@dataclass(frozen=True)
class FoundDoor:
    """A door found on a wall of the measured floor.

    Attributes
    ----------
    feet_px : (2, 2) float64
        Photo pixels of the feet of its two sides (as ``--door`` takes them).
    segment_m : (2, 2) float64
        The same on the floor, meters.
    score : float
        How sure (0-1): the door model's mean probability over its columns, or for the
        rules the share of its columns that differ from the wall all the way up (0.5 for
        a casing's two lines).
    """

    feet_px: np.ndarray
    segment_m: np.ndarray
    score: float


def _wall_strip(lab: np.ndarray, calibration, a: np.ndarray, b: np.ndarray, step_m: float, top_m: float):
    """The wall standing on the floor edge a -> b, sampled front-on: (z, s, 3) Lab colours
    (rows from the floor up) and a (z, s) mask of the samples inside the photo."""
    length = float(np.linalg.norm(b - a))
    s = np.arange(0.5 * step_m, length, step_m)
    z = np.arange(0.5 * step_m, top_m, step_m)
    u = (b - a) / length
    S, Z = np.meshgrid(s, z)
    pts = np.stack([a[0] + S * u[0], a[1] + S * u[1], Z], axis=-1).reshape(-1, 3)
    cam = pts @ calibration.camera_from_floor[:3, :3].T + calibration.camera_from_floor[:3, 3]
    px = calibration.pixels_from_floor(pts).reshape(len(z), len(s), 2).astype(np.float32)
    h, w = lab.shape[:2]
    inside = ((cam[:, 2] > 0.1).reshape(len(z), len(s)) & (px[..., 0] >= 0) & (px[..., 0] <= w - 1)
              & (px[..., 1] >= 0) & (px[..., 1] <= h - 1))
    strip = cv2.remap(lab, px[..., 0], px[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return strip, inside, s


def _lab(image: np.ndarray) -> np.ndarray:
    """CIELAB of an RGB uint8 image, float32: L 0-100, a and b about 0."""
    lab = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2LAB).astype(np.float32)
    lab[..., 0] *= 100.0 / 255.0
    lab[..., 1:] -= 128.0
    return lab


def column_features(lab: np.ndarray, calibration, a: np.ndarray, b: np.ndarray, settings=None):
    """What the door model reads of the wall standing on a -> b: per column of its
    front-on strip (``settings.step_m`` apart), the strip's samples every two steps from
    the floor to ``settings.model_top_m`` as their colour less the wall's own, their
    lightness, the step in lightness across the column (a casing's edge) and whether they
    are in view. Returns ((channels, columns) float32, (columns,) positions along the
    wall, m), or None for a wall too little in view to tell its colour."""
    settings = settings or ROOM.doors
    strip, inside, s = _wall_strip(lab, calibration, a, b, settings.step_m, settings.model_top_m)
    wall = _wall_colour(strip, inside, settings)
    return None if wall is None else (_strip_features(strip, inside, wall), s)


@dataclass(frozen=True)
class FoundWindow:
    """A window found on a wall of the measured floor.

    Attributes
    ----------
    segment_m : (2, 2) float64
        The floor points under its two sides, meters.
    sill_m, top_m : float
        Its lower and upper edge above the floor, meters (the top as far as the photo
        shows it).
    corners_px : (4, 2) float64
        Photo pixels of its corners: the sill's two ends, then the top's.
    """

    segment_m: np.ndarray
    sill_m: float
    top_m: float
    corners_px: np.ndarray


@dataclass(frozen=True)
class Openings:
    """What :func:`find_openings` finds: doors and windows, walls in the polygon's order,
    left to right along each."""

    doors: list
    windows: list


def _rows(step_m: float, top_m: float) -> int:
    """How many rows :func:`_wall_strip` samples up to ``top_m``."""
    return len(np.arange(0.5 * step_m, top_m, step_m))


def _wall_colour(strip: np.ndarray, inside: np.ndarray, settings) -> np.ndarray | None:
    """The wall's own Lab colour: the median of the strip between ``wall_from_m`` and
    ``wall_to_m`` (None when too little of that shows)."""
    z = (np.arange(strip.shape[0]) + 0.5) * settings.step_m
    bare = inside & (z[:, None] >= settings.wall_from_m) & (z[:, None] <= settings.wall_to_m)
    return np.median(strip[bare], axis=0) if bare.sum() >= 20 else None


def _strip_features(strip: np.ndarray, inside: np.ndarray, wall: np.ndarray) -> np.ndarray:
    """:func:`column_features` of a strip sampled to ``settings.model_top_m``, the wall's
    own colour ``wall`` (:func:`_wall_colour`)."""
    light = strip[..., 0]
    across = np.zeros_like(light)
    across[:, 1:-1] = np.abs(light[:, 2:] - light[:, :-2]) / 2.0
    seen = inside.astype(np.float32)
    planes = [(strip[..., c] - wall[c]) / 20.0 * seen for c in range(3)]
    planes += [(light - 50.0) / 50.0 * seen, across / 5.0 * seen, seen]
    rows = strip.shape[0] // 2 * 2
    stack = np.stack([p[:rows].reshape(rows // 2, 2, -1).mean(axis=1) for p in planes])
    return stack.reshape(-1, stack.shape[-1]).astype(np.float32)


def _walls(poly: np.ndarray, edge_kind, settings) -> list[tuple[np.ndarray, np.ndarray, bool, bool]]:
    """The walls along the floor's outline, as (start, end, open start, open end): foot
    points of runs of wall edges that turn by less than ``settings.wall_turn_deg``, or by
    any angle over an edge shorter than ``settings.jog_m`` (the outline steps round a
    door's threshold or a casing), fitted with one straight line each; an end is open
    where the outline goes on along the photo's edge (the wall goes on out of view at
    its foot, though higher up it may show)."""
    m = len(poly)
    wall = [kind == "boundary" for kind in edge_kind]
    if not any(wall):
        return []
    start = next((k for k in range(m) if not wall[k - 1] or not wall[k]), 0)
    chains, chain = [], []
    for q in range(m):
        k = (start + q) % m
        if not wall[k]:
            if chain:
                chains.append(chain)
            chain = []
            continue
        if chain:
            # The chain's direction is its longest edge's; a short edge that turns away
            # belongs to it when the edge after it turns back (a jog, not a corner).
            main = max(chain, key=lambda e: np.linalg.norm(poly[(e + 1) % m] - poly[e]))
            d0 = poly[(main + 1) % m] - poly[main]
            d1 = poly[(k + 1) % m] - poly[k]
            after = poly[(k + 2) % m] - poly[(k + 1) % m]
            jog = (np.linalg.norm(d1) < settings.jog_m and wall[(k + 1) % m]
                   and _turn_deg(d0, after) <= settings.wall_turn_deg)
            if _turn_deg(d0, d1) > settings.wall_turn_deg and not jog:
                chains.append(chain)
                chain = []
        chain.append(k)
    if chain:
        chains.append(chain)
    out = []
    for chain in chains:
        pts = np.array([poly[chain[0]]] + [poly[(k + 1) % m] for k in chain])
        center = pts.mean(axis=0)
        direction = np.linalg.svd(pts - center)[2][0]
        if direction @ (pts[-1] - pts[0]) < 0:
            direction = -direction
        t = (pts - center) @ direction
        out.append((center + t.min() * direction, center + t.max() * direction,
                    edge_kind[(chain[0] - 1) % m] == "image", edge_kind[(chain[-1] + 1) % m] == "image"))
    return out


def _turn_deg(d0: np.ndarray, d1: np.ndarray) -> float:
    return abs(float(np.degrees(np.arctan2(d0[0] * d1[1] - d0[1] * d1[0], d0 @ d1))))


def _column_share(flags: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Per column of a wall strip, the share of its ``where`` samples that are ``flags``
    (0 where it has none)."""
    return (flags & where).sum(axis=0) / np.maximum(where.sum(axis=0), 1)


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(start, end) index pairs of the runs of True, end exclusive."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def door_probability(features: np.ndarray) -> np.ndarray:
    """Per column of a wall, the door model's probability that a door stands there, from
    :func:`column_features`. (columns,) float."""
    # Both ends padded with columns of nothing in view, as in training.
    margin = ROOM.doors.model_margin
    padded = np.pad(features, ((0, 0), (margin, margin)))[None]
    logits = shipped_session(str(DOOR_MODEL)).run(None, {"features": padded})[0].reshape(-1)[margin:-margin]
    return 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))


def _model_spans(features: np.ndarray, settings) -> list:
    """(start, end, score) column spans of the door model's doors on a wall, from its
    :func:`column_features`."""
    p = door_probability(features)
    door = p >= settings.model_threshold
    door = cv2.morphologyEx(door.astype(np.uint8)[None], cv2.MORPH_CLOSE, np.ones((1, 5), np.uint8))[0] > 0
    lo_w, hi_w = settings.width_m
    return [(i0, i1, float(p[i0:i1].mean())) for i0, i1 in _runs(door)
            if lo_w <= (i1 - i0) * settings.step_m <= hi_w]


def find_openings(image: np.ndarray, calibration, floor) -> Openings:
    """The doors and windows on the walls of ``floor`` in ``image``.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo, RGB, as calibrated. Not modified.
    calibration : Calibration
    floor : FloorPolygon
        Its edges of kind ``"boundary"`` are walls.

    Returns
    -------
    Openings
        ``doors`` (FoundDoor) and ``windows`` (FoundWindow, :func:`_window_spans`).
    """
    settings = ROOM.doors
    lab = _lab(image)
    step = settings.step_m
    poly = np.asarray(floor.polygon_m, dtype=np.float64)
    lo_w, hi_w = settings.width_m
    found, windows = [], []
    for a, b, open_a, open_b in _walls(poly, floor.edge_kind, settings):
        if np.linalg.norm(b - a) < lo_w:
            continue
        # One strip for both readers: the rules read it to top_m, the model to model_top_m.
        tall_strip, tall_inside, s = _wall_strip(lab, calibration, a, b, step, max(settings.top_m,
                                                                                   settings.model_top_m))
        rows = _rows(step, settings.top_m)
        strip, inside = tall_strip[:rows], tall_inside[:rows]
        wall = _wall_colour(strip, inside, settings)
        if wall is None:
            continue
        z = (np.arange(strip.shape[0]) + 0.5) * step
        differs = np.linalg.norm(strip - wall, axis=-1) > settings.min_difference
        low = inside & (z[:, None] >= settings.leaf_from_m)
        seen = low.sum(axis=0)
        # How far up each column shows; a call needs at least min_seen_m of leaf in view.
        tall = seen * step >= settings.min_seen_m
        foot = low & (z[:, None] < settings.sill_m)
        # The highest samples in view differ too: a radiator's top shows wall above it.
        top_z = np.max(np.where(low, z[:, None], 0.0), axis=0)
        top = low & (z[:, None] >= top_z - settings.top_band_m)
        share = _column_share(differs, low)
        leaf = tall & (share >= settings.min_share) & (_column_share(differs, foot) >= settings.min_share) & (
            _column_share(differs, top) >= settings.min_share)
        leaf = cv2.morphologyEx(leaf.astype(np.uint8)[None], cv2.MORPH_CLOSE, np.ones((1, 3), np.uint8))[0] > 0
        # A door the wall's colour: the casing's two sides, vertical lines from the floor up.
        lines = _upright_lines(strip[..., 0], low, tall, settings, settings.line_share)
        # A leaf of its own colour has a hard edge at a side at least (light on a wall fades).
        edges = _upright_lines(strip[..., 0], low, tall, settings, settings.side_share)
        spans = [(i0, i1, float(share[i0:i1].mean())) for i0, i1 in _runs(leaf)
                 if lo_w <= (i1 - i0) * step <= hi_w and any(min(abs(e - i0), abs(e - i1)) <= 3 for e in edges)]
        # A window's casing may run down to the floor (an apron, wainscot): between the
        # lines glass over the wall's colour is a window, not a door of the wall's colour.
        window_like = _window_like(strip, inside, differs, wall, settings)
        for i, j in ((i, j) for i in lines for j in lines if lo_w <= (j - i) * step <= hi_w):
            if not any(i0 - 3 <= i and j <= i1 + 3 for i0, i1, _ in spans) and window_like[i:j + 1].mean() < 0.5:
                spans.append((i, j + 1, 0.5))
        rows = _rows(step, settings.model_top_m)
        spans = _with_model_spans(spans, _model_spans(_strip_features(tall_strip[:rows], tall_inside[:rows], wall),
                                                      settings), settings)
        spans = _without_overlaps([sp for sp in spans if _has_head(tall_strip[..., 0], tall_inside, *sp[:2], settings)])
        u = (b - a) / np.linalg.norm(b - a)

        def segment(i0, i1):
            """The floor under columns i0 to i1 (end exclusive) of a strip starting at a."""
            return np.stack([a + (i0 * step) * u, a + (i1 * step) * u])

        for i0, i1, score in spans:
            seg = segment(i0, i1)
            found.append(FoundDoor(calibration.pixels_from_floor(seg), seg, score))
        # Windows on the wall also where it goes on past an open end, whole steps further.
        reach = round(settings.window_reach_m / step)
        before, after = int(open_a) * reach, int(open_b) * reach
        if before or after:
            tall_strip, tall_inside, _ = _wall_strip(lab, calibration, a - before * step * u,
                                                     b + after * step * u, step,
                                                     max(settings.top_m, settings.model_top_m))
        in_door = np.zeros(tall_strip.shape[1], bool)
        for i0, i1, _ in spans:
            in_door[before + i0:before + i1] = True
        for i0, i1, sill, top in _window_spans(tall_strip, tall_inside, wall, in_door, settings):
            seg = segment(i0 - before, i1 - before)
            corners = np.vstack([np.column_stack([seg, np.full(2, h)]) for h in (sill, top)])
            windows.append(FoundWindow(seg, sill, top, calibration.pixels_from_floor(corners)))
    return Openings(found, windows)


def _window_spans(strip: np.ndarray, inside: np.ndarray, wall: np.ndarray, in_door: np.ndarray, settings) -> list:
    """(start, end, sill m, top m) column spans of the windows on a wall strip sampled from
    the floor up (:func:`_wall_strip`): runs of columns, outside the doors found, that
    differ from the wall's colour (glass, sky, a frame) over most of the band every
    window covers (``settings.window_band_m``) and nowhere near the floor (a door or an
    opening does), as wide as a window, with a vertical edge near a side and a step in
    lightness at the sill. The sill is the median over the run of where the difference
    ends below the band, the top where it ends above."""
    step = settings.step_m
    z = (np.arange(strip.shape[0]) + 0.5) * step
    differs = np.linalg.norm(strip - wall, axis=-1) > settings.min_difference
    lo, hi = settings.window_band_m
    band, floor_band, shows = _window_bands(inside, settings)
    glass = shows & ~in_door & (_column_share(differs, band) >= settings.min_share) & (
        _column_share(differs, floor_band) < settings.window_floor_share)
    middle = int(np.searchsorted(z, 0.5 * (lo + hi)))
    sill_m, top_m, sill_step = _window_edges(strip, differs | ~inside, inside, z, middle,
                                             round(settings.window_mullion_m / step) + 1)
    # A sill is a line across the wall, light on a wall brightens it gradually: a column
    # whose wall below shows keeps its place in a window only with a step there (half the
    # run's, which one shadowed column or a radiator's top may lack).
    smooth_step = cv2.medianBlur(np.nan_to_num(sill_step, nan=255.0).astype(np.uint8)[None], 5)[0]
    glass &= np.isnan(sill_m) | (smooth_step >= 0.5 * settings.window_sill_step)
    # Glass panes either side of a mullion or a frame the wall's colour are one window.
    bridge = np.ones((1, round(settings.window_mullion_m / step) + 1), np.uint8)
    glass = cv2.morphologyEx(glass.astype(np.uint8)[None], cv2.MORPH_CLOSE, bridge)[0] > 0
    lo_w, hi_w = settings.window_width_m
    # A frame or a reveal at a side (the other may be a corner): light falling off across a wall has no edge.
    sides = _upright_lines(strip[..., 0], band, shows, settings, settings.side_share)
    out = []
    near = settings.window_frame_m / step
    for i0, i1 in _runs(glass):
        if not lo_w <= (i1 - i0) * step <= hi_w or not any(
                any(abs(e - end) <= near for e in sides) for end in (i0, i1 - 1)):
            continue
        sills = sill_m[i0:i1][~np.isnan(sill_m[i0:i1])]
        if len(sills) and np.median(sill_step[i0:i1][~np.isnan(sill_m[i0:i1])]) >= settings.window_sill_step:
            out.append((i0, i1, float(np.median(sills)), float(np.median(top_m[i0:i1]))))
    return out


def _window_edges(strip: np.ndarray, other: np.ndarray, inside: np.ndarray, z: np.ndarray, middle: int,
                  bar: int):
    """Per column of a wall strip (Lab), where the run of samples ``other`` than the wall
    through row ``middle`` ends below (the sill, m; NaN where no wall shows below it) and
    above (the top, m, or the highest sample in view), and the step in colour (CIELAB
    distance) across the sill over 8 cm (NaN with no sill): a sill board may be as light
    as the wall. Above, fewer than ``bar`` samples like the wall with glass over them are
    a transom's bar the wall's colour, not the top. Three (columns,) float arrays."""
    cols = other.shape[1]
    # The wall below a sill: three samples in a row like the wall (a lone one in a sill's shadow is noise).
    wall = ~other
    wall[2:] &= wall[1:-1] & wall[:-2]
    step = z[1] - z[0]
    sill, top, edge = np.full(cols, np.nan), np.full(cols, np.nan), np.full(cols, np.nan)
    # The head: the first sample above the band starting a run like the wall ``bar`` long, or
    # reaching the strip's top (shorter, it is a transom's bar with glass over it).
    like_wall = ~other[middle:]
    n = len(like_wall)
    counts = np.vstack([np.zeros((1, cols), int), np.cumsum(like_wall, axis=0)])
    ends = np.minimum(np.arange(n) + bar, n)
    head = like_wall & (counts[ends] - counts[:n] == (ends - np.arange(n))[:, None])
    for c in range(cols):
        below = np.flatnonzero(wall[:middle, c])
        seen = np.flatnonzero(inside[:, c])
        above = np.flatnonzero(head[:, c])
        if len(seen):
            top[c] = z[middle + above[0]] - 0.5 * step if len(above) else z[seen[-1]] + 0.5 * step
        if len(below) and 0 < below[-1] < middle - 3:
            k = below[-1]
            sill[c] = z[k] + 0.5 * step
            edge[c] = np.linalg.norm(strip[k + 3, c] - strip[k - 1, c])
    return sill, top, edge


def _upright_lines(lightness: np.ndarray, low: np.ndarray, tall: np.ndarray, settings, min_share: float
                   ) -> list[int]:
    """Columns of the wall strip where a vertical line runs up from the floor: a step in
    lightness across the column in most samples in view (a casing's edge, a leaf's
    shadow), the strongest of its neighbours, off the wall's ends."""
    step_l = np.zeros_like(lightness)
    step_l[:, 1:-1] = np.abs(lightness[:, 2:] - lightness[:, :-2]) / 2.0
    share = _column_share(step_l > settings.line_step, low)
    share[: settings.line_margin] = 0.0
    share[-settings.line_margin:] = 0.0
    keep = tall & (share >= min_share)
    peaks = [i for i in np.flatnonzero(keep) if share[i] >= share[max(i - 2, 0): i + 3].max()]
    return peaks


def _window_bands(inside: np.ndarray, settings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of a wall strip's samples in view (rows from the floor up), those in the band every
    window covers (``settings.window_band_m``) and those near the floor, below any sill;
    and the columns that show enough of that band (``settings.window_seen_m``)."""
    z = (np.arange(inside.shape[0]) + 0.5) * settings.step_m
    lo, hi = settings.window_band_m
    band = inside & (z[:, None] >= lo) & (z[:, None] <= hi)
    floor_band = inside & (z[:, None] >= settings.leaf_from_m) & (z[:, None] <= settings.window_below_m)
    return band, floor_band, band.sum(axis=0) * settings.step_m >= settings.window_seen_m


def _window_like(strip: np.ndarray, inside: np.ndarray, differs: np.ndarray, wall: np.ndarray,
                 settings) -> np.ndarray:
    """Per column of a wall strip, whether it shows a window's glass over the wall: it is
    brighter than the wall's colour over the band every window covers (daylight through
    it) and does not differ near the floor (as :func:`_window_spans` reads a window).
    (columns,) bool."""
    band, floor_band, shows = _window_bands(inside, settings)
    brighter = differs & (strip[..., 0] > wall[0] + settings.min_difference)
    return (shows & (_column_share(brighter, band) >= settings.min_share)
            & (_column_share(differs, floor_band) < settings.window_floor_share))


def _has_head(lightness: np.ndarray, inside: np.ndarray, i0: int, i1: int, settings) -> bool:
    """Whether the columns i0 to i1 (end exclusive) of a wall strip show a door's head: a
    horizontal line (a lightness step across the row) between ``head_m`` high, in
    ``head_share`` of them at least. True when that band is not in view: it cannot tell.
    A wall between two windows, or next to a wide closet, has a casing's edge or another
    colour at its sides but nothing across its top."""
    z = (np.arange(lightness.shape[0]) + 0.5) * settings.step_m
    rows = np.flatnonzero((z >= settings.head_m[0]) & (z <= settings.head_m[1]))
    rows = rows[(rows >= 1) & (rows < lightness.shape[0] - 1)]
    if len(rows) == 0 or inside[rows.min() - 1:rows.max() + 2, i0:i1].all(axis=0).mean() < 0.5:
        return True
    step = np.abs(lightness[rows + 1, i0:i1] - lightness[rows - 1, i0:i1]) / 2.0 > settings.line_step
    step &= inside[rows + 1, i0:i1] & inside[rows - 1, i0:i1]
    # A row's line, one sample up or down, in each column.
    near = step.copy()
    near[1:] |= step[:-1]
    near[:-1] |= step[1:]
    return float(near.mean(axis=1).max()) >= settings.head_share


def _with_model_spans(rules: list, model: list, settings) -> list:
    """The rules' and the model's (start, end, score) spans together. A casing's two lines
    around a model's door that fills less than ``settings.model_in_casing`` of the span
    between them are that door's sides: the model saw a louvred or panelled leaf in part.
    (A door the model sees whole fills more: its casing's own width is all it leaves.)"""
    out = list(rules)
    for m0, m1, score in model:
        around = [(i0, i1) for i0, i1, _ in rules
                  if i0 <= m0 and m1 <= i1 and (m1 - m0) < settings.model_in_casing * (i1 - i0)]
        out.append((*min(around, key=lambda t: t[1] - t[0]), score) if around else (m0, m1, score))
    return out


def _without_overlaps(spans: list) -> list:
    """Of overlapping (start, end, score) spans, the best scored; then a span left out
    that shares no more than a line with those kept (a double door's or a folding
    closet's middle) is kept too."""
    kept = []
    for sp in sorted(spans, key=lambda t: -t[2]):
        if all(sp[1] <= k[0] or sp[0] >= k[1] for k in kept):
            kept.append(sp)
    for sp in sorted(spans, key=lambda t: -t[2]):
        if sp not in kept and all(sp[1] <= k[0] + 1 or sp[0] >= k[1] - 1 for k in kept):
            kept.append(sp)
    return sorted(kept)
