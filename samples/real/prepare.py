"""Write samples/real/NAME.jpg from the original Pexels photos: each re-projected as a
phone held a little below level would have taken it, 1600 x 1200.

The originals are real-estate photos with their verticals straightened (a level camera
whose principal point sits on the horizon, high in the frame); Stager, like a phone,
assumes it at the centre. A camera turning about its own centre sees the same rays, so
the photo is warped exactly (no parallax) to a camera tipped down until the horizon is
300 original pixels above its optical axis, as wide as the original's frame allows.
``rooms.json`` keeps each original's focal length and horizon row (read from the
vanishing points of its walls' feet and ceiling lines) and gets the new focal length
and tilt.

Run by hand: ``python samples/real/prepare.py FOLDER_WITH_THE_ORIGINALS``.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
SIZE_PX = (1600, 1200)
AIM_BELOW_HORIZON_PX = 300  # in the original


def reproject(image: np.ndarray, focal_px: float, horizon_row: float) -> tuple[np.ndarray, float, float]:
    """(photo, focal px, pitch rad) of the widest view tipped down that the original fills."""
    h, w = image.shape[:2]
    K0 = np.array([[focal_px, 0, w / 2], [0, focal_px, horizon_row], [0, 0, 1.0]])
    pitch = float(np.arctan(AIM_BELOW_HORIZON_PX / focal_px))
    c, s = np.cos(pitch), np.sin(pitch)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])  # new camera's frame from the original's
    W, H = SIZE_PX
    border = np.array([[x, y] for x in np.linspace(0, W - 1, 17) for y in (0, H - 1)]
                      + [[x, y] for y in np.linspace(0, H - 1, 13) for x in (0, W - 1)], np.float64)

    def old_from_new(f):
        return K0 @ R.T @ np.linalg.inv(np.array([[f, 0, (W - 1) / 2], [0, f, (H - 1) / 2], [0, 0, 1.0]]))

    def fits(f):
        p = np.column_stack([border, np.ones(len(border))]) @ old_from_new(f).T
        p = p[:, :2] / p[:, 2:]
        return bool(np.all((p >= 0) & (p <= [w - 1, h - 1])))

    lo, hi = 100.0, 20000.0
    for _ in range(50):
        lo, hi = (lo, (lo + hi) / 2) if fits((lo + hi) / 2) else ((lo + hi) / 2, hi)
    f = round(hi * 1.01, 1)
    half = np.array([[0.5, 0, -0.25], [0, 0.5, -0.25], [0, 0, 1.0]])  # twice the size, then averaged down
    big = cv2.warpPerspective(image, old_from_new(f) @ half, (2 * W, 2 * H),
                              flags=cv2.INTER_CUBIC | cv2.WARP_INVERSE_MAP)
    return cv2.resize(big, SIZE_PX, interpolation=cv2.INTER_AREA), f, pitch


def main(folder: str) -> None:
    rooms = json.loads((HERE / "rooms.json").read_text())
    for name, room in rooms.items():
        original = room["original"]
        image = cv2.imread(str(Path(folder) / original["file"]))
        photo, room["focal_px"], pitch = reproject(image, original["focal_px"], original["horizon_row"])
        room["pitch_deg"] = round(float(np.degrees(pitch)), 2)
        cv2.imwrite(str(HERE / f"{name}.jpg"), photo, [cv2.IMWRITE_JPEG_QUALITY, 87])
        print(name, room["focal_px"], room["pitch_deg"])
    (HERE / "rooms.json").write_text(json.dumps(rooms, indent=2) + "\n")


if __name__ == "__main__":
    main(sys.argv[1])
