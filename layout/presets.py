"""Automatic furnishing: a room type and a floor area give a furniture set.

After Henderson et al. ("room type -> furniture set"): each preset picks what a room
of that type and size typically holds, keeping the summed footprint of the items
that block the floor to about a third of its area so the layout stays walkable.
The result has the shape of a spec file's ``[[groups]]``, ``[[items]]`` and
``[[constraints]]`` tables (see :mod:`layout.spec`); the catalog's default rules do
the rest (a sofa faces the TV, nightstands flank the bed, …).
"""
from __future__ import annotations

import math

from .catalog import CATALOG
from .errors import LayoutError

# Summed footprint the presets aim to stay under, as a fraction of the floor area.
TARGET_FILL = 0.35


def _item(id_, kind, count=1, **fields):
    d = {"id": id_, "kind": kind, **fields}
    if count > 1:
        d["count"] = count
    return d


# Dining chairs pulled in: their seats this far under the table's edge (clear of a
# trestle's foot), and kept this far from the table's ends (clear of its legs).
TUCK_M = 0.08
END_CLEAR_M = 0.1


def _table_set(group, table_kind, seat_kind, n_seats, *, table_size=None, gap_m=0.02, end_m=0.0):
    """A rigid table-and-seats group: seats spread along the table's long sides, ``end_m``
    clear of its ends (and at its ends for more than four), each facing the table
    ``gap_m`` from its edge (negative: pulled in under it; rigid members do not collide
    with each other).

    Returns the group table and its item tables.
    """
    tw, td = (table_size or CATALOG[table_kind].size_m)[:2]
    sw, sd = CATALOG[seat_kind].size_m[:2]
    round_ = table_kind in ("round_table", "game_table") and n_seats <= 4 and abs(tw - td) < 1e-9
    offsets, yaws = [], []
    if round_:
        # One seat per side of a square/round table.
        for k in range(n_seats):
            a = 2 * math.pi * k / n_seats
            r = 0.5 * tw + 0.5 * sd + gap_m
            offsets.append([round(r * math.cos(a), 4), round(r * math.sin(a), 4)])
            yaws.append(round(math.degrees(a + math.pi), 4))
    else:
        ends = 2 if n_seats > 4 else 0
        per_side = (n_seats - ends) // 2
        # Table frame: x along its depth (front), y along its width (long side).
        span = tw - 2 * end_m
        for side in (1.0, -1.0):
            for k in range(per_side):
                y = (k + 0.5) * span / per_side - 0.5 * span
                x = side * (0.5 * td + 0.5 * sd + gap_m)
                offsets.append([round(x, 4), round(y, 4)])
                yaws.append(180.0 if side > 0 else 0.0)
        for side in (1.0, -1.0)[:ends]:
            offsets.append([0.0, round(side * (0.5 * tw + 0.5 * sd + gap_m), 4)])
            yaws.append(-90.0 if side > 0 else 90.0)
        if (n_seats - ends) % 2:
            raise ValueError("odd number of seats at a rectangular table")
    table = _item(f"{group}_table", table_kind, group=group, offset=[0.0, 0.0])
    if table_size is not None:
        table["size"] = list(table_size)
    seats = _item(f"{group}_{seat_kind}", seat_kind, count=n_seats, group=group,
                  offset=offsets if n_seats > 1 else offsets[0],
                  yaw_deg=yaws if n_seats > 1 else yaws[0])
    return {"id": group, "rigid": True}, [table, seats]


# A loveseat and a small TV bench (with its TV) fit where a full sofa set would not.
LOVESEAT = (1.5, 0.85, 0.85)
TV_BENCH = (1.2, 0.4, 1.05)


def _living_room(area):
    # The conversation group first (what is dropped first goes last): seating, the TV it
    # faces and the coffee table, then the rug, side table and lamp at the sofa that make
    # even a small visible floor read as a furnished room, then what lines the walls.
    items, groups = [], []
    if area < 10:
        items += [_item("sofa", "sofa", size=list(LOVESEAT)), _item("tv_stand", "tv_stand", size=list(TV_BENCH)),
                  _item("side_table", "side_table")]
    else:
        items += [_item("sofa", "sofa"), _item("tv_stand", "tv_stand"),
                  _item("coffee_table", "coffee_table")]
        if area >= 14:
            items.append(_item("armchair", "armchair", count=1 if area < 20 else 2))
        items += [_item("rug", "rug"), _item("side_table", "side_table", count=1 if area < 20 else 2)]
    if area >= 12:
        items += [_item("floor_lamp", "floor_lamp"), _item("plant", "plant", count=1 if area < 20 else 2)]
    if area >= 16:
        items.append(_item("bookcase", "bookcase", count=1 if area < 30 else 2))
    if area >= 30:
        items.append(_item("dresser", "dresser"))
    # In rooms this size the sofa goes against a wall, which keeps the middle free.
    return groups, items, [{"type": "against_wall", "item": "sofa"}, {"type": "balance"}]


