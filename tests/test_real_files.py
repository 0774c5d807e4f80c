"""Real scene files (issue 29): degenerate faces dropped on request and counted
otherwise, collinear triangles far from the origin, nonplanar="split" at the cost of
what it splits, the scene summary without the BSP tree."""

from fractions import Fraction

import numpy as np
import pytest

import exactff as ef
from exactff.predicates import collinear

#: the issue's triangle: exactly collinear (its vertices differ in y only), 1e3 from the
#: origin
FAR_COLLINEAR = [[1620.33, -0.045731, -1013.51], [1620.33, -0.045334, -1013.51],
                 [1620.33, 0.016953, -1013.51]]


def _exactly_collinear(P):
    """The reference: every vertex's cross product with the first edge, in rationals."""
    X = [[Fraction(float(c)) for c in v] for v in P]
    d = [[v[k] - X[0][k] for k in range(3)] for v in X]
    e = max(d, key=lambda w: sum(c * c for c in w))
    return all(w[1] * e[2] == w[2] * e[1] and w[2] * e[0] == w[0] * e[2]
               and w[0] * e[1] == w[1] * e[0] for w in d)


# ---------------------------------------------------------------------------------------
# finding 2: collinear triangles far from the origin are zero area, not self-intersecting
# ---------------------------------------------------------------------------------------
def test_collinear_triangle_far_from_the_origin_is_zero_area():
    with pytest.raises(ef.SceneError, match="polygon 4: zero area"):
        ef.validate_polygon(FAR_COLLINEAR, index=4)
    moved = np.array(FAR_COLLINEAR) - np.array(FAR_COLLINEAR[0])
    with pytest.raises(ef.SceneError, match="zero area"):
        ef.validate_polygon(moved)


@pytest.mark.parametrize("origin", [[0.0, 0.0, 0.0], [1620.33, -1013.51, 7.1],
                                    [-3.3e6, 2.5e5, 1e7]])
@pytest.mark.parametrize("steps", [[0, 1, 3], [0, 5, 2, 7], [0, 1, 1, 2]])
def test_exactly_collinear_polygons_in_any_direction_are_zero_area(origin, steps):
    # vertices o + t d with dyadic d and small integers t: exactly collinear in floats
    # (checked in rationals), in a direction no coordinate plane contains
    d = np.array([0.125, 0.25, -0.375])
    P = np.array(origin) + np.outer(steps, d)
    assert _exactly_collinear(P)
    assert collinear(P)
    with pytest.raises(ef.SceneError, match="zero area|fewer than 3 distinct"):
        ef.validate_polygon(P)


@pytest.mark.parametrize("ulps", [1, 2, 7])
def test_a_triangle_one_ulp_off_its_line_is_valid_far_from_the_origin(ulps):
    # lifted by a few ulps of its z coordinate: not collinear (rationals), and valid
    # with the area of its exact coordinates
    P = np.array(FAR_COLLINEAR)
    z = P[1, 2]
    for _ in range(ulps):
        z = np.nextafter(z, 0)
    P[1, 2] = z
    assert not _exactly_collinear(P) and not collinear(P)
    s = ef.Scene.from_polygons([P])
    # the area: half the base (y extent) times the height (dz), both exact differences
    expect = 0.5 * (P[2, 1] - P[0, 1]) * (P[1, 2] - P[0, 2])
    assert s.areas[0] == pytest.approx(abs(expect), rel=1e-9)


def test_collinear_predicate_against_rationals_on_random_near_lines():
    rng = np.random.default_rng(29)
    seen = {True: 0, False: 0}
    for _ in range(400):
        o = rng.uniform(-2e3, 2e3, 3)
        scale = 2.0 ** -int(rng.integers(0, 20))
        d = (rng.integers(-8, 9, 3) if rng.random() < 0.5 else rng.normal(size=3)) * scale
        t = np.sort(rng.integers(-4, 5, size=int(rng.integers(3, 6))))
        P = o + np.outer(t, d)
        if rng.random() < 0.5:          # push one vertex off by an ulp
            k, axis = int(rng.integers(0, len(P))), int(rng.integers(0, 3))
            P[k, axis] = np.nextafter(P[k, axis], np.inf)
        truth = _exactly_collinear(P)
        assert collinear(P) == truth
        seen[truth] += 1
    assert seen[True] > 50 and seen[False] > 50
