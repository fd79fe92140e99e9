"""Render a furnished layout back into the photo it was measured from.

:func:`render_staged` takes the photo, its :class:`~augment.camera.calibration.Calibration` and the
placed items of a layout (floor frame: the board's, z up, meters) and returns the staged
photo at full resolution, with an optional RGBA layer of furniture and shadows.

How. The furniture (:mod:`augment.render.furniture`) is drawn with pyrender through
:mod:`augment.render.gl` with the calibrated intrinsics and pose (lens distortion applied by
warping the render), only over the part of the frame it and its shadows can reach,
antialiased by the renderer's 4x multisampling and by supersampling where the pixel
budget allows. The light is estimated from the photo (:func:`estimate_lighting`):
exposure and colour from the white squares of the board, paper of known whiteness lying
on the floor; a key light from the sun's patches on the floor or the brightest window, or
from overhead behind the camera when there is none; ceiling lamps from their pools of
light on the floor (:mod:`augment.render.lamps`). It is computed per vertex (key light
with a highlight, lamps, sky, room, floor bounce, ambient, baked occlusion near the
floor) and drawn with pyrender's flat shader, which llvmpipe runs several times faster
than its physically based one; the key light's shadows on the furniture come per pixel
from a depth map seen from the light (the lamps' per vertex, from one seen from each).

Shadows on the real floor are differential: the floor's irradiance is computed with and
without the furniture in a top-down raster of the floor (the key light's cast shadow,
averaged over directions across the light's extent so it is soft and hardens toward
contact; each lamp's, cast away from it; ambient occlusion from what stands over and
beside each floor point), and the photo is multiplied by their ratio (in the photo's
gamma, the 2.2 power the renderer also uses). Floor-level items (rugs) take the same
shadows, and only those. Walls (the floor polygon's wall edges) take the key light's
shadow and the floor's occlusion at their foot (:func:`_wall_gain`).

Occlusion. The photo hides furniture where its walls or objects stand in front of it. With
a floor mask, a pixel that shows something other than floor shows a vertical thing
standing on the first floor pixel below it (along the image of the vertical through it):
furniture farther from the camera than that is hidden. Wall segments (the boundary edges
of the floor polygon) hide what lies beyond them. Without either, furniture is drawn
wherever it projects.

Image convention: arrays are (row, col); points are (x, y) pixels, pixel centers at
integers (OpenCV). Colours are RGB uint8.
"""
from __future__ import annotations

import dataclasses
import hashlib
import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import cv2
import numpy as np
import skimage.measure
from numba import njit, prange

from layout.fileio import write_atomic

from ..photo.io import JPEG_QUALITY, encode_image
from .furniture import furniture_for, part_texture, placed_items, world_from_item
from .gl import Renderer, Scene, far_camera, gl_from_cv_pose, pyrender, pyrender_camera
from .lamps import find_lamps
from .look import PhotoLook, apply_look, blur_like_photo, estimate_look
from .settings import RENDER, StagedSettings
from .sun import (REC709, SunOnFloor, bright_floor, find_sun, linear_luminance, sun_elevation_rad, unit_colour,
                  wall_angles_rad)

GAMMA = 2.2                 # the renderer writes linear ** (1 / 2.2); photos are treated alike


# --------------------------------------------------------------------------------------
# Light from the photo
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Lighting:
    """The light the photo was taken in, as far as one photo tells.

    Attributes
    ----------
    irradiance_rgb : (3,) tuple of float
        Linear RGB a white (albedo 1) floor would show under this light: the photo's
        exposure and white balance.
    direction : (3,) tuple of float
        Unit vector along which the key light travels, floor frame (z < 0: downward).
    key_fraction : float
        Share of the floor's irradiance that comes from the key light; the rest is
        sky light from above and ambient.
    softness_rad : float
        Angular radius of the key light (0.01: the sun; 0.3: a big window or a lamp
        shade): how soft its shadows are.
    floor_rgb : (3,) tuple of float
        Linear RGB of the floor in the photo (light bounced from it onto furniture).
    source : str
        ``"sun"`` (the sun, its direction from the sunlit patches on the floor),
        ``"window"`` (from the brightest window) or ``"default"``.
    sun : SunOnFloor or None
        With the sun (:func:`augment.render.sun.find_sun`, or through a window in view
        :func:`augment.render.sun.bright_floor`): where the floor is in the sun.
        Then the key light reaches only what stands in its beam (where the light through
        a point lands on sunlit floor), and ``key_fraction`` is its share of the light in
        the sun.
    lamps : tuple of Lamp
        Ceiling lamps whose pools of light the floor shows (:mod:`augment.render.lamps`):
        light besides the rest, from above, with shadows of their own.
    key_rgb : (3,) tuple of float
        The key light's colour over ``irradiance_rgb`` (luminance 1): the sun's, read off
        its patches against the shade beside them.
    way : str
        What told the key light's way. The sun: ``"window_casts"`` (the window in view
        lands on its patches), ``"far_end_at_wall"`` (its patches run into a wall),
        ``"window_in_line"`` (the window in view lies back along its edges),
        ``"nearer_photo_edge"`` (its window is out of view past the nearer edge),
        ``"camera_side"`` (out of view behind the camera's side) or
        ``"plain_wall_upstream"`` (a plain wall in view rules the other way out). A window
        in view: ``"window_patch"`` (its outline lands on the bright floor) or
        ``"line_to_window"``. Else ``"behind_camera"``.
    floor_gloss : float
        Share of the light the floor mirrors (a glossy floor shows the furniture's
        reflection), read off the reflection of the window in view; 0 where none is read.
    """

    irradiance_rgb: tuple
    direction: tuple
    key_fraction: float
    softness_rad: float
    floor_rgb: tuple
    source: str
    sun: object = field(default=None, compare=False, repr=False)
    lamps: tuple = ()
    key_rgb: tuple = (1.0, 1.0, 1.0)
    way: str = ""
    floor_gloss: float = 0.0

    def to_json(self) -> dict:
        return {"source": self.source, "way": self.way, "direction": [round(float(v), 4) for v in self.direction],
                "key_fraction": round(float(self.key_fraction), 3), "softness_rad": round(float(self.softness_rad), 3),
                "irradiance_rgb": [round(float(v), 4) for v in self.irradiance_rgb],
                "key_rgb": [round(float(v), 3) for v in self.key_rgb],
                "floor_gloss": round(float(self.floor_gloss), 3),
                "lamps": [lamp.to_json() for lamp in self.lamps]}


def _to_linear(rgb_uint8) -> np.ndarray:
    return (np.asarray(rgb_uint8, dtype=np.float64) / 255.0) ** GAMMA


def _camera(calibration):
    K = np.asarray(calibration.intrinsics.K, dtype=np.float64)
    dist = np.asarray(calibration.intrinsics.distortion, dtype=np.float64).ravel()
    pose = np.asarray(calibration.camera_from_floor, dtype=np.float64)
    return K, dist, pose


def _project(points_m, K, camera_from_floor, dist=None):
    """Pixels (n, 2) and camera depths (n,) of floor-frame points (n, 3)."""
    p = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    cam = p @ camera_from_floor[:3, :3].T + camera_from_floor[:3, 3]
    z = cam[:, 2]
    if dist is not None and np.any(dist):
        px, _ = cv2.projectPoints(p.reshape(-1, 1, 3), cv2.Rodrigues(camera_from_floor[:3, :3])[0],
                                  camera_from_floor[:3, 3], K, dist)
        return px.reshape(-1, 2), z
    uv = cam @ K.T
    return uv[:, :2] / np.where(np.abs(uv[:, 2:]) < 1e-12, 1e-12, uv[:, 2:]), z


def _sample_rgb(image, px, radius=1):
    """Mean RGB (n, 3) of the (2r+1)^2 pixels around each point; NaN outside the image."""
    h, w = image.shape[:2]
    out = np.full((len(px), 3), np.nan)
    for k, (x, y) in enumerate(np.round(px).astype(int)):
        if radius <= x < w - radius and radius <= y < h - radius:
            out[k] = image[y - radius:y + radius + 1, x - radius:x + radius + 1].reshape(-1, 3).mean(axis=0)
    return out


def _floor_region(shape, K, pose, max_m=8.0):
    """Boolean (h, w) of the pixels below the horizon that the floor plane puts within
    ``max_m`` of the camera (where the floor is when no mask says so)."""
    h, w = shape
    ys, xs = np.mgrid[0:h, 0:w]
    rays = np.linalg.inv(K) @ np.stack([xs.ravel(), ys.ravel(), np.ones(h * w)])
    world = pose[:3, :3].T @ rays
    cam_z = -(pose[:3, :3].T @ pose[:3, 3])[2]
    down = world[2] < -1e-6
    t = np.where(down, cam_z / np.maximum(-world[2], 1e-9), np.inf)
    reach = t * np.hypot(world[0], world[1])
    return (down & (reach < max_m)).reshape(h, w)


def _window(lum, candidates, settings: StagedSettings, height_m=None):
    """The brightest window-like blob of a small photo's luminance (h, w): its centroid
    (x, y) in pixels and its pixels (h, w) bool, or None. ``height_m(x, y)``, when given,
    says how high on its wall a pixel lies (meters, NaN where no wall in view): a blob
    whose foot lies lower than ``settings.window_min_sill_m`` is sun climbing the wall or a
    lit door, not a window."""
    if candidates.sum() < 0.01 * lum.size:
        return None
    # A window is the brightest thing in view and clearly brighter than the walls around,
    # or blown out where bright walls leave no headroom for that.
    peak = float(np.percentile(lum[candidates], 99.5))
    thresh = max(120.0, 0.85 * peak, min(1.35 * float(np.median(lum[candidates])), settings.window_clipped))
    bright = (lum >= thresh) & candidates
    n, labels, stats, centroids = cv2.connectedComponentsWithStats(bright.astype(np.uint8), connectivity=8)
    if n <= 1:
        return None
    # A window is a compact bright quadrilateral: not a thin line of lit trim along the
    # ceiling or a baseboard, nor a ragged pool of light; and its frame cuts it off
    # sharply, where a lamp's glow on a wall fades out.
    ring = np.ones((5, 5), np.uint8)
    for k in 1 + np.argsort(-stats[1:, cv2.CC_STAT_AREA])[:4]:
        area = int(stats[k, cv2.CC_STAT_AREA])
        if area < 0.003 * lum.size:
            return None
        blob = (labels == k).astype(np.uint8)
        ys, xs = np.nonzero(blob)
        _, (a, b), _ = cv2.minAreaRect(np.column_stack([xs, ys]).astype(np.float32))
        if not (min(a, b) >= 5 and max(a, b) <= 6 * min(a, b) and area >= 0.6 * a * b):
            continue
        outside = (cv2.dilate(blob, ring) > 0) & (blob == 0)
        inside = (blob > 0) & (cv2.erode(blob, ring) == 0)
        if not (outside.any() and np.median(lum[outside]) <= settings.window_edge_ratio * np.median(lum[inside])):
            continue
        foot_y = np.percentile(ys, 95)
        if height_m is not None and height_m(float(np.median(xs[ys >= foot_y])), foot_y) < settings.window_min_sill_m:
            continue
        return centroids[k], blob > 0
    return None


def _on_wall_m(x_px: float, y_px: float, K, pose, walls) -> tuple[np.ndarray, int]:
    """Where the ray through pixel (x, y) meets the first wall segment (k, 2, 2) ahead:
    (3,) floor-frame meters, z its height (lens distortion ignored), and that wall's index;
    NaN and -1 when it meets none."""
    R = pose[:3, :3]
    eye = -R.T @ pose[:3, 3]
    ray = R.T @ np.linalg.solve(K, [x_px, y_px, 1.0])
    t_m, which = _first_wall(walls, ray[None], eye[:2])
    if which[0] < 0:
        return np.full(3, np.nan), -1
    return eye + ray * (t_m[0] / max(float(np.hypot(*ray[:2])), 1e-9)), int(which[0])


