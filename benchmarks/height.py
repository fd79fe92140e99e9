"""Wall-height accuracy on synthetic renders, and the time for a 12 MP photo.

Run by hand: ``python benchmarks/height.py [--count 30] [--seed 77]`` (a few minutes:
rendering dominates). Prints a per-image table and writes ``results/height.{json,md}`` and
one overlay, ``results/height_overlay.png``.

Photos: ``--count`` renders from the synthetic photographer at ``--size`` (seeds
``[--seed, i]``), with the phone held ``--pitch`` degrees down (default 0-15). The
photographer's own range, 5-40 degrees, mostly frames the floor: the ceiling is in view in
about one photo in seven. A photo counts as *eligible* when the ceiling covers at least
``ELIGIBLE_CEILING`` of it (the renderer's labels): then the ceiling line, and any room
corner in view, reach the top of the wall. Elsewhere the right answer is the fallback.

Each photo is measured five ways, to separate the height's own error from calibration's
and from segmentation's:

* ``truth+mask``: true K and pose, the renderer's floor mask (standing in for the floor
  segmentation of ``augment/segment.py``);
* ``truth``: true K and pose, no mask (feet checked by color only);
* ``board+mask``, ``board``: calibrated from the board alone (single view, as
  ``stage check`` without EXIF); refusals are counted apart;
* ``exif+mask``: the true focal length (what EXIF gives a phone photo) and the pose from
  the board.

Errors are height / truth - 1. The pose's floor is the board's plane, 1 mm above the
floor the truth is measured from; the truth columns use the same.
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

import augment.synth.camera as synth_camera  # noqa: E402
from augment.camera.board import Board  # noqa: E402
from augment.camera.calibrate import exif_intrinsics  # noqa: E402
from augment.camera.calibrate import calibrate_file, calibrate_photo
from augment.camera.calibration import Calibration
from augment.errors import CalibrationError
from augment.render.gl import Renderer  # noqa: E402
from augment.room.height import measure_height  # noqa: E402
from augment.draw.height import height_overlay  # noqa: E402
from augment.floor.model import FloorModel  # noqa: E402
from augment.floor.segment import segment_floor  # noqa: E402
from augment.synth import CEILING, render_sample  # noqa: E402
from augment.synth.camera import Shot  # noqa: E402
from layout.fileio import write_atomic  # noqa: E402

ELIGIBLE_CEILING = 0.002          # fraction of the photo that must show ceiling
TARGET_MEDIAN, TARGET_P90 = 0.03, 0.08
SAMPLE_PHOTO = Path(__file__).resolve().parents[1] / "samples" / "photos" / "room_1.jpg"
# "+mask": the renderer's true floor mask; "+segmented": the floor model's (the product's path).
MODES = ("truth+mask", "truth", "board+mask", "board", "exif+mask", "exif+segmented")
BIG_SIZE = (4000, 3000)


@contextmanager
def pitch_range(low_deg: float, high_deg: float):
    """Narrow the synthetic photographer's pitch for the renders of this run."""
    saved = synth_camera.PITCH_DOWN_DEG
    synth_camera.PITCH_DOWN_DEG = (low_deg, high_deg)
    try:
        yield
    finally:
        synth_camera.PITCH_DOWN_DEG = saved


def truth_calibration(template: Calibration, truth: dict, scale: float = 1.0) -> Calibration:
    """A calibration with the render's true intrinsics and pose (in the board's frame,
    floor 1 mm below it), for a photo scaled by ``scale``. Built from a real calibration
    so fields this benchmark does not know about keep valid values."""
    S = np.array([[scale, 0, (scale - 1) / 2], [0, scale, (scale - 1) / 2], [0, 0, 1]])
    K = S @ np.array(truth["K"], dtype=np.float64)
    pose = np.array(truth["camera_from_world"]) @ np.array(truth["board"]["world_from_board"])
    pose[:3, 3] -= 0.001 * pose[:3, 2]
    R, t = pose[:3, :3], pose[:3, 3]
    normal = R[:, 2]
    d = -float(normal @ t)
    image_from_floor = K @ np.column_stack([R[:, 0], R[:, 1], t])
    horizon = -(np.linalg.inv(K).T @ normal)
    w, h = truth["size_px"]
    intrinsics = dataclasses.replace(template.intrinsics, K=K, distortion=np.zeros(5), source="truth",
                                     focal_uncertainty=0.0, note="the render's true intrinsics")
    return dataclasses.replace(template, size_px=(round(w * scale), round(h * scale)), intrinsics=intrinsics,
                               camera_from_floor=pose, camera_height_m=d, floor_plane_camera=np.append(normal, d),
                               image_from_floor=image_from_floor / image_from_floor[2, 2],
                               horizon=horizon / np.hypot(horizon[0], horizon[1]), rms_px=0.0)


