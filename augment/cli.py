"""The ``stage`` command: the image side of Stager (photo in, staged images out).

::

    stage board [--paper A3|A4] [--board 7x5] [--square MM] [--out board.pdf] [--quiet]
    stage calibrate SHOT... [--board 7x5] [--square 45] [--out profile.json] [--quiet]
    stage check PHOTO [--board 7x5] [--square 45] [--camera profile.json] [--out DIR] [--quiet]

``board`` writes the checkerboard to print; ``calibrate`` makes a camera profile from
several photos of it (any angle, e.g. held up or on a table); ``check`` calibrates one
photo of the board lying on the floor and draws the result over it. The later
``measure`` and ``furnish`` commands build on ``check``.

Exit status: 0 success, 2 bad input (one ``error:`` line on stderr saying what and
where, and what would work), 1 an unexpected failure (a bug: the traceback is printed).
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from layout.command import EXIT_OK, Parser, dispatch, parse

from .board import DEFAULT_INNER_CORNERS, DEFAULT_PAPER, DEFAULT_SQUARE_MM, PAPER_MM

PHOTO_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".webp", ".bmp")
DEFAULT_PROFILE = "profile.json"
DEFAULT_BOARD_PDF = "board.pdf"


class StageError(Exception):
    """Bad input: the message names the file, flag or value and says what would work."""


def parse_board(text: str) -> tuple[int, int]:
    """``"7x5"`` -> ``(7, 5)``: inner corners per row and per column."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    counting = ("it counts inner corners, where four squares meet, not squares: "
                "a board of 8 x 6 squares is --board 7x5")
    if match is None:
        raise argparse.ArgumentTypeError(f"{text!r} is not COLSxROWS like 7x5; {counting}")
    cols, rows = int(match[1]), int(match[2])
    if cols < 2 or rows < 2:
        raise argparse.ArgumentTypeError(f"{text!r}: needs at least 2x2 inner corners; {counting}")
    return cols, rows


