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
from typing import NoReturn

from .errors import StagerError, UsageError

EXIT_OK, EXIT_BUG, EXIT_INPUT = 0, 1, 2


class Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")


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
