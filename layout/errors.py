"""Stager's one error root, and the layout package's kinds of it.

Every refusal of bad input is a :class:`StagerError` whose message names the file, the
field or flag and the offending value, and says what would work. The front ends catch
the root once: the command lines print the message alone and exit 2, the web app answers
with it; :attr:`StagerError.kind` says which stage refused. It lives here, in the
package the image side builds on, so that both share it.
"""
import re

# A run of this many characters without a space in a message is cut to its ends: an
# offending value is named, never echoed whole (a 10 MB field name, a pasted photo).
LONG_RUN = 200
_LONG = re.compile(r"\S{%d,}" % (LONG_RUN + 1))


def shorten(text: str) -> str:
    """``text`` with each run of more than ``LONG_RUN`` non-space characters cut to its
    first and last characters around ``…`` and how many were left out."""
    def cut(match):
        run = match[0]
        return f"{run[:80]}…({len(run) - 160} characters)…{run[-80:]}"

    return _LONG.sub(cut, text)


class StagerError(ValueError):
    """Bad input, said in words; ``kind`` names the stage that refused it. The message
    never holds a run of more than ``LONG_RUN`` characters without a space."""

    kind = "input"

    def __str__(self) -> str:
        return shorten(super().__str__())


class UsageError(StagerError):
    """A command-line flag or argument that will not do."""

    kind = "usage"


class LayoutError(StagerError):
    """A spec, room preset or layout that cannot be laid out as given."""

    kind = "layout"
