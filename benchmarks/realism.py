"""Staged photos against the truth: the synthetic photographer furnishes the room itself.

Run by hand: ``python benchmarks/realism.py [--count 40] [--seed 9700] [--old d0f695e]
[--fill occluded|through|shadowed]`` (about half an hour). Writes
``results/realism.{json,md}`` and ``results/realism_worst.png``, or
``realism_<fill>_fill.*`` for another ``--fill``. The photographer's bounce light (its
ambient light and its fill light from the ceiling's middle) in the truth:

* ``occluded`` (default): the furniture hides it from the floor and the walls as in a real
  room, a cosine-weighted share of a uniform sky (:func:`augment.synth.bounce.bounce_visibility`):
  the soft darkening under, around and behind furniture;
* ``through``: it lights the floor through the furniture (pyrender's own lights);
* ``shadowed``: the fill is a wide spot that casts shadows, in the empty photo and in the
  truth alike, as a real lamp there would; the ambient light passes through.

Each case (seed ``[--seed, i]``, sizes from 1280x960 to 4032x3024, the living room, bedroom,
dining room and office presets in turn) is an empty synthetic room with the board on the
floor, saved as a phone would (JPEG, the 35 mm focal length in EXIF). ``stage furnish``'s
pipeline (:func:`augment.pipeline.furnish`) calibrates, segments, solves one layout and
stages it. The photographer then renders the same room, camera, lights and degradation
once more with that layout's furniture standing in it (the same pieces, materials and
styles, placed in the world by the true board pose) and without the board: the truth of
the staged photo, lit by physically based shading with shadow maps of the sun and the
ceiling lights, a different renderer from the staged photo's.

Scores, per case (also for the renderer with its key light from windows only, no sun read
off the floor: ``RENDER.staged.sun_from_floor = False``):
* ``delta_e``: median CIEDE2000 between the staged photo and the truth over the truth's
  furniture pixels (where the furniture stands nearer than the empty room), eroded by 2 px
  per 1280 px of width so misregistered outlines do not dominate.
* ``shadow_iou``: IoU of the floor pixels darkened by more than 10 % (linear luminance,
  smoothed by a Gaussian of 1 px per 1280) in the truth (furnished / empty) and in the
  staged photo (staged / board erased), over the floor that shows in both, off the
  board's sheet; cases with neither shadow are left out.
* ``wall_shadow_iou``: the same over the walls (no target): what the furniture's shadows and
  occlusion darken on the walls beside and above it.
* ``light_error_deg`` (rooms with sun): the angle on the floor plane between the sun's
  direction and the key light the renderer estimated.

The same layouts are rendered by the renderer of ``--old`` (a git revision: today's
renderer when issue 51 was filed), run in a subprocess from a worktree of that revision,
into the same board-erased photos with the same calibration, floor and layout.
"""
from __future__ import annotations

import argparse
import math
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OLD_DRIVER = "--old-driver" in sys.argv
if not OLD_DRIVER:  # the old driver imports the old revision's augment, from PYTHONPATH
    sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

SIZES = ((1280, 960), (1600, 1200), (2016, 1512), (4032, 3024))
ROOMS = ("living_room", "bedroom", "dining_room", "office")
TARGETS = {"delta_e_median": ("<=", 6.0), "shadow_iou_median": (">=", 0.7), "light_error_deg_median": ("<=", 15.0)}
# A render shows its sun when this share of the floor in view is sunlit (the truth's
# ``floor_in_view``); on the others no photo tells where the sun is.
SUN_IN_VIEW = 0.02


def old_driver(folder: Path) -> int:
    """Render every ``case_*.pkl`` in ``folder`` with the revision on PYTHONPATH."""
    from augment.render.gl import Renderer
    from augment.render.staged import estimate_lighting, render_staged

    renderer = Renderer()
    for path in sorted(folder.glob("case_*.pkl")):
        case = pickle.loads(path.read_bytes())
        t = time.perf_counter()
        lighting = estimate_lighting(case["image"], case["calibration"], case["mask"])
        done = render_staged(case["image"], case["calibration"], {"items": case["items"]}, renderer,
                             floor_mask=case["mask"], floor_polygon=case["floor"], lighting=lighting,
                             seed=case["seed"])
        np.savez_compressed(path.with_suffix(".old.npz"), image=done.image, alpha=done.alpha,
                            direction=np.asarray(lighting.direction), seconds=time.perf_counter() - t)
    renderer.close()
    return 0


