"""The ``stage`` command: the image side of Stager (photo in, staged images out).

::

    stage board [--paper A3|A4] [--board 7x5|charuco:7x5] [--square MM] [--out board.pdf] [--quiet]
    stage calibrate SHOT... [--board 7x5] [--square 45] [--out profile.json] [--quiet]
    stage check PHOTO [--board 7x5] [--square 45] [--camera profile.json] [--out DIR] [--quiet]
    stage segment PHOTO [--model M.onnx] [--method onnx|grabcut] [--board ...] [--out MASK.png] [--quiet]
    stage measure PHOTO [--board 7x5] [--square 45] [--camera profile.json] [--out DIR] [--quiet]
    stage furnish PHOTO... [--board 7x5] [--square 45] [--room NAME | --spec FILE | --layout FILE] [-n 4]
                  [--seed 0] [--camera profile.json] [--model M.onnx] [--asset KIND=FILE ...]
                  [--style NAME] [--layers] [--out DIR] [--quiet]
    stage batch INPUT --out DIR [--room NAME | --spec FILE] [-n 4] [--style NAME] [--address ADDR]
                [--workers N] [--retries 2] [--quiet]
    stage serve [--host 127.0.0.1] [--port 8000] [--workers N] [--jobs DIR] [--address ADDR]

``--board`` counts inner corners, ``COLSxROWS`` for a plain checkerboard (the default
7x5), ``charuco:COLSxROWS`` for a ChArUco board (ArUco markers of DICT_4X4_50 in the
white squares), which still calibrates when part of it is hidden or out of the frame.

``board`` writes the board to print; ``calibrate`` makes a camera profile from
several photos of it (any angle, e.g. held up or on a table); ``check`` calibrates one
photo of the board lying on the floor and draws the result over it; ``segment`` finds
the floor (mask, overlay, and the floor polygon in meters when the board is found);
``measure`` does both and measures the wall height: "measure my room" without furniture;
``furnish`` goes on to lay out furniture (a room preset, default living_room, or a spec
file) on the measured floor and renders each suggestion into the photo
(:mod:`augment.pipeline` lists the files it writes); ``batch`` does it for a folder or
manifest of photos on Ray workers (:mod:`augment.app.batch`); ``serve`` runs the web app
(:mod:`augment.app.web`) that does what ``furnish`` does from a browser.

Exit status: 0 success, 2 bad input (one ``error:`` line on stderr saying what and
where, and what would work: an unreadable photo, no board, no floor, a floor too small
for any furniture, an output folder that cannot be written, an invalid spec file), 1 an
unexpected failure (a bug: the traceback is printed), 130 interrupted. ``measure`` and
``furnish`` write their files only when everything is done, all or none: a failure
leaves the output folder as it was.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
from pathlib import Path

from layout.command import EXIT_INPUT, EXIT_OK, Parser, arg_type, dispatch, parse, path_arg, seed_arg
from layout.command import run as run_command
from layout.errors import StagerError, UsageError
from layout.fileio import path_problem
from layout.presets import PRESETS

from ..camera.board import (CHARUCO_DICTIONARY, DEFAULT_BOARD, DEFAULT_INNER_CORNERS, DEFAULT_PAPER, DEFAULT_SQUARE_MM,
                            PAPER_MM, parse_board)
from ..render.styles import STYLES
from .values import count as _count
from .values import height_m as _height_m
from .values import square_mm as _square_mm
from .values import whole as _whole

DEFAULT_PROFILE = "profile.json"
DEFAULT_BOARD_PDF = "board.pdf"


def _paper(text: str) -> str:
    key = text.upper()
    if key not in PAPER_MM:
        raise argparse.ArgumentTypeError(f"{text!r}: choose one of {', '.join(sorted(PAPER_MM))}")
    return key


def _finite_numbers(text: str, count: int, usage: str) -> tuple[float, ...]:
    """``count`` finite numbers separated by commas, else a usage error saying ``usage``."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: give {usage}")
    return values


def _click(text: str) -> tuple[float, float]:
    """``X,Y`` of ``--floor-at`` and ``--not-floor-at``."""
    return _finite_numbers(text, 2, "X,Y, a pixel of the photo (0,0 at its top left), e.g. 640,900")


def _door(text: str) -> tuple[float, float, float, float]:
    """``X1,Y1,X2,Y2`` of ``--door``."""
    return _finite_numbers(text, 4, "X1,Y1,X2,Y2, the photo pixels of the feet of the door's two sides (where "
                                    "they meet the floor), e.g. 980,220,1190,280")


class _ClickAction(argparse.Action):
    """Both click flags add to one list, in the order given: a later click wins."""

    def __call__(self, parser, namespace, values, option_string=None):
        clicks = list(getattr(namespace, self.dest) or [])
        clicks.append((*values, 1.0 if self.const else 0.0))
        setattr(namespace, self.dest, clicks)


def _add_click_args(p) -> None:
    """--floor-at and --not-floor-at: the user's corrections of the floor found."""
    p.add_argument("--floor-at", dest="clicks", action=_ClickAction, const=True, type=_click, default=None,
                   metavar="X,Y", help="a pixel of floor the floor found left out (repeat for more; x,y in the "
                                       "photo's pixels, as in the floor overlay): its region of that colour "
                                       "becomes floor")
    p.add_argument("--not-floor-at", dest="clicks", action=_ClickAction, const=False, type=_click,
                   metavar="X,Y", help="a pixel of something taken for floor (a carton, a wall's foot): its "
                                       "region of that colour is not floor. Clicks apply in order, a later "
                                       "one winning where two overlap")


