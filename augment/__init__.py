"""Stager's image stage: calibration, floor, height, rendering and the ``stage`` command."""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("stager")
except PackageNotFoundError:  # run from a source tree that was never installed
    __version__ = "0+unknown"