def _window_on_wall(blob_small, wall_m, small_scale, K, pose, cam_xy):
    """The window in view on its wall: the outline of its pixels (``blob_small`` (h, w) on
    the photo scaled by ``small_scale``) where their rays meet the vertical plane through
    the wall segment ``wall_m`` (2, 2), (n, 3) floor-frame meters; and the wall's direction
    and its normal into the room (toward ``cam_xy``), (2,) each. None when the outline
    does not lie on the wall ahead, above the floor."""
    contours, _ = cv2.findContours(blob_small.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return None
    outline = cv2.convexHull(np.vstack(contours)).reshape(-1, 2) / small_scale
    a, b = np.asarray(wall_m, dtype=np.float64)
    along = (b - a) / max(float(np.linalg.norm(b - a)), 1e-9)
    inward = np.array([-along[1], along[0]])
    if (np.asarray(cam_xy) - a) @ inward < 0:
        inward = -inward
    R = pose[:3, :3]
    eye = -R.T @ pose[:3, 3]
    rays = (R.T @ np.linalg.solve(K, np.column_stack([outline, np.ones(len(outline))]).T)).T
    toward = rays[:, :2] @ inward
    if not np.all(toward < -1e-9):
        return None
    window = eye + rays * (((a - eye[:2]) @ inward) / toward)[:, None]
    return (window, along, inward) if window[:, 2].min() > 0.0 else None


def _on_floor(sun: SunOnFloor, points_m) -> tuple[float, float, float]:
    """Of the convex region floor points (n, 2) span, on the top-down view of ``sun``: the
    share of it in view, the share of that in the sun (NaN when none is in view), and the
    share of the sun's patches it covers."""
    lo, cell = np.asarray(sun.lo_m), sun.cell_m
    hull = cv2.convexHull(np.round((np.asarray(points_m) - lo) / cell).astype(np.int32))
    region = np.zeros(sun.seen.shape, np.uint8)
    cv2.fillConvexPoly(region, hull, 1)
    region = region > 0
    seen = int((region & sun.seen).sum())
    lit = int((region & sun.lit).sum())
    return (seen / max(cv2.contourArea(hull.astype(np.float32)), 1.0), lit / seen if seen else math.nan,
            lit / max(int(sun.lit.sum()), 1))


def _climbs(sun: SunOnFloor, outline, run, lit: float, settings: StagedSettings) -> bool:
    """Whether the floor a window's sill would shade, from its wall's foot to short of its
    patch (0.8 of the sill's slide ``run`` (2,) per meter of height: the edge's blur), is
    about as often in the sun as the patch (``lit``, less ``settings.cast_min_margin``):
    then the light climbs that wall, and the window (``outline`` (n, 3)) is not the one
    in the sun."""
    sill = float(outline[:, 2].min())
    in_view, shade_lit, _ = _on_floor(sun, np.vstack([outline[:, :2], outline[:, :2] + run * 0.8 * sill]))
    return in_view >= settings.cast_min_in_view and shade_lit > lit - settings.cast_min_margin


def _window_casts(window, sun: SunOnFloor, settings: StagedSettings) -> float:
    """Which way the sun's light travels along ``sun.axes_xy[0]`` (+1.0 or -1.0) when the
    window in view (:func:`_window_on_wall`) casts its patches, else 0.0.

    Light through a window travels into the room, and the window's outline slid down along
    it lands on the floor as its patch, the wall below the sill as shade before it. So the
    window casts the patches when, at some height of the sun, its outline lands mostly on
    them (``settings.cast_min_lit``) while its sill's shade lands on floor less often lit
    (``settings.cast_min_margin``): where the patches run on to its wall, the light climbs
    that wall, and a window there is not the one in the sun.
    """
    outline, _, inward = window
    axis = np.asarray(sun.axes_xy[0], dtype=np.float64)
    into = 1.0 if axis @ inward > 0 else -1.0
    low, high = RENDER.sun.elevation_deg
    for elev_deg in np.arange(low, high + 1e-6, 2.0):
        run = into * axis / math.tan(math.radians(elev_deg))  # floor meters per meter of height
        in_view, lit, _ = _on_floor(sun, outline[:, :2] + run * outline[:, 2:])
        if in_view >= settings.cast_min_in_view and lit >= settings.cast_min_lit and not _climbs(
                sun, outline, run, lit, settings):
            return into
    return 0.0


def _window_casts_either(window, sun: SunOnFloor, settings: StagedSettings) -> tuple[SunOnFloor, float]:
    """:func:`_window_casts`, trying both edge families where neither runs along a wall
    (``sun.along_wall`` false: either may be the sun's): ``sun``, its families swapped
    when the window casts the patches along the second only, and which way the light
    travels along its first (0.0: the window does not cast them)."""
    cast = _window_casts(window, sun, settings)
    if cast or len(sun.axes_xy) < 2 or sun.along_wall:
        return sun, cast
    swapped = dataclasses.replace(sun, axes_xy=sun.axes_xy[::-1])
    cast = _window_casts(window, swapped, settings)
    return (swapped, cast) if cast else (sun, 0.0)


def _window_sun(window, bright: SunOnFloor, settings: StagedSettings):
    """The sun's direction (3,) through the window in view (:func:`_window_on_wall`) that
    casts the bright floor ``bright`` (:func:`augment.render.sun.bright_floor`, edges too
    soft to read): the way into the room and the height at which its outline, slid down
    along the sun, best covers the bright floor (intersection over union at least
    ``settings.window_sun_min_iou``; its sill's shade not as lit, as in
    :func:`_window_casts`), or None."""
    outline, along, inward = window
    low, high = RENDER.sun.elevation_deg
    # Searched on a view 4x coarser (4 cm cells): some 1300 ways and heights.
    coarse = {k: cv2.resize(getattr(bright, k).astype(np.float32), None, fx=0.25, fy=0.25,
                            interpolation=cv2.INTER_AREA) > 0.5 for k in ("lit", "seen")}
    bright = dataclasses.replace(bright, **coarse, cell_m=4 * bright.cell_m,
                                 lo_m=tuple(np.asarray(bright.lo_m) + 1.5 * bright.cell_m))
    best, found = settings.window_sun_min_iou, None
    for az in np.radians(np.arange(-75.0, 75.1, 3.0)):
        way = inward * math.cos(az) + along * math.sin(az)
        for elev_deg in np.arange(low, high + 1e-6, 2.0):
            run = way / math.tan(math.radians(elev_deg))
            in_view, lit, covered = _on_floor(bright, outline[:, :2] + run * outline[:, 2:])
            if not in_view >= settings.cast_min_in_view:
                continue
            iou = 1.0 / (1.0 / max(lit, 1e-9) + 1.0 / max(covered, 1e-9) - 1.0)
            if iou <= best or _climbs(bright, outline, run, lit, settings):
                continue
            best, found = iou, (way, math.radians(elev_deg))
    if found is None:
        return None
    return np.append(found[0] * math.cos(found[1]), -math.sin(found[1]))


def _mirrors_window(window, bright: SunOnFloor, eye_m, aim, settings: StagedSettings) -> bool:
    """Whether the bright floor ``bright`` is the window in view (:func:`_window_on_wall`)
    mirrored by a glossy floor, not its sun: the window's mirror image below the floor, seen
    from the camera at ``eye_m`` (3,), lands on bright floor (``settings.reflection_min_lit``
    of it in view, at least), and the sun fitted to it (``aim`` (3,), :func:`_window_sun`;
    None: none fits) comes from the window straight at the camera, as a reflection always
    does (within ``settings.reflection_max_gap_deg``)."""
    outline = window[0]
    eye = np.asarray(eye_m, dtype=np.float64)
    # A point at height z mirrored to -z is seen where the camera's ray to it meets the floor.
    mirrored = outline * np.array([1.0, 1.0, -1.0])
    on_floor = eye + (eye[2] / (eye[2] + outline[:, 2:])) * (mirrored - eye)
    in_view, lit, _ = _on_floor(bright, on_floor[:, :2])
    if not (in_view >= settings.cast_min_in_view and lit >= settings.reflection_min_lit):
        return False
    if aim is None:
        return True
    to_camera = eye[:2] - outline[:, :2].mean(axis=0)
    way = np.asarray(aim[:2], dtype=np.float64)
    cos = way @ to_camera / max(float(np.linalg.norm(way) * np.linalg.norm(to_camera)), 1e-9)
    return bool(cos >= math.cos(math.radians(settings.reflection_max_gap_deg)))


def _floor_gloss(image, floor_mask, K, dist, pose, outline, sheet_m, settings: StagedSettings) -> float:
    """Share of the light the floor mirrors, read off the window in view's reflection: the
    floor where the window's mirror image below it is seen, over the floor around that,
    against the window itself (linear light, medians; within ``settings.max_floor_gloss``).
    ``outline`` (n, 3): the window on its wall (:func:`_window_on_wall`), floor-frame meters;
    ``sheet_m`` (4, 2): the board's sheet, no floor (its paper is brighter)."""
    h, w = floor_mask.shape
    scale = min(1.0, settings.gloss_view_px / max(h, w))
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    small = linear_luminance(cv2.resize(image, size, interpolation=cv2.INTER_AREA))
    floor = cv2.resize(floor_mask.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0

    def polygon(points_m):
        px, _ = _project(points_m, K, pose, dist)
        out = np.zeros(small.shape, np.uint8)
        if np.all(np.isfinite(px)):
            cv2.fillConvexPoly(out, np.round(cv2.convexHull((px * scale).astype(np.float32))).astype(np.int32), 1)
        return out

    floor &= polygon(np.column_stack([sheet_m, np.zeros(len(sheet_m))])) == 0
    pane = cv2.erode(polygon(outline), np.ones((3, 3), np.uint8)) > 0
    mirror = polygon(outline * np.array([1.0, 1.0, -1.0]))
    grow = max(3, round(0.5 * math.sqrt(float(mirror.sum()))))
    ring = (cv2.dilate(mirror, np.ones((2 * grow + 1,) * 2, np.uint8)) > 0) & ~(
        cv2.dilate(mirror, np.ones((5, 5), np.uint8)) > 0) & floor
    mirror = (cv2.erode(mirror, np.ones((3, 3), np.uint8)) > 0) & floor
    if min(pane.sum(), mirror.sum(), ring.sum()) < settings.gloss_min_px:
        return 0.0
    around = float(np.median(small[ring]))
    gloss = (float(np.median(small[mirror])) - around) / max(float(np.median(small[pane])) - around, 1e-3)
    return float(np.clip(gloss, 0.0, settings.max_floor_gloss))


def _plain_wall_upstream(center_m, up_xy, walls, K, dist, pose, lum, wall_lum, small_scale,
                         band_m=None) -> bool:
    """Whether the photo shows a plain wall where the window casting sun patches at
    ``center_m`` would have to be, were the light coming from ``up_xy``: the first wall
    that way, over the heights ``band_m`` (m) every window covers, mostly in view and
    hardly brighter than the walls (``wall_lum``, on the small photo's luminance ``lum``);
    ``band_m`` defaults to ``RENDER.staged.window_band_m``."""
    t_m, which = _first_wall(walls, np.array([[up_xy[0], up_xy[1], 0.0]]), center_m)
    if which[0] < 0:
        return False
    foot = np.asarray(center_m) + np.asarray(up_xy) * t_m[0]
    band_m = RENDER.staged.window_band_m if band_m is None else band_m
    column = np.column_stack([np.repeat(foot[None], 12, axis=0), np.linspace(*band_m, 12)])
    px = np.rint(_project(column, K, pose, dist)[0] * small_scale).astype(int)
    h, w = lum.shape
    inside = (px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0) & (px[:, 1] < h)
    if inside.mean() < 0.75 or wall_lum is None:
        return False
    bright = lum[px[inside, 1], px[inside, 0]] >= 1.35 * wall_lum
    return float(bright.mean()) < 0.2


def _nearer_edge_upstream(center_m, axis_xy, walls, floor_polygon) -> float:
    """Which way along ``axis_xy`` the sun's light travels (+1.0 or -1.0) when, looking
    back against it from its patches at ``center_m``, neither way meets a wall in view:
    the window is past the photo's edge, and a patch lies within a few meters of its
    window (sill to head height over the sun's slope), so past the nearer edge. 0.0 when
    a wall is met either way (then the walls tell, :func:`_plain_wall_upstream`)."""
    ups = np.array([[-axis_xy[0], -axis_xy[1], 0.0], [axis_xy[0], axis_xy[1], 0.0]])
    if (_first_wall(walls, ups, center_m)[1] >= 0).any():
        return 0.0
    edges = wall_segments(getattr(floor_polygon, "polygon_m", floor_polygon))  # every edge, the photo's too
    out_m, _ = _first_wall(edges, ups, center_m)  # where each way leaves the floor in view
    if not np.isfinite(out_m).all() or abs(out_m[0] - out_m[1]) < 0.1:
        return 0.0
    return 1.0 if out_m[0] < out_m[1] else -1.0


def _sheet_grown_m(board) -> np.ndarray:
    """The board's sheet on the floor (4, 2), meters, grown by ``RENDER.sun.board_margin_m``:
    no floor to read the light on (its paper is brighter, its edges are steps)."""
    sheet = np.asarray(board.outline_m(), dtype=np.float64)[:, :2]
    return sheet + np.sign(sheet - sheet.mean(axis=0)) * RENDER.sun.board_margin_m


def _sun_patches(image, floor_mask, calibration, cam_xy, floor_polygon, toward_xy=None, colour=True):
    """:func:`augment.render.sun.find_sun` on this photo (the board's sheet left out; read in
    colour too where ``colour``), or with the sun's way ``toward_xy`` (2,) known,
    :func:`augment.render.sun.bright_floor`; or None."""
    mask = np.asarray(floor_mask, dtype=bool)
    if mask.shape != image.shape[:2]:
        mask = cv2.resize(mask.astype(np.uint8), image.shape[1::-1], interpolation=cv2.INTER_NEAREST) > 0
    walls_rad = None
    if floor_polygon is not None:
        poly = np.asarray(getattr(floor_polygon, "polygon_m", floor_polygon), dtype=np.float64)
        walls_rad = wall_angles_rad(poly, getattr(floor_polygon, "edge_kind", None))
    grown = _sheet_grown_m(calibration.board)
    floor_from_image = np.linalg.inv(calibration.image_from_floor)
    if toward_xy is not None:
        return bright_floor(image, mask, floor_from_image, cam_xy, toward_xy, grown)
    return find_sun(image, mask, floor_from_image, cam_xy, walls_rad, grown, colour=colour)


def estimate_lighting(image: np.ndarray, calibration, floor_mask: np.ndarray | None = None,
                      settings: StagedSettings | None = None, floor_polygon=None,
                      ceiling_m: float | None = None) -> Lighting:
    """Estimate exposure, colour, the key light's direction and the ceiling lamps from a calibrated photo.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo, RGB. Not modified.
    calibration : Calibration
        Of this photo (:func:`augment.camera.calibrate.calibrate_photo`): its board gives the
        exposure (white paper on the floor).
    floor_mask : (h, w) bool, optional
        Visible floor; else the floor is taken below the horizon, within 8 m.
    settings : StagedSettings, optional
        Default ``RENDER.staged`` (:mod:`augment.render.settings`).
    floor_polygon : FloorPolygon or (n, 2) float, optional
        The measured floor: its walls tell the sun's edges from the window's
        (:mod:`augment.render.sun`), and on which wall a window in view stands.
    ceiling_m : float, optional
        The room's height, where ceiling lamps hang (default ``RENDER.lamps.ceiling_m``);
        lamps are looked for with a floor mask only.

    Returns
    -------
    Lighting
    """
    settings = RENDER.staged if settings is None else settings
    image = _check_image(image)
    K, dist, pose = _camera(calibration)
    h, w = image.shape[:2]
    # Exposure and white balance: the white squares of the board.
    board = calibration.board
    s = board.square_m
    i, j = np.meshgrid(np.arange(board.cols + 1), np.arange(board.rows + 1))
    centers = np.column_stack([(i.ravel() - board.cols / 2) * s, (j.ravel() - board.rows / 2) * s,
                               np.zeros(i.size)])
    px, _ = _project(centers, K, pose, dist)
    radius = int(np.clip(0.2 * np.min(np.linalg.norm(np.diff(px[:2], axis=0), axis=1)), 0, 4))
    rgb = _sample_rgb(image, px, radius)
    rgb = rgb[~np.isnan(rgb[:, 0])]
    if len(rgb) == 0:
        raise ValueError("the board's squares are not in the photo: cannot read its exposure from the board")
    lum = rgb @ np.array([0.299, 0.587, 0.114])
    white = rgb[lum >= np.percentile(lum, 60)]
    paper = np.median(_to_linear(white), axis=0)
    irradiance = paper / settings.paper_albedo

    # The board may lie in a sunny patch or a shadow: scale to the floor at large.
    small_scale = min(1.0, 320.0 / max(h, w))
    small = cv2.resize(image, (max(1, round(w * small_scale)), max(1, round(h * small_scale))),
                       interpolation=cv2.INTER_AREA).astype(np.float64)
    if floor_mask is not None:
        region_small = cv2.resize(floor_mask.astype(np.uint8), small.shape[1::-1],
                                  interpolation=cv2.INTER_NEAREST) > 0
    else:
        region_small = _floor_region(small.shape[:2], _scaled_K(K, small_scale), pose)
    floor_lin = _to_linear(small[region_small]) if region_small.any() else _to_linear(white)
    floor_rgb = np.median(floor_lin, axis=0)
    # The floor around the board: 24 points 0.5 m from its centre.
    around_m = 0.5 * np.column_stack([np.cos(np.linspace(0, 2 * np.pi, 24)), np.sin(np.linspace(0, 2 * np.pi, 24))])
    near = _project(np.column_stack([around_m, np.zeros(24)]), K, pose, dist)[0]
    ring = _sample_rgb(image, near, max(radius, 1))
    ring = ring[~np.isnan(ring[:, 0])]
    if len(ring) >= 6:
        ring_lum = float(np.median(_to_linear(ring) @ [0.299, 0.587, 0.114]))
        all_lum = float(floor_rgb @ [0.299, 0.587, 0.114])
        irradiance = irradiance * float(np.clip(all_lum / max(ring_lum, 1e-6), 0.6, 1.4))

    # Key light: the sun where the floor shows its patches, else the brightest window.
    R = pose[:3, :3]
    eye = -R.T @ pose[:3, 3]
    cam_xy = eye[:2]
    forward = R.T @ np.array([0, 0, 1.0])
    lum_small = small @ np.array([0.299, 0.587, 0.114])
    wall_lum = float(np.median(lum_small[~region_small])) if (~region_small).any() else None
    horiz = forward[:2] / max(np.linalg.norm(forward[:2]), 1e-9)
    walls = None if floor_polygon is None else wall_segments(floor_polygon)
    found = _window(lum_small, ~region_small, settings, None if walls is None or len(walls) == 0 else (
        lambda x, y: _on_wall_m(x / small_scale, y / small_scale, K, pose, walls)[0][2]))
    window_xy = window = None
    if found is not None:
        (cx, cy), blob = found
        ray = R.T @ np.linalg.solve(K, [cx / small_scale, cy / small_scale, 1.0])
        toward = ray[:2] / max(np.linalg.norm(ray[:2]), 1e-9)
        if walls is not None:  # the window's wall: the first one the ray meets
            at, k = _on_wall_m(cx / small_scale, cy / small_scale, K, pose, walls)
            if k >= 0:
                window_xy, window = at[:2], _window_on_wall(blob, walls[k], small_scale, K, pose, cam_xy)
    floor_seen = region_small if floor_mask is None else floor_mask  # where the sun's patches are read
    # A sun read in colour only, faint in light, is less sure than a window in view.
    patches = None if not settings.sun_from_floor else _sun_patches(image, floor_seen, calibration, cam_xy,
                                                                     floor_polygon, colour=found is None)
    key_rgb = (1.0, 1.0, 1.0)
    gloss = 0.0
    if (patches is not None and window is not None and patches.rim_sharpness < RENDER.sun.rim_step_per_lit_sure
            and _mirrors_window(window, patches, eye, None, settings)):
        # An unsure sun's patches lying where a glossy floor mirrors the window in view:
        # the floor's sheen. Read again as the window's light (or its sun, edges aside).
        patches = None
    if patches is not None:
        patches, cast = (patches, 0.0) if window is None else _window_casts_either(window, patches, settings)
        axis = np.asarray(patches.axes_xy[0])
        center = np.asarray(patches.center_m)
        from_window = None if window_xy is None else center - window_xy
        if cast:
            sign, way = cast, "window_casts"
        elif not patches.downstream and from_window is not None and abs(axis @ from_window) >= (
                settings.sun_window_alignment * max(float(np.linalg.norm(from_window)), 1e-9)):
            sign, way = (1.0 if axis @ from_window >= 0 else -1.0), "window_in_line"
        else:
            # The patches run into the wall they climb; else their window is out of view:
            # past the nearer photo edge where no wall in view stands behind them either
            # way, else on the camera's side. Unless a plain wall in view stands where it would be.
            if patches.downstream:
                sign, way = float(patches.downstream), "far_end_at_wall"
            else:
                sign, way = (1.0 if axis @ (center - cam_xy) >= 0 else -1.0), "camera_side"
                edge = 0.0 if walls is None else _nearer_edge_upstream(center, axis, walls, floor_polygon)
                if edge:
                    sign, way = edge, "nearer_photo_edge"
            plain = [walls is not None and _plain_wall_upstream(center, -s * axis, walls, K, dist, pose, lum_small,
                                                                wall_lum, small_scale, settings.window_band_m)
                     for s in (sign, -sign)]
            if plain[0] and not plain[1]:
                sign, way = -sign, "plain_wall_upstream"
        elev = sun_elevation_rad(patches, math.radians(settings.sun_elevation_deg))
        direction = np.append(sign * axis * math.cos(elev), -math.sin(elev))
        soft, source = settings.sun_softness_rad, "sun"
    elif found is not None:
        # Sunlit floor (a bright patch well above the floor's median, the board's white
        # paper left out) means direct sun: its edges too soft to read, the window in view
        # gives its way (where its outline lands on that floor, else the camera's line to
        # it), and only the floor that bright loses it under the furniture.
        bright = _sun_patches(image, floor_seen, calibration, cam_xy, floor_polygon, -toward)
        aim = None if bright is None or window is None else _window_sun(window, bright, settings)
        if bright is not None and window is not None and _mirrors_window(window, bright, eye, aim, settings):
            bright = aim = None
        sunny = bright is not None
        patches = bright if settings.sun_from_floor else None
        aim = aim if settings.sun_from_floor else None
        elev = math.radians(settings.sun_elevation_deg if sunny else settings.window_elevation_deg)
        direction, way = np.append(-toward * math.cos(elev), -math.sin(elev)), "line_to_window"
        if aim is not None:  # the window's patch found on the bright floor: the sun's way and height
            direction, way = aim, "window_patch"
            axis = aim[:2] / np.linalg.norm(aim[:2])
            patches = dataclasses.replace(patches, axes_xy=(tuple(axis),))
        key, soft = ((settings.window_sun_key, settings.window_sun_softness_rad) if sunny
                     else (settings.window_key, settings.window_softness_rad))
        source = "window"
        if not sunny and window is not None and floor_mask is not None:
            gloss = _floor_gloss(image, np.asarray(floor_mask, dtype=bool), K, dist, pose, window[0],
                                 _sheet_grown_m(board), settings)
    else:
        elev = math.radians(65.0)
        direction = np.append(horiz * math.cos(elev), -math.sin(elev))
        # Nothing in the photo says where the light comes from: a weak, very soft key, so
        # no shadow is thrown far in a direction that is only a guess.
        key, soft, source, way = 0.15, 0.5, "default", "behind_camera"
    sun = patches
    if sun is not None:
        if source == "sun":
            key = float(np.clip(1.0 - 1.0 / sun.contrast, *settings.sun_key_range))
            # A rim hardly sharper than a real floor's grain: as much a window's light as the sun's.
            low, sure_from = RENDER.sun.rim_step_per_lit, RENDER.sun.rim_step_per_lit_sure
            sure = float(np.clip((sun.rim_sharpness - low) / (sure_from - low), 0.0, 1.0))
            key = settings.window_key + sure * (key - settings.window_key)
            soft = soft + (1.0 - sure) * (settings.window_softness_rad - soft)
        else:
            sure = 1.0
        # The sun's colour against the shade's: on the paper in the sun, the two mixed
        # (the sheet itself is left out of the sunlit floor: the floor around it tells).
        # (An unsure sun's colour, as its light, goes part of the way to a window's: white.)
        ratio = np.asarray(sun.ratio_rgb, dtype=np.float64)
        if np.median(sun.sunlit(around_m)) > 0.5:
            irradiance = irradiance * np.asarray(unit_colour(1.0 / (1.0 + sure * (ratio - 1.0))))
        key_rgb = unit_colour(1.0 - sure + sure * np.asarray(unit_colour(ratio - 1.0)))
    lamps = ()
    if floor_mask is not None:
        lamps = find_lamps(image, np.asarray(floor_mask, dtype=bool), calibration,
                           RENDER.lamps.ceiling_m if ceiling_m is None else float(ceiling_m),
                           float(floor_rgb @ REC709),
                           None if sun is None else (lambda xy: sun.sunlit(xy) > 0.25),
                           inside=None if walls is None or len(walls) == 0 else _in_room(walls, cam_xy))
    return Lighting(tuple(float(v) for v in irradiance), tuple(float(v) for v in direction), key, soft,
                    tuple(float(v) for v in floor_rgb), source, sun, lamps, tuple(float(v) for v in key_rgb), way,
                    gloss)


# --------------------------------------------------------------------------------------
# The furniture passes (pyrender)
# --------------------------------------------------------------------------------------
#
# Light is computed per vertex and drawn with pyrender's flat shader (colour = vertex
# colour x base colour x texture), which llvmpipe runs several times faster than its
# physically based one. Two passes: the fill light (sky, room, floor bounce, ambient,
# emission) and the key light alone, so the key light can be shadowed per pixel from a
# depth map seen from the light. Vertex colours are the linear light to the power 1/2.2,
# the photo's encoding; pixel = (fill + key x visibility) in linear light.


def _vertex_occlusion(z_m, normals, item_height_m):
    """Baked ambient occlusion per vertex (n,): darker near the item's base (over 5 cm,
    less for small things) and facing down. ``item_height_m`` per vertex or scalar."""
    small = np.minimum(1.0, np.asarray(item_height_m) / 0.5)
    ao = 1.0 - 0.3 * small * np.exp(-np.maximum(z_m, 0.0) / (0.05 * small))
    return ao * (1.0 - 0.35 * np.maximum(-normals[:, 2], 0.0))


def _vertex_light(v, n, albedo, roughness, metal, emissive, ao, lighting: Lighting, cam_pos, forward_xy,
                  settings: StagedSettings):
    """Linear light leaving each vertex toward the camera: (fill (n, 3), key (n, 3)).

    Per vertex (n,) or (n, 3) arrays: positions, unit normals, albedo (linear RGB),
    roughness, metalness, emission, occlusion. Scaled so that a white (albedo 1) floor
    facing up shows ``lighting.irradiance_rgb``: key f (n . l) / sin(elevation), sky
    (1 - f) s (1 + n_z) / 2, ambient (1 - f)(1 - s), with f the key fraction and s the
    sky share; plus light from behind the camera and off the floor, a Blinn-Phong
    highlight of the key light (exponent from the roughness), and for metals a share of
    the room mirrored."""
    E = np.asarray(lighting.irradiance_rgb, dtype=np.float64)
    floor = np.asarray(lighting.floor_rgb, dtype=np.float64)
    d = np.asarray(lighting.direction, dtype=np.float64)
    l = -d / np.linalg.norm(d)
    sin_e = max(l[2], 0.15)
    f_key = lighting.key_fraction
    rest = 1.0 - f_key
    diffuse = albedo * (1.0 - 0.96 * metal)[:, None]
    nz = n[:, 2]
    front = np.append(-forward_xy, 0.35)
    front /= np.linalg.norm(front)
    sky = settings.sky_share
    # With the sun in the room the caller's light map is the shade's, over which the sky
    # and the ambient rise with the sun's contrast; the room's own light (behind the
    # camera, off the floor) is the shade's as it is.
    c = _sun_contrast(lighting) if lighting.sun is not None else 1.0
    around = c * rest * (sky * (0.5 + 0.5 * nz) + 1.0 - sky) + settings.front_fill * np.maximum(n @ front, 0)
    fill = (around[:, None] * E + settings.bounce * floor * (0.5 - 0.5 * nz)[:, None]) * diffuse
    fill += (settings.metal_env * metal * (0.6 + 0.4 * np.maximum(nz, 0.0)))[:, None] * albedo * E
    ndl = np.maximum(n @ l, 0.0)
    E_key = E * np.asarray(lighting.key_rgb, dtype=np.float64)
    key = (f_key * ndl / sin_e)[:, None] * E_key * diffuse
    # Highlight: normalized Blinn-Phong with Schlick's Fresnel.
    view = cam_pos - v
    view /= np.maximum(np.linalg.norm(view, axis=1, keepdims=True), 1e-9)
    half = view + l
    half /= np.maximum(np.linalg.norm(half, axis=1, keepdims=True), 1e-9)
    alpha = np.maximum(roughness, 0.08) ** 2
    power = 2.0 / alpha ** 2 - 2.0
    f0 = 0.04 * (1.0 - metal)[:, None] + albedo * metal[:, None]
    fresnel = f0 + (1.0 - f0) * ((1.0 - np.clip((view * half).sum(1), 0, 1)) ** 5)[:, None]
    lobe = (power + 8.0) / (8.0 * np.pi) * np.clip((n * half).sum(1), 0, 1) ** power * ndl
    key += np.minimum(lobe, 50.0)[:, None] * fresnel * (f_key * np.pi / sin_e) * E_key
    return fill * ao[:, None] + emissive * float(E.max()), key * ao[:, None]


def _roll_off(linear, knee):
    """(n,) factors that bring light (n, 3) above ``knee`` smoothly toward 1 by its
    brightest channel, hue kept: a white top under a lamp keeps its shading instead of
    clipping flat, as a camera's shoulder keeps it."""
    peak = np.max(linear, axis=1)
    over = np.maximum(peak - knee, 0.0)
    soft = knee + (1.0 - knee) * -np.expm1(-over / (1.0 - knee))
    return np.where(peak > knee, soft / np.maximum(peak, 1e-9), 1.0)


def _encode(linear):
    """Vertex colours (n, 4) float32: linear light in the photo's gamma, alpha 1. Above 1
    is kept: a surface texture (at most 1) multiplies it before the shader clamps."""
    return np.column_stack([np.maximum(linear, 0.0) ** (1.0 / GAMMA), np.ones(len(linear))]).astype(np.float32)


@dataclass(frozen=True)
class _LightMap:
    """How much light the floor gets around each point, relative to its median: read off
    the photo's own floor (a top-down raster, blurred), so furniture by a window is lit
    brighter than furniture in a dim corner, as the floor beside each is."""

    grid: "_FloorGrid"
    gain: np.ndarray  # (rows, cols) float32

    def at(self, xy) -> np.ndarray:
        """Gain (n,) at floor points (n, 2+), bilinear; the edge's value beyond it."""
        px = (self.grid.to_px(xy) - 0.5).astype(np.float32)
        n = len(px)
        # cv2.remap takes maps of under 32767 a side: the points in rows of 1024.
        rows = -(-n // 1024)
        maps = np.zeros((rows * 1024, 2), np.float32)
        maps[:n] = px
        maps = maps.reshape(rows, 1024, 2)
        return cv2.remap(self.gain, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE).ravel()[:n]


def _mirrors(lighting: Lighting, settings: StagedSettings) -> bool:
    """Whether the photo's floor is glossy enough to mirror the furniture."""
    return lighting.floor_gloss >= settings.min_reflection_gloss


def floor_light_map(image, floor_mask, K, dist, pose, lighting: Lighting, lo_m, hi_m,
                    settings: StagedSettings) -> _LightMap | None:
    """The floor's light around the furniture, from the photo (None without a floor mask,
    with too little floor in view, or on a floor that mirrors the furniture: what it
    mirrors, a window's reflection above all, is no light falling there). ``lo_m``,
    ``hi_m``: the floor box to cover."""
    if floor_mask is None or _mirrors(lighting, settings):
        return None
    cell = settings.light_cell_m
    lo = np.asarray(lo_m, dtype=np.float64)[:2]
    shape = tuple(int(v) for v in np.maximum(1, np.ceil((np.asarray(hi_m)[:2] - lo) / cell))[::-1])
    grid = _FloorGrid(lo, cell, shape)
    xy = grid.centers_m()
    px, depth = _project(np.column_stack([xy, np.zeros(len(xy))]), K, pose, dist)
    h, w = floor_mask.shape
    ij = np.round(px).astype(np.int64)
    ok = (depth > 0) & (ij[:, 0] >= 0) & (ij[:, 0] < w) & (ij[:, 1] >= 0) & (ij[:, 1] < h)
    ok[ok] = floor_mask[ij[ok, 1], ij[ok, 0]]
    if ok.sum() < 50:
        return None
    reference = max(float(np.asarray(lighting.floor_rgb) @ REC709), 1e-6)
    lum = np.zeros(len(xy), np.float32)
    lum[ok] = linear_luminance(image[ij[ok, 1], ij[ok, 0]])
    if lighting.sun is not None:  # the light in the shade: the sun's beam is traced apart
        lum /= 1.0 + (_sun_contrast(lighting) - 1.0) * (lighting.sun.sunlit(xy) > 0.5)
    if lighting.lamps:  # and the lamps' light: they light the furniture themselves
        lum[ok] = np.maximum(lum[ok] - reference * sum(lamp.on_floor(xy[ok]) for lamp in lighting.lamps), 0.0)
    weight = ok.astype(np.float32).reshape(shape)
    sigma = settings.light_sigma_m / cell
    num = cv2.GaussianBlur(lum.reshape(shape), (0, 0), sigma)
    den = cv2.GaussianBlur(weight, (0, 0), sigma)
    trust = np.clip(den / 0.2, 0.0, 1.0)
    local = np.where(den > 1e-3, num / np.maximum(den, 1e-3), reference)
    # Far from any floor in view, the light of the floor at large (the median), less the lamps'.
    far = float(np.median(lum[ok])) / reference if lighting.lamps else 1.0
    gain = trust * local / reference + (1.0 - trust) * far
    return _LightMap(grid, np.clip(gain, *settings.light_gain_range).astype(np.float32))


def _sun_contrast(lighting: Lighting) -> float:
    """The sunlit floor's light over the shade's, as the key share says."""
    return 1.0 / max(1.0 - lighting.key_fraction, 1e-3)


def _in_beam(points_m, lighting: Lighting) -> np.ndarray:
    """(n,) 1 where the sun reaches points (n, 3), 0 where not: the light through a
    point would land on the floor further along, sunlit in the photo of the empty room
    if the point is in the beam; the share in the sun where that floor is not seen."""
    d = np.asarray(lighting.direction, dtype=np.float64)
    t = np.maximum(points_m[:, 2], 0.0) / max(-d[2], 1e-3)
    return lighting.sun.sunlit(points_m[:, :2] + t[:, None] * d[:2])


def _furniture_meshes(placed, lighting: Lighting, cam_pos, forward_xy, settings: StagedSettings,
                      light_map: _LightMap | None = None, renderer: Renderer | None = None,
                      beam_per_pixel: bool = False):
    """The furniture as pyrender meshes in the floor frame, lit: (all light, key light
    alone), one primitive per texture (all untextured parts share one). ``light_map``
    scales each vertex's light by the floor's light below it; with ``renderer``, what
    stands between a lamp and a vertex keeps the lamp's light from it. With
    ``beam_per_pixel`` the first meshes carry the fill light alone and the sun's key is
    left whole: the caller adds it where the beam and the key's shadows let it through,
    per pixel (the beam's edge crosses a face between vertices)."""
    lamp_views = [_lamp_view(renderer, placed, lamp) for lamp in lighting.lamps] if renderer is not None else []
    groups: dict = {}
    for item, furniture in placed:
        T = world_from_item(item)
        for part in furniture.parts:
            key, image, uv, scale = part_texture(part)
            groups.setdefault(key, (image, []))[1].append((part, T, item.size_m[2], uv, scale))
    fills, keys = [], []
    for tex_key, (image, members) in groups.items():
        vs, ns, fs, hs, per = [], [], [], [], []
        count = 0
        for part, T, height, _, scale in members:
            vs.append(part.vertices @ T[:3, :3].T + T[:3, 3])
            ns.append(part.normals @ T[:3, :3].T)
            hs.append(np.full(len(part.vertices), T[2, 3]))
            fs.append(part.faces + count)
            m = part.material
            per.append((len(part.vertices), np.ones(3) if scale is None else np.asarray(m.color_rgb) * scale,
                        m.roughness, m.metallic, m.emissive_rgb, height))
            count += len(part.vertices)
        v, n = np.concatenate(vs), np.concatenate(ns)
        sizes = [p[0] for p in per]
        albedo = np.repeat(np.array([p[1] for p in per], dtype=np.float64), sizes, axis=0)
        rough = np.repeat([p[2] for p in per], sizes)
        metal = np.repeat([p[3] for p in per], sizes)
        emissive = np.repeat(np.array([p[4] for p in per], dtype=np.float64), sizes, axis=0)
        ao = _vertex_occlusion(v[:, 2] - np.concatenate(hs), n, np.repeat([p[5] for p in per], sizes))
        ao *= np.concatenate([part.light_share() for part, *_ in members])
        fill, key = _vertex_light(v, n, albedo, rough, metal, emissive, ao, lighting, cam_pos, forward_xy, settings)
        gain = np.ones((len(v), 1)) if light_map is None else light_map.at(v)[:, None]
        if lighting.sun is not None:
            # The light map is the shade's: with the sun's share f of the light in the sun,
            # shade = (1 - f) x sun, so the key scales by 1 / (1 - f) = contrast (the
            # sky and the ambient did in _vertex_light).
            c = _sun_contrast(lighting)
            if light_map is None:  # the floor at large: a share in the sun
                gain = gain / (1.0 + (c - 1.0) * lighting.sun.lit_share)
            fill, key = fill * gain, key * gain * c
            beam = _in_beam(v, lighting)[:, None]
        else:
            fill, key = fill * gain, key * gain
            beam = 1.0
        if lighting.lamps:
            # Floor-level pieces (rugs) take the floor's shadows instead.
            raised = v[:, 2] >= settings.floor_level_m
            lit = sum(lamp.on(v, n) * np.where(raised, lamp_views[k].visible(v, n), 1.0) if lamp_views
                      else lamp.on(v, n) for k, lamp in enumerate(lighting.lamps)) * ao
            fill = fill + lit[:, None] * np.asarray(lighting.irradiance_rgb) * albedo * (1.0 - 0.96 * metal)[:, None]
        roll = _roll_off(fill + key * beam, settings.highlight_knee)[:, None]
        fill, key = fill * roll, key * roll * (1.0 if beam_per_pixel else beam)
        first = fill if beam_per_pixel else fill + key
        positions, normals = v.astype(np.float32), n.astype(np.float32)
        indices = np.concatenate(fs).astype(np.uint32)
        uv = np.concatenate([m[3] for m in members]).astype(np.float32) if tex_key else None
        # One texture for both meshes: pyrender uploads it once while it stays in the scenes.
        tex = None if image is None else pyrender.Texture(source=image, source_channels="RGB")
        for colors, out in ((first, fills), (key, keys)):
            material = pyrender.MetallicRoughnessMaterial(baseColorFactor=(1.0, 1.0, 1.0, 1.0), baseColorTexture=tex)
            out.append(pyrender.Mesh([pyrender.Primitive(
                positions=positions, normals=normals, texcoord_0=uv, color_0=_encode(colors), indices=indices,
                material=material, mode=pyrender.GLTF.TRIANGLES)]))
    return fills, keys


@dataclass(frozen=True)
class _LampView:
    """A camera at a lamp looking straight down, and the furniture's depth map from it:
    which vertices the lamp sees."""

    camera_from_floor: np.ndarray
    K: np.ndarray
    depth_m: np.ndarray
    texel_per_m: float  # a texel's size at a depth of one meter

    def visible(self, points, normals) -> np.ndarray:
        """(n,) share of the lamp that reaches vertices (n, 3) with unit normals (n, 3):
        tested a texel and a half off their surface, with a bias for surfaces aslant to it."""
        R, t = self.camera_from_floor[:3, :3], self.camera_from_floor[:3, 3]
        depth = np.maximum(points @ R[2] + t[2], 1e-3)
        texel = depth * self.texel_per_m
        to_lamp = -(points @ R.T + t) @ R  # toward the camera's centre, floor frame
        to_lamp /= np.maximum(np.linalg.norm(to_lamp, axis=1, keepdims=True), 1e-9)
        ndl = np.clip((normals * to_lamp).sum(axis=1), 0.05, 1.0)
        slope = np.minimum(np.sqrt(1.0 - ndl ** 2) / ndl, 4.0)
        pushed = points + normals * (1.5 * texel)[:, None]
        return _key_visibility(np.ascontiguousarray(pushed), 0.003 + texel * (1.0 + 1.5 * slope), R, t, self.K,
                               self.depth_m, 1.5)


def _lamp_view(renderer, placed, lamp, size_px=512) -> _LampView:
    """The furniture's depth seen from ``lamp``, as wide as it needs (75 degrees off
    straight down at most: beyond, the lamp's light is slight and counted as seen).
    Read per vertex, 512 texels do: at 1024 a bed's duvet came out darker than the
    synthetic photographer's truth (ΔE 5.5 against 3.5), and the view cost 0.1 s more."""
    vs, fs, count = [], [], 0
    for item, furniture in placed:
        T = world_from_item(item)
        for part in furniture.parts:
            vs.append(part.vertices @ T[:3, :3].T + T[:3, 3])
            fs.append(part.faces + count)
            count += len(part.vertices)
    v = np.concatenate(vs)
    position = np.asarray(lamp.position_m, dtype=np.float64)
    R = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0, -1.0]])  # looking straight down
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, -R @ position
    cam = v @ R.T + pose[:3, 3]
    ahead = cam[:, 2] > 0.05
    reach = float(np.max(np.abs(cam[ahead, :2]) / cam[ahead, 2:3])) if ahead.any() else 1.0
    reach = min(max(reach, 0.1), math.tan(math.radians(75.0)))
    f = 0.5 * size_px / reach
    c = 0.5 * size_px - 0.5
    K = np.array([[f, 0, c], [0, f, c], [0, 0, 1.0]])
    camera = pyrender.IntrinsicsCamera(fx=f, fy=f, cx=c + 0.5, cy=c + 0.5, znear=0.02,
                                       zfar=float(position[2]) + 1.0)
    mesh = pyrender.Mesh([pyrender.Primitive(positions=v.astype(np.float32),
                                             indices=np.concatenate(fs).astype(np.uint32),
                                             mode=pyrender.GLTF.TRIANGLES)])
    scene = _flat_scene([mesh], camera, gl_from_cv_pose(np.linalg.inv(pose)))
    depth = renderer.render(scene, size_px, size_px, flags=pyrender.RenderFlags.DEPTH_ONLY)
    return _LampView(pose, K, np.ascontiguousarray(depth, dtype=np.float32), 2.0 * reach / size_px)