def _add_floor_args(p) -> None:
    """--model or --floor-mask: where the floor comes from; clicks correct the first."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--model", type=path_arg, default=None, metavar="MODEL.onnx",
                       help="floor model (default: Stager's models/floor_segnet.onnx, with its MODEL.json)")
    where.add_argument("--floor-mask", type=path_arg, default=None, metavar="MASK.png",
                       help="your own floor mask (white = floor), used instead of finding the floor: the "
                            "floor.png `stage segment` wrote, corrected in an image editor")
    _add_click_args(p)


def _add_height_arg(p) -> None:
    p.add_argument("--height", type=_height_m, default=None, metavar="M",
                   help="the wall height in meters, used when the photo does not show it (the ceiling out of "
                        "view; default: 2.5, or the top of a door in view if higher)")


def _click_flag(click) -> str:
    """A click as it was given on the command line, e.g. ``--floor-at 640,900``."""
    x, y, is_floor = click
    return f"{'--floor-at' if is_floor else '--not-floor-at'} {x:g},{y:g}"


def _check_clicks_with_mask(args) -> None:
    """Clicks correct the floor Stager finds; a user's mask is taken as it is."""
    if args.clicks and args.floor_mask is not None:
        raise UsageError(f"{_click_flag(args.clicks[0])}: clicks correct the floor Stager finds, and "
                         f"--floor-mask {args.floor_mask} is used as it is; paint the correction into the mask, "
                         "or leave --floor-mask out")


def _add_board_args(p, square_help=None):
    p.add_argument("--board", type=arg_type(parse_board), default=DEFAULT_BOARD, metavar="[charuco:]COLSxROWS",
                   help="inner corners per row and column, where four squares meet (default %dx%d: "
                        "a checkerboard of 8 x 6 squares); charuco:COLSxROWS for a ChArUco board, "
                        "which may be partly hidden" % DEFAULT_INNER_CORNERS)
    p.add_argument("--square", type=_square_mm, default=None, metavar="MM",
                   help=square_help or f"side of one printed square, millimeters (default {DEFAULT_SQUARE_MM:g}); "
                                       "measure the print")


