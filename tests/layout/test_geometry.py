"""Floor-plane geometry helpers against hand-computed answers."""
import numpy as np
import pytest

from layout.geometry import edge_distances, point_segment_distances, polygon_area, triangulate_polygon


def test_point_segment_distances_by_hand():
    points = [[0, 1], [3, 4], [-2, 0]]
    starts, ends = [[0, 0], [1, 1]], [[2, 0], [1, 1]]  # a segment on the x axis, and a point
    np.testing.assert_allclose(point_segment_distances(points, starts, ends),
                               [[1, 1], [np.hypot(1, 4), np.hypot(2, 3)], [2, np.hypot(3, 1)]])


def test_edge_distances_of_a_square():
    square = [[0, 0], [4, 0], [4, 3], [0, 3]]
    np.testing.assert_allclose(edge_distances([[1, 1], [5, 1]], square), [[1, 3, 2, 1], [np.hypot(1, 1), 1, np.hypot(1, 2), 5]])


def test_access_zones_by_hand():
    from layout.geometry import access_zones

    # 1 m wide, 2 m deep: clearance 0.5 ahead only; behind and left; none.
    zones = access_zones([[1, 2, 1]] * 3, [[0, 0, 0.5, 0], [0.4, 0.3, 0, 0], [0, 0, 0, 0]])
    np.testing.assert_allclose(zones[0], [1.25, 0, 0.5 * np.hypot(0.5, 1)])  # the box ahead: x 1..1.5
    # Behind (x -1.4..-1, y -0.5..0.5) and left (x -1..1, y 0.5..0.8): box x -1.4..1, y -0.5..0.8.
    np.testing.assert_allclose(zones[1], [-0.2, 0.15, 0.5 * np.hypot(2.4, 1.3)])
    np.testing.assert_array_equal(zones[2], [0, 0, -1])


def test_triangulate_an_l_shape_in_either_winding():
    ell = np.array([[0, 0], [4, 0], [4, 1], [1, 1], [1, 3], [0, 3]], float)
    for poly in (ell, ell[::-1]):
        tris = triangulate_polygon(poly)
        assert tris.shape == (4, 3)
        areas = [polygon_area(poly[t]) for t in tris]
        assert min(areas) > 0  # every triangle counter-clockwise
        assert sum(areas) == pytest.approx(6.0, abs=1e-12)
        # the reflex corner (1, 1) must not be cut off: no triangle covers the missing square
        centroids = poly[tris].mean(axis=1)
        assert not np.any((centroids[:, 0] > 1) & (centroids[:, 1] > 1))


def test_stepped_wall_finds_the_wall_an_outline_draws_in_steps():
    """By hand: a 4 x 3 m room whose bottom wall has a 6 cm deep, 0.4 m wide step (a
    door's threshold) under a 1 m opening: the opening lies on the line between the step
    and the wall, 1 m long; by a corner it slides along its wall; on a 0.6 m wall between
    two corners there is no place for it."""
    from layout.geometry import stepped_wall

    room = np.array([(0, 0), (1.8, 0), (1.8, 0.06), (2.2, 0.06), (2.2, 0), (4, 0), (4, 3), (0, 3)], float)
    at = stepped_wall(room, (2.0, 0.06), 1.0, 0.15)
    np.testing.assert_allclose(at[:, 0], [1.5, 2.5], atol=1e-9)  # in the outline's (counter-clockwise) direction
    assert np.all((at[:, 1] > 0.0) & (at[:, 1] < 0.06))
    np.testing.assert_allclose(stepped_wall(room, (3.7, 0.0), 1.0, 0.15), [[3.0, 0.0], [4.0, 0.0]], atol=0.01)
    assert stepped_wall(np.array([(0, 0), (0.6, 0), (0.6, 3), (0, 3)], float), (0.3, 0.0), 1.0, 0.15) is None
