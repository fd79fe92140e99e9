"""Weiss et al. Table 1, side by side: PBD (Stager) against the SA-McMC baseline.

Run by hand: ``python benchmarks/table1.py [--seeds 10] [--only theater,desk]``.

Both methods start from the same random initial layouts (seed k draws start k) and
use the same energy (Eq. 1). PBD runs as in the paper: one run, no restarts. Times are
medians and maxima after JIT warm-up; the compile (or disk-cache load) is reported once.
Quality is measured exactly: box overlaps (> 1 cm²), footprint area outside the floor,
and traversability (Henderson et al., 0.25 m radius).

Writes ``benchmarks/results/table1.{json,md}`` and the energy traces of the tightly
packed picnic, both methods in one plot (the paper's Fig. 17),
``benchmarks/results/energy_trace_tp_picnic.png``.
"""
from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

import results_io

ROOT = Path(__file__).resolve().parents[1]
# name: (spec, the paper's Table 1: objects, PBD s, SA-McMC s)
SCENARIOS = {
    "theater": ("samples/theater.toml", 201, 39.50, 5852.0),
    "picnic": ("samples/picnic.toml", 77, 4.77, 253.0),
    "living_room": ("samples/living_room.toml", 10, 0.62, 27.0),
    "desk": ("samples/desk.toml", 21, 0.69, 37.0),
    "tp_bedroom": ("samples/tp_bedroom.toml", 12, 0.67, 22.0),
    "tp_picnic": ("samples/tp_picnic.toml", 53, 2.42, 109.0),
}
HEADER = ("| scenario | objects | method | median s | max s | E median | overlaps (median) | outside m² (median) "
          "| traversable | SA/PBD time | paper s |")


def run(seeds, only, trace_png):
    from layout.annealing import Annealer
    from layout.plot import plot_energy
    from layout.report import evaluate
    from layout.solver import initial_state
    from layout.spec import build, load_spec

    t0 = time.perf_counter()
    m, solver = build(load_spec(ROOT / SCENARIOS["living_room"][0]))
    dataclasses.replace(solver, restarts=0).solve(m, seed=0)
    Annealer(iterations=100).solve(m, seed=0)
    compile_s = time.perf_counter() - t0
    rows = []
    for name, (path, paper_n, paper_pbd, paper_sa) in SCENARIOS.items():
        if only and name not in only:
            continue
        model, base = build(load_spec(ROOT / path))
        methods = {"PBD": dataclasses.replace(base, restarts=0), "SA-McMC": Annealer(collision=base.collision)}
        starts = [initial_state(model, np.random.default_rng(seed)) for seed in range(seeds)]
        for method in methods.values():
            method.solve(model, seed=0, state=starts[0])  # warm-up for this model's shapes
        results = {}
        for label, method in methods.items():
            runs = [method.solve(model, seed=seed, state=starts[seed]) for seed in range(seeds)]
            evs = [evaluate(r) for r in runs]
            times = [r.time_s for r in runs]
            results[label] = runs
            rows.append(dict(
                scenario=name, objects=len(model.items), method=label,
                median_s=float(np.median(times)), max_s=float(np.max(times)),
                median_energy=float(np.median([r.energy for r in runs])),
                median_iterations=float(np.median([r.iterations for r in runs])),
                overlaps_median=float(np.median([e["overlaps"]["count"] for e in evs])),
                overlap_free=int(sum(e["overlaps"]["count"] == 0 for e in evs)),
                outside_m2_median=float(np.median([e["outside_m2"] for e in evs])),
                traversable=int(sum(e["traversable"] for e in evs)), seeds=seeds,
                paper_s=paper_pbd if label == "PBD" else paper_sa, paper_objects=paper_n,
            ))
        pbd, sa = rows[-2], rows[-1]
        ratio = sa["median_s"] / pbd["median_s"]
        pbd["ratio"] = sa["ratio"] = ratio
        print(_line(pbd), _line(sa), sep="\n", flush=True)
        if name == "tp_picnic" and trace_png:
            plot_energy(trace_png, {f"PBD ({results['PBD'][0].iterations} iterations)": results["PBD"][0].trace,
                                    f"SA-McMC ({results['SA-McMC'][0].iterations} proposals)":
                                        results["SA-McMC"][0].trace},
                        title="Tightly packed picnic, seed 0: energy per iteration", log=True)
    return compile_s, rows


def _line(r):
    return (f"| {r['scenario']} | {r['objects']} | {r['method']} | {r['median_s']:.4f} | {r['max_s']:.4f} | "
            f"{r['median_energy']:.3f} | {r['overlaps_median']:.0f} ({r['overlap_free']}/{r['seeds']} free) | "
            f"{r['outside_m2_median']:.3f} | {r['traversable']}/{r['seeds']} | "
            f"{r['ratio']:.0f}x | {r['paper_s']:g} |")


def main():
    seeds, only = results_io.scenario_args(__doc__)
    results_io.RESULTS.mkdir(parents=True, exist_ok=True)
    trace_png = results_io.RESULTS / "energy_trace_tp_picnic.png"
    t_all = time.perf_counter()
    print(HEADER)
    print("|" + "---|" * 11)
    compile_s, rows = run(seeds, only, trace_png)
    total_s = time.perf_counter() - t_all
    meta = results_io.machine(compile_or_cache_s=compile_s, total_s=total_s)
    print(f"\nJIT compile or cache load (once): {compile_s:.1f} s; whole run {total_s / 60:.1f} min")
    md = ["# Table 1 side by side: PBD vs SA-McMC (benchmarks/table1.py)", "",
          f"{meta['machine']}, {meta['cpu_count']} cores, {meta['date']}; {seeds} seeds, same starts for both.", "",
          HEADER, "|" + "---|" * 11, *[_line(r) for r in rows], "",
          f"JIT compile or cache load, once: {compile_s:.1f} s. Whole run: {total_s / 60:.1f} min.",
          "Paper s: the paper's Table 1 (mean of 10 runs, Python + Cython, 2.5 GHz i7)."]
    paths = results_io.write("table1", dict(meta=meta, rows=rows), md)
    print("wrote", *paths, trace_png)


if __name__ == "__main__":
    main()
