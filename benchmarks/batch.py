"""Batch runs on Ray against one process: photos per core-hour, memory, driver overhead.

Run by hand: ``python benchmarks/batch.py [--photos 16] [--big 6] [--long 200]`` (about
25 minutes on a 2-core machine). Writes ``results/batch.{json,md}``.

In one run, on the same photos (the four sample photos, copied under new names; at
1280x960 and upscaled to 4000x3000 = 12 MP), four suggestions each:
* ``loop``: one ``stage furnish PHOTO`` command per photo, one after the other (what a
  shell loop does: a new process, floor model and GL context per photo);
* ``one process``: one ``stage furnish P1 P2 ...`` (one process, one floor model, one GL
  context, the photos in turn);
* ``batch``: ``stage batch`` with two Ray workers on this machine (:func:`augment.app.batch.run_batch`,
  in this process, so that its driver time is measured), Ray's start included.
Throughput is photos over wall time; per core-hour divides by this machine's cores. Then
a long batch (``--long`` photos, one suggestion each to keep it short) reads each
worker's resident memory after every photo from ``results.jsonl``: it must not grow.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

import results_io  # noqa: E402

from augment.app.batch import RESULTS, run_batch  # noqa: E402

SAMPLES = ROOT / "samples" / "photos"
STAGE = str(Path(sys.executable).with_name("stage"))
SIZES = {"1280x960": None, "12 MP": (4000, 3000)}
TARGET_SPEEDUP = 1.8
WORKERS = 2


def make_photos(folder: Path, count: int, size) -> list[Path]:
    folder.mkdir(parents=True)
    photos = []
    for i in range(count):
        source = SAMPLES / f"room_{i % 4 + 1}.jpg"
        path = folder / f"photo_{i:03d}.jpg"
        if size is None:
            shutil.copyfile(source, path)
        else:
            image = cv2.resize(cv2.imread(str(source)), size, interpolation=cv2.INTER_CUBIC)
            cv2.imwrite(str(path), image, [cv2.IMWRITE_JPEG_QUALITY, 92])
        photos.append(path)
    return photos


def defaults(suggestions: int) -> dict:
    return {"board": (7, 5, "chessboard"), "square": 45.0, "room": None, "spec": None, "camera": None,
            "suggestions": suggestions, "seed": 0, "style": None, "auto_doors": True}


CPU_S = []  # the CPU seconds (user + system) of each command timed


def timed(command: list[str]) -> float:
    """Wall seconds of ``command``; its CPU seconds go to ``CPU_S``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    CPU_S.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    if done.returncode not in (0, 2):
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
    return seconds


def throughput(work: Path, label: str, size, count: int) -> dict:
    photos = make_photos(work / label / "in", count, size)
    row = {"photos": count}
    # Warm numba's cache and the OS's file cache first: no mode pays the first compile.
    timed([STAGE, "furnish", str(photos[0]), "-n", "1", "-q", "--out", str(work / label / "warm")])
    row["loop_s"] = sum(timed([STAGE, "furnish", str(p), "-q", "--out", str(work / label / "loop" / p.stem)])
                        for p in photos)
    row["one_process_s"] = timed([STAGE, "furnish", *map(str, photos), "-q", "--out", str(work / label / "one")])
    # How many cores the one process keeps busy on average: what two workers can gain over it.
    row["one_process_cores_used"] = CPU_S[-1] / row["one_process_s"]
    summary = run_batch(photos[0].parent, work / label / "batch", defaults(4), workers=WORKERS)
    assert summary.done == count, summary
    row["batch_s"] = summary.seconds
    row["driver_ms_per_photo"] = 1000 * summary.driver_s / count
    cores = os.cpu_count() or 1
    for mode in ("loop", "one_process", "batch"):
        row[f"{mode}_per_core_hour"] = count / (row[f"{mode}_s"] / 3600) / cores
    row["speedup_vs_one_process"] = row["one_process_s"] / row["batch_s"]
    row["speedup_vs_loop"] = row["loop_s"] / row["batch_s"]
    lines = [json.loads(line) for line in (work / label / "batch" / RESULTS).read_text().splitlines()]
    row["worker_s_median"] = statistics.median(r["seconds"] for r in lines)
    # Steady state, start-up left out: the batch's photos per second once each worker has
    # finished one, against the one process's own seconds per photo (its reports).
    ends = sorted(r["run_s"] for r in lines)
    row["batch_steady_s_per_photo"] = (ends[-1] - ends[WORKERS - 1]) / (count - WORKERS)
    row["one_process_s_per_photo"] = statistics.median(
        json.loads((work / label / "one" / p.stem / "report.json").read_text())["timings_s"]["total"] for p in photos)
    row["steady_speedup_vs_one_process"] = row["one_process_s_per_photo"] / row["batch_steady_s_per_photo"]
    return row


