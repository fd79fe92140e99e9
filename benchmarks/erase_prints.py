"""The board erased from prints as users make them: paper, margins, marks, shadows, floors.

Run by hand: ``python benchmarks/erase_prints.py [--count 40] [--seed 9300] [--size 1280x960]``
(a few minutes). Prints a row per case and writes ``results/erase_prints.{json,md}``,
``results/erase_prints_worst.png``, ``results/erase_prints_real.png`` and
``results/erase_prints_real_shadow.png``.

Each case (:func:`augment.synth.prints.pasted_board`, seeds ``[--seed, i]``) is a print on
white, off-white or cream paper, with the A3 sheet's margin or trimmed to the squares,
with ``stage board``'s ruler and caption or without, Stager's chessboard, its ChArUco
board or OpenCV's 9x6 chessboard, on carpet, planks, laminate, tiles or concrete, half of
them under a shadow's edge, blurred, noisy and saved as JPEG like a phone photo; and the
same floor without it. The photo is calibrated from the board with the true focal length
(as EXIF gives it) and the board erased with the drawn floor as the floor mask. Scored by
:func:`augment.synth.prints.erasure_scores`: light, contrast, seam and bright spots
against the floor that was there, each with its limit. Then the same print on the real
floors of ``samples/real`` (pasted by :func:`augment.synth.prints.paste_print`), erased on
the floor the model finds; and again with the photo and its truth under a shadow's edge
across the print.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from results_io import RESULTS, machine, write  # noqa: E402

from augment.camera.board import Board  # noqa: E402
from augment.camera.calibrate import calibrate_photo, exif_intrinsics  # noqa: E402
from augment.errors import CalibrationError  # noqa: E402
from augment.render.erase import erase_board  # noqa: E402
from augment.synth.prints import CONTRAST_RANGE, LIGHT_MAX, SEAM_MAX, SPOT_LEVELS, erasure_scores, pasted_board  # noqa: E402,E501
from layout.fileio import write_atomic  # noqa: E402


def crop(images, sheet_px, pad=30, size=(260, 195)):
    x0, y0 = np.floor(sheet_px.min(axis=0)).astype(int) - pad
    x1, y1 = np.ceil(sheet_px.max(axis=0)).astype(int) + pad
    h, w = images[0].shape[:2]
    x0, y0, x1, y1 = max(0, x0), max(0, y0), min(w, x1), min(h, y1)
    return np.hstack([cv2.resize(im[y0:y1, x0:x1], size, interpolation=cv2.INTER_AREA) for im in images])


def under_a_shadow(image: np.ndarray, K: np.ndarray, camera_from_floor: np.ndarray, angle_rad: float,
                   offset_m: float = 0.03, width_m: float = 0.008, depth: float = 0.5) -> np.ndarray:
    """``image`` with a straight shadow's soft edge on the floor (a window frame's): in
    linear light, the floor beyond the line at ``angle_rad`` passing ``offset_m`` from the
    board's middle darkened by ``depth``, over a logistic width ``width_m``."""
    h, w = image.shape[:2]
    floor_from_pixels = np.linalg.inv(K @ camera_from_floor[:3][:, [0, 1, 3]])
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    q = floor_from_pixels @ np.stack([u.ravel(), v.ravel(), np.ones(u.size)])
    seen = q[2] > 1e-9
    along = (np.cos(angle_rad) * q[0] + np.sin(angle_rad) * q[1]) / np.where(seen, q[2], 1.0) - offset_m
    shade = 1.0 - depth / (1.0 + np.exp(-np.clip(along / width_m, -50, 50)))
    factor = np.where(seen, shade, 1.0).reshape(h, w) ** (1 / 2.2)
    return np.clip(image * factor[..., None] + 0.5, 0, 255).astype(np.uint8)


