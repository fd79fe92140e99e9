"""The furnishing presets in three rooms: how often the solver's suggestion is usable.

Run by hand: ``python benchmarks/presets.py [--seeds 30] [--only bedroom,office]``.
Prints a table and writes ``benchmarks/results/presets.{json,md}``.

Each preset (``layout.presets``, what ``stage furnish`` lays out) is solved in a small
(3 x 3.2 m), a middle (4.5 x 4 m) and a large room (6 x 5 m), each with a door, with
Stager's default solver, twice in one run for a side-by-side comparison:

  before  restarts only when a run collides, leaves the floor or is not walkable
          (``ACCESS_CLEAR_M`` set to infinity: the solver before clearances counted)
  default restarts also when an item stands more than 10 cm inside another's clearance

"clean" = no overlap, nothing off the floor, walkable; "clear" = no item more than
``ACCESS_CLEAR_M`` inside another's clearance; "worst" = the deepest such intrusion over
the seeds (m). Times are medians per suggestion after JIT warm-up, all runs included.
``results/presets_example.png``: the first seed whose suggestion was not clear before
and is now, the two plans side by side.
"""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

import results_io

ROOMS = {"small": (3.0, 3.2), "middle": (4.5, 4.0), "large": (6.0, 5.0)}
PRESETS = ("living_room", "bedroom", "dining_room", "office", "game_room")


def run(seeds, only):
    import layout.solver as solver_module
    from layout.report import evaluate
    from layout.spec import build, load_spec

    clear_m = solver_module.ACCESS_CLEAR_M
    rows, example = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for preset in PRESETS:
            if only and preset not in only:
                continue
            for room, (w, d) in ROOMS.items():
                path = Path(tmp) / f"{preset}_{room}.toml"
                path.write_text(f'[room]\npolygon = [[0, 0], [{w}, 0], [{w}, {d}], [0, {d}]]\nheight = 2.5\n'
                                f'preset = "{preset}"\ndoors = [{{ at = [1.0, 0.0], width = 0.8 }}]\n')
                model, solver = build(load_spec(path))
                blocked = {}
                for mode, limit in (("before", math.inf), ("default", clear_m)):
                    solver_module.ACCESS_CLEAR_M = limit
                    solver.solve(model, seed=0)  # warm-up: JIT for this model's shapes
                    times, runs, deepest, clean = [], [], [], 0
                    for seed in range(seeds):
                        layout = solver.solve(model, seed=seed)
                        ev = evaluate(layout)
                        times.append(layout.time_s)
                        runs.append(layout.runs)
                        deepest.append(ev["clearances"]["deepest_m"])
                        if mode == "before" and deepest[-1] > clear_m:
                            blocked[seed] = layout
                        elif example is None and seed in blocked and deepest[-1] <= clear_m:
                            example = _side_by_side([blocked[seed], layout], f"{preset}, {room} room, seed {seed}: ")
                        clean += ev["overlaps"]["count"] == 0 and ev["outside_m2"] == 0.0 and ev["traversable"]
                    deepest = np.array(deepest)
                    rows.append(dict(preset=preset, room=room, mode=mode, items=len(model.items), seeds=seeds,
                                     clean=int(clean), clear=int((deepest <= clear_m).sum()),
                                     worst_m=float(deepest.max()), mean_runs=float(np.mean(runs)),
                                     median_ms=1e3 * float(np.median(times)), max_ms=1e3 * float(np.max(times))))
                    print(_line(rows[-1]), flush=True)
    solver_module.ACCESS_CLEAR_M = clear_m
    return rows, example


def _side_by_side(layouts, title):
    """The plans of ``layouts`` (before, now) in one RGB image."""
    import cv2

    from layout.report import output_files

    plans = []
    for lay, when in zip(layouts, ("before", "now")):
        png = output_files([lay], title=f"{title}{when}, ")["plan_1.png"]
        plans.append(cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR))
    rows = min(p.shape[0] for p in plans)
    return np.hstack([p[:rows] for p in plans])


HEADER = "| preset | room | mode | items | clean | clear | worst m | runs | median ms | max ms |"


def _line(r):
    return (f"| {r['preset']} | {r['room']} | {r['mode']} | {r['items']} | {r['clean']}/{r['seeds']} | "
            f"{r['clear']}/{r['seeds']} | {r['worst_m']:.2f} | {r['mean_runs']:.1f} | {r['median_ms']:.1f} | "
            f"{r['max_ms']:.1f} |")


def _totals(rows):
    lines = []
    for mode in ("before", "default"):
        sel = [r for r in rows if r["mode"] == mode]
        n = sum(r["seeds"] for r in sel)
        lines.append(f"{mode}: clean {sum(r['clean'] for r in sel)}/{n}, clear {sum(r['clear'] for r in sel)}/{n}, "
                     f"median of the rooms' median times {np.median([r['median_ms'] for r in sel]):.1f} ms")
    return lines


def main():
    seeds, only = results_io.scenario_args(__doc__)
    print(HEADER)
    print("|" + "---|" * 10)
    rows, example = run(seeds, only)
    totals = _totals(rows)
    print("", *totals, sep="\n")
    meta = results_io.machine()
    md = [f"# Presets in three rooms, {seeds} seeds (benchmarks/presets.py)", "",
          f"{meta['machine']}, {meta['date']}", "", HEADER, "|" + "---|" * 10, *[_line(r) for r in rows], "",
          *totals]
    paths = results_io.write("presets", dict(meta=meta, rows=rows), md)
    if example is not None:
        import cv2

        from layout.fileio import write_atomic

        ok, png = cv2.imencode(".png", example)
        paths += (results_io.RESULTS / "presets_example.png",)
        write_atomic(paths[-1], png.tobytes())
    print("wrote", *paths)


if __name__ == "__main__":
    main()