def _flat_scene(meshes, camera, camera_pose_gl):
    scene = Scene(bg_color=(0.0, 0.0, 0.0, 0.0))
    for k, mesh in enumerate(meshes):
        scene.add(mesh, name=f"furniture{k:03d}")
    scene.add(camera, pose=camera_pose_gl, name="camera")
    return scene


@dataclass(frozen=True)
class _LightView:
    """A nearly orthographic camera looking along the key light (a perspective camera
    100 m away, so pyrender's depth is exact), and its depth map."""

    camera_from_floor: np.ndarray
    K: np.ndarray
    depth_m: np.ndarray
    texel_m: float


_LIGHT_DISTANCE_M = 100.0


def _light_view(renderer, meshes, lighting: Lighting, lo_m, hi_m, size_px) -> _LightView:
    center = 0.5 * (np.asarray(lo_m) + np.asarray(hi_m))
    radius = max(0.5 * float(np.linalg.norm(np.asarray(hi_m) - np.asarray(lo_m))), 0.05)
    pose, K, camera = far_camera(center, radius, lighting.direction, size_px, _LIGHT_DISTANCE_M)
    scene = _flat_scene(meshes, camera, gl_from_cv_pose(np.linalg.inv(pose)))
    depth = renderer.render(scene, size_px, size_px, flags=pyrender.RenderFlags.DEPTH_ONLY)
    return _LightView(pose, K, np.ascontiguousarray(depth, dtype=np.float32), 2.0 * radius / size_px)


