"""Rendering speed, and the pictures of the README's rendering section.

Run by hand (from the repository root):

* ``python benchmarks/render.py [--repeats 5]``: stages the four sample photos
  (``samples/photos/room_K.jpg``, calibrated from their board, floor mask from their
  ground truth) with two layouts each (presets bedroom, living room, living room,
  office): one solved for the visible floor's polygon (``augment.floor.polygon.floor_polygon``),
  as the furnishing pipeline does, and a heavier one for the room's whole floor, at
  1280x960 and upscaled to 4032x3024, with one renderer for everything. Prints the median
  seconds per stage and writes ``results/render.{json,md}``. The first render of each photo builds its furniture and
  is reported apart ("cold"); the medians are of the renders after it, as for the second
  and later suggestions of a photo.
* ``python benchmarks/render.py --gallery``: ``docs/furniture_gallery.png``, every catalog
  kind rendered by :func:`augment.render.staged.render_staged` on a plain studio floor (its style in
  brackets), ``docs/render_rooms.jpg``, the four sample photos before and after staging, and
  ``docs/surfaces.jpg``, every surface as a 20 cm swatch and three pieces close up.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

from augment.camera.board import Board  # noqa: E402
from augment.camera.calibrate import calibrate_photo  # noqa: E402
from augment.photo.io import read_photo  # noqa: E402
from augment.floor.polygon import floor_polygon  # noqa: E402
from augment.render.furniture import PlacedItem, furniture_for, placed_items  # noqa: E402
from augment.render.gl import Renderer  # noqa: E402
from augment.render.look import estimate_look  # noqa: E402
from augment.render.staged import Lighting, estimate_lighting, render_staged, write_jpeg, write_png  # noqa: E402
from augment.render.surfaces import surface  # noqa: E402
from layout.catalog import CATALOG  # noqa: E402
from layout.spec import build, load_spec  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PHOTOS = ROOT / "samples" / "photos"
DOCS = ROOT / "docs"
ROOMS = (("room_1", "bedroom"), ("room_2", "living_room"), ("room_3", "living_room"), ("room_4", "office"))
BIG = (4032, 3024)


def load_room(name: str, preset: str):
    """Photo, calibration (from its board), floor mask (its ground truth), the visible
    floor's polygon (:func:`augment.floor.polygon.floor_polygon`) and a layout of ``preset`` on it,
    as the furnishing pipeline would make them."""
    image = read_photo(PHOTOS / f"{name}.jpg")
    calibration = calibrate_photo(image, Board())
    mask = cv2.imread(str(PHOTOS / f"{name}_floor.png"), cv2.IMREAD_GRAYSCALE) > 127
    truth = json.loads((PHOTOS / f"{name}.json").read_text())
    floor = floor_polygon(mask, calibration)
    items = room_layout(floor.polygon_m, truth["room"]["height_m"], preset)
    return image, calibration, mask, floor, items


def whole_room_layout(name: str, preset: str) -> list[PlacedItem]:
    """A layout of ``preset`` on the room's whole floor (its ground truth, in the board's
    frame): more furniture, some of it beside or behind the camera."""
    truth = json.loads((PHOTOS / f"{name}.json").read_text())
    board_from_world = np.linalg.inv(np.array(truth["board"]["world_from_board"]))
    poly = np.array(truth["room"]["polygon_m"])
    poly = (np.column_stack([poly, np.zeros(len(poly)), np.ones(len(poly))]) @ board_from_world.T)[:, :2]
    return room_layout(poly, truth["room"]["height_m"], preset)


def room_layout(polygon_m, height_m: float, preset: str, seed: int = 0) -> list[PlacedItem]:
    """A layout of ``preset`` solved for a floor polygon in the calibration's floor frame."""
    text = (f'[room]\npolygon = {np.asarray(polygon_m).round(4).tolist()}\nheight = {height_m:.3f}\n'
            f'preset = "{preset}"\n')
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "room.toml"
        path.write_text(text)
        model, solver = build(load_spec(path))
    return placed_items(solver.suggest(model, 1, seed=seed)[0])