def _parser():
    p = Parser(prog="stage", description="Furnish a photo of an empty room: print a checkerboard, lay it "
                                          "on the floor, photograph the room. Layout synthesis alone: see "
                                          "`layout --help`.")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)

    b = sub.add_parser("board", help="write the board to print (PDF)",
                       description="Write the board as a one-page PDF at exact scale, with a 100 mm ruler "
                                   "to check the print and the --board/--square values (and a ChArUco "
                                   "board's marker dictionary) in the margin. Print it at actual size "
                                   "(100 %, no 'fit to page') and lay it flat on the floor. "
                                   "--board charuco:7x5 prints a ChArUco board.")
    b.add_argument("--paper", type=_paper, default=DEFAULT_PAPER,
                   help=f"A3 or A4, used landscape (default {DEFAULT_PAPER})")
    _add_board_args(b, square_help="side of one square, millimeters (default 45 on A3, 30 on A4)")
    b.add_argument("--out", "-o", type=path_arg, default=Path(DEFAULT_BOARD_PDF), metavar="FILE.pdf",
                   help=f"the PDF to write (default {DEFAULT_BOARD_PDF}; its folder is created)")
    b.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    c = sub.add_parser("calibrate", help="camera profile from several photos of the board",
                       description="Make a camera profile (focal length, principal point, lens distortion) "
                                   "from several photos of the board taken with one camera in one mode "
                                   "(same zoom and resolution): 10-20 shots from different angles and "
                                   "distances, the board filling much of the frame. Pass it to `stage check "
                                   "--camera`. Photos where the board is not found, and files that are not "
                                   "photos Stager reads (named, with why), are skipped.")
    c.add_argument("shots", type=path_arg, nargs="+", metavar="SHOT",
                   help="photos of the board, or folders of them")
    _add_board_args(c)
    c.add_argument("--out", "-o", type=path_arg, default=Path(DEFAULT_PROFILE), metavar="FILE.json",
                   help=f"the profile to write (default {DEFAULT_PROFILE} in the current folder; "
                        "its folder is created)")
    c.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    k = sub.add_parser("check", help="calibrate one photo of the room and draw the calibration over it",
                       description="Calibrate PHOTO (the board lying flat on the floor): focal length from "
                                   "--camera, else the photo's EXIF, else the board itself; then the camera's "
                                   "pose and height above the floor. Writes DIR/calibration.json and "
                                   "DIR/overlay_calibration.png (corners, floor axes, a 1 m floor grid, the "
                                   "horizon).")
    k.add_argument("photo", type=path_arg, metavar="PHOTO")
    _add_board_args(k)
    k.add_argument("--camera", type=path_arg, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate` (most accurate focal length)")
    k.add_argument("--out", "-o", type=path_arg, default=None, metavar="DIR",
                   help="output folder (default out/<photo name>; created)")
    k.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    g = sub.add_parser("segment", help="find the floor: mask, overlay and floor polygon",
                       description="Find the floor in PHOTO with the floor model refined by GrabCut (or GrabCut "
                                   "alone). Writes MASK.png (255 = floor, the photo's size), MASK_overlay.png "
                                   "and, when the board is found, MASK.json with the floor polygon in meters.")
    g.add_argument("photo", type=path_arg, metavar="PHOTO")
    _add_board_args(g)
    g.add_argument("--camera", type=path_arg, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate`")
    g.add_argument("--method", choices=("onnx", "grabcut"), default="onnx",
                   help="onnx: the model, refined by GrabCut (default); grabcut: GrabCut alone, seeded "
                        "from the board and the horizon (needs the board)")
    g.add_argument("--no-refine", dest="refine", action="store_false",
                   help="take the model's mask as it is, without GrabCut")
    _add_click_args(g)
    g.add_argument("--model", type=path_arg, default=None, metavar="MODEL.onnx",
                   help="an ONNX segmentation model (default: Stager's models/floor_segnet.onnx). Its "
                        "input and classes are read from MODEL.json beside it, else these options:")
    g.add_argument("--input-size", type=_size_px, default=None, metavar="WxH",
                   help="fixed model input size (default: long side 256, sides multiples of 32)")
    g.add_argument("--mean", type=_triple, default=None, metavar="R,G,B",
                   help="input mean after scaling to 0..1 (default 0.485,0.456,0.406)")
    g.add_argument("--std", type=_triple, default=None, metavar="R,G,B",
                   help="input standard deviation (default 0.229,0.224,0.225)")
    g.add_argument("--channel-order", choices=("RGB", "BGR"), default=None)
    g.add_argument("--floor-class", type=_classes, default=None, metavar="K[,K...]",
                   help="output class(es) meaning floor, e.g. 2 for a SUN RGB-D 37-class model, 3,28 "
                        "for ADE20K's floor and rug (default 1)")
    g.add_argument("--output-kind", dest="output", choices=("logits", "probabilities"), default=None,
                   help="whether the model's output needs a softmax (default logits)")
    g.add_argument("--out", "-o", type=path_arg, default=None, metavar="MASK.png",
                   help="the mask to write (default out/<photo name>/floor.png; folder created)")
    g.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    m = sub.add_parser("measure", help="measure the room: camera, floor polygon and wall height",
                       description="Calibrate PHOTO from the board, find the floor and its polygon, and "
                                   "measure the wall height from vertical edges. Writes DIR/report.json and "
                                   "the three overlays overlay_calibration.png, overlay_floor.png, "
                                   "overlay_height.png.")
    m.add_argument("photo", type=path_arg, metavar="PHOTO")
    _add_board_args(m)
    m.add_argument("--camera", type=path_arg, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate`")
    _add_floor_args(m)
    _add_height_arg(m)
    m.add_argument("--out", "-o", type=path_arg, default=None, metavar="DIR",
                   help="output folder (default out/<photo name>; created)")
    m.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")

    f = sub.add_parser("furnish", help="furnish the photo: staged images of several layout suggestions",
                       description="Calibrate PHOTO from the board, find the floor, measure the walls, lay out "
                                   "furniture on the floor in view (a room preset, or the items of a spec file) "
                                   "and render each suggestion into the photo. Writes to DIR: staged_K.jpg, "
                                   "staged_all.jpg (contact sheet), layout_K.json, plan_K.png, energy.png, "
                                   "scene_K.glb (glTF: floor, walls, furniture), overlay_calibration.png, "
                                   "overlay_floor.png, overlay_height.png and report.json.")
    f.add_argument("photo", type=path_arg, nargs="+", metavar="PHOTO",
                   help="the photo; with several, each one's files go to DIR/<photo name>/ and one process "
                        "(one GL context, one floor model) furnishes them all")
    _add_board_args(f)
    what = f.add_mutually_exclusive_group()
    what.add_argument("--room", choices=tuple(PRESETS), default=None, metavar="NAME",
                      help=f"room preset: {', '.join(PRESETS)} (default living_room); the furniture is "
                           "chosen for the floor's area")
    what.add_argument("--spec", type=path_arg, default=None, metavar="FILE.toml",
                      help="a layout spec (see `layout solve`): its items, groups and constraints on the "
                           "measured floor (its own room, doors and windows are not used)")
    what.add_argument("--layout", type=path_arg, default=None, metavar="LAYOUT.json",
                      help="render a layout_K.json made before for this photo again as it stands, with its "
                           "designs, e.g. in another --style (default out: out/<photo name>_<layout name>"
                           "[_<style>])")
    f.add_argument("--suggestions", "-n", type=_count, default=None, metavar="N",
                   help="number of layout suggestions (default 4)")
    f.add_argument("--seed", type=seed_arg, default=0, help="seed of suggestion 1; K uses seed + K - 1 (default 0)")
    f.add_argument("--camera", type=path_arg, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate`")
    _add_floor_args(f)
    _add_height_arg(f)
    f.add_argument("--door", type=_door, action="append", default=[], metavar="X1,Y1,X2,Y2",
                   help="a door to keep clear: the photo pixels of the feet of its two sides, where they "
                        "meet the floor (as in the floor overlay); its swing zone, as deep as the door is "
                        "wide, stays free of furniture. Repeat for more doors. Without it, the doors "
                        "found in the photo are kept clear")
    f.add_argument("--no-auto-doors", dest="auto_doors", action="store_false",
                   help="do not look for doors or windows in the photo (keep clear only the doors given "
                        "with --door)")
    f.add_argument("--asset", type=_asset, action="append", default=[], metavar="KIND=FILE",
                   help="your own model of a furniture kind (GLB, glTF or OBJ; y up, front toward +z), "
                        "stretched onto each item of that kind; repeat for more kinds "
                        "(e.g. --asset sofa=models/my_sofa.glb)")
    f.add_argument("--layers", action="store_true",
                   help="also write staged_K_layer.png: what suggestion K adds to the photo (furniture, "
                        "shadows and the floor over the board) as RGBA, to composite by hand")
    f.add_argument("--style", choices=tuple(STYLES), default=None, metavar="NAME",
                   help=f"the furniture's look: {', '.join(STYLES)}; by default each suggestion takes "
                        "another, so that they look different")
    f.add_argument("--keep-board", action="store_true",
                   help="leave the board in the staged photos (by default its sheet is filled with the floor "
                        "around it)")
    f.add_argument("--out", "-o", type=path_arg, default=None, metavar="DIR",
                   help="output folder (default out/<photo name>; created)")
    f.add_argument("--quiet", "-q", action="store_true",
                   help="print nothing but errors and warnings (no progress bar either)")

    a = sub.add_parser("batch", help="furnish a folder or manifest of photos on Ray (this machine or a cluster)",
                       description="Furnish every photo of INPUT (a folder of photos, or a manifest: CSV with a "
                                   "header line, or JSONL, with the fields photo and optionally board, square, "
                                   "room, spec, camera, suggestions, seed, style per photo; paths from the "
                                   "manifest's folder) on Ray workers, one per core, each with its own floor "
                                   "model and GL context. Each photo's files go to DIR/<photo name>/ as `stage "
                                   "furnish` writes them, all or none; DIR/results.jsonl gets one line per "
                                   "photo as it finishes. Run it again on the same DIR to go on after an "
                                   "interruption: photos done are skipped.")
    a.add_argument("input", type=path_arg, metavar="INPUT", help="a folder of photos, or a .csv / .jsonl manifest")
    a.add_argument("--out", "-o", type=path_arg, required=True, metavar="DIR", help="output folder (created)")
    _add_board_args(a)
    what = a.add_mutually_exclusive_group()
    what.add_argument("--room", choices=tuple(PRESETS), default=None, metavar="NAME",
                      help=f"room preset: {', '.join(PRESETS)} (default living_room)")
    what.add_argument("--spec", type=path_arg, default=None, metavar="FILE.toml", help="a layout spec")
    a.add_argument("--suggestions", "-n", type=_count, default=4, metavar="N",
                   help="layout suggestions per photo (default 4)")
    a.add_argument("--seed", type=seed_arg, default=0, help="seed of suggestion 1 (default 0)")
    a.add_argument("--style", choices=tuple(STYLES), default=None, metavar="NAME",
                   help=f"the furniture's look: {', '.join(STYLES)} (default: a different one per suggestion)")
    a.add_argument("--camera", type=path_arg, default=None, metavar="PROFILE.json",
                   help="camera profile from `stage calibrate`, for every photo")
    _add_height_arg(a)
    a.add_argument("--no-auto-doors", dest="auto_doors", action="store_false",
                   help="do not look for doors or windows in the photos")
    a.add_argument("--address", default=None, metavar="ADDRESS",
                   help="a Ray cluster to run on: host:port or ray://host:port (as `ray start --head` prints), "
                        "or auto; default: a Ray of this machine's own, started and stopped by Stager")
    a.add_argument("--workers", type=_count, default=None, metavar="N",
                   help="workers, one photo at a time each (default one per CPU of the cluster)")
    a.add_argument("--retries", type=lambda t: _whole(t, 0, 10), default=2, metavar="N",
                   help="times a photo is tried again when its worker dies under it (default 2)")
    a.add_argument("--worker-memory", type=lambda t: _whole(t, 256, 1_000_000, ", e.g. 4096"), default=4096,
                   metavar="MB", help="a worker using more memory than this after a photo is replaced (default "
                                      "4096)")
    a.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors (no progress bar)")

    s = sub.add_parser("serve", help="run the web app: upload a photo in a browser, get staged images",
                       description="Serve the web page and its API (augment.app.web; OpenAPI page at /docs) until "
                                   "interrupted. Photos are furnished in worker processes; finished jobs and "
                                   "their files are deleted after an hour.")
    s.add_argument("--host", default="127.0.0.1",
                   help="address to listen on (default 127.0.0.1: this machine only; 0.0.0.0 for all)")
    s.add_argument("--port", type=_port, default=8000, help="port (default 8000)")
    s.add_argument("--workers", type=_count, default=None, metavar="N",
                   help="worker processes, each furnishing one photo at a time (default one per core)")
    s.add_argument("--address", default=None, metavar="ADDRESS",
                   help="furnish on this Ray cluster's workers (host:port or ray://host:port, as `ray start "
                        "--head` prints, or auto) instead of worker processes of this machine; --workers then "
                        "defaults to one per CPU of the cluster")
    s.add_argument("--jobs", type=path_arg, default=Path("out") / "jobs", metavar="DIR",
                   help="folder for uploads and results (default out/jobs; created)")
    return p


def _port(text: str) -> int:
    return _whole(text, 1, 65535, ", e.g. 8000")


def _size_px(text: str) -> tuple[int, int]:
    from ..floor.model import MAX_INPUT_PX

    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if match is None or not all(16 <= int(v) <= MAX_INPUT_PX for v in match.groups()):
        raise argparse.ArgumentTypeError(f"{text!r}: expected WIDTHxHEIGHT in pixels, each from 16 to "
                                         f"{MAX_INPUT_PX}, e.g. 320x240")
    return int(match[2]), int(match[1])  # (rows, cols)


def _triple(text: str) -> tuple[float, float, float]:
    return _finite_numbers(text, 3, "three numbers R,G,B, e.g. 0.485,0.456,0.406")


def _classes(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(v) for v in text.split(","))
    except ValueError:
        values = ()
    if not values or min(values) < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected class indices like 2 or 3,28")
    return values


def _board(args, square_default=DEFAULT_SQUARE_MM):
    from ..camera.board import Board

    cols, rows, kind = args.board
    square = square_default if args.square is None else args.square
    try:
        return Board(cols, rows, square, kind=kind)
    except ValueError as error:
        raise UsageError(str(error)) from None


def _prepare_file_out(out: Path, example: str) -> None:
    """Refuse an output file path that cannot be one (a folder, a name whose suffix is not
    ``example``'s), before any work is done."""
    if out.is_dir():
        raise UsageError(f"--out {out}: is a folder; give a file name, e.g. {out / example}")
    suffix = Path(example).suffix
    if out.suffix.lower() != suffix:
        # A PDF written to board.txt opens as text; a mask named floor.jpg would be a PNG.
        raise UsageError(f"--out {out}: it is written as {suffix[1:].upper()}; give a name ending in {suffix}, "
                         f"e.g. {out.with_suffix(suffix) if out.name else example}")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise UsageError(f"--out {out}: {parent} is a file, not a folder")
            break


def _prepare_dir_out(out: Path, flag: str = "--out") -> None:
    """Refuse an output folder that cannot be one (:func:`layout.fileio.folder_problem`),
    before any work is done."""
    from layout.fileio import folder_problem

    if (problem := folder_problem(out)) is not None:
        raise UsageError(f"{flag} {out}: {problem}")


def _mkdir(folder: Path, flag: str, shown: Path) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"{flag} {shown}: cannot create folder {folder} ({error.strerror or error})") from None


def _write(path: Path, data, flag: str, shown: Path) -> None:
    from layout.fileio import write_atomic

    try:
        write_atomic(path, data)
    except OSError as error:
        raise UsageError(f"{flag} {shown}: cannot write {path} ({error.strerror or error}); "
                         "choose a folder you can write to") from None


def _board_cmd(args):
    from ..camera.printable import (
        DEFAULT_SQUARE_BY_PAPER_MM,
        board_for_paper,
        write_board_pdf,
    )

    _prepare_file_out(args.out, DEFAULT_BOARD_PDF)
    cols, rows, kind = args.board
    try:
        board = board_for_paper(args.paper, cols, rows, args.square, kind)
    except ValueError as error:
        square = DEFAULT_SQUARE_BY_PAPER_MM[args.paper] if args.square is None else args.square
        spec = f"{cols}x{rows}" if kind == "chessboard" else f"{kind}:{cols}x{rows}"
        raise UsageError(f"--paper {args.paper} --board {spec} --square {square:g}: {error}") from None
    _mkdir(args.out.parent, "--out", args.out)
    try:
        write_board_pdf(args.out, board, args.paper)
    except OSError as error:
        raise UsageError(f"--out {args.out}: cannot write it ({error.strerror or error}); "
                         "choose a folder you can write to") from None
    if not args.quiet:
        what = "checkerboard" if board.kind == "chessboard" else f"ChArUco board (markers {CHARUCO_DICTIONARY})"
        print(f"wrote {args.out}: {what}, {board.cols}x{board.rows} inner corners "
              f"({board.cols + 1} x {board.rows + 1} squares of {board.square_mm:g} mm) on {args.paper}")
        print(f"print at actual size (100 %, no 'fit to page'), check the 100 mm ruler, then use "
              f"--board {board.spec} --square {board.square_mm:g}")
    return EXIT_OK


def _expand_shots(paths: list[Path]) -> list[Path]:
    from ..photo.io import PHOTO_SUFFIXES

    shots = []
    for path in paths:
        if path_problem(path, "folder") is None:
            found = sorted(p for p in path.iterdir() if p.suffix.lower() in PHOTO_SUFFIXES and p.is_file())
            if not found:
                raise UsageError(f"folder {path} holds no photos ({', '.join(PHOTO_SUFFIXES)})")
            shots += found
        else:
            shots.append(path)
    return shots


def _calibrate_cmd(args):
    from ..camera.calibrate import camera_profile

    board = _board(args)
    _prepare_file_out(args.out, DEFAULT_PROFILE)
    shots = _expand_shots(args.shots)
    _keep_inputs([args.out], shots)
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
          + (f" (no {board.describe()} found): {', '.join(skipped)}" if skipped else "")
          + (f"; counted once: {', '.join(profile['repeated'])}" if profile["repeated"] else "")
          + (f"; not read: {', '.join(profile['unreadable'])}" if profile["unreadable"] else ""))
    print(f"size        {w} x {h} px")
    sigma = profile.get("focal_uncertainty") or 0.0
    print(f"focal       fx {K[0][0]:.2f}  fy {K[1][1]:.2f} px"
          + (f"  (\u00b1 {100 * sigma:.2f} %)" if sigma > 0 else ""))
    print(f"center      cx {K[0][2]:.2f}  cy {K[1][2]:.2f} px")
    print(f"distortion  k1 {k1:.4f}  k2 {k2:.4f}  p1 {p1:.5f}  p2 {p2:.5f}  k3 {k3:.4f}")
    print(f"RMS         {profile['rms_px']:.3f} px  (worst {used[worst]}: {per_view[worst]:.3f} px)")
    print(f"wrote {args.out}; use it with `stage check PHOTO --camera {args.out}`")
    return EXIT_OK


