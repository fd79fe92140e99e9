"""The paper's scenarios, 10 seeds each: quality and speed of the PBD solver.

Run by hand: ``python benchmarks/scenarios.py [--seeds 10] [--only theater,desk]``.
Prints a table per solver mode and writes ``benchmarks/results/scenarios.{json,md}``.

Modes:
  paper   one run per seed, as in Weiss et al. (restarts=0), exact box collisions
  sphere  the same with the paper's bounding-sphere collisions
  default Stager's defaults: up to 20 fresh restarts when a run's best layout still
          collides, leaves the floor, is not walkable or has an item more than 10 cm
          inside another's clearance (the time covers all runs)

"clean" = zero exact box overlaps (> 1 cm²), nothing outside the floor, and walkable
(Henderson et al.'s traversability: 0.25 m radius, every door and access side
connected). "clear" = no item more than 10 cm (``ACCESS_CLEAR_M``) inside another's
clearance. Times are medians after JIT warm-up; compile time is reported once.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

import results_io

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = {
    # name: (spec, objects in the paper, paper's time in s (Table 1, Python + Cython))
    "theater": ("samples/theater.toml", 201, 39.50),
    "picnic": ("samples/picnic.toml", 77, 4.77),
    "living_room": ("samples/living_room.toml", 10, 0.62),
    "desk": ("samples/desk.toml", 21, 0.69),
    "tp_bedroom": ("samples/tp_bedroom.toml", 12, 0.67),
    "tp_picnic": ("samples/tp_picnic.toml", 53, 2.42),
}
MODES = {"paper": dict(restarts=0), "sphere": dict(restarts=0, collision="sphere"), "default": {}}


def run(seeds, only):
    from layout.report import evaluate
    from layout.solver import ACCESS_CLEAR_M
    from layout.spec import build, load_spec

    t0 = time.perf_counter()
    m, solver = build(load_spec(ROOT / SCENARIOS["living_room"][0]))
    solver.solve(m, seed=0)
    compile_s = time.perf_counter() - t0
    rows = []
    for name, (path, paper_n, paper_s) in SCENARIOS.items():
        if only and name not in only:
            continue
        model, base = build(load_spec(ROOT / path))
        for mode, overrides in MODES.items():
            solver = dataclasses.replace(base, **overrides)
            solver.solve(model, seed=0)  # warm-up: JIT for this model's shapes
            times, energies, iters, runs, clean = [], [], [], [], []
            overlaps = outside = walkable = clear = 0
            for seed in range(seeds):
                layout = solver.solve(model, seed=seed)
                ev = evaluate(layout)
                times.append(layout.time_s)
                energies.append(layout.energy)
                iters.append(layout.iterations)
                runs.append(layout.runs)
                overlaps += ev["overlaps"]["count"] == 0
                outside += ev["outside_m2"] == 0.0
                walkable += ev["traversable"]
                clear += ev["clearances"]["deepest_m"] <= ACCESS_CLEAR_M
                clean.append(ev["overlaps"]["count"] == 0 and ev["outside_m2"] == 0.0 and ev["traversable"])
            rows.append(dict(
                scenario=name, mode=mode, objects=len(model.items), paper_objects=paper_n,
                median_ms=1e3 * float(np.median(times)), max_ms=1e3 * float(np.max(times)),
                paper_s=paper_s, speedup=paper_s / float(np.median(times)),
                median_energy=float(np.median(energies)), median_iterations=float(np.median(iters)),
                mean_runs=float(np.mean(runs)), no_overlap=overlaps, inside=outside, walkable=walkable,
                clean=int(sum(clean)), clear=clear, seeds=seeds,
            ))
            print(_line(rows[-1]), flush=True)
    return compile_s, rows


HEADER = ("| scenario | mode | objects | median ms | max ms | paper s | x faster | E median | "
          "iterations | runs | no overlap | inside | walkable | clean | clear |")


def _line(r):
    return (f"| {r['scenario']} | {r['mode']} | {r['objects']} | {r['median_ms']:.1f} | {r['max_ms']:.1f} | "
            f"{r['paper_s']:.2f} | {r['speedup']:.0f} | {r['median_energy']:.3f} | {r['median_iterations']:.0f} | "
            f"{r['mean_runs']:.1f} | {r['no_overlap']}/{r['seeds']} | {r['inside']}/{r['seeds']} | "
            f"{r['walkable']}/{r['seeds']} | {r['clean']}/{r['seeds']} | {r['clear']}/{r['seeds']} |")


def main():
    seeds, only = results_io.scenario_args(__doc__)
    print(HEADER)
    print("|" + "---|" * 15)
    compile_s, rows = run(seeds, only)
    print(f"\nfirst solve in a fresh process (JIT compile or cache load): {compile_s:.1f} s")
    meta = results_io.machine(compile_or_cache_s=compile_s)
    md = ["# Paper scenarios, 10 seeds (benchmarks/scenarios.py)", "", f"{meta['machine']}, {meta['date']}", "",
          HEADER, "|" + "---|" * 15, *[_line(r) for r in rows], "",
          f"First solve in a fresh process: {compile_s:.1f} s (JIT compile, or loading numba's disk cache)."]
    paths = results_io.write("scenarios", dict(meta=meta, rows=rows), md)
    print("wrote", *paths)


if __name__ == "__main__":
    main()
