import dataclasses
import time

import numpy as np
import pytest

from layout import geometry, metrics


def square(x0, y0, side=1.0):
    return np.array([[x0, y0], [x0 + side, y0], [x0 + side, y0 + side], [x0, y0 + side]])


def aabb(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64)


def readonly(*arrays):
    out = []
    for a in arrays:
        a = np.array(a, dtype=np.float64)
        a.setflags(write=False)
        out.append(a)
    return out


# L-shaped floor: 4 x 4 square without the [2, 4] x [2, 4] quadrant; reflex corner (2, 2).
L_FLOOR = np.array([[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]], dtype=np.float64)


def test_offset_unit_squares_overlap_half():
    assert metrics.convex_intersection_area(square(0, 0), square(0.5, 0)) == pytest.approx(0.5)


def test_rotated_square_against_axis_aligned_square():
    # Both unit squares centered at the origin; the 45° one is the diamond |x| + |y| <= √2/2.
    # It cuts four corner triangles off the axis-aligned square, each with legs
    # 0.5 - (√2/2 - 0.5) = 1 - √2/2, so they remove 4 · (1 - √2/2)² / 2 = 3 - 2√2 and the
    # octagon left has area 1 - (3 - 2√2) = 2(√2 - 1).
    diamond = geometry.box_corners([[0.0, 0.0]], [np.pi / 4], [1.0], [1.0])[0]
    area = metrics.convex_intersection_area(diamond, square(-0.5, -0.5))
    assert area == pytest.approx(2 * (np.sqrt(2) - 1), abs=1e-12)


def test_intersection_ignores_orientation_and_touching():
    a, b = square(0, 0), square(0.5, 0.25)
    expected = 0.5 * 0.75
    assert metrics.convex_intersection_area(a[::-1], b) == pytest.approx(expected)
    assert metrics.convex_intersection_area(a, b[::-1]) == pytest.approx(expected)
    assert metrics.convex_intersection_area(square(0, 0), square(1, 0)) == 0.0
    assert metrics.convex_intersection_area(square(0, 0), square(3, 3)) == 0.0


def test_box_overlaps_filters():
    corners = np.stack(
        [
            square(0, 0),  # 0 overlaps 1 by 0.5 m²
            square(0.5, 0),  # 1
            square(1.5, 0),  # 2 only touches 1 along x = 1.5
            square(0.2, 0.2),  # 3 overlaps 0 and 1 in plan but sits above them
            square(0.1, 0.1),  # 4 overlaps 0 and 1 but does not collide
        ]
    )
    z = np.array([[0, 1], [0, 1], [0, 1], [1, 2], [0, 1]], dtype=np.float64)
    collides = np.array([True, True, True, True, False])
    corners_ro, z_ro = readonly(corners, z)
    pairs, area = metrics.box_overlaps(corners_ro, z_ro, collides)
    np.testing.assert_array_equal(pairs, [[0, 1]])
    assert pairs.dtype == np.int64
    np.testing.assert_allclose(area, [0.5])

    # Lifted just above box 0's top, box 1 leaves it and meets box 3 instead.
    z_lifted = z.copy()
    z_lifted[1] = [1.0 + 1e-7, 2]
    np.testing.assert_array_equal(metrics.box_overlaps(corners, z_lifted, collides)[0], [[1, 3]])


