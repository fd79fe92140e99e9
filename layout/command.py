"""Command-line plumbing shared by ``layout`` and ``stage``: exit statuses, an argparse
parser that reports usage errors instead of exiting, and the one place that turns a
command's exceptions into an exit status and a message.

Exit status: 0 success, 2 bad input (one ``error:`` line on stderr), 1 an unexpected
failure (a bug: the traceback is printed), 130 interrupted.
"""
from __future__ import annotations

import argparse
import gc
import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from .errors import StagerError, UsageError, shorten

EXIT_OK, EXIT_BUG, EXIT_INPUT = 0, 1, 2


class Parser(argparse.ArgumentParser):
    """An argparse parser that reports usage errors instead of exiting, and takes a value
    that starts with a dash as the value of the option before it (``--board -3x5`` is
    ``--board=-3x5``: argparse would say "expected one argument" and never name the value)."""

    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")

    def parse_known_args(self, args=None, namespace=None):
        return super().parse_known_args(self._values_joined(args), namespace)

    def _values_joined(self, args):
        if args is None:
            args = sys.argv[1:]
        args = [str(a) for a in args]
        takes_one = {}
        for parser in self._all_parsers():
            for action in parser._actions:
                if action.option_strings and action.nargs is None:
                    takes_one.update(dict.fromkeys(action.option_strings))
        known = {o for parser in self._all_parsers() for o in parser._option_string_actions}
        out, k = [], 0
        while k < len(args):
            arg = args[k]
            following = args[k + 1] if k + 1 < len(args) else None
            if (arg in takes_one and following is not None and following.startswith("-")
                    and following not in ("-", "--", *known) and following.split("=", 1)[0] not in known):
                out.append(f"{arg}={following}")
                k += 2
                continue
            out.append(arg)
            k += 1
        return out

    def _all_parsers(self):
        parsers = [self]
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    parsers += sub._all_parsers() if isinstance(sub, Parser) else [sub]
        return parsers


def path_arg(text: str) -> Path:
    """A path flag's value, refused when no file system here could hold it: empty, with a
    NUL character, a name over the longest a folder takes, or a path over the longest the
    system takes (later checks would fail with a traceback on it)."""
    shown = shorten(repr(text))
    if not text:
        raise argparse.ArgumentTypeError("'': give a path")
    if "\0" in text:
        raise argparse.ArgumentTypeError(f"{shown}: a path cannot hold a NUL character")
    name_max, path_max = _limits()
    for part in Path(text).parts:
        if len(os.fsencode(part)) > name_max:
            raise argparse.ArgumentTypeError(f"{shown}: the name {shorten(part)!r} is {len(os.fsencode(part))} "
                                             f"bytes long, and a file or folder name is at most {name_max}")
    if len(os.fsencode(text)) > path_max:
        raise argparse.ArgumentTypeError(f"{shown}: the path is {len(os.fsencode(text))} bytes long, at most "
                                         f"{path_max} are allowed")
    return Path(text)


def _limits() -> tuple[int, int]:
    """The longest file name and path the current folder's file system takes."""
    try:
        return os.pathconf(".", "PC_NAME_MAX"), os.pathconf(".", "PC_PATH_MAX")
    except (OSError, ValueError):
        return 255, 4096


def seed_arg(text: str) -> int:
    """``--seed``: a whole number from 0 (numpy's generators take no negative seeds)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: expected a whole number from 0, e.g. 7")
    return value


def arg_type(parse_text: Callable[[str], object]) -> Callable[[str], object]:
    """An argparse ``type`` from a parser that raises ``ValueError`` with a message:
    argparse shows that message (of a plain ``ValueError`` it says only "invalid value")."""

    def convert(text: str):
        try:
            return parse_text(text)
        except ValueError as error:
            raise argparse.ArgumentTypeError(str(error)) from None

    convert.__name__ = parse_text.__name__
    return convert


def parse(parser: argparse.ArgumentParser, argv) -> argparse.Namespace | int:
    """Parsed arguments, or the exit status when parsing ends the run (a usage error,
    reported on stderr, or ``--help``)."""
    try:
        return parser.parse_args(argv)
    except UsageError as e:
        print(f"error: {e}", file=sys.stderr)
        return EXIT_INPUT
    except SystemExit as e:  # --help
        return int(e.code or 0)


def dispatch(command: Callable[[argparse.Namespace], int], args: argparse.Namespace, program: str) -> int:
    """Run ``command(args)`` and return its exit status.

    Bad input (a :class:`~layout.errors.StagerError`) is printed as one ``error:`` line
    (status 2). Anything else is a bug in ``program``: its traceback is printed (status 1).
    """
    t0 = time.perf_counter()
    interrupted = []

    def on_interrupt(signum, frame):
        interrupted.append(True)
        raise KeyboardInterrupt

    # Ctrl-C raises where the program happens to be; inside PyOpenGL's wrappers it comes
    # out as another exception (a TypeError), which must still read as an interruption.
    watch = threading.current_thread() is threading.main_thread() and \
        signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if watch:
        signal.signal(signal.SIGINT, on_interrupt)
    try:
        return command(args)
    except BrokenPipeError:
        # The reader went away (`layout kinds | head`): not an error of ours.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except KeyboardInterrupt:
        return _interrupted(t0)
    except Exception as e:  # noqa: BLE001 - sorted into interruptions, bad input and bugs below
        if interrupted:
            return _interrupted(t0)
        if isinstance(e, StagerError):
            print(f"error: {e}", file=sys.stderr)
            return EXIT_INPUT
        traceback.print_exc()
        print(f"error: unexpected failure (a bug in {program}); please report the traceback above",
              file=sys.stderr)
        return EXIT_BUG
    finally:
        if watch:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def _interrupted(t0: float) -> int:
    print(f"error: interrupted after {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    return 130


def run(main: Callable[[], int]) -> NoReturn:
    """A console script: exit with ``main()``'s status.

    What is still alive is frozen out of garbage collection first: the interpreter's
    last collections would otherwise walk every object numba, SciPy and matplotlib made
    at import, half a second on every ``stage`` command.
    """
    status = main()
    gc.freeze()
    sys.exit(status)