def _bedroom(area):
    items = []
    if area < 13:
        items += [_item("bed", "single_bed"), _item("nightstand", "nightstand")]
        if area >= 8:
            items.append(_item("wardrobe", "wardrobe"))
        if area >= 10:
            items.append(_item("dresser", "dresser"))
    else:
        items += [_item("bed", "bed"), _item("nightstand", "nightstand", count=2),
                  _item("wardrobe", "wardrobe")]
        if area >= 15:
            items.append(_item("dresser", "dresser"))
        if area >= 17:
            items += [_item("armchair", "armchair"), _item("rug", "rug"), _item("plant", "plant")]
        if area >= 24:
            items += [_item("wardrobe_2", "wardrobe"), _item("floor_lamp", "floor_lamp")]
    return [], items, []


def _dining_room(area):
    pulled_in = {"gap_m": -TUCK_M, "end_m": END_CLEAR_M}
    if area < 9:
        group, items = _table_set("dining", "round_table", "chair", 4, **pulled_in)
    elif area < 18:
        group, items = _table_set("dining", "dining_table", "chair", 6, **pulled_in)
    else:
        group, items = _table_set("dining", "dining_table", "chair", 8, table_size=[2.0, 0.95, 0.75], **pulled_in)
    if area >= 11:
        items.append(_item("sideboard", "dresser"))
    if area >= 16:
        items.append(_item("plant", "plant", count=1 if area < 25 else 2))
    if area >= 25:
        items.append(_item("bookcase", "bookcase"))
    return [group], items, [{"type": "balance"}]


# A home office's one desk stands this far (its center) from the wall it faces, the chair
# between them: whoever sits there looks into the room, and the photo shows the chair's front.
DESK_INTO_ROOM_M = 1.45


