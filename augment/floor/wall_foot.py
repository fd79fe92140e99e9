"""The floor reaches the wall's foot and stops there: a far strip the mask dropped, given
back; a thing against the wall the mask took in, cut off.

A second floor past a threshold near the far wall (a strip of carpet beyond planks), or a
band of sun along it, is often dropped whole by the floor model and GrabCut: the mask's
edge is the threshold, and the wall seems to stand there. The photo says otherwise where
a skirting board stands on the wall: the floor ends at the board's lower edge. A board
shows in a column as a step from the floor to a band of one colour 4.5-22 cm tall
(upright, through the calibration; a lit bevel along its top aside), ending in a sharp
step to a plain wall.

:func:`reach_wall_foot` looks up each column from the mask's edge for the lowest such
floor line. Where it is the mask's edge itself, the floor already ends at the wall, and
that column tells where the wall's foot runs. Higher up, a single column can be fooled
(a carton's lid looks like a board), so a strip is only given back along a straight line
that many columns agree on, whose boards' tops line up as well, over a tenth of the
photo's width at least in one stretch (then in its shorter stretches between things
standing before the wall too), where the strip is at most a third of a meter tall as seen
upright (taller is a thing standing in front of the wall), and where the wall's foot
and board seen beside it, at the mask's edge, run on along the same lines. A "board" read
at the mask's edge may be a board over a far strip of nearly its colour (dark carpet
under a dark board): where it parts at a sharp step into a board's height over a strip's,
each plain, the board's foot is that step (:func:`_split_boards`).

The other way round, where the mask's edge rises past a foot seen beside it and comes
back down to it within a meter, a carton or a radiator against the wall was taken for
floor, and the mask is cut along the foot (:func:`_things_on_the_foot`).

A sun patch ending a hand's width before the wall stops the mask at its edge, and the shaded
strip above reads with the board as one taller board: under one board's top, the higher of
two feet seen is the wall's (:func:`_one_board_two_feet`).

The thresholds and sizes are :data:`augment.floor.settings.FLOOR`'s ``wall_foot`` section.
"""
from __future__ import annotations

import cv2
import numpy as np
from skimage.measure import LineModelND, ransac

from .model import shrink_area
from .settings import FLOOR
from .skirting import px_per_m_upright, working_mask

CANDIDATES = 4  # floor lines kept per column, lowest first
K_STEP_PX = 4  # pixels per upright meter are worked out every this many rows and held between
EDGE_PX = 3  # a floor line this near the mask's edge (or a line) is at it
ADJACENT_PX = 2  # wall columns this far apart or nearer follow on in one stretch


class _Sums:
    """Running sums down each wall column of the band, (k, rows + 1, 3): any run of rows'
    mean colour and colour spread in a few operations, for many runs at once. ``band``: the
    photo's rows the search reads, (n, width, 3) float; ``cols``: the wall columns, (k,)."""

    def __init__(self, band: np.ndarray, cols: np.ndarray):
        # float32 sums: a column's squares run to about 4e7, each off by a few units, which
        # moves a spread of 7 over 20 rows by a few hundredths.
        profiles = np.ascontiguousarray(band[:, cols].transpose(1, 0, 2), np.float32)
        pad = np.zeros((profiles.shape[0], 1, 3), profiles.dtype)
        self.sums = np.concatenate([pad, np.cumsum(profiles, axis=1)], axis=1)
        self.squares = np.concatenate([pad, np.cumsum(profiles * profiles, axis=1)], axis=1)

    def mean(self, j, a, b) -> np.ndarray:
        """(..., 3) mean colour of rows ``a`` to ``b`` (exclusive) of columns ``j``."""
        return (self.sums[j, b] - self.sums[j, a]) / np.maximum(b - a, 1)[..., None]

    def spread(self, j, a, b) -> np.ndarray:
        """(...) colour spread (norm of the channels' standard deviations) of those rows."""
        n = np.maximum(b - a, 1)[..., None]
        m = (self.sums[j, b] - self.sums[j, a]) / n
        return np.sqrt(np.maximum((self.squares[j, b] - self.squares[j, a]) / n - m * m, 0).sum(axis=-1))


