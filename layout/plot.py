"""Pictures of layouts: top-down floor plans and energy traces.

Figures are built on :class:`matplotlib.figure.Figure` directly (never pyplot), so
plotting touches no global state and needs no display. Files are written atomically:
a reader never sees a half-written image.
"""
from __future__ import annotations

import io
import zlib
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Polygon as PolygonPatch

from .fileio import atomic_path, write_atomic

DPI = 120
_SAVE = {"dpi": DPI, "bbox_inches": "tight"}
# Longest side of the plan's axes box; the margins for labels come on top of it.
_MAX_AXES_IN = 9.0
_MARGIN_IN = {"left": 0.75, "right": 0.25, "bottom": 0.6, "top": 0.45}
_PAD_M = 0.45
_WALL_PT = 4.0
# Mean advance of a DejaVu Sans character as a fraction of the font size.
_CHAR_EM = 0.62
_MIN_FONT_PT = 4.5
_MAX_FONT_PT = 11.0
_FLOOR_COLOR = "#f3efe6"
_WALL_COLOR = "#2b2b2b"
_DOOR_COLOR = "#9c5a1c"
_WINDOW_COLOR = "#8cc8f0"
# Light colors keep dark label text legible on the footprints; Set3's salmon is left
# out because red marks overlapping items.
_PALETTE = tuple(c for i, c in enumerate(matplotlib.colormaps["Set3"].colors) if i != 3)


def _kind_color(kind):
    # A hash of the name, not its rank in this plot, gives a kind the same color in
    # every plan.
    return _PALETTE[zlib.crc32(kind.encode("utf-8")) % len(_PALETTE)]


def _array(value, shape, name):
    """``value`` as float64 with ``shape`` (``None`` entries match any length)."""
    a = np.asarray(value, dtype=np.float64)
    if a.ndim != len(shape) or any(s is not None and s != t for s, t in zip(shape, a.shape)):
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _optional(value, shape, name):
    if value is None:
        return np.zeros([0 if s is None else s for s in shape])
    return _array(np.asarray(value, dtype=np.float64).reshape((-1,) + shape[1:]), shape, name)


def figure_png(fig) -> bytes:
    """``fig`` as PNG bytes, cropped to what it draws."""
    buffer = io.BytesIO()
    # zlib's fastest level: plans are flat colours, so files grow by a fifth while
    # encoding takes a third of the time.
    fig.savefig(buffer, format="png", pil_kwargs={"compress_level": 1}, **_SAVE)
    return buffer.getvalue()


def _save_atomic(fig, path):
    path = Path(path)
    if path.suffix.lower() in ("", ".png"):
        write_atomic(path, figure_png(fig))
        return
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=path.suffix[1:], **_SAVE)


