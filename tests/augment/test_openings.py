"""Windows read off a wall's front-on strip (augment.room.openings), by hand-made strips
and on a sample photo with its truth."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from augment import pipeline
from augment.camera.board import Board
from augment.draw.settings import DRAW
from augment.room.openings import _window_spans
from augment.room.settings import ROOM

PHOTOS = Path(__file__).resolve().parents[2] / "samples" / "photos"
STEP = ROOM.doors.step_m
WALL = np.array([60.0, 4.0, 6.0], np.float32)  # Lab


def _strip(paint) -> tuple:
    """A 3 m wall sampled every 2 cm up to 2.4 m, all in view, ``paint(z, s)`` -> Lab."""
    z = (np.arange(120) + 0.5) * STEP
    s = (np.arange(150) + 0.5) * STEP
    Z, S = np.meshgrid(z, s, indexing="ij")
    strip = np.broadcast_to(WALL, (120, 150, 3)).copy()
    paint(strip, Z, S)
    return strip, np.ones((120, 150), bool)


def test_a_pane_on_a_wall_is_a_window_a_door_and_light_on_the_wall_are_not():
    """A pane (Lab 95, -2, -8) from 0.9 to 2.0 m up, 1.0-2.2 m along a wall of Lab (60, 4,
    6), is one window: its ends within a sample, sill 0.9 and top 2.0 m within a sample.
    The same pane from the floor up (a door) is none, and so is a pool of light
    brightening the wall smoothly to L 85 at 1.5 m up (no edge, no sill)."""
    def pane(strip, Z, S, bottom=0.9):
        strip[(Z >= bottom) & (Z < 2.0) & (S >= 1.0) & (S < 2.2)] = [95.0, -2.0, -8.0]

    strip, inside = _strip(pane)
    none = np.zeros(150, bool)
    ((i0, i1, sill, top),) = _window_spans(strip, inside, WALL, none, ROOM.doors)
    assert abs(i0 - 50) <= 1 and abs(i1 - 110) <= 1
    assert abs(sill - 0.9) <= STEP and abs(top - 2.0) <= STEP

    strip, inside = _strip(lambda st, Z, S: pane(st, Z, S, bottom=0.0))
    assert _window_spans(strip, inside, WALL, none, ROOM.doors) == []

    def pool(strip, Z, S):
        strip[..., 0] = 60.0 + 25.0 * np.exp(-((Z - 1.5) ** 2 + (S - 1.6) ** 2) / (2 * 0.45 ** 2))

    strip, inside = _strip(pool)
    assert (np.linalg.norm(strip - WALL, axis=-1)[60, 60:100] > ROOM.doors.min_difference).all()  # it differs
    assert _window_spans(strip, inside, WALL, none, ROOM.doors) == []
    # Where a door was found, no window.
    strip, inside = _strip(pane)
    assert _window_spans(strip, inside, WALL, np.arange(150) < 120, ROOM.doors) == []


def test_the_window_of_room_1_is_found_and_kept_free_of_tall_furniture():
    """room_1 (the synthetic photographer's, truth beside it): its window over the
    radiator is found within 15 cm of the true window's middle, its sill within 10 cm;
    the layout keeps furniture taller than the sill out of its zone (no overlap with the
    window's particle), the report lists it and the floor overlay outlines it."""
    from augment.synth.truth import true_doors_on_floor

    photo = PHOTOS / "room_1.jpg"
    result = pipeline.furnish(photo, Board(), suggestions=1, seed=0)
    truth = json.loads(photo.with_suffix(".json").read_text())
    (true,) = true_doors_on_floor(truth, result.calibration.camera_from_floor, "windows")
    (window,) = result.report["furniture"]["windows"]
    assert np.linalg.norm(np.subtract(window["at_m"], true.mean(axis=0))) < 0.15
    assert abs(window["sill_m"] - truth["room"]["windows"][0]["bottom_m"]) < 0.10
    (lay,), (rep,) = result.layouts, result.reports
    assert len(lay.model.window_segments_m) == 1 and rep["overlaps"]["count"] == 0
    overlay = result.overlays["overlay_floor.png"]
    assert (np.abs(overlay.astype(int) - DRAW.floor.window_color).max(axis=-1) < 30).sum() > 200


def test_panes_split_by_a_mullion_are_one_window_and_light_beside_it_is_not_part_of_it():
    """Two panes 1.0-1.6 and 1.74-2.2 m along, split by a 14 cm mullion the wall's colour,
    sill 0.6 m, top 1.5 m (a low window), are one window from 1.0 to 2.2 m; with light
    brightening the wall smoothly left of the window (L 60 -> 85 at 0.5 m along, 1.4 m
    up), the window still ends at 1.0 m, within two samples: the lit wall has no sill."""
    def panes(strip, Z, S):
        strip[(Z >= 0.6) & (Z < 1.5) & (S >= 1.0) & (S < 2.2) & ~((S >= 1.6) & (S < 1.74))] = [95.0, -2.0, -8.0]

    strip, inside = _strip(panes)
    none = np.zeros(150, bool)
    ((i0, i1, sill, top),) = _window_spans(strip, inside, WALL, none, ROOM.doors)
    assert abs(i0 - 50) <= 1 and abs(i1 - 110) <= 1
    assert abs(sill - 0.6) <= STEP and abs(top - 1.5) <= STEP

    def lit(strip, Z, S):
        strip[..., 0] = 60.0 + 25.0 * np.exp(-((Z - 1.4) ** 2 + (S - 0.5) ** 2) / (2 * 0.45 ** 2))
        panes(strip, Z, S)

    strip, inside = _strip(lit)
    assert (np.linalg.norm(strip - WALL, axis=-1)[60, 40:50] > ROOM.doors.min_difference).all()  # it differs
    ((i0, i1, _, _),) = _window_spans(strip, inside, WALL, none, ROOM.doors)
    assert abs(i0 - 50) <= 2 and abs(i1 - 110) <= 1


def test_a_transom_bar_the_walls_colour_is_not_the_windows_top():
    """Panes 0.9-1.7 m and, over an 8 cm bar the wall's colour, a transom 1.78-2.1 m up, 1.0
    to 2.2 m along: one window whose top is the transom's, 2.1 m (it stopped at the bar, 1.7
    m, and the transom's glass took the walls' shadows). A bar of 20 cm is wall between
    two windows: the top stays at 1.7 m."""
    def panes(bar_m):
        def paint(strip, Z, S):
            glass = (S >= 1.0) & (S < 2.2) & (((Z >= 0.9) & (Z < 1.7)) | ((Z >= 1.7 + bar_m) & (Z < 2.1)))
            strip[glass] = [95.0, -2.0, -8.0]
        return paint

    none = np.zeros(150, bool)
    for bar_m, top_m in ((0.08, 2.1), (0.2, 1.7)):
        strip, inside = _strip(panes(bar_m))
        ((i0, i1, sill, top),) = _window_spans(strip, inside, WALL, none, ROOM.doors)
        assert abs(i0 - 50) <= 1 and abs(i1 - 110) <= 1
        assert abs(sill - 0.9) <= STEP and abs(top - top_m) <= STEP, (bar_m, top)
