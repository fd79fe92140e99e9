"""A suggestion as a 3-D scene (binary glTF 2.0): the measured floor, its walls, the
furniture, for Blender, three.js or a viewer on a listing page."""
from __future__ import annotations

import numpy as np

from layout.geometry import triangulate_polygon

from .furniture import furniture_for, placed_items, world_from_item
from .settings import RENDER
from .staged import wall_segments

# glTF is y up; the floor frame is z up: (x, y, z) -> (x, z, -y).
GLTF_FROM_FLOOR = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]])


def _floor_mesh(polygon_m: np.ndarray):
    import trimesh

    poly = np.asarray(polygon_m, dtype=np.float64)
    vertices = np.column_stack([poly, np.zeros(len(poly))])
    return trimesh.Trimesh(vertices, triangulate_polygon(poly), face_colors=RENDER.gltf.floor_rgba, process=False)


def _wall_mesh(walls_m: np.ndarray, height_m: float):
    """Quads of ``height_m`` on the (k, 2, 2) wall segments of a counter-clockwise floor,
    facing into the room, or None."""
    import trimesh

    if len(walls_m) == 0:
        return None
    v, f = [], []
    for (x0, y0), (x1, y1) in walls_m:
        n = len(v)
        v += [(x0, y0, 0.0), (x1, y1, 0.0), (x1, y1, height_m), (x0, y0, height_m)]
        f += [(n, n + 2, n + 1), (n, n + 3, n + 2)]
    return trimesh.Trimesh(np.array(v), np.array(f), face_colors=RENDER.gltf.wall_rgba, process=False)


def _matte(tree: dict) -> None:
    """glTF's default material is fully metallic, which PBR viewers show nearly black:
    every primitive without a material gets a matte, two-sided one that shows its
    vertex colours."""
    materials = tree.setdefault("materials", [])
    materials.append({"name": "matte", "doubleSided": True,
                      "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                                               "roughnessFactor": 0.85}})
    for mesh in tree.get("meshes", []):
        for primitive in mesh["primitives"]:
            primitive.setdefault("material", len(materials) - 1)


def scene_glb(floor, height_m: float, layout, seed: int = 0, cache: dict | None = None,
              assets: dict | None = None, style: str | None = None) -> bytes:
    """A suggestion as a binary glTF 2.0 scene (y up, meters, as Blender, three.js and
    Unity expect): the measured floor, walls of ``height_m`` along its ``"boundary"``
    edges, and the furniture (node names are the item ids).

    Parameters
    ----------
    floor : FloorPolygon or (n, 2) float64
        In the floor frame; for an array every edge gets a wall.
    height_m : float
    layout : Layout, layout dict or sequence of PlacedItem
    seed : int
        Furniture style seed, as given to :func:`augment.render.staged.render_staged` (the
        scene shows the same pieces as the staged photo).
    cache : dict, optional
        Built furniture kept between calls (:func:`augment.render.furniture.furniture_for`).
    assets : dict, optional
        Kind -> the user's model, as for :func:`augment.render.staged.render_staged`.
    style : str, optional
        The furniture's style, as given to :func:`augment.render.staged.render_staged`.
    """
    import trimesh

    scene = trimesh.Scene()
    scene.add_geometry(_floor_mesh(getattr(floor, "polygon_m", floor)), node_name="floor", geom_name="floor",
                       transform=GLTF_FROM_FLOOR)
    walls = _wall_mesh(wall_segments(floor), float(height_m))
    if walls is not None:
        scene.add_geometry(walls, node_name="walls", geom_name="walls", transform=GLTF_FROM_FLOOR)
    items = list(layout) if isinstance(layout, (list, tuple)) else placed_items(layout)
    for k, item in enumerate(items):
        mesh = furniture_for(item, seed, assets, cache, style).to_trimesh(world_from_item(item))
        name = item.id or f"{item.kind}_{k + 1}"
        scene.add_geometry(mesh, node_name=name, geom_name=name, transform=GLTF_FROM_FLOOR)
    from trimesh.exchange.gltf import export_glb

    return export_glb(scene, include_normals=True, tree_postprocessor=_matte)
