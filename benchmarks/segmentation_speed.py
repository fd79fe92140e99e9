"""The floor step's speed alone, the shipped model beside another, side by side in one run.

    .venv/bin/python benchmarks/segmentation_speed.py [--other OLD.onnx] [--old REV] [--repeats 9]

The same render as ``segmentation.py``'s speed line ([901, 1000] at 1008x756, and scaled
to 4032x3024 for the whole step); medians, the two models alternating so that the
machine's load falls on both alike. ``--old REV`` also times the whole step of another
revision of the code (a git worktree, in its own processes, rounds alternating with
this tree's). Writes ``results/segmentation_speed.{json,md}``.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if "--step-only" not in sys.argv:  # then the code timed comes from PYTHONPATH (this tree or an old one)
    sys.path.insert(0, str(ROOT))

from augment.camera.board import Board  # noqa: E402
from augment.camera.calibrate import calibrate_photo, exif_intrinsics  # noqa: E402
from augment.floor.model import DEFAULT_MODEL, FloorModel  # noqa: E402
from augment.floor.segment import segment_floor  # noqa: E402
from augment.render.gl import Renderer  # noqa: E402
from augment.synth import render_sample  # noqa: E402
from layout.fileio import write_atomic  # noqa: E402

OUT = ROOT / "benchmarks" / "results"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--other", type=Path, default=None, help="a second model (with its JSON) to time beside")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--old", help="a git revision whose whole step is timed beside this tree's")
    parser.add_argument("--step-only", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.step_only:
        print(json.dumps(_step_times(FloorModel(DEFAULT_MODEL), args.step_only)))
        return 0
    models = {"shipped": FloorModel(DEFAULT_MODEL)}
    if args.other is not None:
        models["other"] = FloorModel(args.other)
    sample, big, cal = _sample()
    by_code = _side_by_side(args.old, args.repeats) if args.old else None
    times = {name: {"model": [], "step": []} for name in models}
    for name, model in models.items():  # warm up
        model.floor_probability(sample.image)
        segment_floor(big, model, cal)
    for _ in range(args.repeats):
        for name, model in models.items():
            start = time.perf_counter()
            model.floor_probability(sample.image)
            times[name]["model"].append(time.perf_counter() - start)
            start = time.perf_counter()
            segment_floor(big, model, cal)
            times[name]["step"].append(time.perf_counter() - start)
    rows = {name: {"inputs": models[name].inputs_label(756, 1008),
                   "model_ms": 1000 * float(np.median(t["model"])), "step_12mp_s": float(np.median(t["step"]))}
            for name, t in times.items()}
    lines = ["# Floor step speed", "", f"medians of {args.repeats}, models alternating; 2-core machine", "",
             "| model | inputs | model alone, 1008x756 | whole step, 12 MP |", "|---|---|---|---|"]
    lines += [f"| {name} | {r['inputs']} | {r['model_ms']:.1f} ms | {r['step_12mp_s']:.2f} s |"
              for name, r in rows.items()]
    if by_code is not None:
        rows["code"] = by_code
        lines += ["", f"Whole step, 12 MP, shipped model, this tree beside `{args.old}`: rounds of "
                  f"{args.repeats} in fresh processes, alternating, {len(by_code['this'])} timings each", "",
                  "| code | median | ratio |", "|---|---|---|",
                  f"| this tree | {np.median(by_code['this']):.3f} s | "
                  f"{np.median(by_code['this']) / np.median(by_code['old']):.2f} |",
                  f"| {args.old} | {np.median(by_code['old']):.3f} s | 1 |"]
    text = "\n".join(lines) + "\n"
    print(text)
    write_atomic(OUT / "segmentation_speed.md", text)
    write_atomic(OUT / "segmentation_speed.json", json.dumps(rows, indent=1))
    return 0


def _sample():
    with Renderer() as renderer:
        sample = render_sample([901, 1000], renderer, size_px=(1008, 756))
    big = cv2.resize(sample.image, (4032, 3024), interpolation=cv2.INTER_CUBIC)
    return sample, big, calibrate_photo(big, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0] * 4,
                                                                                   (4032, 3024)))


def _step_times(model, repeats):
    """The whole step's times on the 12 MP photo, after one warm-up."""
    _, big, cal = _sample()
    segment_floor(big, model, cal)
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        segment_floor(big, model, cal)
        out.append(time.perf_counter() - start)
    return out


def _side_by_side(old, repeats, rounds=3):
    """Whole-step times of this tree and of revision ``old``, each round in a fresh process."""
    times = {"this": [], "old": []}
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "old"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(tree), old], check=True)
        try:
            for _ in range(rounds):
                for name, root in (("old", tree), ("this", ROOT)):
                    run = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--step-only", str(repeats)],
                                         cwd=root, env={**os.environ, "PYTHONPATH": str(root)},
                                         capture_output=True, text=True, check=True)
                    times[name] += json.loads(run.stdout.strip().splitlines()[-1])
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=False)
    return times


if __name__ == "__main__":
    sys.exit(main())
