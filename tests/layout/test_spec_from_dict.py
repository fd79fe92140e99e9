"""Specs made in code (layout.spec.spec_from_dict): same checks and results as a file."""
import copy
import textwrap

import numpy as np
import pytest

from layout import LayoutError, spec

FLOOR = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.5], [0.0, 3.5]]


def test_a_dict_gives_the_same_spec_as_the_file(tmp_path):
    text = """
        [room]
        polygon = [[0, 0], [4, 0], [4, 3.5], [0, 3.5]]
        height = 2.6
        [[items]]
        id = "bed"
        kind = "bed"
        [[constraints]]
        type = "balance"
        """
    path = tmp_path / "room.toml"
    path.write_text(textwrap.dedent(text))
    doc = {"room": {"polygon": FLOOR, "height": 2.6}, "items": [{"id": "bed", "kind": "bed"}],
           "constraints": [{"type": "balance"}]}
    kept = copy.deepcopy(doc)
    from_dict, from_file = spec.spec_from_dict(doc, where="in code"), spec.load_spec(path)
    assert doc == kept  # not modified
    assert str(from_dict.path) == "in code"
    assert from_dict.items == from_file.items and from_dict.constraints == from_file.constraints
    assert np.array_equal(from_dict.polygon_m, from_file.polygon_m) and from_dict.height_m == 2.6


def test_a_preset_on_a_given_floor_is_furnished_for_its_area():
    def beds(polygon):
        s = spec.spec_from_dict({"room": {"preset": "bedroom", "height": 2.5, "polygon": polygon}}, "--room bedroom")
        model, _ = spec.build(s)
        assert len(model.items) == len(s.items)
        return {i.kind.name for i in s.items} & {"bed", "single_bed"}

    assert beds(FLOOR) == {"bed"}  # 14 m²
    assert beds([[0, 0], [3, 0], [3, 3.5], [0, 3.5]]) == {"single_bed"}  # 10.5 m²


def test_a_preset_without_a_floor_waits_for_one():
    s = spec.spec_from_dict({"room": {"preset": "office", "height": 2.7}}, where="--room office")
    assert s.preset == "office" and s.polygon_m is None and not s.items
    model, _ = spec.build(s, polygon_m=FLOOR)
    assert len(model.items) >= 3


@pytest.mark.parametrize("doc, needle", [
    ({"room": {"preset": "ballroom"}}, "ballroom"),
    ({"room": {"height": 2.5}, "items": [{"id": "x", "kind": "sofaa"}]}, "sofaa"),
    ({"rooom": {}}, "did you mean [room]"),
    ([1, 2], "expected a table"),
])
def test_errors_name_where_the_spec_came_from(doc, needle):
    with pytest.raises(LayoutError) as info:
        spec.spec_from_dict(doc, where="--room test")
    message = str(info.value)
    assert message.startswith("--room test: ") and needle in message and "\n" not in message
