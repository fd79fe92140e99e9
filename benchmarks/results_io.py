"""What the hand-run benchmarks share: the results folder, the machine description,
atomic JSON + Markdown writing, and the --seeds/--only command line."""
from __future__ import annotations

import argparse
import json
import os
import platform
import time
from importlib import metadata
from pathlib import Path

from layout.fileio import write_atomic

RESULTS = Path(__file__).resolve().parent / "results"
# The numbers move with these (a new OpenCV reads boards differently), so each result names them.
PACKAGES = ("numpy", "numba", "opencv-contrib-python-headless", "onnxruntime", "scikit-image", "trimesh", "pyrender2")


def _versions() -> dict[str, str]:
    found = {}
    for name in PACKAGES:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    return found


def machine(**extra) -> dict:
    """Where and when the numbers were taken, with which packages, plus ``extra`` (compile time, seeds...)."""
    return dict(machine=platform.platform(), cpu_count=os.cpu_count(), python=platform.python_version(),
                packages=_versions(), date=time.strftime("%Y-%m-%d"), **extra)


def write(stem: str, data: dict, md_lines: list[str]) -> tuple[Path, Path]:
    """Write ``results/<stem>.json`` and ``results/<stem>.md``, each atomically."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    paths = RESULTS / f"{stem}.json", RESULTS / f"{stem}.md"
    for path, text in zip(paths, (json.dumps(data, indent=2) + "\n", "\n".join(md_lines) + "\n")):
        write_atomic(path, text)
    return paths


def scenario_args(doc: str) -> tuple[int, set[str]]:
    """Parse ``--seeds N`` (default 10) and ``--only a,b`` (scenario names)."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--only", default="", help="comma-separated scenario names")
    args = parser.parse_args()
    return args.seeds, {s for s in args.only.split(",") if s}
