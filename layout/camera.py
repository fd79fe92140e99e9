"""The photo's camera as the layout sees it: a few numbers, no image.

A staged photo is judged through the camera, so a layout made for a photo knows it:
the space the photo shows (a frustum whose lower edge is raised to keep the
foreground clear) bounds every item's 3-D box in the solver (:meth:`Camera.frame_planes`,
hard, part of the layout boundary); what is hidden and what is seen from behind are
criteria the restarts choose by (:func:`judge`). See ``docs/layout.md``.

Conventions: ``camera_from_floor`` maps floor points (meters, z up, the layout's floor
frame) to camera coordinates with OpenCV's axes (x right, y down, z ahead); pixels are
undistorted, ``(0, 0)`` the top-left corner of the top-left pixel.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _codes as codes
from ._kernels import ray_box_entry
from .catalog import CATALOG
from .errors import LayoutError

# Seating that is looked at and so has a good side; chairs at a table are seen from
# any side (the arrangement needs it) and are not judged.
FRONT_KINDS = ("sofa", "armchair", "lounge_chair", "bench")
# A TV no seat faces is looked at for itself: its screen is not shown edge-on or from behind.
SCREEN_KINDS = ("tv_stand",)
TABLE_KINDS = ("dining_table", "round_table", "picnic_table", "game_table", "desk")


@dataclass(frozen=True)
class CameraRules:
    """What the camera asks of a layout; the tolerances in one place."""

    margin: float = 0.01  # items keep this share of the image's longer side from its edges
    foreground: float = 0.15  # the lowest share of the frame stays clear of furniture
    min_visible: float = 0.7  # share of an item's box not hidden behind other items
    back_view_deg: float = 60.0  # seen from behind: the camera within this of the item's back
    screen_view_deg: float = 70.0  # a TV no seat faces: the camera within this of its screen's normal
    grid_px: int = 96  # rays across the image's longer side for the visibility test
    max_cover: float = 0.15  # a piece taller than the lens fills at most this share of the frame


CAMERA = CameraRules()


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera over the layout's floor.

    Attributes
    ----------
    K : (3, 3) float64
        Intrinsics, pixels.
    camera_from_floor : (4, 4) float64
        Floor frame (meters, z up) to camera frame (OpenCV axes).
    size_px : (2,) int
        Image width, height.
    """

    K: np.ndarray
    camera_from_floor: np.ndarray
    size_px: tuple

    def __post_init__(self):
        K = np.array(self.K, dtype=np.float64)
        T = np.array(self.camera_from_floor, dtype=np.float64)
        if K.shape != (3, 3) or not np.isfinite(K).all() or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise LayoutError(f"camera.K = {K.tolist()}: must be a 3 x 3 intrinsic matrix with positive focal lengths")
        if T.shape != (4, 4) or not np.isfinite(T).all() or not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3),
                                                                              atol=1e-6):
            raise LayoutError("camera.camera_from_floor: must be a 4 x 4 rigid transform (a rotation and a "
                              "translation)")
        w, h = (int(v) for v in self.size_px)
        if w < 2 or h < 2:
            raise LayoutError(f"camera.size_px = {list(self.size_px)}: width and height must be at least 2 pixels")
        if self.center_m[2] <= 0.0:
            raise LayoutError(f"camera.camera_from_floor: the camera stands {self.center_m[2]:.2f} m above the "
                              "floor; it must be above it")
        K.flags.writeable = False
        T.flags.writeable = False
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "camera_from_floor", T)
        object.__setattr__(self, "size_px", (w, h))

    @property
    def center_m(self) -> np.ndarray:
        """(3,) the camera's center in the floor frame."""
        R, t = np.asarray(self.camera_from_floor)[:3, :3], np.asarray(self.camera_from_floor)[:3, 3]
        return -R.T @ t

    def project(self, points_m) -> tuple[np.ndarray, np.ndarray]:
        """Pixels and depths of floor-frame points.

        Parameters
        ----------
        points_m : (..., 3) array_like

        Returns
        -------
        pixels_px : (..., 2) float64
        depth_m : (...,) float64
            Distance along the optical axis; points at or behind the camera get NaN pixels.
        """
        p = np.asarray(points_m, dtype=np.float64)
        cam = p @ self.camera_from_floor[:3, :3].T + self.camera_from_floor[:3, 3]
        z = cam[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = (cam @ self.K.T)[..., :2] / np.where(z > 1e-9, z, np.nan)[..., None]
        return uv, z

    def rays(self, grid_px: int) -> np.ndarray:
        """(k, 3) unit directions, floor frame, of the rays through the centres of a grid of
        ``grid_px`` cells along the image's longer side (row by row); kept with the camera,
        as every judged layout of a photo casts the same ones."""
        cached = self.__dict__.setdefault("_rays", {})
        if grid_px not in cached:
            w, h = self.size_px
            step = max(w, h) / grid_px
            U, V = np.meshgrid(np.arange(step / 2, w, step), np.arange(step / 2, h, step))
            pix = np.stack([U.ravel(), V.ravel(), np.ones(U.size)], axis=1)
            dirs = np.linalg.solve(self.K, pix.T).T @ self.camera_from_floor[:3, :3]
            dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
            dirs.flags.writeable = False
            cached[grid_px] = dirs
        return cached[grid_px]

    def frame_planes(self, rules: CameraRules = CAMERA) -> np.ndarray:
        """The space the photo shows, as planes through the camera's center.

        Left, right and top: the image's edges moved in by ``rules.margin``; bottom: the
        line ``rules.foreground`` of the image height above the lower edge, so nothing
        stands in the foreground and nothing is cut by an edge.

        Returns
        -------
        planes : (4, 4) float64
            Rows ``(n_x, n_y, n_z, d)``, unit ``n``, floor frame: a point p is in view
            where ``n . p + d >= 0`` for every row.
        """
        w, h = self.size_px
        m = rules.margin * max(w, h)
        fx, fy, cx, cy = self.K[0, 0], self.K[1, 1], self.K[0, 2], self.K[1, 2]
        bottom = h * (1.0 - rules.foreground)
        # In camera coordinates u >= m reads fx X + (cx - m) Z >= 0, and so on.
        in_camera = np.array([[fx, 0.0, cx - m], [-fx, 0.0, w - m - cx], [0.0, fy, cy - m],
                              [0.0, -fy, bottom - cy]])
        R, t = self.camera_from_floor[:3, :3], self.camera_from_floor[:3, 3]
        n = in_camera @ R
        d = in_camera @ t
        scale = np.linalg.norm(n, axis=1)
        return np.column_stack([n / scale[:, None], d / scale])

    def to_dict(self) -> dict:
        return {"K": self.K.tolist(), "camera_from_floor": self.camera_from_floor.tolist(),
                "size_px": list(self.size_px)}


def box_corners_3d(position_m, yaw_rad, size_m) -> np.ndarray:
    """(n, 8, 3) corners of boxes centred at ``position_m`` (n, 3), turned by ``yaw_rad``,
    ``size_m`` (n, 3) width, depth, height (depth along the facing, layout.geometry);
    the even-numbered corners are the lower ones."""
    pos = np.asarray(position_m, dtype=np.float64).reshape(-1, 3)
    size = np.asarray(size_m, dtype=np.float64).reshape(-1, 3)
    yaw = np.asarray(yaw_rad, dtype=np.float64).reshape(-1)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], np.float64)
    local = 0.5 * signs[None] * size[:, None, [1, 0, 2]]  # x front (depth), y left (width), z up
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    x = c * local[..., 0] - s * local[..., 1]
    y = s * local[..., 0] + c * local[..., 1]
    return pos[:, None, :] + np.stack([x, y, local[..., 2]], axis=-1)