def _check_floor_mask(path) -> None:
    """A ``--floor-mask`` that is not there is named before any work is done."""
    if path is not None and (problem := path_problem(path, missing="no such file")) is not None:
        raise UsageError(f"--floor-mask {path}: {problem}; give the floor.png `stage segment` wrote "
                         "(white = floor), corrected by hand")


def _check_camera(args) -> None:
    """A ``--camera`` profile that is not there is named before any work is done."""
    if path_problem(args.photo) is None:
        _check_input_file("--camera", args.camera, CAMERA_HINT)


CAMERA_HINT = "make a camera profile with `stage calibrate`"


def _check_input_file(flag: str, path: Path | None, hint: str) -> None:
    """Refuse an input file named by ``flag`` (``"--asset sofa="`` joins its path) that is
    not one, saying what it is instead."""
    if path is not None and (what := path_problem(path, missing="no such file", folder="is a folder")) is not None:
        raise UsageError(f"{flag}{'' if flag.endswith('=') else ' '}{path}: {what}; {hint}")


def _check_cmd(args):
    from ..camera.calibrate import calibrate_file
    from ..draw.calibration import calibration_overlay
    from ..photo.io import encode_image, read_photo

    board = _board(args)
    out = args.out if args.out is not None else Path("out") / args.photo.stem
    _prepare_dir_out(out)
    _check_camera(args)
    calibration = calibrate_file(args.photo, board, profile=args.camera)
    overlay = calibration_overlay(read_photo(args.photo), calibration)
    report = {"photo": str(args.photo), **calibration.to_json()}
    # Everything is computed: only now is anything written, the pair or nothing.
    paths = (out / "calibration.json", out / "overlay_calibration.png")
    _write_all({paths[0]: json.dumps(report, indent=2) + "\n", paths[1]: encode_image(overlay, ".png")}, out,
               [args.photo, args.camera])
    if args.quiet:
        return EXIT_OK
    i = calibration.intrinsics
    w, h = calibration.size_px
    seen = len(calibration.corner_ids)
    print(f"photo       {args.photo}: {w} x {h} px, {board.describe()} found ({calibration.detector} detector"
          + (f", {seen} of {board.corner_count} corners" if seen < board.corner_count else "") + ")")
    print(f"focal       {i.K[0, 0]:.1f} px \u00b1 {100 * i.focal_uncertainty:.1f} % from {i.source}"
          + (f" ({i.note})" if i.note else ""))
    print(f"camera      {calibration.camera_height_m:.3f} m above the floor")
    print(f"RMS         {calibration.rms_px:.3f} px (board corners reprojected)")
    for warning in calibration.warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {paths[0]} and {paths[1]}")
    return EXIT_OK


