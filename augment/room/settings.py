"""The room stage's tuning: measuring the wall height, and fitting the furniture to the floor.

One mutable dataclass per module, each field with its reason, composed into :data:`ROOM`.
Code reads the values at call time (``ROOM.height.cluster_width``), so a caller, or a
test with ``monkeypatch.setattr(ROOM.height, "min_m", 2.0)``, can change one. Lengths
given as a fraction are of the photo's longer side unless the reason says otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class HeightSettings:
    """Wall height from vertical edges (:mod:`augment.room.height`)."""

    fallback_m: float = 2.5  # assumed when nothing trustworthy is in view
    min_m: float = 2.2  # rooms are at least 2.2 m high, doors 2.0-2.1 m: door frames fall below
    bound_min_m: float = 1.8  # a whole edge on the floor this tall or more bounds the height from below (doors)
    max_m: float = 5.0  # ... and at most this: plausible wall heights
    merge_gap_fraction: float = 0.015  # pieces of one edge merge across gaps up to this
    bridge_gap_fraction: float = 0.12  # ... and up to this where the image shows the edge in the gap
    bridge_contrast: float = 2.0  # ... as a gradient across it this many times the wall's beside it
    min_edge_fraction: float = 0.08  # a measured vertical edge spans at least this x the shorter side
    border_fraction: float = 0.01  # ends this close to the frame are cut off by it
    horizon_margin_fraction: float = 0.003  # a foot lies at least this far below the horizon
    junction_fraction: float = 0.012  # a line meets an end when it passes this close
    min_junction_fraction: float = 0.06  # ... and is at least this long
    floor_band_fraction: float = 0.02  # the mask is searched this far either side of a foot,
    floor_band_edge: float = 0.08  # ... or this x the edge's length if more (a baseboard's height)
    wall_straightness: float = 0.02  # feet of one wall lie this close to a line (x their distance)
    span_probe_fraction: np.ndarray = field(
        default_factory=lambda: np.array([0.05, 0.08, 0.11]))  # probed beyond a junction's ends
    floor_color_below: tuple[float, float] = (0.03, 0.15)  # a foot's floor colour is read this far below (x length)
    against_wall_m: float = 0.15  # radiators and the like stand this close to their wall
    floor_run_px: int = 5  # the floor begins where this many floor pixels follow
    trace_fraction: float = 0.06  # edge ends are followed at most this far
    trace_ratio: float = 0.35  # ... while the gradient across keeps this x its median
    trace_gap_px: int = 3  # ... across gaps up to this (detection pixels)
    cluster_width: float = 0.03  # heights within 3 % form one cluster
    confidence_weight: float = 0.3  # cluster weight (edge length / side, x2 if capped) for confidence 0.63
    unverified_confidence: float = 0.5  # confidence factor when no floor mask checked the feet


@dataclass
class FitSettings:
    """Fitting the furniture to the measured floor (:mod:`augment.room.fit`) and putting
    the doors the user marked on it (:mod:`augment.room.doors`)."""

    wall_margin_m: float = 0.05  # layouts keep this far inside the measured floor: its outline strays; baseboards
    max_fill: float = 0.5  # summed footprint of floor-standing items: at most this share of the floor
    seed_tries: int = 3  # seeds tried per suggestion before an item is dropped
    last_tries: int = 12  # ... and, once, for the first suggestion before the main piece and all with it go
    far_starts: int = 2  # starts far from the earlier suggestions, for one that repeats them
    twin_tries: int = 16  # a repeat still: this many more tries, in turn of each furniture set (all, fewer, corners)
    restarts: int = 4  # at most this many solver restarts per try: the tries and the drops do the rest
    min_iterations: int = 60  # a run may stop this early once settled (the solver's 100 is for many pieces)
    rule_distance_m: float = 0.15  # a rule's distance or place off by more than this is a fault of a try
    rule_angle_deg: float = 15.0  # ... and a facing off by more than this
    astray_m: float = 0.3  # a wall-bound piece (a TV, a wardrobe) farther off its wall than this: not clean
    astray_deg: float = 30.0  # ... nor two pieces that should face each other turned farther off than this
    for_camera: bool = True  # lay out for the photo's camera (layout.camera); False: as a plan seen from above
    min_difference_m: float = 0.3  # a suggestion this close to an earlier one (fit.apart_m) is a twin
    sparse_share: float = 0.45  # furnishing less of the floor than this x the first suggestion: worse than a twin
    fit_cell_m: float = 0.02  # raster cell of the "does this footprint fit the floor" test
    fit_angles: int = 36  # orientations tried, over 180 degrees
    inset_cell_m: float = 0.01  # raster cell of the floor shrunk by the wall margin
    door_graze_m2: float = 0.005  # furniture area inside a marked door's swing zone that still leaves the door usable
    door_width_m: tuple[float, float] = (0.5, 2.5)  # a door's feet this far apart: a cupboard door to a double door
    door_from_wall_m: float = 0.5  # a door's middle at most this far from a wall of the layouts' floor (a margin in)
    max_leaf_m: float = 0.9  # a found door's zone is as deep as it is wide, up to a single leaf's width
    found_door_margin_m: float = 0.1  # a found door's zone reaches this far past its found sides and depth
    found_window_margin_m: float = 0.15  # a found window's zone reaches this far past its found sides
    window_clearance_m: float = 0.4  # furniture taller than a found window's sill keeps this far from it
    window_on_wall_m: float = 0.3  # a found window past the floor in view: this much of it along a wall in view


@dataclass
class DoorSettings:
    """Doors found in the photo (:mod:`augment.room.openings`); lengths in meters."""

    step_m: float = 0.02  # a wall is sampled front-on this finely
    top_m: float = 2.2  # ... from the floor up to this height (a door is 2.0-2.1 m)
    wall_from_m: float = 0.15  # the wall's own colour: the median between these heights (a door or
    wall_to_m: float = 0.7  # ... a radiator is a small part of a wall), below the windows' sills
    min_difference: float = 10.0  # a sample differs from the wall by this CIELAB distance
    leaf_from_m: float = 0.15  # a door leaf is judged from above the skirting board's height
    sill_m: float = 0.7  # ... and must differ below this too (a window's sill is higher)
    min_seen_m: float = 0.6  # at least this much of a column's leaf must be in view,
    top_band_m: float = 0.1  # ... and its highest samples in view, this deep, differ too
    min_share: float = 0.85  # share of a column's samples that differ, up and below the sill
    width_m: tuple[float, float] = (0.6, 1.4)  # a door leaf with its casing, single or wide
    line_step: float = 2.0  # a vertical line: lightness (CIELAB L) steps this much per sample across it
    line_share: float = 0.8  # ... in this share of its column's samples in view
    side_share: float = 0.5  # a door of its own colour has such a line at a side in this share at least
    line_margin: int = 4  # ... and stands this many samples off the wall's ends (its corners)
    wall_turn_deg: float = 20.0  # the outline's edges form one wall while they turn less than this,
    jog_m: float = 0.3  # ... or by any angle over an edge shorter than this (round a threshold)
    model_in_casing: float = 0.75  # a model's door filling less of the casing around it is a leaf seen in part
    head_m: tuple[float, float] = (1.9, 2.25)  # a door's head (its casing's top) lies between these heights ...
    head_share: float = 0.4  # ... across this share of its columns at least, where the photo shows it
    model_threshold: float = 0.5  # a column is a door's where the model's probability is this or more
    model_margin: int = 64  # columns of nothing in view padded at a wall's ends, as in training
    model_top_m: float = 2.4  # the door model reads the wall up to here (a door's head and the wall above)
    window_band_m: tuple[float, float] = (1.0, 1.4)  # every window covers this band of its wall (sill to head)
    window_seen_m: float = 0.2  # ... of which this much must be in view
    window_below_m: float = 0.45  # below this (and above leaf_from_m) a window's column is wall, a door's is not
    window_floor_share: float = 0.5  # ... where less than this share differs (a sill's shadow may reach into it)
    window_width_m: tuple[float, float] = (0.4, 3.5)  # a window's width, a narrow one to a picture window
    window_frame_m: float = 0.15  # a vertical edge (the glass's, the casing's) this near one of its sides
    window_mullion_m: float = 0.16  # panes this far apart or nearer are one window
    window_reach_m: float = 1.5  # windows are looked for this far past a wall's open end (its foot out of view)
    window_sill_step: float = 8.0  # and at its sill the colour steps this much (CIELAB distance) over 8 cm


@dataclass
class RoomSettings:
    """The room stage's settings, one section per module."""

    height: HeightSettings = field(default_factory=HeightSettings)
    fit: FitSettings = field(default_factory=FitSettings)
    doors: DoorSettings = field(default_factory=DoorSettings)


ROOM = RoomSettings()
