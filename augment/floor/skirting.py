"""Skirting boards: the strip at the foot of a wall that segmentation calls floor.

A floor mask from the model and GrabCut usually ends at the top of the skirting board,
not at the floor line below it. Seen from a camera 1.5 m up, a 10 cm board that counts
as floor puts the wall 7 % farther away than it is, and the floor's area grows by more
than that: this strip is most of the floor polygon's area error.

:func:`trim_skirting` looks straight down from the mask's top edge in every image
column. Where a wall stands on the floor, a board shows as a uniform strip that ends in
a sharp step to the floor colour; a shadow at the foot of the wall fades out instead,
and so does not count. A hard-edged shadow does not fade, but it keeps the floor's
colour, only darker: strips like that are left alone. Boards have one height all round
a room, so the strip is cut only where the photo agrees on that height. In a column on
its own the strongest step may be a plank joint or a grout line instead of the board's
lower edge, so once the photo agrees, every column looks again for its step within a
pixel or two of the most common height. The cut then runs along every stretch of wall
where most columns show the board (a column that cannot tell, left standing, is a spike
in the outline that puts the wall back at the board's top).

Often GrabCut has already stopped at the floor line, and what lies below the mask's edge
is floor: a plank along the wall, a band of light, a contact shadow, with a step at its
far side just like a board's lower edge. Rules on colour cannot tell those from a board
(many of their trims cut a band of floor), so a small learned model
(``models/skirting_board.onnx``, trained by ``models/train_skirting.py`` on renders with
known floor lines) looks at each column's colours across the mask's edge. The trim is
skipped when it sees no board anywhere along the walls, and made when it is sure of one
even where the rules doubt it (heights that spread past deep shadows); in between, the
rules decide.

GrabCut also stops short of the floor line: below a board's cast shadow or a dark band at
the foot of the wall it sees something that is neither floor nor wall, and far away a few
rows of floor are many square meters. :func:`extend_to_floor_line` asks a second small
model (``models/skirting_gap.onnx``, trained on the same columns) whether the floor line
lies above the mask's edge and how far, and moves the edge up to it along the walls where
most columns say so.

Where to cut is the rules' step, when it is the board's lower edge; but on a grained floor
or below a board's shadow the strongest step is often another, and a board of the floor's
own colour shows the rules a step in a few columns only, or none. A third small model
(``models/skirting_depth.onnx``, trained on the same columns) says per column how tall
the board is; a wall whose rules' height disagrees with it is cut at the step nearest
its height instead, and a wall the board model is sure of is cut whole, also where the
rules see no step.

Whether the mask holds the board can differ from wall to wall: GrabCut may stop at the
floor line along one wall and at the board's top along another. When the photo as a
whole shows a board, the stretches of wall the board model is sure hold none are left
(their strip is floor, the board stands above the mask's edge); when it does not, each
wall is judged on its own (its columns between corners of the mask's top edge), and
the walls where the board model is sure of one are cut (where the photo leans to no
board, only if the rules see a step on them too: a strip of floor along one wall fools
the model more often than one along every wall), and the walls whose strip the user
clicked as not floor (a board darker than the floor and of its hue looks like shade to
both the rules and the model), at the depth model's height where the rules see no strip
on them (a board of the floor's colour).

A strip of a second floor along a wall (concrete or tiles past a threshold) ends in a
sharp step toward the camera just like a board; where most of a wall's columns show a
board standing on the mask's edge (:func:`_board_above`), the edge is the floor line and
the strip is left.

A board of the floor's colour that the board model leans to without being sure of is
left; :func:`trim_skirting` then says where it may be (``doubt_px``, on the wall left
uncut with the highest mean probability, from ``FLOOR.skirting.doubt_p``), so that the
user can look and, where a board is there, click it.

The thresholds and sizes are :data:`augment.floor.settings.FLOOR`'s ``skirting`` section.
"""
from __future__ import annotations

from functools import cache

import cv2
import numpy as np
from scipy.ndimage import median_filter

from .model import MODELS_DIR, shipped_session, shrink_area
from .settings import FLOOR

BOARD_MODEL = MODELS_DIR / "skirting_board.onnx"
GAP_MODEL = MODELS_DIR / "skirting_gap.onnx"
DEPTH_MODEL = MODELS_DIR / "skirting_depth.onnx"


def wall_columns(mask: np.ndarray, calibration):
    """Columns whose top floor pixel meets something above it (not the image's top
    edge), that pixel's row, and how many pixels one meter upright there spans; only
    columns where the board's search (``FLOOR.skirting.search_m`` upright) fits in the
    photo."""
    top = np.argmax(mask, axis=0)
    cols = np.flatnonzero(mask[top, np.arange(mask.shape[1])] & (top > 0))
    rows = top[cols]
    if len(cols) == 0:
        return cols, rows, np.zeros(0)
    px_per_m = px_per_m_upright(calibration, cols, rows)
    # Where the floor's pose puts an upright meter beyond the photo's height (or nowhere:
    # a pixel on the horizon, or a "floor" that is a board held up at the camera), no
    # board shows; each column's search would take a slice of that many rows.
    fits = np.isfinite(px_per_m) & (px_per_m > 0) & (FLOOR.skirting.search_m * px_per_m < mask.shape[0])
    return cols[fits], rows[fits], px_per_m[fits]