def _load_model(path, **spec_overrides):
    """The floor model at ``path`` (Stager's when None), its sidecar spec with the given
    fields replaced."""
    from dataclasses import replace

    from ..floor.model import DEFAULT_MODEL, FloorModel, ModelSpec

    path = path if path is not None else DEFAULT_MODEL
    if (problem := path_problem(path, missing="no such file")) is not None:
        hint = "use --method grabcut" if path != DEFAULT_MODEL else \
            "the repository's models/floor_segnet.onnx is missing; reinstall, or use --method grabcut"
        raise UsageError(f"--model {path}: {problem}; {hint}")
    sidecar = path.with_suffix(".json")
    spec = ModelSpec.from_json(sidecar) if sidecar.is_file() else ModelSpec()
    return FloorModel(path, spec=replace(spec, **spec_overrides))


def _segment_cmd(args):
    from ..camera.calibrate import calibrate_file
    from ..draw.floor import floor_overlay
    from ..errors import CalibrationError
    from ..floor.polygon import floor_polygon
    from ..floor.segment import segment_floor
    from ..photo.io import encode_image, read_photo

    board = _board(args)
    out = args.out if args.out is not None else Path("out") / args.photo.stem / "floor.png"
    _prepare_file_out(out, "floor.png")
    _check_camera(args)
    image = read_photo(args.photo)
    overrides = {k: getattr(args, k) for k in ("input_size", "mean", "std", "channel_order", "floor_class", "output")
                 if getattr(args, k) is not None}
    if args.method == "grabcut" and (args.model is not None or overrides):
        flag = "--model" if args.model is not None else "--" + next(iter(overrides)).replace("_", "-")
        raise UsageError(f"{flag}: no model is used with --method grabcut (GrabCut alone, seeded by the board); "
                         f"leave out one of the two")
    model = _load_model(args.model, **overrides) if args.method == "onnx" else None
    warnings = []
    try:
        calibration = calibrate_file(args.photo, board, profile=args.camera)
        warnings += calibration.warnings  # the polygon's meters rest on it
    except CalibrationError as error:
        if args.method == "grabcut":
            raise UsageError(f"--method grabcut needs the board to seed the floor: {error}") from None
        calibration = None
        warnings.append(f"no calibration ({error}); the floor is found without the board and horizon, "
                        "and no floor polygon is made")
    seg = segment_floor(image, model, calibration, method=args.method, refine=args.refine, clicks=args.clicks)
    warnings += seg.warnings
    polygon = None
    if calibration is not None and seg.mask.any():
        try:
            polygon = floor_polygon(seg.mask, calibration, seg.floor_clicks_px)
        except ValueError as error:
            warnings.append(f"no floor polygon: {error}")
    overlay = floor_overlay(image, seg.mask, polygon, calibration, seg.doubted, seg.clicks, seg.doubt_px)
    files = {out: encode_image(seg.mask.astype("uint8") * 255, ".png"),
             out.with_name(out.stem + "_overlay.png"): encode_image(overlay, ".png")}
    if polygon is not None:
        report = {"photo": str(args.photo), **seg.to_json(), "floor": polygon.to_json(), "warnings": warnings}
        files[out.with_suffix(".json")] = json.dumps(report, indent=2) + "\n"
    # Into a folder of the user's: each file replaced on its own.
    _write_all(files, out.parent, [args.photo, args.camera, args.model], whole=False)
    if not args.quiet:
        print(f"floor       {100 * seg.mask.mean():.1f} % of the photo ({seg.method})")
        if polygon is not None:
            print(f"polygon     {len(polygon.polygon_m)} corners, {polygon.area_m2:.2f} m\u00b2 visible")
            if polygon.caveat:
                print(f"note        {polygon.caveat}")
        print("wrote " + ", ".join(str(p) for p in files))
    _print_warnings(warnings, seg, f"edit {out} and give it to stage measure or furnish with --floor-mask")
    return EXIT_OK


