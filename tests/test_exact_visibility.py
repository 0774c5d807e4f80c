"""The tests' own reference for occluded values (tests/exact_visibility.py), against values
it does not compute: the kernel's mpmath value of the visible part where that part is
known in closed form, and the invariants a visible part must keep."""

from fractions import Fraction

import mpmath
import numpy as np
import pytest

import exactff as ef
from exactff.kernel import mp_form_factor

from common import rect_xy, rotation
from exact_visibility import (polygon_form_factor_mp, seen_whole, unoccluded_form_factor,
                              visible_form_factor, visible_pieces)

P, N = np.array([0.5, 0.5, 2.0]), np.array([0.0, 0.0, -1.0])
FLOOR = rect_xy(0, 1, 0, 1, 0.0, facing_down=False)


def value(scene, j, **kw):
    U = visible_form_factor(scene, P, N, j, **kw)
    assert U is not None
    return float(U)


def test_unoccluded_is_the_kernels_value():
    scene = ef.Scene([FLOOR])
    assert value(scene, 0) == pytest.approx(mp_form_factor(P, N, FLOOR, tolerance=1e-30),
                                            rel=1e-15)


def test_a_blocker_leaves_a_known_rectangle():
    # a slab at z = 1 over x >= 0.5: its shadow from P, twice as large about P, covers
    # x >= 0.5 of the floor; what remains is [0, 0.5] x [0, 1]
    blocker = rect_xy(0.5, 2, -2, 3, 1.0)
    scene = ef.Scene([FLOOR, blocker])
    rest = rect_xy(0, 0.5, 0, 1, 0.0, facing_down=False)
    assert value(scene, 0) == pytest.approx(mp_form_factor(P, N, rest, tolerance=1e-30),
                                            rel=1e-15)
    pieces = visible_pieces(scene, P, 0)
    area = sum(abs(float(_area_xy(q))) for q in pieces)
    assert area == pytest.approx(0.5, rel=1e-15)


def _polar_form_factor(polygon, h):
    """From the origin (normal z) to a convex polygon in the plane z = h around the z
    axis, by quadrature in polar angle: the disc of radius R gives R^2 / (R^2 + h^2) / 2,
    so F = int R(phi)^2 / (R(phi)^2 + h^2) dphi / (2 pi), R from each edge's line."""
    V = [[mpmath.mpf(float(c)) for c in v[:2]] for v in polygon]
    total = mpmath.mpf(0)
    for k in range(len(V)):
        (ax, ay), (bx, by) = V[k], V[(k + 1) % len(V)]
        # the edge's line: its unit normal (cos alpha, sin alpha) at distance d
        nx, ny = by - ay, ax - bx
        length = mpmath.sqrt(nx * nx + ny * ny)
        nx, ny = nx / length, ny / length
        d = nx * ax + ny * ay
        alpha = mpmath.atan2(ny, nx)
        # the angle the edge subtends, signed by the polygon's orientation
        phi_a = mpmath.atan2(ay, ax)
        phi_b = phi_a + mpmath.atan2(ax * by - ay * bx, ax * bx + ay * by)

        def share(phi):
            R2 = (d / mpmath.cos(phi - alpha)) ** 2
            return R2 / (R2 + h * h)
        total += mpmath.quad(share, [phi_a, phi_b])
    return abs(total) / (2 * mpmath.pi)


def test_a_hole_to_the_working_precision():
    # a triangle at z = 1 casts a hole in one at z = 2 (from the origin, looking up): the
    # hole is the small triangle doubled (exact in floats), so the visible part's value is
    # the big triangle's less the doubled small one's, each by quadrature in polar angle;
    # the reference keeps its working precision (a double's rounding is 7e-18 here)
    big = np.array([[1.0, 0.0, 2.0], [-0.4999999999999998, -0.8660254037844387, 2.0],
                    [-0.5000000000000004, 0.8660254037844384, 2.0]])
    small = np.array([[0.125, 0.0, 1.0], [-0.06249999999999997, -0.10825317547305484, 1.0],
                      [-0.06250000000000006, 0.1082531754730548, 1.0]])
    U = visible_form_factor(ef.Scene([big, small]), np.zeros(3), np.array([0.0, 0.0, 1.0]), 0)
    with mpmath.workdps(40):
        expected = _polar_form_factor(big, 2) - _polar_form_factor(2 * small, 2)
        assert abs(U - expected) <= mpmath.mpf(10) ** -30