def px_per_m_upright(calibration, cols, rows) -> np.ndarray:
    """How many pixels one meter upright spans, standing on the floor at each pixel."""
    foot = calibration.floor_from_pixels(np.column_stack([cols, rows]).astype(np.float64))
    head = calibration.pixels_from_floor(np.column_stack([foot, np.full(len(foot), FLOOR.skirting.search_m)]))
    return np.hypot(head[:, 0] - cols, head[:, 1] - rows) / FLOOR.skirting.search_m


def _board_rows(image: np.ndarray, mask: np.ndarray, cols, rows, px_per_m, near_m=None, near_px=None):
    """Per column, the board's height in pixels below the mask's top edge: 0 where the
    column shows none, NaN where it cannot tell (too close to the photo's bottom, or
    the floor below the strip is not in the mask); and how the strip's colour compares
    with the floor's below it: brightness ratio, and angle between the RGB directions
    (degrees). With ``near_m`` (one height, or one per column), a column looks for the
    board's lower edge only within ``near_px`` (one, or one per column; default
    ``FLOOR.skirting.near_px``) of that height, and shows none where that window is
    outside its search."""
    near_px = FLOOR.skirting.near_px if near_px is None else near_px
    h = image.shape[0]
    span = np.ceil(FLOOR.skirting.search_m * px_per_m).astype(int)
    first = np.maximum(4, np.ceil(FLOOR.skirting.min_height_m * px_per_m).astype(int))
    # At least the rows a column too far off to tell (span under 4) is read in, below a
    # strip of the least height.
    length = max(int(span.max()), 4) + 8 if len(span) else 0
    offsets = np.arange(length)
    r = np.minimum(rows[:, None] + offsets[None], h - 1)
    c = image[r, cols[:, None]].astype(np.float32)  # (k, length, 3)
    step = np.linalg.norm(c[:, 3:] - c[:, :-3], axis=2)  # step[j]: between rows j and j + 3
    t_of = np.arange(step.shape[1]) + 2  # the row a step ends the strip at
    allowed = (t_of[None] >= first[:, None]) & (t_of[None] < span[:, None])
    if near_m is not None:
        near_px = np.broadcast_to(near_px, len(cols))[:, None]
        allowed &= np.abs(t_of[None] - np.broadcast_to(near_m, len(cols))[:, None] * px_per_m[:, None]) <= near_px
    best = np.argmax(np.where(allowed, step, -1.0), axis=1)
    t = t_of[best]
    k = np.arange(len(cols))

    strip_color = _prefix_median(c, t - 1)
    below = c[k[:, None], t[:, None] + 2 + np.arange(6)[None]]
    below_color = np.median(below, axis=1)
    contrast = np.linalg.norm(strip_color - below_color, axis=1)
    below_noise = np.median(np.linalg.norm(below - below_color[:, None], axis=2), axis=1)
    strip_noise = _prefix_median(np.linalg.norm(c - strip_color[:, None], axis=2), t - 1)
    board = ((contrast >= np.maximum(FLOOR.skirting.min_contrast, np.maximum(4 * below_noise, 3 * strip_noise)))
             & (step[k, best] >= FLOOR.skirting.sharpness * contrast))
    floor_below = mask[np.minimum(rows[:, None] + t[:, None] + np.arange(8)[None], h - 1), cols[:, None]].all(axis=1)
    out = np.where(board & allowed.any(axis=1), t, 0).astype(np.float64)
    unknown = (span < 4) | (rows + span + 8 >= h) | (board & ~floor_below)
    out[unknown] = np.nan
    strip_norm, below_norm = np.linalg.norm(strip_color, axis=1), np.linalg.norm(below_color, axis=1)
    brightness = strip_norm / np.maximum(below_norm, 1e-6)
    cos = np.sum(strip_color * below_color, axis=1) / np.maximum(strip_norm * below_norm, 1e-6)
    return out, brightness, np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _mode(heights_m: np.ndarray) -> float:
    """The most common height, from a histogram of ``FLOOR.skirting.mode_bin_m`` bins
    smoothed over three."""
    bin_m = FLOOR.skirting.mode_bin_m
    bins = np.arange(0.0, FLOOR.skirting.max_height_m + 2 * bin_m, bin_m)
    counts, _ = np.histogram(heights_m, bins)
    smooth = np.convolve(counts, np.ones(3), mode="same")
    i = int(np.argmax(smooth))
    return float(0.5 * (bins[i] + bins[i + 1]))


