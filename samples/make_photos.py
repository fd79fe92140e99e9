"""Write samples/photos/: four synthetic room photos with their ground truth.

Rendered by the synthetic photographer (``augment.synth``) until real sample photos are
added: image K is seed ``[2026, INDEX]`` at 1280 x 960 with the default board (7x5
inner corners, 45 mm squares on an A3 sheet), picked from ``python -m augment.synth --count 24 --seed 2026 --size
1280x960`` because they look like real phone photos, differ (wood under a window with a radiator;
sunlight and window shadows on carpet with cartons; an L-shaped room; a sunlit floor
with a door and a window), and calibrate from the board alone (`stage check`).

Run ``python samples/make_photos.py`` to regenerate them.
"""
from __future__ import annotations

from pathlib import Path

from augment.render.gl import Renderer
from augment.synth import render_sample, write_sample

SEED = 2026
PICKS = (5, 4, 0, 14)
SIZE_PX = (1280, 960)


def main() -> None:
    out = Path(__file__).resolve().parent / "photos"
    out.mkdir(exist_ok=True)
    with Renderer() as renderer:
        for k, index in enumerate(PICKS, start=1):
            sample = render_sample([SEED, index], renderer, size_px=SIZE_PX)
            paths = write_sample(sample, out, f"room_{k}")
            print(paths["image"])


if __name__ == "__main__":
    main()