def test_box_overlaps_matches_brute_force():
    rng = np.random.default_rng(7)
    n = 2000
    center = rng.uniform(0, 40, (n, 2))
    size = rng.uniform(0.2, 2.0, (n, 2))
    yaw = rng.uniform(-np.pi, np.pi, n)
    bottom = rng.uniform(0, 1.5, n)
    z = np.stack([bottom, bottom + rng.uniform(0.1, 1.0, n)], axis=1)
    # Edge cases: boxes 20-29 duplicate boxes 0-9; boxes 30-39 touch boxes 10-19 along
    # an edge (axis-aligned, so depth runs along x).
    yaw[:40] = 0.0
    for first, copy in ((slice(0, 10), slice(20, 30)), (slice(10, 20), slice(30, 40))):
        center[copy], size[copy], z[copy] = center[first], size[first], z[first]
    center[30:40, 0] += size[30:40, 1]
    corners = geometry.box_corners(center, yaw, size[:, 0], size[:, 1])
    collides = rng.random(n) < 0.9
    collides[:40] = True

    pairs, area = metrics.box_overlaps(corners, z, collides)

    # Reference: every pair, culled only by circumscribed circles (a strictly weaker test).
    radius = 0.5 * np.hypot(size[:, 0], size[:, 1])
    dist = np.linalg.norm(center[:, None] - center[None], axis=-1)
    i_idx, j_idx = np.nonzero(np.triu(dist <= radius[:, None] + radius[None] + 1e-9, k=1))
    expected_pairs, expected_area = [], []
    for i, j in zip(i_idx, j_idx):
        if not (collides[i] and collides[j]):
            continue
        if min(z[i, 1], z[j, 1]) - max(z[i, 0], z[j, 0]) <= 1e-6:
            continue
        a = metrics.convex_intersection_area(corners[i], corners[j])
        if a > 1e-6:
            expected_pairs.append((i, j))
            expected_area.append(a)
    assert len(expected_pairs) > 100
    np.testing.assert_array_equal(pairs, np.array(expected_pairs).reshape(-1, 2))
    np.testing.assert_allclose(area, expected_area, rtol=1e-9, atol=1e-12)
    # The duplicated boxes overlap their originals completely.
    for k in range(20, 30):
        row = np.flatnonzero((pairs[:, 0] == k - 20) & (pairs[:, 1] == k))
        assert area[row] == pytest.approx([size[k, 0] * size[k, 1]])
    # Edge-sharing boxes never count.
    for k in range(30, 40):
        assert not np.any((pairs[:, 0] == k - 20) & (pairs[:, 1] == k))


def test_box_overlaps_ten_thousand_boxes_is_fast():
    rng = np.random.default_rng(3)
    n = 10_000
    corners = geometry.box_corners(
        rng.uniform(0, 100, (n, 2)), rng.uniform(-np.pi, np.pi, n),
        rng.uniform(0.3, 2.0, n), rng.uniform(0.3, 2.0, n),
    )
    z = np.tile([0.0, 1.0], (n, 1))
    start = time.perf_counter()
    pairs, _ = metrics.box_overlaps(corners, z, np.ones(n, dtype=bool))
    elapsed = time.perf_counter() - start
    assert len(pairs) > 10_000
    # About 0.2 s here; the bound is loose for slow machines but fails any O(n²) scheme.
    assert elapsed < 2.0


def test_area_outside_l_shaped_floor():
    diamond_at_reflex = geometry.box_corners([[2.0, 2.0]], [np.pi / 4], [1.0], [1.0])[0]
    corners = np.stack(
        [
            square(0.5, 0.5),  # fully inside
            # Unit diamond centered on the reflex corner: by symmetry a quarter of it,
            # 0.25 m², lies in the missing quadrant.
            diamond_at_reflex,
            # [1.5, 3] x [1.8, 2.6]: the part with x > 2 and y > 2 is 1 x 0.6 outside.
            aabb(1.5, 1.8, 3.0, 2.6),
            square(2.5, 2.5),  # in the missing quadrant: fully outside
            square(3.5, 0.5),  # across the outer wall x = 4: half outside
            square(10, 10),  # far away
        ]
    )
    floor_ro, corners_ro = readonly(L_FLOOR, corners)
    out = metrics.area_outside(floor_ro, corners_ro)
    np.testing.assert_allclose(out, [0.0, 0.25, 0.6, 1.0, 0.5, 1.0], atol=1e-12)
    # A clockwise floor is the same floor.
    np.testing.assert_allclose(metrics.area_outside(L_FLOOR[::-1], corners), out, atol=1e-12)


