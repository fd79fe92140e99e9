"""Scalable synthetic layout problems for the scaling benchmark.

``theater(n)``: n seats in straight rows of 20 (each row a curve group on a segment
with equal spacing, every seat facing the fixed stage), sections separated by aisles,
the hall sized so it is about as deep as it is wide.

``packed(n)``: n boxes of random sizes (0.4–1.2 m) on a square floor they cover to
35 %, each with a front clearance, in pairs that stay within 1.5 m of each other — a large,
tightly packed floor where collisions dominate.
"""
from __future__ import annotations

import math

import numpy as np

from layout import LayoutBuilder

ROW_SEATS = 20
SPACING_M = 0.62
ROW_PITCH_M = 1.2
AISLE_M = 1.4


def theater(n: int):
    """Model with a stage and ``n`` seats (n a multiple of 20 is exact; else rounded up)."""
    rows = math.ceil(n / ROW_SEATS)
    section_w = ROW_SEATS * SPACING_M + AISLE_M
    cols = max(1, round(math.sqrt(rows * ROW_PITCH_M / section_w)))
    depth_rows = math.ceil(rows / cols)
    width = cols * section_w + AISLE_M
    depth = 6.0 + depth_rows * ROW_PITCH_M + 2.0
    b = LayoutBuilder([[0, 0], [width, 0], [width, depth], [0, depth]], wall_height_m=6.0)
    stage = b.add_item("stage", (min(8.0, 0.5 * width), 3.0, 1.0), kind="stage",
                       position_m=(0.5 * width, 1.5), yaw_rad=0.5 * math.pi, fixed=True)
    seat = 0
    for r in range(rows):
        col, tier = divmod(r, depth_rows)
        x0 = AISLE_M + col * section_w + 0.5 * SPACING_M
        y = 6.0 + tier * ROW_PITCH_M
        g = b.add_group(f"row_{r}", position_m=(0.0, 0.0), yaw_rad=0.0, fixed=True)
        members = []
        for _ in range(min(ROW_SEATS, n - seat)):
            i = b.add_item(f"seat_{seat}", (0.5, 0.5, 0.9), kind="seat", access_m=(0, 0, 0.3, 0), group=g)
            b.face(i, stage)
            members.append(i)
            seat += 1
        end = x0 + (len(members) - 1) * SPACING_M
        b.curve(g, members, segment_m=((x0, y), (end, y)), spacing_m=SPACING_M, anchor_fixed=True)
    return b.finalize()


def packed(n: int, seed: int = 0):
    """Model with ``n`` random boxes covering 35 % of a square floor."""
    rng = np.random.default_rng(seed)
    size = rng.uniform(0.4, 1.2, size=(n, 2))
    side = math.sqrt(float((size[:, 0] * size[:, 1]).sum()) / 0.35)
    b = LayoutBuilder([[0, 0], [side, 0], [side, side], [0, side]])
    items = [b.add_item(f"box_{i}", (w, d, 0.8), access_m=(0, 0, 0.3, 0)) for i, (w, d) in enumerate(size)]
    for i in range(0, n - 1, 2):
        b.distance(items[i], items[i + 1], 1.5, mode="max")
    return b.finalize()