def test_a_blocker_across_the_cone_hides_all():
    scene = ef.Scene([FLOOR, rect_xy(-5, 5, -5, 5, 1.0)])
    assert visible_pieces(scene, P, 0) == []
    assert value(scene, 0) == 0


def test_a_blocker_behind_the_target_hides_nothing():
    scene = ef.Scene([FLOOR, rect_xy(-5, 5, -5, 5, -1.0)])
    assert value(scene, 0) == pytest.approx(value(ef.Scene([FLOOR]), 0), rel=1e-15)


def test_one_sided_and_two_sided():
    back = FLOOR[::-1].copy()   # facing down, away from P
    scene = ef.Scene([back])
    assert value(scene, 0) == 0
    assert value(scene, 0, two_sided=True) == pytest.approx(value(ef.Scene([FLOOR]), 0),
                                                            rel=1e-15)


def test_splitting_the_blocker_changes_nothing():
    # two halves of a blocker hide what the whole one hides (the visible part of the
    # floor behind a tilted slab, two ways)
    R = rotation(np.array([1.0, 2.0, 0.5]), 0.3)
    whole = rect_xy(-0.2, 0.2, -0.15, 0.15, 0.0) @ R.T + [0.6, 0.45, 1.0]
    # (rotated, none is exactly planar: each lies wholly between the point and the
    # floor, so its whole image hides)
    halves = [rect_xy(a, b, -0.15, 0.15, 0.0) @ R.T + [0.6, 0.45, 1.0]
              for a, b in ((-0.2, 0.05), (0.05, 0.2))]
    one = visible_form_factor(ef.Scene([FLOOR, whole]), P, N, 0)
    two = visible_form_factor(ef.Scene([FLOOR] + halves), P, N, 0)
    unoccluded = value(ef.Scene([FLOOR]), 0)
    assert one is not None and two is not None
    assert 0 < float(one) < unoccluded
    assert float(one) == pytest.approx(float(two), rel=1e-14)


def test_coplanar_ties_follow_the_rule():
    # coincident squares: the one facing the point hides the one facing away, whatever
    # their order; facing alike, the first in input order hides the second
    whole = value(ef.Scene([FLOOR]), 0, two_sided=True)
    back = FLOOR[::-1].copy()
    for scene, shown in ((ef.Scene([FLOOR, back]), 0), (ef.Scene([back, FLOOR]), 1),
                         (ef.Scene([FLOOR, FLOOR.copy()]), 0)):
        values = [value(scene, j, two_sided=True) for j in range(2)]
        assert values[shown] == pytest.approx(whole, rel=1e-15)
        assert values[1 - shown] == 0


def test_undecided_where_the_construction_does_not_apply():
    # a non-convex target
    L = np.array([[0, 0, 0], [1, 0, 0], [1, 0.5, 0], [0.5, 0.5, 0], [0.5, 1, 0], [0, 1, 0.]])
    assert visible_form_factor(ef.Scene([L]), P, N, 0) is None


