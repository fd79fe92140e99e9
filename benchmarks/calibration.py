"""Calibration accuracy, per image: synthetic renders with ground truth and OpenCV's real
chessboard photos against their published calibration.

Run by hand: ``python benchmarks/calibration.py [--count 24] [--charuco-count 12]`` (a few
minutes). Prints the tables and writes ``results/calibration.{json,md}``.

Synthetic checkerboard: ``--count`` photos from the synthetic photographer (seeds
``[99, i]``, sizes cycling 640x480, 1280x960, 960x1280, 2016x1512), JPEG-compressed as
written, calibrated from the board alone (single view: they carry no EXIF). Errors: focal
length, camera height, and 200 random floor pixels mapped to the floor, as a fraction of
their distance from the camera.

Synthetic ChArUco: ``--charuco-count`` photos of the default ChArUco board (seeds
``[7, i]``, 2016x1512), each rendered twice: whole, and with a flat carton over 40 % of the
board's width (``render_sample(board_hidden=0.4)``). Besides the single-view errors, the
pose given the true focal length (rotation and translation of the board in the camera).
The photographer frames the board for a checkerboard; markers need squares of about 17 px
or more, so only the nearer boards are read.

Real: ``tests/data/opencv-chessboard/left*.jpg`` (9x6 inner corners, 25 mm): the
multi-image profile, and each photo's single-view focal length, against fx = 535.916 px.

Summaries: photos where the board was found, calibrated, refused (by reason); median and
95th percentile of |focal|, |height| and floor-point errors (floor: the per-photo median
and 95th percentile, summarized over photos); photos whose floor 95th percentile exceeds
2 %; and the RMS of focal error over reported uncertainty (about 1 when the uncertainty
is honest, above 1 when it is too small).
"""
from __future__ import annotations

import argparse
import re
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

from augment.camera.board import Board  # noqa: E402
from augment.camera.detect import detect_board  # noqa: E402
from augment.camera.calibrate import calibrate_file, calibrate_photo, camera_profile, exif_intrinsics
from augment.errors import CalibrationError
from augment.render.gl import Renderer  # noqa: E402
from augment.synth import render_sample  # noqa: E402

REAL = Path(__file__).resolve().parents[1] / "tests" / "data" / "opencv-chessboard"
REFERENCE_F_PX = 535.91573396163199
SIZES = ((640, 480), (1280, 960), (960, 1280), (2016, 1512))
CHARUCO_SIZE = (2016, 1512)
HIDDEN = 0.4
FLOOR_TARGET = 0.02


def _jpeg(sample) -> np.ndarray:
    """The photo as written: JPEG-compressed at the render's quality, decoded."""
    ok, jpg = cv2.imencode(".jpg", cv2.cvtColor(sample.image, cv2.COLOR_RGB2BGR),
                           [cv2.IMWRITE_JPEG_QUALITY, sample.truth["photo"]["jpeg_quality"]])
    return cv2.cvtColor(cv2.imdecode(jpg, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


def _reason(error: CalibrationError) -> str:
    """The message's first clause, numbers as N, so that refusals group by cause."""
    return re.sub(r"\d+(\.\d+)?", "N", str(error).split(":")[0].split(".")[0].split(" (")[0])


def _floor_errors(c, sample) -> np.ndarray:
    """Relative floor-point errors of 200 random floor pixels."""
    t = sample.truth
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
    return np.linalg.norm(est[:, :3] - true, axis=1) / np.linalg.norm(true, axis=1)


def _evaluate(sample, photo, board: Board, row: dict) -> dict:
    """Calibrate ``photo`` from the board alone and add its errors to ``row``."""
    t = sample.truth
    detection = detect_board(photo, board)
    row["found"] = detection is not None
    if detection is not None:
        row.update(corners=len(detection.ids), detector=detection.detector)
        truth_px = np.array(t["board"]["corners_px"])
        if board.kind == "charuco":  # ids are absolute: compare corner by corner
            row["corner_rms_px"] = float(np.sqrt(np.mean(np.sum((detection.corners_px - truth_px[detection.ids]) ** 2,
                                                                axis=1))))
    start = time.perf_counter()
    try:
        c = calibrate_photo(photo, board)
    except CalibrationError as error:
        row.update(refused=_reason(error))
        return row
    row["seconds"] = time.perf_counter() - start
    f_true = t["K"][0][0]
    # The board lies 1 mm above the floor the truth is measured from.
    height_true = t["camera"]["height_m"] - 0.001
    err = _floor_errors(c, sample)
    row.update(focal_err=float((c.intrinsics.K[0, 0] - f_true) / f_true), focal_unc=c.intrinsics.focal_uncertainty,
               height_err=float((c.camera_height_m - height_true) / height_true),
               floor_err_median=float(np.median(err)), floor_err_p95=float(np.percentile(err, 95)),
               rms_px=c.rms_px, detector=c.detector)
    return row


def _pose_with_true_focal(sample, photo, board: Board, row: dict) -> None:
    """Rotation (degrees) and translation (mm) error of camera_from_board given the true K."""
    t = sample.truth
    K = np.array(t["K"])
    try:
        c = calibrate_photo(photo, board, intrinsics=exif_intrinsics(K[0, 0], tuple(t["size_px"])))
    except CalibrationError:
        return
    truth = np.array(t["camera_from_world"]) @ np.array(t["board"]["world_from_board"])
    R = c.camera_from_floor[:3, :3].T @ truth[:3, :3]
    row.update(pose_rot_deg=float(np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))),
               pose_t_mm=float(1000 * np.linalg.norm(c.camera_from_floor[:3, 3] - truth[:3, 3])))


