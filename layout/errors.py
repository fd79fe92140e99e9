"""The one exception type users of :mod:`layout` see for bad input."""


class LayoutError(ValueError):
    """Bad input: the message names the file, the entry and the offending value.

    The command-line front ends print the message alone (no traceback) and exit 2.
    """