def _height_state(height) -> str:
    """How the wall height was come by, as the summary line says it."""
    if not height.fallback:
        return f"confidence {height.confidence:.2f}"
    return "given with --height (the photo does not show it)" if height.given else "assumed (fallback)"


def _measure_cmd(args):
    from ..photo.io import encode_image
    from ..pipeline import measure, measure_report, overlays

    board = _board(args)
    out = args.out if args.out is not None else Path("out") / args.photo.stem
    _prepare_dir_out(out)
    _check_camera(args)
    _check_clicks_with_mask(args)
    if args.photo.is_file():
        _check_floor_mask(args.floor_mask)
    m = measure(args.photo, board, camera=args.camera, floor_mask=args.floor_mask, clicks=args.clicks,
                height_m=args.height,
                model=_load_model(args.model) if args.floor_mask is None else None)
    files = {out / "report.json": json.dumps(measure_report(m), indent=2) + "\n",
             **{out / name: encode_image(image, ".png") for name, image in overlays(m).items()}}
    _write_all(files, out, [args.photo, args.camera, args.model, args.floor_mask])
    if not args.quiet:
        calibration, polygon, height = m.calibration, m.floor, m.height
        i = calibration.intrinsics
        print(f"focal       {i.K[0, 0]:.1f} px \u00b1 {100 * i.focal_uncertainty:.1f} % from {i.source}")
        print(f"camera      {calibration.camera_height_m:.3f} m above the floor, RMS {calibration.rms_px:.2f} px")
        print(f"floor       {polygon.area_m2:.2f} m\u00b2 visible, {len(polygon.polygon_m)} corners "
              f"({m.segmentation.method})")
        if polygon.caveat:
            print(f"note        {polygon.caveat}")
        state = _height_state(height)
        print(f"walls       {height.height_m:.2f} m high, {state}")
        print(f"wrote {out}/report.json and overlay_calibration.png, overlay_floor.png, overlay_height.png")
    _print_warnings(m.warnings, m.segmentation,
                    "give a floor mask of your own with --floor-mask (stage segment writes one)")
    return EXIT_OK


def _asset(text: str) -> tuple[str, Path]:
    """``KIND=FILE`` of ``--asset``."""
    kind, sep, path = text.partition("=")
    if not sep or not kind.strip() or not path.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: give KIND=FILE, e.g. --asset sofa=models/my_sofa.glb")
    return kind.strip(), path_arg(path.strip())