def synthetic(count: int, renderer: Renderer) -> list[dict]:
    rows = []
    for i in range(count):
        size = SIZES[i % len(SIZES)]
        sample = render_sample([99, i], renderer, size_px=size)
        t = sample.truth
        row = {"seed": [99, i], "size": f"{size[0]}x{size[1]}", "pitch_deg": t["camera"]["pitch_down_deg"],
               "hfov_deg": t["camera"]["hfov_deg"]}
        rows.append(_evaluate(sample, _jpeg(sample), Board(), row))
    return rows


def charuco(count: int, renderer: Renderer) -> list[dict]:
    board = Board(kind="charuco")
    rows = []
    for i in range(count):
        for hidden in (0.0, HIDDEN):
            sample = render_sample([7, i], renderer, size_px=CHARUCO_SIZE, board=board, board_hidden=hidden)
            t = sample.truth
            photo = _jpeg(sample)
            row = {"seed": [7, i], "size": f"{CHARUCO_SIZE[0]}x{CHARUCO_SIZE[1]}", "hidden": hidden,
                   "visible": int(np.sum(t["board"]["corners_visible"])),
                   "pitch_deg": t["camera"]["pitch_down_deg"], "hfov_deg": t["camera"]["hfov_deg"]}
            row = _evaluate(sample, photo, board, row)
            if row["found"]:
                _pose_with_true_focal(sample, photo, board, row)
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
            row["refused"] = _reason(error)
        else:
            f = c.intrinsics.K[0, 0]
            row.update(focal_err=float((f - REFERENCE_F_PX) / REFERENCE_F_PX), focal_unc=c.intrinsics.focal_uncertainty,
                       rms_px=c.rms_px, note=c.intrinsics.note)
        rows.append(row)
    return profile, rows


def summarize(rows: list[dict]) -> dict:
    """Counts and error statistics of a table's rows (see the module docstring)."""
    ok = [r for r in rows if "refused" not in r]
    refused: dict[str, int] = {}
    for r in rows:
        if "refused" in r:
            refused[r["refused"]] = refused.get(r["refused"], 0) + 1
    out = {"photos": len(rows), "found": sum(bool(r.get("found", True)) for r in rows), "calibrated": len(ok),
           "refused": refused}
    if not ok:
        return out
    for key in ("focal_err", "height_err", "floor_err_median", "floor_err_p95"):
        if key in ok[0]:
            values = np.abs([r[key] for r in ok])
            out[f"{key}_median"] = float(np.median(values))
            out[f"{key}_p95"] = float(np.percentile(values, 95))
            out[f"{key}_max"] = float(values.max())
    if "floor_err_p95" in ok[0]:
        out["floor_p95_over_target"] = int(sum(r["floor_err_p95"] > FLOOR_TARGET for r in ok))
    out["focal_z_rms"] = float(np.sqrt(np.mean([(r["focal_err"] / r["focal_unc"]) ** 2 for r in ok])))
    if "seconds" in ok[0]:
        out["seconds_median"] = float(np.median([r["seconds"] for r in ok]))
        out["seconds_max"] = float(np.max([r["seconds"] for r in ok]))
    return out


def _pct(x):
    return f"{100 * x:+.2f} %"