def real_floors(shadow: bool) -> tuple[list, np.ndarray]:
    """The print pasted on the four real photos of ``samples/real`` (where their camera would
    have seen it, as ``before_after.py`` does), erased on the floor the model finds: their
    scores against the photo without it, and a picture (photo, erased, truth per row).
    ``shadow``: the photo and the truth both under a shadow's edge across the print (a
    different direction on each photo)."""
    import json

    from augment.floor.model import DEFAULT_MODEL, FloorModel
    from augment.floor.segment import segment_floor
    from augment.photo.io import read_photo
    from augment.synth.prints import PastedBoard, paste_planned

    real = Path(__file__).resolve().parent.parent / "samples" / "real"
    model = FloorModel(DEFAULT_MODEL)
    rows, pictures = [], []
    for k, (name, room) in enumerate(json.loads((real / "rooms.json").read_text()).items()):
        truth = read_photo(real / f"{name}.jpg")
        photo, K, pose, sheet_px = paste_planned(truth, room)
        if shadow:
            angle = np.radians(25.0 + 45.0 * k)
            photo, truth = (under_a_shadow(im, K, pose, angle) for im in (photo, truth))
        cal = calibrate_photo(photo, Board(), intrinsics=exif_intrinsics(room["focal_px"], truth.shape[1::-1]))
        mask = segment_floor(photo, calibration=cal, model=model).mask
        erased = erase_board(photo, cal, mask)
        case = PastedBoard(photo, truth, K, pose, Board(), mask, sheet_px, {})
        rows.append({"photo": name, **erasure_scores(case, erased.image)})
        pictures.append(crop([photo, erased.image, truth], sheet_px))
    return rows, np.vstack(pictures)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--seed", type=int, default=9300)
    parser.add_argument("--size", default="1280x960")
    args = parser.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    rows, pictures = [], []
    for i in range(args.count):
        case = pasted_board(np.random.default_rng([args.seed, i]), size)
        row = {"case": i, **case.case}
        try:
            cal = calibrate_photo(case.photo, case.board, intrinsics=exif_intrinsics(case.K[0, 0], size))
        except CalibrationError:
            rows.append({**row, "calibrated": False})
            print(f"{i:3d} {case.case}: not calibrated", flush=True)
            continue
        start = time.perf_counter()
        erased = erase_board(case.photo, cal, case.floor_mask)
        row.update(calibrated=True, ms=1000 * (time.perf_counter() - start), **erasure_scores(case, erased.image))
        rows.append(row)
        pictures.append((row, crop([case.photo, erased.image, case.truth], case.sheet_px)))
        print(f"{i:3d} {row['paper']:9s} {row['margin']:5s} {'marks' if row['marks'] else '     '} "
              f"{row['pattern']:7s} {row['floor']:8s} {'shadow' if row['shadow'] else '      '}  light "
              f"{row['light']:4.1f} contrast {row['contrast']:.2f} seam {row['seam']:.2f} spots {row['spots']}"
              f"  {'ok' if row['ok'] else 'NOT OK'}  {row['ms']:.0f} ms", flush=True)

    done = [r for r in rows if r["calibrated"]]
    ok = [r for r in done if r["ok"]]

    def share(key, value):
        subset = [r for r in done if r[key] == value]
        return f"{sum(r['ok'] for r in subset)}/{len(subset)}"

    summary = {"cases": len(rows), "calibrated": len(done), "ok": len(ok),
               "light_median": float(np.median([r["light"] for r in done])),
               "light_p90": float(np.percentile([r["light"] for r in done], 90)),
               "with_spots": sum(r["spots"] > 0 for r in done),
               "ms_median": float(np.median([r["ms"] for r in done]))}
    lines = ["# The board erased from prints as users make them", "",
             f"{len(done)} of {len(rows)} cases calibrated (seed {args.seed}, {size[0]}x{size[1]}); "
             f"**{len(ok)} of {len(done)} within every limit**. Limits: light (erased against the floor that was "
             f"there, both blurred over a third of the sheet's size) at most {LIGHT_MAX:g} levels; local contrast "
             f"{CONTRAST_RANGE[0]:g}-{CONTRAST_RANGE[1]:g} of the floor's; edges along the sheet's outline at most "
             f"{SEAM_MAX:g} of the floor's; no speck of 3 px or more {SPOT_LEVELS:g} levels brighter than its "
             f"surround and {SPOT_LEVELS / 2:g} than the floor's brightest.", "",
             f"light median {summary['light_median']:.1f}, 90th percentile {summary['light_p90']:.1f} levels; "
             f"cases with a bright spot: {summary['with_spots']}; erasure median {summary['ms_median']:.0f} ms.", "",
             "| within limits, by | |", "|---|---|"]
    for key, values in (("paper", ("white", "off-white", "cream")), ("margin", ("sheet", "none")),
                        ("marks", (True, False)), ("pattern", ("stager", "charuco", "opencv")),
                        ("floor", ("carpet", "wood", "laminate", "tiles", "concrete")), ("shadow", (True, False))):
        lines.append(f"| {key} | " + ", ".join(f"{v}: {share(key, v)}" for v in values) + " |")
    real, picture = real_floors(shadow=False)
    shaded, shaded_picture = real_floors(shadow=True)
    for title, found in (
            ("**Real floors** (`samples/real`: the print pasted where each photo's camera would have seen it, "
             "erased on the floor the model finds; `erase_prints_real.png`: photo, erased, truth):", real),
            ("**Real floors under a shadow's edge** (the same, photo and truth darkened to half the light, in linear "
             "light, beyond a soft straight line across the print, 3 cm from its middle, at 25, 70, 115 and 160 "
             "degrees to the board; `erase_prints_real_shadow.png`):", shaded)):
        lines += ["", title, "", "| photo | light | contrast | seam | spots | within limits |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {r['photo']} | {r['light']:.1f} | {r['contrast']:.2f} | {r['seam']:.2f} | {r['spots']} | "
                  f"{'yes' if r['ok'] else 'no'} |" for r in found]
    for image, name in ((picture, "erase_prints_real.png"), (shaded_picture, "erase_prints_real_shadow.png")):
        ok_png, data = cv2.imencode(".png", cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
        write_atomic(RESULTS / name, data.tobytes())
    lines += ["", "Not calibrated: " + (", ".join(f"{r['case']} ({r['pattern']})" for r in rows if not r["calibrated"])
                                        or "none"), "",
              "`erase_prints_worst.png`: the six worst by light, each the photo, the erased photo and the truth."]
    print("\n".join(lines))
    worst = sorted(pictures, key=lambda p: -p[0]["light"] - 100 * (not p[0]["ok"]))[:6]
    if worst:
        sheet = np.vstack([p[1] for p in worst])
        ok_png, data = cv2.imencode(".png", cv2.cvtColor(sheet, cv2.COLOR_RGB2BGR))
        write_atomic(RESULTS / "erase_prints_worst.png", data.tobytes())
    write("erase_prints", {"machine": machine(seed=args.seed, count=args.count), "summary": summary, "cases": rows,
                           "real": real, "real_shadow": shaded},
          lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