def upscaled(image, calibration, mask, size):
    """The photo, its calibration and mask resized to ``size`` (pixel edges kept)."""
    w, h = size
    s = w / image.shape[1]
    K = calibration.intrinsics.K.copy()
    K[:2, :2] *= s
    K[0, 2], K[1, 2] = (K[0, 2] + 0.5) * s - 0.5, (K[1, 2] + 0.5) * s - 0.5
    cal = replace(calibration, size_px=(w, h), intrinsics=replace(calibration.intrinsics, K=K))
    big = cv2.resize(image, (w, h), interpolation=cv2.INTER_LINEAR)
    big_mask = cv2.resize(mask.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST) > 0
    return big, cal, big_mask


STAGES = ("lighting", "look_estimate", "build", "render", "self_shadows", "occlusion", "shadows", "look", "composite",
          "total")


def benchmark(repeats: int) -> None:
    rows = []
    with Renderer() as renderer:
        for name, preset in ROOMS:
            image, calibration, mask, floor, visible = load_room(name, preset)
            layouts = (("visible floor", visible), ("whole room", whole_room_layout(name, preset)))
            sizes = ((image.shape[1], image.shape[0]), BIG)
            for (layout_name, items), size in [(lay, size) for lay in layouts for size in sizes]:
                img, cal, msk = (image, calibration, mask) if size[0] == image.shape[1] else \
                    upscaled(image, calibration, mask, size)
                runs = []
                for k in range(repeats + 1):
                    t = time.perf_counter()
                    lighting = estimate_lighting(img, cal, msk)
                    t_light = time.perf_counter() - t
                    t = time.perf_counter()
                    look = estimate_look(img, cal)  # once per photo, as the pipeline does
                    t_look = time.perf_counter() - t
                    staged = render_staged(img, cal, items, renderer, floor_mask=msk,
                                           floor_polygon=floor if layout_name == "visible floor" else None,
                                           lighting=lighting, look=look)
                    runs.append(dict(staged.timings_s, lighting=t_light, look_estimate=t_look,
                                     total=staged.timings_s["total"] + t_light + t_look))
                warm = runs[2:] if len(runs) > 2 else runs[1:]
                med = {s: float(np.median([r.get(s, 0.0) for r in warm])) for s in STAGES}
                rows.append(dict(photo=name, layout=layout_name, size=f"{size[0]}x{size[1]}", items=len(items),
                                 roi=list(staged.roi_px), render_scale=staged.render_scale,
                                 cold_s=runs[0]["total"], median_s=med, runs=len(warm)))
                print(f"{name} {layout_name} {size[0]}x{size[1]}: {len(items)} items, scale {staged.render_scale:g}, "
                      f"cold {runs[0]['total']:.2f} s, median {med['total']:.2f} s "
                      + " ".join(f"{s} {med[s]:.3f}" for s in STAGES[:-1]), flush=True)
    load = os.getloadavg()
    md = ["# Rendering speed: `python benchmarks/render.py`", "",
          f"One `Renderer` for all; medians of {repeats - 1} renders after two warm-up renders per photo "
          "(the first builds the furniture: \"cold\"). Seconds. Mesa llvmpipe (CPU), "
          f"{os.cpu_count()} cores; load average during the run {load[0]:.1f} (another job was using the "
          "machine).", "",
          "| photo | layout | size | items | render scale | cold | " + " | ".join(STAGES) + " |",
          "|---|---|---|---|---|---|" + "---|" * len(STAGES)]
    for r in rows:
        md.append(f"| {r['photo']} | {r['layout']} | {r['size']} | {r['items']} | {r['render_scale']:g} | "
                  f"{r['cold_s']:.2f} | "
                  + " | ".join(f"{r['median_s'][s]:.3f}" for s in STAGES) + " |")
    md.append("")
    for size in ("1280x960", f"{BIG[0]}x{BIG[1]}"):
        totals = [r["median_s"]["total"] for r in rows if r["size"] == size]
        md.append(f"- {size}: median over photos and layouts {np.median(totals):.2f} s, max {max(totals):.2f} s.")
    results_io.write("render", results_io.machine(load_average=load, rows=rows), md)
    print("\n".join(md))


