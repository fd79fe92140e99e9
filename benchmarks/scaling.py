"""How PBD solve time grows with the number of items.

Run by hand: ``python benchmarks/scaling.py [--sizes 100,300,1000,3000,10000] [--seeds 3]``.

Two scenes from ``benchmarks/scenes.py``: theater seats in rows (curve groups with
equal spacing, every seat facing the stage) and a large, tightly packed floor of
random boxes with clearances. Prints the median time per solve and per iteration for
each size, fits the growth exponent (slope of log time against log n, least squares),
and writes ``benchmarks/results/scaling.{json,md,png}`` (a log-log plot).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402
from layout.fileio import atomic_path  # noqa: E402
import scenes  # noqa: E402

HEADER = "| scene | items | median s per solve | median ms per iteration | iterations | E median |"


def run(sizes, seeds):
    from layout import Solver

    solver = Solver(restarts=0)
    solver.solve(scenes.theater(100), seed=0)
    solver.solve(scenes.packed(100), seed=0)
    # Large floors take the two-thread kernels: warm those up too.
    solver.solve(scenes.packed(solver.threads_from), seed=0)
    rows = []
    for scene in ("theater", "packed"):
        for n in sizes:
            model = getattr(scenes, scene)(n)
            runs = [solver.solve(model, seed=s) for s in range(seeds)]
            t = np.array([r.time_s for r in runs])
            it = np.array([r.iterations for r in runs])
            rows.append(dict(scene=scene, items=len(model.items), median_s=float(np.median(t)),
                             median_ms_per_iteration=float(np.median(1e3 * t / it)),
                             median_iterations=float(np.median(it)),
                             median_energy=float(np.median([r.energy for r in runs]))))
            print(_line(rows[-1]), flush=True)
    return rows


def _line(r):
    return (f"| {r['scene']} | {r['items']} | {r['median_s']:.3f} | {r['median_ms_per_iteration']:.3f} | "
            f"{r['median_iterations']:.0f} | {r['median_energy']:.3f} |")


def exponents(rows):
    fits = {}
    for scene in sorted({r["scene"] for r in rows}):
        sel = [r for r in rows if r["scene"] == scene]
        n = np.log([r["items"] for r in sel])
        fits[scene] = dict(
            solve=float(np.polyfit(n, np.log([r["median_s"] for r in sel]), 1)[0]),
            iteration=float(np.polyfit(n, np.log([r["median_ms_per_iteration"] for r in sel]), 1)[0]),
        )
    return fits


def plot(rows, fits, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=120)
    for scene, marker in (("theater", "o"), ("packed", "s")):
        sel = [r for r in rows if r["scene"] == scene]
        n = [r["items"] for r in sel]
        ax.loglog(n, [r["median_s"] for r in sel], marker + "-",
                  label=f"{scene}: per solve (slope {fits[scene]['solve']:.2f})")
        ax.loglog(n, [r["median_ms_per_iteration"] / 1e3 for r in sel], marker + "--",
                  label=f"{scene}: per iteration (slope {fits[scene]['iteration']:.2f})")
    ref = np.array([min(r["items"] for r in rows), max(r["items"] for r in rows)], float)
    ax.loglog(ref, 2.0 * ref / ref[-1], ":", color="gray", label="linear, 2 s at the largest n")
    ax.set_xlabel("items")
    ax.set_ylabel("seconds (median)")
    ax.set_title("PBD solve time against the number of items")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="100,300,1000,3000,10000")
    parser.add_argument("--seeds", type=int, default=3)
    args = parser.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    print(HEADER)
    print("|" + "---|" * 6)
    rows = run(sizes, args.seeds)
    fits = exponents(rows)
    for scene, f in fits.items():
        print(f"{scene}: growth exponent per solve {f['solve']:.2f}, per iteration {f['iteration']:.2f}")
    meta = results_io.machine(seeds=args.seeds)
    md = ["# Scaling of the PBD solver (benchmarks/scaling.py)", "",
          f"{meta['machine']}, {meta['cpu_count']} cores, {meta['date']}; median of {args.seeds} seeds.", "",
          HEADER, "|" + "---|" * 6, *[_line(r) for r in rows], "",
          *[f"- {s}: growth exponent per solve {f['solve']:.2f}, per iteration {f['iteration']:.2f}"
            for s, f in fits.items()], "", "![log-log plot](scaling.png)"]
    paths = results_io.write("scaling", dict(meta=meta, rows=rows, exponents=fits), md)
    plot(rows, fits, results_io.RESULTS / "scaling.png")
    print("wrote", *paths, results_io.RESULTS / "scaling.png")


if __name__ == "__main__":
    main()
