"""Stager's one error root, and the layout package's kinds of it.

Every refusal of bad input is a :class:`StagerError` whose message names the file, the
field or flag and the offending value, and says what would work. The front ends catch
the root once: the command lines print the message alone and exit 2, the web app answers
with it; :attr:`StagerError.kind` says which stage refused. It lives here, in the
package the image side builds on, so that both share it.
"""


class StagerError(ValueError):
    """Bad input, said in words; ``kind`` names the stage that refused it."""

    kind = "input"


class UsageError(StagerError):
    """A command-line flag or argument that will not do."""

    kind = "usage"


class LayoutError(StagerError):
    """A spec, room preset or layout that cannot be laid out as given."""

    kind = "layout"