def _floor_lines(sums: _Sums, y0: int, cols, rows, reach, px_per_m) -> tuple[np.ndarray, np.ndarray]:
    """Per column ``cols[j]``, from ``rows[j] + EDGE_PX`` up to ``rows[j] - reach[j]``, the rows
    (lowest first, ``CANDIDATES`` at most) where the floor ends at a board, and the board's
    top row each, (k, CANDIDATES), -1 past the last. A line within ``EDGE_PX`` of the mask's
    edge is the only one kept (the floor ends there). ``sums``: the photo's rows from ``y0``
    down the columns; ``px_per_m[j, i]``: pixels per upright meter ``K_STEP_PX * i`` rows
    above the edge."""
    fw = FLOOR.wall_foot
    k, n = len(cols), sums.sums.shape[1] - 1
    # step[j, y]: between the three rows' mean colours from y down and the three above.
    step = np.zeros((k, n))
    if n >= 6:
        below = (sums.sums[:, 6:n] - sums.sums[:, 3:n - 3]) / 3
        above = (sums.sums[:, 3:n - 3] - sums.sums[:, :n - 6]) / 3
        step[:, 3:n - 3] = np.linalg.norm(below - above, axis=-1)
    steps = np.concatenate([np.zeros((k, 1)), np.cumsum(step, axis=1)], axis=1)
    padded = np.pad(step, ((0, 0), (2, 2)))
    peak2 = np.all([step >= padded[:, i:i + n] for i in (0, 1, 3, 4)], axis=0)
    peak1 = (step >= padded[:, 1:n + 1]) & (step >= padded[:, 3:n + 3])
    edge = (rows - y0).astype(np.int64)

    # The floor line: a step of floor_step or more, the strongest two rows either side.
    y = np.arange(n)[None]
    up = edge[:, None] - y
    j, r = np.nonzero((step >= fw.floor_step) & peak2 & (up >= -EDGE_PX) & (up <= reach[:, None]) & (y >= 5) & (y + 5 <= n))
    up = edge[j] - r
    p = px_per_m[j, np.maximum(up, 0) // K_STEP_PX]
    lo = np.maximum(5, (fw.board_m[0] * p).astype(np.int64))
    hi = (fw.board_m[1] * p).astype(np.int64) + 1
    wall = np.maximum(6, (fw.wall_m * p).astype(np.int64))
    fits = r - hi - wall - 3 >= 0
    j, r, up, lo, hi, wall = j[fits], r[fits], up[fits], lo[fits], hi[fits], wall[fits]

    # The board's top: the highest sharp step below a plain wall, out of the wall's noise.
    t, inside = _rows_between(r - hi, r - lo, n)
    jt, wt = j[:, None], wall[:, None]
    e = step[jt, t]
    good = inside & (e >= fw.board_step) & peak1[jt, t]
    good &= e >= fw.noise_factor * (steps[jt, t - 3] - steps[jt, t - wt]) / (wt - 3)
    a, b = np.nonzero(good)  # the dearest test, on what passed the others
    good[a, b] = sums.spread(j[a], t[a, b] - wall[a], t[a, b] - 1) <= fw.plain
    found = good.any(axis=1)
    top = t[np.arange(len(t)), np.argmax(good, axis=1)]
    j, r, up, wall, top = j[found], r[found], up[found], wall[found], top[found]

    # A plain board, of another colour than the wall above it, whose top step is sharp; a
    # board at the mask's edge may be shaded along its height (a moulded one).
    at_edge = up <= EDGE_PX
    limit = np.where(at_edge, 1.5 * fw.plain, fw.plain)
    keep = sums.spread(j, top + 1, r - 1) <= limit
    board, wall_colour = sums.mean(j, top + 1, r - 1), sums.mean(j, top - wall, top - 1)
    # A board with a lit (or shaded) bevel along its top: its first two rows unlike both the
    # wall and the board's face, which is plain below the bevel.
    face = _below_bevel(top, r)
    bevel, face_colour = sums.mean(j, top + 1, top + 3), sums.mean(j, face, r - 1)
    bevelled = (~keep & (sums.spread(j, face, r - 1) <= limit)
                & (np.linalg.norm(bevel - face_colour, axis=-1) >= fw.floor_step)
                & (np.linalg.norm(bevel - wall_colour, axis=-1) >= fw.floor_step))
    keep |= bevelled
    board[bevelled] = face_colour[bevelled]
    contrast = np.linalg.norm(board - wall_colour, axis=-1)
    keep &= (contrast >= fw.board_step) & (step[j, top] >= fw.sharpness * contrast)
    # The strip given back is not more of the wall above the board.
    strip = edge[j] - 1 - (r + 2) >= 3
    keep &= ~strip | (np.linalg.norm(sums.mean(j, r + 2, edge[j] - 1) - wall_colour, axis=-1) >= fw.floor_step)
    j, r, up, top, at_edge, wall_colour = j[keep], r[keep], up[keep], top[keep], at_edge[keep], wall_colour[keep]

    # A "board" at the mask's edge that is a board over a far strip of another plain colour:
    # split where the board's foot steps sharply down to the strip.
    split = _split_boards(sums, step, peak2, j[at_edge], r[at_edge], top[at_edge], wall_colour[at_edge],
                          px_per_m[j[at_edge], 0])
    r[np.flatnonzero(at_edge)[split >= 0]] = split[split >= 0]
    up = edge[j] - r
    at_edge = up <= EDGE_PX

    # Lowest first per column; a line at the edge ends the column's search.
    order = np.lexsort((up, j))
    j, r, up, top, at_edge = j[order], r[order], up[order], top[order], at_edge[order]
    first = np.searchsorted(j, j)
    rank = np.arange(len(j)) - first
    keep = (rank < CANDIDATES) & ~at_edge[first] | (rank == 0)
    lines = np.full((k, CANDIDATES), -1, np.int64)
    tops = np.full_like(lines, -1)
    lines[j[keep], rank[keep]] = r[keep] + y0
    tops[j[keep], rank[keep]] = top[keep] + y0
    return lines, tops


def _rows_between(first: np.ndarray, last: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``first[i]``, ``first[i] + 1``, ... for each i, as many as the longest run needs
    (held within the band's ``n`` rows), (k, m), and which of them are ``last[i]`` or before."""
    t = first[:, None] + np.arange(max(int((last - first).max(initial=0)) + 1, 1))[None]
    return np.minimum(t, n - 1), t <= last[:, None]


def _below_bevel(top, foot):
    """The first row of a board's face, from its top row to its foot: below a lit bevel
    ``FLOOR.wall_foot.bevel_share`` of its height at most."""
    return top + 1 + (FLOOR.wall_foot.bevel_share * (foot - top)).astype(np.int64)


def _split_boards(sums: _Sums, step, peak2, j, r, top, wall_colour, px_per_m) -> np.ndarray:
    """Per board (column ``j``, floor line ``r`` and top ``top`` in the band's rows, the
    wall's colour above it, pixels per upright meter), the row where it is a board of
    ``FLOOR.wall_foot.board_m[0]`` or more over a strip of ``FLOOR.wall_foot.strip_m[0]`` or
    more upright, each plain, of colours a board's step apart, parted by a sharp step, the
    strip not of the wall's colour; -1 where none. ``step``, ``peak2``: as in
    :func:`_floor_lines`."""
    fw = FLOOR.wall_foot
    found = np.full(len(j), -1, np.int64)
    if len(j) == 0:
        return found
    lo = top + np.maximum(3, (fw.board_m[0] * px_per_m).astype(np.int64))
    hi = r - np.maximum(3, (fw.strip_m[0] * px_per_m).astype(np.int64))
    t, ok = _rows_between(lo, hi, step.shape[1])
    jt = j[:, None]
    ok &= (step[jt, t] >= fw.board_step) & peak2[jt, t]
    a, b = np.nonzero(ok)
    tt = t[a, b]
    face = _below_bevel(top[a], tt)
    upper, lower = sums.mean(j[a], face, tt - 1), sums.mean(j[a], tt + 2, r[a] - 1)
    apart = np.linalg.norm(upper - lower, axis=-1)
    good = ((sums.spread(j[a], face, tt - 1) <= fw.plain) & (sums.spread(j[a], tt + 2, r[a] - 1) <= fw.plain)
            & (apart >= fw.board_step) & (step[j[a], tt] >= fw.sharpness * apart)
            & (np.linalg.norm(lower - wall_colour[a], axis=-1) >= fw.floor_step))
    ok[a[~good], b[~good]] = False
    strength = np.where(ok, step[jt, t], -1.0)
    best = np.argmax(strength, axis=1)
    has = ok.any(axis=1)
    found[has] = t[has, best[has]]
    return found


def _straight_lines(x: np.ndarray, y: np.ndarray, least: int) -> list[tuple[float, float, np.ndarray]]:
    """Lines ``y = slope * x + intercept`` through ``least`` or more of the points, one
    after another (RANSAC): (slope, intercept, indices of its points)."""
    fw = FLOOR.wall_foot
    left = np.arange(len(x))
    found = []
    rng = np.random.default_rng(0)
    while len(left) >= least and len(found) < fw.most_lines:
        points = np.column_stack([x[left], y[left]])
        if np.ptp(points[:, 0]) == 0:
            break
        _, inliers = ransac(points, LineModelND, min_samples=2, residual_threshold=fw.line_px,
                            max_trials=fw.line_trials, rng=rng)
        if inliers is None or inliers.sum() < least or np.ptp(points[inliers, 0]) == 0:
            break
        slope, intercept = np.polyfit(points[inliers, 0], points[inliers, 1], 1)
        on = np.abs(points[:, 1] - (slope * points[:, 0] + intercept)) <= fw.line_px
        found.append((float(slope), float(intercept), left[on]))
        left = left[~on]
    return found


def _runs(index: np.ndarray, cols: np.ndarray, least: int) -> list[np.ndarray]:
    """``index`` (into ``cols``, ascending) in runs whose gaps are at most
    ``FLOOR.wall_foot.gap_px`` columns, of ``least`` columns or more."""
    if len(index) == 0:
        return []
    breaks = np.flatnonzero(np.diff(cols[index]) > FLOOR.wall_foot.gap_px) + 1
    return [run for run in np.split(index, breaks) if len(run) >= least]


def _lined_up(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(n,) bool: the points on the line most of them are on."""
    slope, intercept = np.polyfit(x, y, 1)
    on = np.abs(y - (slope * x + intercept)) <= FLOOR.wall_foot.line_px
    if on.mean() < FLOOR.wall_foot.lined_up and on.sum() > 2:
        slope, intercept = np.polyfit(x[on], y[on], 1)
        on = np.abs(y - (slope * x + intercept)) <= FLOOR.wall_foot.line_px
    return on


def _at(line: tuple[float, float], x) -> np.ndarray:
    return line[0] * np.asarray(x, np.float64) + line[1]


def reach_wall_foot(image: np.ndarray, mask: np.ndarray, calibration) -> np.ndarray:
    """Give the floor mask back its far strips, up to the wall's foot where a board marks it,
    and cut it along that foot where a thing against the wall rose past it.

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
        The mask with the strips between its edge and the wall's foot added and what rose
        past the foot taken out, or the same values where the photo shows neither.
    """
    fw = FLOOR.wall_foot
    rows_px, cols_px = mask.shape
    scale, small_mask, small_cal, cols, rows, _ = working_mask(mask, calibration)
    size = small_mask.shape[::-1]
    least = max(FLOOR.skirting.min_wall_columns, int(fw.min_width_share * size[0]))
    if len(cols) < least:
        return mask.copy()
    reach, px_per_m = _search_window(small_cal, cols, rows)
    band, y0 = _band_at(image, size, scale, cols, rows, reach, px_per_m)
    sums = _Sums(band, cols)
    lines, tops = _floor_lines(sums, y0, cols, rows, reach, px_per_m)

    at_edge = (lines >= 0) & (rows[:, None] - lines <= EDGE_PX)
    seen = _feet_seen(small_cal, cols, rows, at_edge, tops)
    seen, top_row = _one_board_two_feet(sums, y0, cols, rows, px_per_m[:, 0], seen)
    change = np.zeros(small_mask.shape, np.int8)  # 1: floor given back, -1: taken out
    lines[at_edge] = -1
    if (lines >= 0).any(axis=1).sum() >= least:  # a stretch of wall shows its foot above the mask's edge
        top_row = np.minimum(top_row, _foot_rows(small_cal, cols, rows, lines, tops, px_per_m, seen, least))
    for col, row, top in zip(cols, rows, top_row):
        if np.isfinite(top) and top < row:
            change[max(0, round(float(top))):row, col] = 1
    for col, foot in zip(*_things_on_the_foot(small_cal, cols, rows, size[0], at_edge.any(axis=1), seen)):
        change[:max(0, round(float(foot))), col] = -1
    if not change.any():
        return mask.copy()
    if scale < 1.0:
        change = cv2.resize(change, (cols_px, rows_px), interpolation=cv2.INTER_NEAREST)
    return (mask | (change > 0)) & (change >= 0)


def _feet_seen(calibration, cols, rows, at_edge, tops) -> list:
    """The walls' feet where the floor already ends at a board (``at_edge`` (k, n) bool:
    the columns' floor lines at the mask's edge): (foot line, board top line, first and
    last column) per stretch of wall whose boards' tops run along the foot."""
    fw = FLOOR.wall_foot
    least = FLOOR.skirting.min_wall_columns
    seen = []
    edge_cols = np.flatnonzero(at_edge.any(axis=1))
    edge_tops = np.where(at_edge, tops, -1).max(axis=1).astype(np.float64)
    for slope, intercept, on in _straight_lines(cols[edge_cols].astype(np.float64),
                                                rows[edge_cols].astype(np.float64), least):
        for run in _runs(edge_cols[on], cols, least):
            x = cols[run].astype(np.float64)
            lined = _lined_up(x, edge_tops[run])
            if lined.mean() < fw.lined_up:
                continue  # tops all over: no board
            board = tuple(np.polyfit(x[lined], edge_tops[run][lined], 1))
            if _a_board(calibration, (slope, intercept), board, x[[0, -1]]):
                seen.append(((slope, intercept), board, cols[run[0]], cols[run[-1]]))
    return seen


def _one_board_two_feet(sums: _Sums, y0: int, cols, rows, px_per_m, seen) -> tuple[list, np.ndarray]:
    """The stretches of wall ``seen`` at the mask's edge that are far strips, and per column
    the row the floor reaches (inf: its edge stays), (k,).

    Two stretches whose boards' tops run on one line, one foot lower than the other, with
    the strip between the feet not plain: the lower foot is a far strip's edge (a sun
    patch's, a threshold's), the strip read with the board as one taller board, and the
    floor reaches the higher foot, over the lower stretch, the columns between the two and
    on while the strip goes on, where it is ``FLOOR.wall_foot.strip_m`` tall upright at
    most. (A plain strip is the board's own foot under a moulding line.) ``sums``, ``y0``:
    as for :func:`_floor_lines`; ``px_per_m``: pixels per upright meter at the mask's edge,
    (k,). Returns the stretches that are not far strips, and the rows."""
    fw = FLOOR.wall_foot
    top_row = np.full(len(cols), np.inf)
    strips = set()
    for a, (foot, board, lo, hi) in enumerate(seen):
        for b, (other_foot, other_board, other_lo, other_hi) in enumerate(seen):
            ends = np.array([lo, hi, other_lo, other_hi], np.float64)
            # (A strip with no rows to read has a nan spread: not a strip.)
            if (a == b or np.abs(_at(board, ends) - _at(other_board, ends)).max() > fw.clash_px
                    or np.min(_at(other_foot, ends) - _at(foot, ends)) <= EDGE_PX
                    or not _spread_between(sums, y0, cols, (other_lo, other_hi), foot, other_foot) > fw.plain):
                continue
            line = _at(foot, cols)
            fill = (rows - line > EDGE_PX) & (rows - line <= fw.strip_m[1] * px_per_m)
            # From the higher stretch's near end to the lower stretch's far end, then on.
            first, last = np.searchsorted(cols, min(other_lo, hi)), np.searchsorted(cols, max(other_hi, lo), "right") - 1
            first, last = _walk(cols, fill, first, -1), _walk(cols, fill, last, 1)
            span = np.arange(first, last + 1)[fill[first:last + 1]]
            top_row[span] = np.minimum(top_row[span], line[span])
            strips.add(b)
    return [s for i, s in enumerate(seen) if i not in strips], top_row


def _walk(cols, ok, j: int, step: int) -> int:
    """The last index reached from ``j`` stepping by ``step`` (1 or -1) through indices
    where ``ok`` holds and ``cols`` stay within ``ADJACENT_PX`` of the one before: one
    stretch of wall."""
    while 0 <= j + step < len(cols) and ok[j + step] and abs(int(cols[j + step]) - int(cols[j])) <= ADJACENT_PX:
        j += step
    return j


def _spread_between(sums: _Sums, y0: int, cols, span: tuple[int, int], upper, lower) -> float:
    """The median over the columns ``cols`` within ``span`` of the colour spread down each
    between the lines ``upper`` and ``lower``, two rows in from each (``sums``: the band's
    rows from ``y0``); nan where no column has three rows there."""
    j = np.flatnonzero((cols >= span[0]) & (cols <= span[1]))
    n = sums.sums.shape[1] - 1
    a = np.clip(np.round(_at(upper, cols[j])).astype(np.int64) + 2 - y0, 0, n)
    b = np.clip(np.round(_at(lower, cols[j])).astype(np.int64) - 1 - y0, 0, n)
    tall = b - a >= 3
    return float(np.median(sums.spread(j[tall], a[tall], b[tall]))) if tall.any() else np.nan


def _things_on_the_foot(calibration, cols, rows, width, at_edge, seen) -> tuple[np.ndarray, np.ndarray]:
    """The columns where the mask rises past a wall's foot seen beside them, and the foot's
    row there: (columns, rows). Next to a stretch of wall whose floor ends at its board, a
    mask edge higher than the foot (by ``FLOOR.wall_foot.rise_m`` upright), with no board
    on it, that comes back down to the foot (or runs out of the photo) within
    ``FLOOR.wall_foot.thing_m`` is a thing standing against the wall that GrabCut took
    for floor: on the floor plane a carton's lid lies beyond the wall. Floor past a
    corner of the room goes on farther, and ends at a board; a mask edge that runs along
    the board's top says the "board" was a far strip of floor, which the mask reached.
    ``at_edge`` (k,) bool: the columns whose own floor line is the mask's edge (within
    ``EDGE_PX``, the tolerance here too); ``width``: the mask's; ``calibration`` at its size."""
    fw = FLOOR.wall_foot
    cut = np.full(len(cols), np.nan)
    for foot, board, first, last in seen:
        line = _at(foot, cols)
        rise = line - rows
        above = (rise > EDGE_PX) & ~at_edge
        px_per_m = np.zeros(len(cols))
        px_per_m[above] = px_per_m_upright(calibration, cols[above], line[above])
        above &= rise > fw.rise_m * px_per_m
        on_foot = np.abs(rise) <= EDGE_PX
        for end, step in ((np.searchsorted(cols, first), -1), (np.searchsorted(cols, last, "right") - 1, 1)):
            j = _walk(cols, on_foot, end, step) + step  # past the foot's columns at the mask's edge
            if not (0 <= j < len(cols) and above[j]):
                continue
            run = np.arange(j, _walk(cols, above, j, step) + step, step)
            far = np.abs(cols[run] - cols[j]) > fw.thing_m * px_per_m[run]
            if far.any():
                run = run[:np.argmax(far)]
            j = run[-1] + step
            out_of_photo = (j < 0 or j >= len(cols)) and cols[run[-1]] in (0, width - 1)
            back = 0 <= j < len(cols) and abs(int(cols[j]) - int(cols[run[-1]])) <= ADJACENT_PX and on_foot[j]
            # A mask edge along the board's top: the "board" beside it was a far strip of floor.
            strip = np.mean(np.abs(rows[run] - _at(board, cols[run])) <= EDGE_PX) >= 0.5
            if (out_of_photo or back) and not strip:
                cut[run] = line[run]
    keep = np.isfinite(cut)
    return cols[keep], cut[keep]


def _foot_rows(calibration, cols, rows, lines, tops, px_per_m, seen, least) -> np.ndarray:
    """(k,) the row the floor reaches in each column (inf: its edge stays): along straight
    feet that ``least`` columns or more in one stretch found above the mask's edge
    (``lines``, ``tops``: from :func:`_floor_lines`), with their boards' tops on a line too,
    a board's height above, a strip of a strip's height below (``FLOOR.wall_foot.strip_m``),
    and no foot or board ``seen`` beside them running elsewhere (:func:`_clashes`)."""
    fw = FLOOR.wall_foot
    j, n = np.nonzero(lines >= 0)
    x, y, board_y = cols[j].astype(np.float64), lines[j, n].astype(np.float64), tops[j, n].astype(np.float64)
    top_row = np.full(len(cols), np.inf)
    for slope, intercept, on in _straight_lines(x, y, least):
        lined = _lined_up(x[on], board_y[on])
        if lined.mean() < fw.lined_up:
            continue
        foot = (slope, intercept)
        board = tuple(np.polyfit(x[on][lined], board_y[on][lined], 1))
        runs = _runs(np.unique(j[on[lined]]), cols, FLOOR.skirting.min_wall_columns)
        if not any(len(run) >= least for run in runs):
            continue
        for run in runs:  # one wall's foot, seen between the things standing before it
            strip_m = np.median((rows[run] - _at(foot, cols[run])) / px_per_m[run, 0])
            if (not fw.strip_m[0] <= strip_m <= fw.strip_m[1]
                    or not _a_board(calibration, foot, board, cols[run[[0, -1]]].astype(np.float64))
                    or _clashes(foot, board, cols[run[0]], cols[run[-1]], seen)):
                continue
            span = np.flatnonzero((cols >= cols[run[0]]) & (cols <= cols[run[-1]]))
            line = _at(foot, cols[span])
            # Between the columns that saw it too, where the strip is no taller than one may be.
            keep = rows[span] - line <= fw.strip_m[1] * px_per_m[span, 0]
            top_row[span[keep]] = np.minimum(top_row[span[keep]], line[keep])
    return top_row


def _a_board(calibration, foot, board, x: np.ndarray) -> bool:
    """Whether the line ``board`` stands over the line ``foot`` as a board's top does, at
    columns ``x``: one board's height (``FLOOR.wall_foot.board_m``) above it at each,
    upright through ``calibration``. A top line at another slope is another wall's board."""
    foot_y = _at(foot, x)
    tall_m = (foot_y - _at(board, x)) / px_per_m_upright(calibration, x, foot_y)
    lo, hi = FLOOR.wall_foot.board_m
    return bool(np.all((tall_m >= 0.8 * lo) & (tall_m <= 1.2 * hi))
                and np.ptp(tall_m) <= FLOOR.wall_foot.board_spread * np.max(tall_m))


def _clashes(foot, board, lo: int, hi: int, seen) -> bool:
    """Whether a wall's foot or board seen at the mask's edge near columns ``lo``-``hi``
    runs elsewhere than ``foot`` and ``board``, where the two meet: something stands before
    the wall there (a carton), or the line is another wall's."""
    near, off = FLOOR.wall_foot.gap_px, FLOOR.wall_foot.clash_px
    for seen_foot, seen_board, a, b in seen:
        if b < lo - near or a > hi + near:
            continue
        ends = np.array([np.clip(a, lo, hi), np.clip(b, lo, hi), np.clip(lo, a, b), np.clip(hi, a, b)], np.float64)
        if np.abs(_at(seen_board, ends) - _at(foot, ends)).max() <= off:
            continue  # what stood on the mask's edge there like a board is the strip itself, up to this foot
        if np.abs(_at(seen_foot, ends) - _at(foot, ends)).max() > off or np.abs(
                _at(seen_board, ends) - _at(board, ends)).max() > off:
            return True
    return False


def _band_at(image: np.ndarray, size: tuple[int, int], scale: float, cols, rows, reach,
             px_per_m) -> tuple[np.ndarray, int]:
    """The rows of the photo the search reads, at the working ``size`` as float32, each
    pixel the mean of five along its row (a wall's foot is nearly level: the column reads
    through the noise), and the first row's index (a 12 MP photo is shrunk a band, not
    whole)."""
    fw = FLOOR.wall_foot
    reads_px = np.ceil((fw.board_m[1] + fw.wall_m) * px_per_m.max(axis=1)).astype(int)
    y0 = max(0, int((rows - reach - reads_px).min()) - 12)
    y1 = min(size[1], int(rows.max()) + 12)
    if scale < 1:
        band = shrink_area(image[int(y0 / scale):min(image.shape[0], int(np.ceil(y1 / scale)) + 1)], (size[0], y1 - y0))
    else:
        band = image[y0:y1]
    return cv2.blur(band.astype(np.float32), (5, 1)), y0


def _search_window(calibration, cols: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per column, how many rows above the mask's edge the floor is looked for (below the
    horizon, where the lens model reaches, ``FLOOR.wall_foot.reach_m`` beyond the edge on
    the floor at most), and pixels per upright meter every ``K_STEP_PX`` rows up from the
    edge, (k, m)."""
    steps = np.arange(0, int(rows.max()) + K_STEP_PX, K_STEP_PX)
    r = rows[:, None] - steps[None]
    c = np.broadcast_to(cols[:, None], r.shape)
    a, b, h = calibration.horizon
    inside = (r >= 0) & (a * c + b * r + h > 2.0)
    inside[inside] = calibration.lens_maps(np.column_stack([c[inside], r[inside]]))
    points = np.column_stack([c[inside], r[inside]]).astype(np.float64)
    camera = np.linalg.inv(calibration.camera_from_floor)[:2, 3]
    distance = np.full(r.shape, np.inf)
    distance[inside] = np.hypot(*(calibration.floor_from_pixels(points) - camera).T)
    within = inside & (distance - distance[:, :1] <= FLOOR.wall_foot.reach_m)
    # The search stops at the first row out of reach.
    last = np.where(within.all(axis=1), within.shape[1], np.argmin(within, axis=1)) - 1
    reach = np.maximum(last, 0) * K_STEP_PX
    px_per_m = np.ones(r.shape)
    px_per_m[within] = px_per_m_upright(calibration, c[within], r[within])
    return reach.astype(np.int64), px_per_m