def _summary_lines(s: dict, floor: bool = True) -> list[str]:
    refused = ", ".join(f"{n} {reason}" for reason, n in sorted(s["refused"].items(), key=lambda kv: -kv[1]))
    lines = [f"Board found in {s['found']} of {s['photos']}, calibrated {s['calibrated']}"
             + (f"; refused: {refused}" if refused else "") + "."]
    if s["calibrated"]:
        lines.append(f"|focal error| median {100 * s['focal_err_median']:.2f} %, p95 {100 * s['focal_err_p95']:.2f} %,"
                     f" max {100 * s['focal_err_max']:.2f} %; focal error / reported uncertainty: RMS "
                     f"{s['focal_z_rms']:.2f}.")
    if s["calibrated"] and floor:
        lines.append(f"|height error| median {100 * s['height_err_median']:.2f} %, p95 "
                     f"{100 * s['height_err_p95']:.2f} %; floor points (share of their distance): median of "
                     f"per-photo medians {100 * s['floor_err_median_median']:.2f} %, per-photo 95th percentile: "
                     f"median {100 * s['floor_err_p95_median']:.2f} %, p95 {100 * s['floor_err_p95_p95']:.2f} %, "
                     f"max {100 * s['floor_err_p95_max']:.2f} %, above {100 * FLOOR_TARGET:.0f} % in "
                     f"{s['floor_p95_over_target']} of {s['calibrated']}; {s['seconds_median']:.2f} s per photo "
                     f"(median, max {s['seconds_max']:.2f} s).")
    return lines


def _synthetic_table(rows: list[dict], charuco_columns: bool = False) -> list[str]:
    extra_head = " hidden | corners seen/visible | corner RMS px | pose, true f |" if charuco_columns else ""
    md = ["| seed | size | pitch | hfov | detector |" + extra_head + " focal err | focal unc | height err | "
          "floor err median | floor err p95 | RMS px |",
          "|---|---|---|---|---|" + ("---|---|---|---|" if charuco_columns else "") + "---|---|---|---|---|---|"]
    for r in rows:
        head = (f"| {r['seed'][1]} | {r['size']} | {r['pitch_deg']:.0f}° | {r['hfov_deg']:.0f}° | "
                f"{r.get('detector', '-')} |")
        if charuco_columns:
            pose = (f"{r['pose_rot_deg']:.2f}°, {r['pose_t_mm']:.1f} mm" if "pose_rot_deg" in r else "")
            rms = f"{r['corner_rms_px']:.2f}" if "corner_rms_px" in r else ""
            head += f" {100 * r['hidden']:.0f} % | {r.get('corners', 0)}/{r['visible']} | {rms} | {pose} |"
        if "refused" in r:
            md.append(f"{head} refused: {r['refused']} | | | | | |")
        else:
            md.append(f"{head} {_pct(r['focal_err'])} | {100 * r['focal_unc']:.1f} % | {_pct(r['height_err'])} | "
                      f"{100 * r['floor_err_median']:.2f} % | {100 * r['floor_err_p95']:.2f} % | {r['rms_px']:.2f} |")
    return md


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=24, help="synthetic checkerboard photos (default 24)")
    parser.add_argument("--charuco-count", type=int, default=12,
                        help="synthetic ChArUco scenes, each whole and 40 %% hidden (default 12)")
    args = parser.parse_args()

    with Renderer() as renderer:
        syn = synthetic(args.count, renderer)
        ch = charuco(args.charuco_count, renderer)
    summary = summarize(syn)
    md = ["## Synthetic photos, checkerboard, single view (no EXIF)", ""] + _synthetic_table(syn)
    md += [""] + _summary_lines(summary) + [""]

    ch_summary = {f"hidden_{100 * h:.0f}": summarize([r for r in ch if r["hidden"] == h]) for h in (0.0, HIDDEN)}
    md += ["## Synthetic photos, ChArUco board (7x5, DICT_4X4_50), whole and 40 % hidden", ""]
    md += _synthetic_table(ch, charuco_columns=True) + [""]
    for key, s in ch_summary.items():
        posed = [r for r in ch if r["hidden"] == float(key.split("_")[1]) / 100 and "pose_rot_deg" in r]
        md += [f"**{key.replace('_', ' ')} %**: " + " ".join(_summary_lines(s))]
        if posed:
            md[-1] += (f" Pose with the true focal length ({len(posed)} photos): rotation error max "
                       f"{max(r['pose_rot_deg'] for r in posed):.2f}°, translation error max "
                       f"{max(r['pose_t_mm'] for r in posed):.1f} mm.")
        md += [""]

    profile, rows = real()
    real_summary = summarize(rows)
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
    md += [""] + _summary_lines(real_summary, floor=False)
    print("\n".join(md))
    results_io.write("calibration", {"machine": results_io.machine(), "synthetic": syn, "synthetic_summary": summary,
                                     "charuco": ch, "charuco_summary": ch_summary, "profile": profile, "real": rows,
                                     "real_summary": real_summary}, md)


if __name__ == "__main__":
    main()