def _square_mm(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < 1000:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected the side of one printed square in millimeters, e.g. {DEFAULT_SQUARE_MM:g}")
    return value


def _paper(text: str) -> str:
    key = text.upper()
    if key not in PAPER_MM:
        raise argparse.ArgumentTypeError(f"{text!r}: choose one of {', '.join(sorted(PAPER_MM))}")
    return key


def _add_board_args(p, square_help=None):
    p.add_argument("--board", type=parse_board, default=DEFAULT_INNER_CORNERS, metavar="COLSxROWS",
                   help="inner corners per row and column, where four squares meet (default %dx%d: "
                        "a board of 8 x 6 squares)" % DEFAULT_INNER_CORNERS)
    p.add_argument("--square", type=_square_mm, default=None, metavar="MM",
                   help=square_help or f"side of one printed square, millimeters (default {DEFAULT_SQUARE_MM:g}); "
                                       "measure the print")


def _parser():
    p = Parser(prog="stage", description="Furnish a photo of an empty room: print a checkerboard, lay it "
                                          "on the floor, photograph the room. Layout synthesis alone: see "
                                          "`layout --help`.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)

    b = sub.add_parser("board", help="write the checkerboard to print (PDF)",
                       description="Write the checkerboard as a one-page PDF at exact scale, with a 100 mm "
                                   "ruler to check the print. Print it at actual size (100 %%, no 'fit to "
                                   "page') and lay it flat on the floor.")
    b.add_argument("--paper", type=_paper, default=DEFAULT_PAPER,
                   help=f"A3 or A4, used landscape (default {DEFAULT_PAPER})")
    _add_board_args(b, square_help="side of one square, millimeters (default 45 on A3, 30 on A4)")
    b.add_argument("--out", "-o", type=Path, default=Path(DEFAULT_BOARD_PDF), metavar="FILE.pdf",
                   help=f"the PDF to write (default {DEFAULT_BOARD_PDF}; its folder is created)")
    b.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    c = sub.add_parser("calibrate", help="camera profile from several photos of the board",
                       description="Make a camera profile (focal length, principal point, lens distortion) "
                                   "from several photos of the board taken with one camera in one mode "
                                   "(same zoom and resolution): 10-20 shots from different angles and "
                                   "distances, the board filling much of the frame. Pass it to `stage check "
                                   "--camera`. Photos where the board is not found are skipped.")
    c.add_argument("shots", type=Path, nargs="+", metavar="SHOT",
                   help="photos of the board, or folders of them")
    _add_board_args(c)
    c.add_argument("--out", "-o", type=Path, default=Path(DEFAULT_PROFILE), metavar="FILE.json",
                   help=f"the profile to write (default {DEFAULT_PROFILE} in the current folder; "
                        "its folder is created)")
    c.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    k = sub.add_parser("check", help="calibrate one photo of the room and draw the calibration over it",
                       description="Calibrate PHOTO (the board lying flat on the floor): focal length from "
                                   "--camera, else the photo's EXIF, else the board itself; then the camera's "
                                   "pose and height above the floor. Writes DIR/calibration.json and "
                                   "DIR/overlay_calibration.png (corners, floor axes, a 1 m floor grid, the "
                                   "horizon).")
    k.add_argument("photo", type=Path, metavar="PHOTO")
    _add_board_args(k)
    k.add_argument("--camera", type=Path, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate` (most accurate focal length)")
    k.add_argument("--out", "-o", type=Path, default=None, metavar="DIR",
                   help="output folder (default out/<photo name>; created)")
    k.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")
    return p


def _board(args, square_default=DEFAULT_SQUARE_MM):
    from .board import Board

    cols, rows = args.board
    square = square_default if args.square is None else args.square
    try:
        return Board(cols, rows, square)
    except ValueError as error:
        raise StageError(str(error)) from None


def _prepare_file_out(out: Path, example: str) -> None:
    """Refuse an output file path that cannot be one, before any work is done."""
    if out.is_dir():
        raise StageError(f"--out {out}: is a folder; give a file name, e.g. {out / example}")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise StageError(f"--out {out}: {parent} is a file, not a folder")
            break


def _prepare_dir_out(out: Path) -> None:
    if out.exists() and not out.is_dir():
        raise StageError(f"--out {out}: exists and is not a folder; give a folder for the outputs")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise StageError(f"--out {out}: {parent} is a file, not a folder")
            break


def _mkdir(folder: Path, flag: str, shown: Path) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise StageError(f"{flag} {shown}: cannot create folder {folder} ({error.strerror or error})") from None


def _write(path: Path, data, flag: str, shown: Path) -> None:
    from layout.fileio import write_atomic

    try:
        write_atomic(path, data)
    except OSError as error:
        raise StageError(f"{flag} {shown}: cannot write {path} ({error.strerror or error}); "
                         "choose a folder you can write to") from None


def _board_cmd(args):
    from .printable import DEFAULT_SQUARE_BY_PAPER_MM, board_for_paper, write_board_pdf

    _prepare_file_out(args.out, DEFAULT_BOARD_PDF)
    cols, rows = args.board
    try:
        board = board_for_paper(args.paper, cols, rows, args.square)
    except ValueError as error:
        square = DEFAULT_SQUARE_BY_PAPER_MM[args.paper] if args.square is None else args.square
        raise StageError(f"--paper {args.paper} --board {cols}x{rows} --square {square:g}: {error}") from None
    _mkdir(args.out.parent, "--out", args.out)
    try:
        write_board_pdf(args.out, board, args.paper)
    except OSError as error:
        raise StageError(f"--out {args.out}: cannot write it ({error.strerror or error}); "
                         "choose a folder you can write to") from None
    if not args.quiet:
        print(f"wrote {args.out}: {board.cols}x{board.rows} inner corners ({board.cols + 1} x {board.rows + 1} "
              f"squares of {board.square_mm:g} mm) on {args.paper}")
        print(f"print at actual size (100 %, no 'fit to page'), check the 100 mm ruler, then use "
              f"--board {board.cols}x{board.rows} --square {board.square_mm:g}")
    return EXIT_OK


def _expand_shots(paths: list[Path]) -> list[Path]:
    shots = []
    for path in paths:
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.suffix.lower() in PHOTO_SUFFIXES and p.is_file())
            if not found:
                raise StageError(f"folder {path} holds no photos ({', '.join(PHOTO_SUFFIXES)})")
            shots += found
        else:
            shots.append(path)
    return shots


def _calibrate_cmd(args):
    from .calibrate import camera_profile

    board = _board(args)
    _prepare_file_out(args.out, DEFAULT_PROFILE)
    shots = _expand_shots(args.shots)
    profile = camera_profile(shots, board)
    _mkdir(args.out.parent, "--out", args.out)
    _write(args.out, json.dumps(profile, indent=2) + "\n", "--out", args.out)
    if args.quiet:
        return EXIT_OK
    K = profile["K"]
    w, h = profile["size_px"]
    used, skipped = profile["images"], profile["skipped"]
    per_view = profile["per_view_rms_px"]
    worst = max(range(len(per_view)), key=per_view.__getitem__)
    k1, k2, p1, p2, k3 = (profile["distortion"] + [0.0] * 5)[:5]
    print(f"images      {len(used)} used, {len(skipped)} skipped"
          + (f" (no {board.cols}x{board.rows} board found): {', '.join(skipped)}" if skipped else ""))
    print(f"size        {w} x {h} px")
    sigma = profile.get("focal_uncertainty") or 0.0
    print(f"focal       fx {K[0][0]:.2f}  fy {K[1][1]:.2f} px"
          + (f"  (\u00b1 {100 * sigma:.2f} %)" if sigma > 0 else ""))
    print(f"center      cx {K[0][2]:.2f}  cy {K[1][2]:.2f} px")
    print(f"distortion  k1 {k1:.4f}  k2 {k2:.4f}  p1 {p1:.5f}  p2 {p2:.5f}  k3 {k3:.4f}")
    print(f"RMS         {profile['rms_px']:.3f} px  (worst {used[worst]}: {per_view[worst]:.3f} px)")
    print(f"wrote {args.out}; use it with `stage check PHOTO --camera {args.out}`")
    return EXIT_OK


def _check_cmd(args):
    import cv2

    from .calibrate import calibrate_file, read_photo
    from .overlay import calibration_overlay

    board = _board(args)
    out = args.out if args.out is not None else Path("out") / args.photo.stem
    _prepare_dir_out(out)
    if args.camera is not None and args.photo.is_file() and not args.camera.is_file():
        raise StageError(f"--camera {args.camera}: no such file; make a camera profile with "
                         f"`stage calibrate SHOT... --out {args.camera}`")
    calibration = calibrate_file(args.photo, board, profile=args.camera)
    overlay = calibration_overlay(read_photo(args.photo), calibration)
    report = {"photo": str(args.photo), **calibration.to_json()}
    text = json.dumps(report, indent=2) + "\n"
    ok, png = cv2.imencode(".png", cv2.cvtColor(overlay, cv2.COLOR_RGB2BGR))
    if not ok:
        raise RuntimeError("OpenCV could not encode the overlay as PNG")
    # Everything is computed: only now is anything written.
    _mkdir(out, "--out", out)
    paths = (out / "calibration.json", out / "overlay_calibration.png")
    _write(paths[0], text, "--out", out)
    try:
        _write(paths[1], png.tobytes(), "--out", out)
    except StageError:
        paths[0].unlink(missing_ok=True)  # no half-written result: the pair or nothing
        raise
    if args.quiet:
        return EXIT_OK
    i = calibration.intrinsics
    w, h = calibration.size_px
    print(f"photo       {args.photo}: {w} x {h} px, {board.cols}x{board.rows} board found "
          f"({calibration.detector} detector)")
    print(f"focal       {i.K[0, 0]:.1f} px \u00b1 {100 * i.focal_uncertainty:.1f} % from {i.source}"
          + (f" ({i.note})" if i.note else ""))
    print(f"camera      {calibration.camera_height_m:.3f} m above the floor")
    print(f"RMS         {calibration.rms_px:.3f} px (board corners reprojected)")
    for warning in calibration.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {paths[0]} and {paths[1]}")
    return EXIT_OK


def main(argv=None) -> int:
    """Run the command line; returns the exit status."""
    parser = _parser()
    args = parse(parser, argv)
    if isinstance(args, int):
        return args
    if args.command is None:
        parser.print_help()
        return EXIT_OK
    from .calibrate import CalibrationError

    commands = {"board": _board_cmd, "calibrate": _calibrate_cmd, "check": _check_cmd}
    return dispatch(commands[args.command], args, "stage", [((StageError, CalibrationError), str)])


if __name__ == "__main__":
    sys.exit(main())