def _furnish_cmd(args):
    from layout.solver import COMPILE_NOTE, compiled

    from ..pipeline import furnish, write_outputs

    photos = args.photo
    board = _board(args)
    batch = len(photos) > 1
    if args.layout is not None:
        if args.suggestions is not None:
            raise UsageError(f"--layout {args.layout}: it is one suggestion; leave --suggestions out")
        if batch:
            raise UsageError(f"--layout {args.layout}: a layout is of one photo; give one photo with it")
    suggestions = 4 if args.suggestions is None else args.suggestions
    if batch:
        stems = [p.stem for p in photos]
        twice = sorted({stem for stem in stems if stems.count(stem) > 1})
        if twice:
            raise UsageError(f"several photos are named {', '.join(twice)}: each photo's files go to "
                             "--out/<photo name>/; give them different names")
        parent = args.out if args.out is not None else Path("out")
        outs = [parent / p.stem for p in photos]
    elif args.out is None and args.layout is not None:
        # Beside the run that made the layout, not over it.
        outs = [Path("out") / "_".join([photos[0].stem, args.layout.stem] + ([args.style] if args.style else []))]
    else:
        outs = [args.out if args.out is not None else Path("out") / photos[0].stem]
    for out in outs:
        _prepare_dir_out(out)
        # The new folder is made beside out, which it then replaces: the folder above
        # must take it (out itself too, where an earlier run's files are left).
        resolved = out.resolve()
        for folder in ([resolved] if resolved.is_dir() else []) + [next(p for p in resolved.parents if p.exists())]:
            if not os.access(folder, os.W_OK | os.X_OK):
                raise UsageError(f"--out {out}: cannot write in {folder}; choose a folder you can write to")
    if batch and args.floor_mask is not None:
        raise UsageError(f"--floor-mask {args.floor_mask}: a mask is of one photo; give one photo with it, "
                         "or leave --floor-mask out to find each photo's floor")
    if batch and args.clicks:
        raise UsageError(f"{_click_flag(args.clicks[0])}: a click is on one photo; give one photo with it")
    if batch and args.door:
        raise UsageError(f"--door {','.join(f'{v:g}' for v in args.door[0])}: a door is in one photo; give one "
                         "photo with it")
    _check_clicks_with_mask(args)
    if any(p.is_file() for p in photos):
        _check_floor_mask(args.floor_mask)
        for flag, path, hint in (("--camera", args.camera, CAMERA_HINT),
                                 ("--model", args.model, "give an ONNX floor model, or leave --model out"),
                                 ("--spec", args.spec, "write one (see `layout solve --help`)"),
                                 ("--layout", args.layout, "give a layout_K.json that stage furnish wrote"),
                                 *((f"--asset {kind}=", path, "give a GLB, glTF or OBJ file")
                                   for kind, path in args.asset)):
            _check_input_file(flag, path, hint)
    kinds = [kind for kind, _ in args.asset]
    if len(set(kinds)) < len(kinds):
        twice = sorted({k for k in kinds if kinds.count(k) > 1})
        raise UsageError(f"--asset: {', '.join(twice)} given more than once; give one model per kind")
    shared = {}
    if batch:
        # Loaded once for every photo: the floor model's session and the GL context.
        from ..render.gl import Renderer

        shared = {"model": _load_model(args.model), "renderer": Renderer()}
    if not args.quiet and sys.stderr.isatty() and not compiled():  # said where a progress bar shows
        print(f"note: {COMPILE_NOTE}", file=sys.stderr)
    refused, uncertain = 0, []
    try:
        for photo, out in zip(photos, outs):
            try:
                result = furnish(photo, board, room=args.room, spec=args.spec, suggestions=suggestions,
                                 seed=args.seed, camera=args.camera, model=shared.get("model", args.model),
                                 floor_mask=args.floor_mask, clicks=args.clicks, doors=args.door,
                                 auto_doors=args.auto_doors, height_m=args.height,
                                 assets=dict(args.asset), layers=args.layers, keep_board=args.keep_board,
                                 style=args.style, layout=args.layout, renderer=shared.get("renderer"),
                                 progress=not args.quiet and sys.stderr.isatty())
                paths = write_outputs(result, out, inputs=[photo, args.floor_mask, args.spec, args.layout,
                                                            args.camera, args.model, *dict(args.asset).values()])
            except StagerError as error:
                if not batch:
                    raise
                print(f"error: {error}", file=sys.stderr)
                refused += 1
                continue
            _print_furnished(result, out, paths, args.quiet, photo if batch else None)
            if result.segmentation.uncertain:
                uncertain.append(photo.name)
    finally:
        if "renderer" in shared:
            shared["renderer"].close()
    if batch and not args.quiet:
        print(f"furnished {len(photos) - refused} of {len(photos)} photos into {parent}/"
              + (f"; {refused} refused (errors above)" if refused else ""))
        if uncertain:
            print(f"floor uncertain in {len(uncertain)} (check their overlay_floor.png; correct each "
                  f"with --floor-at / --not-floor-at or --floor-mask): {', '.join(uncertain)}")
    return EXIT_INPUT if refused else EXIT_OK


def _print_furnished(result, out: Path, paths: list, quiet: bool, photo: Path | None) -> None:
    """What ``stage furnish`` says of one photo; ``photo`` names it when there are several."""
    from ..room.fit import dropped_summary

    if not quiet:
        if photo is not None:
            print(f"== {photo}")
        cal, floor, height = result.calibration, result.floor, result.height
        i = cal.intrinsics
        print(f"camera      {cal.camera_height_m:.2f} m above the floor, focal {i.K[0, 0]:.0f} px from {i.source}, "
              f"RMS {cal.rms_px:.2f} px")
        print(f"floor       {floor.area_m2:.2f} m\u00b2 in view, {len(floor.polygon_m)} corners "
              f"({result.segmentation.method})")
        state = _height_state(height)
        print(f"walls       {result.room_height_m:.2f} m high, {state}")
        kinds = ", ".join(i.id for i in result.spec.items)
        print(f"furniture   {result.source}: {len(result.spec.items)} items ({kinds})")
        if result.dropped:
            print(f"left out    {dropped_summary(result.dropped)}")
        if result.erased is None:
            print("board       kept in the staged photos (--keep-board)")
        else:
            how = "floor copied from beside it" if len(result.erased.source_m) else "filled in smoothly"
            print(f"board       erased from the staged photos ({how})")
        print(f"{'K':>3} {'energy':>9} {'overlaps':>8} {'outside m²':>11} {'walkable':>8}  style")
        for k, (lay, rep, look) in enumerate(zip(result.layouts, result.reports, result.styles), start=1):
            print(f"{k:>3} {lay.energy:>9.4g} {rep['overlaps']['count']:>8d} {rep['outside_m2']:>11.3f} "
                  f"{'yes' if rep['traversable'] else 'no':>8}  {look}")
        t = result.timings_s
        print("time        " + ", ".join(f"{k} {v:.2f}" for k, v in t.items() if k != "total")
              + f"; total {t['total']:.1f} s")
        n = len(result.staged)
        print(f"staged      {out / 'staged_1.jpg'}" + (f" ... staged_{n}.jpg" if n > 1 else "")
              + f", side by side in {out / 'staged_all.jpg'}")
        print(f"wrote {len(paths)} files to {out}/")
    _print_warnings(result.warnings, result.segmentation,
                    "give a floor mask of your own with --floor-mask (stage segment writes one)",
                    "" if photo is None else f"{photo.name}: ")


