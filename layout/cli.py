"""The ``layout`` command: solve a spec into layout suggestions, list kinds and presets.

::

    layout solve SPEC.toml [--suggestions 5] [--seed 0] [--out DIR] [--quiet]
    layout kinds
    layout presets

Exit status: 0 success, 2 bad input (the message says what and where), 1 an
unexpected failure (a bug: the traceback is printed).
"""
from __future__ import annotations

import sys
from pathlib import Path

from .command import EXIT_OK, Parser, dispatch, parse, path_arg, seed_arg
from .command import run as run_command
from .errors import LayoutError, UsageError

MAX_SUGGESTIONS = 100


def _parser():
    p = Parser(prog="layout", description="Furniture layout synthesis (Weiss et al. 2018).")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=Parser)
    s = sub.add_parser("solve", help="solve a spec file into layout suggestions",
                       description="Solve SPEC (a TOML file, see layout.spec) from several random "
                                   "starts; write layout_K.json, plan_K.png and energy.png.")
    s.add_argument("spec", type=path_arg, metavar="SPEC.toml")
    s.add_argument("--suggestions", "-n", type=int, default=5, metavar="N",
                   help="number of suggestions (default 5)")
    s.add_argument("--seed", type=seed_arg, default=0, help="seed of suggestion 1; K uses seed + K - 1")
    s.add_argument("--out", "-o", type=path_arg, default=None, metavar="DIR",
                   help="output folder (default out/<spec name>)")
    s.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")
    sub.add_parser("kinds", help="list the furniture catalog")
    sub.add_parser("presets", help="list the room presets")
    return p


def _progress(iterable, total, quiet):
    """tqdm over the suggestions when stderr is a terminal, else the plain iterable."""
    if quiet or not sys.stderr.isatty():
        return iterable
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc="solving", unit="layout", file=sys.stderr)


def _check_out_dir(out):
    from .fileio import folder_problem

    if (problem := folder_problem(out)) is not None:
        raise UsageError(f"--out {out}: {problem}")


def _solve(args):
    from . import report, spec
    from .solver import COMPILE_NOTE, compiled, diversity

    if not 1 <= args.suggestions <= MAX_SUGGESTIONS:
        raise LayoutError(f"--suggestions {args.suggestions}: choose from 1 to {MAX_SUGGESTIONS} (each is a "
                          "solve of its own and a plan)")
    out = args.out if args.out is not None else Path("out") / args.spec.stem
    _check_out_dir(out)
    sp = spec.load_spec(args.spec)
    model, solver = spec.build(sp)
    if not args.quiet and sys.stderr.isatty() and not compiled():  # said where a progress bar shows
        print(f"note: {COMPILE_NOTE}", file=sys.stderr)
    layouts, reports = [], []
    for k in _progress(range(args.suggestions), args.suggestions, args.quiet):
        # Same seeds as Solver.suggest: suggestion k + 1 starts from seed + k.
        lay = solver.solve(model, seed=args.seed + k)
        layouts.append(lay)
        reports.append(report.evaluate(lay))
    try:
        paths = report.write_outputs(layouts, out, reports, title=f"{args.spec.stem}: ", inputs=[args.spec])
    except OSError as e:
        raise LayoutError(f"--out {out}: cannot write there ({e.strerror or e})") from None
    if args.quiet:
        return EXIT_OK
    print(f"{'K':>3} {'energy':>10} {'iters':>6} {'overlaps':>8} {'outside m²':>10} "
          f"{'walkable':>8} {'time ms':>9}")
    for k, (lay, rep) in enumerate(zip(layouts, reports), start=1):
        print(f"{k:>3} {lay.energy:>10.4g} {lay.iterations:>6d} {rep['overlaps']['count']:>8d} "
              f"{rep['outside_m2']:>10.3f} {'yes' if rep['traversable'] else 'no':>8} "
              f"{1000 * lay.time_s:>9.1f}")
    if len(layouts) > 1:
        print(f"diversity: {diversity(layouts):.3f} m (mean chamfer distance between suggestions)")
    print(f"wrote {len(paths)} files to {out}/ (layout_K.json, plan_K.png, energy.png)")
    for line in _warnings(reports):
        print(f"warning: {line}", file=sys.stderr)
    return EXIT_OK


def _warnings(reports) -> list[str]:
    """Suggestions a user should not take as they are: colliding, off the floor, not
    walkable or with an item deep in another's clearance. (Suggestions alike are no
    warning: a theater's seats or a desk corner may allow one arrangement; the
    diversity line shows it.)"""
    from .solver import ACCESS_CLEAR_M

    lines = []
    for k, rep in enumerate(reports, start=1):
        problems = []
        if rep["overlaps"]["count"]:
            pairs = ", ".join(f"{a} with {b}" for a, b, _ in rep["overlaps"]["pairs"][:3])
            problems.append(f"{rep['overlaps']['count']} overlapping pair(s) ({pairs})")
        if rep["outside_m2"] > 0:
            problems.append(f"{rep['outside_m2']:.2f} m² of {', '.join(rep['outside_items'])} off the floor")
        if not rep["traversable"]:
            where = ", ".join(f"the {side} of {item}" for item, side in rep["unreachable"][:3])
            doors = ", ".join(str(d) for d in rep["blocked_doors"])
            problems.append("not walkable (" + "; ".join(
                [f"cannot reach {where}"] * bool(where) + [f"door {doors} blocked"] * bool(doors)
                or [f"the free floor falls into {rep['components']} parts"]) + ")")
        deepest = rep["clearances"]["deepest_m"]
        if deepest > ACCESS_CLEAR_M:
            a, b, _ = max(rep["clearances"]["pairs"], key=lambda p: p[2])
            problems.append(f"{a} and {b}: one stands {100 * deepest:.0f} cm inside the other's clearance")
        if problems:
            lines.append(f"suggestion {k}: {'; '.join(problems)}; the room may be too small or narrow for "
                         "these items: remove some, or make them smaller in the spec")
    return lines


def _kinds(args):
    from .catalog import CATALOG, describe

    print(f"{'kind':<15} {'w':>5} {'d':>5} {'h':>5}  {'access b/l/f/r':<17} {'flags':<11} label")
    for kind in CATALOG.values():
        print(describe(kind))
    print("sizes in meters (width, depth along the facing, height); flags: wall = "
          "against a wall by default, no-collide = others may stand on it")
    return EXIT_OK


def _presets(args):
    from .presets import DESCRIPTIONS, PRESETS

    for name in PRESETS:
        print(f"{name:<13} {DESCRIPTIONS[name]}")
    return EXIT_OK


def main(argv=None) -> int:
    """Run the command line; returns the exit status."""
    args = parse(_parser(), argv)
    if isinstance(args, int):
        return args
    commands = {"solve": _solve, "kinds": _kinds, "presets": _presets}
    return dispatch(commands[args.command], args, "layout")


def run() -> None:
    """The console script."""
    run_command(main)


if __name__ == "__main__":
    run()