def _prefix_median(values: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Median over axis 1 of ``values`` (k, n, ...) using only the first ``count[i]``
    entries of row i (nanmedian, without its cost)."""
    keep = np.arange(values.shape[1])[None] < count[:, None]
    keep = keep.reshape(keep.shape + (1,) * (values.ndim - 2))
    ordered = np.sort(np.where(keep, values, np.inf), axis=1)
    lo = ((count - 1) // 2).reshape((-1, 1) + (1,) * (values.ndim - 2))
    hi = (count // 2).reshape(lo.shape)
    take = np.take_along_axis
    return (0.5 * (take(ordered, lo, axis=1) + take(ordered, hi, axis=1)))[:, 0]


def _running_mean(values: np.ndarray, half: int) -> np.ndarray:
    """Mean over axis 0 of ``values`` (k, ...) of the entries up to ``half`` either side
    of each (fewer at the ends), from a running sum."""
    k = len(values)
    summed = np.cumsum(np.concatenate([np.zeros((1,) + values.shape[1:], values.dtype), values]), axis=0)
    lo, hi = np.maximum(np.arange(k) - half, 0), np.minimum(np.arange(k) + half + 1, k)
    return (summed[hi] - summed[lo]) / (hi - lo).reshape((-1,) + (1,) * (values.ndim - 1))


def _stretches(cols: np.ndarray, rows: np.ndarray) -> list[np.ndarray]:
    """Indices into ``cols`` per unbroken stretch of the mask's top edge: split where a
    column is missing or the edge jumps by more than ``FLOOR.skirting.step_px`` rows."""
    breaks = np.flatnonzero((np.diff(cols) > 1) | (np.abs(np.diff(rows)) > FLOOR.skirting.step_px)) + 1
    return np.split(np.arange(len(cols)), breaks)


def _bridge(cols: np.ndarray, rows: np.ndarray, height_m: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """Board heights per column (NaN: no board seen) spread along each stretch of wall
    where enough columns saw it; elsewhere gaps between boards are filled where they are
    up to ``FLOOR.skirting.gap_px`` columns wide, or where the board model ``seen`` (k,)
    bool sees the board. 0 where no board is cut."""
    out = np.nan_to_num(height_m)
    for stretch in _stretches(cols, rows):
        found = stretch[~np.isnan(height_m[stretch])]
        if len(found) < 2:
            continue
        x = cols[found]
        if len(found) >= FLOOR.skirting.stretch_agreeing * len(stretch):
            fill = stretch
        else:
            gap = stretch[(cols[stretch] > x[0]) & (cols[stretch] < x[-1])]
            right = np.searchsorted(x, cols[gap])
            fill = gap[(x[right] - x[right - 1] <= FLOOR.skirting.gap_px) | seen[gap]]
        out[fill] = np.interp(cols[fill], x, height_m[found])
    return out


def _walls(cols: np.ndarray, rows: np.ndarray) -> list[np.ndarray]:
    """The wall columns split into walls: indices into ``cols`` per wall, in order.

    A wall's floor line is straight in the photo (a straight line on the floor stays
    straight), so the mask's top edge is split where it jumps (the stretches of
    :func:`_stretches`) and where it bends by more than ``FLOOR.skirting.corner_px``."""
    walls = []
    for stretch in _stretches(cols, rows):
        if len(stretch) < 3:
            walls.append(stretch)
            continue
        line = np.column_stack([cols[stretch], rows[stretch]]).astype(np.float32).reshape(-1, 1, 2)
        corners = cv2.approxPolyDP(line, FLOOR.skirting.corner_px, False)[1:-1, 0, 0]
        walls.extend(np.split(stretch, np.searchsorted(cols[stretch], corners)))
    return walls


def _no_board_columns(cols: np.ndarray, rows: np.ndarray, p_board: np.ndarray) -> np.ndarray:
    """(k,) bool: the columns where the board model, averaged over the column and half of
    ``FLOOR.skirting.min_wall_columns`` either side in its stretch (:func:`_stretches`), stays
    below ``FLOOR.skirting.no_wall_board_p``, in runs of that many columns at least:
    GrabCut stopped at the floor line there, and the strip below the mask's edge is floor
    even where the photo shows a board elsewhere. A shorter run (a corner, a short piece
    of wall) is left to the rules: cut beside cut columns, it would stand as a spike."""
    out = np.zeros(len(cols), bool)
    least = FLOOR.skirting.min_wall_columns
    for stretch in _stretches(cols, rows):
        low = _running_mean(p_board[stretch], least // 2) < FLOOR.skirting.no_wall_board_p
        edges = np.diff(np.concatenate([[0], low.astype(np.int8), [0]]))
        for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            if b - a >= least:
                out[stretch[a:b]] = True
    return out


def _walls_with_a_board(walls, p_board: np.ndarray, whole: np.ndarray) -> np.ndarray:
    """(k,) bool: the columns of each of ``walls`` (:func:`_walls`) of
    ``FLOOR.skirting.min_wall_columns`` or more where the board model's mean probability
    (over the columns whose window lies in the photo, if any) reaches
    ``FLOOR.skirting.board_p``."""
    judged = np.zeros(len(p_board), bool)
    for wall in walls:
        if len(wall) < FLOOR.skirting.min_wall_columns:
            continue
        inside = wall[whole[wall]]
        if np.mean(p_board[inside if len(inside) else wall]) >= FLOOR.skirting.board_p:
            judged[wall] = True
    return judged


def board_profiles(image: np.ndarray, mask: np.ndarray, cols, rows, px_per_m):
    """What the board model reads in each wall column.

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        The photo at the working size, lightly blurred.
    mask : (rows, cols) bool
        The floor mask at that size.
    cols, rows, px_per_m : (k,) arrays
        The wall columns, their mask-edge rows and pixels per upright meter (from
        ``wall_columns``).

    Returns
    -------
    profile : (k, 7, n) float32
        Per column, n samples from ``FLOOR.skirting.profile_from_m`` to
        ``FLOOR.skirting.profile_to_m`` around the mask's edge: log colour against the
        floor's far below (3), the same averaged over ``FLOOR.skirting.profile_context``
        columns either side (3), and 1 where the sample is inside the photo (1).
    scalars : (k, 2) float32
        log(pixels per meter) / 5, and the fraction of the 39 pixels below the edge that
        are floor in the mask.
    whole : (k,) bool
        Columns whose window lies inside the photo.
    """
    sk = FLOOR.skirting
    offsets_m = np.arange(sk.profile_from_m, sk.profile_to_m + sk.profile_step_m / 2, sk.profile_step_m)
    h = image.shape[0]
    y = rows[:, None] + offsets_m[None] * px_per_m[:, None]
    inside = (y >= 0) & (y <= h - 1)
    y = np.clip(y, 0, h - 1)
    y0 = np.floor(y).astype(int)
    y1 = np.minimum(y0 + 1, h - 1)
    f = (y - y0)[..., None]
    colour = image[y0, cols[:, None]].astype(np.float32) * (1 - f) + image[y1, cols[:, None]].astype(np.float32) * f
    log_colour = np.log1p(colour) * inside[..., None]
    floor = inside & (offsets_m >= sk.profile_floor_m)[None]
    # Near a wall the window runs off the photo: its lowest samples stand in for the floor.
    last = inside.shape[1] - 1 - np.argmax(inside[:, ::-1], axis=1)
    index = np.arange(inside.shape[1])[None]
    lowest = inside & (index > last[:, None] - 8) & (index <= last[:, None])
    floor = np.where(floor.any(axis=1)[:, None], floor, lowest).astype(np.float32)
    reference = (log_colour * floor[..., None]).sum(axis=1) / np.maximum(floor.sum(axis=1), 1)[:, None]
    own = (log_colour - reference[:, None]) * inside[..., None]
    context = _running_mean(own, sk.profile_context)
    profile = np.concatenate([own, context, inside[..., None].astype(np.float32)], axis=2).transpose(0, 2, 1)
    below = mask[np.clip(rows[:, None] + np.arange(1, 40)[None], 0, h - 1), cols[:, None]].mean(axis=1)
    scalars = np.column_stack([np.log(px_per_m) / 5, below])
    return profile.astype(np.float32), scalars.astype(np.float32), inside[:, -1]


def board_probability(profile: np.ndarray, scalars: np.ndarray) -> np.ndarray:
    """Per column, the board model's probability that the mask's edge is a board's top
    edge (the floor line lies below it), from :func:`board_profiles`. (k,) float."""
    if len(profile) == 0:
        return np.zeros(0)
    session = shipped_session(str(BOARD_MODEL))
    logits = session.run(None, {"profile": profile, "scalars": scalars})[0].reshape(-1)
    return 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))


def floor_line_gap(profile: np.ndarray, scalars: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per column, the gap model's probability that the floor line lies above the mask's
    edge, and how far above (m, 0 or more), from :func:`board_profiles`. Two (k,) float."""
    if len(profile) == 0:
        return np.zeros(0), np.zeros(0)
    out = shipped_session(str(GAP_MODEL)).run(None, {"profile": profile, "scalars": scalars})[0].astype(np.float64)
    return 1.0 / (1.0 + np.exp(-out[:, 0])), np.maximum(0.0, -out[:, 1] / 100.0)


