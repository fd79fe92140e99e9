"""Quality numbers and output files of solved layouts (layout.report)."""
import dataclasses
import json

import matplotlib.image
import numpy as np
import pytest

from layout import LayoutBuilder, Solver, cli, report
from layout.errors import LayoutError


def placed(builder, poses):
    """A Layout of ``builder``'s model with items at ``poses`` {name: (x, y, yaw)}.

    Made from a one-iteration solve, so it has every field a real layout has."""
    model = builder.finalize()
    lay = Solver(max_iterations=1).solve(model, seed=0)
    pos, yaw = lay.position_m.copy(), lay.yaw_rad.copy()
    for name, (x, y, a) in poses.items():
        i = model.names.index(name)
        pos[i, :2] = x, y
        yaw[i] = a
    for arr in (pos, yaw):
        arr.setflags(write=False)  # evaluate must not write into a layout
    return dataclasses.replace(lay, position_m=pos, yaw_rad=yaw)


def test_overlaps_and_outside_are_exact():
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]], 2.5)
    b.add_item("a", (1.0, 1.0, 0.5))
    b.add_item("b", (1.0, 1.0, 0.5))
    b.add_item("c", (1.0, 1.0, 0.5))
    b.add_item("rug", (1.0, 1.0, 0.01), collides=False)
    lay = placed(b, {"a": (1.0, 1.0, 0.0), "b": (1.5, 1.0, 0.0), "c": (3.75, 2.0, 0.0),
                     "rug": (1.2, 1.0, 0.0)})
    r = report.evaluate(lay)
    assert r["overlaps"]["count"] == 1
    a, b_, area = r["overlaps"]["pairs"][0]
    assert (a, b_) == ("a", "b") and area == pytest.approx(0.5)
    assert r["overlaps"]["area_m2"] == pytest.approx(0.5)
    # c pokes 0.25 m out of the 4 m wall: 0.25 m² outside.
    assert r["outside_m2"] == pytest.approx(0.25) and r["outside_items"] == ["c"]
    json.dumps(r)  # JSON-ready
    # Without walkability (tries weighed by the pipeline): the rest, the very same.
    walk = ("traversable", "components", "unreachable", "blocked_doors")
    assert report.evaluate(lay, walkable=False) == {k: v for k, v in r.items() if k not in walk}


def test_stacked_items_do_not_overlap():
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]], 2.5)
    desk = b.add_item("desk", (1.2, 0.7, 0.75))
    lamp = b.add_item("lamp", (0.2, 0.2, 0.4))
    b.stack(desk, lamp)
    lay = placed(b, {"desk": (2.0, 1.5, 0.0), "lamp": (2.0, 1.5, 0.0)})
    pos = lay.position_m.copy()
    pos[lamp, 2] = 0.75 + 0.2
    lay = dataclasses.replace(lay, position_m=pos)
    assert report.evaluate(lay)["overlaps"]["count"] == 0


def test_door_zone_and_walkability():
    # A 4 x 1.2 m corridor, door at the left end; a cabinet across the corridor cuts
    # off the bookcase behind it.
    b = LayoutBuilder([[0, 0], [4, 0], [4, 1.2], [0, 1.2]], 2.5)
    b.add_door((0.0, 0.6), width_m=0.8, clearance_m=0.8)
    b.add_item("cabinet", (1.2, 0.4, 1.0))
    b.add_item("bookcase", (0.8, 0.35, 1.9), access_m=(0, 0, 0.6, 0))
    b.add_item("stool", (0.4, 0.4, 0.5))
    lay = placed(b, {"cabinet": (2.0, 0.6, 0.0), "bookcase": (3.8, 0.6, np.pi),
                     "stool": (0.3, 0.6, 0.0)})
    r = report.evaluate(lay)
    assert not r["traversable"]
    assert r["unreachable"] == [["bookcase", "front"]]
    assert r["clearances"] == {"deepest_m": 0.0, "pairs": []}
    assert r["blocked_doors"] == []
    assert r["door_clearance_m2"] == [pytest.approx(0.16)]
    assert r["door_blockers"] == [["stool"]]
    # Cabinet turned along the wall: a 0.8 m passage opens.
    lay = placed(b, {"cabinet": (2.0, 0.2, np.pi / 2), "bookcase": (3.8, 0.6, np.pi),
                     "stool": (2.9, 0.2, 0.0)})
    r = report.evaluate(lay)
    assert r["traversable"] and r["unreachable"] == [] and r["door_blockers"] == [[]]
    # The stool (x 2.7-3.1, y 0-0.4) stands 7.5 cm inside the bookcase's front
    # clearance (x 3.025-3.625, y 0.2-1.0); in the first layout nothing was.
    assert r["clearances"]["deepest_m"] == pytest.approx(0.075)
    assert [p[:2] for p in r["clearances"]["pairs"]] == [["bookcase", "stool"]]
    assert cli._warnings([r]) == []  # within the solver's 10 cm
    # 0.3 m further in, 20 cm deep (the stool's 0.2 m overlap across the clearance's width).
    lay = placed(b, {"cabinet": (2.0, 0.2, np.pi / 2), "bookcase": (3.8, 0.6, np.pi),
                     "stool": (3.2, 0.2, 0.0)})
    r = report.evaluate(lay)
    assert r["clearances"]["deepest_m"] == pytest.approx(0.2)
    (line,) = cli._warnings([r])
    assert "bookcase and stool: one stands 20 cm inside the other's clearance" in line


