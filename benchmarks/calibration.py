"""Calibration accuracy, per image: synthetic renders with ground truth and OpenCV's real
chessboard photos against their published calibration.

Run by hand: ``python benchmarks/calibration.py [--count 24]`` (about a minute). Prints two
tables and writes ``results/calibration.{json,md}``.

Synthetic: ``--count`` photos from the synthetic photographer (seeds ``[99, i]``, sizes
cycling 640x480, 1280x960, 960x1280, 2016x1512), JPEG-compressed as written, calibrated
from the board alone (single view: they carry no EXIF). Errors: focal length, camera
height, and 200 random floor pixels mapped to the floor, as a fraction of their distance
from the camera.

Real: ``tests/data/opencv-chessboard/left*.jpg`` (9x6 inner corners, 25 mm): the
multi-image profile, and each photo's single-view focal length, against fx = 535.916 px.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

from augment.board import Board  # noqa: E402
from augment.calibrate import CalibrationError, calibrate_file, calibrate_photo, camera_profile  # noqa: E402
from augment.gl import Renderer  # noqa: E402
from augment.synth import render_sample  # noqa: E402

REAL = Path(__file__).resolve().parents[1] / "tests" / "data" / "opencv-chessboard"
REFERENCE_F_PX = 535.91573396163199
SIZES = ((640, 480), (1280, 960), (960, 1280), (2016, 1512))


def synthetic(count: int) -> list[dict]:
    rows = []
    with Renderer() as renderer:
        for i in range(count):
            size = SIZES[i % len(SIZES)]
            sample = render_sample([99, i], renderer, size_px=size)
            t = sample.truth
            ok, jpg = cv2.imencode(".jpg", cv2.cvtColor(sample.image, cv2.COLOR_RGB2BGR),
                                   [cv2.IMWRITE_JPEG_QUALITY, t["photo"]["jpeg_quality"]])
            photo = cv2.cvtColor(cv2.imdecode(jpg, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
            row = {"seed": [99, i], "size": f"{size[0]}x{size[1]}", "pitch_deg": t["camera"]["pitch_down_deg"],
                   "hfov_deg": t["camera"]["hfov_deg"]}
            start = time.perf_counter()
            try:
                c = calibrate_photo(photo, Board())
            except CalibrationError as error:
                row.update(refused=str(error).split(":")[0].split(".")[0])
                rows.append(row)
                continue
            row["seconds"] = time.perf_counter() - start
            f_true = t["K"][0][0]
            # The board lies 1 mm above the floor the truth is measured from.
            height_true = t["camera"]["height_m"] - 0.001
            cfw = np.array(t["camera_from_world"])
            K = np.array(t["K"])
            v, u = np.nonzero(sample.floor_mask)
            pick = np.random.default_rng(0).choice(len(v), 200)
            px = np.column_stack([u[pick], v[pick]]).astype(np.float64)
            floor = c.floor_from_pixels(px)
            est = np.column_stack([floor, np.zeros(len(floor)), np.ones(len(floor))]) @ c.camera_from_floor.T
            # True floor points in camera coordinates: rays through the pixels meet z = 0.
            wfc = np.linalg.inv(cfw)
            rays = np.column_stack([px, np.ones(len(px))]) @ np.linalg.inv(K).T @ wfc[:3, :3].T
            world = wfc[:3, 3] + rays * (-wfc[2, 3] / rays[:, 2])[:, None]
            true = world @ cfw[:3, :3].T + cfw[:3, 3]
            err = np.linalg.norm(est[:, :3] - true, axis=1) / np.linalg.norm(true, axis=1)
            row.update(focal_err=float((c.intrinsics.K[0, 0] - f_true) / f_true),
                       focal_unc=c.intrinsics.focal_uncertainty,
                       height_err=float((c.camera_height_m - height_true) / height_true),
                       floor_err_median=float(np.median(err)), floor_err_p95=float(np.percentile(err, 95)),
                       rms_px=c.rms_px, detector=c.detector)
            rows.append(row)
    return rows


def real() -> tuple[dict, list[dict]]:
    board = Board(9, 6, 25)
    paths = sorted(REAL.glob("left*.jpg"))
    profile = camera_profile(paths, board)
    rows = []
    for path in paths:
        row = {"image": path.name}
        try:
            c = calibrate_file(path, board)
        except CalibrationError as error:
            row["refused"] = str(error).split(".")[0]
        else:
            f = c.intrinsics.K[0, 0]
            row.update(focal_err=float((f - REFERENCE_F_PX) / REFERENCE_F_PX), focal_unc=c.intrinsics.focal_uncertainty,
                       rms_px=c.rms_px, note=c.intrinsics.note)
        rows.append(row)
    return profile, rows


def _pct(x):
    return f"{100 * x:+.2f} %"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=24, help="synthetic photos (default 24)")
    args = parser.parse_args()

    syn = synthetic(args.count)
    md = ["## Synthetic photos, single view (no EXIF)", "",
          "| seed | size | pitch | hfov | focal err | focal unc | height err | floor err median | floor err p95 | RMS px |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for r in syn:
        head = f"| {r['seed'][1]} | {r['size']} | {r['pitch_deg']:.0f}° | {r['hfov_deg']:.0f}° |"
        if "refused" in r:
            md.append(f"{head} refused: {r['refused']} | | | | | |")
        else:
            md.append(f"{head} {_pct(r['focal_err'])} | {100 * r['focal_unc']:.1f} % | {_pct(r['height_err'])} | "
                      f"{100 * r['floor_err_median']:.2f} % | {100 * r['floor_err_p95']:.2f} % | {r['rms_px']:.2f} |")
    ok = [r for r in syn if "refused" not in r]
    summary = {
        "calibrated": len(ok), "refused": len(syn) - len(ok),
        "focal_err_abs_median": float(np.median([abs(r["focal_err"]) for r in ok])),
        "height_err_abs_median": float(np.median([abs(r["height_err"]) for r in ok])),
        "floor_err_median": float(np.median([r["floor_err_median"] for r in ok])),
        "floor_err_p95_max": float(np.max([r["floor_err_p95"] for r in ok])),
        "seconds_median": float(np.median([r["seconds"] for r in ok])),
    }
    md += ["", f"Calibrated {summary['calibrated']} of {len(syn)}; median |focal error| "
           f"{100 * summary['focal_err_abs_median']:.2f} %, median |height error| "
           f"{100 * summary['height_err_abs_median']:.2f} %, floor points: median "
           f"{100 * summary['floor_err_median']:.2f} % of their distance (worst 95th percentile "
           f"{100 * summary['floor_err_p95_max']:.2f} %); {summary['seconds_median']:.2f} s per photo (median).", ""]

    profile, rows = real()
    K = np.array(profile["K"])
    md += ["## OpenCV's left01-14 (real, 9x6, 25 mm)", "",
           f"Multi-image profile ({len(profile['images'])} photos): fx = fy = {K[0, 0]:.2f} px "
           f"({_pct((K[0, 0] - REFERENCE_F_PX) / REFERENCE_F_PX)} against OpenCV's 535.92), "
           f"cx = {K[0, 2]:.1f}, cy = {K[1, 2]:.1f}, RMS {profile['rms_px']:.3f} px.", "",
           "| image | single-view focal err | focal unc | RMS px | note |", "|---|---|---|---|---|"]
    for r in rows:
        if "refused" in r:
            md.append(f"| {r['image']} | refused: {r['refused']} | | | |")
        else:
            md.append(f"| {r['image']} | {_pct(r['focal_err'])} | {100 * r['focal_unc']:.1f} % | {r['rms_px']:.2f} | "
                      f"{r['note']} |")
    print("\n".join(md))
    results_io.write("calibration", {"machine": results_io.machine(), "synthetic": syn, "synthetic_summary": summary,
                                     "profile": profile, "real": rows}, md)


if __name__ == "__main__":
    main()
