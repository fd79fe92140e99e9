"""Turn a room, a camera and a board into a lit pyrender scene with segmentation labels.

Walls are quads with the openings cut out and a reveal the depth of the wall, so sunlight
enters only through the windows and the sky shows through them. Surfaces of one material
share one mesh, which keeps a scene to about a dozen draw calls.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from layout.geometry import triangulate_polygon

from ..camera.board import Board
from ..render.furniture import PlacedItem, furniture_for, part_texture, world_from_item
from ..render.gl import Scene as GLScene
from ..render.gl import gl_from_cv_pose, pyrender, pyrender_camera
from . import textures
from .camera import Shot
from .rooms import BASEBOARD_M, FURNITURE_KINDS, Room, contains, inward_normal, wall_ends

WALL_THICKNESS_M = 0.15
# Trim and clutter sink this far into the wall, floor or ceiling they touch: where two
# meshes only meet, a pixel on the seam goes to whichever pyrender draws first, and it
# draws in set order, which changes from run to run.
_EMBED_M = 0.002
# Segmentation colors, one channel per class so a blended edge still votes for one class.
SEG_FLOOR = (255, 0, 0)
SEG_WALL = (0, 255, 0)
SEG_CEILING = (0, 0, 255)
SEG_OTHER = (0, 0, 0)


def kelvin_rgb(kelvin: float) -> np.ndarray:
    """Linear RGB of a black body at ``kelvin`` (1500-12000 K), brightest channel 1.

    A fit to the CIE black-body locus (after Tanner Helland); good to a few percent, which
    is all a white-balance shift needs.
    """
    t = np.clip(kelvin, 1000, 40000) / 100
    r = 255.0 if t <= 66 else 329.698727446 * (t - 60) ** -0.1332047592
    g = 99.4708025861 * np.log(t) - 161.1195681661 if t <= 66 else 288.1221695283 * (t - 60) ** -0.0755148492
    b = 255.0 if t >= 66 else (0.0 if t <= 19 else 138.5177312231 * np.log(t - 10) - 305.0447927307)
    srgb = np.clip([r, g, b], 0, 255) / 255
    linear = srgb ** 2.2
    return linear / linear.max()


_QUAD_FACES = np.array([[0, 1, 2], [0, 2, 3]])
_TRI_FACES = np.array([[0, 1, 2]])


def _unit_box():
    """A box of half-size 1: 24 corners (4 per face, counter-clockwise seen from outside),
    normals, per-face texture coordinates and which two extents each face spans."""
    corners, normals, uv, axes = [], [], [], []
    for a in range(3):
        b, d = (a + 1) % 3, (a + 2) % 3
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[a] = sign
            eb, ed = np.eye(3)[b], np.eye(3)[d]
            square = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
            face = [n + i * eb + j * ed for i, j in square]
            if sign < 0:  # keep counter-clockwise when seen from outside
                face, square = face[::-1], square[::-1]
            corners += face
            uv += square
            normals += [n] * 4
            axes.append([b, d])
    faces = np.concatenate([_QUAD_FACES + 4 * k for k in range(6)])
    return np.array(corners), np.array(normals), np.array(uv, dtype=np.float64), np.array(axes), faces


_BOX_CORNERS, _BOX_NORMALS, _BOX_UV, _BOX_UV_AXES, _BOX_FACES = _unit_box()


class _Batch:
    """Triangles of one material, collected then turned into one pyrender mesh."""

    def __init__(self):
        self.positions, self.normals, self.uvs, self.faces = [], [], [], []
        self._count = 0

    def quad(self, corners, normal, uv=None):
        """Add a planar quad (4, 3) facing ``normal``; the winding is fixed to match."""
        corners = np.asarray(corners, dtype=np.float64)
        normal = np.asarray(normal, dtype=np.float64)
        uv = np.zeros((4, 2)) if uv is None else np.asarray(uv, dtype=np.float64)
        e1, e2 = corners[1] - corners[0], corners[2] - corners[0]
        facing = (e1[1] * e2[2] - e1[2] * e2[1]) * normal[0] + (e1[2] * e2[0] - e1[0] * e2[2]) * normal[1] \
            + (e1[0] * e2[1] - e1[1] * e2[0]) * normal[2]
        if facing < 0:
            corners, uv = corners[::-1], uv[::-1]
        self._append(corners, np.broadcast_to(normal / np.linalg.norm(normal), (4, 3)), uv, _QUAD_FACES)

    def _append(self, positions, normals, uvs, faces):
        self.positions.append(positions)
        self.normals.append(normals)
        self.uvs.append(uvs)
        self.faces.append(faces + self._count)
        self._count += len(positions)

    def box(self, center, size, yaw_rad=0.0, tile_m=1.0):
        """A box (w along yaw, d across, h up) centered at ``center`` (3,), outward faces."""
        c, s = np.cos(yaw_rad), np.sin(yaw_rad)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        half = np.asarray(size, dtype=np.float64) / 2
        positions = (_BOX_CORNERS * half) @ rot.T + np.asarray(center, dtype=np.float64)
        # Each face's texture spans its own two extents.
        uv = _BOX_UV * np.repeat(half[_BOX_UV_AXES], 4, axis=0) / tile_m
        self._append(positions, _BOX_NORMALS @ rot.T, uv, _BOX_FACES)

    def polygon(self, polygon_m, z_m, up: bool, uv_from_xy):
        """A horizontal polygon at height ``z_m`` facing up or down."""
        normal = np.array([0.0, 0.0, 1.0 if up else -1.0])
        for tri in triangulate_polygon(polygon_m):
            tri = tri if up else tri[::-1]
            p = np.column_stack([polygon_m[tri], np.full(3, z_m)])
            self._append(p, np.broadcast_to(normal, (3, 3)), uv_from_xy(polygon_m[tri]), _TRI_FACES)

    def mesh(self, material) -> "pyrender.Mesh":
        primitive = pyrender.Primitive(
            positions=np.concatenate(self.positions).astype(np.float32),
            normals=np.concatenate(self.normals).astype(np.float32),
            texcoord_0=np.concatenate(self.uvs).astype(np.float32),
            indices=np.concatenate(self.faces).astype(np.uint32),
            material=material, mode=pyrender.GLTF.TRIANGLES,
        )
        return pyrender.Mesh([primitive])


class _SharpTexture(pyrender.Texture):
    """A texture sampled anisotropically (up to 16 texels along the foreshortened direction).

    Plain trilinear mipmapping picks its level by the foreshortened direction and so
    blurs a print lying on the floor across as much as along: a checkerboard survives
    that, the bits of a ChArUco marker do not, though any phone lens resolves them."""

    def _add_to_context(self):
        super()._add_to_context()
        from OpenGL import GL
        from OpenGL.GL.EXT.texture_filter_anisotropic import GL_TEXTURE_MAX_ANISOTROPY_EXT

        GL.glBindTexture(self.tex_type, self._texid)
        GL.glTexParameterf(self.tex_type, GL_TEXTURE_MAX_ANISOTROPY_EXT, 16.0)
        GL.glBindTexture(self.tex_type, 0)


def _material(rng, color, texture=None, roughness=(0.6, 0.95), wrap=True, emissive=None, closed=False,
              sharp=False):
    """A PBR material. ``closed`` meshes (boxes) are drawn one-sided: their faces that
    touch a wall, the floor or the ceiling face away from the camera and are culled, so
    no two coplanar surfaces fight over a pixel in an order pyrender leaves to chance.
    ``sharp`` filters the texture anisotropically (:class:`_SharpTexture`)."""
    tex = None
    if texture is not None:
        mode = pyrender.GLTF.REPEAT if wrap else pyrender.GLTF.CLAMP_TO_EDGE
        tex = (_SharpTexture if sharp else pyrender.Texture)(
            source=texture, source_channels="RGB", sampler=pyrender.Sampler(wrapS=mode, wrapT=mode))
    return pyrender.MetallicRoughnessMaterial(
        baseColorFactor=np.append(np.asarray(color, dtype=np.float64), 1.0),
        baseColorTexture=tex, metallicFactor=0.0,
        roughnessFactor=float(rng.uniform(*roughness)), doubleSided=not closed,
        emissiveFactor=emissive,
    )


def _own(rng):
    """A generator of its own for a texture, so a change in how many numbers a texture
    draws does not shift every later choice of the scene."""
    return np.random.default_rng(rng.integers(2**63))


def _random_tint(rng, base, spread):
    return np.clip(np.asarray(base) + rng.normal(0, spread, 3), 0.02, 1.0)


def furniture_meshes(pieces) -> list:
    """Furniture for the physically based renderer: every part with its material's colour,
    roughness, metalness and surface detail at real scale, as staged photos show them.

    Parameters
    ----------
    pieces : iterable of (Furniture, (4, 4) array)
        Each piece and its pose in the world (its item frame to the world's).

    Returns
    -------
    list of pyrender.Mesh
        One per material, so a furnished room adds a few dozen draw calls.
    """
    groups: dict = {}
    for furniture, pose in pieces:
        for part in furniture.parts:
            key, image, uv, scale = part_texture(part)
            groups.setdefault((key, part.material), (image, scale, []))[2].append((part.transformed(pose), uv))
    textures_made: dict = {}
    meshes = []
    for (key, m), (image, scale, members) in groups.items():
        if key and key not in textures_made:
            textures_made[key] = pyrender.Texture(source=image, source_channels="RGB")
        counts = np.cumsum([0] + [len(p.vertices) for p, _ in members[:-1]])
        color = np.ones(3) if scale is None else np.asarray(m.color_rgb) * scale
        material = pyrender.MetallicRoughnessMaterial(
            baseColorFactor=np.append(color, 1.0), baseColorTexture=textures_made.get(key),
            metallicFactor=float(m.metallic), roughnessFactor=float(m.roughness),
            emissiveFactor=np.asarray(m.emissive_rgb, dtype=np.float64), doubleSided=True)
        meshes.append(pyrender.Mesh([pyrender.Primitive(
            positions=np.concatenate([p.vertices for p, _ in members]).astype(np.float32),
            normals=np.concatenate([p.normals for p, _ in members]).astype(np.float32),
            texcoord_0=np.concatenate([uv for _, uv in members]).astype(np.float32) if key else None,
            # The folds' own occlusion, as staged photos bake it (base colour x vertex colour).
            color_0=np.concatenate([p.light_share() for p, _ in members]).astype(np.float32)[:, None].repeat(3, 1),
            indices=np.concatenate([p.faces + c for (p, _), c in zip(members, counts)]).astype(np.uint32),
            material=material, mode=pyrender.GLTF.TRIANGLES)]))
    return meshes


@dataclass
class Scene:
    """A renderable scene: the pyrender scene, its segmentation map and what was sampled."""

    scene: "pyrender.Scene"
    seg_node_map: dict
    info: dict


def _wall_cells(ops, s_range, height):
    """The cells (s0, s1, z0, z1) of a wall from ``s_range`` (meters along it) and floor to
    ceiling, cut at the openings ``ops``, the openings themselves left out."""
    s_breaks = sorted({*s_range, *[o.start_m for o in ops], *[o.end_m for o in ops]})
    z_breaks = sorted({0.0, height, *[o.bottom_m for o in ops], *[o.top_m for o in ops]})
    for s0, s1 in zip(s_breaks[:-1], s_breaks[1:]):
        for z0, z1 in zip(z_breaks[:-1], z_breaks[1:]):
            sm, zm = (s0 + s1) / 2, (z0 + z1) / 2
            if not any(o.start_m < sm < o.end_m and o.bottom_m < zm < o.top_m for o in ops):
                yield s0, s1, z0, z1


def _wall_frame(poly, wall):
    """A wall's start (3,), unit direction (3,), inward normal (3,) and length (m)."""
    a, b = wall_ends(poly, wall)
    length = float(np.linalg.norm(b - a))
    return np.append(a, 0.0), np.append((b - a) / length, 0.0), np.append(inward_normal(poly, wall), 0.0), length


def _walls(room: Room, batch: _Batch, tile_m: float):
    """Wall quads with the openings cut out, and each opening's reveal (its sides, head
    and sill through the wall's thickness)."""
    poly, height = room.polygon_m, room.height_m
    for wall in range(len(poly)):
        a3, u, n, length = _wall_frame(poly, wall)
        ops = [o for o in room.openings if o.wall == wall]

        def point(s, z, depth=0.0):
            return a3 + u * s + np.array([0, 0, z]) - n * depth

        for s0, s1, z0, z1 in _wall_cells(ops, (0.0, length), height):
            uv = np.array([[s0, z0], [s1, z0], [s1, z1], [s0, z1]]) / tile_m
            batch.quad([point(s0, z0), point(s1, z0), point(s1, z1), point(s0, z1)], n, uv)
        t = WALL_THICKNESS_M
        for o in ops:
            s0, s1, z0, z1 = o.start_m, o.end_m, o.bottom_m, o.top_m
            batch.quad([point(s0, z0), point(s0, z1), point(s0, z1, t), point(s0, z0, t)], u)
            batch.quad([point(s1, z0), point(s1, z1), point(s1, z1, t), point(s1, z0, t)], -u)
            batch.quad([point(s0, z1), point(s1, z1), point(s1, z1, t), point(s0, z1, t)], -np.array([0, 0, 1.0]))
            if z0 > 0:
                batch.quad([point(s0, z0), point(s1, z0), point(s1, z0, t), point(s0, z0, t)], np.array([0, 0, 1.0]))


def _outside(room: Room, batch: _Batch):
    """The building's outside: the walls' outer faces (the windows cut out, the doors
    closed) and a roof, facing out. pyrender's shadow maps are drawn with back faces
    culled, double-sided or not, so the walls and the ceiling, which face into the room,
    would cast no shadow: the sun would light the whole floor but for the window frames'
    shadows. Drawn one-sided, these faces are never seen from inside."""
    poly, height, t = room.polygon_m, room.height_m, WALL_THICKNESS_M
    for wall in range(len(poly)):
        a3, u, n, length = _wall_frame(poly, wall)
        windows = [o for o in room.openings if o.wall == wall and o.kind == "window"]
        for s0, s1, z0, z1 in _wall_cells(windows, (-t, length + t), height):
            corners = [a3 + u * s + np.array([0, 0, z]) - n * t for s, z in ((s0, z0), (s1, z0), (s1, z1), (s0, z1))]
            batch.quad(corners, -n)
    lo, hi = poly.min(axis=0) - t, poly.max(axis=0) + t
    batch.quad([[lo[0], lo[1], height], [hi[0], lo[1], height], [hi[0], hi[1], height], [lo[0], hi[1], height]],
               [0, 0, 1.0])


def _openings(rng, room: Room, frames: _Batch, doors: _Batch, baseboard_m):
    """Door leaves and thresholds into ``doors``; casings, window frames and sills and the
    baseboards (all trim paint, ``baseboard_m`` (low, high) tall) into ``frames``."""
    poly = room.polygon_m
    t = WALL_THICKNESS_M
    casing_m = rng.uniform(0.05, 0.09)
    base_h, base_d = rng.uniform(*baseboard_m), rng.uniform(0.012, 0.02)
    for o in room.openings:
        a, b = wall_ends(poly, o.wall)
        u2 = (b - a) / np.linalg.norm(b - a)
        u, n = np.append(u2, 0.0), np.append(inward_normal(poly, o.wall), 0.0)
        yaw = float(np.arctan2(u2[1], u2[0]))
        a3 = np.append(a, 0.0)
        width, top, bottom = o.end_m - o.start_m, o.top_m, o.bottom_m
        mid = a3 + u * (o.start_m + o.end_m) / 2
        if o.kind == "door":
            doors.quad([a3 + u * o.start_m - n * 0.6 * t, a3 + u * o.end_m - n * 0.6 * t,
                        a3 + u * o.end_m - n * 0.6 * t + [0, 0, top],
                        a3 + u * o.start_m - n * 0.6 * t + [0, 0, top]], n)
            # The threshold under the door: without it the sky shows through a slot.
            doors.quad([a3 + u * o.start_m, a3 + u * o.end_m, a3 + u * o.end_m - n * 0.6 * t,
                        a3 + u * o.start_m - n * 0.6 * t], np.array([0, 0, 1.0]))
            # Casing on the room side: two jambs and a head.
            for s in (o.start_m - casing_m / 2, o.end_m + casing_m / 2):
                frames.box(a3 + u * s + n * (0.008 - _EMBED_M) + [0, 0, (top + casing_m) / 2],
                           (casing_m, 0.016, top + casing_m), yaw)
            frames.box(mid + n * (0.008 - _EMBED_M) + [0, 0, top + casing_m / 2], (width + 2 * casing_m, 0.016, casing_m), yaw)
        else:
            bar = rng.uniform(0.04, 0.07)
            depth_c = -n * 0.5 * t
            # Frames stop 1 mm short of the reveals so no faces coincide.
            gap = 0.001
            for z in (bottom + gap + bar / 2, top - gap - bar / 2):
                frames.box(mid + depth_c + [0, 0, z], (width - 2 * gap, 0.06, bar), yaw)
            for s in (o.start_m + gap + bar / 2, o.end_m - gap - bar / 2):
                frames.box(a3 + u * s + depth_c + [0, 0, (bottom + top) / 2], (bar, 0.06, top - bottom - 4 * gap), yaw)
            if width > 1.0 or rng.random() < 0.5:  # a mullion, sometimes a transom
                frames.box(mid + depth_c + [0, 0, (bottom + top) / 2], (bar * 0.8, 0.05, top - bottom - 4 * gap), yaw)
            if rng.random() < 0.3:
                frames.box(mid + depth_c + [0, 0, bottom + 0.7 * (top - bottom)], (width - 4 * gap, 0.05, bar * 0.8), yaw)
            frames.box(mid + n * (0.03 - _EMBED_M) + [0, 0, bottom - 0.015], (width + 0.1, 0.06, 0.03), yaw)  # sill board
    # Baseboards everywhere except across door openings and their casings.
    for wall in range(len(poly)):
        a, b = wall_ends(poly, wall)
        length = np.linalg.norm(b - a)
        u2 = (b - a) / length
        n2 = inward_normal(poly, wall)
        cuts = sorted((o.start_m - casing_m, o.end_m + casing_m) for o in room.openings
                      if o.wall == wall and o.kind == "door")
        s = 0.0
        for c0, c1 in cuts + [(length, length)]:
            if c0 - s > 0.02:
                center = a + u2 * (s + c0) / 2 + n2 * (base_d / 2 - _EMBED_M)
                frames.box([center[0], center[1], base_h / 2 - _EMBED_M], (c0 - s, base_d, base_h),
                               float(np.arctan2(u2[1], u2[0])))
            s = c1


def _sun_direction(rng, room: Room, board_center_m):
    """Direction sunlight travels, through a random window, or None when the sun is out of
    play. Sometimes aimed so the edge of the sunlit patch crosses the board."""
    windows = [o for o in room.openings if o.kind == "window"]
    if not windows or rng.random() > 0.65:
        return None, False
    o = windows[rng.integers(len(windows))]
    n = np.append(inward_normal(room.polygon_m, o.wall), 0.0)
    if rng.random() < 0.35:
        a, b = o.segment_m(room.polygon_m)
        for _ in range(20):
            # A window edge point to a point near the board: the patch's edge lands there.
            s = rng.choice([0.0, 1.0]) if rng.random() < 0.5 else rng.uniform()
            z = rng.choice([o.bottom_m, o.top_m]) if s not in (0.0, 1.0) else rng.uniform(o.bottom_m, o.top_m)
            src = np.append(a + (b - a) * s, z)
            dst = np.append(board_center_m + rng.normal(0, 0.1, 2), 0.0)
            d = dst - src
            d /= np.linalg.norm(d)
            if np.dot(d, n) > 0.2 and -0.94 < d[2] < -0.17:
                return d, True
    azimuth = rng.uniform(-0.9, 0.9)
    c, s = np.cos(azimuth), np.sin(azimuth)
    horizontal = np.array([c * n[0] - s * n[1], s * n[0] + c * n[1], 0.0])
    elevation = rng.uniform(np.radians(15), np.radians(55))
    return np.cos(elevation) * horizontal - [0, 0, np.sin(elevation)], False


def _light_pose(direction, position=(0.0, 0.0, 0.0)):
    """A node pose whose -z axis points along ``direction`` (pyrender lights shine down -z)."""
    z = -np.asarray(direction, dtype=np.float64)
    z /= np.linalg.norm(z)
    helper = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    pose[:3, 3] = position
    return pose


def _second_floor(rng, room: Room, shot: Shot, board_center_m, board_radius_m, far: bool = False):
    """Where a second floor material lies: a half of the room beyond a straight or stepped
    threshold across the view or beside the board (walls are axis-aligned, thresholds run
    along them), never under the board; with ``far``, a strip 0.25-1.2 m deep along a
    wall, mostly the one the camera faces (a few pixels tall in the photo: the hardest to
    see). Returns a test ``(k, 2) points -> (k,) bool`` and the threshold's coordinates,
    which the floor's cells must split at, and whether it is stepped."""
    forward = shot.world_from_camera[:2, 2]
    across = rng.random() < (0.7 if far else 0.6)
    axis = int(np.argmax(np.abs(forward))) if across else int(np.argmin(np.abs(forward)))
    sign = float(np.sign(forward[axis])) if across else float(rng.choice([-1.0, 1.0]))
    # Between the board and the wall it faces, leaving half a meter of the second floor at
    # least; with less room than that there (the region is then empty), the caller redraws.
    room_m = sign * (room.polygon_m[:, axis].max() if sign > 0 else room.polygon_m[:, axis].min())
    room_m -= sign * board_center_m[axis] + board_radius_m
    if far:
        reach = max(room_m - rng.uniform(0.25, 1.2), 0.1 * room_m)
    else:
        reach = rng.uniform(0.15, 0.85) * (room_m - 0.5) if room_m > 0.8 else room_m + 1.0
    line = board_center_m[axis] + sign * (board_radius_m + reach)
    # A stepped threshold (a doorway's recess, an alcove): past ``step`` along the line
    # it moves farther from the board.
    stepped = rng.random() < 0.4
    step = board_center_m[1 - axis] + rng.uniform(-1.5, 1.5) if stepped else np.inf
    line2 = line + sign * rng.uniform(0.3, 1.2) if stepped else line

    def inside(points_m):
        p = np.atleast_2d(points_m)
        at = np.where(p[:, 1 - axis] < step, line, line2)
        return sign * (p[:, axis] - at) > 0

    cuts = {axis: [line, line2], 1 - axis: [step] if stepped else []}
    return inside, cuts, stepped


def _floor_cells(polygon_m, cuts):
    """The floor polygon (axis-aligned walls) cut into rectangles at its own vertices'
    coordinates and at ``cuts`` ({axis: [coordinate, ...]}): (k, 4, 2) corners."""
    lines = []
    for axis in (0, 1):
        values = np.concatenate([polygon_m[:, axis], [c for c in cuts.get(axis, []) if np.isfinite(c)]])
        lo, hi = polygon_m[:, axis].min(), polygon_m[:, axis].max()
        lines.append(np.unique(np.clip(values, lo, hi)))
    cells = []
    for x0, x1 in zip(lines[0][:-1], lines[0][1:]):
        for y0, y1 in zip(lines[1][:-1], lines[1][1:]):
            if x1 - x0 > 1e-6 and y1 - y0 > 1e-6:
                cells.append([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    cells = np.array(cells, dtype=np.float64).reshape(-1, 4, 2)
    return cells[contains(polygon_m, cells.mean(axis=1))]


def _threshold_strips(cells, second, width_m):
    """Flat strips (k, 4, 2) on the edges where a cell of one floor meets one of the other."""
    lo, hi = cells.min(axis=1), cells.max(axis=1)  # (k, 2) each
    strips = []
    for i in np.flatnonzero(second):
        for j in np.flatnonzero(~second):
            for axis in (0, 1):
                other = 1 - axis
                # The two meet along a line of constant ``axis`` and overlap along ``other``.
                if abs(hi[i, axis] - lo[j, axis]) < 1e-9:
                    at = hi[i, axis]
                elif abs(hi[j, axis] - lo[i, axis]) < 1e-9:
                    at = lo[i, axis]
                else:
                    continue
                start, end = max(lo[i, other], lo[j, other]), min(hi[i, other], hi[j, other])
                if end - start > 1e-6:
                    q = np.zeros((4, 2))
                    q[:, axis] = [at - width_m / 2, at + width_m / 2, at + width_m / 2, at - width_m / 2]
                    q[:, other] = [start, start, end, end]
                    strips.append(q)
    return np.array(strips).reshape(-1, 4, 2)


def _low_sun(rng, room: Room, shot: Shot):
    """A low, strong sun through one of the windows, aimed so its patch on the floor lies in
    view: the sunlit bands and patches that floor segmentation finds hardest. None when
    the room has no window."""
    windows = [o for o in room.openings if o.kind == "window"]
    if not windows:
        return None
    best = None
    for _ in range(40):
        o = windows[rng.integers(len(windows))]
        n = np.append(inward_normal(room.polygon_m, o.wall), 0.0)
        azimuth = rng.uniform(-1.1, 1.1)
        c, s = np.cos(azimuth), np.sin(azimuth)
        horizontal = np.array([c * n[0] - s * n[1], s * n[0] + c * n[1], 0.0])
        elevation = rng.uniform(np.radians(6), np.radians(32))
        d = np.cos(elevation) * horizontal - [0, 0, np.sin(elevation)]
        a, b = o.segment_m(room.polygon_m)
        src = np.append((a + b) / 2, (o.bottom_m + o.top_m) / 2)
        patch = src + d * (src[2] / -d[2])
        best = d
        if contains(room.polygon_m, patch[None, :2])[0] and shot.in_view(patch[None])[0]:
            return d
    return best


def build_scene(rng: np.random.Generator, room: Room, shot: Shot, board: Board,
                world_from_board: np.ndarray, texture_px: int = 512, baseboard_m=BASEBOARD_M,
                trim_like_floor: float = 0.0, trim_dark: float = 0.0, board_drawn: bool = True,
                pieces=(), low_sun: float = 0.0, two_floors: float = 0.0, outside: bool = True,
                shadowed_fill: bool = False, far_floor: float = 0.0) -> Scene:
    """Sample materials and lights and assemble the scene seen by ``shot`` (baseboards
    drawn ``baseboard_m`` (low, high) tall; the trim painted the floor's colour, 0.5-1.3
    of its brightness, with the chance ``trim_like_floor``, else a dark colour with the
    chance ``trim_dark``). Without ``board_drawn`` the board is left out and everything
    else drawn as with it: the floor the board hides, as the truth of its removal.
    ``pieces`` (Furniture, (4, 4) world pose) stand in the room besides, drawing nothing
    from ``rng``. With the chance ``low_sun`` a low, strong sun shines through a window
    onto the floor in view (:func:`_low_sun`); with the chance ``two_floors`` part of the
    floor is of a second material past a threshold (:func:`_second_floor`), of those with
    the chance ``far_floor`` a strip along a wall, mostly the one the camera faces. Each at
    0 draws nothing, so the random stream stays as it was. ``outside`` draws the building's
    outside (:func:`_outside`), which keeps the sun out but through the windows.
    ``shadowed_fill`` makes the fill light from the ceiling's middle a wide spot that casts
    shadows (the same light below the horizontal), as any real lamp does."""
    info: dict = {}
    sky = np.clip([0.92, 0.95, 1.0] + rng.normal(0, 0.03, 3), 0.8, 1.0)
    scene = GLScene(bg_color=np.append(sky, 1.0))
    seg = {}

    def add(mesh, label, pose=None):
        # Unique names make the draw order, hence the image, repeatable (see gl.Scene).
        node = scene.add(mesh, pose=pose, name=f"mesh{len(seg):03d}")
        seg[node] = label
        return node

    poly = room.polygon_m
    # Floor
    kind = textures.FLOOR_KINDS[rng.integers(len(textures.FLOOR_KINDS))]
    image, tile_m = textures.floor_texture(kind, _own(rng), texture_px)
    angle = rng.choice([0.0, np.pi / 2]) + rng.normal(0, 0.02)
    offset = rng.uniform(0, 1, 2)
    rot = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    floor = _Batch()
    floor_material = _material(rng, np.ones(3), image, roughness=(0.35, 0.9))
    info["floor_material"] = kind
    if two_floors > 0 and rng.random() < two_floors:
        sheet_m = np.hypot(*board.size_m) / 2 + 0.1
        # Redrawn until the second floor covers a tenth of the floor in view at least.
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        grid = np.stack(np.meshgrid(np.arange(lo[0], hi[0], 0.1), np.arange(lo[1], hi[1], 0.1)), -1).reshape(-1, 2)
        grid = grid[contains(poly, grid)]
        seen = grid[shot.in_view(np.column_stack([grid, np.zeros(len(grid))]))]
        far = far_floor > 0 and rng.random() < far_floor
        best = -1.0
        for _ in range(10):
            drawn = _second_floor(rng, room, shot, world_from_board[:2, 3], sheet_m, far)
            share = drawn[0](seen).mean() if len(seen) else 0.0
            if share > best:
                best, (inside, cuts, stepped) = share, drawn
            if share >= (0.01 if far else 0.1):
                break
        cells = _floor_cells(poly, cuts)
        second = inside(cells.mean(axis=1))
        kind2 = textures.FLOOR_KINDS[(textures.FLOOR_KINDS.index(kind) + rng.integers(1, len(textures.FLOOR_KINDS)))
                                     % len(textures.FLOOR_KINDS)]
        image2, tile2_m = textures.floor_texture(kind2, _own(rng), texture_px)
        angle2 = rng.choice([0.0, np.pi / 2]) + rng.normal(0, 0.02)
        rot2 = np.array([[np.cos(angle2), -np.sin(angle2)], [np.sin(angle2), np.cos(angle2)]])
        other = _Batch()
        for cell, there in zip(cells, second):
            lift = np.column_stack([cell, np.zeros(4)])
            if there:
                other.quad(lift, [0, 0, 1.0], cell @ rot2 / tile2_m)
            else:
                floor.quad(lift, [0, 0, 1.0], cell @ rot / tile_m + offset)
        if other.positions:
            add(other.mesh(_material(rng, np.ones(3), image2, roughness=(0.35, 0.9))), SEG_FLOOR)
            strips = _threshold_strips(cells, second, rng.uniform(0.02, 0.06)) if rng.random() < 0.5 else ()
            if len(strips):
                strip = _Batch()
                for q in strips:
                    strip.quad(np.column_stack([q, np.full(4, 0.001)]), [0, 0, 1.0])
                color = _random_tint(rng, [0.55, 0.5, 0.42], 0.12)
                add(strip.mesh(_material(rng, color, roughness=(0.3, 0.7))), SEG_FLOOR)
            share = float(sum(np.ptp(c[:, 0]) * np.ptp(c[:, 1]) for c in cells[second]))
            info["second_floor"] = {"material": kind2, "area_m2": round(share, 3), "strip": bool(len(strips)),
                                    "stepped": stepped}
    if not floor.positions:
        floor.polygon(poly, 0.0, True, lambda xy: xy @ rot / tile_m + offset)
    add(floor.mesh(floor_material), SEG_FLOOR)

    # Walls and ceiling
    wall_img, wall_tile = textures.wall_texture(_own(rng), max(64, texture_px // 2))
    walls = _Batch()
    _walls(room, walls, wall_tile)
    add(walls.mesh(_material(rng, np.ones(3), wall_img, roughness=(0.7, 1.0))), SEG_WALL)
    ceil_img, ceil_tile = textures.ceiling_texture(_own(rng), 64)
    ceiling = _Batch()
    ceiling.polygon(poly, room.height_m, False, lambda xy: xy / ceil_tile)
    add(ceiling.mesh(_material(rng, np.ones(3), ceil_img, roughness=(0.8, 1.0))), SEG_CEILING)

    # Doors, window frames, baseboards
    frames, doors = _Batch(), _Batch()
    _openings(rng, room, frames, doors, baseboard_m)
    white = _random_tint(rng, [0.85, 0.85, 0.83], 0.03)
    trim = white if rng.random() < 0.7 else _random_tint(rng, [0.45, 0.3, 0.18], 0.08)
    # Drawn only when asked for, so that the default random stream stays as it was.
    if trim_like_floor > 0 and rng.random() < trim_like_floor:
        # The shader decodes textures from sRGB; a colour factor is linear already.
        texels = image.reshape(-1, 3) / 255.0
        linear = np.where(texels <= 0.04045, texels / 12.92, ((texels + 0.055) / 1.055) ** 2.4).mean(axis=0)
        trim = np.clip(linear * rng.uniform(0.5, 1.3), 0.02, 1.0)
        info["trim_like_floor"] = True
    elif trim_dark > 0 and rng.random() < trim_dark:
        # Charcoal to black, lightly tinted: linear 0.004-0.08 is sRGB 13-79.
        trim = rng.uniform(0.004, 0.08) * np.clip(1 + rng.normal(0, 0.15, 3), 0.6, 1.4)
        info["trim_dark"] = True
    if frames.positions:
        add(frames.mesh(_material(rng, trim, roughness=(0.3, 0.7), closed=True)), SEG_OTHER)
    if doors.positions:
        door_color = white if rng.random() < 0.5 else _random_tint(rng, [0.5, 0.35, 0.22], 0.12)
        add(doors.mesh(_material(rng, door_color, roughness=(0.3, 0.8))), SEG_OTHER)

    # Clutter: cartons in one mesh, radiators in another.
    for kind, base, spread in (("box", [0.55, 0.4, 0.25], 0.06), ("radiator", [0.9, 0.9, 0.88], 0.03)):
        b = _Batch()
        for c in room.clutter:
            if c.kind == kind:
                b.box((c.center_m[0], c.center_m[1], c.size_m[2] / 2 - _EMBED_M), c.size_m, c.yaw_rad)
        if b.positions:
            add(b.mesh(_material(rng, _random_tint(rng, base, spread), closed=True)), SEG_OTHER)

    # Furniture (catalog kinds), built as the renderer builds it for staged photos.
    placed = []
    for c in room.clutter:
        if c.kind in FURNITURE_KINDS:
            item = PlacedItem(c.kind, (c.center_m[0], c.center_m[1], c.size_m[2] / 2), c.yaw_rad + np.pi / 2,
                              c.size_m)
            placed.append((furniture_for(item, seed=int(rng.integers(1 << 30))), world_from_item(item)))
    for mesh in furniture_meshes(placed + list(pieces)):
        add(mesh, SEG_OTHER)

    # The board: printed paper, slightly off-white, matte.
    sheet = board.image(px_per_square=32 if texture_px <= 256 else 64)
    h_px, w_px = sheet.shape
    px_m = board.square_m / (32 if texture_px <= 256 else 64)
    w_m, h_m = w_px * px_m, h_px * px_m
    paper = _Batch()
    # Image row 0 is board -y; pyrender flips rows on upload, so v = 1 is row 0.
    paper.quad([[-w_m / 2, -h_m / 2, 0], [w_m / 2, -h_m / 2, 0], [w_m / 2, h_m / 2, 0], [-w_m / 2, h_m / 2, 0]],
               [0, 0, 1.0], [[0, 1], [1, 1], [1, 0], [0, 0]])
    ink = np.repeat(sheet[..., None], 3, axis=2)
    # Only the ChArUco board is filtered sharply: checkerboard photos stay as they were.
    # The material is drawn either way, so the random stream goes on the same.
    printed = _material(rng, np.full(3, rng.uniform(0.8, 0.95)), ink, roughness=(0.6, 0.9), wrap=False,
                        sharp=board.kind == "charuco")
    if board_drawn:
        add(paper.mesh(printed), SEG_FLOOR, pose=world_from_board)
    if outside:  # after the other surfaces, which keep their names' order; draws nothing from rng
        shell = _Batch()
        _outside(room, shell)
        one_sided = pyrender.MetallicRoughnessMaterial(baseColorFactor=(0.5, 0.5, 0.5, 1.0), metallicFactor=0.0,
                                                       roughnessFactor=1.0, doubleSided=False)
        add(shell.mesh(one_sided), SEG_WALL)

    # Lights. One exposure factor scales them all, like the camera's exposure would.
    exposure = float(np.exp(rng.normal(0.0, 0.25)))
    warm = kelvin_rgb(rng.uniform(2700, 4500))
    daylight = kelvin_rgb(rng.uniform(5000, 7500))
    sun_dir, sun_on_board = _sun_direction(rng, room, world_from_board[:2, 3])
    strong = low_sun > 0 and rng.random() < low_sun and (low := _low_sun(rng, room, shot)) is not None
    if strong:
        sun_dir, sun_on_board = low, False
    lights = []
    if sun_dir is not None:
        intensity = float(rng.uniform(4.0, 10.0) if strong else rng.uniform(2.0, 5.0)) * exposure
        scene.add(pyrender.DirectionalLight(color=daylight, intensity=intensity), pose=_light_pose(sun_dir),
                  name="light0-sun")
        lights.append({"kind": "sun", "direction": sun_dir.round(4).tolist(), "intensity": intensity,
                       "edge_on_board": sun_on_board, **({"low": True} if strong else {})})
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    n_ceiling = rng.integers(1 if sun_dir is None else 0, 3)
    placed = 0
    fixtures = _Batch()
    for _ in range(30):
        if placed >= n_ceiling:
            break
        p = rng.uniform(lo, hi)
        if not contains(poly, p[None], margin_m=0.5)[0]:
            continue
        placed += 1
        z = room.height_m
        intensity = float(rng.uniform(8.0, 22.0)) * exposure
        spot = pyrender.SpotLight(color=warm, intensity=intensity,
                                  innerConeAngle=float(rng.uniform(0.3, 0.7)), outerConeAngle=1.25)
        scene.add(spot, pose=_light_pose([0, 0, -1.0], [p[0], p[1], z - 0.08]), name=f"light1-ceiling{placed}")
        fixtures.box([p[0], p[1], z - 0.03 + _EMBED_M], (0.3, 0.3, 0.06), rng.uniform(0, np.pi))
        lights.append({"kind": "ceiling", "position_m": [float(p[0]), float(p[1]), float(z - 0.08)],
                       "intensity": intensity})
    if fixtures.positions:
        add(fixtures.mesh(_material(rng, np.ones(3), emissive=warm * 0.9, closed=True)), SEG_OTHER)
    # Light bouncing off walls and floor: a fill from the ceiling (unshadowed unless asked) plus ambient.
    center = (lo + hi) / 2
    fill = float(rng.uniform(1.5, 5.0)) * exposure
    fill_light = (pyrender.SpotLight(color=(warm + daylight) / 2, intensity=fill, innerConeAngle=1.3,
                                     outerConeAngle=1.35) if shadowed_fill else
                  pyrender.PointLight(color=(warm + daylight) / 2, intensity=fill))
    scene.add(fill_light,
              pose=_light_pose([0, 0, -1.0], [center[0], center[1], room.height_m - 0.3]), name="light2-fill")
    ambient = float(rng.uniform(0.12, 0.35)) * exposure
    scene.ambient_light = ambient * (warm + daylight) / 2
    info["lights"] = lights
    info["ambient"] = ambient

    scene.add(pyrender_camera(shot.K), pose=gl_from_cv_pose(shot.world_from_camera), name="camera")
    return Scene(scene, seg, info)
