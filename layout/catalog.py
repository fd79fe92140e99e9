"""Furniture kinds: default sizes, clearances and the layout rules that come with them.

A :class:`Kind` gives an item its default size ``(width, depth, height)`` in meters
(depth along the facing direction), its accessibility depths ``(back, left, front,
right)`` in meters, whether it stands with its back against a wall, and whether it
takes part in collisions (a rug does not). :data:`CATALOG` maps kind names to kinds;
sizes are typical European retail dimensions.

:func:`apply_default_rules` adds the constraints that make a kind behave like itself:
a wardrobe goes against a wall, a sofa faces the TV, a coffee table stands in front
of the sofa, nightstands flank the head of the bed, chairs around a table face it.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import NamedTuple

from .errors import LayoutError


@dataclass(frozen=True)
class Kind:
    """A furniture kind.

    Attributes
    ----------
    name : str
        Catalog key, e.g. ``"sofa"``.
    size_m : (3,) tuple of float
        Width, depth and height in meters; depth runs along the facing direction.
    access_m : (4,) tuple of float
        Clearance depth in meters in front of the back, left, front and right side
        (0 = none): the space needed to use the item.
    against_wall : bool
        Whether the default rules put its back against a wall, facing the room.
    collides : bool
        False for floor coverings that other items may stand on.
    label : str
        Human-readable description.
    bare_height_m : float
        Its height without its top part (a TV stand without the TV, a bed without its
        headboard), for a photo that shows too little above the floor for the whole; 0 for none.
    bare_part : str
        That top part, for messages: "what it carries", "its headboard".
    """

    name: str
    size_m: tuple
    access_m: tuple = (0.0, 0.0, 0.0, 0.0)
    against_wall: bool = False
    collides: bool = True
    label: str = ""
    bare_height_m: float = 0.0
    bare_part: str = ""

    @property
    def footprint_m2(self) -> float:
        return self.size_m[0] * self.size_m[1]


def _k(name, size_m, access_m=(0.0, 0.0, 0.0, 0.0), against_wall=False, collides=True, label="", bare_m=0.0,
       bare_part=""):
    return name, Kind(name, tuple(float(v) for v in size_m), tuple(float(v) for v in access_m),
                      against_wall, collides, label or name.replace("_", " "), float(bare_m), bare_part)


#: Kind name -> :class:`Kind`. Access tuples are (back, left, front, right) in meters.
#: Where a person stands or walks up to an item the clearance is at least 0.6 m: the
#: walkability check asks for a 0.5 m wide path (Henderson et al.'s 0.25 m radius).
CATALOG = dict(
    [
        # Bedroom.
        # Beds to the headboard's top; without it, 0.5 m (a photo that shows too little above the floor).
        _k("bed", (1.6, 2.1, 1.05), (0, 0.6, 0.6, 0.6), True, label="double bed", bare_m=0.5,
           bare_part="its headboard"),
        _k("single_bed", (0.9, 2.0, 0.95), (0, 0.6, 0.6, 0), True, label="single bed", bare_m=0.5,
           bare_part="its headboard"),
        _k("nightstand", (0.5, 0.4, 0.55), (0, 0, 0.4, 0), label="nightstand"),
        _k("wardrobe", (1.2, 0.6, 2.0), (0, 0, 0.7, 0), True, label="wardrobe"),
        _k("dresser", (1.0, 0.5, 0.8), (0, 0, 0.6, 0), True, label="dresser / sideboard"),
        # Living room.
        _k("sofa", (2.1, 0.95, 0.85), (0, 0, 0.6, 0), label="three-seat sofa"),
        _k("armchair", (0.85, 0.85, 0.9), (0, 0, 0.6, 0), label="armchair"),
        _k("coffee_table", (1.1, 0.6, 0.45), label="coffee table"),
        _k("side_table", (0.5, 0.5, 0.55), label="side table"),
        _k("tv_stand", (1.6, 0.45, 1.25), (0, 0, 0.6, 0), True, label="TV on a low stand", bare_m=0.55,
           bare_part="what it carries"),
        _k("bookcase", (0.8, 0.35, 1.9), (0, 0, 0.6, 0), True, label="bookcase"),
        _k("plant", (0.4, 0.4, 1.0), label="indoor plant in a pot"),
        _k("floor_lamp", (0.35, 0.35, 1.6), label="floor lamp"),
        _k("rug", (2.0, 1.4, 0.01), collides=False, label="rug"),
        _k("coat_rack", (0.5, 0.5, 1.8), (0, 0, 0.6, 0), True, label="coat rack"),
        # Dining.
        _k("dining_table", (1.6, 0.9, 0.75), (0.6, 0.6, 0.6, 0.6), label="dining table for 6"),
        _k("round_table", (1.0, 1.0, 0.75), (0.6, 0.6, 0.6, 0.6), label="round table for 4"),
        _k("chair", (0.45, 0.5, 0.9), (0, 0, 0.4, 0), label="chair"),
        # Office.
        _k("desk", (1.2, 0.7, 0.75), (0, 0, 0.7, 0), True, label="desk"),
        _k("office_chair", (0.6, 0.6, 1.0), label="office chair on casters"),
        # Events, games.
        _k("stage", (4.0, 2.5, 0.6), (0, 0, 1.0, 0), label="stage"),
        _k("seat", (0.55, 0.55, 0.9), (0, 0, 0.4, 0), label="theater seat"),
        _k("pool_table", (2.5, 1.4, 0.8), (1.2, 1.2, 1.2, 1.2), label="8-ft pool table"),
        _k("game_table", (1.0, 1.0, 0.75), (0.6, 0.6, 0.6, 0.6), label="card / board-game table"),
        _k("arcade_cabinet", (0.7, 0.85, 1.8), (0, 0, 0.8, 0), True, label="arcade cabinet"),
        # Outdoor.
        _k("picnic_table", (1.8, 0.8, 0.75), (0.6, 0, 0.6, 0), label="picnic table"),
        _k("bench", (1.5, 0.4, 0.45), (0, 0, 0.3, 0), label="bench"),
        _k("grill", (1.2, 0.6, 1.1), (0, 0, 0.8, 0), label="barbecue grill"),
        _k("trash_can", (0.6, 0.6, 1.0), (0, 0, 0.6, 0), label="outdoor trash can"),
        _k("carousel", (6.0, 6.0, 4.0), (1.0, 1.0, 1.0, 1.0), label="fairground carousel"),
        _k("lounge_chair", (0.7, 1.9, 0.4), (0, 0.6, 0, 0), label="sun lounger"),
        _k("parasol", (0.5, 0.5, 2.4), label="parasol (stand footprint)"),
        # Small items, for stacking on tables and desks.
        _k("book", (0.15, 0.22, 0.03), label="book lying flat"),
        _k("laptop", (0.35, 0.25, 0.02), label="closed laptop"),
        _k("mug", (0.09, 0.09, 0.1), label="mug"),
        _k("plate", (0.26, 0.26, 0.02), label="dinner plate"),
        _k("pencil", (0.01, 0.18, 0.01), label="pencil"),
        _k("binder", (0.06, 0.29, 0.32), label="upright ring binder"),
        _k("photo_frame", (0.2, 0.1, 0.25), label="standing photo frame"),
        _k("desk_lamp", (0.15, 0.15, 0.45), label="desk lamp"),
    ]
)

# Kinds around which chairs of the same group gather, and the kinds that sit there.
TABLE_KINDS = ("dining_table", "round_table", "picnic_table", "game_table")
SEAT_KINDS = ("chair", "bench")

# Comfortable viewing distance from a sofa to a TV (about 2.5 screen diagonals).
TV_DISTANCE_M = 2.5
# Gap between a sofa's front and the coffee table: within reach, with room for legs.
COFFEE_GAP_M = 0.45
# Gap between the coffee table's end and an armchair's front: the group talks across it.
ARMCHAIR_GAP_M = 0.4
# How far a rug reaches under the sofa: its front legs stand on it.
RUG_UNDER_SOFA_M = 0.2
# Gap between a sofa's arm and the side table or lamp beside it.
ARM_GAP_M = 0.05
# A side table or lamp with no seat to stand at keeps its back within this of a wall.
NEAR_WALL_M = 0.3


def kind_or_error(name, where):
    """The catalog :class:`Kind` called ``name``.

    Parameters
    ----------
    name : str
    where : str
        Where the name was read (file and entry), for the error message.

    Raises
    ------
    LayoutError
        When there is no such kind; the message lists close matches.
    """
    kind = CATALOG.get(name) if isinstance(name, str) else None
    if kind is not None:
        return kind
    close = difflib.get_close_matches(str(name), CATALOG, n=3, cutoff=0.6)
    hint = (f"did you mean {' or '.join(repr(c) for c in close)}?" if close
            else "run `layout kinds` for the list")
    raise LayoutError(f"{where}: kind {name!r} is not in the catalog; {hint} "
                      "(or give an explicit size to use it as a plain label)")


class RuleItem(NamedTuple):
    """An item the default rules may constrain.

    Attributes
    ----------
    index : int
        Particle index returned by :meth:`LayoutBuilder.add_item`.
    kind : Kind
        Its kind, with the item's actual size (``dataclasses.replace`` the catalog
        entry when the item overrides it).
    group : hashable or None
        The item's group (any id); chairs gather around a table of the same group.
    rules : bool
        Whether rules apply *to* this item; an item with ``rules=False`` still serves
        as a partner (a sofa faces a TV whose own rules are off).
    rigid : bool
        Whether ``group`` is rigid: rules between two members of one rigid group are
        skipped, their offsets already fix how they stand to each other.
    """

    index: int
    kind: Kind
    group: object = None
    rules: bool = True
    rigid: bool = False


class Rule(NamedTuple):
    """One default rule that was applied: what it did, to which item, with which partner."""

    name: str
    index: int
    partner: int | None


def _first(items, names, group=None, used=None):
    """First item whose kind is in ``names``, preferring the same group and unused ones."""
    candidates = [r for r in items if r.kind.name in names]
    for pick in (
        lambda r: group is not None and r.group == group and (used is None or r.index not in used),
        lambda r: used is None or r.index not in used,
        lambda r: True,
    ):
        for r in candidates:
            if pick(r):
                return r
    return None


def _same_body(a, b):
    """Both in one rigid group: their relative pose is fixed already."""
    return a.rigid and a.group is not None and a.group == b.group


def pairings(items):
    """Partners the rules link, as ``{item index: partner RuleItem}``.

    Nightstands go to a bed (two per bed), office chairs to a desk (one per desk);
    coffee tables, armchairs, side tables and floor lamps to a sofa (the conversation
    group), else to an armchair; a partner in the same group wins. Only items whose rules
    are on get a partner. Used by :func:`apply_default_rules` and by the spec reader,
    which puts unrelated partners in a common group so they may stand in each other's
    clearance (a nightstand in the bed's side access, the chair in the desk's).
    """
    out = {}
    beds = [r for r in items if r.kind.name in ("bed", "single_bed")]
    per_bed = {b.index: 0 for b in beds}
    desks_used = set()
    for r in items:
        if not r.rules:
            continue
        name = r.kind.name
        if name == "nightstand" and beds:
            mates = [b for b in beds if b.group == r.group and r.group is not None]
            pool = mates or beds
            # Two nightstands per bed, then wrap around (a third one shares a side).
            bed = min(pool, key=lambda b: (per_bed[b.index] >= 2, per_bed[b.index], pool.index(b)))
            per_bed[bed.index] += 1
            out[r.index] = bed
        elif name == "office_chair":
            desk = _first(items, ("desk",), r.group, desks_used)
            if desk is not None:
                desks_used.add(desk.index)
                out[r.index] = desk
        elif name in ("coffee_table", "side_table", "floor_lamp", "armchair"):
            host = _first(items, ("sofa",), r.group) or (
                _first(items, ("armchair",), r.group) if name != "armchair" else None)
            if host is not None and host.index != r.index:
                out[r.index] = host
    return out


# The default rules that put an item at a spot in its partner's frame: it follows the partner.
PLACED_AT_PARTNER = ("in_front_of", "beside_coffee_table", "beside_arm", "under", "beside_head", "at_desk")


def _spot(builder, i, host, target_m, applied, name):
    """``i`` at ``target_m`` in ``host``'s frame (x front, y left), turned like it."""
    builder.heat([i], target_m, frame=host.index)
    builder.parallel(i, host.index)
    applied.append(Rule(name, i, host.index))


