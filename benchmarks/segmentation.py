"""Floor segmentation: accuracy on unseen synthetic rooms and on real photos, and speed.

Prints tables and writes ``benchmarks/results/segmentation.{json,md}`` plus pictures:
``segmentation_synth_worst.png`` (the worst held-out renders, model + GrabCut) and
``segmentation_real_masks.png`` (real rooms: truth vs prediction as colours only - the
photos' licence allows measuring, not copying them).

    .venv/bin/python benchmarks/segmentation.py [--count 40] [--seed 901] [--real ../shared/data/real-rooms-dev]
    .venv/bin/python benchmarks/segmentation.py --stress sun --seed 980 --count 40

``--stress`` renders one of the hard cases of real empty rooms on purpose (:data:`STRESS`):
a low, strong sun through a window onto the floor in view; a second floor material past a
threshold (``far_strip``: that floor a strip along a wall, mostly the far one); tall light
or dark baseboards. Its results go to
``segmentation_STRESS_seedN.{json,md}`` and ``segmentation_STRESS_seedN_worst.png``.

Held-out renders use seed 901 (training used 100-103, validation 900), random phone
sizes and orientations; ``--seed`` picks another set, whose results go to
``segmentation_seedN.{json,md}`` and ``segmentation_seedN_worst.png`` beside seed 901's.
Each is calibrated from its board with the true focal length (the floor's accuracy is
measured here, the focal estimate in calibration.py); a render whose board is not found
is segmented without calibration and counted.

The floor polygon is compared with the true visible floor area: the ground-truth mask,
holes filled, integrated over the floor through the true camera. The polygon outlined
from the true mask itself, through the board's calibration, is reported beside it: the
part of the error that segmentation cannot remove (a floor split in two by something
standing on it, of which the polygon outlines one part; the board's pose).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
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
from augment.render.gl import Renderer  # noqa: E402
from augment.floor.segment import segment_floor  # noqa: E402
from augment.floor.model import DEFAULT_MODEL, FloorModel
from augment.floor.settings import FLOOR  # noqa: E402
from augment.synth import render_sample  # noqa: E402
from layout.fileio import write_atomic  # noqa: E402

OUT = ROOT / "benchmarks" / "results"
# The stress sets: render_sample's options for each hard case of real empty rooms.
STRESS = {
    "sun": dict(low_sun=1.0),
    "threshold": dict(two_floors=1.0),
    "far_strip": dict(two_floors=1.0, far_floor=1.0),
    "baseboards": dict(baseboard_m=(0.06, 0.2), trim_dark=0.5),
}


def iou(pred, truth, ignore=None):
    keep = np.ones(truth.shape, bool) if ignore is None else ~ignore
    union = np.logical_or(pred, truth)[keep].sum()
    return float(np.logical_and(pred, truth)[keep].sum() / union) if union else 1.0


def true_visible_area_m2(truth_mask, truth) -> float:
    """Area of the hole-filled truth floor region, through the true camera, out to the
    same distance the polygon believes."""
    K = np.array(truth["K"])
    camera_from_world = np.array(truth["camera_from_world"])
    image_from_floor = K @ camera_from_world[:3][:, [0, 1, 3]]
    filled = truth_mask.astype(np.uint8)
    contours, _ = cv2.findContours(filled, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(filled, contours, -1, 1, -1)
    y, x = np.nonzero(filled)
    H = np.linalg.inv(image_from_floor)
    pts = np.column_stack([x, y, np.ones(len(x))]) @ H.T
    w = pts[:, 2]
    floor = pts[:, :2] / w[:, None]
    cam = np.linalg.inv(camera_from_world)[:2, 3]
    near = np.hypot(*(floor - cam).T) <= FLOOR.segment.max_floor_distance_m
    return float(np.abs(np.linalg.det(H) / w[near] ** 3).sum())


def pair_picture(rows: list[tuple[str, np.ndarray, np.ndarray, np.ndarray | None]], cell=(320, 240)) -> np.ndarray:
    """Tiles: green = both say floor, red = predicted only, blue = missed, grey = ignored."""
    tiles = []
    for name, pred, truth, ignore in rows:
        tile = np.full((*pred.shape, 3), 235, np.uint8)
        tile[pred & truth] = (60, 170, 80)
        tile[pred & ~truth] = (220, 60, 50)
        tile[~pred & truth] = (50, 90, 220)
        if ignore is not None:
            tile[ignore] = (150, 150, 150)
        tile = cv2.resize(tile, cell, interpolation=cv2.INTER_NEAREST)
        cv2.putText(tile, name[:34], (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
        tiles.append(tile)
    while len(tiles) % 3:
        tiles.append(np.full((cell[1], cell[0], 3), 255, np.uint8))
    return np.vstack([np.hstack(tiles[i:i + 3]) for i in range(0, len(tiles), 3)])


def synthetic(args, model):
    rows, worst = [], []
    with Renderer() as renderer:
        for i in tqdm(range(args.count), desc="held-out renders", disable=not sys.stderr.isatty()):
            size = None if args.size is None else tuple(args.size)
            sample = render_sample([args.seed, i], renderer, size_px=size, **STRESS.get(args.stress, {}))
            w, h = sample.truth["size_px"]
            try:
                cal = calibrate_photo(sample.image, Board(),
                                      intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
            except CalibrationError:
                cal = None
            row = {"image": i, "size": f"{w}x{h}", "calibrated": cal is not None,
                   "sun": any(light.get("low") for light in sample.truth["render"]["lights"]),
                   "second_floor": sample.truth["render"].get("second_floor") is not None}
            for name, kwargs in (("onnx", dict(model=model, refine=False)), ("onnx+grabcut", dict(model=model)),
                                 ("grabcut", dict(method="grabcut"))):
                if name == "grabcut" and cal is None:
                    row[name] = None
                    continue
                start = time.perf_counter()
                seg = segment_floor(sample.image, calibration=cal, **kwargs)
                row[f"{name}_s"] = time.perf_counter() - start
                row[name] = iou(seg.mask, sample.floor_mask)
                if name == "onnx+grabcut":
                    mask = seg.mask
                    row["disputed_share"], row["uncertain"] = seg.disputed_share, seg.uncertain
            if cal is not None and mask.any():
                truth_area = true_visible_area_m2(sample.floor_mask, sample.truth)
                try:
                    poly = floor_polygon(mask, cal)
                    row["area_m2"], row["true_area_m2"] = poly.area_m2, truth_area
                    row["area_error"] = (poly.area_m2 - truth_area) / truth_area
                    row["vertices"] = len(poly.polygon_m)
                except ValueError:
                    row["area_error"] = None
                # The same polygon from the true mask: what is left is the polygon's own
                # error (one floor region only) and the board's calibration.
                try:
                    row["truth_mask_area_error"] = floor_polygon(sample.floor_mask, cal).area_m2 / truth_area - 1
                except ValueError:
                    row["truth_mask_area_error"] = None
            rows.append(row)
            worst.append((row["onnx+grabcut"], f"synth {args.seed}/{i} IoU {row['onnx+grabcut']:.3f}", mask, sample.floor_mask,
                          sample.image))
    worst.sort(key=lambda r: r[0])
    return rows, worst[:6]


def real(folder: Path, model):
    rows, pictures = [], []
    for photo in sorted(p for p in folder.iterdir() if p.suffix in (".jpg", ".png") and "_" in p.stem
                        and not p.stem.endswith(("_floor", "_ignore"))):
        image = cv2.cvtColor(cv2.imread(str(photo)), cv2.COLOR_BGR2RGB)
        truth = cv2.imread(str(photo.with_name(photo.stem + "_floor.png")), cv2.IMREAD_GRAYSCALE) > 127
        ignore_path = photo.with_name(photo.stem + "_ignore.png")
        ignore = cv2.imread(str(ignore_path), cv2.IMREAD_GRAYSCALE) > 127 if ignore_path.exists() else None
        row = {"image": photo.stem}
        for name, kwargs in (("onnx", dict(refine=False)), ("onnx+grabcut", {})):
            seg = segment_floor(image, model, None, **kwargs)
            row[name] = iou(seg.mask, truth, ignore)
            if name == "onnx+grabcut":
                pictures.append((f"{photo.stem} {row[name]:.2f}", seg.mask, truth, ignore))
        rows.append(row)
    return rows, pictures


def fmt(v, spec=".3f"):
    return "-" if v is None else format(v, spec)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--seed", type=int, default=901, help="seed of the held-out renders (default 901)")
    parser.add_argument("--size", type=int, nargs=2, default=None, metavar=("W", "H"),
                        help="render size (default: random phone sizes)")
    parser.add_argument("--stress", choices=sorted(STRESS), default=None,
                        help="render a stress set of one hard case (default: plain held-out renders)")
    parser.add_argument("--real", type=Path, default=ROOT.parent / "shared" / "data" / "real-rooms-dev")
    parser.add_argument("--model", type=Path, default=DEFAULT_MODEL)
    args = parser.parse_args(argv)
    model = FloorModel(args.model)

    # Speed: the model alone (at each of its input sizes, probabilities averaged), and the
    # whole step on a 12 MP photo.
    with Renderer() as renderer:
        sample = render_sample([901, 1000], renderer, size_px=(1008, 756))
    big = cv2.resize(sample.image, (4032, 3024), interpolation=cv2.INTER_CUBIC)
    cal_big = calibrate_photo(big, Board(), intrinsics=exif_intrinsics(sample.truth["K"][0][0] * 4, (4032, 3024)))
    inputs = model.inputs_label(*sample.image.shape[:2])
    # A "not floor" click in the middle of the floor found: the dearest correction, a first
    # pass to tell a click on a skirting board from one on a thing standing on the floor.
    ys, xs = np.nonzero(segment_floor(big, model, cal_big).mask)
    click = [[xs[len(xs) // 2], ys[len(ys) // 2], 0]]
    infer, whole, clicked = [], [], []
    for _ in range(7):
        start = time.perf_counter()
        model.floor_probability(sample.image)
        infer.append(time.perf_counter() - start)
        start = time.perf_counter()
        segment_floor(big, model, cal_big)
        whole.append(time.perf_counter() - start)
        start = time.perf_counter()
        segment_floor(big, model, cal_big, clicks=click)
        clicked.append(time.perf_counter() - start)
    speed = {"model_ms": 1000 * float(np.median(infer)), "model_inputs": inputs,
             "segment_12mp_s": float(np.median(whole)), "segment_12mp_not_floor_click_s": float(np.median(clicked))}

    synth_rows, worst = synthetic(args, model)
    real_rows, real_pictures = real(args.real, model) if args.real.is_dir() else ([], [])

    def col(rows, key):
        return [r[key] for r in rows if r.get(key) is not None]

    summary = {
        "synthetic": {k: {"mean": float(np.mean(col(synth_rows, k))), "min": float(np.min(col(synth_rows, k)))}
                      for k in ("onnx", "onnx+grabcut", "grabcut")},
        "area_error_median_abs": float(np.median(np.abs(col(synth_rows, "area_error")))),
        "area_error_p90_abs": float(np.percentile(np.abs(col(synth_rows, "area_error")), 90)),
        "area_within_5pct": f"{sum(abs(e) <= 0.05 for e in col(synth_rows, 'area_error'))}/"
                            f"{len(col(synth_rows, 'area_error'))}",
        "area_within_10pct": f"{sum(abs(e) <= 0.10 for e in col(synth_rows, 'area_error'))}/"
                             f"{len(col(synth_rows, 'area_error'))}",
        "truth_mask_within_5pct": f"{sum(abs(e) <= 0.05 for e in col(synth_rows, 'truth_mask_area_error'))}/"
                                  f"{len(col(synth_rows, 'truth_mask_area_error'))}",
        "uncalibrated": sum(not r["calibrated"] for r in synth_rows),
        # The "floor uncertain" warning against the polygons more than 5 % off.
        "uncertain": {"warned": sum(bool(r.get("uncertain")) for r in synth_rows
                                    if r.get("area_error") is not None),
                      "off_warned": sum(bool(r.get("uncertain")) for r in synth_rows
                                        if r.get("area_error") is not None and abs(r["area_error"]) > 0.05),
                      "off": sum(abs(e) > 0.05 for e in col(synth_rows, "area_error"))},
        "real": {k: float(np.mean(col(real_rows, k))) for k in ("onnx", "onnx+grabcut")} if real_rows else None,
        "speed": speed,
    }
    lines = ["# Floor segmentation benchmark", "",
             f"model `{args.model.name}`; {args.count} held-out renders (seed {args.seed}"
             f"{', stress set ' + args.stress if args.stress else ''}); "
             f"machine: {__import__('os').cpu_count()} cores", "",
             "| render | size | IoU onnx | IoU onnx+grabcut | IoU grabcut | area error | from true mask | disputed | "
             "step s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in synth_rows:
        disputed = fmt(r.get("disputed_share"), ".0%") + (" (warned)" if r.get("uncertain") else "")
        lines.append(f"| {r['image']} | {r['size']} | {fmt(r['onnx'])} | {fmt(r['onnx+grabcut'])} | "
                     f"{fmt(r['grabcut'])} | {fmt(r.get('area_error'), '+.1%')} | {fmt(r.get('truth_mask_area_error'), '+.1%')} | "
                     f"{disputed} | {fmt(r.get('onnx+grabcut_s'), '.2f')} |")
    s = summary["synthetic"]
    lines += ["", "| held-out synthetic | mean IoU | worst IoU |", "|---|---|---|"]
    lines += [f"| {k} | {v['mean']:.3f} | {v['min']:.3f} |" for k, v in s.items()]
    lines += ["", f"floor polygon area vs true visible area: median |error| {summary['area_error_median_abs']:.1%}, "
                  f"90th percentile {summary['area_error_p90_abs']:.1%}, within 5 %: {summary['area_within_5pct']}, "
                  f"within 10 %: {summary['area_within_10pct']} "
                  f"(from the true mask, through the same calibration: {summary['truth_mask_within_5pct']})"]
    u = summary["uncertain"]
    lines += ["", f"\"floor uncertain\" warnings (model and GrabCut disagree on more than "
                  f"{FLOOR.segment.disputed_share_warn:.0%} of the floor): {u['warned']} of "
                  f"{len(col(synth_rows, 'area_error'))}; "
                  f"{u['off_warned']} of the {u['off']} polygons more than 5 % off are among them"]
    if real_rows:
        lines += ["", "| real room (furnished; never trained on) | IoU onnx | IoU onnx+grabcut |", "|---|---|---|"]
        lines += [f"| {r['image']} | {r['onnx']:.3f} | {r['onnx+grabcut']:.3f} |" for r in real_rows]
        lines += [f"| **mean** | {summary['real']['onnx']:.3f} | {summary['real']['onnx+grabcut']:.3f} |"]
    lines += ["", f"speed: model alone {speed['model_ms']:.1f} ms ({speed['model_inputs']} input, 1008x756 photo); "
                  f"whole step on a 12 MP photo (4032x3024, model + GrabCut + clean-up) {speed['segment_12mp_s']:.2f} s, "
                  f"with one \"not floor\" click {speed['segment_12mp_not_floor_click_s']:.2f} s (medians of 7)"]
    text = "\n".join(lines) + "\n"
    print(text)
    OUT.mkdir(parents=True, exist_ok=True)
    stem = ("segmentation" if args.seed == 901 and not args.stress else
            f"segmentation_{args.stress + '_' if args.stress else ''}seed{args.seed}")
    worst_png = "segmentation_synth_worst.png" if stem == "segmentation" else f"{stem}_worst.png"
    write_atomic(OUT / f"{stem}.md", text)
    write_atomic(OUT / f"{stem}.json", json.dumps({"summary": summary, "synthetic": synth_rows,
                                                   "real": real_rows}, indent=1))
    tiles = []
    for _, name, mask, truth, image in worst:
        tile = image.copy()
        tile[mask & ~truth] = (0.4 * tile[mask & ~truth] + [150, 0, 0]).astype(np.uint8)
        tile[~mask & truth] = (0.4 * tile[~mask & truth] + [0, 0, 150]).astype(np.uint8)
        tile[mask & truth] = (0.6 * tile[mask & truth] + [0, 100, 0]).astype(np.uint8)
        tile = cv2.resize(tile, (320, 240), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, name, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(tile)
    # Rows of three; with fewer than three renders, one short row.
    sheet = np.vstack([np.hstack(tiles[i:i + 3]) for i in range(0, max(1, len(tiles) - len(tiles) % 3), 3)])
    write_atomic(OUT / worst_png, cv2.imencode(".png", sheet[..., ::-1])[1].tobytes())
    if real_pictures:
        write_atomic(OUT / "segmentation_real_masks.png",
                     cv2.imencode(".png", pair_picture(real_pictures)[..., ::-1])[1].tobytes())
    return 0


if __name__ == "__main__":
    sys.exit(main())
