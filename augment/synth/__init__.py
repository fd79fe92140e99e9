"""Synthetic room photographer: rendered photos of empty rooms with a checkerboard on the
floor, and their exact ground truth. The fixture factory for every image-stage test and
the training-data source of the floor model.

One image: :func:`render_sample` samples a room (:mod:`.rooms`), a hand-held camera and a
board pose in view (:mod:`.camera`), clutter out of the board's way, materials and lights
(:mod:`.scene`), renders color and a label pass with pyrender, and degrades the render
like a phone would (:mod:`.photo`). Everything random comes from one seed, so the same
seed gives the same image. ``python -m augment.synth`` writes datasets.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from layout.fileio import write_atomic
from layout.geometry import edge_distances

from ..camera.board import CHARUCO_DICTIONARY, Board
from ..render.gl import Renderer, pyrender
from .bounce import bounce_visibility
from .camera import Shot, place_board, random_handling, random_shot, random_size
from .photo import degrade
from .rooms import BASEBOARD_M, Clutter, Room, add_clutter, add_furniture, inward_normal, random_room
from .scene import SEG_CEILING, SEG_FLOOR, SEG_WALL, build_scene
from .truth import sun_exit

FORMAT = "stager-synth-1"
# Label image values (``Sample.labels``).
OTHER, FLOOR, WALL, CEILING = 0, 1, 2, 3
# A board corner counts as visible when the render's depth there is within this of the
# board's own depth (anything nearer is an occluder).
_VISIBLE_DEPTH_TOL_M = 0.02
# The label and colour passes see the same surface where their depths agree within this
# fraction (or the tolerance above).
_SAME_SURFACE_REL = 0.01


@dataclass
class Sample:
    """One synthetic photo and its ground truth.

    image : (h, w, 3) uint8 RGB, degraded (JPEG is applied when written).
    floor_mask : (h, w) bool, visible floor pixels, the board included.
    labels : (h, w) uint8, OTHER / FLOOR / WALL / CEILING.
    depth_m : (h, w) float32, distance along the optical axis; 0 where the sky shows.
    truth : dict, the JSON written beside the image.
    """

    image: np.ndarray
    floor_mask: np.ndarray
    labels: np.ndarray
    depth_m: np.ndarray
    truth: dict


def _texture_px(size_px) -> int:
    longest = max(size_px)
    return 256 if longest <= 480 else 512 if longest <= 1280 else 1024


def _keep_out(shot: Shot, outline_m: np.ndarray) -> list[np.ndarray]:
    """Floor regions clutter must avoid: the board (with room to spare) and the wedge from
    the camera to it, so nothing hides a corner."""
    center = outline_m.mean(axis=0)
    grown = center + (outline_m - center) * 1.6
    cam = shot.world_from_camera[:2, 3]
    ring = cam + 0.4 * np.column_stack([np.cos(np.arange(8) * np.pi / 4), np.sin(np.arange(8) * np.pi / 4)])
    hull = cv2.convexHull(np.vstack([grown, ring]).astype(np.float32))[:, 0, :].astype(np.float64)
    return [hull]


def _board_cover(board: Board, world_from_board: np.ndarray, fraction: float) -> Clutter:
    """A flat carton (3 cm high) over ``fraction`` of the board's squares, from its +x edge
    to 5 cm past the sheet's, and 5 cm past the sheet on both sides."""
    if not 0 < fraction < 1:
        raise ValueError(f"board_hidden {fraction}: expected a fraction of the board between 0 and 1")
    squares_m = (board.cols + 1) * board.square_m
    sheet_w, sheet_h = board.size_m
    x0, x1 = squares_m / 2 - fraction * squares_m, sheet_w / 2 + 0.05
    center = world_from_board[:3, :3] @ [(x0 + x1) / 2, 0.0, 0.0] + world_from_board[:3, 3]
    yaw = float(np.arctan2(world_from_board[1, 0], world_from_board[0, 0]))
    return Clutter("box", (float(center[0]), float(center[1])), (x1 - x0, sheet_h + 0.1, 0.03), yaw)


