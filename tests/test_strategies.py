"""The public hypothesis strategies build valid data, by construction."""

import numpy as np
import pytest
from hypothesis import given, settings

import exactff as ef
from exactff.testing.strategies import convex_polygons, planar_polygons, points, unit_vectors

from common import examples


@settings(max_examples=examples(200))
@given(P=planar_polygons(max_vertices=12))
def test_planar_polygons_are_valid_scenes(P):
    ef.scene.validate_polygon(P)
    assert P.shape[1] == 3 and 3 <= len(P) <= 12


@settings(max_examples=examples(200))
@given(P=convex_polygons())
def test_convex_polygons_are_convex_and_ccw(P):
    n = ef.unit_normal(P)
    k = len(P)
    turns = [np.cross(P[(i + 1) % k] - P[i], P[(i + 2) % k] - P[(i + 1) % k]) @ n
             for i in range(k)]
    assert min(turns) > 0


@given(v=unit_vectors(), p=points(3.0))
def test_unit_vectors_and_points(v, p):
    assert abs(np.linalg.norm(v) - 1) < 1e-15
    assert np.all(np.abs(p) <= 3.0)


def test_unknown_method_option_is_a_value_error():
    with pytest.raises(ValueError, match="hemicube"):
        ef.form_factors(ef.scenes.cornell_box(), [1, 1, 1], [0, 1, 0], method="hemicube",
                        colour="red")


def test_triangles_are_not_mostly_regular():
    # the gap rule used to replace about 45 % of triangles by the regular one
    from exactff.testing.strategies import polygons_2d

    seen = []

    @settings(max_examples=examples(300), database=None)
    @given(P=polygons_2d(3, 3))
    def collect(P):
        ang = np.sort(np.mod(np.arctan2(P[:, 1], P[:, 0]), 2 * np.pi))
        gaps = np.diff(np.r_[ang, ang[0] + 2 * np.pi])
        seen.append(np.ptp(gaps) < 1e-6)
        assert gaps.max() < np.pi

    collect()
    assert len(seen) > 50 and np.mean(seen) < 0.1
