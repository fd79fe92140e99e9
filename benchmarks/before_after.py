"""Photos staged by today's renderer beside the renderer of another revision (default:
when issue 51 was filed), same layouts: the four sample photos in
``docs/before_after.jpg``, the four real photos of ``samples/real/`` (a board pasted where
their camera would have seen it) in ``docs/before_after_real.jpg``.

Run by hand: ``python benchmarks/before_after.py [--old d0f695e]`` (a few minutes). Each
row: the photo as taken | the old renderer | this one, suggestion 1 (the samples: of the
living-room preset; the real photos: of their room's, ``samples/real/rooms.json``). The
old renderer runs in a subprocess from a worktree of ``--old`` (as ``realism.py`` does),
on the same erased photo, calibration, floor and layout.
"""
from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

SAMPLES = [(ROOT / "samples" / "photos" / f"room_{k}.jpg", "living_room") for k in (1, 2, 3, 4)]
REAL = ROOT / "samples" / "real"
WIDTH_PX = 640  # each panel


def _panel(image: np.ndarray, label: str) -> np.ndarray:
    h, w = image.shape[:2]
    out = cv2.resize(image, (WIDTH_PX, round(h * WIDTH_PX / w)), interpolation=cv2.INTER_AREA)
    cv2.putText(out, label, (10, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4, cv2.LINE_AA)
    cv2.putText(out, label, (10, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (255, 255, 255), 2, cv2.LINE_AA)
    return out


def real_photos(folder: Path) -> list[tuple[Path, str]]:
    """``samples/real``'s photos with a board pasted, saved in ``folder`` as a phone would
    (the focal length in EXIF), and each one's room preset."""
    from augment.photo.io import read_photo
    from augment.synth.photo import save_as_phone
    from augment.synth.prints import paste_planned

    out = []
    for name, room in json.loads((REAL / "rooms.json").read_text()).items():
        image = paste_planned(read_photo(REAL / f"{name}.jpg"), room)[0]
        path = folder / f"{name}.jpg"
        save_as_phone(path, image, room["focal_px"], 92)
        out.append((path, room["room"]))
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="d0f695e", help="git revision of the renderer to compare with")
    parser.add_argument("--out", type=Path, default=ROOT / "docs", help="folder for the two sheets")
    args = parser.parse_args(argv)

    from augment.camera.board import Board
    from augment.pipeline import furnish
    from augment.render.furniture import placed_items
    from augment.render.gl import Renderer
    from layout.fileio import write_atomic

    work = Path(tempfile.mkdtemp(prefix="before-after-"))
    old_tree = work / "old"
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(old_tree), args.old], check=True)
    renderer = Renderer()
    rows = []
    try:
        sheets = {"before_after.jpg": SAMPLES, "before_after_real.jpg": real_photos(work)}
        for sheet, photos in sheets.items():
            for photo, room in photos:
                result = furnish(photo, Board(), room=room, suggestions=1, seed=0, renderer=renderer)
                lay = result.layouts[0]
                items = placed_items(lay)
                case = {"image": result.erased.image, "calibration": result.calibration,
                        "mask": result.segmentation.mask, "floor": result.floor,
                        "seed": 0 if lay.seed is None else int(lay.seed),
                        "items": [{"kind": it.kind, "position_m": list(it.position_m), "yaw_rad": it.yaw_rad,
                                   "size_m": list(it.size_m), "id": it.id} for it in items]}
                (work / f"case_{len(rows):02d}.pkl").write_bytes(pickle.dumps(case))
                rows.append((sheet, photo.stem, result.image, result.staged[0], result.styles[0]))
                print(f"{photo.name}: {len(items)} items, style {result.styles[0]}", flush=True)
        env = dict(os.environ, PYTHONPATH=str(old_tree))
        subprocess.run([sys.executable, str(HERE / "realism.py"), "--old-driver", str(work)], env=env,
                       cwd=str(old_tree), check=True)
        panels = {sheet: [] for sheet in sheets}
        for i, (sheet, name, photo, new, style) in enumerate(rows):
            old = np.load(work / f"case_{i:02d}.old.npz")["image"]
            panels[sheet].append(np.hstack([_panel(photo, f"{name}: the photo"), _panel(old, f"renderer at {args.old}"),
                                            _panel(new, f"today ({style})")]))
    finally:
        renderer.close()
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old_tree)], check=False)
    for sheet, stack in panels.items():
        ok, jpeg = cv2.imencode(".jpg", cv2.cvtColor(np.vstack(stack), cv2.COLOR_RGB2BGR),
                                [cv2.IMWRITE_JPEG_QUALITY, 88])
        write_atomic(args.out / sheet, jpeg.tobytes())
        print(f"wrote {args.out / sheet}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