def _print_warnings(warnings, seg, mask_hint: str, prefix: str = "") -> None:
    """The warnings, then, when the floor is uncertain, the flags that would correct it
    where it is in doubt (the web app says "click the overlay" instead)."""
    for warning in warnings:
        print(f"warning: {prefix}{warning}", file=sys.stderr)
    doubt = seg.doubt_json()
    if doubt is not None:
        # The click that would overrule the mask there.
        flag = _click_flag((doubt["x_px"], doubt["y_px"], not doubt["floor"]))
        print(f"hint: {prefix}where the floor is wrong, run again with {flag} "
              f"(and --floor-at / --not-floor-at X,Y elsewhere), or {mask_hint}", file=sys.stderr)


def _batch_cmd(args):
    from .batch import RESULTS, read_tasks, run_batch

    if path_problem(args.input, "folder") is not None:
        if (problem := path_problem(args.input, missing="no such file or folder")) is not None:
            raise UsageError(f"input {args.input}: {problem}; give a folder of photos or a .csv / .jsonl manifest")
        if args.input.suffix.lower() not in (".csv", ".jsonl"):
            raise UsageError(f"input {args.input}: not a folder, and a manifest's name ends in .csv or .jsonl")
    _prepare_dir_out(args.out)
    for flag, path, hint in (("--camera", args.camera, CAMERA_HINT),
                             ("--spec", args.spec, "write one (see `layout solve --help`)")):
        _check_input_file(flag, path, hint)
    board = _board(args)
    defaults = {"board": (board.cols, board.rows, board.kind), "square": board.square_mm, "room": args.room,
                "spec": args.spec, "camera": args.camera, "suggestions": args.suggestions, "seed": args.seed,
                "style": args.style, "auto_doors": args.auto_doors, "height": args.height}
    next(iter(read_tasks(args.input, defaults)), None)  # a manifest's columns checked before Ray starts
    _mkdir(args.out, "--out", args.out)
    say = (lambda line: None) if args.quiet else (lambda line: print(line, file=sys.stderr))
    summary = run_batch(args.input, args.out, defaults, address=args.address, workers=args.workers,
                        retries=args.retries, worker_mb=args.worker_memory,
                        progress=not args.quiet and sys.stderr.isatty(), say=say)
    results = args.out / RESULTS
    if summary.interrupted:
        print(f"stopped: {summary.done} photos done, {summary.left} left; run the same command again to go on "
              f"(photos done are skipped; each line of {results} says how a photo went)", file=sys.stderr)
        return 130
    if not args.quiet:
        finished = summary.done + summary.refused + summary.failed
        print(f"furnished {summary.done} of {finished + summary.skipped} photos into {args.out}/ in "
              f"{summary.seconds:.0f} s" + (f" ({summary.skipped} done before, skipped)" if summary.skipped else "")
              + (f"; {summary.refused} refused" if summary.refused else "")
              + (f"; {summary.failed} failed" if summary.failed else "") + f"; one line per photo in {results}")
    return 1 if summary.failed else EXIT_INPUT if summary.refused else EXIT_OK


def _serve_cmd(args):
    try:
        from .web import serve
    except ImportError as error:
        raise UsageError(f"the web app needs {error.name}: pip install fastapi uvicorn python-multipart") from None
    _prepare_dir_out(args.jobs, "--jobs")
    _check_listen(args.host, args.port)
    _mkdir(args.jobs, "--jobs", args.jobs)
    serve(args.host, args.port, workers=args.workers, jobs_dir=args.jobs, address=args.address)
    return EXIT_OK


def _check_listen(host: str, port: int) -> None:
    """Bind where the app will listen, and let go: an address in use, or not of this
    machine, is one error line here rather than uvicorn's log and exit status 3."""
    import socket

    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, proto) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as uvicorn binds
            probe.bind(address)
    except OSError as error:
        raise UsageError(f"--host {host} --port {port}: cannot listen there ({error.strerror or error}); choose "
                         "another port (e.g. --port 8001) or an address of this machine") from None


def _keep_inputs(outputs, inputs) -> None:
    """Refuse ``outputs`` (paths) of which one is one of the command's ``inputs``."""
    from layout.fileio import replaced_input

    if (clash := replaced_input(outputs, inputs)) is not None:
        raise UsageError(f"--out {clash[0]}: is the input {clash[1]}, which Stager never overwrites; "
                         "write the outputs to another file or folder")


def _write_all(files: dict, folder: Path, inputs, whole: bool = True) -> None:
    """Write ``files`` ({path in ``folder``: bytes or text}) all or none: made beside
    ``folder``, then moved in (:func:`layout.fileio.staged_folder`); none of them may be
    one of the command's ``inputs`` (paths or None)."""
    from layout.fileio import staged_folder

    _keep_inputs(files, inputs)
    try:
        with staged_folder(folder, whole=whole) as staging:
            for path, data in files.items():
                (staging / path.name).write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
    except OSError as error:
        raise UsageError(f"--out {folder}: cannot write there ({error.strerror or error}); nothing was "
                         "changed in it; choose a folder you can write to") from None


def main(argv=None) -> int:
    """Run the command line; returns the exit status."""
    # OpenCV's own messages (a TIFF it cannot handle, a header it cannot read) would come
    # before Stager's one error line that says the same; a user's OPENCV_LOG_LEVEL still wins.
    os.environ.setdefault("OPENCV_LOG_LEVEL", "SILENT")
    # A staged photo renders through many short GL and NumPy calls, each taking the GIL
    # back from the thread that draws the plans meanwhile: switching sooner than Python's
    # 5 ms gives it back sooner (room_4's render stage 2.58 -> 2.42 s, in-process).
    sys.setswitchinterval(1e-4)
    parser = _parser()
    args = parse(parser, argv)
    if isinstance(args, int):
        return args
    if args.command is None:
        parser.print_help()
        return EXIT_OK
    commands = {"board": _board_cmd, "calibrate": _calibrate_cmd, "check": _check_cmd, "segment": _segment_cmd,
                "measure": _measure_cmd, "furnish": _furnish_cmd, "batch": _batch_cmd, "serve": _serve_cmd}
    return dispatch(commands[args.command], args, "stage")


def run() -> None:
    """The console script."""
    run_command(main)


if __name__ == "__main__":
    run()