def in_view_share(camera: Camera, polygon_m, size_m, rules: CameraRules | None = None, step_m: float = 0.1,
                  yaws: int = 8) -> float:
    """Share of the poses on the floor (a ``step_m`` grid inside ``polygon_m``, ``yaws``
    directions) where a box of ``size_m`` (width, depth, height; standing on the floor)
    has its footprint on the floor and lies whole in the space ``camera`` shows: 0 when
    the photo has no place for it."""
    from .solver import _inside

    poly = np.asarray(polygon_m, dtype=np.float64)
    planes = camera.frame_planes(rules or CAMERA)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    xs, ys = np.meshgrid(np.arange(lo[0], hi[0], step_m), np.arange(lo[1], hi[1], step_m))
    pts = np.column_stack([xs.ravel(), ys.ravel()])
    pts = pts[_inside(poly, pts)]
    if not len(pts):
        return 0.0
    w, d, h = (float(v) for v in size_m)
    n = len(pts)
    ok = 0
    for yaw in np.linspace(0.0, 2.0 * np.pi, yaws, endpoint=False):
        corners = box_corners_3d(np.column_stack([pts, np.full(n, h / 2)]), np.full(n, yaw), np.tile([w, d, h], (n, 1)))
        in_frame = ((corners @ planes[:, :3].T + planes[:, 3]) >= 0.0).all(axis=(1, 2))
        feet = corners[in_frame][:, ::2, :2]  # the lower four corners (box_corners_3d's order)
        ok += int(_inside(poly, feet.reshape(-1, 2)).reshape(-1, 4).all(axis=1).sum())
    return ok / (n * yaws)