# --------------------------------------------------------------------------------------
# Pictures
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Intrinsics:
    K: np.ndarray
    distortion: np.ndarray


@dataclass(frozen=True)
class _View:
    """What render_staged needs of a calibration, for a made-up studio camera."""

    size_px: tuple
    intrinsics: _Intrinsics
    camera_from_floor: np.ndarray


def _studio_view(size_m, cell_px, azimuth_deg=-35.0, elevation_deg=24.0):
    """A camera looking at a box of ``size_m`` (width, depth, height) at the origin, its
    front toward +x, from front-right and above, framing it with a margin."""
    W, D, H = size_m
    w, h = cell_px
    a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
    target = np.array([0.0, 0.0, 0.5 * H])
    radius = 0.5 * float(np.linalg.norm([W, D, H]))
    f = 1.6 * w
    dist = radius * f / (0.5 * min(w, h)) + 0.5 * radius
    eye = target + dist * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, [0, 0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z])  # camera_from_floor rotation (OpenCV axes)
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = R, -R @ eye
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])
    return _View((w, h), _Intrinsics(K, np.zeros(5)), pose)


def _backdrop(view):
    """A studio photo: a pale floor (darker toward the horizon) under a plain wall."""
    w, h = view.size_px
    K, R = view.intrinsics.K, view.camera_from_floor[:3, :3]
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float64)
    rays = np.linalg.solve(K, np.stack([xs.ravel(), ys.ravel(), np.ones(w * h)]))
    up = (R.T @ rays)[2].reshape(h, w)
    floor = up < 0
    shade = np.clip(-up / np.linalg.norm(rays, axis=0).reshape(h, w), 0, 1) ** 0.25
    img = np.empty((h, w, 3), np.float64)
    img[...] = np.array([214, 212, 208.0]) * (0.82 + 0.18 * shade)[..., None]
    img[~floor] = np.array([232, 231, 229.0])
    return np.clip(img, 0, 255).astype(np.uint8), floor


_STUDIO_LIGHT = Lighting((1.0, 0.985, 0.96), (-0.45, 0.55, -0.70), 0.5, 0.1, (0.62, 0.6, 0.58), "studio")


def _label(tile: np.ndarray, text: str, size: int) -> np.ndarray:
    img = Image.fromarray(tile)
    draw = ImageDraw.Draw(img)
    font = ImageFont.load_default(size=size)
    draw.text((8, tile.shape[0] - size - 8), text, fill=(40, 40, 40), font=font)
    return np.asarray(img)


def _studio_render(renderer, kind: str, cell):
    """One catalog piece alone on the studio floor, framed in a ``cell`` (w, h) photo."""
    size = CATALOG[kind].size_m
    view = _studio_view(size, cell)
    photo, floor = _backdrop(view)
    item = PlacedItem(kind, (0.0, 0.0, size[2] / 2), 0.0, size, kind)
    staged = render_staged(photo, view, [item], renderer, floor_mask=floor, lighting=_STUDIO_LIGHT,
                           supersample=2.0, self_shadows=True)
    return staged.image, item


def _grid(tiles, columns):
    """The tiles in rows of ``columns``, the last row filled with white."""
    blank = np.full_like(tiles[0], 255)
    return [np.hstack(tiles[i:i + columns] + [blank] * (columns - len(tiles[i:i + columns])))
            for i in range(0, len(tiles), columns)]


def gallery(path: Path, cell=(320, 240), columns=8) -> None:
    kinds = list(CATALOG)
    tiles = []
    with Renderer() as renderer:
        for kind in kinds:
            image, item = _studio_render(renderer, kind, cell)
            tiles.append(_label(image, f"{kind.replace('_', ' ')} ({furniture_for(item).style})", 15))
    write_png(path, np.vstack(_grid(tiles, columns)))
    print(f"wrote {path} ({len(kinds)} kinds)")