def _shadow_receivers(world, lit, cam_pos, lighting: Lighting, texel_m, radius_px):
    """Where to test the key light's shadow: the points of the ``lit`` pixels of a world
    image (h, w, 3), NaN where empty, pushed off their surface by a texel and a half
    along its normal (from the neighbouring pixels), and a depth bias growing with the
    surface's slope to the light over the filter's reach, so surfaces do not shadow
    themselves in stripes ("acne"). Returns (rows, cols, points (n, 3), bias (n,))."""
    h, w = lit.shape
    y, x = np.nonzero(lit)
    p = world[y, x].astype(np.float64)

    def diff(dy, dx):
        ahead = world[np.minimum(y + dy, h - 1), np.minimum(x + dx, w - 1)] - p
        behind = p - world[np.maximum(y - dy, 0), np.maximum(x - dx, 0)]
        return np.where(np.isnan(ahead), behind, ahead)
    n = np.cross(diff(0, 1), diff(1, 0))
    norm = np.linalg.norm(n, axis=1)
    l = -np.asarray(lighting.direction, dtype=np.float64)
    l /= np.linalg.norm(l)
    ok = np.isfinite(norm) & (norm > 1e-12)
    n = np.where(ok[:, None], n / np.where(ok, norm, 1.0)[:, None], l)  # unknown: facing the light
    n *= np.where((n * (cam_pos - p)).sum(axis=1) < 0, -1.0, 1.0)[:, None]
    ndl = np.clip(n @ l, 0.05, 1.0)
    slope = np.minimum(np.sqrt(1.0 - ndl ** 2) / ndl, 4.0)
    return y, x, p + n * (1.5 * texel_m), 0.003 + texel_m * (1.0 + radius_px * slope)


@njit(cache=True, parallel=True)
def _key_visibility(points, bias_m, R, t, K, depth, radius_px):
    """Share of the key light reaching each floor-frame point (n, 3): nine depth
    comparisons spread over ``radius_px`` texels of the light's depth map, each point with
    its own depth bias (n,)."""
    n = points.shape[0]
    h, w = depth.shape
    out = np.ones(n, np.float32)
    for k in prange(n):
        x = R[0, 0] * points[k, 0] + R[0, 1] * points[k, 1] + R[0, 2] * points[k, 2] + t[0]
        y = R[1, 0] * points[k, 0] + R[1, 1] * points[k, 1] + R[1, 2] * points[k, 2] + t[1]
        z = R[2, 0] * points[k, 0] + R[2, 1] * points[k, 1] + R[2, 2] * points[k, 2] + t[2]
        u = K[0, 0] * x / z + K[0, 2]
        v = K[1, 1] * y / z + K[1, 2]
        lit = 0.0
        for dy in (-1.0, 0.0, 1.0):
            for dx in (-1.0, 0.0, 1.0):
                i = int(v + dy * radius_px + 0.5)
                j = int(u + dx * radius_px + 0.5)
                if i < 0 or j < 0 or i >= h or j >= w:
                    lit += 1.0
                elif depth[i, j] <= 0.0 or z - bias_m[k] <= depth[i, j]:
                    lit += 1.0
        out[k] = lit / 9.0
    return out


# Gamma tables for _combine: 8-bit code -> linear, and linear -> code by the square root
# of the linear value (even steps there are fine enough everywhere, for linear interpolation).
_DECODE = ((np.arange(256) / 255.0) ** GAMMA).astype(np.float32)
_ENCODE_STEPS = 4096
_ENCODE = (255.0 * (np.arange(_ENCODE_STEPS + 2) / _ENCODE_STEPS).clip(0, 1) ** (2.0 / GAMMA)).astype(np.float32)


@njit(cache=True, parallel=True)
def _combine(fill, key, visibility, decode, encode, out):
    """Premultiplied RGBA (h, w, 4) uint8 of the fill light plus the key light's unshadowed
    share, in linear light: fill + key x visibility. ``fill`` and ``key`` are the two
    passes, premultiplied by coverage (``fill``'s alpha); ``visibility`` (h, w). (Adding
    the key, not taking it off a pass of all the light: a strong coloured key clips that
    pass in one channel, and taking it off there tints the shade.)"""
    h, w = fill.shape[0], fill.shape[1]
    steps = encode.shape[0] - 2
    for i in prange(h):
        for j in range(w):
            cov = fill[i, j, 3]
            out[i, j, 3] = cov
            lit = visibility[i, j]
            if cov == 0 or lit <= 1e-3 or (key[i, j, 0] == 0 and key[i, j, 1] == 0 and key[i, j, 2] == 0):
                for c in range(3):
                    out[i, j, c] = fill[i, j, c]
                continue
            for c in range(3):
                if cov == 255:
                    lin = decode[fill[i, j, c]] + lit * decode[key[i, j, c]]
                else:
                    scale = 1.0 / cov
                    lin = (fill[i, j, c] * scale) ** 2.2 + lit * (key[i, j, c] * scale) ** 2.2
                t = np.sqrt(max(lin, 0.0)) * steps
                k = min(int(t), steps)
                f = t - k
                value = (encode[k] * (1.0 - f) + encode[k + 1] * f) * (cov / 255.0) + 0.5
                out[i, j, c] = 255 if value >= 255.0 else np.uint8(value)


# --------------------------------------------------------------------------------------
# Shadows on the floor: a top-down raster of irradiance ratios
# --------------------------------------------------------------------------------------

@dataclass
class _Caster:
    """What one part contributes to the floor's shading, floor frame."""

    points: np.ndarray             # (n, 3) vertices
    triangles: np.ndarray | None   # (m, 3, 3) for non-convex parts, else None
    z_bottom: float
    z_top: float

    @property
    def corners(self) -> np.ndarray:
        """(k, 3) every point of the part: its vertices, or its triangles' corners."""
        return self.points if self.triangles is None else self.triangles.reshape(-1, 3)


def _casters(placed, settings: StagedSettings):
    out = []
    for item, furniture in placed:
        T = world_from_item(item)
        for part in furniture.parts:
            if not part.casts_shadow:
                continue
            if part.convex and part.outline is not None:  # a few points stand in for a stuffed or draped part
                v = part.outline @ T[:3, :3].T + T[:3, 3]
            else:
                v = part.vertices @ T[:3, :3].T + T[:3, 3]
            if v[:, 2].max() < settings.caster_min_height_m:
                continue
            tri = None if part.convex else v[part.faces]
            out.append(_Caster(v, tri, float(v[:, 2].min()), float(v[:, 2].max())))
    return out


_SUB = 4  # fixed-point bits for cv2's polygon filling


@dataclass(frozen=True)
class _FloorGrid:
    """A raster over the floor: cell (col, row) covers [origin + (col, row) * cell, + cell)."""

    origin_m: np.ndarray
    cell_m: float
    shape: tuple  # rows, cols

    def to_px(self, xy):
        """Continuous raster coordinates (col, row) of floor points; cell centers at +0.5."""
        return (np.asarray(xy)[..., :2] - self.origin_m) / self.cell_m

    def fixed_px(self, xy) -> np.ndarray:
        """Raster coordinates of floor points, cell centers at integers, in cv2's fixed
        point (``_SUB`` fractional bits), int32."""
        return np.rint((self.to_px(xy) - 0.5) * (1 << _SUB)).astype(np.int32)

    def centers_m(self) -> np.ndarray:
        """(rows * cols, 2) floor points of the cell centres, row by row."""
        rows, cols = np.mgrid[0:self.shape[0], 0:self.shape[1]]
        return np.column_stack([self.origin_m[0] + (cols.ravel() + 0.5) * self.cell_m,
                                self.origin_m[1] + (rows.ravel() + 0.5) * self.cell_m])

    def floor_from_raster(self) -> np.ndarray:
        """3x3 map from raster (col, row, 1), cell centers at integers, to floor (x, y, 1)."""
        return np.array([[self.cell_m, 0, self.origin_m[0] + 0.5 * self.cell_m],
                         [0, self.cell_m, self.origin_m[1] + 0.5 * self.cell_m], [0, 0, 1.0]])


class _Footprints:
    """The casters' points gathered once, so each light direction projects them all in one
    go and fills one convex hull per convex part and all triangles of the others."""

    def __init__(self, casters):
        convex = [c for c in casters if c.triangles is None]
        self.points = np.concatenate([c.points for c in convex]) if convex else np.zeros((0, 3))
        self.ends = np.cumsum([len(c.points) for c in convex])
        tris = [c.triangles.reshape(-1, 3) for c in casters if c.triangles is not None]
        self.triangles = np.concatenate(tris) if tris else np.zeros((0, 3))

    def fill(self, raster, grid, direction=None, source=None):
        """Fill the casters' shadows along ``direction``, or from a point ``source`` (3,)
        above them; their footprints when neither."""
        for pts, convex in ((self.points, True), (self.triangles, False)):
            if not len(pts):
                continue
            if source is not None:
                xy = _from_source(pts, source)
            else:
                xy = pts[:, :2] if direction is None else pts[:, :2] - (pts[:, 2:3] / direction[2]) * direction[:2]
            fixed = grid.fixed_px(xy)
            if convex:
                for part in np.split(fixed, self.ends[:-1]):
                    cv2.fillConvexPoly(raster, cv2.convexHull(part), 1, lineType=cv2.LINE_8, shift=_SUB)
            else:
                cv2.fillPoly(raster, list(fixed.reshape(-1, 3, 2)), 1, lineType=cv2.LINE_8, shift=_SUB)


def _from_source(points, source):
    """Where the light from ``source`` (3,) past points (n, 3) meets the floor, (n, 2).
    Points high up near the source are taken lower: their shadows would run far, faint."""
    s = np.asarray(source, dtype=np.float64)
    z = np.minimum(points[:, 2:3], RENDER.lamps.shadow_top_share * s[2])
    return s[:2] + (points[:, :2] - s[:2]) * (s[2] / (s[2] - z))


def _lamp_shadow(footprints, grid, lamp, settings: StagedSettings):
    """A lamp's shadow on the floor raster (rows, cols) float32 in [0, 1]: hard shadows
    from points spread over the lamp's shade, averaged."""
    shade = np.zeros(grid.shape, np.float32)
    layer = np.zeros(grid.shape, np.uint8)
    radius, n = RENDER.lamps.shade_radius_m, settings.shadow_samples
    for share, angle in _spiral(n):
        r = radius * share
        layer[:] = 0
        footprints.fill(layer, grid, source=np.asarray(lamp.position_m) + [r * math.cos(angle),
                                                                          r * math.sin(angle), 0.0])
        shade += layer
    return _blur(shade / n, max(0.5, 0.5 * radius / math.sqrt(n) / grid.cell_m))


def _blur(image, sigma_px):
    """Gaussian blur whose cost does not grow with sigma (large ones go through a smaller copy)."""
    if sigma_px <= 3.0:
        return cv2.GaussianBlur(image, (0, 0), max(sigma_px, 0.3))
    h, w = image.shape[:2]
    f = sigma_px / 2.5
    small = cv2.resize(image, (max(1, round(w / f)), max(1, round(h / f))), interpolation=cv2.INTER_AREA)
    return cv2.resize(cv2.GaussianBlur(small, (0, 0), 2.5), (w, h), interpolation=cv2.INTER_LINEAR)


def hemisphere_directions(n: int) -> np.ndarray:
    """``n`` unit directions (n, 3) over the upper hemisphere (z > 0), cosine-weighted and
    evenly spread (a golden-angle spiral on the disk, lifted onto the hemisphere): their
    mean visibility is a horizontal surface's share of a uniform sky."""
    k = np.arange(n) + 0.5
    r = np.sqrt(k / n)
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - r * r)], axis=1)