def render_sample(seed, renderer: Renderer, size_px: tuple[int, int] | None = None,
                  board: Board | None = None, clutter: bool = True, photographic: bool = True,
                  board_hidden: float = 0.0, furnished: float = 0.0, baseboard_m=BASEBOARD_M,
                  trim_like_floor: float = 0.0, trim_dark: float = 0.0, board_drawn: bool = True,
                  pieces=(), low_sun: float = 0.0, two_floors: float = 0.0, outside: bool = True,
                  shadowed_fill: bool = False, occluded_bounce: bool = False, far_floor: float = 0.0) -> Sample:
    """Render one synthetic room photo with its ground truth.

    Parameters
    ----------
    seed : int or sequence of int
        Everything random derives from ``np.random.default_rng(seed)``.
    renderer : Renderer
        The process's GL context.
    size_px : (width, height), optional
        Image size; random (landscape or portrait phone sizes) when None.
    board : Board, optional
        Checkerboard or ChArUco board; the CLI default when None.
    clutter : bool
        Allow cartons and radiators on the floor.
    photographic : bool
        Apply exposure, white balance, vignetting, blur and noise (JPEG happens on write).
    furnished : float
        Chance that the room gets 1-6 pieces of catalog furniture (0: never, and the
        random stream is the same as without this option). Empty rooms are what Stager
        is for; furnished ones teach the floor model where furniture ends.
    board_hidden : float
        Put a flat carton over this fraction of the board's squares (across its width, from
        its +x edge): a partly hidden board, as ChArUco boards allow. The truth's
        ``corners_visible`` says which corners the render shows.
    baseboard_m : (low, high)
        The range the baseboards' height is drawn from, meters (another range keeps the
        random stream: only the boards' heights change).
    trim_like_floor : float
        Chance that the baseboards, casings and window frames are painted the floor's
        colour, 0.5-1.3 of its brightness (0: never, and the random stream is the same as
        without this option). Such boards look like a band of light or shade on the floor,
        the skirting check's hardest case.
    board_drawn : bool
        False: the same photo without the board (the floor under it shows), for the truth
        of the board's removal from staged photos.
    trim_dark : float
        Chance that they are painted a dark colour instead (charcoal to black, lightly
        tinted; 0: never, and the random stream is the same as without this option).
    pieces : sequence of (Furniture, (4, 4) array)
        Furniture to stand in the room as it is, at its pose in the world (e.g. a staged
        layout's, for the truth of a staged photo); the random stream stays the same.
    low_sun : float
        Chance of a low, strong sun through a window onto the floor in view: bright bands
        and patches, the floor stage's hardest light (0: never, and the random stream is
        the same as without this option).
    two_floors : float
        Chance that part of the floor, past a straight or stepped threshold away from the
        board, is of a second material (0: never, and the random stream is the same).
    far_floor : float
        Of those rooms, the chance that the second floor is a strip 0.25-1.2 m deep along
        a wall, mostly the one the camera faces: a few pixels tall, the threshold case the
        floor model misses most (0: never, and the random stream is the same).
    outside : bool
        Draw the building's outside, so that the walls and the ceiling keep the sun out
        (:func:`augment.synth.scene._outside`). Without it the sun lights the whole room
        but for the window frames' shadows: the photos some regression tests were found
        on, drawn the same.
    shadowed_fill : bool
        The fill light from the ceiling's middle casts shadows (a wide spot, the same
        light below the horizontal) instead of lighting through the furniture: the
        realism benchmark's truth. Off by default: the training renders stay as they were.
    occluded_bounce : bool
        The furniture (``pieces``) hides the bounce light (ambient and fill) from the floor
        and the walls as it would in a real room (:func:`_hide_bounce`): the truth of the
        soft darkening under, around and behind furniture. Off by default; not with
        ``shadowed_fill``.
    """
    if occluded_bounce and shadowed_fill:
        raise ValueError("occluded_bounce and shadowed_fill are two models of the fill light: choose one")
    board = Board() if board is None else board
    rng = np.random.default_rng(seed)
    size_px = random_size(rng) if size_px is None else (int(size_px[0]), int(size_px[1]))
    # The phone's handling is drawn once, so pitch, height and lens keep their stated
    # distributions; rooms and standpoints are redrawn until the board lies in view.
    # Only a handling that never shows a board (rare: nearly level and narrow) is redrawn.
    world_from_board = None
    for _ in range(20):
        handling = random_handling(rng, size_px)
        for _ in range(30):
            room = random_room(rng)
            shot = random_shot(rng, room, handling)
            world_from_board = place_board(rng, room, shot, board)
            if world_from_board is not None:
                break
        if world_from_board is not None:
            break
    else:
        raise RuntimeError(f"seed {seed}: found no camera that sees a {board.cols}x{board.rows} board")
    outline = (board.outline_m() @ world_from_board[:3, :3].T + world_from_board[:3, 3])[:, :2]
    if clutter:
        room = add_clutter(rng, room, _keep_out(shot, outline))
    if furnished > 0 and rng.random() < furnished:
        room = add_furniture(rng, room, _keep_out(shot, outline))
    if board_hidden > 0:
        room = replace(room, clutter=room.clutter + (_board_cover(board, world_from_board, board_hidden),))

    built = build_scene(rng, room, shot, board, world_from_board, _texture_px(size_px), baseboard_m,
                        trim_like_floor, trim_dark, board_drawn, pieces, low_sun, two_floors, outside,
                        shadowed_fill, far_floor)
    width, height = size_px
    flags = pyrender.RenderFlags.SHADOWS_DIRECTIONAL | pyrender.RenderFlags.SHADOWS_SPOT
    # Small frames cannot show a 2048-texel shadow map's detail; it would cost half the time.
    shadow_px = 1024 if max(size_px) <= 800 else 2048
    color, depth_m = renderer.render(built.scene, width, height, flags=flags, shadow_map_px=shadow_px)
    labels = render_labels(renderer, built.scene, built.seg_node_map, depth_m)
    if occluded_bounce and len(pieces):
        color = _hide_bounce(renderer, built.scene, color, labels, depth_m, shot, room, pieces)
    for light in built.info["lights"]:
        if light["kind"] == "sun" and outside:
            light["floor_in_view"] = round(_sunlit_share(labels == FLOOR, depth_m, shot, room, light["direction"]), 4)

    if photographic:
        image, photo_params = degrade(rng, color)
    else:
        image, photo_params = color, {"jpeg_quality": 95}

    corners_world = board.corners_m() @ world_from_board[:3, :3].T + world_from_board[:3, 3]
    corners_px, corner_depth = shot.project(corners_world)
    ij = np.round(corners_px).astype(int)
    inside = (ij[:, 0] >= 0) & (ij[:, 0] < width) & (ij[:, 1] >= 0) & (ij[:, 1] < height)
    visible = inside.copy()
    seen = depth_m[ij[inside, 1], ij[inside, 0]]
    visible[inside] = np.abs(seen - corner_depth[inside]) < _VISIBLE_DEPTH_TOL_M
    truth = _truth(seed, room, shot, board, world_from_board, corners_px, visible, built.info, photo_params)
    return Sample(image, labels == FLOOR, labels, depth_m, truth)


