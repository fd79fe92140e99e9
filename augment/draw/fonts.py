"""The one typeface of every picture Stager draws."""
from __future__ import annotations

import importlib.util
from pathlib import Path

from PIL import ImageFont


def overlay_font(size_px: int) -> ImageFont.ImageFont:
    """DejaVu Sans (shipped with matplotlib, as the printed board uses), else PIL's own."""
    spec = importlib.util.find_spec("matplotlib")  # found without importing matplotlib (slow)
    for folder in (spec.submodule_search_locations or []) if spec else []:
        try:
            return ImageFont.truetype(str(Path(folder) / "mpl-data" / "fonts" / "ttf" / "DejaVuSans.ttf"), size_px)
        except OSError:
            continue
    return ImageFont.load_default(size=size_px)