def plan_figure(
    polygon_m,
    corners_m,
    labels,
    yaw_rad,
    *,
    door_zones_m=None,
    door_segments_m=None,
    window_segments_m=None,
    lanes_m=None,
    overlap_pairs=None,
    title="",
    access_corners_m=None,
    access_depth_m=None,
    kinds=None,
    open_edges=(),
):
    """Top-down plan of a furnished room.

    Parameters
    ----------
    polygon_m : (m, 2) array_like
        Floor polygon in meters, counter-clockwise.
    corners_m : (n, 4, 2) array_like
        Footprint corners in meters (as from :func:`layout.geometry.box_corners`).
    labels : sequence of str, length n
        Text written inside each footprint; dropped where it cannot be read.
    yaw_rad : (n,) array_like
        Facing direction of each item; an arrow points from its center to its front.
    door_zones_m : (d, 4, 2) array_like, optional
        Clearance zone in front of each door, drawn lightly filled.
    door_segments_m : (d, 2, 2) array_like, optional
        Door openings on the walls, drawn as a colored gap in the wall.
    window_segments_m : (w, 2, 2) array_like, optional
        Windows on the walls, drawn as a double light-blue line.
    lanes_m : (l, 2, 2) array_like, optional
        Traffic-lane segments, drawn dashed.
    overlap_pairs : (k, 2) array_like of int, optional
        Pairs of overlapping items; both are drawn in red.
    title : str
    access_corners_m : (n, 4, 4, 2) array_like, optional
        Access rectangles (from :func:`layout.geometry.access_box_corners`), hatched.
    access_depth_m : (n, 4) array_like, optional
        Access depth per side in meters; sides of depth 0 are not drawn. Required with
        ``access_corners_m``.
    kinds : sequence of str, length n, optional
        Item categories; footprints of one kind share a color. Defaults to ``labels``.
    open_edges : iterable of int, optional
        Edges (k = corner k to k + 1) that are not walls, drawn as a thin dashed line.

    Returns
    -------
    fig : matplotlib.figure.Figure
        Axes in meters with equal aspect; the figure is sized to the room, with the
        longer side of the axes 9 in.
    """
    polygon = _array(polygon_m, (None, 2), "polygon_m")
    if len(polygon) < 3:
        raise ValueError("polygon_m needs at least 3 vertices")
    corners = _array(corners_m, (None, 4, 2), "corners_m")
    n = len(corners)
    yaw = _array(yaw_rad, (n,), "yaw_rad")
    labels = [str(s) for s in labels]
    kinds = labels if kinds is None else [str(s) for s in kinds]
    if len(labels) != n or len(kinds) != n:
        raise ValueError(f"labels and kinds must have {n} entries")
    zones = _optional(door_zones_m, (None, 4, 2), "door_zones_m")
    doors = _optional(door_segments_m, (None, 2, 2), "door_segments_m")
    windows = _optional(window_segments_m, (None, 2, 2), "window_segments_m")
    lanes = _optional(lanes_m, (None, 2, 2), "lanes_m")
    pairs = np.asarray([] if overlap_pairs is None else overlap_pairs, dtype=np.int64)
    pairs = pairs.reshape(-1, 2)
    if np.any((pairs < 0) | (pairs >= n)):
        raise ValueError("overlap_pairs must index items")
    if (access_corners_m is None) != (access_depth_m is None):
        raise ValueError("access_corners_m and access_depth_m go together")
    access = _optional(access_corners_m, (n, 4, 4, 2), "access_corners_m")
    access_depth = _optional(access_depth_m, (n, 4), "access_depth_m")

    points = np.vstack(
        [polygon, corners.reshape(-1, 2), zones.reshape(-1, 2), doors.reshape(-1, 2),
         windows.reshape(-1, 2), lanes.reshape(-1, 2)]
    )
    lo, hi = points.min(axis=0) - _PAD_M, points.max(axis=0) + _PAD_M
    extent_m = hi - lo
    in_per_m = _MAX_AXES_IN / extent_m.max()
    axes_in = extent_m * in_per_m
    fig_w = axes_in[0] + _MARGIN_IN["left"] + _MARGIN_IN["right"]
    fig_h = axes_in[1] + _MARGIN_IN["bottom"] + _MARGIN_IN["top"]
    fig = Figure(figsize=(fig_w, fig_h), dpi=DPI)
    # A fixed axes box makes one meter a known number of points, so labels can be
    # sized to fit their footprint before drawing.
    ax = fig.add_axes(
        (_MARGIN_IN["left"] / fig_w, _MARGIN_IN["bottom"] / fig_h, axes_in[0] / fig_w,
         axes_in[1] / fig_h)
    )
    pt_per_m = in_per_m * 72.0
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)

    ax.add_patch(PolygonPatch(polygon, closed=True, facecolor=_FLOOR_COLOR, edgecolor="none", zorder=1))
    for i, k in zip(*np.nonzero(access_depth > 0)):
        ax.add_patch(
            PolygonPatch(access[i, k], closed=True, fill=False, hatch="////", edgecolor="#b8b8b8",
                         linewidth=0.4, zorder=2)
        )
    for zone in zones:
        ax.add_patch(
            PolygonPatch(zone, closed=True, facecolor="#f7dcb4", edgecolor="#d9a05b",
                         linestyle="--", linewidth=0.8, alpha=0.7, zorder=2)
        )
    for lane in lanes:
        ax.plot(lane[:, 0], lane[:, 1], color="#2e8b57", linewidth=1.5, linestyle=(0, (6, 4)), zorder=3)

    overlapping = np.zeros(n, dtype=bool)
    overlapping[pairs.ravel()] = True
    for i in range(n):
        box = corners[i]
        ax.add_patch(
            PolygonPatch(
                box,
                closed=True,
                facecolor="#ff8a80" if overlapping[i] else _kind_color(kinds[i]),
                edgecolor="#d50000" if overlapping[i] else "#555555",
                linewidth=2.0 if overlapping[i] else 0.8,
                alpha=0.9,
                zorder=4,
            )
        )
        center = box.mean(axis=0)
        depth = np.linalg.norm(box[1] - box[0])
        width = np.linalg.norm(box[2] - box[1])
        facing = np.array([np.cos(yaw[i]), np.sin(yaw[i])])
        ax.annotate(
            "",
            xy=center + 0.45 * depth * facing,
            xytext=center,
            arrowprops={"arrowstyle": "-|>", "color": "#333333", "linewidth": 0.9,
                        "shrinkA": 0, "shrinkB": 0, "mutation_scale": 8},
            zorder=5,
        )
        # Run the text along the longer side, turned so it never reads upside down.
        along_deg = np.degrees(yaw[i]) + (90.0 if width >= depth else 0.0)
        along_deg = (along_deg + 90.0) % 180.0 - 90.0
        long_pt, short_pt = max(width, depth) * pt_per_m, min(width, depth) * pt_per_m
        size_pt = min(
            0.9 * long_pt / (_CHAR_EM * max(len(labels[i]), 1)), 0.6 * short_pt, _MAX_FONT_PT
        )
        if labels[i] and size_pt >= _MIN_FONT_PT:
            ax.text(*center, labels[i], rotation=along_deg, rotation_mode="anchor", ha="center",
                    va="center", fontsize=size_pt, color="#1a1a1a", zorder=6, clip_on=True)

    ax.add_patch(
        PolygonPatch(polygon, closed=True, fill=False, edgecolor=_WALL_COLOR, linewidth=_WALL_PT,
                     joinstyle="miter", zorder=7)
    )
    for e in open_edges:
        # Floor color over the wall, then a dashed line: the floor goes on here.
        seg = polygon[[e, (e + 1) % len(polygon)]]
        ax.plot(seg[:, 0], seg[:, 1], color=_FLOOR_COLOR, linewidth=_WALL_PT + 1.0, solid_capstyle="butt", zorder=8)
        ax.plot(seg[:, 0], seg[:, 1], color=_WALL_COLOR, linewidth=1.0, linestyle=(0, (4, 3)), zorder=9)
    for seg in doors:
        # Floor color over the wall opens the gap; the thin line marks the door leaf.
        ax.plot(seg[:, 0], seg[:, 1], color=_FLOOR_COLOR, linewidth=_WALL_PT + 1.0,
                solid_capstyle="butt", zorder=8)
        ax.plot(seg[:, 0], seg[:, 1], color=_DOOR_COLOR, linewidth=1.6, solid_capstyle="butt", zorder=9)
    for seg in windows:
        # A white core on a wide blue stroke reads as the double line of a window.
        ax.plot(seg[:, 0], seg[:, 1], color=_WINDOW_COLOR, linewidth=_WALL_PT + 1.0,
                solid_capstyle="butt", zorder=8)
        ax.plot(seg[:, 0], seg[:, 1], color="white", linewidth=1.2, solid_capstyle="butt", zorder=9)

    bar = lo + np.array([0.15, 0.18])
    ax.plot([bar[0], bar[0] + 1.0], [bar[1], bar[1]], color="black", linewidth=2.5,
            solid_capstyle="butt", zorder=10)
    ax.text(bar[0] + 1.08, bar[1], "1 m", va="center", ha="left", fontsize=8, zorder=10)
    return fig