def test_area_outside_box_across_both_arms_of_u_floor():
    # U floor: [0, 3]² minus the notch [1, 2] x [1, 3]. The box [-1, 4] x [2, 2.5]
    # (2.5 m²) keeps [0, 1] x [2, 2.5] and [2, 3] x [2, 2.5] (1 m²) on the floor.
    u_floor = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], float)
    out = metrics.area_outside(u_floor, aabb(-1, 2, 4, 2.5)[None])
    np.testing.assert_allclose(out, [1.5], atol=1e-12)


def test_door_clearance_hand_case():
    zones = np.stack([aabb(0, 0, 1, 1), aabb(5, 5, 6, 6)])
    corners = np.stack(
        [
            aabb(0.5, 0.5, 1.5, 1.5),  # blocks 0.5 x 0.5 = 0.25 m² of door 0
            aabb(0.0, 0.0, 1.0, 0.2),  # a rug: does not block
            aabb(0.8, 0.0, 2.0, 0.1),  # blocks 0.2 x 0.1 = 0.02 m² of door 0
        ]
    )
    blocks = np.array([True, False, True])
    zones_ro, corners_ro = readonly(zones, corners)
    np.testing.assert_allclose(
        metrics.door_clearance(zones_ro, corners_ro, blocks), [0.27, 0.0], atol=1e-12
    )
    np.testing.assert_array_equal(
        metrics.door_clearance(zones, corners[:0], blocks[:0]), [0.0, 0.0]
    )


def items(center, yaw, width, depth, access):
    """Footprints and access boxes of items, as the solver would pass them."""
    center = np.asarray(center, dtype=np.float64)
    corners = geometry.box_corners(center, yaw, width, depth)
    access = np.asarray(access, dtype=np.float64)
    return corners, geometry.access_box_corners(center, yaw, width, depth, access), access


ROOM = aabb(0, 0, 6, 3)
DOOR_LEFT = aabb(0.5, 0, 1.5, 0.9)[None]  # on the bottom wall of the left half


def test_empty_room_with_door_is_traversable():
    corners, access_corners, access = items(
        [[3.0, 1.5]], [0.0], [1.0], [0.5], [[0.0, 0.0, 0.6, 0.0]]
    )
    args = readonly(ROOM, corners, access_corners, access, DOOR_LEFT)
    result = metrics.traversability(args[0], args[1], [True], args[2], args[3], args[4])
    assert result.ok
    assert result.n_components == 1
    assert result.unreachable == () and result.blocked_doors == ()
    passable = result.passable
    # Pixel (r, c) covers origin + resolution * [c, c + 1] x [r, r + 1].
    def pixel(x, y):
        c, r = np.floor((np.array([x, y]) - result.origin_m) / result.resolution_m).astype(int)
        return passable[r, c]

    assert pixel(1.0, 1.5)  # open floor
    assert not pixel(3.0, 1.5)  # under the item
    assert not pixel(5.9, 1.5)  # within a person's half width of the wall
    assert pixel(1.0, 0.05)  # the door zone is walkable up to the wall
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.ok = False


def test_wall_of_wardrobes_splits_the_room():
    # Three wardrobes along x = 3 close the room from wall to wall; they open towards the
    # door's half. A chair in the other half faces them and needs its front free.
    corners, access_corners, access = items(
        [[3.0, 0.5], [3.0, 1.5], [3.0, 2.5], [5.0, 1.5]],
        [np.pi, np.pi, np.pi, np.pi],
        [1.0, 1.0, 1.0, 0.6],
        [0.6, 0.6, 0.6, 0.6],
        [[0, 0, 0.6, 0], [0, 0, 0.6, 0], [0, 0, 0.6, 0], [0, 0, 0.6, 0]],
    )
    result = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access, DOOR_LEFT)
    assert not result.ok
    assert result.n_components == 2
    assert result.unreachable == ((3, 2),)
    assert result.blocked_doors == ()

    # Without doors all access sides must still meet: here they cannot.
    no_doors = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access, np.zeros((0, 4, 2)))
    assert not no_doors.ok and no_doors.unreachable == ((3, 2),)

    # A chair that needs no access imposes nothing.
    access_free = access.copy()
    access_free[3] = 0
    calm = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access_free, DOOR_LEFT)
    assert calm.ok and calm.unreachable == ()