def board_depth_m(profile: np.ndarray, scalars: np.ndarray) -> np.ndarray:
    """Per column, the depth model's height of the board whose top is the mask's edge
    (m upright, at the edge), from :func:`board_profiles`: where the floor line lies below
    the edge if the column shows a board. (k,) float."""
    if len(profile) == 0:
        return np.zeros(0)
    out = shipped_session(str(DEPTH_MODEL)).run(None, {"profile": profile, "scalars": scalars})[0]
    return np.clip(out.reshape(-1).astype(np.float64) / 100.0, 0.0, FLOOR.skirting.max_height_m)


def _cut_depth_px(view, walls, rules_px: np.ndarray, decided: np.ndarray, profiles) -> np.ndarray:
    """(k,) depth to cut (px, 0: none) in the ``decided`` columns, wall by wall.

    The rules' cut (``rules_px``) follows the board's lower edge exactly where their step
    is that edge, but on a grained floor or below a board's shadow the strongest step is
    often another, and a board the floor's colour shows them none. The depth model says
    about where the edge lies (within a centimeter or two): a wall whose rules' height
    is within ``FLOOR.skirting.rules_near_m`` of it keeps the rules' cut (at their height
    in the columns they leave); on any other, the step nearest the model's height (within
    ``FLOOR.skirting.learned_near_m``) places it, one height along the wall, as boards
    have."""
    _, small_image, small_mask, _, cols, rows, px_per_m = view
    out = np.zeros(len(decided))
    if not decided.any():
        return out
    profile, scalars, _ = profiles()
    depth_m = np.zeros(len(cols))
    depth_m[decided] = board_depth_m(profile[decided], scalars[decided])  # only the columns cut are read
    learned_m = np.zeros(len(cols))
    rules_m = np.full(len(cols), np.nan)
    for wall in walls:
        cut = wall[decided[wall]]
        if len(cut):
            learned_m[wall] = np.median(depth_m[cut])
        ruled = wall[rules_px[wall] > 0]
        if len(ruled):
            rules_m[wall] = np.median(rules_px[ruled] / px_per_m[ruled])
    trusted = np.abs(rules_m - learned_m) <= FLOOR.skirting.rules_near_m
    t = np.zeros(len(cols))
    look = decided & ~trusted
    if look.any():
        t[look] = _board_rows(small_image, small_mask, cols[look], rows[look], px_per_m[look], learned_m[look],
                              FLOOR.skirting.learned_near_m * px_per_m[look])[0]
    for wall in walls:
        cut = wall[decided[wall]]
        if not len(cut):
            continue
        if trusted[wall[0]]:
            out[cut] = np.where(rules_px[cut] > 0, rules_px[cut], rules_m[cut] * px_per_m[cut])
            continue
        found = cut[t[cut] > 0]
        height_m = np.median(t[found] / px_per_m[found]) if len(found) else learned_m[cut[0]]
        out[cut] = height_m * px_per_m[cut]
    return out * (out >= FLOOR.skirting.min_height_m * px_per_m)