def plot_plan(path, polygon_m, corners_m, labels, yaw_rad, **options):
    """Write a top-down plan image (PNG unless ``path`` says otherwise).

    Parameters
    ----------
    path : str or os.PathLike
        Output file; replaced atomically.
    polygon_m, corners_m, labels, yaw_rad, **options
        As for :func:`plan_figure`.
    """
    _save_atomic(plan_figure(polygon_m, corners_m, labels, yaw_rad, **options), path)


def energy_figure(traces, title="", log=False):
    """Energy against iteration for one or more runs (Weiss et al., Fig. 17).

    Parameters
    ----------
    traces : dict of str to (t,) array_like
        Energy per iteration of each run or method, keyed by its legend label.
    title : str
    log : bool
        Logarithmic energy axis; all finite energies must then be positive.

    Returns
    -------
    fig : matplotlib.figure.Figure
    """
    if not traces:
        raise ValueError("traces is empty")
    series = {}
    for name, values in traces.items():
        v = np.asarray(values, dtype=np.float64)
        if v.ndim != 1 or len(v) == 0:
            raise ValueError(f"trace {name!r} must be a non-empty 1-D array, got {v.shape}")
        if log and np.any(v[np.isfinite(v)] <= 0):
            raise ValueError(f"trace {name!r} has energies <= 0, which a log axis cannot show")
        series[str(name)] = v
    fig = Figure(figsize=(7.0, 4.2), dpi=DPI)
    ax = fig.add_subplot()
    for name, v in series.items():
        ax.plot(np.arange(len(v)), v, label=name, linewidth=1.3)
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel("energy")
    ax.grid(alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    return fig


def plot_energy(path, traces, title="", log=False):
    """Write an energy-versus-iteration plot; see :func:`energy_figure`.

    Parameters
    ----------
    path : str or os.PathLike
        Output file (PNG unless its suffix says otherwise); replaced atomically.
    traces : dict of str to (t,) array_like
    title : str
    log : bool
    """
    _save_atomic(energy_figure(traces, title=title, log=log), path)