def test_past_an_open_edge_people_walk_around():
    """Three wardrobes across the room leave 0.3 m along the bottom edge, narrower than a
    person (0.5 m): with that edge a wall the chair's side is cut off; with it open (the
    photo's edge: the room goes on) people walk round past it, and only there."""
    corners, access_corners, access = items(
        [[3.0, 0.8], [3.0, 1.7], [3.0, 2.55]],
        [np.pi, np.pi, np.pi],
        [1.0, 0.8, 0.9],
        [0.6, 0.6, 0.6],
        [[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]],
    )
    chair_corners, chair_access, chair_depth = items([[5.0, 1.5]], [np.pi], [0.6], [0.6], [[0, 0, 0.6, 0]])
    corners = np.concatenate([corners, chair_corners])
    access_corners = np.concatenate([access_corners, chair_access])
    access = np.concatenate([access, chair_depth])
    walled = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access, DOOR_LEFT)
    assert not walled.ok and walled.unreachable == ((3, 2),)
    for wall in (1, 2, 3):  # the right, top and left edges open instead: still closed off
        other = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access, DOOR_LEFT,
                                       open_edges=[wall])
        assert not other.ok and other.unreachable == ((3, 2),)
    opened = metrics.traversability(ROOM, corners, np.ones(4, bool), access_corners, access, DOOR_LEFT,
                                    open_edges=[0])
    assert opened.ok and opened.n_components == 1

    def passable(result, x, y):
        c, r = np.floor((np.array([x, y]) - result.origin_m) / result.resolution_m).astype(int)
        return result.passable[r, c]

    assert passable(opened, 3.0, 0.0) and not passable(walled, 3.0, 0.0)  # round the wardrobes' end
    assert not passable(opened, 5.9, 1.5)  # the walls still keep a person's half width


@pytest.mark.parametrize("gap_m, passable", [(0.4, False), (0.7, True)])
def test_gap_between_boxes(gap_m, passable):
    # Two boxes across the room at x = 3 leave a gap centered on y = 1.5.
    low = 1.5 - gap_m / 2
    corners, access_corners, access = items(
        [[3.0, low / 2], [3.0, 3.0 - low / 2], [5.0, 1.5]],
        [0.0, 0.0, np.pi],
        [low, low, 0.6],
        [0.6, 0.6, 0.6],
        [[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0.6, 0]],
    )
    result = metrics.traversability(
        ROOM, corners, np.ones(3, bool), access_corners, access, DOOR_LEFT, radius_m=0.25
    )
    assert result.ok is passable
    assert result.unreachable == (() if passable else ((2, 2),))


def test_blocked_door():
    corners, access_corners, access = items(
        [[1.0, 0.6]], [0.0], [1.2], [1.4], [[0, 0, 0, 0]]
    )
    result = metrics.traversability(ROOM, corners, [True], access_corners, access, DOOR_LEFT)
    assert not result.ok
    assert result.blocked_doors == (0,)
    # A rug on the same spot blocks nothing.
    rug = metrics.traversability(ROOM, corners, [False], access_corners, access, DOOR_LEFT)
    assert rug.ok and rug.blocked_doors == ()


def test_shape_validation():
    with pytest.raises(ValueError):
        metrics.box_overlaps(np.zeros((3, 3, 2)), np.zeros((3, 2)), np.ones(3, bool))
    with pytest.raises(ValueError):
        metrics.area_outside(np.zeros((2, 2)), np.zeros((1, 4, 2)))
