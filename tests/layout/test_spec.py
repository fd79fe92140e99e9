"""Spec files (layout.spec) and the furniture catalog with its default rules (layout.catalog)."""
import json
import math
import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from layout import LayoutBuilder, LayoutError, Solver, catalog, spec
from layout.catalog import CATALOG, RuleItem, apply_default_rules, kind_or_error

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

ROOM = """
[room]
polygon = [[0, 0], [5, 0], [5, 4], [0, 4]]
height = 2.6
"""


def write(tmp_path, text, name="spec.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def load(tmp_path, text):
    return spec.load_spec(write(tmp_path, text))


def error_of(tmp_path, text, build=False):
    """The LayoutError message of a bad spec (loading, or building when asked)."""
    path = write(tmp_path, text)
    with pytest.raises(LayoutError) as info:
        s = spec.load_spec(path)
        if build:
            spec.build(s)
    message = str(info.value)
    # Every message starts with the file it is about, and is one line.
    assert message.startswith(str(path) + ":"), message
    assert "\n" not in message
    return message


# ------------------------------------------------------------------ happy paths


@pytest.mark.parametrize("name", ["living_room", "bedroom", "l_shaped_office"])
def test_samples_load_and_build(name):
    s = spec.load_spec(SAMPLES / f"{name}.toml")
    model, solver = spec.build(s)
    assert isinstance(solver, Solver)
    assert len(model.items) >= 4
    assert len(model.door_particles) == 1


def test_living_room_sample_has_the_papers_ten_items():
    s = spec.load_spec(SAMPLES / "living_room.toml")
    assert len(s.items) == 10
    kinds = {i.kind.name for i in s.items}
    assert {"sofa", "armchair", "tv_stand", "desk", "office_chair", "coat_rack", "plant"} <= kinds


def test_count_expands_ids_and_bare_id_means_all(tmp_path):
    s = load(tmp_path, ROOM + """
        [[groups]]
        id = "dining"

        [[items]]
        id = "table"
        kind = "dining_table"
        group = "dining"

        [[items]]
        id = "chair"
        kind = "chair"
        count = 4
        group = "dining"

        [[constraints]]
        type = "focal_distance"
        focal = "table"
        members = ["chair"]
        distance = 0.7
    """)
    assert [i.id for i in s.items] == ["table", "chair_1", "chair_2", "chair_3", "chair_4"]
    (c,) = s.constraints
    assert c.args["members"] == ("chair_1", "chair_2", "chair_3", "chair_4")
    model, _ = spec.build(s)
    # 4 from the constraint, 4 x 2 (min and max) from the chairs' default rule.
    assert model.counts()["distance"] == 12


def test_catalog_defaults_and_overrides(tmp_path):
    s = load(tmp_path, ROOM + """
        [[items]]
        id = "sofa"
        kind = "sofa"

        [[items]]
        id = "big_sofa"
        kind = "sofa"
        size = [2.6, 1.0, 0.9]
        access = [0, 0.2, 0.8, 0.2]

        [[items]]
        id = "crate"
        kind = "crate"
        size = [0.5, 0.4, 0.3]
        collides = false
    """)
    sofa, big, crate = s.items
    assert sofa.kind == CATALOG["sofa"]
    assert big.kind.size_m == (2.6, 1.0, 0.9) and big.kind.access_m == (0, 0.2, 0.8, 0.2)
    assert big.in_catalog and not crate.in_catalog
    model, _ = spec.build(s)
    i = model.names.index("crate")
    assert model.kinds[i] == "crate" and not model.particle_collides[i]
    np.testing.assert_allclose(model.particle_size_m[model.names.index("big_sofa")], [2.6, 1.0, 0.9])


def test_every_constraint_type_reaches_the_model(tmp_path):
    s = load(tmp_path, ROOM + """
        [[groups]]
        id = "set"
        rigid = true

        [[items]]
        id = "desk"
        kind = "desk"
        group = "set"
        offset = [0.0, 0.0]

        [[items]]
        id = "lamp"
        kind = "desk_lamp"

        [[items]]
        id = "sofa"
        kind = "sofa"
        rules = false

        [[items]]
        id = "tv"
        kind = "tv_stand"
        rules = false

        [[items]]
        id = "plant"
        kind = "plant"
        count = 2

        [[constraints]]
        type = "distance"
        a = "plant"
        b = "sofa"
        distance = 1.0
        mode = "min"

        [[constraints]]
        type = "focal_distance"
        focal = "tv"
        members = ["sofa"]
        distance = 2.5
        stiffness = 0.8
        schedule = "constant"

        [[constraints]]
        type = "lane"
        origin = "sofa"
        length = 2.0
        half_width = 0.3
        angle_deg = 0
        start = [0.5, 0]

        [[constraints]]
        type = "heat"
        members = ["plant_1"]
        target = [0.3, 0.3]

        [[constraints]]
        type = "heat"
        members = ["plant_2"]
        target = [0.0, 0.6]
        frame = "sofa"

        [[constraints]]
        type = "symmetry"
        focal = "tv"
        members = ["sofa"]
        angle_deg = 0

        [[constraints]]
        type = "balance"

        [[constraints]]
        type = "wall"
        items = ["plant"]
        distance = 0.3

        [[constraints]]
        type = "wall_orientation"
        item = "tv"
        angle_deg = 0

        [[constraints]]
        type = "against_wall"
        item = "tv"
        gap = 0.05

        [[constraints]]
        type = "face"
        a = "sofa"
        b = "tv"
        angle_deg = 90
        mutual = true

        [[constraints]]
        type = "parallel"
        a = "set"
        b = "sofa"

        [[constraints]]
        type = "stack"
        base = "desk"
        top = "lamp"
    """)
    model, _ = spec.build(s)
    counts = model.counts()
    assert counts["distance"] == 3  # 2 plants + the focal distance
    assert counts["lane"] == 5  # every item but the origin (desk, lamp, tv, plant_1, plant_2)
    assert counts["heat"] == 2
    assert counts["symmetry"] == 1 and counts["balance"] == 1
    # wall: 2 plants + against_wall (tv) + desk's default rule.
    assert counts["wall_distance"] == 4
    assert counts["wall_orientation"] == 3
    assert counts["orientation"] == 2 and counts["stack"] == 1
    # Degrees in the file, radians in the model; stiffness and schedule carried over.
    face = int(np.flatnonzero(model.orientation_mode == 0)[0])
    np.testing.assert_allclose(model.orientation_angle_rad[face], [math.pi / 2, 0.0])
    assert 0.8 in model.distance_k0
    tv = model.names.index("tv")
    gap = model.wall_distance_rest_m[list(model.wall_distance_item).index(tv)]
    assert gap == pytest.approx(0.5 * CATALOG["tv_stand"].size_m[1] + 0.05)
    # Balance covers every item (grouped ones too), not only top-level ones.
    assert len(model.balance_members) == len(model.items)


def test_groups_nest_curve_and_rigid_offsets(tmp_path):
    s = load(tmp_path, ROOM + """
        [[groups]]
        id = "inner"
        rigid = true
        group = "outer"
        offset = [0.5, 0.0]

        [[groups]]
        id = "outer"
        rigid = true
        at = [2.5, 2.0]
        yaw_deg = 90
        fixed = true

        [[groups]]
        id = "row"
        curve = { arc = { center = [0, 0], radius = 3.0, start_deg = 200, end_deg = 340 }, spacing = 0.6 }

        [[items]]
        id = "table"
        kind = "side_table"
        group = "inner"

        [[items]]
        id = "seat"
        kind = "seat"
        count = 3
        group = "row"
    """)
    model, _ = spec.build(s)
    assert model.counts()["curve"] == 1
    np.testing.assert_allclose(model.curve_params[0, 3:], np.radians([200, 340]))
    table = model.names.index("table")
    assert model.particle_body[table] == model.names.index("outer")
    assert model.particle_inv_mass[table] == 0.0  # fixed outer group


def test_polygon_override_and_preset_follow_the_floor(tmp_path):
    path = write(tmp_path, """
        [room]
        polygon = [[0, 0], [3, 0], [3, 2.5], [0, 2.5]]
        preset = "bedroom"
        doors = [{ at = [2.5, 0.0], width = 0.8 }]
    """)
    s = spec.load_spec(path)
    small, _ = spec.build(s)
    floor = np.array([[0, 0], [5.0, 0], [5.0, 4.0], [0, 4.0]])
    floor.setflags(write=False)  # build must not write into its input
    big, _ = spec.build(s, polygon_m=floor)
    np.testing.assert_allclose(np.abs(big.floor_polygon_m).max(0), [5.0, 4.0])
    assert "single_bed" in small.kinds and "bed" in big.kinds
    assert len(big.items) > len(small.items)
    assert len(big.door_particles) == 1


def test_spec_without_polygon_needs_one_from_the_caller(tmp_path):
    path = write(tmp_path, """
        [room]
        preset = "office"
    """)
    s = spec.load_spec(path)
    with pytest.raises(LayoutError, match="room.polygon is missing"):
        spec.build(s)
    model, _ = spec.build(s, polygon_m=[[0, 0], [4, 0], [4, 3], [0, 3]])
    assert "desk" in model.kinds


def test_solver_section(tmp_path):
    s = load(tmp_path, ROOM + """
        [solver]
        max_iterations = 200
        collision = "sphere"
        rate = 20

        [[items]]
        id = "bed"
        kind = "bed"
    """)
    assert s.solver.max_iterations == 200 and s.solver.collision == "sphere" and s.solver.rate == 20.0


def test_loading_does_not_modify_the_file(tmp_path):
    path = write(tmp_path, ROOM + '[[items]]\nid = "bed"\nkind = "bed"\n')
    before = path.read_bytes()
    spec.build(spec.load_spec(path))
    assert path.read_bytes() == before


# --------------------------------------------------------------------- errors

ITEM = '[[items]]\nid = "sofa"\nkind = "sofa"\n'


@pytest.mark.parametrize(
    "text, expected",
    [
        # Typos in section names and fields name the typo and what is allowed.
        (ROOM + ITEM + "[itmes]\nx = 1\n", ["'itmes'", "did you mean [items]"]),
        (ROOM + '[[items]]\nid = "sofa"\nkind = "sofa"\nszie = [1, 1, 1]\n',
         ['items[0] (id "sofa")', "'szie'", "did you mean 'size'", "allowed fields"]),
        (ROOM.replace("height = 2.6", "heigth = 2.6") + ITEM, ["room", "'heigth'"]),
        (ROOM + ITEM + '[solver]\nmax_iter = 5\n', ["solver", "'max_iter'"]),
        # Kinds and sizes.
        (ROOM + '[[items]]\nid = "s"\nkind = "sofaa"\n', ['items[0] (id "s")', "'sofaa'", "'sofa'"]),
        (ROOM + '[[items]]\nid = "ship"\nkind = "spaceship"\n', ["'spaceship'", "explicit size"]),
        (ROOM + '[[items]]\nid = "x"\n', ['items[0] (id "x")', "size"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\nsize = [2, nan, 1]\n', ["size", "NaN", "finite"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\nsize = [2, -1, 1]\n', ["size", "[2, -1, 1]", "greater than 0"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\nsize = [2, 0, 1]\n', ["size", "greater than 0"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\nsize = [2, 1]\n', ["size", "3 numbers"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\naccess = [0, 0, -1, 0]\n', ["access", "negative"]),
        # Types.
        (ROOM.replace("2.6", '"2.6"') + ITEM, ["room", 'height = "2.6"', "not a number"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\ncount = 2.5\n', ["count", "not an integer"]),
        (ROOM + '[[items]]\nid = "s"\nkind = "sofa"\nrules = "yes"\n', ["rules", "true or false"]),
        (ROOM + '[[items]]\nid = 3\nkind = "sofa"\n', ["items[0]", "id = 3", "not a string"]),
        (ROOM + ITEM + "[solver]\nmethod = 'newton'\n", ["solver.method", "newton"]),
        # Polygons.
        ('[room]\npolygon = [[0, 0], [1, 0]]\n' + ITEM, ["room.polygon", "2 vertices", "at least 3"]),
        ('[room]\npolygon = [[0, 0], [4, 3], [4, 0], [0, 3]]\n' + ITEM, ["room.polygon", "intersect"]),
        ('[room]\npolygon = [[0, 0], [4, "a"], [4, 3]]\n' + ITEM, ["room.polygon", "vertex 1"]),
        # Names.
        (ROOM + ITEM + ITEM, ["duplicate id 'sofa'", "items[1]"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "face"\na = "sofa"\nb = "tv"\n',
         ['constraints[0] (type "face")', '"tv"', "known ids: sofa"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "wall"\nitem = "sfoa"\n', ["'sofa'"]),
        (ROOM + '[[items]]\nid = "c"\nkind = "chair"\ncount = 2\n' + ITEM
         + '[[constraints]]\ntype = "face"\na = "sofa"\nb = "c"\n', ["names 2 items", "c_1"]),
        (ROOM + '[[items]]\nid = "c"\nkind = "chair"\ngroup = "dining"\n', ["group", "dining", "not a [[groups]] id"]),
        # Constraints.
        (ROOM + ITEM + '[[constraints]]\ntype = "distnace"\n', ["constraints[0]", "distnace", "'distance'"]),
        (ROOM + ITEM + '[[constraints]]\na = "sofa"\n', ["constraints[0]", "missing field 'type'"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "distance"\na = "sofa"\n', ["missing field 'b'"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "wall"\nitem = "sofa"\nmode = "exact"\n', ["mode", "exact", "'eq'"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "wall"\nitem = "sofa"\nstiffness = 2\n', ["stiffness", "[0, 1]"]),
        (ROOM + ITEM + '[[constraints]]\ntype = "face"\na = "sofa"\nb = "sofa"\nangel_deg = 5\n',
         ["'angel_deg'", "'angle_deg'"]),
        (ROOM + '[[groups]]\nid = "g"\n' + ITEM + '[[constraints]]\ntype = "against_wall"\nitem = "g"\n',
         ["is a group"]),
        # Presets.
        ('[room]\npolygon = [[0, 0], [4, 0], [4, 3], [0, 3]]\npreset = "kitchen"\n', ["preset", "kitchen", "bedroom"]),
        ('[room]\npolygon = [[0, 0], [4, 0], [4, 3], [0, 3]]\npreset = "bedrom"\n', ["did you mean 'bedroom'"]),
        ('[room]\npolygon = [[0, 0], [4, 0], [4, 3], [0, 3]]\npreset = "bedroom"\n' + ITEM, ["preset", "[[items]]"]),
        # Doors far from every wall; no items at all.
        (ROOM.replace("height = 2.6", "doors = [{ at = [2.5, 2.0] }]") + ITEM, ["room.doors[0]", "from the nearest wall"]),
        (ROOM, ["no [[items]]"]),
    ],
)
def test_bad_specs_name_file_entry_and_value(tmp_path, text, expected):
    message = error_of(tmp_path, text)
    for part in expected:
        assert part in message, (part, message)


def test_items_that_cannot_fit_the_floor(tmp_path):
    text = """
        [room]
        polygon = [[0, 0], [3, 0], [3, 2], [0, 2]]

        [[items]]
        id = "wardrobe"
        kind = "wardrobe"
        count = 9
    """
    message = error_of(tmp_path, text, build=True)
    assert "footprints add up" in message and "6.00 m²" in message


def test_item_taller_than_the_room(tmp_path):
    message = error_of(tmp_path, ROOM.replace("2.6", "1.5") + '[[items]]\nid = "w"\nkind = "wardrobe"\n',
                       build=True)
    assert 'items[0] (id "w")' in message and "exceeds the room height" in message


def test_toml_syntax_error_has_line_and_column(tmp_path):
    message = error_of(tmp_path, ROOM + "[[items]]\nid = sofa\n")
    assert "invalid TOML" in message and "line 6" in message and "column" in message


def test_toml_nested_too_deep_is_a_syntax_error(tmp_path):
    # tomllib recurses per level: this was a RecursionError traceback.
    message = error_of(tmp_path, ROOM + "x = " + "[" * 100_000 + "]" * 100_000 + "\n")
    assert "invalid TOML" in message and "nested thousands deep" in message


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(LayoutError, match="no such file"):
        spec.load_spec(tmp_path / "nope.toml")
    with pytest.raises(LayoutError, match="is a directory"):
        spec.load_spec(tmp_path)


# -------------------------------------------------------------------- catalog


def test_catalog_sizes_are_believable():
    for name, kind in CATALOG.items():
        assert kind.name == name
        w, d, h = kind.size_m
        assert 0 < w <= 6.0 and 0 < d <= 6.0 and 0 < h <= 4.0, name
        assert all(a >= 0 for a in kind.access_m) and len(kind.access_m) == 4
        assert kind.label
    assert CATALOG["bed"].size_m == (1.6, 2.1, 1.05) and CATALOG["bed"].bare_height_m == 0.5  # headboard, mattress
    assert CATALOG["sofa"].size_m == (2.1, 0.95, 0.85)
    assert not CATALOG["rug"].collides and CATALOG["rug"].size_m[2] <= 0.02
    against = {n for n, k in CATALOG.items() if k.against_wall}
    assert {"bed", "wardrobe", "dresser", "bookcase", "tv_stand", "desk", "coat_rack",
            "arcade_cabinet"} <= against
    assert CATALOG["mug"].size_m[0] < 0.15 and CATALOG["pencil"].size_m[0] < 0.02


def test_kind_or_error_suggests_close_names():
    assert kind_or_error("desk", "here") is CATALOG["desk"]
    with pytest.raises(LayoutError, match=r"here: kind 'nightstnd'.*'nightstand'"):
        kind_or_error("nightstnd", "here")
    with pytest.raises(LayoutError, match="layout kinds"):
        kind_or_error("zzzz", "here")


def _builder_with(*kinds, group=None, rigid=False):
    b = LayoutBuilder([[0, 0], [5, 0], [5, 4], [0, 4]], 2.6)
    g = None if group is None else b.add_group(group, rigid=rigid)
    records = []
    for n, name in enumerate(kinds):
        k = CATALOG[name]
        i = b.add_item(f"{name}{n}", k.size_m, kind=name, access_m=k.access_m, collides=k.collides,
                       group=g, offset_m=(0.0, 0.0 if not rigid else 1.0 * n))
        records.append(RuleItem(i, k, group, True, rigid))
    return b, records


def test_rules_bedroom():
    b, items = _builder_with("bed", "nightstand", "nightstand", "wardrobe")
    applied = apply_default_rules(b, items)
    names = [(r.name, r.index) for r in applied]
    bed, n1, n2, wardrobe = (r.index for r in items)
    assert ("against_wall", bed) in names and ("against_wall", wardrobe) in names
    assert ("beside_head", n1) in names and ("beside_head", n2) in names
    model = b.finalize()
    # One nightstand left of the head, one right, both at the head end (bed frame x < 0).
    targets = model.heat_target_m
    assert targets[0, 1] > 0 > targets[1, 1]
    assert np.all(targets[:, 0] < 0)
    assert model.counts()["orientation"] == 2


def test_rules_living_room_and_rules_off_partner():
    b, items = _builder_with("sofa", "tv_stand", "coffee_table", "armchair", "rug", "armchair", "floor_lamp",
                             "side_table")
    sofa, tv, table, chair, rug, chair2, lamp, side = items
    items[1] = tv._replace(rules=False)  # the TV still serves as the sofa's partner
    applied = {(r.name, r.index, r.partner) for r in apply_default_rules(b, items)}
    assert ("face_tv", sofa.index, tv.index) in applied
    assert ("beside_coffee_table", chair.index, table.index) in applied
    assert ("in_front_of", table.index, sofa.index) in applied
    assert ("under", rug.index, sofa.index) in applied
    assert ("beside_arm", side.index, sofa.index) in applied
    assert not any(r[0] == "against_wall" and r[1] == tv.index for r in applied)
    model = b.finalize()
    # By hand, in the sofa's frame (x front, y left): sofa 2.1 x 0.95, coffee table 1.1 x 0.6,
    # armchair 0.85 deep, rug 1.4 deep, side table 0.5, lamp 0.35.
    ahead = 0.45 + (0.95 + 0.6) / 2
    np.testing.assert_allclose(model.heat_target_m, [
        [ahead, 0.0],  # the coffee table, 45 cm off the sofa's front
        [ahead, 0.55 + 0.4 + 0.425],  # an armchair 40 cm off the table's left end ...
        [(0.95 + 1.4) / 2 - 0.2, 0.0],  # the rug 20 cm under the sofa's front
        [ahead, -(0.55 + 0.4 + 0.425)],  # ... the other off its right end
        [-(0.95 - 0.35) / 2 + 0.05, -((2.1 + 0.35) / 2 + 0.05)],  # the lamp at the right arm,
        [-(0.95 - 0.5) / 2 + 0.05, (2.1 + 0.5) / 2 + 0.05],  # as the side table has the left
    ])
    assert catalog.TV_DISTANCE_M in model.distance_rest_m


def test_a_side_table_or_lamp_with_no_seat_stands_by_a_wall():
    """With no sofa or armchair, a side table (0.5 m deep) and a floor lamp (0.35 m) keep
    their centres at most half their depth + 0.3 m from a wall (0.55 / 0.475 m, mode max);
    beside a sofa they stand at its arms instead, with no wall rule."""
    from layout import _codes as codes

    b, items = _builder_with("side_table", "floor_lamp", "plant")
    applied = {(r.name, r.index) for r in apply_default_rules(b, items)}
    assert applied == {("by_wall", items[0].index), ("by_wall", items[1].index)}
    model = b.finalize()
    np.testing.assert_allclose(model.wall_distance_rest_m, [0.55, 0.475])
    assert list(model.wall_distance_mode) == [codes.MAX, codes.MAX]
    b, items = _builder_with("sofa", "side_table", "floor_lamp")
    names = {r.name for r in apply_default_rules(b, items)}
    assert "by_wall" not in names and "beside_arm" in names


def test_rules_chairs_at_a_table_only_in_a_loose_group():
    b, items = _builder_with("dining_table", "chair", "chair", "chair", group="dining")
    applied = apply_default_rules(b, items)
    assert sum(r.name == "at_table" for r in applied) == 3
    assert any(r.name == "around_table" for r in applied)
    b, items = _builder_with("dining_table", "chair", group="dining", rigid=True)
    assert apply_default_rules(b, items) == []  # the offsets already place them
    b, items = _builder_with("dining_table", "chair")
    assert apply_default_rules(b, items) == []  # no group, no table to gather at


def test_rules_office_chair_pairs_with_one_desk_each():
    b, items = _builder_with("desk", "desk", "office_chair", "office_chair")
    applied = [r for r in apply_default_rules(b, items) if r.name == "at_desk"]
    assert sorted(r.partner for r in applied) == [items[0].index, items[1].index]


def test_companion_groups_let_partners_share_clearance(tmp_path):
    s = load(tmp_path, ROOM + """
        [[items]]
        id = "desk"
        kind = "desk"

        [[items]]
        id = "chair"
        kind = "office_chair"

        [[items]]
        id = "bed"
        kind = "bed"

        [[items]]
        id = "ns"
        kind = "nightstand"
        count = 2
    """)
    groups = {i.id: i.group for i in s.items}
    assert groups["desk"] == groups["chair"] == "desk_set"
    assert groups["bed"] == groups["ns_1"] == groups["ns_2"] == "bed_set"


def test_nightstands_end_up_beside_the_head_of_the_bed(tmp_path):
    s = load(tmp_path, """
        [room]
        polygon = [[0, 0], [4, 0], [4, 3.5], [0, 3.5]]

        [[items]]
        id = "bed"
        kind = "bed"

        [[items]]
        id = "ns"
        kind = "nightstand"
        count = 2
    """)
    model, _ = spec.build(s)
    layouts = Solver(max_iterations=300).suggest(model, 3)
    best = min(layouts, key=lambda lay: lay.energy)
    bed = model.names.index("bed")
    c, s_ = math.cos(best.yaw_rad[bed]), math.sin(best.yaw_rad[bed])
    for name in ("ns_1", "ns_2"):
        i = model.names.index(name)
        d = best.position_m[i, :2] - best.position_m[bed, :2]
        along = c * d[0] + s_ * d[1]  # bed frame: x to the foot end
        across = -s_ * d[0] + c * d[1]
        assert along < -0.6 and 0.9 < abs(across) < 1.3, (name, along, across)
        # Same facing as the bed (not turned to the wall).
        assert abs(math.remainder(best.yaw_rad[i] - best.yaw_rad[bed], 2 * math.pi)) < 0.3


def test_open_edges_reach_the_model_in_the_builders_order(tmp_path):
    # Clockwise in the file: its edge 1 ((0, 4) -> (5, 4)) is edge 1 of the reversed,
    # counter-clockwise polygon as well ((5, 4) -> (0, 4)); its edge 0 becomes edge 2.
    s = load(tmp_path, """
    [room]
    polygon = [[0, 0], [0, 4], [5, 4], [5, 0]]
    open_edges = [0, 1]

    [[items]]
    id = "bed"
    kind = "bed"
    """)
    assert s.open_edges == (1, 2)
    model, _ = spec.build(s)
    np.testing.assert_array_equal(model.floor_edge_wall, [True, False, False, True])
    layout = Solver(restarts=0).solve(model, seed=0)
    assert layout.to_dict()["room"]["open_edges"] == [1, 2]


@pytest.mark.parametrize("value,expect", [
    ("[4]", "room.open_edges: 4 is not an edge number 0-3"),
    ("[-1]", "open_edges = -1 must be at least 0"),
    ('"north"', 'open_edges = "north" must be a list of edge numbers'),
])
def test_bad_open_edges_are_named(tmp_path, value, expect):
    message = error_of(tmp_path, ROOM + f"open_edges = {value}\n" + """
    [[items]]
    id = "bed"
    kind = "bed"
    """)
    assert expect in message


def test_a_solved_layout_reads_back_as_it_stands(tmp_path):
    """layout_K.json read back (``read_layout``): every item where the solver left it
    (a lamp stacked on the desk included), fixed, with the seed and energy it was solved at."""
    model, solver = spec.build(spec.load_spec(SAMPLES / "desk.toml"))
    (solved,) = solver.suggest(model, 1, seed=3)
    path = tmp_path / "layout_1.json"
    path.write_text(json.dumps(solved.to_dict()))
    loaded_spec, again = spec.read_layout(path)
    assert all(item.fixed for item in loaded_spec.items)
    assert again.seed == 3 and again.energy == solved.energy and again.trace.size == 0
    assert [again.model.names[i] for i in again.items] == [solved.model.names[i] for i in solved.items]
    np.testing.assert_allclose(again.position_m[again.items], solved.position_m[solved.items], atol=2e-6)
    np.testing.assert_allclose(again.yaw_rad[again.items], solved.yaw_rad[solved.items], atol=2e-6)
    # What the pipeline renders (as_written) is what the file holds, to the last bit or two.
    written = solved.as_written()
    assert written.to_dict() == solved.to_dict() and np.array_equal(written.as_written().position_m, written.position_m)
    assert 0 < np.abs(written.position_m - solved.position_m).max() <= 5e-7
    np.testing.assert_allclose(again.position_m[again.items], written.position_m[written.items], rtol=0, atol=1e-15)
    np.testing.assert_allclose(again.yaw_rad[again.items], written.yaw_rad[written.items], rtol=0, atol=1e-15)
    top = [solved.model.names.index(f"book_{s}_6") for s in "ab"]  # six 3 cm books: 15 cm up
    np.testing.assert_allclose(again.position_m[top, 2], [0.165, 0.165], atol=1e-9)
    np.testing.assert_allclose(again.model.floor_polygon_m, solved.model.floor_polygon_m)


@pytest.mark.parametrize("change, expected", [
    (lambda d: d.pop("items"), "not a layout_K.json (expected an object with room and items)"),
    (lambda d: d["items"][0].pop("yaw_rad"), "items[0]: missing field 'yaw_rad'"),
    (lambda d: d["items"][0].update(position_m=[1, 2]), "items[0]: position_m"),
    (lambda d: d["items"][1].update(size_m=[0.5, 0, 0.5]), "items[1]: size_m = [0.5, 0, 0.5]"),
    (lambda d: d["room"].update(polygon_m=[[0, 0], [1, 0]]), "room"),
])
def test_bad_layout_files_name_the_file_and_entry(tmp_path, change, expected):
    model, solver = spec.build(spec.load_spec(SAMPLES / "desk.toml"))
    doc = solver.suggest(model, 1, seed=0)[0].to_dict()
    change(doc)
    path = tmp_path / "layout_1.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(LayoutError, match=rf"^{re.escape(str(path))}: .*{re.escape(expected)}"):
        spec.read_layout(path)
    assert json.loads(path.read_text()) == doc  # never modified