def _photo(sample) -> np.ndarray:
    """The render as written: JPEG-compressed at its recorded quality."""
    q = int(sample.truth["photo"]["jpeg_quality"])
    _, jpg = cv2.imencode(".jpg", cv2.cvtColor(sample.image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, q])
    return cv2.cvtColor(cv2.imdecode(jpg, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


def _entry(result, truth_h: float) -> dict:
    return {"height_m": result.height_m, "err": result.height_m / truth_h - 1, "fallback": result.fallback,
            "confidence": result.confidence, "reason": result.reason, "at_least_m": result.at_least_m}


def door_tops_in_view(sample) -> list[float]:
    """The heights of the doors whose head (its middle) and a foot show in the photo: not
    hidden (the render's depth there within 5 % of the point's) and inside the frame."""
    t = sample.truth
    shot = Shot(np.array(t["K"]), np.linalg.inv(np.array(t["camera_from_world"])), tuple(t["size_px"]))
    tops = []
    for door in t["room"]["doors"]:
        a, b = np.array(door["segment_m"])
        points = np.array([[*(a + b) / 2, door["top_m"]], [*a, 0.0], [*b, 0.0]])
        px, depth = shot.project(points)
        seen = shot.in_view(points)
        u, v = px[seen].astype(int).T
        seen[seen] = np.abs(sample.depth_m[v, u] / depth[seen] - 1) < 0.05
        if seen[0] and (seen[1] or seen[2]):
            tops.append(float(door["top_m"]))
    return tops


def measure(args, template: Calibration) -> tuple[list[dict], dict]:
    rows, keep = [], None
    board = Board()
    model = FloorModel()
    with pitch_range(*args.pitch), Renderer() as renderer:
        for i in range(args.count):
            sample = render_sample([args.seed, i], renderer, size_px=args.size)
            photo, t = _photo(sample), sample.truth
            truth_h = t["room"]["height_m"]
            ceiling = float(np.mean(sample.labels == CEILING))
            row = {"seed": [args.seed, i], "height_true_m": truth_h, "ceiling_fraction": ceiling,
                   "eligible": ceiling >= ELIGIBLE_CEILING, "pitch_deg": t["camera"]["pitch_down_deg"],
                   "door_tops_m": door_tops_in_view(sample),
                   "camera_height_m": t["camera"]["height_m"]}
            cal = truth_calibration(template, t)
            times = []
            for _ in range(3):
                start = time.perf_counter()
                result = measure_height(photo, cal, sample.floor_mask)
                times.append(time.perf_counter() - start)
            row["truth+mask"], row["seconds"] = _entry(result, truth_h), float(np.median(times))
            row["truth"] = _entry(measure_height(photo, cal), truth_h)
            try:
                board_cal = calibrate_photo(photo, board)
            except CalibrationError as error:
                row["board_refused"] = str(error).split(":")[0].split(" (")[0].split(".")[0]
            else:
                row["focal_err"] = board_cal.intrinsics.K[0, 0] / t["K"][0][0] - 1
                row["board+mask"] = _entry(measure_height(photo, board_cal, sample.floor_mask), truth_h)
                row["board"] = _entry(measure_height(photo, board_cal), truth_h)
            try:
                exif_cal = calibrate_photo(photo, board, intrinsics=exif_intrinsics(t["K"][0][0], args.size))
            except CalibrationError as error:
                row["exif_refused"] = str(error).split(":")[0].split(" (")[0].split(".")[0]
            else:
                row["exif+mask"] = _entry(measure_height(photo, exif_cal, sample.floor_mask), truth_h)
                segmented = segment_floor(photo, model, exif_cal).mask
                row["exif+segmented"] = _entry(measure_height(photo, exif_cal, segmented), truth_h)
            rows.append(row)
            if keep is None and row["eligible"] and not row["truth+mask"]["fallback"]:
                keep = (photo, sample.floor_mask, t, cal)
            print(f"{i + 1}/{args.count}", end="\r", file=sys.stderr, flush=True)
    extra = {}
    if keep is not None:
        photo, mask, t, cal = keep
        overlay = height_overlay(photo, cal, measure_height(photo, cal, mask))
        ok, png = cv2.imencode(".png", cv2.cvtColor(overlay, cv2.COLOR_RGB2BGR))
        results_io.RESULTS.mkdir(parents=True, exist_ok=True)
        write_atomic(results_io.RESULTS / "height_overlay.png", png.tobytes())
        extra["overlay_seed"] = t["seed"]
        extra["timing_12mp"] = time_big(photo, mask, t, template)
    return rows, extra


def time_big(photo: np.ndarray, mask: np.ndarray, truth: dict, template: Calibration, repeats: int = 7) -> dict:
    """Median time of measure_height on the photo scaled up to 4000 x 3000 (12 MP)."""
    scale = BIG_SIZE[0] / photo.shape[1]
    big = cv2.resize(photo, BIG_SIZE, interpolation=cv2.INTER_CUBIC)
    big_mask = cv2.resize(mask.astype(np.uint8), BIG_SIZE, interpolation=cv2.INTER_NEAREST).astype(bool)
    cal = truth_calibration(template, truth, scale)
    out = {}
    for name, m in (("mask", big_mask), ("no_mask", None)):
        measure_height(big, cal, m)                      # warm caches
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            result = measure_height(big, cal, m)
            times.append(time.perf_counter() - start)
        out[name] = {"seconds_median": float(np.median(times)), "seconds_min": float(np.min(times)),
                     "height_m": result.height_m, "fallback": result.fallback}
    return out


def summarize(rows: list[dict]) -> dict:
    out = {}
    for mode in MODES:
        done = [r for r in rows if mode in r]
        el = [r for r in done if r["eligible"]]
        measured = [abs(r[mode]["err"]) for r in el if not r[mode]["fallback"]]
        wrong = [abs(r[mode]["err"]) for r in done if not r["eligible"] and not r[mode]["fallback"]]
        out[mode] = {
            "photos": len(done), "eligible": len(el), "eligible_measured": len(measured),
            "eligible_fallback": len(el) - len(measured),
            "err_abs_median": float(np.median(measured)) if measured else None,
            "err_abs_p90": float(np.percentile(measured, 90)) if measured else None,
            "err_abs_max": float(np.max(measured)) if measured else None,
            "not_eligible_measured": len(wrong),
            "not_eligible_err_abs_median": float(np.median(wrong)) if wrong else None,
        }
        # Photos that show a door's top but not the ceiling: a lower bound, not a height.
        doors = [r for r in done if not r["eligible"] and r["door_tops_m"]]
        bounded = [r for r in doors if r[mode]["fallback"] and r[mode]["at_least_m"] is not None]
        out[mode].update({
            "door_only": len(doors), "door_only_bounded": len(bounded),
            "door_only_bound_over_door_median": float(np.median([r[mode]["at_least_m"] / max(r["door_tops_m"]) - 1
                                                                 for r in bounded])) if bounded else None,
            "door_only_bound_above_truth": sum(r[mode]["at_least_m"] > r["height_true_m"] for r in bounded)})
    out["board_refused"] = sum("board_refused" in r for r in rows)
    out["exif_refused"] = sum("exif_refused" in r for r in rows)
    return out


def _cell(entry: dict | None) -> str:
    if entry is None:
        return ""
    if entry["fallback"]:
        return "fallback" + (f" (\u2265 {entry['at_least_m']:.2f} m)" if entry.get("at_least_m") else "")
    return f"{100 * entry['err']:+.1f} % ({entry['confidence']:.2f})"


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.2f} %"


def report(args, rows: list[dict], summary: dict, extra: dict) -> list[str]:
    md = [f"## Wall height on {len(rows)} synthetic photos ({args.size[0]}x{args.size[1]}, pitch "
          f"{args.pitch[0]:g}-{args.pitch[1]:g} degrees down, seeds [{args.seed}, i])", "",
          "Each cell: height error (confidence), or fallback (with the lower bound when one). Eligible: the "
          "ceiling is in view "
          f"(at least {100 * ELIGIBLE_CEILING:.1f} % of the photo).", "",
          "| seed | H m | ceiling | eligible | door tops m | " + " | ".join(MODES) + " | board calibration |",
          "|---|---|---|---|---|" + "---|" * len(MODES) + "---|"]
    for r in rows:
        board = (f"refused: {r['board_refused']}" if "board_refused" in r
                 else f"focal {100 * r['focal_err']:+.1f} %")
        md.append(f"| {r['seed'][1]} | {r['height_true_m']:.2f} | {100 * r['ceiling_fraction']:.1f} % | "
                  f"{'yes' if r['eligible'] else 'no'} | {', '.join(f'{h:.2f}' for h in r['door_tops_m'])} | "
                  + " | ".join(_cell(r.get(m)) for m in MODES)
                  + f" | {board} |")
    md += ["", "| mode | photos | eligible | measured | fell back | median abs err | p90 abs err | max abs err | "
               "measured though not eligible (median abs err) |",
           "|---|---|---|---|---|---|---|---|---|"]
    for mode in MODES:
        s = summary[mode]
        md.append(f"| {mode} | {s['photos']} | {s['eligible']} | {s['eligible_measured']} | {s['eligible_fallback']} | "
                  f"{_pct(s['err_abs_median'])} | {_pct(s['err_abs_p90'])} | {_pct(s['err_abs_max'])} | "
                  f"{s['not_eligible_measured']} ({_pct(s['not_eligible_err_abs_median'])}) |")
    md += ["", "Photos that show a door's top (and a foot) but not the ceiling: the height is not measured, "
               "but the tallest whole vertical edge on the floor bounds it from below.", "",
           "| mode | door-only photos | bounded | bound over the door's top (median) | bound above the true height |",
           "|---|---|---|---|---|"]
    for mode in MODES:
        s = summary[mode]
        md.append(f"| {mode} | {s['door_only']} | {s['door_only_bounded']} | "
                  f"{_pct(s['door_only_bound_over_door_median'])} | {s['door_only_bound_above_truth']} |")
    md += ["", f"Board calibration refused {summary['board_refused']} of {len(rows)} photos (single view), "
           f"{summary['exif_refused']} with the true focal length. Targets: median < {100 * TARGET_MEDIAN:.0f} %, "
           f"p90 < {100 * TARGET_P90:.0f} % on eligible photos."]
    timing = extra.get("timing_12mp")
    if timing:
        md += ["", f"12 MP ({BIG_SIZE[0]}x{BIG_SIZE[1]}, photo {extra['overlay_seed']} scaled up): "
               f"measure_height {timing['mask']['seconds_median']:.3f} s with a floor mask, "
               f"{timing['no_mask']['seconds_median']:.3f} s without (median of 7; target < 0.3 s)."]
    md.append(f"At {args.size[0]}x{args.size[1]}: {np.median([r['seconds'] for r in rows]):.3f} s per photo "
              "(median over photos of the median of 3 runs, with a mask).")
    return md


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=30, help="synthetic photos (default 30)")
    parser.add_argument("--seed", type=int, default=77)
    parser.add_argument("--size", default="1280x960", help="WIDTHxHEIGHT (default 1280x960)")
    parser.add_argument("--pitch", default="0,15", help="LOW,HIGH degrees down (default 0,15)")
    args = parser.parse_args()
    args.size = tuple(int(v) for v in args.size.lower().split("x"))
    args.pitch = tuple(float(v) for v in args.pitch.split(","))

    template = calibrate_file(SAMPLE_PHOTO, Board())
    rows, extra = measure(args, template)
    summary = summarize(rows)
    md = report(args, rows, summary, extra)
    print("\n".join(md))
    results_io.write("height", {"machine": results_io.machine(), "args": {"count": args.count, "seed": args.seed,
                                                                          "size": list(args.size),
                                                                          "pitch_deg": list(args.pitch)},
                                "eligible_ceiling_fraction": ELIGIBLE_CEILING, "summary": summary, **extra,
                                "photos": rows}, md)


if __name__ == "__main__":
    main()
