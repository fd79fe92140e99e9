"""The room's bounce light as the furniture hides it from the floor: the soft darkening a
real floor shows under and around furniture, for the truth of a staged photo.

The photographer's ambient and fill lights stand for light bounced off the walls, the
ceiling and the floor, and pyrender draws both through the furniture. A real floor point
gets that light from its whole upper hemisphere, cosine-weighted; the furniture hides part
of it. :func:`floor_bounce_visibility` measures that share with depth maps of the furniture
seen from many directions of the hemisphere.
"""
from __future__ import annotations

import math

import numpy as np

from ..render.gl import Renderer, Scene, gl_from_cv_pose, pyrender

# Far enough that the depth maps' perspective hardly differs from parallel rays; the
# points are projected with the same camera, so what difference remains is exact.
_DISTANCE_M = 60.0


def hemisphere_directions(n: int) -> np.ndarray:
    """``n`` unit directions (n, 3) over the upper hemisphere (z > 0), cosine-weighted and
    evenly spread (a Fibonacci spiral on the disk, lifted onto the hemisphere): their mean
    visibility is a horizontal surface's share of a uniform sky."""
    k = np.arange(n) + 0.5
    r = np.sqrt(k / n)
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - r * r)], axis=1)


def floor_bounce_visibility(renderer: Renderer, pieces, points_m: np.ndarray, n_directions: int = 48,
                            texel_m: float = 0.01, bias_m: float = 0.02) -> np.ndarray:
    """The share of the sky each floor point sees past the furniture, cosine-weighted.

    Parameters
    ----------
    renderer : Renderer
    pieces : sequence of (Furniture, (4, 4) array)
        The furniture and its poses in the world (z up, meters).
    points_m : (n, 3) float
        Points on the floor, world frame.
    n_directions : int
        Directions sampled over the hemisphere.
    texel_m : float
        The depth maps' resolution where the furniture stands (at most 1024 texels a side).
    bias_m : float
        Depth slack: a point counts as hidden only behind furniture nearer than this.

    Returns
    -------
    (n,) float32 in [0, 1]
    """
    points = np.asarray(points_m, dtype=np.float64).reshape(-1, 3)
    parts = [part.transformed(np.asarray(pose, dtype=np.float64)) for furniture, pose in pieces
             for part in furniture.parts]
    if not parts or not len(points):
        return np.ones(len(points), np.float32)
    vertices = np.concatenate([p.vertices for p in parts])
    offsets = np.cumsum([0] + [len(p.vertices) for p in parts[:-1]])
    faces = np.concatenate([p.faces + o for p, o in zip(parts, offsets)])
    mesh = pyrender.Mesh([pyrender.Primitive(positions=vertices.astype(np.float32),
                                             indices=faces.astype(np.uint32), mode=pyrender.GLTF.TRIANGLES)])
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    center, radius = 0.5 * (lo + hi), max(0.5 * float(np.linalg.norm(hi - lo)), 0.05)
    size = int(min(1024, max(64, math.ceil(2.0 * radius / texel_m))))
    f = 0.5 * size * _DISTANCE_M / radius
    c = 0.5 * size - 0.5
    scene = Scene(bg_color=[0.0, 0.0, 0.0, 0.0])
    scene.add(mesh, name="furniture")
    camera = pyrender.IntrinsicsCamera(fx=f, fy=f, cx=c + 0.5, cy=c + 0.5, znear=_DISTANCE_M - 2.0 * radius,
                                       zfar=_DISTANCE_M + 2.0 * radius)
    camera_node = scene.add(camera, name="camera")
    seen = np.zeros(len(points), np.float32)
    directions = hemisphere_directions(n_directions)
    for d in directions:
        eye = center + d * _DISTANCE_M
        forward = -d  # the camera's z, OpenCV axes
        x = np.cross(forward, [0.0, 0.0, 1.0]) if abs(forward[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
        x /= np.linalg.norm(x)
        y = np.cross(forward, x)
        R = np.stack([x, y, forward])
        world_from_camera = np.eye(4)
        world_from_camera[:3, :3], world_from_camera[:3, 3] = R.T, eye
        scene.set_pose(camera_node, gl_from_cv_pose(world_from_camera))
        depth = renderer.render(scene, size, size, flags=pyrender.RenderFlags.DEPTH_ONLY)
        local = (points - eye) @ R.T
        z = local[:, 2]
        u = np.round(f * local[:, 0] / z + c).astype(np.int64)
        v = np.round(f * local[:, 1] / z + c).astype(np.int64)
        inside = (u >= 0) & (u < size) & (v >= 0) & (v < size)
        hidden = np.zeros(len(points), bool)
        nearest = depth[v[inside], u[inside]]
        hidden[inside] = (nearest > 0) & (nearest < z[inside] - bias_m)
        seen += ~hidden
    return seen / len(directions)

