"""exactff.testing as other projects use it: the strategies build valid data and reach
their hard cases, the assertions report what failed, ground_truth is the exact row."""

import numpy as np
import pytest
from hypothesis import find, given, settings
from hypothesis import strategies as st

import exactff as ef
from exactff.testing import (assert_form_factors_close, assert_reciprocity,
                             assert_rows_sum_to_one, ground_truth)
from exactff.testing.strategies import (enclosures, occluded_scenes, planar_polygons,
                                        points_above, scenes)

from common import examples, parallel_rect_corner, perpendicular_rect, rect_xy

# a search budget that reaches rare cases every time (the dev profile's 30 may not)
SEARCH = settings(database=None, max_examples=5000)
SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)


@given(data=st.data())
def test_points_above_are_in_front(data):
    P = data.draw(planar_polygons())
    p, n = data.draw(points_above(P))
    assert ef.unit_normal(P) @ (p - P.mean(axis=0)) > 0
    assert abs(np.linalg.norm(n) - 1) < 1e-12
    F = ef.point_polygon_form_factor(p, n, P)
    assert 0 <= F <= 1


def test_points_above_reach_the_plane_and_the_horizon():
    def near_plane(pn):
        return pn[0][2] < 1e-4
    p, _ = find(points_above(SQUARE), near_plane, settings=SEARCH)
    assert 0 < p[2] < 1e-4

    def grazing(pn):
        p, n = pn
        F = ef.point_polygon_form_factor(p, n, SQUARE)
        U = ef.point_polygon_form_factor(p, n, SQUARE, two_sided=True)
        # the horizon cuts the polygon: part of it is below
        below = np.any((SQUARE - p) @ n < 0) and np.any((SQUARE - p) @ n > 0)
        return below and F > 0 and U >= F
    find(points_above(SQUARE), grazing, settings=SEARCH)


@settings(max_examples=examples(20))
@given(case=enclosures())
def test_enclosure_rows_sum_to_one(case):
    scene, p, n = case
    assert_rows_sum_to_one(ef.form_factors(scene, p, n))


def test_enclosures_reach_obstacles_that_touch_the_floor():
    def touching(case):
        scene, _, _ = case
        lo, size = scene.bounds[0][2], np.ptp(scene.bounds, axis=0).max()
        return any(g != "room" and abs(c[2] - lo) <= 1e-12 * size for g, c in
                   zip(scene.groups, scene.centroids))
    find(enclosures(), touching, settings=SEARCH)


@settings(max_examples=examples(20))
@given(case=occluded_scenes())
def test_occluded_scenes_really_occlude(case):
    scene, p, n = case
    F = ef.form_factors(scene, p, n)
    U = ef.point_polygon_form_factors(p, n, scene)
    assert F[0] < U[0] * (1 - 1e-6)
    assert np.all(F <= U + 1e-12)


@settings(max_examples=examples(30))
@given(scene=scenes())
def test_scenes_are_valid_and_vary_in_size(scene):
    assert 1 <= len(scene) <= 8
    ef.describe(scene)


def test_strategy_options_are_checked_eagerly():
    with pytest.raises(ValueError, match="max_polygons"):
        scenes(max_polygons=0)
    with pytest.raises(ValueError, match="max_boxes"):
        enclosures(max_boxes=-1)
    with pytest.raises(ValueError, match="polygon"):
        points_above(np.zeros((2, 3)))


def test_assertions_report_the_polygon_and_the_amount():
    with pytest.raises(AssertionError, match=r"row 1, polygon 2.*error 0\.1"):
        assert_form_factors_close([[0, 0, 0], [0, 0, 0.1]], np.zeros((2, 3)))
    with pytest.raises(AssertionError, match=r"row 1 sums to 0\.9"):
        assert_rows_sum_to_one([[0.5, 0.5], [0.4, 0.5]])
    with pytest.raises(AssertionError, match="A_0 F_01"):
        assert_reciprocity([1.0, 2.0], [[0.0, 0.5], [0.2, 0.0]])


def test_ground_truth_is_the_exact_row_with_estimates():
    # unoccluded: points on the floor of the unit box, each value by Howell's catalogue
    # (the ceiling cut into four rectangles with a corner over the point, each wall into
    # two with an edge end beside it); design target 1e-13 + 1e-12 F
    box = ef.scenes.subdivided_box(1)
    pts = np.array([[0.5, 0.5, 0.0], [0.3, 0.65, 0.0], [0.05, 0.9, 0.0], [0.999, 0.002, 0.0]])
    F, E = ground_truth(box, pts, [0, 0, 1])
    assert F.shape == E.shape == (4, 6)
    for k, (x, y, _) in enumerate(pts):
        ceiling = sum(parallel_rect_corner(u, v, 1.0) for u in (x, 1 - x) for v in (y, 1 - y))
        def wall(d, s):         # a unit wall at distance d, the point beside it at s
            return perpendicular_rect(s, 1.0, d) + perpendicular_rect(1 - s, 1.0, d)
        walls = [wall(y, x), wall(1 - y, x), wall(x, y), wall(1 - x, y)]  # y=0, 1, x=0, 1
        ref = np.array([0.0, ceiling] + walls)
        assert np.all(np.abs(F[k] - ref) <= 1e-13 + 1e-12 * ref), (k, F[k] - ref)
        assert np.all(np.abs(F[k] - ref) <= E[k] + 4 * 2.0**-53 * ref), (k, F[k] - ref, E[k])
    # occluded: from the origin (normal +z) a 0.3 x 0.4 rectangle at height 1 hides the
    # corner [0, 0.6] x [0, 0.8] of a 1.5 x 1.1 rectangle at height 2 (central
    # projection doubles it); the visible L is the rectangle minus that corner
    near, far = rect_xy(0, 0.3, 0, 0.4, 1.0), rect_xy(0, 1.5, 0, 1.1, 2.0)
    F, E = ground_truth(ef.Scene.from_polygons([far, near]), [0, 0, 0], [0, 0, 1])
    ref = [parallel_rect_corner(1.5, 1.1, 2.0) - parallel_rect_corner(0.6, 0.8, 2.0),
           parallel_rect_corner(0.3, 0.4, 1.0)]
    assert np.all(np.abs(F - ref) <= 1e-11), F - ref
    assert np.all(np.abs(F - ref) <= E + 4 * 2.0**-53 * np.abs(ref)), (F - ref, E)
    # a closed room with blocks: every row from a centroid sums to 1
    scene = ef.scenes.cornell_box(closed=True)
    F, E = ground_truth(scene, scene.centroids[:4], scene.normals[:4])
    assert F.shape == E.shape == (4, len(scene))
    assert np.all(np.abs(F.sum(axis=1) - 1) <= 1e-11)
    assert np.all(E >= 0) and E.max() < 1e-13