def _spiral(n):
    """``n`` points spread evenly over the unit disk (a golden-angle spiral), as
    (distance from the centre, angle) pairs."""
    golden = math.pi * (3 - math.sqrt(5))
    return [(math.sqrt((k + 0.5) / n), k * golden) for k in range(n)]


def _shadow_directions(direction, softness_rad, n):
    """``n`` directions spread evenly over a disk of angular radius ``softness_rad`` about ``direction``."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    a = np.cross(d, [0, 0, 1.0]) if abs(d[2]) < 0.99 else np.array([1.0, 0, 0])
    a /= np.linalg.norm(a)
    b = np.cross(d, a)
    out = []
    for share, angle in _spiral(n):
        v = d + math.tan(softness_rad * share) * (math.cos(angle) * a + math.sin(angle) * b)
        out.append(v / np.linalg.norm(v))
    return out


@dataclass(frozen=True)
class _FloorShading:
    """The furniture's shading of the floor: (rows, cols) float32 rasters over ``grid``."""

    gain: np.ndarray        # what the floor's brightness is multiplied by, in the photo's gamma
    grid: _FloorGrid
    key_shadow: np.ndarray  # share of the key light the furniture takes, 0-1, the floor run on past the walls
    ao: np.ndarray          # share of the ambient light it takes, 0-1, before ``ao_strength``


def _ao_reach_m(height_m, settings: StagedSettings) -> float:
    """How far beside a thing of this height its occlusion of the sky is worked out."""
    return float(np.clip(settings.ao_reach_rel * height_m, 0.35, settings.ao_reach_max_m))