def extend_to_floor_line(image: np.ndarray, mask: np.ndarray, calibration) -> np.ndarray:
    """Move the floor mask's top edge up to the floor line where it stops short of it.

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        The photo. Not modified.
    mask : (rows, cols) bool
        Floor mask at the photo's size, its boards already trimmed. Not modified.
    calibration : Calibration
        The photo's calibration.

    Returns
    -------
    mask : (rows, cols) bool
        The mask with the strips of floor below the walls added, or the same values.
    """
    view = working_view(image, mask, calibration)
    if view is None:
        return mask.copy()
    return _extended(mask, view, _profiles_of(view))


def _profiles_of(view):
    """The view's :func:`board_profiles`, computed on the first call only: the trim and
    the extension read the same columns."""
    _, small_image, small_mask, _, cols, rows, px_per_m = view
    return cache(lambda: board_profiles(small_image, small_mask, cols, rows, px_per_m))


def _extended(mask: np.ndarray, view, profiles) -> np.ndarray:
    """:func:`extend_to_floor_line` on a :func:`working_view` and its ``profiles``."""
    scale, _, small_mask, _, cols, rows, px_per_m = view
    profile, scalars, _ = profiles()
    p_gap, gap_m = floor_line_gap(profile, scalars)
    add = np.zeros(small_mask.shape, np.uint8)
    sk = FLOOR.skirting
    for wall in _walls(cols, rows):
        sure = p_gap[wall] >= sk.gap_p
        if len(wall) < sk.min_wall_columns or np.mean(sure) < sk.gap_agreeing:
            continue
        # A wall's floor line is straight: the columns that doubt the gap take the wall's.
        reach_m = np.where(sure, gap_m[wall], np.median(gap_m[wall][sure]))
        reach_px = median_filter(reach_m * px_per_m[wall], size=sk.gap_smooth_columns, mode="nearest")
        for col, row, n in zip(cols[wall], rows[wall], np.round(reach_px).astype(int)):
            add[max(0, row - n):row, col] = n > 0
    if not add.any():
        return mask.copy()
    if scale < 1.0:
        add = cv2.resize(add, mask.shape[::-1], interpolation=cv2.INTER_NEAREST)
    return mask | (add > 0)


