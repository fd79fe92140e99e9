"""The floor step's speed alone, the shipped model beside another, side by side in one run.

    .venv/bin/python benchmarks/segmentation_speed.py [--other OLD.onnx] [--repeats 9]

The same render as ``segmentation.py``'s speed line ([901, 1000] at 1008x756, and scaled
to 4032x3024 for the whole step); medians, the two models alternating so that the
machine's load falls on both alike. Writes ``results/segmentation_speed.{json,md}``.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
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
    args = parser.parse_args(argv)
    models = {"shipped": FloorModel(DEFAULT_MODEL)}
    if args.other is not None:
        models["other"] = FloorModel(args.other)
    with Renderer() as renderer:
        sample = render_sample([901, 1000], renderer, size_px=(1008, 756))
    big = cv2.resize(sample.image, (4032, 3024), interpolation=cv2.INTER_CUBIC)
    cal = calibrate_photo(big, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0] * 4, (4032, 3024)))
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
    rows = {name: {"inputs": "+".join(f"{c}x{r}" for r, c in models[name].input_shapes(756, 1008)),
                   "model_ms": 1000 * float(np.median(t["model"])), "step_12mp_s": float(np.median(t["step"]))}
            for name, t in times.items()}
    lines = ["# Floor step speed", "", f"medians of {args.repeats}, models alternating; 2-core machine", "",
             "| model | inputs | model alone, 1008x756 | whole step, 12 MP |", "|---|---|---|---|"]
    lines += [f"| {name} | {r['inputs']} | {r['model_ms']:.1f} ms | {r['step_12mp_s']:.2f} s |" for name, r in rows.items()]
    text = "\n".join(lines) + "\n"
    print(text)
    write_atomic(OUT / "segmentation_speed.md", text)
    write_atomic(OUT / "segmentation_speed.json", json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
