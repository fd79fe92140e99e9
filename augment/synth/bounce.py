"""The room's bounce light as the furniture hides it from the floor and the walls: the soft
darkening a real room shows under, around and behind furniture, for the truth of a staged
photo.

The photographer's ambient and fill lights stand for light bounced off the walls, the
ceiling and the floor, and pyrender draws both through the furniture. A real floor or wall
point gets that light from the whole hemisphere it faces, cosine-weighted; the furniture
hides part of it. :func:`bounce_visibility` measures that share with depth maps of the
furniture seen from many directions of the hemisphere.
"""
from __future__ import annotations

import math

import numpy as np

from ..render.gl import Renderer, Scene, far_camera, gl_from_cv_pose, pyrender
from ..render.staged import hemisphere_directions

# Far enough that the depth maps' perspective hardly differs from parallel rays; the
# points are projected with the same camera, so what difference remains is exact.
_DISTANCE_M = 60.0


def bounce_visibility(renderer: Renderer, pieces, points_m: np.ndarray, normal=(0.0, 0.0, 1.0),
                      n_directions: int = 48, texel_m: float = 0.01, bias_m: float = 0.02) -> np.ndarray:
    """The share of a uniform sky each point of a plane sees past the furniture, cosine-weighted.

    Parameters
    ----------
    renderer : Renderer
    pieces : sequence of (Furniture, (4, 4) array)
        The furniture and its poses in the world (z up, meters).
    points_m : (n, 3) float
        Points on one plane (the floor, a wall), world frame.
    normal : (3,) float
        The plane's normal, toward the room (up for the floor).
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
    scene = Scene(bg_color=[0.0, 0.0, 0.0, 0.0])
    scene.add(mesh, name="furniture")
    # Every direction's camera has the same intrinsics: one node, moved.
    camera_node = scene.add(far_camera(center, radius, (0.0, 0.0, -1.0), size, _DISTANCE_M)[2], name="camera")
    seen = np.zeros(len(points), np.float32)
    n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    # The hemisphere's frame (rows), z along the normal; the world's own for the floor, so
    # its samples (and their noise) stay those the floor's truth always had.
    t = np.cross([0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [0.0, 0.0, 1.0], n)
    t /= np.linalg.norm(t)
    about_n = np.stack([t, np.cross(n, t), n])
    for d in hemisphere_directions(n_directions) @ about_n:
        camera_from_world, K, _ = far_camera(center, radius, -d, size, _DISTANCE_M)
        scene.set_pose(camera_node, gl_from_cv_pose(np.linalg.inv(camera_from_world)))
        depth = renderer.render(scene, size, size, flags=pyrender.RenderFlags.DEPTH_ONLY)
        local = points @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
        z = local[:, 2]
        u = np.round(K[0, 0] * local[:, 0] / z + K[0, 2]).astype(np.int64)
        v = np.round(K[1, 1] * local[:, 1] / z + K[1, 2]).astype(np.int64)
        inside = (u >= 0) & (u < size) & (v >= 0) & (v < size)
        hidden = np.zeros(len(points), bool)
        nearest = depth[v[inside], u[inside]]
        hidden[inside] = (nearest > 0) & (nearest < z[inside] - bias_m)
        seen += ~hidden
    return seen / n_directions

