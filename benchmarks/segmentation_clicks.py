"""Correcting the floor with clicks: how many clicks bring a wrong floor polygon within 5 %.

Renders a held-out set (as ``segmentation.py`` does: random phone sizes, calibrated from
the board with the true focal length), segments each render, and for every calibrated
render whose floor polygon is more than 5 % off the true visible floor area, plays a
user who looks at the floor overlay and clicks the middle of the largest wrong patch:
``--floor-at`` on floor left out, ``--not-floor-at`` on something taken for floor. The
clicks accumulate, in order, up to ``--clicks`` of them, stopping once within 5 %.

    .venv/bin/python benchmarks/segmentation_clicks.py --seed 920 --count 80 [--clicks 3]

Prints a table and writes ``benchmarks/results/segmentation_clicks_seedN.{md,json}`` and
``segmentation_clicks_seedN.png`` (the corrected renders: truth against the mask before
and after, the clicks marked).

The simulated user sees the truth, which a real one sees in the photo; the middle of the
largest patch in pixels is what the eye goes to, not where a click helps most.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from augment.camera.board import Board  # noqa: E402
from augment.camera.calibrate import calibrate_photo, exif_intrinsics  # noqa: E402
from augment.errors import CalibrationError  # noqa: E402
from augment.draw.floor import floor_overlay  # noqa: E402
from augment.floor.polygon import floor_polygon  # noqa: E402
from augment.render.gl import Renderer  # noqa: E402
from augment.errors import SegmentationError  # noqa: E402
from augment.floor.model import DEFAULT_MODEL, FloorModel  # noqa: E402
from augment.floor.segment import patch_middle, segment_floor  # noqa: E402
from augment.synth import render_sample  # noqa: E402
from layout.fileio import write_atomic  # noqa: E402
from segmentation import true_visible_area_m2  # noqa: E402

OUT = ROOT / "benchmarks" / "results"
WITHIN = 0.05


def simulated_click(mask: np.ndarray, truth: np.ndarray) -> tuple[float, float, float]:
    """The middle (farthest from its edge) of the largest wrong patch, and whether it is
    floor left out (1) or something taken for floor (0)."""
    best = None
    for wrong, is_floor in ((truth & ~mask, 1.0), (mask & ~truth, 0.0)):
        n, labels, stats, _ = cv2.connectedComponentsWithStats(wrong.astype(np.uint8), connectivity=8)
        if n > 1:
            k = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
            if best is None or stats[k, cv2.CC_STAT_AREA] > best[0]:
                best = (stats[k, cv2.CC_STAT_AREA], labels == k, is_floor)
    x, y = patch_middle(best[1])
    return float(x), float(y), best[2]


def tile(image, mask, truth, clicks, label, size=(320, 240)) -> np.ndarray:
    out = image.copy()
    out[mask & ~truth] = (0.4 * out[mask & ~truth] + [150, 0, 0]).astype(np.uint8)
    out[~mask & truth] = (0.4 * out[~mask & truth] + [0, 0, 150]).astype(np.uint8)
    out[mask & truth] = (0.6 * out[mask & truth] + [0, 100, 0]).astype(np.uint8)
    out = floor_overlay(out, np.zeros_like(mask), clicks=clicks)
    out = cv2.resize(out, size, interpolation=cv2.INTER_AREA)
    cv2.putText(out, label, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=80)
    parser.add_argument("--seed", type=int, default=920, help="seed of the held-out renders")
    parser.add_argument("--clicks", type=int, default=3, help="most clicks per render (default 3)")
    parser.add_argument("--model", type=Path, default=DEFAULT_MODEL)
    args = parser.parse_args(argv)
    model = FloorModel(args.model)

    rows, pictures = [], []
    with Renderer() as renderer:
        for i in tqdm(range(args.count), desc="renders", disable=not sys.stderr.isatty()):
            sample = render_sample([args.seed, i], renderer)
            w, h = sample.truth["size_px"]
            try:
                cal = calibrate_photo(sample.image, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
            except CalibrationError:
                continue
            truth = sample.floor_mask
            truth_area = true_visible_area_m2(truth, sample.truth)
            clicks, errors, first = [], [], None
            for k in range(args.clicks + 1):
                try:
                    seg = segment_floor(sample.image, model, cal, clicks=clicks or None)
                    error = floor_polygon(seg.mask, cal, seg.floor_clicks_px).area_m2 / truth_area - 1
                except (SegmentationError, ValueError) as exc:
                    errors.append(str(exc))
                    break
                errors.append(error)
                first = seg.mask if first is None else first
                if abs(error) <= WITHIN or k == args.clicks:
                    break
                clicks.append(simulated_click(seg.mask, truth))
            rows.append({"image": i, "size": f"{w}x{h}", "errors": errors, "clicks": clicks})
            if clicks and isinstance(errors[-1], float) and abs(errors[-1]) <= WITHIN:
                pictures.append((tile(sample.image, first, truth, [], f"{args.seed}/{i} {errors[0]:+.1%}"),
                                 tile(sample.image, seg.mask, truth, clicks,
                                      f"{len(clicks)} click{'s' * (len(clicks) > 1)}: {errors[-1]:+.1%}")))

    def within_after(k):
        """Renders within 5 % once at most k clicks were made."""
        return sum(any(isinstance(e, float) and abs(e) <= WITHIN for e in r["errors"][:k + 1]) for r in rows)

    counts = {k: within_after(k) for k in range(args.clicks + 1)}
    off = [r for r in rows if isinstance(r["errors"][0], float) and abs(r["errors"][0]) > WITHIN]
    worse = [r for r in off if isinstance(r["errors"][-1], float) and abs(r["errors"][-1]) > abs(r["errors"][0])]
    lines = ["# Correcting the floor with clicks", "",
             f"model `{args.model.name}`; {args.count} renders (seed {args.seed}), {len(rows)} calibrated; "
             f"{len(off)} polygons more than 5 % off before any click", "",
             "| clicks at most | polygons within 5 % |", "|---|---|"]
    lines += [f"| {k} | {counts[k]} of {len(rows)} |" for k in counts]
    lines += ["", f"left further off than before the clicks: {len(worse)} of {len(off)}", "",
              "| render | size | area error after each click | clicks (x, y, floor) |", "|---|---|---|---|"]
    for r in off:
        trail = " → ".join(f"{e:+.1%}" if isinstance(e, float) else f"error: {e}" for e in r["errors"])
        marks = "; ".join(f"{x:.0f},{y:.0f} {'floor' if f else 'not floor'}" for x, y, f in r["clicks"])
        lines.append(f"| {r['image']} | {r['size']} | {trail} | {marks} |")
    text = "\n".join(lines) + "\n"
    print(text)
    OUT.mkdir(parents=True, exist_ok=True)
    stem = f"segmentation_clicks_seed{args.seed}"
    write_atomic(OUT / f"{stem}.md", text)
    write_atomic(OUT / f"{stem}.json", json.dumps({"counts": counts, "renders": rows}, indent=1))
    if pictures:
        sheet = np.vstack([np.hstack(pair) for pair in pictures[:6]])
        write_atomic(OUT / f"{stem}.png", cv2.imencode(".png", sheet[..., ::-1])[1].tobytes())
    return 0


if __name__ == "__main__":
    sys.exit(main())