def working_mask(mask: np.ndarray, calibration):
    """The mask and calibration at the trim's working size (``FLOOR.skirting.work_long_px``
    long at most), with the wall columns: (scale, mask, calibration, cols, rows, px_per_m)
    (:func:`wall_columns`)."""
    rows_px, cols_px = mask.shape
    scale = min(1.0, FLOOR.skirting.work_long_px / max(rows_px, cols_px))
    size = (round(cols_px * scale), round(rows_px * scale))
    small_mask = cv2.resize(mask.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0 if scale < 1 else mask
    small_cal = calibration.scaled(scale)
    return (scale, small_mask, small_cal, *wall_columns(small_mask, small_cal))


def working_view(image: np.ndarray, mask: np.ndarray, calibration):
    """The photo, mask and calibration at the trim's working size, with the wall columns.

    Returns None when no column of the mask meets a wall; else (scale, image (blurred,
    filled only in the band of rows the search looks at), mask, calibration, cols, rows,
    px_per_m).
    """
    rows_px = mask.shape[0]
    scale, small_mask, small_cal, cols, rows, px_per_m = working_mask(mask, calibration)
    if len(cols) == 0:
        return None
    size = small_mask.shape[::-1]
    # Only the band of rows the searches and the profiles look at is needed at the working
    # size; a profile cut short reads black there, which the models would take for shade.
    sk = FLOOR.skirting
    top = max(0, int(np.floor((rows + sk.profile_from_m * px_per_m).min())) - 2)
    bottom = min(size[1], int(np.ceil((rows + max(sk.search_m, sk.profile_to_m) * px_per_m).max())) + 12)
    # The search for a board above the edge (:func:`_board_above`) reads higher: those rows
    # are shrunk on their own, so that the band's pixels stay what the models were trained on.
    above = max(0, int(np.floor((rows - np.ceil(sk.search_m * px_per_m)).min())) - 12)
    small_image = np.zeros((size[1], size[0], 3), np.uint8)
    for y0, y1 in ((above, top), (top, bottom)):
        if y1 > y0:
            band = image[int(y0 / scale):min(rows_px, int(np.ceil(y1 / scale)) + 1)]
            small_image[y0:y1] = shrink_area(band, (size[0], y1 - y0), least=2)  # blurred next
    small_image = cv2.GaussianBlur(small_image, (3, 3), 0)
    return scale, small_image, small_mask, small_cal, cols, rows, px_per_m


def _board_above(view) -> np.ndarray:
    """(k,) bool: the view's columns whose mask edge has a board standing on it: above the
    edge a strip of one colour, ``FLOOR.skirting.above_min_m`` tall or more (a board's lit
    top edge is thinner), ends at a sharp step. The rules' test for a board below the
    edge, on the photo turned upside down."""
    _, small_image, _, _, cols, rows, px_per_m = view
    h = small_image.shape[0]
    up, _, _ = _board_rows(small_image[::-1], np.ones(small_image.shape[:2], bool), cols, h - rows, px_per_m)
    return up >= FLOOR.skirting.above_min_m * px_per_m


def _strip_of_one_height(known, shown, height_m) -> bool:
    """Whether enough wall columns show a strip, of one height a board can have."""
    sk = FLOOR.skirting
    if known.sum() < 0.3 * len(known) or shown.sum() < sk.min_agreeing * known.sum():
        return False
    median = float(np.median(height_m[shown]))
    q1, q3 = np.percentile(height_m[shown], [25, 75])
    return sk.min_height_m <= median <= sk.max_height_m and q3 - q1 <= sk.max_spread * median


def _rules_see_a_board(known, shown, height_m, brightness, hue_deg) -> bool:
    """Whether enough wall columns show a strip of one height that is not shade."""
    return _strip_of_one_height(known, shown, height_m) and not (
        np.median(brightness[shown]) < FLOOR.skirting.shadow_ratio
        and np.median(hue_deg[shown]) < FLOOR.skirting.shadow_deg)


def _walls_clicked(walls, cols, rows, px_per_m, points, reach_px) -> np.ndarray:
    """(k,) bool: the columns of each of ``walls`` whose strip the user clicked as not
    floor: a point within ``reach_px`` across of one of the wall's columns and on its strip
    (from the mask's top edge down by a board's greatest height)."""
    clicked = np.zeros(len(cols), bool)
    for wall in walls:
        if len(wall) < FLOOR.skirting.min_wall_columns:
            continue
        for x, y in points:
            if ((np.abs(cols[wall] - x) <= reach_px) & (y >= rows[wall] - 2)
                    & (y <= rows[wall] + FLOOR.skirting.max_height_m * px_per_m[wall] + 2)).any():
                clicked[wall] = True
    return clicked


def _rules_cut(small_image, small_mask, cols, rows, px_per_m, p_board, p_mean, whole, walls, clicked):
    """(k,) the depth the rules (with the board model's say) cut at each wall column (px; 0:
    none): the board's lower edge as the column's step at the photo's most common height.
    ``clicked`` (k,) bool: the columns of the walls whose strip the user clicked as not
    floor (:func:`_walls_clicked`)."""
    none = np.zeros(len(cols))
    t, brightness, hue_deg = _board_rows(small_image, small_mask, cols, rows, px_per_m)
    known = ~np.isnan(t)
    shown = known & (t > 0)
    if not shown.any():
        return none
    height_m = t / px_per_m
    # Each column's strongest step is the board's lower edge in most columns, but a
    # plank seam or a grout line in others: the heights' mode is the board, and each
    # column looks again for its step at that height.
    t_mode = None
    if p_mean >= FLOOR.skirting.no_board_p:
        t_mode, brightness_mode, hue_mode = _board_rows(small_image, small_mask, cols, rows, px_per_m,
                                                        _mode(height_m[shown]))
        shown_mode = ~np.isnan(t_mode) & (t_mode > 0)
        # The rules judge both readings: on a grained floor the strongest steps spread too
        # widely for one height even where the board is plain to see at the mode.
        if not shown_mode.any() or not (
                p_mean >= FLOOR.skirting.board_p
                or _rules_see_a_board(known, shown, height_m, brightness, hue_deg)
                or _rules_see_a_board(~np.isnan(t_mode), shown_mode, t_mode / px_per_m, brightness_mode, hue_mode)):
            t_mode = None
    if t_mode is None:
        judged = _walls_with_a_board(walls, p_board, whole)
        for wall in walls:
            # No shade test: the user has seen the board.
            if clicked[wall].any() and _strip_of_one_height(known[wall], shown[wall], height_m[wall]):
                judged[wall] = True
        if not (shown & judged).any():
            return none
        t_mode, _, _ = _board_rows(small_image, small_mask, cols, rows, px_per_m, _mode(height_m[shown & judged]))
        shown_mode = ~np.isnan(t_mode) & (t_mode > 0) & judged
        if not shown_mode.any():
            return none
    else:
        judged = ~_no_board_columns(cols, rows, p_board)
    t, shown, height_m = t_mode, shown_mode, t_mode / px_per_m
    median = float(np.median(height_m[shown]))
    agree = shown & (height_m > 0.5 * median) & (height_m < 1.5 * median)
    # A board in dashes (its lower edge too faint for the rules in some columns, as on a
    # grained floor) is cut whole where the board model sees it between the dashes.
    return _bridge(cols, rows, np.where(agree, height_m, np.nan), p_board >= FLOOR.skirting.seen_p) * px_per_m * judged


def trim_skirting(image: np.ndarray, mask: np.ndarray, calibration,
                  board_at=None, extend: bool = False) -> tuple[np.ndarray, float | None, tuple[int, int] | None]:
    """Remove the skirting board from the top of a floor mask.

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        The photo. Not modified.
    mask : (rows, cols) bool
        Floor mask at the photo's size. Not modified.
    calibration : Calibration
        The photo's calibration, to know how tall a board looks at each wall.
    board_at : (n, 2) array_like of float, optional
        Photo pixels ``x, y`` the user marked not floor. One on the strip at the top of
        a wall's floor makes that wall's strip a board, whatever the board model and the
        shade rule say (a board darker than the floor and of its hue looks like shade).
    extend : bool
        Where no board is trimmed, move the mask's edge up to the floor line instead
        (:func:`extend_to_floor_line`, on the same columns).

    Returns
    -------
    mask : (rows, cols) bool
        The mask without the board; when the photo shows none, the same values, or with
        ``extend`` the mask extended to the floor line.
    height_m : float or None
        The board's height when it was trimmed.
    doubt_px : (x, y) int or None
        Where a board may have been left: on the strip of a wall left uncut that the board
        model leans to a board on (``FLOOR.skirting.doubt_p``), most often a board the
        floor's colour. A "not floor" click there (``board_at``) trims that wall.
    """
    rows_px, cols_px = mask.shape
    view = working_view(image, mask, calibration)
    if view is None:
        return mask.copy(), None, None
    scale, small_image, small_mask, small_cal, cols, rows, px_per_m = view
    profiles = _profiles_of(view)

    def no_board(doubt_px=None):
        return (_extended(mask, view, profiles) if extend else mask.copy()), None, doubt_px

    profile, scalars, whole = profiles()
    p_board = board_probability(profile, scalars)
    p_mean = float(np.mean(p_board[whole] if whole.any() else p_board))
    walls = _walls(cols, rows)
    clicked = np.zeros(len(cols), bool)
    if board_at is not None and len(board_at):
        clicked = _walls_clicked(walls, cols, rows, px_per_m, np.asarray(board_at, np.float64)[:, :2] * scale,
                                 FLOOR.skirting.board_click_reach * max(small_mask.shape))
    rules_px = _rules_cut(small_image, small_mask, cols, rows, px_per_m, p_board, p_mean, whole, walls, clicked)
    # A board the floor's colour shows the rules no step to cut at, in some columns or in
    # all: where the board model is sure of a wall's board, that wall is cut too, unless
    # the photo as a whole leans to no board and the rules see no step on that wall.
    sure = _walls_with_a_board(walls, p_board, whole)
    if p_mean < FLOOR.skirting.alone_p:
        for wall in walls:
            sure[wall] &= (rules_px[wall] > 0).any()
    # Nor does it show them a strip of one height to cut on a wall the user clicked; the
    # click says the board is there, and the depth model says how tall.
    sure |= clicked
    depth_px = _cut_depth_px(view, walls, rules_px, (rules_px > 0) | sure, profiles)
    # A strip along a wall with a board standing above it is floor (a second floor's
    # strip past a threshold reads like a board): that wall keeps it, unless clicked.
    above = _board_above(view) if (depth_px > 0).any() else None
    for wall in walls if above is not None else ():
        if (len(wall) >= FLOOR.skirting.min_wall_columns and not clicked[wall].any()
                and np.mean(above[wall]) >= FLOOR.skirting.above_agreeing):
            depth_px[wall] = 0
    doubt_px = _board_doubt_px(view, walls, p_board, whole, depth_px, profiles)
    if doubt_px is not None:
        doubt_px = (min(doubt_px[0], cols_px - 1), min(doubt_px[1], rows_px - 1))
    if not (depth_px > 0).any():
        return no_board(doubt_px)
    cut = np.zeros(small_mask.shape, np.uint8)
    for col, row, n in zip(cols, rows, depth_px):
        if n > 0:
            # From a little above the top: at full size the mask's edge wavers by a pixel
            # around the working size's, and a sliver left above the cut is a spike.
            cut[max(0, row - 2):row + int(round(n)), col] = 1
    if scale < 1.0:
        cut = cv2.resize(cut, (cols_px, rows_px), interpolation=cv2.INTER_NEAREST)
    # The height to report is measured where the board stands: the mask's top is the
    # board's top, which lies on the floor beyond the wall, where a meter looks shorter.
    cut_cols = depth_px > 0
    at_foot = px_per_m_upright(small_cal, cols[cut_cols], rows[cut_cols] + depth_px[cut_cols])
    return mask & (cut == 0), float(np.median(depth_px[cut_cols] / at_foot)), doubt_px


def board_clicks(image: np.ndarray, mask: np.ndarray, calibration, points) -> np.ndarray:
    """Which clicks lie on the strip at the foot of a wall, where a "not floor" click
    marks a skirting board (``board_at`` of :func:`trim_skirting`).

    Parameters
    ----------
    image : (rows, cols, 3) uint8
        The photo. Not modified.
    mask : (rows, cols) bool
        Floor mask at the photo's size, not yet trimmed.
    calibration : Calibration
    points : (n, 2) array_like of float
        Photo pixels ``x, y``.

    Returns
    -------
    (n,) bool
        True for a point within ``FLOOR.skirting.board_click_reach`` across of a wall's
        column and from the mask's top edge there down by a board's greatest height
        (``FLOOR.skirting.max_height_m``).
    """
    points = np.asarray(points, np.float64).reshape(-1, 2)
    out = np.zeros(len(points), bool)
    view = working_view(image, mask, calibration) if mask.any() and len(points) else None
    if view is None:
        return out
    scale, _, small_mask, _, cols, rows, px_per_m = view
    walls = _walls(cols, rows)
    for i, point in enumerate(points):
        out[i] = _walls_clicked(walls, cols, rows, px_per_m, point[None] * scale,
                                FLOOR.skirting.board_click_reach * max(small_mask.shape)).any()
    return out


def _board_doubt_px(view, walls, p_board: np.ndarray, whole: np.ndarray, depth_px: np.ndarray,
                    profiles) -> tuple[int, int] | None:
    """Photo pixel ``x, y`` on the strip of the wall left uncut (in most of its columns)
    whose board model's mean probability is highest, at ``FLOOR.skirting.doubt_p`` or
    more: the middle of its strip, where a "not floor" click trims it. None when there is
    none."""
    scale, _, _, _, cols, rows, px_per_m = view
    best, best_p = None, FLOOR.skirting.doubt_p
    for wall in walls:
        if len(wall) < FLOOR.skirting.min_wall_columns or np.mean(depth_px[wall] > 0) >= 0.5:
            continue
        inside = wall[whole[wall]]
        p = float(np.mean(p_board[inside if len(inside) else wall]))
        if p >= best_p:
            best, best_p = wall, p
    if best is None:
        return None
    profile, scalars, _ = profiles()
    height_m = float(np.median(board_depth_m(profile[best], scalars[best])))
    mid = best[len(best) // 2]
    return (int(round(cols[mid] / scale)),
            int(round((rows[mid] + 0.5 * height_m * px_per_m[mid]) / scale)))