def judge(layout, rules: CameraRules | None = None, camera: Camera | None = None) -> dict:
    """How a layout looks through its model's camera (or ``camera``: e.g. a layout
    made without one, judged as the photo shows it).

    Rules (per item, rugs and other floor coverings left out):

    - ``cut``: its box reaches past the image's edge (no margin) or into the foreground
      (the lowest ``rules.foreground`` of the frame, with a pixel's tolerance);
    - ``hidden``: under ``rules.min_visible`` of its box's pixels show it rather than
      another item's box in front (rays cast on a ``rules.grid_px`` grid); chairs at a
      table, pulled in under it, and items standing on others are not judged, and a table
      or desk is not hidden by its own chairs (:func:`seats_at`: a set is seen as one);
    - ``from_behind``: seating in :data:`FRONT_KINDS`, not at a table, nearer than the
      floor's middle, with the camera within ``rules.back_view_deg`` of its back; and a TV
      (:data:`SCREEN_KINDS`, carrying its screen) that no seat faces, with the camera more
      than ``rules.screen_view_deg`` off its front (edge-on or from behind);
    - ``looms``: its top is above the lens, so the photo shows nothing past it, and its box
      fills more than ``rules.max_cover`` of the frame (a wardrobe in the foreground walls
      off the room a stager would show).

    Returns
    -------
    dict
        ``visible`` (item name -> share shown, for the items judged), the names ``cut``,
        ``hidden``, ``from_behind``, ``looms``, and ``hidden_by`` (hidden item -> the item
        in front of most of what is hidden); empty without a camera.
    """
    model = layout.model
    cam = model.camera if camera is None else camera
    if cam is None:
        return {}
    rules = rules or model.camera_rules or CAMERA
    items = [i for i in model.items if model.particle_collides[i]]
    pos = layout.position_m[items]
    yaw = layout.yaw_rad[items]
    size = model.particle_size_m[items]
    names = [model.names[i] for i in items]
    w, h = cam.size_px
    corners = box_corners_3d(pos, yaw, size)
    uv, z = cam.project(corners)
    tol = 1.0
    fore = h * (1.0 - rules.foreground) + tol
    with np.errstate(invalid="ignore"):
        out = ~((z > 0) & (uv[..., 0] >= -tol) & (uv[..., 0] <= w + tol) & (uv[..., 1] >= -tol)
                & (uv[..., 1] <= fore)).all(axis=1)
    cut = [n for n, o in zip(names, out) if o]

    # Visibility: rays through a grid of pixel centres.
    dirs = cam.rays(rules.grid_px)
    hits = np.empty((len(dirs), len(items)))
    ray_box_entry(np.asarray(cam.center_m, dtype=np.float64), dirs, np.ascontiguousarray(pos),
                  np.ascontiguousarray(yaw, dtype=np.float64), np.ascontiguousarray(size), hits)
    seen = np.isfinite(hits)
    tall = pos[:, 2] + 0.5 * size[:, 2] > cam.center_m[2]
    looms = [n for n, t, cover in zip(names, tall, seen.mean(axis=0)) if t and cover > rules.max_cover]
    exempt = _not_judged_for_hiding(model, items)
    seats = seats_at(model)
    visible = {}
    hidden = []
    hidden_by = {}
    for k, name in enumerate(names):
        if exempt[k]:
            continue
        total = int(seen[:, k].sum())
        cols = [c for c in range(len(names)) if c != k and names[c] not in seats.get(name, ())]
        others = hits[:, cols]
        in_front = others.min(axis=1, initial=np.inf) < hits[:, k]
        share = float((seen[:, k] & ~in_front).sum() / total) if total else 0.0
        visible[name] = round(share, 4)
        if share < rules.min_visible:
            hidden.append(name)
            if (seen[:, k] & in_front).any():
                blocker = np.bincount(others[seen[:, k] & in_front].argmin(axis=1), minlength=len(cols))
                hidden_by[name] = names[cols[int(blocker.argmax())]]

    # Seen from behind.
    at_table = _at_table(model, items)
    poly = model.floor_polygon_m
    eye = cam.center_m
    middle = np.hypot(*(poly.mean(axis=0) - eye[:2]))
    behind = []
    faced = set(model.orientation_pairs[model.orientation_mode == codes.FACE].ravel())
    cos_back, cos_screen = np.cos(np.radians(rules.back_view_deg)), np.cos(np.radians(rules.screen_view_deg))
    for k, i in enumerate(items):
        kind = model.kinds[i]
        seat = kind in FRONT_KINDS and not at_table[k]
        # A bare stand is a cabinet; a TV its sofa faces is seen as the group is.
        screen = kind in SCREEN_KINDS and i not in faced and size[k, 2] > CATALOG[kind].bare_height_m + 1e-6
        to_eye = eye[:2] - pos[k, :2]
        dist = np.hypot(*to_eye)
        if not (seat or screen) or dist < 1e-9:
            continue
        front = to_eye @ np.array([np.cos(yaw[k]), np.sin(yaw[k])]) / dist  # cos of the camera's angle off its front
        if (seat and dist < middle and -front >= cos_back) or (screen and front < cos_screen):
            behind.append(names[k])
    return {"visible": visible, "cut": cut, "hidden": hidden, "hidden_by": hidden_by, "from_behind": behind,
            "looms": looms}