def test_the_engines_conventions_decided_or_left_undecided():
    # found by drawn scenes (occluded_scenes), from the origin looking up. A vertical
    # triangle whose plane passes 0.4 ulp from the point: the engines see it edge-on
    # (no image), its exact image is a sliver of F = 6.5e-20
    big = np.array([[2.0, 0.0, 2.0], [-0.9999999999999996, -1.7320508075688774, 2.0],
                    [-1.0000000000000009, 1.7320508075688767, 2.0]])
    edge_on = np.array([[0.7080734182735711, -0.4546487134128409, 1.9596976941318602],
                        [-0.7477740447502165, 0.4801401925214618, 2.041415903542922],
                        [0.03970062647664507, -0.025491479108620707, 3.4988864023252177]])
    p, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    scene = ef.Scene([big, edge_on])
    assert visible_form_factor(scene, p, n, 1) is None
    # and the sliver it would hide of the triangle it crosses: undecided too
    assert visible_form_factor(scene, p, n, 0) is None
    assert visible_form_factor(ef.Scene([big]), p, n, 0) > 0
    # a triangle and a smaller one on its plane, each rounded its own way after the
    # rotation: each within the other's near-coplanar band, so a depth tie by the rule of
    # docs/explanation/conventions.md (the first in input order in front), which the
    # construction now decides as the engines do: the outer one whole, the inner hidden
    # (exactly, the smaller one would be wholly in front within the cone over it)
    outer = np.array([[2.0, 0.0, 0.7679491924311226], [0.5000000000000002, 1.7320508075688774,
                      3.3660254037844384], [0.49999999999999956, -1.7320508075688767,
                      3.3660254037844393]])
    inner = np.array([[1.5, 0.0, 1.6339745962155612], [0.7500000000000001, 0.8660254037844387,
                      2.933012701892219], [0.7499999999999998, -0.8660254037844384,
                      2.9330127018922196]])
    pair = ef.Scene([outer, inner])
    alone = visible_form_factor(ef.Scene([outer]), p, n, 0, two_sided=True)
    assert visible_form_factor(pair, p, n, 0, two_sided=True) == alone > 0
    assert visible_form_factor(pair, p, n, 1, two_sided=True) == 0
    # and one lying off the other's band by far more than its own: the exact geometry
    lifted = ef.Scene([outer, inner + 1e-9 * np.cross(outer[1] - outer[0], outer[2] - outer[0])])
    for j in (0, 1):
        assert visible_form_factor(lifted, p, n, j, two_sided=True) is not None
    # both decided without the other
    assert visible_form_factor(ef.Scene([inner]), p, n, 0, two_sided=True) > 0


def test_mpmath_contour_converges_on_a_sliver():
    # office(600) from (7.5, 1.8, 6): floor tile 174 shows a sliver of 2.4e-32 m^2, far
    # below double precision's resolution; 60 and 100 digits agree
    scene = ef.scenes.office(600)
    p, n = np.array([7.5, 1.8, 6.0]), np.array([0.0, 0.0, -1.0])
    a = visible_form_factor(scene, p, n, 174, dps=60)
    b = visible_form_factor(scene, p, n, 174, dps=100)
    assert 1e-34 < b < 1e-33
    assert abs(a - b) <= mpmath.mpf(10) ** -40 * b


def _area_xy(q):
    return sum(q[k][0] * q[(k + 1) % len(q)][1] - q[(k + 1) % len(q)][0] * q[k][1]
               for k in range(len(q))) / 2


#: an L-shaped target at z = 2 facing down (its image is not convex: visible_pieces
#: leaves it undecided) over the point (0.5, 0.5, 0) facing up
L_SHAPE = np.array([[0, 0, 2], [2, 0, 2], [2, 1, 2], [1, 1, 2], [1, 2, 2], [0, 2, 2.0]])[::-1]


def _speck(x, d=2e-6, z=1.0):
    return np.array([[x, x, z], [x + d, x, z], [x + d, x + d, z], [x, x + d, z]])[::-1]


def test_seen_whole_finds_a_speck_of_shadow_on_a_nonconvex_target():
    p, n = np.array([0.5, 0.5, 0.0]), np.array([0.0, 0.0, 1.0])
    # a speck at x casts its shadow at 2x - 0.5: at 0.3 (on the L) for x = 0.4, at -0.3
    # (off it) for x = 0.1, at 1.3 (in the L's notch: inside its hull, so not decided
    # whole: the check is conservative) for x = 0.9
    hiding = ef.Scene.from_polygons([L_SHAPE, _speck(0.4)])
    aside = ef.Scene.from_polygons([L_SHAPE, _speck(0.1)])
    behind = ef.Scene.from_polygons([L_SHAPE, _speck(0.4, z=3.0)])
    assert not seen_whole(hiding, p, 0) and seen_whole(hiding, p, 1)
    assert seen_whole(aside, p, 0) and seen_whole(behind, p, 0)
    assert not seen_whole(ef.Scene.from_polygons([L_SHAPE, _speck(0.9)]), p, 0)
    assert unoccluded_form_factor(hiding, p, n, 0) is None
    # the L's whole value: the sum of its two rectangles' (contour form at 60 digits)
    rects = [rect_xy(0, 2, 0, 1, 2.0), rect_xy(0, 1, 1, 2, 2.0)]
    with mpmath.workdps(60):
        expect = sum(polygon_form_factor_mp(
            p, n, [tuple(Fraction(float(c)) for c in v) for v in R]) for R in rects)
        assert abs(unoccluded_form_factor(aside, p, n, 0) - expect) < 1e-50