def memory(work: Path, count: int) -> dict:
    photos = make_photos(work / "long" / "in", count, None)
    summary = run_batch(photos[0].parent, work / "long" / "out", defaults(1), workers=WORKERS)
    lines = [json.loads(line) for line in (work / "long" / "out" / RESULTS).read_text().splitlines()]
    by_worker = {}
    for r in lines:
        by_worker.setdefault(r["worker"], []).append(r["worker_mb"])
    per_worker = {}
    for worker, mb in by_worker.items():
        early, late = mb[25:45], mb[-20:]
        per_worker[worker] = {"photos": len(mb), "mb_after_10": mb[min(9, len(mb) - 1)], "mb_last": mb[-1],
                              "median_mb_photos_26_45": statistics.median(early or mb),
                              "median_mb_last_20": statistics.median(late),
                              "max_mb": max(mb)}
    return {"photos": count, "done": summary.done, "seconds": summary.seconds,
            "driver_ms_per_photo": 1000 * summary.driver_s / count, "workers": per_worker}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--photos", type=int, default=16, help="photos per mode at 1280x960")
    parser.add_argument("--big", type=int, default=6, help="photos per mode at 12 MP")
    parser.add_argument("--long", type=int, default=200, help="photos of the memory run (0: none)")
    args = parser.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="stager-batch-bench-"))
    try:
        rows = {"1280x960": throughput(work, "small", None, args.photos),
                "12 MP": throughput(work, "big", SIZES["12 MP"], args.big)}
        for label, row in rows.items():
            print(label, json.dumps(row), flush=True)
        mem = memory(work, args.long) if args.long else None
    finally:
        shutil.rmtree(work, ignore_errors=True)
    small, big = rows["1280x960"], rows["12 MP"]
    md = ["# Batch runs on Ray: `python benchmarks/batch.py`", "",
          f"{os.cpu_count()} cores; four suggestions per photo; the same photos in each mode, in one run; "
          "the loop and the one process are `stage furnish` commands, the batch `stage batch` with "
          f"{WORKERS} Ray workers on this machine (Ray's start included).", "",
          "| photos | mode | wall s | photos per core-hour | batch speed-up |", "|---|---|---|---|---|"]
    for label, row in rows.items():
        for mode, name in (("loop", "loop of `stage furnish`"), ("one_process", "one `stage furnish`, all photos"),
                           ("batch", f"`stage batch`, {WORKERS} workers")):
            speed = "" if mode == "batch" else f"{row[f'{mode}_s'] / row['batch_s']:.2f}x"
            md.append(f"| {label}, {row['photos']} | {name} | {row[f'{mode}_s']:.1f} | "
                      f"{row[f'{mode}_per_core_hour']:.0f} | {speed} |")
    md += ["", f"Target: batch at least {TARGET_SPEEDUP}x one process: "
           f"{small['speedup_vs_one_process']:.2f}x at 1280x960, {big['speedup_vs_one_process']:.2f}x at 12 MP, "
           "Ray's and the workers' start included. In steady state (the batch's seconds per photo after each "
           "worker's first, against the one process's own seconds per photo from its reports): "
           f"{small['one_process_s_per_photo']:.2f} s against {small['batch_steady_s_per_photo']:.2f} s, "
           f"{small['steady_speedup_vs_one_process']:.2f}x at 1280x960; {big['one_process_s_per_photo']:.2f} s "
           f"against {big['batch_steady_s_per_photo']:.2f} s, {big['steady_speedup_vs_one_process']:.2f}x at 12 MP.",
           f"The one process keeps {small['one_process_cores_used']:.2f} cores busy on average at 1280x960 "
           f"({big['one_process_cores_used']:.2f} at 12 MP: onnxruntime, numba's parallel loops, Mesa's "
           f"threads, a second thread for plans): two single-threaded workers on {os.cpu_count()} cores can gain "
           f"at most about {os.cpu_count() / small['one_process_cores_used']:.2f}x over it.",
           f"Driver's own time per photo (reading the photo, handing it out, writing its folder): "
           f"{small['driver_ms_per_photo']:.0f} ms at 1280x960, {big['driver_ms_per_photo']:.0f} ms at 12 MP "
           "(target under 50 ms).", ""]
    if mem is not None:
        md += [f"## Memory: {mem['photos']} photos at 1280x960, one suggestion each, {WORKERS} workers "
               f"({mem['seconds']:.0f} s)", "",
               "| worker | photos | MB after 10 | median MB, photos 26-45 | median MB, last 20 | max MB |",
               "|---|---|---|---|---|---|"]
        for worker, w in mem["workers"].items():
            md.append(f"| {worker} | {w['photos']} | {w['mb_after_10']:.0f} | {w['median_mb_photos_26_45']:.0f} | "
                      f"{w['median_mb_last_20']:.0f} | {w['max_mb']:.0f} |")
        md.append("")
    per_hour = {label: row["batch_per_core_hour"] for label, row in rows.items()}
    md += ["## Cores for 10,000 photos an hour", ""]
    for label, rate in per_hour.items():
        md.append(f"* {label}: {rate:.0f} photos per core-hour in `stage batch` here, so 10,000 photos an hour "
                  f"need about {10000 / rate:.0f} cores of this kind (plus the driver, "
                  f"{rows[label]['driver_ms_per_photo']:.0f} ms a photo: "
                  f"{10000 * rows[label]['driver_ms_per_photo'] / 1000 / 3600:.2f} of a core).")
    data = {"machine": results_io.machine(workers=WORKERS), "throughput": rows, "memory": mem}
    paths = results_io.write("batch", data, md)
    print("\n".join(md))
    print(f"wrote {paths[0]} and {paths[1]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