def _office(area):
    desks = max(1, min(8, int(area // 6)))
    constraints = []
    desk = _item("desk", "desk", count=desks)
    if desks == 1:
        # Not the catalog's back-to-the-wall: its front (the chair's side) to the wall.
        desk["rules"] = False
        constraints += [{"type": "wall", "item": "desk", "distance": DESK_INTO_ROOM_M},
                        {"type": "wall_orientation", "item": "desk", "angle_deg": 180.0}]
    items = [desk, _item("office_chair", "office_chair", count=desks), _item("plant", "plant")]
    items.append(_item("bookcase", "bookcase", count=1 if area < 10 else 2 if area < 30 else 3))
    if area >= 20:
        items.append(_item("coat_rack", "coat_rack"))
    return [], items, constraints


def _game_room(area):
    groups, items = [], []
    if area >= 28:
        items.append(_item("pool_table", "pool_table"))
    group, table = _table_set("games", "game_table", "chair", 2 if area < 9 else 4)
    groups.append(group)
    items += table
    arcades = 1 if area < 12 else 2 if area < 40 else 4
    items.append(_item("arcade", "arcade_cabinet", count=arcades))
    if area >= 40:
        items.append(_item("sofa", "sofa"))
    return groups, items, []


def _outdoor_yard(area):
    groups, items = [], []
    if area < 11:
        group, table = _table_set("bistro", "round_table", "chair", 2, table_size=[0.7, 0.7, 0.75])
        groups.append(group)
        items += table
        items.append(_item("grill", "grill", size=[0.8, 0.5, 1.0]))
        return groups, items, [{"type": "against_wall", "item": "grill"}]
    for k in range(1 if area < 35 else 2):
        g, its = _table_set(f"picnic{k + 1}", "picnic_table", "bench", 2)
        groups.append(g)
        items += its
    items += [_item("grill", "grill"), _item("trash_can", "trash_can")]
    if area >= 20:
        items += [_item("parasol", "parasol"),
                  _item("lounge_chair", "lounge_chair", count=2 if area < 50 else 4)]
    # Grill and trash can by the fence, their fronts to the yard.
    return groups, items, [{"type": "against_wall", "items": ["grill", "trash_can"]}]


# The preset of `stage furnish` and the web page when none is chosen.
DEFAULT_ROOM = "living_room"
PRESETS = {
    "living_room": _living_room,
    "bedroom": _bedroom,
    "dining_room": _dining_room,
    "office": _office,
    "game_room": _game_room,
    "outdoor_yard": _outdoor_yard,
}

DESCRIPTIONS = {
    "living_room": "sofa, TV, coffee table, rug, side table; lamp, plants, armchairs, bookcases with space",
    "bedroom": "single bed + nightstand (< 13 m²) or double bed + 2 nightstands; wardrobe, dresser",
    "dining_room": "table with 4/6/8 chairs by area, sideboard, plants",
    "office": "one desk and office chair per 6 m² (one alone faces into the room), bookcases, plant, coat rack",
    "game_room": "game table with chairs, arcade cabinets; a pool table from 28 m²",
    "outdoor_yard": "bistro set or picnic tables with benches, grill, trash can, parasol, loungers",
}


def preset_items(name, floor_area_m2):
    """The furniture a room of type ``name`` and area ``floor_area_m2`` gets.

    Parameters
    ----------
    name : str
        One of :data:`PRESETS`.
    floor_area_m2 : float
        Floor area in m² (> 0).

    Returns
    -------
    parts : dict
        ``{"groups": [...], "items": [...], "constraints": [...]}``, lists of tables
        shaped like a spec file's entries (fresh objects: the caller may modify them).

    Raises
    ------
    LayoutError
        For an unknown preset or an area that is not a positive number.
    """
    if name not in PRESETS:
        import difflib

        close = difflib.get_close_matches(str(name), PRESETS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise LayoutError(f"preset {name!r} does not exist; {hint}choose one of {', '.join(PRESETS)}")
    try:
        area = float(floor_area_m2)
    except (TypeError, ValueError):
        raise LayoutError(f"preset {name!r}: floor area {floor_area_m2!r} is not a number") from None
    if not (math.isfinite(area) and area > 0):
        raise LayoutError(f"preset {name!r}: floor area {floor_area_m2!r} must be a positive number of m²")
    groups, items, constraints = PRESETS[name](area)
    return {"groups": groups, "items": items, "constraints": constraints}


# Corner sets for a floor that shows too little for a preset's whole furniture: when every
# arrangement of what fits repeats the first suggestion, the next suggestions stage one of
# these instead (the first piece of each is its point: a set that cannot keep it is not
# offered). A stager shows a small corner as one small group, not as the same piece again.
def _set(items, groups=(), constraints=()):
    return {"groups": list(groups), "items": list(items), "constraints": list(constraints)}


# A reading chair of a corner set stands with its back to a wall, not alone in the room
# (as a corner set's loveseat does).
CHAIR_TO_WALL = [{"type": "against_wall", "item": "armchair", "gap": 0.1}]


def _living_corners():
    return [
        _set([_item("armchair", "armchair"), _item("side_table", "side_table"), _item("floor_lamp", "floor_lamp")],
             constraints=CHAIR_TO_WALL),
        _set([_item("tv_stand", "tv_stand", size=list(TV_BENCH)), _item("plant", "plant")]),
        _set([_item("sofa", "sofa", size=list(LOVESEAT)), _item("side_table", "side_table")],
             constraints=[{"type": "against_wall", "item": "sofa"}]),
        _set([_item("bookcase", "bookcase"), _item("plant", "plant")]),
        _set([_item("armchair", "armchair"), _item("plant", "plant")], constraints=CHAIR_TO_WALL),
        _set([_item("plant", "plant"), _item("side_table", "side_table")]),
    ]


def _bedroom_corners():
    return [
        _set([_item("bed", "single_bed"), _item("nightstand", "nightstand")]),
        _set([_item("dresser", "dresser"), _item("plant", "plant")]),
        _set([_item("armchair", "armchair"), _item("floor_lamp", "floor_lamp")], constraints=CHAIR_TO_WALL),
        _set([_item("wardrobe", "wardrobe"), _item("plant", "plant")]),
    ]


def _dining_corners():
    four, four_items = _table_set("dining", "round_table", "chair", 4, gap_m=-TUCK_M, end_m=END_CLEAR_M)
    two, two_items = _table_set("bistro", "round_table", "chair", 2, table_size=[0.7, 0.7, 0.75], gap_m=-TUCK_M)
    return [
        _set(four_items, [four]),
        _set(two_items + [_item("plant", "plant")], [two]),
        _set([_item("sideboard", "dresser"), _item("plant", "plant")]),
    ]


def _office_corners():
    facing_in = [{"type": "wall", "item": "desk", "distance": DESK_INTO_ROOM_M},
                 {"type": "wall_orientation", "item": "desk", "angle_deg": 180.0}]
    return [
        _set([_item("desk", "desk", rules=False), _item("office_chair", "office_chair")], constraints=facing_in),
        _set([_item("desk", "desk"), _item("office_chair", "office_chair"), _item("plant", "plant")]),
        _set([_item("bookcase", "bookcase"), _item("armchair", "armchair"), _item("floor_lamp", "floor_lamp")],
             constraints=CHAIR_TO_WALL),
        _set([_item("bookcase", "bookcase"), _item("plant", "plant")]),
    ]


CORNERS = {"living_room": _living_corners, "bedroom": _bedroom_corners, "dining_room": _dining_corners,
           "office": _office_corners}


def corner_sets(name) -> list[dict]:
    """Small furniture sets for a corner of a room of type ``name``, in order of preference
    (none for a preset without them).

    Returns
    -------
    list of dict
        ``{"groups", "items", "constraints"}`` each, shaped as :func:`preset_items`' result
        (fresh objects).
    """
    if name not in PRESETS:
        raise LayoutError(f"preset {name!r} does not exist; choose one of {', '.join(PRESETS)}")
    return CORNERS[name]() if name in CORNERS else []


def footprint_m2(items):
    """Summed footprint (m²) of the item tables that block the floor (rugs do not)."""
    total = 0.0
    for t in items:
        kind = CATALOG.get(t.get("kind"))
        size = t.get("size") or (kind.size_m if kind else None)
        collides = t.get("collides", kind.collides if kind else True)
        if size is not None and collides:
            total += size[0] * size[1] * t.get("count", 1)
    return total
