"""The camera stage's tuning: finding the board, calibrating, and the line helpers that
calibration and the wall height share.

One mutable dataclass per module, each field with its reason, composed into
:data:`CAMERA`. Code reads the values at call time (``CAMERA.detect.max_side_px``), so a
caller, or a test with ``monkeypatch.setattr(CAMERA.calibrate, "ambiguous_rms_ratio", 1.0)``,
can change one. Facts that are not tuned (paper sizes, the ChArUco dictionary, OpenCV's
flags) stay constants of their modules.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class DetectSettings:
    """Finding the board's inner corners (:mod:`augment.camera.detect`)."""

    max_side_px: int = 1280  # a checkerboard is looked for in a copy no larger than this
    min_charuco_corners: int = 6  # a partly hidden ChArUco board needs this many corners, not in a line
    charuco_zoom: float = 2.0  # markers not read at full size are looked for again this much enlarged ...
    charuco_zoom_max_px: int = 4096  # ... when the enlarged photo's long side stays within this
    # A ChArUco board whose markers are read by neither is found as a checkerboard when its
    # white squares' middles correlate this well with the markers (blurred prints 0.5-0.94;
    # a plain checkerboard 0.04).
    min_marker_match: float = 0.3
    saddle_window: dict[str, float] = field(
        default_factory=lambda: {"chessboard": 0.4, "charuco": 0.15})  # x spacing: in a corner's squares, off markers
    max_saddle_radius_px: int = 24  # the saddle window's radius at most: the fit's cost grows with its area
    outlier_squares: float = 0.25  # a corner this far (x spacing, and 1 px) from where its neighbours say is redone
    outlier_reach: int = 2  # neighbours up to this many corners away say where a corner is (local: lens-proof)
    min_square_contrast: float = 0.3  # inner squares alternate by this x the median (true boards' worst: 0.46)
    goes_on_share: float = 0.75  # a side of the next ring out alternating this much: a patch of a larger board
    crop_candidates: int = 3  # crops are tried around this many strongest groups of saddle points
    crop_margin: float = 0.3  # a crop reaches this x the group's extent past it on each side
    crop_zoom_below_px: int = 16  # corner spacing under which a crop is also tried enlarged 2x
    rectified_spacings_px: tuple[float, ...] = (28.0, 20.0, 40.0)  # corner spacing of a far board's unsquashed view
    rectified_max_px: int = 2048  # a view larger than this a side is a stray line of saddles, not a board


@dataclass
class CalibrateSettings:
    """Settling the intrinsics and the pose (:mod:`augment.camera.calibrate`,
    :mod:`augment.camera.calibration`)."""

    min_board_extent_px: int = 60  # smaller boards give too few pixels for a pose
    small_photo_boards: int = 8  # a photo under this many boards' least extent (long side) is called too small
    max_rms_px: float = 2.0  # worse reprojection means a bent, moved or mis-sized board
    min_tilt_deg: float = 15.0  # single-view focal needs perspective: a face-on board says nothing of f
    max_tilt_deg: float = 85.0  # ... and a board seen nearly edge-on is a sliver
    max_single_view_uncertainty: float = 0.05  # relative focal uncertainty allowed before refusing
    camera_height_m: tuple[float, float] = (0.3, 2.5)  # crouching to arms raised; else the board's scale is wrong
    usual_camera_height_m: tuple[float, float] = (1.0, 1.8)  # standing, as most photos of a room are taken
    exif_gap_sigmas: float = 3.0  # EXIF this many joint sigmas off the board's focal: a crop (true EXIF stays in 2)
    corner_noise_floor_px: dict[str, float] = field(
        default_factory=lambda: {"chessboard": 0.05, "charuco": 0.2})  # least corner noise: what detectors reach
    ambiguous_rms_ratio: float = 2.0  # two tilts fitting within this RMS ratio: the vertical edges decide
    min_vertical_support: float = 0.25  # ... when the winner's edges are at least this many photo sides long
    vertical_support_ratio: float = 2.0  # ... and this many times the other tilt's
    line_noise_px: float = 0.5  # least noise of a detected segment's end, in the detector's copy
    floor_side_fraction: float = 0.004  # a segment's sides are read this far off it (x the longer side)
    lens_reach_share: float = 0.98  # pixels map to the floor only this far out of where the distortion turns back


@dataclass
class LineSettings:
    """Line segments, vertical edges and the floor's colour (:mod:`augment.camera.lines`)."""

    side_px: int = 1280  # lines are found on a copy shrunk by a whole factor to about this
    min_segment_fraction: float = 0.015  # detected segments shorter than this x the longer side are dropped
    canny_low: int = 10  # FastLineDetector's Canny: low, as a wall and its ceiling may differ by 6 gray levels
    canny_high: int = 20  # ... and its upper threshold
    blur_px: int = 3  # a Gaussian first quiets floor texture (and halves the time on wood)
    min_vertical_cos: float = float(np.cos(np.radians(1.5)))  # 3D: the floor normal within 1.5 deg of the edge
    vp_distance_fraction: float = 0.0015  # ends' distance from the midpoint-vanishing-point line (x longer side)
    floor_ring_m: tuple[float, float] = (0.35, 0.6)  # without a mask, the floor's colour is read this far out
    floor_color_slack: np.ndarray = field(
        default_factory=lambda: np.array([4.0, 2.0, 2.0]))  # ... with at least this spread (Lab)
    floor_color_z: np.ndarray = field(
        default_factory=lambda: np.array([6.0, 3.0, 3.0]))  # ... and a pixel is floor within this many spreads
    floor_share: float = 0.8  # floor on one side of a foot: at least this share of samples


@dataclass
class CameraSettings:
    """The camera stage's settings, one section per module."""

    detect: DetectSettings = field(default_factory=DetectSettings)
    calibrate: CalibrateSettings = field(default_factory=CalibrateSettings)
    lines: LineSettings = field(default_factory=LineSettings)


CAMERA = CameraSettings()