def linear_luminance(rgb: np.ndarray) -> np.ndarray:
    x = rgb.astype(np.float32) / 255.0
    return ((x ** 2.2) @ np.array([0.2126, 0.7152, 0.0722], np.float32)).astype(np.float32)


def scores(truth_f, truth_e, staged, erased, staged_alpha, sheet, floor_f, wall_f, sun_world, est_world) -> dict:
    """The scores of one case (see the module docstring); NaN where undefined."""
    from skimage.color import deltaE_ciede2000, rgb2lab

    h, w = staged.shape[:2]
    unit = w / 1280.0
    depth_e = np.where(truth_e.depth_m > 0, truth_e.depth_m, np.inf)
    furniture = (truth_f.depth_m > 0) & (truth_f.depth_m < depth_e - 0.01)
    r = max(1, round(2 * unit))
    core = cv2.erode(furniture.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0
    out = {"furniture_px": int(furniture.sum())}
    if core.sum() >= 50:
        d = deltaE_ciede2000(rgb2lab(truth_f.image[core]), rgb2lab(staged[core]))
        out["delta_e"] = float(np.median(d))
    else:
        out["delta_e"] = math.nan

    sigma = max(0.8, unit)
    def darkened(a, b):
        ratio = cv2.GaussianBlur(linear_luminance(a), (0, 0), sigma) / np.maximum(
            cv2.GaussianBlur(linear_luminance(b), (0, 0), sigma), 1e-4)
        return ratio < 0.9
    grow = np.ones((2 * r + 1, 2 * r + 1), np.uint8)
    near = cv2.dilate((furniture | (staged_alpha > 0.5)).astype(np.uint8), grow) > 0
    region = floor_f & ~near & ~(cv2.dilate(sheet.astype(np.uint8), grow) > 0)
    for key, where in (("shadow", region), ("wall_shadow", wall_f & ~near)):
        t, s = darkened(truth_f.image, truth_e.image) & where, darkened(staged, erased) & where
        union = int((t | s).sum())
        out[f"{key}_truth_px"], out[f"{key}_staged_px"] = int(t.sum()), int(s.sum())
        out[f"{key}_iou"] = float((t & s).sum() / union) if union >= 0.0005 * h * w else math.nan
    out["light_error_deg"] = math.nan if sun_world is None else azimuth_error_deg(sun_world, est_world)
    return out


def azimuth_error_deg(a, b) -> float:
    """Angle between the floor-plane parts of two directions (3,), degrees in [0, 180]."""
    a, b = np.asarray(a, dtype=np.float64)[:2], np.asarray(b, dtype=np.float64)[:2]
    cos = float(a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-12))
    return math.degrees(math.acos(np.clip(cos, -1.0, 1.0)))


def _crop(images, mask, height=260):
    ys, xs = np.nonzero(mask)
    if len(xs) == 0:
        ys, xs = np.array([0, images[0].shape[0] - 1]), np.array([0, images[0].shape[1] - 1])
    pad = int(0.08 * images[0].shape[1])
    h, w = images[0].shape[:2]
    x0, x1 = max(0, xs.min() - pad), min(w, xs.max() + pad)
    y0, y1 = max(0, ys.min() - pad), min(h, ys.max() + pad)
    width = max(1, round(height * (x1 - x0) / max(1, y1 - y0)))
    return [cv2.resize(im[y0:y1, x0:x1], (min(width, 520), height), interpolation=cv2.INTER_AREA) for im in images]


