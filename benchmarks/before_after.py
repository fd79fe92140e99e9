"""The four sample photos staged by today's renderer beside the renderer of another
revision (default: when issue 51 was filed), same layouts: ``docs/before_after.jpg``.

Run by hand: ``python benchmarks/before_after.py [--old d0f695e]`` (a few minutes). Each
row: the photo as taken | the old renderer | this one, suggestion 1 of the living-room
preset. The old renderer runs in a subprocess from a worktree of ``--old`` (as
``realism.py`` does), on the same erased photo, calibration, floor and layout.
"""
from __future__ import annotations

import argparse
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

PHOTOS = [ROOT / "samples" / "photos" / f"room_{k}.jpg" for k in (1, 2, 3, 4)]
WIDTH_PX = 640  # each panel


def _panel(image: np.ndarray, label: str) -> np.ndarray:
    h, w = image.shape[:2]
    out = cv2.resize(image, (WIDTH_PX, round(h * WIDTH_PX / w)), interpolation=cv2.INTER_AREA)
    cv2.putText(out, label, (10, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (0, 0, 0), 4, cv2.LINE_AA)
    cv2.putText(out, label, (10, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.8, (255, 255, 255), 2, cv2.LINE_AA)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", default="d0f695e", help="git revision of the renderer to compare with")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "before_after.jpg")
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
        for i, photo in enumerate(PHOTOS):
            result = furnish(photo, Board(), room="living_room", suggestions=1, seed=0, renderer=renderer)
            lay = result.layouts[0]
            items = placed_items(lay)
            case = {"image": result.erased.image, "calibration": result.calibration, "mask": result.segmentation.mask,
                    "floor": result.floor, "seed": 0 if lay.seed is None else int(lay.seed),
                    "items": [{"kind": it.kind, "position_m": list(it.position_m), "yaw_rad": it.yaw_rad,
                               "size_m": list(it.size_m), "id": it.id} for it in items]}
            (work / f"case_{i:02d}.pkl").write_bytes(pickle.dumps(case))
            rows.append((photo.stem, result.image, result.staged[0], result.styles[0]))
            print(f"{photo.name}: {len(items)} items, style {result.styles[0]}", flush=True)
        env = dict(os.environ, PYTHONPATH=str(old_tree))
        subprocess.run([sys.executable, str(HERE / "realism.py"), "--old-driver", str(work)], env=env,
                       cwd=str(old_tree), check=True)
        sheet = []
        for i, (name, photo, new, style) in enumerate(rows):
            old = np.load(work / f"case_{i:02d}.old.npz")["image"]
            sheet.append(np.hstack([_panel(photo, f"{name}: the photo"), _panel(old, f"renderer at {args.old}"),
                                    _panel(new, f"today ({style})")]))
    finally:
        renderer.close()
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old_tree)], check=False)
    ok, jpeg = cv2.imencode(".jpg", cv2.cvtColor(np.vstack(sheet), cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
    write_atomic(args.out, jpeg.tobytes())
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
