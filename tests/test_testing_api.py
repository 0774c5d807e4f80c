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

from common import examples

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
        U = ef.point_polygon_form_factor(p, n, SQUARE, one_sided=False)
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
        lo = scene.bounds[0][2]
        return any(g != "room" and np.isclose(c[2], lo) for g, c in
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
    scene = ef.scenes.cornell_box(closed=True)
    pts, nrm = scene.centroids[:4], scene.normals[:4]
    F, E = ground_truth(scene, pts, nrm)
    assert F.shape == E.shape == (4, len(scene))
    assert_form_factors_close(F, ef.form_factors(scene, pts, nrm), rtol=0, atol=0)
    assert_rows_sum_to_one(F)
    assert np.all(E >= 0) and E.max() < 1e-13