def _median(rows, key):
    v = np.array([r[key] for r in rows if key in r and not math.isnan(r[key])])
    return (float(np.median(v)), len(v)) if len(v) else (math.nan, 0)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--seed", type=int, default=9700)
    parser.add_argument("--old", default="d0f695e", help="git revision of the renderer to compare with")
    parser.add_argument("--fill", choices=("occluded", "through", "shadowed"), default="occluded",
                        help="the truth's bounce light: hidden from the floor by the furniture (default), "
                             "through it, or the fill light casting shadows")
    parser.add_argument("--old-driver", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.old_driver:
        return old_driver(args.old_driver)

    from results_io import RESULTS, machine, write

    from augment.camera.board import Board
    from augment.errors import StagerError
    from augment.pipeline import furnish
    from augment.render.furniture import furniture_for, placed_items, world_from_item
    from augment.render.gl import Renderer
    from augment.render.look import estimate_look
    from augment.render.settings import RENDER
    from augment.render.staged import estimate_lighting, render_staged
    from augment.synth import FLOOR, WALL, render_sample
    from augment.synth.photo import save_as_phone
    from augment.synth.truth import floor_in_world
    from layout.fileio import write_atomic

    work = Path(tempfile.mkdtemp(prefix="realism-"))
    old_tree = work / "old"
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(old_tree), args.old], check=True)
    renderer = Renderer()
    rows, kept, cal_poses = [], {}, {}
    try:
        for i in range(args.count):
            size, room = SIZES[i % len(SIZES)], ROOMS[(i // len(SIZES)) % len(ROOMS)]
            seed = [args.seed, i]
            row = {"case": i, "size": f"{size[0]}x{size[1]}", "room": room}
            t = time.perf_counter()
            empty = render_sample(seed, renderer, size, clutter=False, shadowed_fill=args.fill == "shadowed")
            truth = empty.truth
            photo = work / f"case_{i:02d}.jpg"
            save_as_phone(photo, empty.image, truth["K"][0][0], truth["photo"]["jpeg_quality"])
            try:
                result = furnish(photo, Board(), room=room, suggestions=1, seed=i, renderer=renderer)
            except StagerError as error:
                row["refused"] = str(error)
                rows.append(row)
                print(f"case {i:2d} {row['size']:>9} {room:<12} refused: {error}", flush=True)
                continue
            lay, style = result.layouts[0], result.styles[0]
            lay_seed = i if lay.seed is None else int(lay.seed)
            items = placed_items(lay)
            world_from_floor = floor_in_world(truth, result.calibration.camera_from_floor)
            pieces = [(furniture_for(it, lay_seed, style=style), world_from_floor @ world_from_item(it))
                      for it in items]
            truth_f = render_sample(seed, renderer, size, clutter=False, board_drawn=False, pieces=pieces,
                                    shadowed_fill=args.fill == "shadowed", occluded_bounce=args.fill == "occluded")
            t_truth = time.perf_counter() - t

            cal, mask = result.calibration, result.segmentation.mask
            base = result.erased.image
            lighting = estimate_lighting(result.image, cal, mask, floor_polygon=result.floor,
                                        ceiling_m=result.room_height_m)
            t = time.perf_counter()
            panes = [w.corners_px for w in result.windows]
            new = render_staged(base, cal, lay, renderer, floor_mask=mask, floor_polygon=result.floor,
                                lighting=lighting, look=estimate_look(result.image, cal), seed=lay_seed, style=style,
                                windows_px=panes)
            row["new_render_s"] = time.perf_counter() - t
            assert np.array_equal(new.image, result.staged[0]), "the re-render differs from the pipeline's"
            sun = next((np.asarray(lt["direction"]) for lt in truth["render"]["lights"] if lt["kind"] == "sun"), None)
            est = world_from_floor[:3, :3] @ np.asarray(lighting.direction)
            sheet = result.erased.full_alpha() > 0.01
            floor_f, wall_f = truth_f.labels == FLOOR, truth_f.labels == WALL
            sun_share = next((lt["floor_in_view"] for lt in truth["render"]["lights"] if lt["kind"] == "sun"), 0.0)
            row.update(items=len(items), style=style, sun=sun is not None, sun_in_view=sun_share,
                       light_source=lighting.source, lamps=len(lighting.lamps), truth_s=t_truth)
            row["new"] = scores(truth_f, empty, new.image, base, new.alpha, sheet, floor_f, wall_f, sun, est)
            # The same renderer with the key light from windows only (no sun read off the floor).
            windows_only = replace(RENDER.staged, sun_from_floor=False)
            lit_w = estimate_lighting(result.image, cal, mask, windows_only, floor_polygon=result.floor,
                                    ceiling_m=result.room_height_m)
            plain = render_staged(base, cal, lay, renderer, floor_mask=mask, floor_polygon=result.floor,
                                  lighting=lit_w, look=estimate_look(result.image, cal), seed=lay_seed, style=style,
                                  windows_px=panes, settings=windows_only)
            row["no_sun"] = scores(truth_f, empty, plain.image, base, plain.alpha, sheet, floor_f, wall_f, sun,
                                   world_from_floor[:3, :3] @ np.asarray(lit_w.direction))
            case = {"image": base, "calibration": cal, "mask": mask, "floor": result.floor,
                    "items": [{"kind": it.kind, "position_m": list(it.position_m), "yaw_rad": it.yaw_rad,
                               "size_m": list(it.size_m), "id": it.id} for it in items], "seed": lay_seed}
            (work / f"case_{i:02d}.pkl").write_bytes(pickle.dumps(case))
            cal_poses[i] = cal.camera_from_floor
            kept[i] = (truth_f, empty, new.image, base, sheet, floor_f, wall_f, sun)
            print(f"case {i:2d} {row['size']:>9} {room:<12} {style:<12} new dE {row['new']['delta_e']:5.2f} "
                  f"shadow IoU {row['new']['shadow_iou']:.2f} light {row['new']['light_error_deg']:6.1f}", flush=True)
            rows.append(row)

        # Today's renderer of --old, on the same inputs, in one process.
        env = dict(os.environ, PYTHONPATH=str(old_tree))
        subprocess.run([sys.executable, str(Path(__file__).resolve()), "--old-driver", str(work)], env=env,
                       cwd=str(old_tree), check=True)
        pictures = []
        for row in rows:
            i = row["case"]
            if i not in kept:
                continue
            old = np.load(work / f"case_{i:02d}.old.npz")
            truth_f, empty, new_image, base, sheet, floor_f, wall_f, sun = kept[i]
            world_from_floor = floor_in_world(empty.truth, cal_poses[i])
            est = world_from_floor[:3, :3] @ old["direction"]
            row["old"] = scores(truth_f, empty, old["image"], base, old["alpha"], sheet, floor_f, wall_f, sun, est)
            row["old_render_s"] = float(old["seconds"])
            pictures.append((row["new"]["delta_e"], i, _crop([truth_f.image, new_image, old["image"]],
                                                             truth_f.depth_m < np.where(empty.depth_m > 0,
                                                                                        empty.depth_m, np.inf) - 0.01)))
    finally:
        renderer.close()
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old_tree)], check=False)

    summary = {}
    for which in ("new", "no_sun", "old"):
        done = [r[which] for r in rows if which in r]
        summary[which] = {}
        for key in ("delta_e", "shadow_iou", "wall_shadow_iou", "light_error_deg"):
            med, n = _median(done, key)
            summary[which][f"{key}_median"] = med
            summary[which][f"{key}_cases"] = n
        seen = [r[which] for r in rows if which in r and r.get("sun_in_view", 0.0) >= SUN_IN_VIEW]
        med, n = _median(seen, "light_error_deg")
        summary[which]["light_error_deg_sun_in_view_median"] = med
        summary[which]["light_error_deg_sun_in_view_cases"] = n
    passed = {k: (summary["new"][k] <= v if op == "<=" else summary["new"][k] >= v) for k, (op, v) in TARGETS.items()}
    name = "realism" if args.fill == "occluded" else f"realism_{args.fill}_fill"
    flag = "" if args.fill == "occluded" else f" --fill {args.fill}"
    data = {"machine": machine(count=args.count, seed=args.seed, old=args.old, fill=args.fill),
            "targets": TARGETS,
            "summary": summary, "passed": passed, "cases": rows}
    refused = [r for r in rows if "refused" in r]
    md = ["# Realism: staged photos against the synthetic photographer's truth", "",
          f"`python benchmarks/realism.py --count {args.count} --seed {args.seed} --old {args.old}{flag}` "
          f"({data['machine']['date']}, {data['machine']['cpu_count']} cores). {len(rows) - len(refused)} of "
          f"{len(rows)} cases staged; {len(refused)} refused by the pipeline.", "",
          "| measure | target | new | new, no sun from the floor | old renderer | cases |", "|---|---|---|---|---|---|"]
    for key, (op, v) in TARGETS.items():
        short = key.replace("_median", "")
        md.append(f"| {key} | {op} {v:g} | {summary['new'][key]:.3g} | {summary['no_sun'][key]:.3g} | "
                  f"{summary['old'][key]:.3g} | {summary['new'][short + '_cases']} |")
    md.append("| wall_shadow_iou_median | | " + " | ".join(f"{summary[w]['wall_shadow_iou_median']:.3g}"
                                                         for w in ("new", "no_sun", "old"))
              + f" | {summary['new']['wall_shadow_iou_cases']} |")
    md.append(f"| light_error_deg_median, sun on the floor in view (>= {SUN_IN_VIEW:.0%} of it) | <= 15 | "
              + " | ".join(f"{summary[w]['light_error_deg_sun_in_view_median']:.3g}" for w in ("new", "no_sun", "old"))
              + f" | {summary['new']['light_error_deg_sun_in_view_cases']} |")
    md += ["", "| case | size | room | style | sun (share of the floor in view) | key light from | "
           "dE new / no sun / old | "
           "shadow IoU new / no sun / old | wall shadow IoU new / old | light error new / no sun / old ° |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "refused" in r:
            md.append(f"| {r['case']} | {r['size']} | {r['room']} | refused: {r['refused'][:80]} | | | | | | |")
            continue
        n, w, o = r["new"], r["no_sun"], r.get("old", {})
        sun = format(r["sun_in_view"], ".0%") if r["sun"] else ""
        lamps = r.get("lamps", 0)
        source = r["light_source"] + (f" + {lamps} lamp{'s' if lamps > 1 else ''}" if lamps else "")
        md.append(f"| {r['case']} | {r['size']} | {r['room']} | {r['style']} | {sun} | "
                  f"{source} | {n['delta_e']:.1f} / {w['delta_e']:.1f} / {o.get('delta_e', math.nan):.1f} | "
                  f"{n['shadow_iou']:.2f} / {w['shadow_iou']:.2f} / {o.get('shadow_iou', math.nan):.2f} | "
                  f"{n['wall_shadow_iou']:.2f} / {o.get('wall_shadow_iou', math.nan):.2f} | "
                  f"{n['light_error_deg']:.0f} / {w['light_error_deg']:.0f} / "
                  f"{o.get('light_error_deg', math.nan):.0f} |")
    fill = {"occluded": "its bounce light (ambient and fill) reaches the floor and the walls as far as the furniture "
                        "leaves a uniform sky open in front of each point; the furniture's own surfaces take it "
                        "unoccluded",
            "through": "its ambient light and its fill light from the ceiling's middle light through the furniture: "
                       "its floor darkens only under the sun and the ceiling lamps, and the renderer's occlusion "
                       "under furniture, which real rooms show, counts against it in shadow IoU",
            "shadowed": "its fill light from the ceiling's middle casts shadows (`--fill shadowed`), its ambient "
                        "light does not"}[args.fill]
    md += ["", f"`{name}_worst.png`: the six cases with the largest ΔE, each truth | new | old renderer.", "",
           "Lamps: ceiling lamps the renderer found from their pools of light on the floor (the photographer's fill "
           f"light's pool counts as one). The truth: pyrender with shadow maps, and {fill}. The old renderer reads its "
           "light off the board-erased photo, as the pipeline then did."]
    write(name, data, md)
    worst = sorted((p for p in pictures if not math.isnan(p[0])), key=lambda p: -p[0])[:6]
    if worst:
        width = max(sum(c.shape[1] for c in p[2]) for p in worst)
        strips = [np.pad(np.hstack(p[2]), ((0, 6), (0, width - sum(c.shape[1] for c in p[2])), (0, 0)),
                         constant_values=255) for p in worst]
        ok, png = cv2.imencode(".png", cv2.cvtColor(np.vstack(strips), cv2.COLOR_RGB2BGR))
        write_atomic(RESULTS / f"{name}_worst.png", png.tobytes())
    shutil.rmtree(work, ignore_errors=True)
    print("\n".join(md[:10]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