def _next_side(placed: dict, host: int) -> float:
    """+1 (left) for the first piece placed beside ``host``, -1 (right) for the second, and
    so on; ``placed`` counts them."""
    k = placed.get(host, 0)
    placed[host] = k + 1
    return 1.0 if k % 2 == 0 else -1.0


def _coffee_ahead_m(seat: Kind, table: Kind) -> float:
    """The coffee table's center ahead of its seat's center."""
    return COFFEE_GAP_M + 0.5 * (seat.size_m[1] + table.size_m[1])


def apply_default_rules(builder, items):
    """Add each kind's default constraints to ``builder``.

    Parameters
    ----------
    builder : LayoutBuilder
        Holds the items already (their indices are in ``items``).
    items : sequence of RuleItem
        Every item of the layout that may take part in a rule.

    Returns
    -------
    rules : list of Rule
        The rules applied, in order (for reports and tests).

    Notes
    -----
    * ``against_wall`` kinds: back to the nearest wall, facing the room.
    * sofa: faces the first TV stand (and the TV faces it) at 2.5 m.
    * coffee table: 0.45 m in front of its sofa (heat point in the sofa's frame),
      parallel to it.
    * armchair of a sofa with a coffee table: at an end of the coffee table, 0.4 m off
      it, facing it (left, then right); otherwise it faces the TV from 1.5-3.2 m.
    * side table, then floor lamp: beside the sofa's arms (left, then right), turned like
      it; a third finds no arm and gets no rule; one with no seat at all stands with its
      back within 0.3 m of a wall.
    * rug: under the sofa's front legs and the coffee table; without a sofa, under the
      coffee table or half under the foot end of a bed.
    * nightstand: beside the head of its bed (left, then right), facing like the bed.
    * chair/bench in the same group as a table: faces it and keeps about half the
      table's depth plus 0.25 m from its center; together they center on the table.
    * office chair: faces its desk from 0.35 m in front of the desk's edge.
    * theater seat: faces the first stage.
    """
    items = list(items)
    applied = []
    partner = pairings(items)
    tv = _first(items, ("tv_stand",))
    stage = _first(items, ("stage",))
    tables = [r for r in items if r.kind.name in TABLE_KINDS]
    coffee = _first(items, ("coffee_table",))
    bed = _first(items, ("bed", "single_bed"))
    sofa = _first(items, ("sofa",))
    beside = {}  # host index -> pieces placed beside it so far (nightstands, armchairs)
    seats_at = {}  # table index -> seats
    # The sofa's arms, left then right: side tables first, then lamps.
    arms = {}
    for r in sorted((r for r in items if r.kind.name in ("side_table", "floor_lamp") and r.index in partner),
                    key=lambda r: r.kind.name != "side_table"):
        taken = arms.setdefault(partner[r.index].index, [])
        if len(taken) < 2:
            taken.append(r.index)
    coffee_of = {p.index: r for r in items if r.kind.name == "coffee_table" and (p := partner.get(r.index))}

    for r in items:
        if not r.rules:
            continue
        k = r.kind
        i = r.index
        if k.against_wall:
            builder.against_wall(i)
            applied.append(Rule("against_wall", i, None))
        name = k.name
        if name == "sofa" and tv is not None and not _same_body(r, tv):
            builder.face(i, tv.index, mutual=tv.rules)
            builder.distance(i, tv.index, TV_DISTANCE_M)
            applied.append(Rule("face_tv", i, tv.index))
        elif (name == "armchair" and i in partner and partner[i].index in coffee_of
              and not _same_body(r, partner[i]) and not _same_body(r, coffee_of[partner[i].index])):
            s, table = partner[i], coffee_of[partner[i].index]
            ahead = _coffee_ahead_m(s.kind, table.kind)
            lateral = 0.5 * table.kind.size_m[0] + ARMCHAIR_GAP_M + 0.5 * k.size_m[1]
            builder.heat([i], (ahead, lateral * _next_side(beside, s.index)), frame=s.index)
            builder.face(i, table.index)
            applied.append(Rule("beside_coffee_table", i, table.index))
        elif name == "armchair" and tv is not None and not _same_body(r, tv):
            builder.face(i, tv.index)
            builder.distance(i, tv.index, 1.5, mode="min")
            builder.distance(i, tv.index, 3.2, mode="max")
            applied.append(Rule("face_tv", i, tv.index))
        elif name == "coffee_table" and i in partner and not _same_body(r, partner[i]):
            _spot(builder, i, partner[i], (_coffee_ahead_m(partner[i].kind, k), 0.0), applied, "in_front_of")
        elif name in ("side_table", "floor_lamp") and i in partner and i in arms.get(partner[i].index, ()):
            s = partner[i]
            side = 1.0 if arms[s.index].index(i) == 0 else -1.0
            back = -0.5 * (s.kind.size_m[1] - k.size_m[1]) + ARM_GAP_M
            lateral = 0.5 * (s.kind.size_m[0] + k.size_m[0]) + ARM_GAP_M
            if not _same_body(r, s):
                _spot(builder, i, s, (back, side * lateral), applied, "beside_arm")
        elif name in ("side_table", "floor_lamp") and i not in partner:
            # No seat to stand at: by a wall, not alone mid-floor where balance draws it.
            builder.wall_distance(i, 0.5 * k.size_m[1] + NEAR_WALL_M, mode="max")
            applied.append(Rule("by_wall", i, None))
        elif name == "rug":
            if sofa is not None and not _same_body(r, sofa):
                # Its back edge under the sofa's front legs.
                ahead = 0.5 * (sofa.kind.size_m[1] + k.size_m[1]) - RUG_UNDER_SOFA_M
                _spot(builder, i, sofa, (ahead, 0.0), applied, "under")
            else:
                host = coffee if coffee is not None else bed
                if host is not None and not _same_body(r, host):
                    # Under the coffee table; half under the foot end of a bed.
                    ahead = 0.0 if host is coffee else 0.5 * host.kind.size_m[1]
                    _spot(builder, i, host, (ahead, 0.0), applied, "under")
        elif name == "nightstand" and i in partner and not _same_body(r, partner[i]):
            b = partner[i]
            bw, bd = b.kind.size_m[:2]
            nw, nd = k.size_m[:2]
            # Left of the head first, then right (bed frame: x front, y left).
            lateral = (0.5 * (bw + nw) + 0.02) * _next_side(beside, b.index)
            back = -0.5 * (bd - nd)
            builder.heat([i], (back, lateral), frame=b.index)
            # Facing like the bed, written as an angle off the direction to the bed's
            # center (parallel would also accept facing the wall).
            builder.face(i, b.index, angle_rad=math.atan2(lateral, -back))
            applied.append(Rule("beside_head", i, b.index))
        elif name in SEAT_KINDS and r.group is not None and not r.rigid:
            table = next((t for t in tables if t.group == r.group), None)
            if table is not None:
                tw, td = table.kind.size_m[:2]
                near = 0.5 * min(tw, td) + 0.25
                far = 0.5 * max(tw, td) + 0.5 * k.size_m[1] + 0.1
                builder.face(i, table.index)
                if far - near < 0.2:
                    builder.distance(i, table.index, near)
                else:
                    # Rectangular table: anywhere from its long side to its short end.
                    builder.distance(i, table.index, near, mode="min")
                    builder.distance(i, table.index, far, mode="max")
                seats_at.setdefault(table.index, []).append(i)
                applied.append(Rule("at_table", i, table.index))
        elif name == "office_chair" and i in partner and not _same_body(r, partner[i]):
            d = partner[i]
            builder.face(i, d.index)
            builder.heat([i], (0.5 * d.kind.size_m[1] + 0.35, 0.0), frame=d.index)
            applied.append(Rule("at_desk", i, d.index))
        elif name == "seat" and stage is not None and not _same_body(r, stage):
            builder.face(i, stage.index)
            applied.append(Rule("face_stage", i, stage.index))

    # Seats spread around their table: their center of mass on the table's center.
    for t, seats in seats_at.items():
        if len(seats) >= 2:
            builder.heat(seats, (0.0, 0.0), frame=t)
            applied.append(Rule("around_table", t, None))
    return applied


def describe(kind: Kind) -> str:
    """One line of the catalog table: name, size, access, flags, label."""
    w, d, h = kind.size_m
    acc = "/".join(f"{a:g}" for a in kind.access_m)
    flags = ",".join(f for f, on in (("wall", kind.against_wall), ("no-collide", not kind.collides)) if on)
    return f"{kind.name:<15} {w:5.2f} {d:5.2f} {h:5.2f}  {acc:<17} {flags:<11} {kind.label}"
