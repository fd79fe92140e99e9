"""Paired segmentation runs: render held-out rooms once, then score any version of the
code on the very same photos, and list the renders a change moves.

Counts of polygons within 5 % move by 1 or 2 per set from one rendering to the next
(GrabCut's start moves with a pixel), so a change is judged on the same renders as the
code before it. Three steps::

    .venv/bin/python benchmarks/segmentation_paired.py render --seeds 930 931 --cache data/paired
    .venv/bin/python benchmarks/segmentation_paired.py score --cache data/paired --out before.json
    # ... change the code (or check out another revision) ...
    .venv/bin/python benchmarks/segmentation_paired.py score --cache data/paired --out after.json
    .venv/bin/python benchmarks/segmentation_paired.py compare before.json after.json

``score --follow-doubt N`` also plays a user who looks at the spot the warnings ring
(``Segmentation.doubt_px``: where the model and GrabCut disagree most, or a skirting board
may be left) and, where the mask is wrong there, clicks: ``--floor-at`` or
``--not-floor-at`` as the truth says; then looks at the new ring, up to N clicks.

``render`` keeps, per render, the photo (PNG), its true floor mask, the true visible
floor area (as ``benchmarks/segmentation.py`` measures it) and the truth, under
``--cache``; ``--tall`` draws the boards 12-20 cm tall, ``--hue`` paints every room's
trim the floor's colour, ``--stress NAME`` renders one of ``segmentation.py``'s stress
cases (use seeds other than its held-out ones to work on a change). ``score`` calibrates
each photo from its board with the true focal length and runs the whole segmentation and the floor
polygon with the code as it is now; a render it cannot calibrate or outline counts as
failed, so a change to the calibration shows too. ``compare`` prints both counts and
every render that crosses 5 %, moves by more than a point, or fails on one side only.
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
from augment.floor.polygon import floor_polygon  # noqa: E402
from augment.floor.model import DEFAULT_MODEL, FloorModel  # noqa: E402
from augment.floor.segment import segment_floor  # noqa: E402
from layout.fileio import write_atomic  # noqa: E402
from segmentation import STRESS, iou, true_visible_area_m2  # noqa: E402

TALL_BASEBOARD_M = (0.12, 0.20)


def render(seeds: list[int], count: int, cache: Path, tall: bool, hue: bool = False, stress: str | None = None) -> None:
    from augment.render.gl import Renderer
    from augment.synth import render_sample

    cache.mkdir(parents=True, exist_ok=True)
    with Renderer() as renderer:
        for seed in seeds:
            for i in tqdm(range(count), desc=f"seed {seed}", disable=not sys.stderr.isatty()):
                extra = {"baseboard_m": TALL_BASEBOARD_M} if tall else {}
                if hue:
                    extra["trim_like_floor"] = 1.0
                extra.update(STRESS.get(stress, {}))
                sample = render_sample([seed, i], renderer, **extra)
                stem = cache / f"{seed}_{i}"
                write_atomic(stem.with_suffix(".png"), cv2.imencode(".png", sample.image[..., ::-1])[1].tobytes())
                write_atomic(stem.with_name(stem.name + "_floor.png"),
                             cv2.imencode(".png", sample.floor_mask.astype(np.uint8) * 255)[1].tobytes())
                write_atomic(stem.with_suffix(".json"), json.dumps(
                    {"true_area_m2": true_visible_area_m2(sample.floor_mask, sample.truth), "truth": sample.truth}))


def score(cache: Path, out: Path, follow_doubt: int = 0) -> None:
    model = FloorModel(DEFAULT_MODEL)
    rows = {}
    photos = sorted(p for p in cache.glob("*.png") if not p.stem.endswith("_floor"))
    for photo in tqdm(photos, desc="renders", disable=not sys.stderr.isatty()):
        meta = json.loads(photo.with_suffix(".json").read_text())
        image = cv2.imread(str(photo))[..., ::-1].copy()
        truth = cv2.imread(str(photo.with_name(photo.stem + "_floor.png")), cv2.IMREAD_GRAYSCALE) > 127
        w, h = meta["truth"]["size_px"]
        row = {}
        try:
            cal = calibrate_photo(image, Board(), intrinsics=exif_intrinsics(meta["truth"]["K"][0][0], (w, h)))
            seg = segment_floor(image, model, cal)
            row["iou"] = iou(seg.mask, truth)
            row["area_error"] = floor_polygon(seg.mask, cal).area_m2 / meta["true_area_m2"] - 1
            if follow_doubt and seg.doubt_px is not None:
                row["doubt"] = "floor" if seg.uncertain else "board"
            clicks = []
            # A user who looks where the ring is and clicks there where the mask is wrong,
            # then looks again, up to ``follow_doubt`` clicks.
            while len(clicks) < follow_doubt and seg.doubt_px is not None:
                x, y = seg.doubt_px
                if seg.mask[y, x] == truth[y, x] or (x, y) in [c[:2] for c in clicks]:
                    break
                clicks.append((x, y, float(truth[y, x])))
                seg = segment_floor(image, model, cal, clicks=clicks)
                row["area_error_clicked"] = floor_polygon(seg.mask, cal).area_m2 / meta["true_area_m2"] - 1
                row["clicks"] = len(clicks)
        except (CalibrationError, ValueError) as error:
            row["failed"] = str(error)
        rows[photo.stem] = row
    write_atomic(out, json.dumps(rows, indent=1))
    print(summary(rows))
    if follow_doubt:
        print(doubt_summary(rows))


def summary(rows: dict) -> str:
    errors = [r["area_error"] for r in rows.values() if "area_error" in r]
    inside = sum(abs(e) <= 0.05 for e in errors)
    failed = sum("failed" in r for r in rows.values())
    return (f"{inside} of {len(errors)} polygons within 5 %, mean |error| {100 * np.mean(np.abs(errors)):.2f} %, "
            f"mean IoU {np.mean([r['iou'] for r in rows.values() if 'iou' in r]):.4f}; {failed} failed")


def doubt_summary(rows: dict) -> str:
    """What the rings (``Segmentation.doubt_px``) are worth to a user who follows them."""
    lines = []
    for kind in ("floor", "board"):
        ringed = [r for r in rows.values() if r.get("doubt") == kind]
        wrong = [r for r in ringed if "area_error_clicked" in r]
        before = sum(abs(r["area_error"]) <= 0.05 for r in wrong)
        after = sum(abs(r["area_error_clicked"]) <= 0.05 for r in wrong)
        clicks = sum(r["clicks"] for r in wrong)
        lines.append(f"{kind} ringed in {len(ringed)}; the mask wrong at the ring in {len(wrong)}, of those "
                     f"{before} within 5 % as found, {after} after following the rings ({clicks} clicks)")
    errors = [r.get("area_error_clicked", r["area_error"]) for r in rows.values() if "area_error" in r]
    lines.append(f"{sum(abs(e) <= 0.05 for e in errors)} of {len(errors)} within 5 % with those clicks")
    return "\n".join(lines)


def compare(before_path: Path, after_path: Path) -> None:
    before, after = (json.loads(p.read_text()) for p in (before_path, after_path))
    print(f"before: {summary(before)}\nafter:  {summary(after)}")
    for name in sorted(before.keys() & after.keys()):
        a, b = before[name].get("area_error"), after[name].get("area_error")
        if a is None or b is None:
            if (a is None) != (b is None):
                print(f"{name:>10}  {before[name].get('failed', a)} -> {after[name].get('failed', b)}")
            continue
        crossed = (abs(a) <= 0.05) != (abs(b) <= 0.05)
        if crossed or abs(a - b) > 0.01:
            tag = ("in" if abs(b) <= 0.05 else "out") if crossed else ""
            print(f"{name:>10}  {100 * a:+6.1f} % -> {100 * b:+6.1f} %  {tag}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    verbs = parser.add_subparsers(dest="verb", required=True)
    r = verbs.add_parser("render", help="render and keep held-out rooms")
    r.add_argument("--seeds", type=int, nargs="+", required=True)
    r.add_argument("--count", type=int, default=80)
    r.add_argument("--tall", action="store_true", help="boards 12-20 cm tall")
    r.add_argument("--hue", action="store_true", help="trim painted the floor's colour")
    r.add_argument("--stress", choices=sorted(STRESS), default=None, help="one of segmentation.py's stress cases")
    r.add_argument("--cache", type=Path, default=ROOT / "data" / "paired")
    s = verbs.add_parser("score", help="segment the kept renders with the code as it is now")
    s.add_argument("--cache", type=Path, default=ROOT / "data" / "paired")
    s.add_argument("--out", type=Path, required=True)
    s.add_argument("--follow-doubt", type=int, default=0, metavar="N",
                   help="also play a user who clicks at the ringed spot where the mask is wrong there, "
                        "and looks again, up to N clicks")
    c = verbs.add_parser("compare", help="the renders two scores disagree on")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    args = parser.parse_args(argv)
    if args.verb == "render":
        render(args.seeds, args.count, args.cache, args.tall, args.hue, args.stress)
    elif args.verb == "score":
        score(args.cache, args.out, args.follow_doubt)
    else:
        compare(args.before, args.after)
    return 0


if __name__ == "__main__":
    sys.exit(main())
