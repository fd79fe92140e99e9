"""Sizes a user controls are bounded, and what is checked below the bounds is fast: a
spec can neither hang `layout solve` (or the web app checking it) nor fill the memory."""
from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from layout import LayoutBuilder, LayoutError, Solver
from layout.geometry import segments_intersect, self_intersection
from layout.spec import MAX_ENTRIES, MAX_GROUP_DEPTH, spec_from_bytes

ROOM = "[room]\npolygon = [[0, 0], [5, 0], [5, 4], [0, 4]]\n"
SOFA = '[[items]]\nid = "sofa"\nkind = "sofa"\n'


def _every_pair(p):
    """The obvious reference: every pair of non-adjacent edges, in order."""
    m = len(p)
    for a in range(m):
        for b in range(a + 1, m):
            if b != a + 1 and not (a == 0 and b == m - 1) and \
                    segments_intersect(p[a], p[(a + 1) % m], p[b], p[(b + 1) % m]):
                return a, b
    return None


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(st.lists(st.tuples(st.integers(0, 4), st.integers(0, 4)), min_size=3, max_size=12),
       st.sampled_from([1e-3, 1.0, 250.0]))
def test_the_self_intersection_test_answers_as_testing_every_pair(corners, scale):
    """On a lattice, so that edges touch, overlap and meet at corners, as in a hand-made
    outline; with the same first pair."""
    p = np.array(corners, float) * scale
    assert self_intersection(p) == _every_pair(p)


def test_a_ten_thousand_corner_outline_is_checked_in_well_under_a_second():
    angle = np.linspace(0, 2 * np.pi, 10_000, endpoint=False)
    radius = 5 + 0.5 * np.sin(7 * angle)
    outline = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    t0 = time.perf_counter()
    assert self_intersection(outline) is None
    crossed = outline.copy()
    crossed[[100, 5100]] = crossed[[5100, 100]]
    assert self_intersection(crossed) is not None
    assert time.perf_counter() - t0 < 1.0


@pytest.mark.parametrize("text, needle", [
    (lambda: "[room]\npolygon = " + str([[round(5 * float(np.cos(a)), 4), round(5 * float(np.sin(a)), 4)]
                                          for a in np.linspace(0, 6.28, 10_000, endpoint=False)]) + "\n" + SOFA,
     "10,000 corners; a room's outline has at most 1,000"),
    (lambda: ROOM + "".join(f'[[groups]]\nid = "g{k}"\n' + (f'group = "g{k - 1}"\n' if k else "")
                            for k in range(5000)) + SOFA, f"nest more than {MAX_GROUP_DEPTH} deep"),
    (lambda: ROOM + "[solver]\nmax_iterations = 1000000000\n" + SOFA, "max_iterations: 1000000000 must be a whole"),
    (lambda: ROOM + f"[solver]\nmax_iterations = {2 ** 63 - 1}\n" + SOFA, "from 1 to 100,000"),
    (lambda: ROOM + "[solver]\nrestarts = -1\n" + SOFA, "restarts = -1 must be at least"),
    (lambda: ROOM + "".join(f'[[items]]\nid = "c{k}"\nkind = "chair"\ncount = 1000\n' for k in range(21)),
     f"more than {MAX_ENTRIES:,} items"),
    (lambda: ROOM + "[[items]]\n" + "x" * 10_000_000 + ' = 1\nid = "s"\nkind = "sofa"\n', "unknown field"),
])
def test_a_spec_past_a_limit_is_refused_at_once(text, needle):
    """Each was accepted and then took minutes, or gigabytes (1e9 iterations), or crashed
    (2**63): now one message, in well under a second, that names the limit."""
    data = text().encode()
    t0 = time.perf_counter()
    with pytest.raises(LayoutError) as error:
        spec_from_bytes(data, "room.toml")
    assert time.perf_counter() - t0 < 3.0
    message = str(error.value)
    assert needle in message and len(message) < 600, message[:300]


def test_the_builder_and_solver_bound_what_the_api_is_given():
    with pytest.raises(LayoutError, match="at most 1,000"):
        LayoutBuilder(np.column_stack([np.cos(np.linspace(0, 6, 2000)), np.sin(np.linspace(0, 6, 2000))]) * 3)
    for field, value in (("max_iterations", 10 ** 9), ("max_iterations", 2 ** 63), ("rate", float("inf")),
                         ("omega", 5.0), ("pad_m", float("nan"))):
        with pytest.raises(LayoutError, match=field):
            Solver(**{field: value})