def _floor_gain(casters, lighting: Lighting, extent_m, settings: StagedSettings,
                light_map: _LightMap | None = None) -> _FloorShading:
    """What the floor's brightness is multiplied by, in the photo's gamma: (irradiance with
    the furniture / without) ** (1 / 2.2), as a (rows, cols) float32 raster over the floor
    rectangle ``extent_m`` ((xmin, ymin), (xmax, ymax)); with its grid and the key light's
    shadow and the occlusion it is made of (the walls take them too, :func:`_wall_gain`).

    The key light's shadow is the average of hard shadows cast along directions spread
    over the light's angular size (soft, and sharper near contact); ambient occlusion is
    the share of a uniform sky the parts hide, sampled over the hemisphere (under a raised
    top and beside a cabinet alike); what stands on the floor darkens a thin line around
    its foot (contact). Ceiling lamps light the floor besides (their share where
    ``light_map`` says how much the rest gives), partly shadowed from the lamp, partly
    occluded like the sky."""
    lo, hi = np.asarray(extent_m[0], dtype=np.float64), np.asarray(extent_m[1], dtype=np.float64)
    size = hi - lo
    cell = max(settings.floor_cell_min_m, float(size.max()) / settings.floor_cell_max_px)
    shape = (int(math.ceil(size[1] / cell)) + 1, int(math.ceil(size[0] / cell)) + 1)
    grid = _FloorGrid(lo, cell, shape)
    if not casters:
        none = np.zeros(shape, np.float32)
        return _FloorShading(np.ones(shape, np.float32), grid, none, none)
    shadow = np.zeros(shape, np.float32)
    layer = np.zeros(shape, np.uint8)
    dirs = [d for d in _shadow_directions(lighting.direction, lighting.softness_rad, settings.shadow_samples)
            if d[2] < -0.05]
    footprints = _Footprints(casters)
    height = float(np.median([c.z_top for c in casters]))  # a typical height, for the samples' spacing
    for d in dirs:
        layer[:] = 0
        footprints.fill(layer, grid, d)
        shadow += layer
    if dirs:
        shadow /= len(dirs)
        # The samples are discrete copies; blur by about their spacing at a typical height.
        spacing = height * math.tan(lighting.softness_rad) * 2.0 / math.sqrt(len(dirs))
        shadow = _blur(shadow, max(0.5, 0.35 * spacing / cell))
    k = max(1, int(round(settings.ao_cell_m / cell)))  # occlusion is smooth: a coarser raster
    coarse = _FloorGrid(lo, cell * k, (shape[0] // k + 1, shape[1] // k + 1))
    # Ambient occlusion: the share of a uniform sky each floor point sees past the parts,
    # the mean over cosine-weighted directions of the parts' shadows cast along them.
    n = settings.ao_directions
    hidden = np.zeros(coarse.shape, np.float32)
    raster = np.zeros(coarse.shape, np.uint8)
    for up in hemisphere_directions(n):
        raster[:] = 0
        footprints.fill(raster, coarse, -up)
        hidden += raster
    hidden = _blur(hidden / n, settings.ao_blur_rel * height * math.sqrt(math.pi / n) / coarse.cell_m)
    # Past each part's reach its occlusion fades out (over the last quarter): the few
    # directions' shadows that land that far are sampling noise, and the raster ends there.
    near = np.zeros(coarse.shape, np.float32)
    reach = np.ceil(np.array([_ao_reach_m(c.z_top, settings) for c in casters]) * 4.0) / 4.0  # in 25 cm steps
    for r in np.unique(reach):
        raster[:] = 0
        tops = [_Caster(casters[i].corners, None, 0.0, 0.0) for i in np.flatnonzero(reach == r)]
        _Footprints(tops).fill(raster, coarse)
        dist_m = cv2.distanceTransform(1 - raster, cv2.DIST_L2, 3) * coarse.cell_m
        near = np.maximum(near, np.clip((r - dist_m) / (0.25 * r), 0.0, 1.0))

    def fine(raster):  # a coarse raster at the full one's cells (their centres line up)
        return cv2.resize(raster.astype(np.float32), None, fx=k, fy=k,
                          interpolation=cv2.INTER_LINEAR)[:shape[0], :shape[1]]
    ao = fine(hidden * near)
    f_key = lighting.key_fraction
    if lighting.sun is not None:  # only the floor in the sun loses the sun
        f_key = (f_key * lighting.sun.sunlit(grid.centers_m())).reshape(shape).astype(np.float32)
    ratio = 1.0 - f_key * shadow - (1.0 - f_key) * settings.ao_strength * ao
    if lighting.lamps:
        # The lamps' shares of the light change slowly: worked out on the coarse raster.
        xy = coarse.centers_m()
        rest = np.ones(len(xy)) if light_map is None else light_map.at(xy)
        if lighting.sun is not None:  # the light map is the shade's
            rest = rest * (1.0 + (_sun_contrast(lighting) - 1.0) * lighting.sun.sunlit(xy))
        lamps = [lamp.on_floor(xy) for lamp in lighting.lamps]
        total = rest + sum(lamps)
        ratio = ratio * fine((rest / total).reshape(coarse.shape))
        direct = 1.0 - settings.lamp_diffuse_share
        for lamp, light in zip(lighting.lamps, lamps):
            ratio += fine((light / total).reshape(coarse.shape)) * (
                direct * (1.0 - _lamp_shadow(footprints, grid, lamp, settings))
                + (1.0 - direct) * (1.0 - settings.ao_strength * ao))
    # Contact: right beside a leg or a base standing on the floor, the floor sees little of
    # any light; a dark line a centimetre or two wide, at the full raster's resolution.
    feet = [c.points[c.points[:, 2] < c.z_bottom + settings.contact_band_m] for c in casters
            if c.z_bottom < settings.contact_height_m]
    feet = [p for p in feet if len(p) >= 3]
    if feet:
        raster = np.zeros(shape, np.uint8)
        _Footprints([_Caster(p, None, 0.0, 0.0) for p in feet]).fill(raster, grid)
        contact = np.clip(_blur(raster.astype(np.float32), settings.contact_sigma_m / cell), 0, 1)
        ratio = ratio * (1.0 - settings.contact_strength * contact)
    return _FloorShading(np.power(np.clip(ratio, 0.02, 1.0), 1.0 / GAMMA).astype(np.float32), grid, shadow,
                         ao.astype(np.float32))


def _wall_gain(shading: _FloorShading, casters, walls_m, floor_m, lighting: Lighting, K, pose, box,
               settings: StagedSettings):
    """What the photo's pixels that are not floor are multiplied by for the furniture's
    shadows where they show a wall, (height, width) float32 over ``box`` (x0, y0, x1, y1;
    undistorted pixels); and the share of each pixel whose ray meets the floor inside
    ``floor_m`` (n, 2) before any wall (floor the mask left out: it takes the floor's
    gain), (height, width) float32. Past the floor's outline where it is not a wall (the
    photo's edge), what stands is not known: 1.

    A wall point (the first of ``walls_m`` (k, 2, 2) a pixel's ray meets) takes the key
    light's shadow, by the key light's share of the wall's light (it depends on how
    squarely the light meets the wall): it is in shadow as far as the floor it would light
    past the wall, were the wall not there, is, since the furniture stands in front of the
    wall. The rest of its light, but the lamps', is the room's, which the furniture
    occludes (:func:`_wall_shading`); each lamp's, by its share, is shadowed from the lamp
    or occluded, as on the floor."""
    x0, y0, x1, y1 = box
    bw, bh = x1 - x0, y1 - y0
    step = max(1, math.ceil(math.sqrt(bw * bh / settings.wall_samples)))  # the shadows are soft
    X, Y = np.meshgrid(np.arange(0, bw, step, dtype=np.float64) + x0, np.arange(0, bh, step, dtype=np.float64) + y0)
    shape = X.shape
    R = pose[:3, :3]
    cam = -R.T @ pose[:3, 3]
    rays = (R.T @ (np.linalg.inv(K) @ np.stack([X.ravel(), Y.ravel(), np.ones(X.size)]))).T
    reach = np.maximum(np.hypot(rays[:, 0], rays[:, 1]), 1e-12)  # horizontal meters per unit of ray
    t_wall, which = _first_wall(walls_m, rays, cam[:2])
    t_floor = np.full(len(rays), np.inf)
    down = rays[:, 2] < 0
    t_floor[down] = cam[2] / -rays[down, 2] * reach[down]
    on_wall = np.isfinite(t_wall) & (t_wall <= t_floor)
    grid = shading.grid

    def sample(raster, xy, outside, on=grid):  # a raster over ``on`` at the samples' points
        m = (on.to_px(xy) - 0.5).astype(np.float32).reshape(shape + (2,))
        return cv2.remap(raster, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                         borderValue=outside).ravel()

    floor = t_floor < t_wall
    hit = cam[:2] + rays[floor, :2] * (t_floor[floor] / reach[floor])[:, None]
    floor[floor] = skimage.measure.points_in_poly(hit, floor_m)
    floor = floor.reshape(shape).astype(np.float32)
    gain = np.ones(shape, np.float32)
    if on_wall.any():
        p = cam + rays * (np.where(on_wall, t_wall, 0.0) / reach)[:, None]
        e = walls_m[:, 1] - walls_m[:, 0]
        normals = np.column_stack([-e[:, 1], e[:, 0]]) / np.maximum(np.hypot(e[:, 0], e[:, 1]), 1e-12)[:, None]
        normals *= np.where(np.einsum("ij,ij->i", cam[:2] - walls_m[:, 0], normals) < 0, -1.0, 1.0)[:, None]
        n = normals[np.maximum(which, 0)]
        foot = p[:, :2] + 0.01 * n  # just in front of the wall: which floor is in the sun there
        ao = np.zeros(len(p))
        lamp_shadow = np.zeros((len(lighting.lamps), len(p)))
        for k, found in enumerate(_wall_shading(casters, walls_m, normals, lighting.lamps, settings)):
            mine = which == k
            if found is not None and mine.any():
                uz = np.column_stack([(p[:, :2] - walls_m[k, 0]) @ _unit(walls_m[k, 1] - walls_m[k, 0]), p[:, 2]])
                ao[mine] = sample(found.hidden, uz, 0.0, found.grid)[mine]
                for i, shade in enumerate(found.lamp_shadows):
                    lamp_shadow[i, mine] = sample(shade, uz, 0.0, found.grid)[mine]
        d = np.asarray(lighting.direction, dtype=np.float64)
        d = d / np.linalg.norm(d)
        key = np.zeros(len(p))
        lit = np.zeros(len(p))  # the key light on the wall, over the floor at large's
        f = lighting.key_fraction
        if d[2] < -0.05 and f > 0:
            key = sample(shading.key_shadow, p[:, :2] + (p[:, 2] / -d[2])[:, None] * d[:2], 0.0)
            square = np.maximum(0.0, -(n @ d[:2])) / -d[2]  # the key light on the wall over that on the floor
            f = f if lighting.sun is None else f * lighting.sun.sunlit(foot)
            lit = f * square
        rest = np.maximum(lit + (1.0 - f) * settings.wall_ambient_share, 1e-9)
        occluded = 1.0 - settings.ao_strength * ao
        ratio = 1.0 - (lit * key + (rest - lit) * settings.ao_strength * ao) / rest
        if lighting.lamps:  # as on the floor: each lamp's share, shadowed from it or occluded
            normals3 = np.column_stack([n, np.zeros(len(n))])
            on = [lamp.on(p, normals3) for lamp in lighting.lamps]
            total = rest + sum(on)
            direct = 1.0 - settings.lamp_diffuse_share
            ratio = ratio * rest / total + sum(light / total * (direct * (1.0 - shade) + (1.0 - direct) * occluded)
                                               for light, shade in zip(on, lamp_shadow))
        ratio = np.power(np.clip(ratio, 0.02, 1.0), 1.0 / GAMMA).reshape(shape).astype(np.float32)
        # Smoothed over the walls alone (the outline's short steps would show as seams).
        wall = on_wall.reshape(shape).astype(np.float32)
        sigma = settings.wall_smooth_px / step
        smooth = cv2.GaussianBlur(ratio * wall, (0, 0), sigma) / np.maximum(cv2.GaussianBlur(wall, (0, 0), sigma), 1e-6)
        # Where neither wall nor floor inside the outline (what stands in front of a wall: a
        # carton), the wall's gain runs on over a sample or two, fading, and the floor's share
        # is blurred as much: hard switches would step along the sample grid across the carton.
        near = cv2.GaussianBlur(wall, (0, 0), 1.0)
        neither = near * smooth + (1.0 - near)
        gain = np.where(wall > 0, smooth, np.where(floor > 0, 1.0, neither)).astype(np.float32)
        floor = cv2.GaussianBlur(floor, (0, 0), 1.0)
    up = np.array([[1.0 / step, 0, 0], [0, 1.0 / step, 0]])
    return tuple(cv2.warpAffine(a, up, (bw, bh), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                borderMode=cv2.BORDER_REPLICATE) for a in (gain, floor))


def _unit(v) -> np.ndarray:
    return np.asarray(v, dtype=np.float64) / max(float(np.linalg.norm(v)), 1e-12)


def _in_front(local):
    """Points in a wall's frame (along, height, distance) kept in front of it: what reaches
    through it (a piece touching the wall, the wall measured a little off) stands on it."""
    return np.concatenate([local[..., :2], np.maximum(local[..., 2:], 1e-3)], axis=-1)


@dataclass(frozen=True)
class _WallShading:
    """What the furniture takes of one wall's light, over a raster in the wall's own plane
    (grid x: meters along the wall from its first end; y: height above the floor)."""

    grid: _FloorGrid
    hidden: np.ndarray         # share of the room's light (sky, ceiling, floor) hidden, cosine-weighted
    lamp_shadows: tuple        # per lamp of the lighting: the share of its light the furniture stops


def _wall_shading(casters, walls_m, normals, lamps, settings: StagedSettings) -> list:
    """Per wall of ``walls_m`` (k, 2, 2) facing the room along ``normals`` (k, 2): its
    :class:`_WallShading`, or None where nothing stands near it. The occlusion is the
    floor's sampling turned onto the wall: it falls off with distance and height, not the
    outline of what stands there. A lamp's shadow falls from its shade's points through
    what stands between it and the wall."""
    out = []
    radius, n_shade = RENDER.lamps.shade_radius_m, settings.shadow_samples
    for (a, b), n in zip(np.asarray(walls_m, dtype=np.float64), np.asarray(normals, dtype=np.float64)):
        e = _unit(b - a)
        length = float(np.linalg.norm(b - a))

        def local(q):  # (along the wall, height, distance in front of it)
            return np.stack([(q[..., :2] - a) @ e, q[..., 2], (q[..., :2] - a) @ n], axis=-1)
        near, reach = [], 0.0
        for c in casters:
            at = local(c.corners)
            r = _ao_reach_m(c.z_top, settings)
            if at[:, 2].min() > r or at[:, 2].max() <= 0 or at[:, 0].max() < -r or at[:, 0].min() > length + r:
                continue
            near.append(_Caster(_in_front(local(c.points)), None if c.triangles is None else
                                _in_front(local(c.triangles)), 0.0, 0.0))
            reach = max(reach, r)
        if not near:
            out.append(None)
            continue
        pts = np.concatenate([c.corners for c in near])
        lo = np.array([pts[:, 0].min() - reach, 0.0])
        above = settings.wall_ao_above * reach
        hi = np.array([pts[:, 0].max() + reach, pts[:, 1].max() + above])
        size = hi - lo
        cell = max(settings.wall_ao_cell_m, float(size.max()) / settings.floor_cell_max_px)
        grid = _FloorGrid(lo, cell, (int(math.ceil(size[1] / cell)) + 1, int(math.ceil(size[0] / cell)) + 1))
        footprints = _Footprints(near)
        n_dirs = settings.wall_ao_directions
        hidden = np.zeros(grid.shape, np.float32)
        raster = np.zeros(grid.shape, np.uint8)
        for up in hemisphere_directions(n_dirs):  # about the wall's normal, in (along, height, out)
            raster[:] = 0
            footprints.fill(raster, grid, -up)
            hidden += raster
        # The copies lie about their distance from the wall x the directions' spacing apart.
        gap = float(np.median([c.corners[:, 2].max() for c in near]))
        hidden = _blur(hidden / n_dirs, settings.ao_blur_rel * gap * math.sqrt(math.pi / n_dirs) / cell)
        # Faded out toward the reach's sides and top (over its last quarter), where the
        # samples thin out and what is left is faint.
        u = grid.origin_m[0] + (np.arange(grid.shape[1]) + 0.5) * cell
        z = (np.arange(grid.shape[0]) + 0.5) * cell
        side = np.minimum(u - (pts[:, 0].min() - reach), pts[:, 0].max() + reach - u) / (0.25 * reach)
        top = (pts[:, 1].max() + above - z) / (0.25 * above)
        fade = np.clip(np.minimum(top[:, None], side[None, :]), 0.0, 1.0).astype(np.float32)
        hidden *= fade
        # Less than a level of 255 left out: the shading (and a layer's alpha) ends somewhere.
        least = settings.wall_ao_min
        hidden = (hidden * np.clip(hidden / least - 1.0, 0.0, 1.0)).astype(np.float32)  # 0 up to it, as is from 2x
        # A lamp in front of the wall shades it with what stands nearer the wall than it,
        # as far as the occlusion reaches (the region worked out ends there).
        shadows = []
        for lamp in lamps:
            source = local(np.asarray(lamp.position_m, dtype=np.float64))
            between = [c for c in near if c.corners[:, 2].max() < source[2] - 0.05]
            shade = np.zeros(grid.shape, np.float32)
            if source[2] > 0 and between:
                lamp_footprints = _Footprints(between)
                for share, angle in _spiral(n_shade):
                    offset = radius * share * np.array([math.cos(angle), math.sin(angle)])  # on the shade's disk
                    raster[:] = 0
                    lamp_footprints.fill(raster, grid, source=source + [offset @ e, 0.0, offset @ n])
                    shade += raster
                shade = _blur(shade / n_shade, max(0.5, 0.5 * radius / math.sqrt(n_shade) / cell)) * fade
            shadows.append(shade)
        out.append(_WallShading(grid, hidden, tuple(shadows)))
    return out


def _panes(windows_px, K, dist, box) -> np.ndarray:
    """(height, width) bool over ``box`` (undistorted pixels): inside the windows
    ``windows_px`` (each (4, 2) photo pixels)."""
    x0, y0, x1, y1 = box
    inside = np.zeros((y1 - y0, x1 - x0), np.uint8)
    for quad in windows_px:
        q = np.asarray(quad, dtype=np.float64).reshape(-1, 1, 2)
        if np.any(dist):
            q = cv2.undistortPoints(q, K, dist, P=K)
        hull = cv2.convexHull(np.round((q.reshape(-1, 2) - [x0, y0]) * (1 << _SUB)).astype(np.int32))
        cv2.fillConvexPoly(inside, hull, 1, lineType=cv2.LINE_8, shift=_SUB)
    return inside > 0


# --------------------------------------------------------------------------------------
# Occlusion by what the photo shows in front of the furniture
# --------------------------------------------------------------------------------------

def _box_K(K, box, size):
    """Intrinsics of the photo's box (x0, y0, x1, y1) rendered at ``size`` (cols, rows)
    (pixel edges kept, as :func:`_scaled_K`)."""
    Kb = K.astype(np.float64).copy()
    for axis, (low, n, m) in enumerate(((box[0], size[0], box[2] - box[0]), (box[1], size[1], box[3] - box[1]))):
        Kb[axis, axis] = K[axis, axis] * n / m
        Kb[axis, 2] = (K[axis, 2] - low + 0.5) * n / m - 0.5
    return Kb


def _scaled_K(K, s):
    """Intrinsics of the image resized by ``s`` (pixel edges kept: centers move by (s - 1) / 2)."""
    Ks = K.astype(np.float64).copy()
    Ks[0, 0] *= s
    Ks[1, 1] *= s
    Ks[0, 2] = (K[0, 2] + 0.5) * s - 0.5
    Ks[1, 2] = (K[1, 2] + 0.5) * s - 0.5
    return Ks


def _mask_occluders(floor_mask, K, pose, settings: StagedSettings):
    """How far (horizontally, meters) from the camera the photo's content stands at each
    pixel, (h', w') float32 at working scale ``s`` (also returned): a pixel that is not
    floor shows something standing on the first floor pixel below it, along the image of
    the vertical through it; 1e6 where that walk leaves the photo first."""
    h, w = floor_mask.shape
    s = min(1.0, settings.occlusion_long_px / max(h, w))
    hs, ws = max(2, round(h * s)), max(2, round(w * s))
    m = cv2.resize(floor_mask.astype(np.uint8) * 255, (ws, hs), interpolation=cv2.INTER_AREA) > 127
    # Specks of "not floor" inside the floor are segmentation noise.
    n, labels, stats, _ = cv2.connectedComponentsWithStats((~m).astype(np.uint8), connectivity=4)
    speck = np.zeros(n, bool)
    speck[1:] = stats[1:, cv2.CC_STAT_AREA] < max(4, 2e-4 * hs * ws)
    m |= speck[labels]
    Ks = _scaled_K(K, s)
    R, t = pose[:3, :3], pose[:3, 3]
    down = Ks @ (R @ np.array([0, 0, -1.0]))  # the vertical's vanishing point, homogeneous
    y_ref = float(hs - 1)
    if abs(down[2]) > 1e-9 * np.linalg.norm(down[:2]):
        vx, vy = down[0] / down[2], down[1] / down[2]

        def x_of(u, y):  # the line through the vanishing point and (u, y_ref), at row y
            return vx + (u - vx) * (y - vy) / (y_ref - vy)

        def u_of(x, y):
            return vx + (x - vx) * (y_ref - vy) / np.where(np.abs(y - vy) < 1e-9, 1e-9, y - vy)
    else:  # level camera: verticals are parallel in the image
        slope = down[0] / down[1] if abs(down[1]) > 1e-12 else 0.0

        def x_of(u, y):
            return u + slope * (y - y_ref)

        def u_of(x, y):
            return x - slope * (y - y_ref)
    cu = u_of(np.array([0.0, ws - 1.0, 0.0, ws - 1.0]), np.array([0.0, 0.0, y_ref, y_ref]))
    u_lo, u_hi = float(cu.min()), float(cu.max())
    nu = int(np.clip(u_hi - u_lo + 1, 2, 4 * ws))
    us = np.linspace(u_lo, u_hi, nu, dtype=np.float32)
    ys = np.arange(hs, dtype=np.float32)
    X = x_of(us[:, None], ys[None, :]).astype(np.float32)  # (nu, hs): column u, row y
    xi = np.rint(X).astype(np.int32)
    inside = (xi >= 0) & (xi < ws)
    floor = np.zeros(X.shape, bool)
    yi = np.broadcast_to(np.arange(hs, dtype=np.int32), X.shape)
    floor[inside] = m[yi[inside], xi[inside]]
    # Walking down the image (increasing y): the first floor sample, or the photo's edge.
    idx = np.where(floor | ~inside, np.arange(hs, dtype=np.int32)[None, :], hs)
    first = np.minimum.accumulate(idx[:, ::-1], axis=1)[:, ::-1]
    j = np.minimum(first, hs - 1)
    hit = (first < hs) & np.take_along_axis(floor, j, axis=1)
    # Horizontal distance of that floor sample from the camera.
    fx = np.take_along_axis(X, j, axis=1)
    fy = j.astype(np.float32)
    Hinv = np.linalg.inv(Ks @ np.column_stack([R[:, 0], R[:, 1], t])).astype(np.float32)
    qx = Hinv[0, 0] * fx + Hinv[0, 1] * fy + Hinv[0, 2]
    qy = Hinv[1, 0] * fx + Hinv[1, 1] * fy + Hinv[1, 2]
    qw = Hinv[2, 0] * fx + Hinv[2, 1] * fy + Hinv[2, 2]
    cam_xy = (-R.T @ t)[:2]
    ok = hit & (qw > 1e-9)
    qw = np.where(ok, qw, 1.0)
    dist = np.where(ok, np.hypot(qx / qw - cam_xy[0], qy / qw - cam_xy[1]), 1e6).astype(np.float32)
    # Back to image pixels.
    yy, xx = np.mgrid[0:hs, 0:ws].astype(np.float32)
    U = ((u_of(xx, yy) - u_lo) * ((nu - 1) / max(u_hi - u_lo, 1e-9))).astype(np.float32)
    out = cv2.remap(np.ascontiguousarray(dist.T), U, yy, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT,
                    borderValue=1e6)
    return out, s


class _Bounded(dict):
    """A dict that forgets its oldest entries beyond ``size``."""

    def __init__(self, size):
        super().__init__()
        self.size = size

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        while len(self) > self.size:
            del self[next(iter(self))]


# Per photo: the same mask and camera for every suggestion. Furniture: per item and style,
# enough for one photo's suggestions; more only grows a batch worker (photos share no piece).
_OCCLUDERS = _Bounded(4)
_MATTES = _Bounded(2)
_FURNITURE = _Bounded(64)


def _mask_occluders_cached(floor_mask, K, pose, settings):
    key = (hashlib.sha1(np.packbits(floor_mask)).hexdigest(), floor_mask.shape, K.tobytes(), pose.tobytes(),
           settings.occlusion_long_px)
    if key not in _OCCLUDERS:
        _OCCLUDERS[key] = _mask_occluders(floor_mask, K, pose, settings)
    return _OCCLUDERS[key]


def _floor_matte_cached(image, floor_mask, settings):
    """:func:`floor_matte` of the whole photo, once for all its suggestions: known by its
    mask and every fourth pixel of it each way (hashing all of a 12 MP photo per render
    costs 30 ms)."""
    h, w = floor_mask.shape
    key = (hashlib.sha1(np.packbits(floor_mask)).hexdigest(),
           hashlib.sha1(np.ascontiguousarray(image[::4, ::4])).hexdigest(), floor_mask.shape,
           settings.matte_radius_share, settings.matte_eps, settings.matte_long_px)
    if key not in _MATTES:
        _MATTES[key] = floor_matte(image, floor_mask, max(h, w) * settings.matte_radius_share, settings.matte_eps,
                                   min(1.0, settings.matte_long_px / max(h, w)))
    return _MATTES[key]


def _first_wall(walls_m, rays_floor, cam_xy):
    """Horizontal distance along each ray's azimuth to the first wall segment (n,), inf if
    none; and that wall's index (n,), -1 if none.

    walls_m : (k, 2, 2) segments; rays_floor : (n, 3) ray directions in the floor frame."""
    rays = np.ascontiguousarray(np.asarray(rays_floor)[:, :2], dtype=np.float64)
    best = np.full(len(rays), np.inf)
    which = np.full(len(rays), -1, np.int64)
    _first_wall_kernel(np.ascontiguousarray(walls_m, dtype=np.float64), rays,
                       float(cam_xy[0]), float(cam_xy[1]), best, which)
    return best, which


@njit(cache=True, parallel=True)
def _first_wall_kernel(walls, rays, cx, cy, best, which):
    """Per ray (its horizontal direction), the nearest wall it crosses ahead: into ``best``, ``which``."""
    for i in prange(rays.shape[0]):
        n = math.hypot(rays[i, 0], rays[i, 1])
        if n < 1e-12:
            n = 1e-12
        dx, dy = rays[i, 0] / n, rays[i, 1] / n
        for k in range(walls.shape[0]):
            ex, ey = walls[k, 1, 0] - walls[k, 0, 0], walls[k, 1, 1] - walls[k, 0, 1]
            rx, ry = walls[k, 0, 0] - cx, walls[k, 0, 1] - cy
            denom = ey * -dx + dy * ex
            if abs(denom) <= 1e-12:
                continue
            t = (ey * -rx + ry * ex) / denom
            u = (dx * ry - dy * rx) / denom
            if t > 0.0 and 0.0 <= u <= 1.0 and t < best[i]:
                best[i] = t
                which[i] = k


def _in_room(walls_m, cam_xy, slack_m: float = 0.1):
    """Floor points (n, 2) -> (n,) bool: not behind a wall in view (seen from the camera's
    foot, no wall segment (k, 2, 2) crosses the way there more than ``slack_m`` before it)."""
    def inside(xy):
        way = np.asarray(xy, dtype=np.float64)[:, :2] - np.asarray(cam_xy, dtype=np.float64)
        wall_m, _ = _first_wall(walls_m, way, cam_xy)
        return wall_m >= np.linalg.norm(way, axis=1) - slack_m
    return inside


def wall_segments(floor_polygon) -> np.ndarray:
    """Wall segments (k, 2, 2) of a floor polygon: every edge of an (n, 2) array, or the
    ``"boundary"`` edges of a :class:`~augment.floor.polygon.FloorPolygon` (its ``"image"`` and
    ``"far"`` edges are not walls)."""
    poly = np.asarray(getattr(floor_polygon, "polygon_m", floor_polygon), dtype=np.float64)
    if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3:
        raise ValueError(f"floor polygon must be (n, 2) with n >= 3 vertices in meters, got shape {poly.shape}")
    edges = np.stack([poly, np.roll(poly, -1, axis=0)], axis=1)
    kinds = getattr(floor_polygon, "edge_kind", None)
    if kinds is not None:
        edges = edges[np.asarray(kinds) == "boundary"]
    return edges


def _walls_run_on(floor_polygon, run_on_m) -> np.ndarray:
    """The wall segments of :func:`wall_segments`, those that end at the photo's edge or the
    far floor run on by ``run_on_m`` there: the wall goes on where the floor leaves the view."""
    walls = wall_segments(floor_polygon)
    kinds = getattr(floor_polygon, "edge_kind", None)
    if kinds is None:
        return walls
    wall = np.asarray(kinds) == "boundary"
    e = walls[:, 1] - walls[:, 0]
    e = e / np.maximum(np.linalg.norm(e, axis=1), 1e-12)[:, None]
    walls = walls.copy()
    walls[:, 0] -= e * (run_on_m * ~np.roll(wall, 1)[wall])[:, None]
    walls[:, 1] += e * (run_on_m * ~np.roll(wall, -1)[wall])[:, None]
    return walls


# --------------------------------------------------------------------------------------
# render_staged
# --------------------------------------------------------------------------------------

@dataclass
class Staged:
    """A staged photo.

    Attributes
    ----------
    image : (h, w, 3) uint8
        The photo with the furniture and its shadows, full resolution.
    layer : (h, w, 4) uint8 or None
        Furniture and shadows alone, straight alpha: laid over the photo it gives ``image``.
    alpha : (h, w) float32
        Furniture coverage, 0-1, after occlusion.
    gain : (h, w) float32
        What the photo was multiplied by for the shadows (1 = untouched).
    lighting : Lighting
    roi_px : (4,) tuple of int
        x0, y0, x1, y1 of the rendered region (outside it the photo is untouched).
    render_scale : float
        Rendered pixels per photo pixel along each axis (above 1: supersampled).
    timings_s : dict
        Seconds per stage.
    """

    image: np.ndarray
    layer: np.ndarray | None
    alpha: np.ndarray
    gain: np.ndarray
    lighting: Lighting
    roi_px: tuple
    render_scale: float
    timings_s: dict = field(default_factory=dict)


def _check_image(image) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise ValueError(f"image must be (h, w, 3) uint8 RGB, got shape {a.shape} dtype {a.dtype}")
    return a


def _reach_points(placed, lighting: Lighting, settings: StagedSettings):
    """Floor-frame points whose projection bounds what the furniture and its shadows can
    touch: each box's corners grown by its occlusion's reach, sideways and up (the walls'),
    and the shadows of its upper corners along the key light's extreme directions and from
    the lamps."""
    out = []
    dirs = [v for v in _shadow_directions(lighting.direction, lighting.softness_rad, 8) if v[2] < -0.05]
    for item, _ in placed:
        reach = _ao_reach_m(item.size_m[2], settings)
        world = _item_corners(item, reach)
        out.append(world)
        top = world[1::2]
        out.append(top + [0.0, 0.0, settings.wall_ao_above * reach])  # the walls' occlusion above it
        for v in dirs:
            out.append(top - np.outer(top[:, 2] / v[2], v))
        for lamp in lighting.lamps:
            out.append(np.column_stack([_from_source(top, lamp.position_m), np.zeros(len(top))]))
    return np.concatenate(out)


def _roi(points_px, depth, size_px, margin):
    w, h = size_px
    if np.any(depth <= RENDER.gl.znear_m):  # something reaches behind the camera: everything may show
        return (0, 0, w, h)
    x0, y0 = np.floor(points_px.min(axis=0)).astype(int) - margin
    x1, y1 = np.ceil(points_px.max(axis=0)).astype(int) + margin + 1
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(w, x1), min(h, y1)
    if x1 <= x0 or y1 <= y0:
        return None
    return (int(x0), int(y0), int(x1), int(y1))


def _furniture_box(placed, K, pose, box, margin):
    """The part of ``box`` (pixels of the undistorted view) the items' bounding boxes
    cover, grown by ``margin``: all of ``box`` where one reaches behind the camera."""
    px, depth = _project(np.concatenate([_item_corners(item, 0.0) for item, _ in placed]), K, pose)
    inner = _roi(px - box[:2], depth, (box[2] - box[0], box[3] - box[1]), margin)
    if inner is None:
        return box
    return (inner[0] + box[0], inner[1] + box[1], inner[2] + box[0], inner[3] + box[1])


def _item_corners(item, grow_m: float) -> np.ndarray:
    """(8, 3) floor-frame corners of an item's bounding box, grown by ``grow_m`` across
    the floor (its base at z = 0, its top at its height, in its own frame)."""
    W, D, H = item.size_m
    T = world_from_item(item)
    c = np.array([[x, y, z] for x in (-D / 2 - grow_m, D / 2 + grow_m) for y in (-W / 2 - grow_m, W / 2 + grow_m)
                  for z in (0.0, H)])
    return c @ T[:3, :3].T + T[:3, 3]


def _in_box(rgba, low, at, shape):
    """The furniture's layers (its own box) placed at ``at`` in transparent ones of ``shape``."""
    if rgba.shape[:2] == tuple(shape):
        return rgba, low
    inner = rgba, low
    rgba, low = np.zeros((*shape, 4), np.uint8), np.zeros(shape, np.uint8)
    rgba[at], low[at] = inner
    return rgba, low


def _undistort_map(K, dist, roi, step=8):
    """Undistorted pixel coordinates of the photo pixels of ``roi`` (two (h, w) float32
    maps), computed every ``step`` pixels and interpolated."""
    x0, y0, x1, y1 = roi
    gx = np.arange(x0, x1 + step, step, dtype=np.float64)
    gy = np.arange(y0, y1 + step, step, dtype=np.float64)
    X, Y = np.meshgrid(gx, gy)
    # OpenCV's default 5 iterations leave pixels of error toward the corners.
    und = cv2.undistortPoints(np.stack([X.ravel(), Y.ravel()], axis=1).reshape(-1, 1, 2), K, dist, None, None, K,
                              (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-9))
    und = und.reshape(X.shape + (2,)).astype(np.float32)
    # Bilinear between the grid points (cv2.resize would align pixel centers, not grid points).
    u = np.arange(x1 - x0, dtype=np.float32) / step
    v = np.arange(y1 - y0, dtype=np.float32) / step
    U, V = np.meshgrid(u, v)
    mx = cv2.remap(und[..., 0], U, V, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    my = cv2.remap(und[..., 1], U, V, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return mx, my


def _render_scale(box_px, supersample, blur_px, settings: StagedSettings):
    if supersample is not None:
        return float(supersample)
    lowest, highest = settings.min_render_scale, settings.max_supersample
    if blur_px > 0:
        # The scale whose edge spread is the given share of the photo's: coarser is still
        # sharper than the photo, finer the look blurs away (supersampling a soft photo buys nothing).
        enough = settings.render_edge_px / (settings.render_blur_share * blur_px)
        lowest = float(np.clip(enough, settings.blurred_render_scale, lowest))
        highest = float(np.clip(enough, 1.0, highest))
    s = math.sqrt(settings.render_budget_px / box_px)
    s = float(np.clip(s, lowest, highest))
    if 0.85 <= s < 1.3:
        return 1.0  # resampling by a few percent would blur more than it smooths
    return round(s * 4) / 4 if s > 1 else s


def _shadows(placed, reach, lighting: Lighting, light_map, floor_mask, floor_polygon, walls, windows_px, K, dist,
             pose, box, undistort, settings: StagedSettings):
    """The furniture's shading of the photo over ``box``: the floor's gain (the floor raster
    warped onto the box, only where the floor can be: rays pointing down, as the warp
    folds the floor's far side into the sky), the walls' gain, and which pixels are floor
    by the outline; warped onto the photo's pixels by ``undistort`` (the maps of
    :func:`_undistort_map` in the box's pixels, or None).
    Needs nothing of the render: worked out beside it."""
    R, tvec = pose[:3, :3], pose[:3, 3]
    bw, bh = box[2] - box[0], box[3] - box[1]
    casters = _casters(placed, settings)
    on_floor = reach[reach[:, 2] < 1e-6, :2]
    pts = np.concatenate([on_floor] + [c.points[:, :2] for c in casters])
    # The raster reaches as far as the sides' occlusion spreads.
    pad = max((_ao_reach_m(it.size_m[2], settings) for it, _ in placed), default=0.35)
    shading = _floor_gain(casters, lighting, (pts.min(axis=0) - pad, pts.max(axis=0) + pad), settings, light_map)
    shift = np.array([[1.0, 0, -box[0]], [0, 1, -box[1]], [0, 0, 1]])
    H_box = shift @ K @ np.column_stack([R[:, 0], R[:, 1], tvec]) @ shading.grid.floor_from_raster()
    gain = cv2.warpPerspective(shading.gain, H_box, (bw, bh), flags=cv2.INTER_LINEAR,
                               borderMode=cv2.BORDER_CONSTANT, borderValue=1.0)
    up = np.linalg.inv(K).T @ R[:, 2]  # the floor's pixels: up . K^-1 p < 0
    _clear_above_horizon(gain, float(up[0]), float(up[1]), float(up[2]), box[0], box[1])
    # What the mask says is not floor: walls take shadows too (only where the walls are known).
    if floor_mask is not None and walls is not None and len(walls):
        wall_gain, floor_share = _wall_gain(shading, casters, _walls_run_on(floor_polygon, settings.wall_run_on_m),
                                            np.asarray(getattr(floor_polygon, "polygon_m", floor_polygon)), lighting,
                                            K, pose, box, settings)
        if len(windows_px):  # no box-sized mask per render where no window was found
            wall_gain[_panes(windows_px, K, dist, box)] = 1.0
    else:
        wall_gain, floor_share = np.ones_like(gain), np.zeros_like(gain)
    if undistort is not None:
        mx, my = undistort
        gain, wall_gain = (cv2.remap(g, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=1.0)
                           for g in (gain, wall_gain))
        floor_share = cv2.remap(floor_share, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
    return gain, wall_gain, floor_share


def render_staged(image: np.ndarray, calibration, items, renderer: Renderer, *,
                  floor_mask: np.ndarray | None = None, floor_polygon=None,
                  lighting: Lighting | None = None, look: PhotoLook | None = None, seed: int = 0,
                  style: str | None = None, assets: dict | None = None,
                  supersample: float | None = None, self_shadows: bool = True, layer: bool = False,
                  windows_px=(), settings: StagedSettings | None = None) -> Staged:
    """Render furniture into a calibrated photo, with its shadows on the photo's floor.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The photo, RGB. Not modified.
    calibration : Calibration
        Of this photo (``size_px`` must be ``(w, h)``): intrinsics (K, distortion) and
        ``camera_from_floor``. The items are in its floor frame (meters, z up).
    items : sequence of PlacedItem, a Layout, or a layout dict (``layout_K.json``)
        What to render (:func:`augment.render.furniture.placed_items`).
    renderer : Renderer
        The GL context, reused for every render.
    floor_mask : (h, w) bool, optional
        Visible floor (segmentation): what the photo shows standing in front of the
        furniture hides it, and the floor's shadows fall on floor pixels (the walls' on
        the rest, with ``floor_polygon``).
    floor_polygon : FloorPolygon or (n, 2) float, optional
        The floor's outline in the floor frame, meters: its wall edges (every edge of an
        array; the ``"boundary"`` edges of a FloorPolygon) hide what lies beyond them and,
        with ``floor_mask``, take the furniture's shadows.
    lighting : Lighting, optional
        Estimated from the photo (:func:`estimate_lighting`) when None; pass it to reuse
        one estimate for several suggestions.
    look : PhotoLook, optional
        The photo's noise and sharpness, given to the furniture
        (:func:`augment.render.look.estimate_look`, from ``image`` when None; pass the
        estimate from the photo as taken when ``image`` has its board erased).
    seed : int
        Picks each item's design and materials, with the item's id: an item looks the same
        in every suggestion of one style. Also seeds the furniture's noise.
    style : str, optional
        A name of :data:`augment.render.styles.STYLES`: every item in its palette and
        materials; any material when None.
    assets : dict, optional
        Kind -> GLB/OBJ path, or parts from :func:`augment.render.furniture.load_asset`.
    supersample : float, optional
        Rendered pixels per photo pixel along each axis. Default: as many as
        ``settings.render_budget_px`` allows over the region furniture and shadows reach, up
        to 2, and in a soft photo no more than its edge spread asks (1 from ``look.blur_px``
        0.8 on). Larger photos are rendered below 1 and upsampled: down to
        ``settings.min_render_scale``, or lower where the photo's edge spread
        (``look.blur_px``) is wider than the coarser render's. The renderer's 4x
        multisampling antialiases edges in any case.
    self_shadows : bool
        Shadows of the key light on the furniture itself (from a depth map seen from
        the light).
    layer : bool
        Also return the RGBA layer.
    windows_px : sequence of (4, 2) float
        The photo's pixels of each window's corners on the walls
        (:class:`augment.room.openings.FoundWindow`): a pane shows the outside, which the
        furniture's shadows on the walls do not reach.
    settings : StagedSettings, optional
        Default ``RENDER.staged`` (:mod:`augment.render.settings`).

    Returns
    -------
    Staged
    """
    settings = RENDER.staged if settings is None else settings
    timings = {}
    t0 = time.perf_counter()
    image = _check_image(image)
    h, w = image.shape[:2]
    if tuple(calibration.size_px) != (w, h):
        raise ValueError(f"the calibration is for a {calibration.size_px[0]}x{calibration.size_px[1]} photo, "
                         f"the image is {w}x{h}")
    if floor_mask is not None:
        floor_mask = np.asarray(floor_mask)
        if floor_mask.shape != (h, w):
            raise ValueError(f"floor_mask must be ({h}, {w}) like the image, got {floor_mask.shape}")
        floor_mask = floor_mask.astype(bool, copy=False)
    items = list(items) if isinstance(items, (list, tuple)) else placed_items(items)
    walls = None if floor_polygon is None else wall_segments(floor_polygon)
    K, dist, pose = _camera(calibration)
    if lighting is None:
        lighting = estimate_lighting(image, calibration, floor_mask, settings, floor_polygon)
    if look is None:
        look = estimate_look(image, calibration if hasattr(calibration, "board") else None)
    placed = [(it, furniture_for(it, seed, assets, _FURNITURE, style)) for it in items]
    timings["build"] = time.perf_counter() - t0

    # The region of the photo furniture and shadows can reach, and the box to render.
    t = time.perf_counter()
    out = image.copy()
    roi = None
    if placed:
        reach = _reach_points(placed, lighting, settings)
        roi = _roi(*_project(reach, K, pose, dist), (w, h), settings.margin_px)
    if roi is None:  # nothing in view
        zeros, ones = np.zeros((h, w), np.float32), np.ones((h, w), np.float32)
        lay = np.dstack([out, np.zeros((h, w), np.uint8)]) if layer else None
        return Staged(out, lay, zeros, ones, lighting, (0, 0, 0, 0), 1.0, timings)
    x0, y0, x1, y1 = roi
    distorted = bool(np.any(dist))
    if distorted:  # render the undistorted view of the region, then warp it onto the photo
        map_x, map_y = _undistort_map(K, dist, roi)
        box = (int(np.floor(map_x.min())) - 2, int(np.floor(map_y.min())) - 2,
               int(np.ceil(map_x.max())) + 3, int(np.ceil(map_y.max())) + 3)
        undistort = (map_x - box[0], map_y - box[1])  # the box's pixels of each photo pixel
    else:
        box, undistort = roi, None
    bw, bh = box[2] - box[0], box[3] - box[1]
    # The furniture is rendered over its own box within it (the floor's shading reaches
    # further, but costs no rendered pixels): a wide occlusion halo leaves its resolution be.
    fbox = _furniture_box(placed, K, pose, box, settings.margin_px + math.ceil(3.0 * look.blur_px))
    fw, fh = fbox[2] - fbox[0], fbox[3] - fbox[1]
    s = _render_scale(fw * fh, supersample, look.blur_px, settings)
    rw, rh = max(1, round(fw * s)), max(1, round(fh * s))
    Kr = _box_K(K, fbox, (rw, rh))
    timings["setup"] = time.perf_counter() - t

    # The flat passes: all light, and the key light alone for its shadows (premultiplied:
    # the background is transparent black).
    t = time.perf_counter()
    R, tvec = pose[:3, :3], pose[:3, 3]
    cam_pos = -R.T @ tvec
    cam_xy = cam_pos[:2]
    forward_xy = R[2, :2] / max(float(np.linalg.norm(R[2, :2])), 1e-9)
    corners = np.concatenate([world_from_item(it)[:2, 3][None] + np.array([[-1, -1], [1, 1]]) * max(it.size_m[:2])
                              for it, _ in placed])
    light_map = floor_light_map(image, floor_mask, K, dist, pose, lighting, corners.min(axis=0) - 0.5,
                                corners.max(axis=0) + 0.5, settings)
    # The shadows on the photo need nothing of the render: worked out on a second core
    # meanwhile (OpenCV and NumPy let go of the interpreter in their loops).
    beside = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stager-shadows")
    shadows = beside.submit(_shadows, placed, reach, lighting, light_map, floor_mask, floor_polygon, walls,
                            windows_px, K, dist, pose, box, undistort, settings)
    beside.shutdown(wait=False)  # its thread ends with the task
    self_shadows = self_shadows and lighting.key_fraction > 0
    # With self-shadows the first pass is the fill light alone, the key added per pixel.
    fulls, keys = _furniture_meshes(placed, lighting, cam_pos, forward_xy, settings, light_map, renderer,
                                    beam_per_pixel=self_shadows)
    camera, camera_gl = pyrender_camera(Kr), gl_from_cv_pose(np.linalg.inv(pose))
    flags = pyrender.RenderFlags.RGBA | pyrender.RenderFlags.FLAT
    full, depth = renderer.render(_flat_scene(fulls, camera, camera_gl), rw, rh, flags=flags)
    if self_shadows:
        key, _ = renderer.render(_flat_scene(keys, camera, camera_gl), rw, rh, flags=flags, depth=False)
    timings["render"] = time.perf_counter() - t

    # Each furniture pixel's point on the floor frame; the key light's shadows on the
    # furniture (a depth map from the light, filtered over the light's size).
    t = time.perf_counter()
    # Per furniture pixel, millions on a large photo: int32 indices and float32 points
    # (a few micrometers at room distances) halve what float64 would hold.
    ys, xs = (i.astype(np.int32) for i in np.nonzero(full[..., 3]))
    d = depth[ys, xs]
    if (d <= 0).any():  # edge pixels whose depth sample missed: a neighbour's depth
        grown = cv2.dilate(depth, np.ones((3, 3), np.uint8))
        d = np.where(d > 0, d, grown[ys, xs])
    rays = np.empty((3, len(xs)), np.float32)
    rays[0] = (xs - Kr[0, 2]) / Kr[0, 0]
    rays[1] = (ys - Kr[1, 2]) / Kr[1, 1]
    rays[2] = 1.0
    world = (R.T.astype(np.float32) @ (rays * d - tvec[:, None].astype(np.float32))).T
    if self_shadows:
        corners = np.concatenate([_reach_points([(it, f)], lighting, settings)[:8] for it, f in placed])
        # 1024 texels a side at any photo size: a large render is tested on every third
        # pixel below, about as coarse as these texels on a 12 MP photo.
        view = _light_view(renderer, fulls, lighting, corners.min(axis=0), corners.max(axis=0), 1024)
        radius_px = float(np.clip(0.3 * math.tan(lighting.softness_rad) / view.texel_m, 1.0, 8.0))
        # Tested on every second or third pixel of large renders (the shadows are soft).
        step = 3 if rw * rh > 2.5e6 else 2 if rw * rh > 6e5 else 1
        on_grid = (ys % step == 0) & (xs % step == 0)
        world_image = np.full((-(-rh // step), -(-rw // step), 3), np.nan, np.float32)
        world_image[ys[on_grid] // step, xs[on_grid] // step] = world[on_grid]
        lit = key[::step, ::step, :3].max(axis=2) > 0  # surfaces the key light reaches
        beam = np.ones(lit.shape, np.float32)
        if lighting.sun is not None:  # and only what stands in the sun's beam
            beam[ys[on_grid] // step, xs[on_grid] // step] = _in_beam(world[on_grid].astype(np.float64), lighting)
            lit &= beam > 0
        ly, lx, points, bias = _shadow_receivers(world_image, lit, cam_pos, lighting, view.texel_m, radius_px)
        visibility = np.ones(lit.shape, np.float32)
        visibility[ly, lx] = _key_visibility(points, bias, view.camera_from_floor[:3, :3],
                                             view.camera_from_floor[:3, 3], view.K, view.depth_m, radius_px)
        with np.errstate(invalid="ignore"):  # floor-level pieces (rugs) take the floor's shadows instead
            visibility[world_image[..., 2] < settings.floor_level_m] = 1.0
        visibility *= beam
        if step > 1:
            visibility = cv2.resize(visibility, (rw, rh), interpolation=cv2.INTER_LINEAR)
        visibility = cv2.blur(visibility, (3, 3))
        rgba = np.empty((rh, rw, 4), np.uint8)
        _combine(full, key, visibility, _DECODE, _ENCODE, rgba)
        del world_image, visibility, key, points
    else:
        rgba = np.ascontiguousarray(full)
    # Render-sized buffers a large photo need not hold through the stages below.
    del full, depth
    timings["self_shadows"] = time.perf_counter() - t

    # Occlusion, and which furniture pixels lie on the floor (rugs), at render resolution.
    t = time.perf_counter()
    low = np.zeros((rh, rw), np.uint8)
    low[ys, xs] = np.where(world[:, 2] < settings.floor_level_m, 255, 0)
    if floor_mask is not None or (walls is not None and len(walls)):
        if floor_mask is not None and not distorted:  # the photo pixel of each render pixel
            px = np.stack([(xs + 0.5) * (fw / rw) - 0.5 + fbox[0], (ys + 0.5) * (fh / rh) - 0.5 + fbox[1]], 1)
        elif floor_mask is not None:
            px = _project(world, K, pose, dist)[0]
        else:
            px = None
        hidden = _hidden(world, rays, px, floor_mask, walls, K, pose, cam_xy, settings)
        if hidden.any():
            # Hidden pixels grown by one (so a hidden silhouette's soft edge goes too), then
            # a cut a pixel wide.
            cut = np.zeros((rh, rw), np.uint8)
            cut[ys[hidden], xs[hidden]] = 255
            cut = cv2.blur(cv2.dilate(cut, np.ones((3, 3), np.uint8)), (3, 3))
            iy, ix = np.nonzero(cut)
            keep = (255 - cut[iy, ix]).astype(np.float32) * (1.0 / 255.0)
            rgba[iy, ix] = (rgba[iy, ix] * keep[:, None] + 0.5).astype(np.uint8)
    del world, rays, ys, xs, d
    timings["occlusion"] = time.perf_counter() - t

    # Back to photo pixels: resample the render onto the box.
    t = time.perf_counter()
    if (rw, rh) != (fw, fh):
        interp = cv2.INTER_AREA if s > 1 else cv2.INTER_LINEAR
        rgba = cv2.resize(rgba, (fw, fh), interpolation=interp)
        low = cv2.resize(low, (fw, fh), interpolation=interp)
    at = np.s_[fbox[1] - box[1]:fbox[3] - box[1], fbox[0] - box[0]:fbox[2] - box[0]]
    if distorted:  # warped below as the box
        rgba, low = _in_box(rgba, low, at, (bh, bw))
    gain, wall_gain, floor_share = shadows.result()
    if distorted:
        mx, my = undistort
        rgba, low = (cv2.remap(a, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
                     for a in (rgba, low))
    timings["shadows"] = time.perf_counter() - t

    t = time.perf_counter()
    rgba = apply_look(rgba, look, settings.render_edge_px / s, seed)
    low = blur_like_photo(low, look, settings.render_edge_px / s)  # as soft as the rug's edges it marks
    if not distorted:  # the look only where furniture is: a wide halo costs little
        rgba, low = _in_box(rgba, low, at, (bh, bw))
    timings["look"] = time.perf_counter() - t

    t = time.perf_counter()
    full_alpha = np.zeros((h, w), np.float32)
    full_gain = np.ones((h, w), np.float32)
    floor_roi = (_floor_matte_cached(image, floor_mask, settings)[y0:y1, x0:x1] if floor_mask is not None
                 else np.full((1, 1), 255, np.uint8))
    _composite(image[y0:y1, x0:x1], rgba, low, gain, wall_gain, floor_share, floor_roi, floor_mask is not None,
               out[y0:y1, x0:x1], full_alpha[y0:y1, x0:x1], full_gain[y0:y1, x0:x1])
    timings["composite"] = time.perf_counter() - t
    t = time.perf_counter()
    layer_alpha = full_alpha
    if _mirrors(lighting, settings) and floor_mask is not None:
        # The mirror shows all the light, the key's too (the first pass is the fill alone with self-shadows).
        passes = (fulls, keys) if self_shadows else (fulls,)
        mirrored = _floor_reflection(renderer, passes, placed, K, dist, pose, lighting, look, (h, w), settings)
        if mirrored is not None:
            layer_alpha = full_alpha.copy()
            _mirror_onto_floor(out, layer_alpha, mirrored, _floor_matte_cached(image, floor_mask, settings),
                               lighting.floor_gloss)
    timings["reflection"] = time.perf_counter() - t
    lay = _layer(out, layer_alpha, full_gain, image) if layer else None
    timings["total"] = time.perf_counter() - t0
    return Staged(out, lay, full_alpha, full_gain, lighting, roi, s, timings)


def _floor_reflection(renderer, passes, placed, K, dist, pose, lighting: Lighting, look: PhotoLook, shape,
                      settings: StagedSettings):
    """The furniture as a glossy floor mirrors it: its box in the photo (x0, y0, x1, y1) and
    there (rows, cols, 4) float32 premultiplied linear RGB and coverage, fading with the
    height of what is mirrored over ``settings.reflection_fade_m`` (a wood floor's gloss
    blurs all but what stands on it) and blurred by ``settings.reflection_blur_m`` at its
    distance; None where none is in view.

    The mirror image is the furniture seen from the camera mirrored below the floor: a
    proper camera (the mirror, times a flip of the image's rows) whose picture, flipped
    back, is the reflection; the flat passes' light per vertex is kept, ``passes`` (mesh
    lists of one geometry) adding up."""
    h, w = shape
    reach = min(settings.reflection_reach_m, 3.0 * settings.reflection_fade_m)
    corners = np.concatenate([_item_corners(it, 0.0) for it, _ in placed])
    mirrored = corners * np.array([1.0, 1.0, -1.0])
    mirrored[:, 2] = np.maximum(mirrored[:, 2], -reach)
    px, _ = _project(mirrored, K, pose, dist)
    if not np.all(np.isfinite(px)):
        return None
    x0, y0 = np.maximum(np.floor(px.min(axis=0)).astype(int) - 2, 0)
    x1, y1 = np.minimum(np.ceil(px.max(axis=0)).astype(int) + 3, [w, h])
    if x1 - x0 < 4 or y1 - y0 < 4:
        return None
    # Its blur in the photo's pixels (at the furniture's median depth, or the photo's own),
    # rendered as coarse as that allows (a 12 MP photo's blurs over some 15 pixels).
    distance = float(np.median((corners @ pose[:3, :3].T + pose[:3, 3])[:, 2]))
    blur_px = max(settings.reflection_blur_m * float(K[0, 0]) / max(distance, 0.1), look.blur_px)
    s = float(np.clip(settings.reflection_blur_px / blur_px, 0.05, settings.reflection_scale))
    rw, rh = max(2, round((x1 - x0) * s)), max(2, round((y1 - y0) * s))
    Kb = _box_K(K, (x0, y0, x1, y1), (rw, rh))
    Kb[1, 2] = (rh - 1) - Kb[1, 2]  # rows flipped back below
    mirror_pose = np.diag([1.0, -1.0, 1.0, 1.0]) @ pose @ np.diag([1.0, 1.0, -1.0, 1.0])
    flags = pyrender.RenderFlags.RGBA | pyrender.RenderFlags.FLAT
    camera, camera_gl = pyrender_camera(Kb), gl_from_cv_pose(np.linalg.inv(mirror_pose))
    rgba, depth = renderer.render(_flat_scene(passes[0], camera, camera_gl), rw, rh, flags=flags)
    cover = np.maximum(rgba[..., 3:], 1).astype(np.float32)
    colour = (rgba[..., :3].astype(np.float32) / cover) ** 2.2
    for meshes in passes[1:]:
        more, _ = renderer.render(_flat_scene(meshes, camera, camera_gl), rw, rh, flags=flags, depth=False)
        colour += (more[..., :3].astype(np.float32) / cover) ** 2.2
    # Each pixel's height over the floor, from its depth in the mirror camera.
    v, u = np.mgrid[0:rh, 0:rw].astype(np.float32)
    rays = np.stack([(u - Kb[0, 2]) / Kb[0, 0], (v - Kb[1, 2]) / Kb[1, 1], np.ones_like(u)], axis=-1)
    points = rays * depth[..., None] - mirror_pose[:3, 3].astype(np.float32)
    height = points @ mirror_pose[:3, 2].astype(np.float32)  # the floor frame's z: row 3 of R^T
    alpha = rgba[..., 3].astype(np.float32) / 255.0
    fade = np.where(depth > 0, np.exp(-np.maximum(height, 0.0) / settings.reflection_fade_m), 0.0) * alpha
    out = np.dstack([np.minimum(colour, 1.0) * fade[..., None], fade]).astype(np.float32)[::-1]
    out = cv2.GaussianBlur(np.ascontiguousarray(out), (0, 0), max(blur_px * s, 0.5))
    return (int(x0), int(y0), int(x1), int(y1)), cv2.resize(out, (x1 - x0, y1 - y0), interpolation=cv2.INTER_LINEAR)


def _mirror_onto_floor(out, alpha, mirrored, floor_matte_u8, gloss: float) -> None:
    """The reflection (:func:`_floor_reflection`) over the staged photo ``out`` (h, w, 3)
    uint8, in place: on the floor (``floor_matte_u8``, 0-255) where no furniture covers it
    (``alpha``), the share ``gloss`` of the floor's light that mirrored the room now
    mirrors the furniture (linear light). ``alpha`` takes the reflection's coverage, for
    the layer."""
    (x0, y0, x1, y1), refl = mirrored
    region = np.s_[y0:y1, x0:x1]
    weight = gloss * floor_matte_u8[region].astype(np.float32) / 255.0 * (1.0 - alpha[region])
    cover = weight * refl[..., 3]
    lin = _DECODE[out[region]]
    lin = lin * (1.0 - cover[..., None]) + weight[..., None] * refl[..., :3]
    out[region] = _LEVEL_OF_LINEAR[np.clip(lin * 65535.0 + 0.5, 0, 65535).astype(np.uint16)]
    alpha[region] = 1.0 - (1.0 - alpha[region]) * (1.0 - cover)


# Linear light (in 1/65535) back to the photo's levels, a table: a 12 MP photo's powers cost
# more (:data:`_DECODE` is the way there).
_LEVEL_OF_LINEAR = np.clip(255.0 * (np.arange(65536) / 65535.0) ** (1.0 / GAMMA) + 0.5, 0, 255).astype(np.uint8)


def _hidden(world, rays, px, floor_mask, walls, K, pose, cam_xy, settings) -> np.ndarray:
    """Which furniture pixels (points ``world`` (n, 3), camera rays ``rays`` (3, n),
    photo pixels ``px`` (n, 2) when a floor mask is given) lie behind the nearest thing
    the photo shows along their ray: the floor mask's edge or a wall."""
    R = pose[:3, :3]
    reach_xy = np.hypot(world[:, 0] - cam_xy[0], world[:, 1] - cam_xy[1])
    occluder = np.full(len(world), np.inf)
    if floor_mask is not None:
        dmap, ms = _mask_occluders_cached(floor_mask, K, pose, settings)
        mi = np.clip(np.rint((px[:, 1] + 0.5) * ms - 0.5).astype(int), 0, dmap.shape[0] - 1)
        mj = np.clip(np.rint((px[:, 0] + 0.5) * ms - 0.5).astype(int), 0, dmap.shape[1] - 1)
        occluder = np.minimum(occluder, dmap[mi, mj])
    if walls is not None and len(walls):
        occluder = np.minimum(occluder, _first_wall(walls, (R.T @ rays).T, cam_xy)[0])
    slack = settings.occlusion_m + settings.occlusion_rel * np.where(np.isfinite(occluder), occluder, 0.0)
    return reach_xy > occluder + slack


@njit(cache=True)
def _clear_above_horizon(gain, a, b, c, x0, y0):
    """Set ``gain`` to 1 at pixels (x0 + col, y0 + row) with a x + b y + c >= 0."""
    for i in range(gain.shape[0]):
        v = b * (i + y0) + c
        for j in range(gain.shape[1]):
            if a * (j + x0) + v >= 0.0:
                gain[i, j] = 1.0


@njit(cache=True, parallel=True)
def _composite(photo, rgba, low, gain, wall, share, floor, use_floor, out, alpha_out, gain_out):
    """One pass over the region: the photo times its shadow gain under what shows of it,
    the premultiplied furniture over it; floor-level furniture (``low``, 0-255) takes the
    shadows too. With ``use_floor``, the floor's gain on floor pixels; on the rest the walls'
    ``wall``, or the floor's where their ray meets the floor first (its ``share`` of them);
    mixed by ``floor``, each pixel's share of floor (:func:`floor_matte`, 0-255).

    photo, out : (h, w, 3) uint8; rgba : (h, w, 4) uint8 premultiplied; low, floor : (h, w)
    uint8; gain, wall, share : (h, w) float32; alpha_out, gain_out : (h, w) float32, written."""
    h, w = photo.shape[0], photo.shape[1]
    for i in prange(h):
        for j in range(w):
            g = gain[i, j]
            if use_floor:
                f = floor[i, j] * (1.0 / 255.0)
                g = f * g + (1.0 - f) * (share[i, j] * g + (1.0 - share[i, j]) * wall[i, j])
            a = rgba[i, j, 3] * (1.0 / 255.0)
            k = g * (1.0 - a)
            fg = 1.0 - low[i, j] * (1.0 / 255.0) * (1.0 - g)
            for ch in range(3):
                v = photo[i, j, ch] * k + rgba[i, j, ch] * fg + 0.5
                out[i, j, ch] = 255 if v >= 255.0 else np.uint8(v)
            alpha_out[i, j] = a
            gain_out[i, j] = g


def floor_matte(photo: np.ndarray, floor_mask: np.ndarray, radius_px: float, eps: float,
                scale: float = 1.0) -> np.ndarray:
    """Each pixel's share of floor, (h, w) uint8, 0-255: ``floor_mask`` (h, w) bool moved
    onto the edges of ``photo`` (h, w, 3) uint8 by a guided filter (He et al.)
    ``radius_px`` wide. A mask segmented at a few hundred pixels a side and enlarged runs a
    pixel or two off a carton's edge in steps; the floor's shadow would stop along those
    steps.

    ``eps`` (8-bit units squared): steps of colour well above its square root are edges
    the matte keeps. With ``scale`` below 1 the filter runs on the photo shrunk by it and
    its result is enlarged back (a large photo's edges span a few pixels anyway)."""
    mask = np.asarray(floor_mask, dtype=bool).view(np.uint8)
    h, w = mask.shape
    if mask.size == 0:
        return mask.copy()
    size = (max(1, round(w * scale)), max(1, round(h * scale)))
    small = size != (w, h)
    guide = cv2.resize(photo, size, interpolation=cv2.INTER_AREA) if small else np.ascontiguousarray(photo)
    # Shrunk as 0-255 bytes: a float copy of a large photo's mask would cost four bytes a pixel.
    src = (cv2.resize(mask * np.uint8(255), size, interpolation=cv2.INTER_AREA) if small else mask * np.uint8(255))
    src = src.astype(np.float32) * np.float32(1 / 255)
    radius = max(1, math.ceil(radius_px * size[0] / w))
    matte = np.rint(np.clip(cv2.ximgproc.guidedFilter(guide, src, radius, float(eps)), 0.0, 1.0) * 255.0)
    matte = matte.astype(np.uint8)
    return cv2.resize(matte, (w, h), interpolation=cv2.INTER_LINEAR) if small else matte


def _layer(staged, alpha, gain, photo) -> np.ndarray:
    """Straight-alpha RGBA of what was added: laid over ``photo`` it gives ``staged``.

    Over the photo P a layer (c, a) gives a c + (1 - a) P; the staged pixel is
    S = F + (1 - alpha) g P, so a = 1 - (1 - alpha) g and c = (S - (1 - a) P) / a."""
    a = 1.0 - (1.0 - alpha) * gain
    added = staged.astype(np.float32) - (1.0 - a)[..., None] * photo.astype(np.float32)
    c = added / np.maximum(a, 1e-4)[..., None]
    rgba = np.dstack([np.clip(c, 0, 255), np.clip(a * 255.0, 0, 255)])
    return (rgba + 0.5).astype(np.uint8)


def write_jpeg(path, image: np.ndarray, quality: int = JPEG_QUALITY):
    """Write an RGB image as JPEG (quality 92 by default), atomically. Returns the path."""
    return write_atomic(path, encode_image(_check_image(image), ".jpg", quality))


def write_png(path, image: np.ndarray):
    """Write an RGB or RGBA uint8 image as PNG, atomically. Returns the path."""
    a = np.asarray(image)
    if a.ndim != 3:
        raise ValueError(f"PNG image must be (h, w, 3 or 4) uint8, got shape {a.shape} dtype {a.dtype}")
    return write_atomic(path, encode_image(a, ".png"))
