"""`stage`: the image side of Stager (photo in, staged images out).

Subcommands arrive with the image-stage issues (calibrate, segment, measure, furnish);
until then the command only prints its usage.
"""
from __future__ import annotations

import argparse


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="stage",
        description="Furnish a photo of an empty room. Layout synthesis alone: see `layout --help`.",
    )
    parser.parse_args(argv)
    parser.print_help()
    return 0