def test_group_mates_may_take_an_access_side():
    # A chair pushed under its table's front: the side is the chair's, not a walkway.
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]], 2.5)
    g = b.add_group("dining")
    b.add_item("table", (1.0, 1.0, 0.75), access_m=(0, 0, 0.6, 0), group=g)
    b.add_item("chair", (0.45, 0.5, 0.9), group=g)
    b.add_item("wall", (0.3, 3.0, 1.0))  # closes off the front of the table
    lay = placed(b, {"table": (1.5, 1.5, 0.0), "chair": (2.27, 1.5, np.pi), "wall": (2.85, 1.5, np.pi / 2)})
    r = report.evaluate(lay)
    assert r["overlaps"]["count"] == 0
    assert r["traversable"], r["unreachable"]


def test_lane_segments_follow_the_origin():
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]], 2.5)
    sofa = b.add_item("sofa", (2.0, 0.9, 0.8))
    plant = b.add_item("plant", (0.4, 0.4, 1.0))
    b.lane(sofa, [plant], angle_rad=0.0, length_m=2.0, half_width_m=0.3, start_m=(0.5, 0.0))
    lay = placed(b, {"sofa": (1.0, 1.0, np.pi / 2), "plant": (3.0, 2.0, 0.0)})
    seg = report.lane_segments(lay.model, lay)
    np.testing.assert_allclose(seg, [[[1.0, 1.5], [1.0, 3.5]]], atol=1e-12)


def test_write_outputs(tmp_path):
    b = LayoutBuilder([[0, 0], [4, 0], [4, 3], [0, 3]], 2.5)
    b.add_door((2.0, 0.0))
    b.add_window((0.0, 1.5))
    bed = b.add_item("bed", (1.6, 2.1, 0.5), access_m=(0, 0.6, 0.6, 0.6))
    b.against_wall(bed)
    model = b.finalize()
    layouts = Solver(max_iterations=200).suggest(model, 2)
    out = tmp_path / "out" / "deeper"
    paths = report.write_outputs(layouts, out, title="test: ")
    names = sorted(p.name for p in paths)
    assert names == ["energy.png", "layout_1.json", "layout_2.json", "plan_1.png", "plan_2.png"]
    assert sorted(p.name for p in out.iterdir()) == names  # no temporary files left
    data = json.loads((out / "layout_2.json").read_text())
    assert data["seed"] == 1 and data["items"][0]["id"] == "bed"
    assert {"energy", "overlaps", "outside_m2", "traversable", "door_clearance_m2"} <= set(data["metrics"])
    assert set(data["energy_by_kind"]) >= {"collision", "access"}
    for p in paths:
        if p.suffix == ".png":
            assert matplotlib.image.imread(p).shape[2] in (3, 4)
    # The same files in memory, byte for byte (stage furnish writes these).
    files = report.output_files(layouts, title="test: ")
    assert list(files) == [p.name for p in paths]
    assert all(files[p.name] == p.read_bytes() for p in paths)
    # Writing again replaces the files in place, and takes away the earlier run's second
    # suggestion; files that are not a run's suggestions stay.
    (out / "notes.txt").write_text("mine")
    (out / "layout_7.json").write_text('{"room": "mine, not a layout"}')
    report.write_outputs(layouts[:1], out)
    assert json.loads((out / "layout_1.json").read_text())["seed"] == 0
    assert sorted(p.name for p in out.iterdir()) == ["energy.png", "layout_1.json", "layout_7.json", "notes.txt",
                                                     "plan_1.png"]
    # ... but never one of the run's inputs, however its path is written: nothing is written.
    spec = out / "energy.png"
    before = spec.read_bytes()
    with pytest.raises(LayoutError, match="energy.png there is the input"):
        report.write_outputs(layouts[:1], out, inputs=[tmp_path / "out" / ".." / "out" / "deeper" / "energy.png"])
    assert spec.read_bytes() == before
