"""The light read off empty photos: the key light's direction and the ceiling lamps, against
the synthetic photographer's truth, without staging anything.

Run by hand: ``python benchmarks/light.py [--seeds 9800 9801 9802] [--count 48]`` (about 3
minutes a seed on 2 cores). Writes ``results/light.{json,md}``. :mod:`realism` scores the
same light through the staged photos, ten times slower; this is for trying a change to
:func:`augment.render.staged.estimate_lighting` on many rooms.

Each case (seed ``[seed, i]``, the sizes 1280x960 to 4032x3024 in turn, as in
:mod:`realism`) is an empty room with the board, saved as a phone would and measured by
``stage measure``'s pipeline (:func:`augment.pipeline.measure`). Scores:

* ``light_error_deg`` (rooms with sun): the angle on the floor between the sun's direction
  and the key light's; ``sun_in_view``: the share of the floor in view that the sun lights
  (at least 2 %: the photo shows it). ``elevation_error_deg`` (the sun read off the floor):
  the sun's height over the floor, estimated against true, degrees (signed).
* ``false_sun``: rooms without sun where a sun was read off the floor.
* ``lamp_error_m``: per lamp found, the distance on the floor to the nearest true light
  (ceiling lamps, and the photographer's fill light at the ceiling's middle: a real pool).
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from realism import SIZES, SUN_IN_VIEW, azimuth_error_deg  # the same cases and scores


def one_case(seed: int, i: int, renderer, folder: Path) -> dict:
    from augment.camera.board import Board
    from augment.errors import StagerError
    from augment.pipeline import measure
    from augment.render.staged import estimate_lighting
    from augment.synth import render_sample
    from augment.synth.photo import save_as_phone
    from augment.synth.truth import floor_in_world

    size = SIZES[i % len(SIZES)]
    row = {"case": f"{seed}/{i}", "size": f"{size[0]}x{size[1]}"}
    sample = render_sample([seed, i], renderer, size, clutter=False)
    truth = sample.truth
    photo = folder / f"case_{seed}_{i:02d}.jpg"
    save_as_phone(photo, sample.image, truth["K"][0][0], truth["photo"]["jpeg_quality"])
    try:
        m = measure(photo, Board())
    except StagerError as error:
        return dict(row, refused=str(error))
    lighting = estimate_lighting(m.image, m.calibration, m.segmentation.mask, floor_polygon=m.floor,
                                 ceiling_m=m.height.height_m)
    world_from_floor = floor_in_world(truth, m.calibration.camera_from_floor)
    floor_from_world = np.linalg.inv(world_from_floor)
    lights = truth["render"]["lights"]
    sun = next((lt for lt in lights if lt["kind"] == "sun"), None)
    row.update(source=lighting.source, sun=sun is not None, sun_in_view=0.0 if sun is None else sun["floor_in_view"],
               sun_read=lighting.sun is not None and lighting.source == "sun")
    if sun is not None:
        row["light_error_deg"] = azimuth_error_deg(sun["direction"], world_from_floor[:3, :3] @ lighting.direction)
        if row["sun_read"]:
            row["elevation_error_deg"] = math.degrees(math.asin(-lighting.direction[2]) - math.asin(-sun["direction"][2]))
    room = truth["room"]
    poly = np.asarray(room["polygon_m"], dtype=np.float64)
    middle = (poly.min(axis=0) + poly.max(axis=0)) / 2
    true_xy = [np.append(lt["position_m"], 1.0) for lt in lights if lt["kind"] == "ceiling"]
    true_xy.append(np.array([middle[0], middle[1], room["height_m"] - 0.3, 1.0]))  # the fill light
    true_xy = np.array([(floor_from_world @ p)[:2] for p in true_xy])
    row["ceiling_lamps"] = len(true_xy) - 1
    row["lamp_error_m"] = [float(np.min(np.linalg.norm(true_xy - np.asarray(lamp.position_m[:2]), axis=1)))
                           for lamp in lighting.lamps]
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="+", default=[9800, 9801, 9802])
    parser.add_argument("--count", type=int, default=48)
    args = parser.parse_args(argv)

    from results_io import machine, write
    from tqdm import tqdm

    from augment.render.gl import Renderer

    rows = []
    with Renderer() as renderer, tempfile.TemporaryDirectory(prefix="light-") as folder:
        cases = [(s, i) for s in args.seeds for i in range(args.count)]
        for seed, i in tqdm(cases, disable=not sys.stderr.isatty()):
            rows.append(one_case(seed, i, renderer, Path(folder)))

    done = [r for r in rows if "refused" not in r]
    sunny = [r for r in done if r["sun"]]
    seen = [r for r in sunny if r["sun_in_view"] >= SUN_IN_VIEW]
    read = [r for r in sunny if r["sun_read"]]
    lamps = [e for r in done for e in r["lamp_error_m"]]

    def med(values):
        return float(np.median(values)) if len(values) else math.nan

    summary = {
        "cases": len(rows), "measured": len(done),
        "light_error_deg_median": med([r["light_error_deg"] for r in sunny]), "sunny": len(sunny),
        "light_error_deg_sun_in_view_median": med([r["light_error_deg"] for r in seen]), "sun_in_view": len(seen),
        "sun_in_view_within_15_deg": sum(r["light_error_deg"] <= 15 for r in seen),
        "sun_in_view_reversed": sum(r["light_error_deg"] >= 150 for r in seen),
        "sun_in_view_read": sum(r["sun_read"] for r in seen),
        "elevation_error_deg_median": med([abs(r["elevation_error_deg"]) for r in read]), "sun_read": len(read),
        "elevation_within_10_deg": sum(abs(r["elevation_error_deg"]) <= 10 for r in read),
        "false_sun": sum(r["sun_read"] for r in done if not r["sun"]), "without_sun": len(done) - len(sunny),
        "lamps_found": len(lamps), "ceiling_lamps": sum(r["ceiling_lamps"] for r in done),
        "lamp_error_m_median": med(lamps), "lamps_within_0_5_m": sum(e <= 0.5 for e in lamps),
    }
    s = summary
    seeds = " ".join(str(v) for v in args.seeds)
    md = ["# The light read off empty photos", "",
          (f"`python benchmarks/light.py --seeds {seeds} --count {args.count}` "
           f"({machine()['date']}, {machine()['cpu_count']} cores): {s['measured']} of {s['cases']} renders measured."),
          "", "| measure | value |", "|---|---|",
          f"| key light's azimuth error, median, {s['sunny']} rooms with sun | {s['light_error_deg_median']:.1f}° |",
          (f"| ... the {s['sun_in_view']} showing it on the floor (>= {SUN_IN_VIEW:.0%}) | "
           f"{s['light_error_deg_sun_in_view_median']:.1f}°: {s['sun_in_view_within_15_deg']} within 15°, "
           f"{s['sun_in_view_reversed']} reversed (150° or more); read off the floor in {s['sun_in_view_read']} |"),
          (f"| the sun's height, error, median, {s['sun_read']} rooms whose sun was read | "
           f"{s['elevation_error_deg_median']:.1f}°: {s['elevation_within_10_deg']} within 10° |"),
          f"| sun read in rooms without sun | {s['false_sun']} of {s['without_sun']} |",
          f"| lamps found / ceiling lamps | {s['lamps_found']} / {s['ceiling_lamps']} |",
          (f"| lamp to the nearest true light (the fill counted), median | {s['lamp_error_m_median']:.2f} m; "
           f"{s['lamps_within_0_5_m']} within 0.5 m |"),
          "", "| case | size | key light from | sun in view | error ° | lamps: error m |", "|---|---|---|---|---|---|"]
    for r in rows:
        if "refused" in r:
            md.append(f"| {r['case']} | {r['size']} | refused: {r['refused'][:70]} | | | |")
            continue
        view = format(r["sun_in_view"], ".0%") if r["sun"] else "no sun"
        error = format(r["light_error_deg"], ".1f") if r["sun"] else ""
        md.append(f"| {r['case']} | {r['size']} | {r['source']}{' (sun read)' if r['sun_read'] else ''} | {view} | "
                  f"{error} | {', '.join(format(e, '.2f') for e in r['lamp_error_m'])} |")
    write("light", {"machine": machine(seeds=args.seeds, count=args.count), "summary": summary, "cases": rows}, md)
    print("\n".join(md[:13]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