def faults(judged: dict) -> int:
    """How many items a camera judgement finds at fault (0 without a camera)."""
    return sum(len(judged.get(k, ())) for k in ("cut", "hidden", "from_behind", "looms"))


def _group_kinds(model, i) -> set:
    g = model.particle_parent[i]
    if g < 0:
        return set()
    return {model.kinds[j] for j in np.flatnonzero(model.particle_parent == g)}


def _at_table(model, items) -> list[bool]:
    return [model.kinds[i] not in TABLE_KINDS and bool(_group_kinds(model, i) & set(TABLE_KINDS)) for i in items]


def seats_at(model) -> dict:
    """Table or desk name -> the names of the seats pulled in at it (its rigid set's
    chairs, a chair placed at a desk): a photo shows a table through its chairs as one
    piece, so they do not hide it."""
    out = {}
    for i in range(model.n):
        if model.kinds[i] not in TABLE_KINDS:
            continue
        g = model.particle_parent[i]
        mates = {j for j in np.flatnonzero(model.particle_parent == g) if j != i} if g >= 0 else set()
        for c in np.flatnonzero(model.heat_frame == i):
            mates.update(int(j) for j in model.heat_members[model.heat_start[c]:model.heat_start[c + 1]])
        if mates:
            out[model.names[i]] = sorted(model.names[j] for j in mates)
    return out


def _not_judged_for_hiding(model, items) -> list[bool]:
    """Chairs at a table (pulled in under it) and items standing on another item."""
    at_table = _at_table(model, items)
    tops = set(int(t) for t in model.stack_pairs[:, 1]) if len(model.stack_pairs) else set()
    return [at_table[k] or i in tops or model.particle_role[i] != codes.ITEM for k, i in enumerate(items)]