# The truth's hemisphere samples: at 48 their streaks alone moved a room's shadow IoU at
# the 10 % threshold by up to 0.05 (the same directions turned 90 degrees).
_BOUNCE_DIRECTIONS = 144


def _hide_bounce(renderer: Renderer, scene, color, labels, depth_m, shot: Shot, room: Room, pieces) -> np.ndarray:
    """``color`` with the bounce light of the floor and the walls dimmed by the share of the
    sky the furniture hides from them (:func:`.bounce.bounce_visibility`, each wall about
    its own normal, on a grid about 640 points wide: the occlusion is smooth). The bounce
    light is the render with the ambient and the fill light alone; pyrender's output is
    linear light to the power 1/2.2. Removes the scene's other lights."""
    h, w = depth_m.shape
    step = max(1, round(w / 640))
    coarse = labels[::step, ::step]
    grid = ((coarse == FLOOR) | (coarse == WALL)) & (depth_m[::step, ::step] > 0)
    v, u = np.nonzero(grid)
    points = shot.unproject(u * step, v * step, depth_m[::step, ::step][v, u])
    # Each wall point faces the room from the wall it lies nearest to.
    plane = np.full(len(points), -1)
    walls = np.flatnonzero(coarse[v, u] == WALL)
    if len(walls):
        plane[walls] = np.argmin(edge_distances(points[walls, :2], room.polygon_m), axis=1)
    hidden = np.zeros(grid.shape, np.float32)
    for k in np.unique(plane):
        mine = plane == k
        normal = (0.0, 0.0, 1.0) if k < 0 else (*inward_normal(room.polygon_m, int(k)), 0.0)
        hidden[v[mine], u[mine]] = 1.0 - bounce_visibility(renderer, pieces, points[mine], normal, _BOUNCE_DIRECTIONS)
    # Back to every pixel: the grid points only, averaged (a normalized interpolation).
    map_x, map_y = np.meshgrid(np.arange(w, dtype=np.float32) / step, np.arange(h, dtype=np.float32) / step)
    total = cv2.remap(hidden, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    weight = cv2.remap(grid.astype(np.float32), map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    lit = (labels == FLOOR) | (labels == WALL)
    hidden = np.where(lit & (weight > 1e-3), total / np.maximum(weight, 1e-3), 0.0).astype(np.float32)
    for node in list(scene.light_nodes):
        if not node.name.startswith("light2"):  # the sun (light0) and the ceiling lamps (light1)
            scene.remove_node(node)
    bounce, _ = renderer.render(scene, w, h)
    linear = (color.astype(np.float32) / 255.0) ** 2.2
    linear -= hidden[..., None] * (bounce.astype(np.float32) / 255.0) ** 2.2
    return np.round(np.clip(linear, 0.0, 1.0) ** (1 / 2.2) * 255.0).astype(np.uint8)


def _sunlit_share(floor, depth_m, shot, room: Room, direction) -> float:
    """Share of the floor in view that the sun reaches through a window (from geometry:
    the frames' and the clutter's shadows not counted), every 4th pixel."""
    v, u = np.nonzero(floor[::4, ::4] & (depth_m[::4, ::4] > 0))
    if len(v) == 0:
        return 0.0
    points = shot.unproject(u * 4, v * 4, depth_m[v * 4, u * 4])
    windows = [(o.segment_m(room.polygon_m), o.bottom_m, o.top_m) for o in room.openings if o.kind == "window"]
    return float(np.mean(sun_exit(points, direction, room.polygon_m, room.height_m, windows) > 0))


def render_labels(renderer: Renderer, scene, seg_node_map: dict, depth_m: np.ndarray) -> np.ndarray:
    """The label image (OTHER / FLOOR / WALL / CEILING) of ``scene``, as its photo shows it.

    Parameters
    ----------
    renderer : Renderer
    scene : pyrender.Scene
        With its camera; ``seg_node_map`` gives each mesh node its ``SEG_*`` colour.
    depth_m : (h, w) float32
        Depth of the colour render (:meth:`Renderer.render`), 0 where nothing was drawn.

    Returns
    -------
    (h, w) uint8
    """
    height, width = depth_m.shape
    seg, seg_depth_m = renderer.render(scene, width, height, flags=pyrender.RenderFlags.SEG,
                                       seg_node_map=seg_node_map)
    # pyrender's label pass culls back faces even of two-sided materials, which the colour
    # pass draws: where the photo shows a wall or a door from behind (through a window,
    # across the notch of an L-shaped room) the labels would show what lies beyond it. A
    # label counts only where its surface is the one the photo shows. (The two passes'
    # depths of one surface differ by up to 0.3 % on the floor at a grazing angle.)
    shown = np.abs(seg_depth_m - depth_m) <= np.maximum(_VISIBLE_DEPTH_TOL_M, _SAME_SURFACE_REL * depth_m)
    labels = np.zeros((height, width), np.uint8)
    for value, rgb in ((FLOOR, SEG_FLOOR), (WALL, SEG_WALL), (CEILING, SEG_CEILING)):
        labels[(seg[..., int(np.argmax(rgb))] > 127) & shown] = value
    return labels


def _openings_json(room: Room, kind: str) -> list[dict]:
    return [{"segment_m": o.segment_m(room.polygon_m).round(4).tolist(), "wall": o.wall,
             "bottom_m": round(o.bottom_m, 4), "top_m": round(o.top_m, 4)}
            for o in room.openings if o.kind == kind]


def _truth(seed, room, shot, board, world_from_board, corners_px, visible, info, photo_params) -> dict:
    R = shot.world_from_camera[:3, :3]
    forward, right = R[:, 2], R[:, 0]
    pitch = np.arcsin(-forward[2])
    return {
        "format": FORMAT,
        "seed": np.asarray(seed).tolist(),
        "size_px": list(shot.size_px),
        "K": shot.K.tolist(),
        "distortion": [0.0] * 5,
        "camera_from_world": shot.camera_from_world.tolist(),
        "camera": {
            "height_m": float(shot.world_from_camera[2, 3]),
            "pitch_down_deg": float(np.degrees(pitch)),
            "roll_deg": float(np.degrees(np.arcsin(np.clip(-right[2] / np.cos(pitch), -1, 1)))),
            "hfov_deg": float(np.degrees(2 * np.arctan(shot.size_px[0] / 2 / shot.K[0, 0]))),
        },
        "room": {
            "polygon_m": room.polygon_m.round(6).tolist(),
            "height_m": room.height_m,
            "doors": _openings_json(room, "door"),
            "windows": _openings_json(room, "window"),
            "clutter": [{"kind": c.kind, "footprint_m": c.footprint_m().round(4).tolist(),
                         "height_m": round(c.size_m[2], 4)} for c in room.clutter],
        },
        "board": {
            "kind": board.kind,
            **({"dictionary": CHARUCO_DICTIONARY} if board.kind == "charuco" else {}),
            "inner_corners": [board.cols, board.rows],
            "square_mm": board.square_mm,
            "sheet_mm": list(board.sheet_mm),
            "world_from_board": world_from_board.tolist(),
            "corners_px": corners_px.round(4).tolist(),
            "corners_visible": visible.tolist(),
        },
        "render": info,
        "photo": photo_params,
    }


def write_sample(sample: Sample, out_dir, stem: str) -> dict[str, Path]:
    """Write ``stem.jpg``, ``stem_floor.png`` (255 = floor) and ``stem.json``, atomically.

    The JSON is written last, so a complete JSON means a complete sample.
    """
    out_dir = Path(out_dir)
    quality = int(sample.truth["photo"]["jpeg_quality"])
    ok, jpg = cv2.imencode(".jpg", cv2.cvtColor(sample.image, cv2.COLOR_RGB2BGR),
                           [cv2.IMWRITE_JPEG_QUALITY, quality])
    ok2, png = cv2.imencode(".png", sample.floor_mask.astype(np.uint8) * 255)
    if not (ok and ok2):
        raise RuntimeError(f"could not encode sample {stem}")
    paths = {"image": out_dir / f"{stem}.jpg", "floor_mask": out_dir / f"{stem}_floor.png",
             "truth": out_dir / f"{stem}.json"}
    write_atomic(paths["image"], jpg.tobytes())
    write_atomic(paths["floor_mask"], png.tobytes())
    truth = dict(sample.truth, image=paths["image"].name, floor_mask=paths["floor_mask"].name)
    write_atomic(paths["truth"], json.dumps(truth, indent=1) + "\n")
    return paths