# A typical colour per surface for its swatch (linear RGB), and the swatches' order.
_SWATCHES = {"wood:oak": (0.45, 0.30, 0.17), "wood:light oak": (0.62, 0.47, 0.30), "wood:ash": (0.66, 0.55, 0.40),
             "wood:pine": (0.62, 0.45, 0.25), "wood:teak": (0.42, 0.24, 0.11), "wood:walnut": (0.28, 0.16, 0.09),
             "wood:dark walnut": (0.16, 0.09, 0.05), "wood:weathered": (0.40, 0.36, 0.31),
             "weave": (0.35, 0.37, 0.40), "linen": (0.62, 0.58, 0.50), "boucle": (0.80, 0.77, 0.70),
             "velvet": (0.10, 0.22, 0.16), "wool": (0.45, 0.28, 0.18), "felt": (0.30, 0.30, 0.32),
             "rug": (0.55, 0.48, 0.38), "leather": (0.38, 0.18, 0.08), "metal:brushed": (0.60, 0.50, 0.30),
             "metal:powder": (0.04, 0.04, 0.04), "paint": (0.80, 0.80, 0.78), "ceramic": (0.65, 0.68, 0.70),
             "terracotta": (0.55, 0.25, 0.13), "concrete": (0.45, 0.44, 0.42), "marble": (0.85, 0.85, 0.83),
             "basket": (0.55, 0.40, 0.22), "leaf": (0.10, 0.28, 0.07)}


def surfaces_picture(path: Path, swatch_px=200, columns=9, close=(480, 360)) -> None:
    """Every surface as a 20 cm square (its colour times its detail, sampled at 1 px per
    mm), and a sofa, a dresser and an armchair rendered close."""
    tiles = []
    for name, rgb in _SWATCHES.items():
        surf = surface(name)
        n = round(0.2 / surf.tile_m * surf.image.shape[0])  # texels in 20 cm
        detail = (np.resize(surf.image, (n, n, 3)) if n > surf.image.shape[0] else surf.image[:n, :n]) / 255.0
        linear = detail ** 2.2 * np.asarray(rgb) / np.asarray(surf.mean_rgb)
        srgb = np.clip(255.0 * np.clip(linear, 0, 1) ** (1 / 2.2), 0, 255).astype(np.uint8)
        tile = cv2.resize(srgb, (swatch_px, swatch_px), interpolation=cv2.INTER_AREA)
        tile = _label(np.vstack([tile, np.full((28, swatch_px, 3), 255, np.uint8)]), name.replace("wood:", ""), 15)
        tiles.append(tile)
    rows = _grid(tiles, columns)
    with Renderer() as renderer:
        strip = np.hstack([_studio_render(renderer, kind, close)[0] for kind in ("sofa", "dresser", "armchair")])
    width = rows[0].shape[1]
    strip = cv2.resize(strip, (width, round(strip.shape[0] * width / strip.shape[1])), interpolation=cv2.INTER_AREA)
    write_jpeg(path, np.vstack(rows + [strip]), quality=90)
    print(f"wrote {path}")


def rooms_picture(path: Path, width=640) -> None:
    pairs = []
    with Renderer() as renderer:
        for name, preset in ROOMS:
            image, calibration, mask, floor, items = load_room(name, preset)
            staged = render_staged(image, calibration, items, renderer, floor_mask=mask, floor_polygon=floor)
            h = round(image.shape[0] * width / image.shape[1])
            pairs.append(np.hstack([cv2.resize(a, (width, h), interpolation=cv2.INTER_AREA)
                                    for a in (image, staged.image)]))
    write_jpeg(path, np.vstack(pairs), quality=90)
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5, help="timed renders per photo and size")
    parser.add_argument("--gallery", action="store_true", help="write the pictures instead of timing")
    args = parser.parse_args()
    if args.gallery:
        gallery(DOCS / "furniture_gallery.png")
        rooms_picture(DOCS / "render_rooms.jpg")
        surfaces_picture(DOCS / "surfaces.jpg")
    else:
        benchmark(max(2, args.repeats))


if __name__ == "__main__":
    main()
