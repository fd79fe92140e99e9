"""``python -m augment.synth``: write a dataset of synthetic room photos with ground truth.

Image ``i`` of a run is rendered from seed ``[SEED, i]``, so any image can be re-made on
its own and the output does not depend on ``--workers``.

Examples
--------
python -m augment.synth --count 20000 --seed 0 --out data/synth --size 320x240
python -m augment.synth --count 16 --seed 7 --out out/synth --sheet docs/synth_sheet.png
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path

import cv2
from tqdm import tqdm

from layout.fileio import write_atomic

from ..camera.board import DEFAULT_BOARD, DEFAULT_INNER_CORNERS, DEFAULT_SQUARE_MM, Board, parse_board
from .dataset import contact_sheet, init_worker, render_one, truth_view
from .rooms import BASEBOARD_M


def _parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--size {text!r}: expected WIDTHxHEIGHT in pixels, e.g. 640x480")
    if not (64 <= w <= 8192 and 64 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"--size {text!r}: each side must be 64-8192 pixels")
    return w, h


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m augment.synth", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, required=True, help="number of images")
    parser.add_argument("--seed", type=int, default=0, help="dataset seed (default 0)")
    parser.add_argument("--out", type=Path, required=True, help="output folder (created)")
    parser.add_argument("--size", type=_parse_size, default=None,
                        help="WIDTHxHEIGHT; default: random phone sizes 640x480-2016x1512, landscape and portrait")
    parser.add_argument("--board", type=parse_board, default=DEFAULT_BOARD,
                        help="inner corners COLSxROWS (default %dx%d), or charuco:COLSxROWS for a ChArUco "
                             "board" % DEFAULT_INNER_CORNERS)
    parser.add_argument("--square", type=float, default=DEFAULT_SQUARE_MM,
                        help=f"square size in mm (default {DEFAULT_SQUARE_MM:g})")
    parser.add_argument("--no-clutter", dest="clutter", action="store_false", help="keep floors clean")
    parser.add_argument("--furnished", type=float, default=0.0, metavar="P",
                        help="chance that a room gets 1-6 pieces of furniture (default 0: empty rooms)")
    parser.add_argument("--baseboard-m", type=float, nargs=2, default=BASEBOARD_M, metavar=("LOW", "HIGH"),
                        help="range of the baseboards' height, meters (default %g %g; real ones reach 0.2)"
                             % BASEBOARD_M)
    parser.add_argument("--trim-like-floor", type=float, default=0.0, metavar="P",
                        help="chance that a room's baseboards and frames are painted the floor's colour "
                             "(default 0; the skirting check's hardest boards)")
    parser.add_argument("--trim-dark", type=float, default=0.0, metavar="P",
                        help="chance that they are painted a dark colour instead (default 0)")
    parser.add_argument("--low-sun", type=float, default=0.0, metavar="P",
                        help="chance of a low, strong sun through a window onto the floor in view (default 0)")
    parser.add_argument("--two-floors", type=float, default=0.0, metavar="P",
                        help="chance that part of the floor is of a second material, past a straight or "
                             "stepped threshold (default 0)")
    parser.add_argument("--far-floor", type=float, default=0.0, metavar="P",
                        help="of those, the chance that the second floor is a strip along a wall, mostly the "
                             "one the camera faces (default 0)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                        help="render processes (default: one per core)")
    parser.add_argument("--sheet", type=Path, default=None,
                        help="also write a contact sheet PNG of the first 16 images here, and beside it "
                             "NAME_truth.png with their floor masks and board corners drawn on")
    parser.add_argument("--quiet", action="store_true", help="print only errors")
    args = parser.parse_args(argv)
    if args.count < 1:
        parser.error(f"--count {args.count}: must be at least 1")
    if args.square <= 0:
        parser.error(f"--square {args.square}: must be a positive size in millimeters, e.g. 50")
    if not 0.0 <= args.furnished <= 1.0:
        parser.error(f"--furnished {args.furnished}: must be a chance between 0 and 1, e.g. 0.7")
    if not 0.0 <= args.trim_like_floor <= 1.0:
        parser.error(f"--trim-like-floor {args.trim_like_floor}: must be a chance between 0 and 1, e.g. 0.5")
    for flag, value in (("--trim-dark", args.trim_dark), ("--low-sun", args.low_sun),
                        ("--two-floors", args.two_floors), ("--far-floor", args.far_floor)):
        if not 0.0 <= value <= 1.0:
            parser.error(f"{flag} {value}: must be a chance between 0 and 1, e.g. 0.5")
    low, high = args.baseboard_m
    if not 0.0 < low <= high <= 0.5:
        parser.error(f"--baseboard-m {low:g} {high:g}: give a low and a high height in meters, "
                     "0 < low <= high <= 0.5, e.g. 0.1 0.2")
    try:
        args.out.mkdir(parents=True, exist_ok=True)
        probe = args.out / ".write_test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as error:
        print(f"error: cannot write to --out {args.out}: {error.strerror}", file=sys.stderr)
        return 2

    options = dict(seed=args.seed, size=args.size, out=args.out, clutter=args.clutter, furnished=args.furnished,
                   baseboard_m=(low, high), trim_like_floor=args.trim_like_floor,
                   trim_dark=args.trim_dark, low_sun=args.low_sun, two_floors=args.two_floors,
                   far_floor=args.far_floor,
                   board=Board(args.board.cols, args.board.rows, args.square, kind=args.board.kind))
    workers = max(1, min(args.workers, args.count))
    start = time.perf_counter()
    bar = tqdm(total=args.count, unit="img", disable=args.quiet or not sys.stderr.isatty())
    if workers == 1:
        init_worker(options)
        for i in range(args.count):
            render_one(i)
            bar.update()
    else:
        # spawn: a forked child would share the parent's GL and llvmpipe threads.
        with mp.get_context("spawn").Pool(workers, initializer=init_worker, initargs=(options,)) as pool:
            for _ in pool.imap_unordered(render_one, range(args.count)):
                bar.update()
    bar.close()
    seconds = time.perf_counter() - start
    if args.sheet is not None:
        stems = [f"{i:05d}" for i in range(min(16, args.count))]
        args.sheet.parent.mkdir(parents=True, exist_ok=True)
        truth_path = args.sheet.with_name(args.sheet.stem + "_truth.png")
        for path, images in ((args.sheet, [cv2.imread(str(args.out / f"{s}.jpg")) for s in stems]),
                             (truth_path, [truth_view(args.out, s) for s in stems])):
            ok, png = cv2.imencode(".png", contact_sheet(images))
            write_atomic(path, png.tobytes())
    if not args.quiet:
        print(f"wrote {args.count} images to {args.out}/ in {seconds:.1f} s "
              f"({args.count / seconds:.1f} images/s, {workers} worker{'s' if workers > 1 else ''})"
              + (f"; contact sheet {args.sheet}" if args.sheet else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
