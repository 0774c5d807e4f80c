"""Area-to-area form factors, unoccluded (issue 15, item 1): ``polygon_form_factor``.

References: Howell's catalogue (C-11, parallel opposed rectangles; C-14, perpendicular
rectangles with a common edge), evaluated here in mpmath at 40 digits (the double
closed forms cancel badly for small or far rectangles); reciprocity; splitting.
"""

import math
import os

import mpmath as mp

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

import exactff as ef
from exactff.area import AreaStats
from exactff.testing.strategies import occluded_scenes, polygons_2d

from common import checkout_env, examples, rotation, rotations


def howell_parallel(a, b, c):
    """C-11: a x b rectangles in parallel planes c apart, directly opposed."""
    with mp.workdps(40):
        X, Y = mp.mpf(a) / c, mp.mpf(b) / c
        t = (mp.log(mp.sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)))
             + X * mp.sqrt(1 + Y * Y) * mp.atan(X / mp.sqrt(1 + Y * Y))
             + Y * mp.sqrt(1 + X * X) * mp.atan(Y / mp.sqrt(1 + X * X))
             - X * mp.atan(X) - Y * mp.atan(Y))
        return float(2 / (mp.pi * X * Y) * t)


def howell_perpendicular(h, l, w):
    """C-14: from a w x l rectangle to an h x l one, perpendicular, sharing the edge l."""
    with mp.workdps(40):
        H, W = mp.mpf(h) / l, mp.mpf(w) / l
        S = H * H + W * W
        t = W * mp.atan(1 / W) + H * mp.atan(1 / H) - mp.sqrt(S) * mp.atan(1 / mp.sqrt(S))
        g = (mp.log((1 + W * W) * (1 + H * H) / (1 + S))
             + W * W * mp.log(W * W * (1 + S) / ((1 + W * W) * S))
             + H * H * mp.log(H * H * (1 + S) / ((1 + H * H) * S))) / 4
        return float((t + g) / (mp.pi * W))


def parallel_pair(a, b, c):
    P = np.array([[0, 0, 0], [a, 0, 0], [a, b, 0], [0, b, 0]], float)
    Q = np.array([[0, 0, c], [0, b, c], [a, b, c], [a, 0, c]], float)
    return P, Q


def perpendicular_pair(h, l, w):
    P = np.array([[0, 0, 0], [w, 0, 0], [w, l, 0], [0, l, 0]], float)      # faces +z
    Q = np.array([[0, 0, 0], [0, l, 0], [0, l, h], [0, 0, h]], float)      # faces +x
    return P, Q


def _safe_log_term(coef, arg):
    return mp.mpf(0) if arg == 0 else coef * mp.log(arg)


def _safe_atan_term(v, r):
    return mp.mpf(0) if r == 0 else v * r * mp.atan(v / r)


def gross_parallel(x, y, xi, eta, c):
    """Aligned parallel rectangles in general position (Gross, Spindler and Hahne 1981,
    the superposition of Howell's C-11): from [x1, x2] x [y1, y2] in z = 0 to
    [xi1, xi2] x [eta1, eta2] in z = c, in mpmath at 40 digits."""
    with mp.workdps(40):
        x, y, xi, eta = ([mp.mpf(v) for v in r] for r in (x, y, xi, eta))
        c, total = mp.mpf(c), mp.mpf(0)
        for i, j, k, l in np.ndindex(2, 2, 2, 2):
            u, v = x[i] - xi[k], y[j] - eta[l]
            G = (_safe_atan_term(v, mp.sqrt(u * u + c * c)) + _safe_atan_term(u, mp.sqrt(v * v + c * c))
                 - _safe_log_term(c * c / 2, u * u + v * v + c * c))
            total += (-1) ** (i + j + k + l) * G
        return float(total / (2 * mp.pi * (x[1] - x[0]) * (y[1] - y[0])))


def gross_perpendicular(x, y, eta, z):
    """Rectangles in perpendicular planes in general position (the superposition of
    C-14): from x in [x1, x2] (x >= 0), y in [y1, y2] in the plane z = 0, facing +z, to
    y in [eta1, eta2], z in [z1, z2] (z >= 0) in the plane x = 0, facing +x; mpmath at 40
    digits. Touching edges and corners are limits (0 log 0 = 0)."""
    with mp.workdps(40):
        x, y, eta, z = ([mp.mpf(v) for v in r] for r in (x, y, eta, z))
        total = mp.mpf(0)
        for i, j, k, l in np.ndindex(2, 2, 2, 2):
            d, s = y[j] - eta[k], x[i] ** 2 + z[l] ** 2
            G = _safe_atan_term(d, mp.sqrt(s)) - _safe_log_term((s - d * d) / 4, s + d * d)
            total += (-1) ** (i + j + k + l) * G
        return float(total / (2 * mp.pi * (x[1] - x[0]) * (y[1] - y[0])))


def aligned_rectangles_form_factor(P, Q):
    """F(P -> Q) for two axis-aligned rectangles (Gross et al.'s closed forms), each on
    one side of the other's plane: 0 unless their fronts face each other."""
    P, Q = np.asarray(P, float), np.asarray(Q, float)
    nP, nQ = (np.cross(R[1] - R[0], R[2] - R[0]) for R in (P, Q))
    a, b = int(np.argmax(np.abs(nP))), int(np.argmax(np.abs(nQ)))
    lo = lambda R, k: R[:, k].min()                                   # noqa: E731
    hi = lambda R, k: R[:, k].max()                                   # noqa: E731
    span = lambda R, k: (lo(R, k), hi(R, k))                          # noqa: E731
    towards = lambda n, R, k, plane: n[k] * (R[:, k].mean() - plane)  # noqa: E731
    if towards(nP, Q, a, P[0, a]) <= 0 or towards(nQ, P, b, Q[0, b]) <= 0:
        return 0.0
    if a == b:
        u, v = [k for k in range(3) if k != a]
        return gross_parallel(span(P, u), span(P, v), span(Q, u), span(Q, v),
                              abs(Q[0, a] - P[0, a]))
    c = 3 - a - b
    x = sorted(abs(t - Q[0, b]) for t in span(P, b))      # P's distances from Q's plane
    z = sorted(abs(t - P[0, a]) for t in span(Q, a))      # Q's distances from P's plane
    return gross_perpendicular(x, span(P, c), span(Q, c), z)


def test_gross_references_reduce_to_howell():
    # the general-position references against the catalogue's own cases
    for a, b, c in [(1, 1, 1), (1, 2, 0.5), (3, 0.2, 1)]:
        assert aligned_rectangles_form_factor(*parallel_pair(a, b, c)) == pytest.approx(
            howell_parallel(a, b, c), rel=1e-14)
    for h, l, w in [(1, 1, 1), (2, 1, 0.5), (0.1, 3, 1)]:
        assert aligned_rectangles_form_factor(*perpendicular_pair(h, l, w)) == pytest.approx(
            howell_perpendicular(h, l, w), rel=1e-14)
    # and against values of a 30-point Gauss-Legendre product rule (in each of the four
    # coordinates) on separated pairs, quoted (the closed forms were 3e-17 and 1e-17
    # from them)
    P = np.array([[0, 0, 0], [.5, 0, 0], [.5, .5, 0], [0, .5, 0]], float)
    Q = np.array([[.5, .5, 1], [.5, 1, 1], [1, 1, 1], [1, .5, 1]], float)
    assert aligned_rectangles_form_factor(P, Q) == pytest.approx(0.03510710090969401, rel=1e-14)
    P = np.array([[.2, 0, 0], [1, 0, 0], [1, .5, 0], [.2, .5, 0]], float)
    Q = np.array([[0, .1, .3], [0, .9, .3], [0, .9, 1], [0, .1, 1]], float)
    assert aligned_rectangles_form_factor(P, Q) == pytest.approx(0.08437647949468154, rel=1e-14)


@pytest.mark.parametrize("a,b,c", [
    (1, 1, 1), (1, 2, 0.5), (3, 0.2, 1), (0.01, 0.01, 1), (10, 10, 0.1), (100, 1, 1),
    (1e-3, 2e-3, 10), (1, 1, 1e4), (2, 7, 3), (0.5, 0.5, 2.9), (0.5, 0.5, 3.1)])
def test_parallel_rectangles_howell(a, b, c):
    P, Q = parallel_pair(a, b, c)
    ref = howell_parallel(a, b, c)
    assert ef.polygon_form_factor(P, Q) == pytest.approx(ref, rel=1e-12)


@pytest.mark.parametrize("h,l,w", [
    (1, 1, 1), (2, 1, 0.5), (0.1, 3, 1), (5, 0.2, 5), (1, 10, 1), (0.01, 1, 0.01),
    (100, 1, 0.5), (0.3, 0.7, 20)])
def test_perpendicular_rectangles_with_a_common_edge_howell(h, l, w):
    P, Q = perpendicular_pair(h, l, w)
    assert np.cross(Q[1] - Q[0], Q[2] - Q[0])[0] > 0
    ref = howell_perpendicular(h, l, w)
    assert ef.polygon_form_factor(P, Q) == pytest.approx(ref, rel=1e-12)


@st.composite
def facing_convex_pairs(draw):
    """Two convex polygons (3 to 6 vertices, stretched in x and y) in parallel planes
    0.05 to 8 apart, facing each other, offset sideways, under a drawn rotation."""
    def polygon():
        P2 = draw(polygons_2d(3, 6, convex=True)) * [draw(st.floats(0.3, 1.5)),
                                                       draw(st.floats(0.3, 1.5))]
        return np.column_stack([P2, np.zeros(len(P2))])
    P = polygon()                                         # faces +z
    Q = polygon()[::-1] + [draw(st.floats(-1, 1)), draw(st.floats(-1, 1)),
                           draw(st.floats(0.05, 8.0))]    # faces -z
    M = draw(rotations())
    return P @ M.T, Q @ M.T


@given(facing_convex_pairs())
@settings(max_examples=examples(40), deadline=None)
def test_reciprocity_on_random_pairs(pair):
    P, Q = pair
    ap = np.linalg.norm(ef.area_vector(P))
    aq = np.linalg.norm(ef.area_vector(Q))
    fpq, fqp = ef.polygon_form_factor(P, Q), ef.polygon_form_factor(Q, P)
    assert fpq > 0
    assert ap * fpq == pytest.approx(aq * fqp, rel=1e-12)


def test_splitting_the_receiver_and_the_emitter():
    P, Q = parallel_pair(1.0, 1.0, 0.7)
    Q = Q + [0.3, -0.2, 0]
    whole = ef.polygon_form_factor(P, Q)
    # Q cut in two along x = 0.55
    Q1 = np.array([[0.3, -0.2, 0.7], [0.3, 0.8, 0.7], [0.55, 0.8, 0.7], [0.55, -0.2, 0.7]])
    Q2 = np.array([[0.55, -0.2, 0.7], [0.55, 0.8, 0.7], [1.3, 0.8, 0.7], [1.3, -0.2, 0.7]])
    assert ef.polygon_form_factor(P, Q1) + ef.polygon_form_factor(P, Q2) == pytest.approx(whole, rel=1e-12)
    # P cut in two: area-weighted
    P1 = np.array([[0, 0, 0], [0.4, 0, 0], [0.4, 1, 0], [0, 1, 0]], float)
    P2 = np.array([[0.4, 0, 0], [1, 0, 0], [1, 1, 0], [0.4, 1, 0]], float)
    combined = 0.4 * ef.polygon_form_factor(P1, Q) + 0.6 * ef.polygon_form_factor(P2, Q)
    assert combined == pytest.approx(whole, rel=1e-12)


def _rect_xy(x0, x1, y0, y1):
    return np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]], float)


def _wall_minus_y(x0, x1, y, h):
    """A vertical rectangle in the plane y = const, facing -y."""
    return np.array([[x0, y, 0], [x0, y, h], [x1, y, h], [x1, y, 0]][::-1], float)


@pytest.mark.parametrize("x0, x1", [(0.2, 0.6), (-0.1, 0.3), (0.1, 0.4), (-0.2, 0.7)])
def test_partly_shared_edges_split_into_wholly_shared_ones(x0, x1):
    # a wall standing on an emitter's edge over part of it (T-junctions: a vertex of one
    # in the interior of the other's edge). Cut at those vertices, every touching pair
    # shares whole edges or end points, where the contour rule is checked against
    # Howell; the pieces' sum must give the whole (it was off by 8e-7 when the outer
    # rule ran across the junction)
    P, Q = _rect_xy(0, 0.5, 0, 0.3), _wall_minus_y(x0, x1, 0.3, 0.35)
    whole = 0.15 * ef.polygon_form_factor(P, Q)
    xs = sorted({0.0, 0.5, x0, x1})
    px = [x for x in xs if 0 <= x <= 0.5]
    qx = [x for x in xs if x0 <= x <= x1]
    parts = sum((b - a) * 0.3 * ef.polygon_form_factor(_rect_xy(a, b, 0, 0.3), _wall_minus_y(c, d, 0.3, 0.35))
                for a, b in zip(px, px[1:]) for c, d in zip(qx, qx[1:]))
    assert whole == pytest.approx(parts, rel=1e-13, abs=1e-17)
    # reciprocity across the junction
    back = (x1 - x0) * 0.35 * ef.polygon_form_factor(Q, P)
    assert whole == pytest.approx(back, rel=1e-13)


def test_non_convex_emitter_equals_its_convex_parts():
    # an L-shaped emitter and its two rectangles (a far receiver: the area integral's
    # triangulation; a near one: the contour integral)
    L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    R1 = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], float)
    R2 = np.array([[0, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    for z in (0.8, 20.0):
        Q = np.array([[0, 0, z], [0, 2, z], [2, 2, z], [2, 0, z]], float)
        parts = 2 * ef.polygon_form_factor(R1, Q) + 1 * ef.polygon_form_factor(R2, Q)
        assert 3 * ef.polygon_form_factor(L, Q) == pytest.approx(parts, rel=1e-12)


def test_one_sided():
    P, Q = parallel_pair(1, 1, 1)
    assert ef.polygon_form_factor(P, Q[::-1]) == 0.0      # Q faces away from P
    assert ef.polygon_form_factor(P[::-1], Q) == 0.0      # P faces away from Q
    # Q half behind P's plane: only its front half counts
    Qh = np.array([[0, 0, 0.5], [0, 1, 0.5], [0, 1, -0.5], [0, 0, -0.5]], float)
    Qf = np.array([[0, 0, 0.5], [0, 1, 0.5], [0, 1, 0.0], [0, 0, 0.0]], float)
    P2 = np.array([[0.1, 0, 0], [1.1, 0, 0], [1.1, 1, 0], [0.1, 1, 0]], float)
    assert ef.polygon_form_factor(P2, Qh) == pytest.approx(ef.polygon_form_factor(P2, Qf), rel=1e-12)


def test_clipping_twice_repeats_no_vertex():
    # the closed Cornell box's ceiling against a wall: cutting the ceiling at the wall's
    # plane a second time met a vertex on that plane and repeated it (an edge of length
    # 0: 0/0 in the contour rule's cuts, NaN had it been the receiver's)
    import warnings

    from exactff.halfspace import clip_front as _clip_front

    scene = ef.scenes.cornell_box(closed=True)
    P, Q = (np.asarray(scene.polygons[k], float) for k in (3, 8))
    nQ = ef.area_vector(Q) / np.linalg.norm(ef.area_vector(Q))
    once = _clip_front(P, nQ, Q[0])
    twice = _clip_front(once, nQ, Q[0])
    assert np.all(np.linalg.norm(twice - np.roll(twice, 1, axis=0), axis=1) > 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        whole = np.linalg.norm(ef.area_vector(P)) * ef.polygon_form_factor(P, Q)
        part = np.linalg.norm(ef.area_vector(once)) * ef.polygon_form_factor(once, Q)
    assert whole > 0 and part == pytest.approx(whole, rel=1e-12)


def test_bad_polygons_raise_scene_errors():
    P, Q = parallel_pair(1, 1, 1)
    with pytest.raises(ef.SceneError, match="polygon 1"):
        ef.polygon_form_factor(P, [[0, 0, 0], [1, 0, 0], [2, 0, 0]])


# ---------------------------------------------------------------------------------------
# with occlusion: area_form_factors
# ---------------------------------------------------------------------------------------
def _square(z, up):
    P = [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]]
    return P if up else P[::-1]


# Issue 15's references: unit emitter [0,1]^2 at z = 0 facing up, unit receiver at z = 2
# facing down, a 0.5 x 0.5 plate at z = 1. Computed independently of exactff (the emitter
# split at its visibility kinks, inner rows from a 2-D boolean construction,
# Gauss-Legendre 8 and 12 agreeing to 1e-16); quoted to 12 significant digits.
#: plates between the unit squares 2 apart, and F(lower -> upper) past them to 17 digits
#: (tools/occluded_plate_references.py: Howell's corner superposition of the visible
#: rectangle, mpmath quadrature over the emitter's pieces; 25 digits agree at 30 and 40)
OCCLUDED_REFERENCES = [
    ([[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]], 0.031402694247996356),
    ([[.6, .25, 1], [1.1, .25, 1], [1.1, .75, 1], [.6, .75, 1]], 0.052027663045404715),
]


@pytest.mark.parametrize("plate, reference", OCCLUDED_REFERENCES)
@pytest.mark.parametrize("tolerance", [1e-6, 1e-10])
@pytest.mark.parametrize("low_first", [False, True])
def test_occluded_references(plate, reference, tolerance, low_first, monkeypatch):
    # low_first: every pair starts with the low pair of rules, as one with many cells;
    # else with the high pair, at either tolerance
    if low_first:
        monkeypatch.setattr(ef._tolerances, "AREA_MANY_CELLS", 0)
    else:
        monkeypatch.setattr(ef._tolerances, "AREA_LOW_RULES_TOLERANCE", np.inf)
    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
    F, E = ef.area_form_factors(scene, rows=[0], tolerance=tolerance, error=True)
    err = abs(F[0, 1] - reference)
    assert E[0, 1] <= tolerance
    assert err <= E[0, 1]                    # the bound holds (the reference: 17 digits)
    assert err < tolerance
    # unoccluded: with the plate moved away, the opposed unit squares 2 apart (Howell
    # C-11, DESIGN's unoccluded target 1e-13 + 1e-12 F); the plate faces away: 0
    clear = ef.Scene.from_polygons([_square(0, True), _square(2, False),
                                    np.array(plate) + [5, 0, 0]])
    F = ef.area_form_factors(clear, rows=[0])
    want = howell_parallel(1, 1, 2)
    assert abs(F[0, 1] - want) <= 1e-13 + 1e-12 * want
    assert F[0, 0] == F[0, 2] == 0


def _room_with_plate():
    room = list(ef.scenes.subdivided_box(1).polygons)
    up = np.array([[.3, .35, .45], [.65, .35, .45], [.65, .7, .45], [.3, .7, .45]])
    return ef.Scene.from_polygons(room + [up, up[::-1].copy()])    # a two-sided plate


def _box_faces(lo, hi):
    """The five faces of an open-bottomed box standing on z = lo[2], facing outwards."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return [np.array(f, float) for f in (
        [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
        [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
        [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]],
        [[x1, y1, z0], [x0, y1, z0], [x0, y1, z1], [x1, y1, z1]],
        [[x0, y1, z0], [x0, y0, z0], [x0, y0, z1], [x0, y1, z1]])]


@pytest.mark.parametrize("rule, degree", [("symmetric 2", 2), ("symmetric 4", 4),
                                          ("symmetric 8", 8),
                                          ("collapsed 3", 4), ("collapsed 5", 8),
                                          ("collapsed 6", 10), ("collapsed 10", 18)])
@given(seed=st.integers(0, 2**32 - 1))
def test_triangle_rules_integrate_their_degree_exactly(rule, degree, seed):
    # the integral of L^k over a triangle, L linear, is 2 A k! / (k + 2)! times the
    # complete homogeneous polynomial of degree k in L's values at the vertices
    # (evaluated in mpmath at 40 digits): exact up to the rule's degree
    from scipy.special import roots_legendre

    from exactff.area.rules import symmetric_triangle_rule, triangle_rule

    rng = np.random.default_rng(seed)
    T = rng.normal(size=(3, 3))
    u, c = rng.normal(size=3), rng.normal()
    kind, n = rule.split()
    n = int(n)
    X, W = (symmetric_triangle_rule(T, n) if kind == "symmetric"
            else triangle_rule(T, roots_legendre(n)))
    assert len(W) == ({2: 3, 4: 6, 8: 16}[n] if kind == "symmetric" else n * n)
    with mp.workdps(40):
        A = mp.mpf(float(np.linalg.norm(np.cross(T[1] - T[0], T[2] - T[0])))) / 2
        La, Lb, Lc = (mp.mpf(float(v)) for v in T @ u + c)
        for k in range(degree + 1):
            h = sum(La ** i * Lb ** j * Lc ** (k - i - j) for i in range(k + 1)
                    for j in range(k + 1 - i))
            want = 2 * A * mp.factorial(k) / mp.factorial(k + 2) * h
            scale = 2 * A * max(abs(La), abs(Lb), abs(Lc)) ** k
            got = float((W * (X @ u + c) ** k).sum())
            assert abs(got - float(want)) / float(scale) <= 1e-13, k


@given(seed=st.integers(0, 2**32 - 1))
def test_symmetric_null_rules_give_zero_to_degree_5(seed):
    # the null rules on the nodes of the symmetric rules of degree 4 and 8 (built from
    # the S3-invariant polynomials alone) on L^k, L a random linear function on a random
    # triangle (not symmetric): 0 up to degree 5, against the scale of L^k, and at degree
    # 6 not 0 (what their spread sees: at least 0.002 of the scale where L is 0 at the
    # centroid, over 20,000 random triangles and L); each as long as the degree-8 rule,
    # orthogonal
    from exactff.area.rules import (SYMMETRIC_NULL_RULES, SYMMETRIC_RULES,
                                    symmetric_null_spread, symmetric_triangle_rule)

    rng = np.random.default_rng(seed)
    T = rng.normal(size=(3, 3))
    u, c = rng.normal(size=3), rng.normal()
    X = np.concatenate([symmetric_triangle_rule(T, d)[0] for d in (4, 8)])
    A = np.linalg.norm(np.cross(T[1] - T[0], T[2] - T[0])) / 2
    def spread(L, scale, k):
        return float(symmetric_null_spread((L ** k)[None], np.array([A]))[0]) / (A * scale ** k)

    ups = [spread(X @ u + c, np.abs(T @ u + c).max(), k) for k in range(6)]
    assert max(ups) <= 1e-13, ups
    m = T.mean(axis=0)
    assert spread((X - m) @ u, np.abs((T - m) @ u).max(), 6) >= 1e-3
    N = SYMMETRIC_NULL_RULES
    assert np.allclose(N @ N.T, np.eye(2) * (SYMMETRIC_RULES[8][1] ** 2).sum(), rtol=0,
                       atol=1e-15)
    assert np.allclose(N.sum(axis=1), 0, atol=1e-15)


def _hidden_cases():
    sq0, sq2 = np.array(_square(0, True), float), np.array(_square(2, False), float)
    for plate, _ in OCCLUDED_REFERENCES:
        yield sq0, sq2, [np.array(plate, float)]
    room = [np.asarray(p, float) for p in ef.scenes.subdivided_box(1).polygons]
    plate = [P for P in _room_with_plate().polygons[6:]]
    for j in (1, 2, 3):
        yield room[0], room[j], plate
    # the floor's quarter against the back wall's, past a box standing on the floor
    yield (_rect_xy(0, 0.5, 0, 0.5), np.array([[0, 1, 0], [.5, 1, 0], [.5, 1, .5], [0, 1, .5]], float),
           _box_faces([.2, .3, 0], [.6, .7, .35])[1:])


@pytest.mark.parametrize("case", range(6))
def test_hidden_part_against_the_engine(case):
    # the hidden part F(x -> Q) - F_occ(x -> Q), built by 2-D booleans in Q's plane,
    # against the engine (BSP tree and clipper on the hemisphere) and the kernel, at
    # random points of the emitter (and on the box's footprint lines)
    from exactff.area.hidden import hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values

    P, Q, B = list(_hidden_cases())[case]
    nP = ef.area_vector(P) / np.linalg.norm(ef.area_vector(P))
    a, b = np.random.default_rng(case).random((2, 200))
    a[:20], b[20:40] = 0.4, 0.6                     # x = 0.2, y = 0.3 on the last case
    X = P[0] + np.outer(a, P[1] - P[0]) + np.outer(b, P[3] - P[0])
    H, EH = _hidden_values(X, nP, Q, B)
    F, E = ef.form_factors(ef.Scene.from_polygons([Q] + B), X, nP, error=True)
    U, EU = (v[0] for v in _point_values(X, nP, [Q]))
    assert np.all(H >= 0) and H.max() > 0.01
    assert np.all(np.abs(H - (U - F[:, 0])) <= EH + EU + E[:, 0] + 1e-16)
    # the estimates themselves within DESIGN's targets (occluded 1e-11, unoccluded
    # 1e-13 + 1e-12 F), not taken as they come
    assert np.all(EH <= 1e-11) and np.all(E[:, 0] <= 1e-11), (EH.max(), E[:, 0].max())
    assert np.all(EU <= 1e-13 + 1e-12 * U), (EU / U).max()


# View3D's gunter1, rotated (a random rotation): the receiver 19 (a wall whose top edge
# lies in the plane of the emitter 9, a ceiling strip) clipped to the front of that
# plane, with a vertex and its copy 7e-15 apart (rounding's clip), and its two blockers
_SLIVER_Q = np.array([
    [0.0, 0.0, 0.0], [2.792691612011918, -20.109531066922518, 8.473938507487304],
    [2.792691612011925, -20.10953106692252, 8.473938507487304],
    [-12.546670441331106, -15.842226468703416, 23.65597009955291],
    [-15.339362053343033, 4.267304598219106, 15.182031592065606]])
_SLIVER_B = [np.array([
    [0.0, 0.0, 0.0], [-47.26883399190872, -23.863011126707654, -41.051358479494944],
    [-44.4761423798968, -43.972542193630176, -32.57741997200764],
    [2.7926916120119243, -20.10953106692252, 8.473938507487304]]), np.array([
    [-46.6341313528151, -28.433359096462773, -39.12546336415692],
    [-31.29476929947207, -32.70066369468187, -54.30749495622253],
    [-29.13678032655376, -48.23984679184928, -47.759451564073245],
    [-44.4761423798968, -43.972542193630176, -32.57741997200764]])]
_SLIVER_P = np.array([
    [-31.228511515645994, -47.657941619364856, -45.689174528791575],
    [-29.13678032655376, -48.23984679184928, -47.759451564073245],
    [-55.9459697548005, -61.77409190848944, -71.04231159721964],
    [-58.03770094389274, -61.19218673600502, -68.97203456193796]])


def test_hidden_part_by_the_engine_leaves_out_a_blocker_part_of_no_area():
    # the engine's fallback builds a scene of the receiver and the blockers' parts; a
    # part of no area (a clip's sliver of rounding: test4 turned, scaled 1e-3 and moved
    # by 296, row 9 without shortcuts at 1e-10 raised SceneError) hides nothing: the
    # values equal those without it
    from exactff.area.hidden import hidden_values_by_engine

    Q = np.array(_square(1, False), float)
    plate = np.array([[.25, .25, .5], [.75, .25, .5], [.75, .75, .5], [.25, .75, .5]])
    flat = np.array([[.1, .1, .5], [.2, .2, .5], [.3, .3, .5]])          # collinear
    X = np.array([[0.5, 0.5, 0.0], [0.1, 0.2, 0.0]])
    nP = np.array([0, 0, 1.0])
    H, EH = hidden_values_by_engine(X, nP, Q, [plate, flat])
    G, EG = hidden_values_by_engine(X, nP, Q, [plate])
    assert np.array_equal(H, G) and np.array_equal(EH, EG)
    # from below the centre, the plate (half as wide, halfway) hides the whole unit
    # square: the hidden part is the plate's own point value there
    F, E = ef.form_factors(ef.Scene.from_polygons([plate[::-1]]), X[:1], nP, error=True)
    assert abs(H[0] - F[0, 0]) <= EH[0] + E[0, 0] + 1e-15
    # the receiver itself is never left out: a receiver of no area raises, where
    # dropping it would make the first blocker column 0 (a silent wrong value)
    with pytest.raises(ef.SceneError):
        hidden_values_by_engine(X, nP, flat, [plate])


def test_hidden_part_of_a_receiver_with_a_sliver_of_rounding_against_the_engine():
    # Q's convex parts include a triangle 7e-15 wide, which its frame's rounding may
    # turn over: its sides' half-planes then kept the whole base, and the hidden part
    # came out 0.0040 where the engine gives 0.0036, above the unoccluded 0.00356
    # (gunter1 rotated, pair (9, 19): -2.6e-4 below 0 beyond its estimate of 2e-8).
    # Against the engine at random points of the emitter
    from exactff.area.hidden import hidden_setup as _hidden_setup
    from exactff.area.hidden import hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values

    nP = ef.area_vector(_SLIVER_P) / np.linalg.norm(ef.area_vector(_SLIVER_P))
    a, b = np.random.default_rng(0).random((2, 100))
    P = _SLIVER_P
    X = P[0] + np.outer(a, P[1] - P[0]) + np.outer(b, P[3] - P[0])
    setup = _hidden_setup(_SLIVER_Q, _SLIVER_B)
    assert 0 < setup.sliver_area < 1e-12 and len(setup.part_counts) == 2
    H, EH = _hidden_values(X, nP, _SLIVER_Q, _SLIVER_B, setup=setup)
    F, E = ef.form_factors(ef.Scene.from_polygons([_SLIVER_Q] + _SLIVER_B), X, nP, error=True)
    U, EU = (v[0] for v in _point_values(X, nP, [_SLIVER_Q]))
    assert H.max() > 1e-3
    assert np.all(np.abs(H - (U - F[:, 0])) <= EH + EU + E[:, 0] + 1e-16), \
        np.abs(H - (U - F[:, 0])).max()


@pytest.mark.parametrize("seed, scale, shift, row", [
    (3, 1.0, 0.0, 9), (0, 1.0, 0.0, 4), (2, 1e-3, 0.0, 17), (2, 1e-3, 0.0, 21),
    (0, 1.0, 1e3, 4)])
def test_rotated_gunter1_row_within_the_estimates_of_the_row_unrotated(seed, scale, shift, row):
    # rows of the scene rotated (scaled, moved), against those of the scene as read,
    # within the two estimates:
    # - (3, 9): the pair above, -2.6e-4 raised before;
    # - (0, 4): its pair (4, 17), 1.8e-18 against 0 beyond estimates of 2e-19, a sliver
    #   1e-15 wide that the clip to the other's plane left (clip_front);
    # - (2, 1e-3, 17): pair (17, 4), faces sharing an edge, whose front parts the signs
    #   alone clipped to a sliver (2e-34 against 0, beyond estimates of 7e-36): a vertex
    #   within the band of the other's plane is in it now (front_distances);
    # - (2, 1e-3, 21): a receiver touching the emitter along an edge, whose contour rule
    #   clipped it by the signs alone (0.02785 against 0.02973, estimate 2.5e-15): it
    #   takes the row's front parts now;
    # - (0, +1000, 4): a blocker with an edge in the receiver's plane but for rounding,
    #   whose clip's crossing left the edge's line by 0.36 (0.0001549 against
    #   0.0001555, 567 times the estimates): clip_halfspace keeps it on the line
    scene = ef.read_vs3(os.path.join(os.path.dirname(__file__), "data", "view3d", "gunter1.vs3"))
    Q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    Q[:, 0] *= np.sign(np.linalg.det(Q))
    turned = ef.Scene.from_polygons([scale * (np.asarray(P) @ Q.T) + shift
                                     for P in scene.polygons])
    F, E = ef.area_form_factors(scene, rows=[row], tolerance=1e-6, error=True)
    G, EG = ef.area_form_factors(turned, rows=[row], tolerance=1e-6, error=True)
    assert np.all(np.abs(F - G) <= E + EG), (np.abs(F - G) / (E + EG)).max()
    assert np.all(E <= 1e-6) and np.all(EG <= 1e-6) and (row != 9 or F[0, 19] < 1e-10)


@pytest.mark.parametrize("turn, move, row, column", [
    ([[-0.9947883549867707, -0.08383857136380336, 0.05802777554232997],
      [0.07091545166755886, -0.9778273424358492, -0.1970398109510627],
      [0.07326068179795148, -0.19189784349106392, 0.9786767035982712]],
     [843.9798000549588, -170.38599283577207, -931.6780266696907], 17, 6),
    ([[-0.5313053413084576, 0.838345561246631, -0.12203013658590536],
      [-0.5740502142175976, -0.250325298956079, 0.779617596170892],
      [0.6230417207971178, 0.4842664190717967, 0.6142516174220018]],
     [-80.41588777077433, 2.647511013740882, 58.201571464053586], 6, 22)])
def test_gunter1_turned_vertex_on_an_edge_line_makes_no_event(turn, move, row, column):
    # a blocker's vertex and another blocker's edge (its far end and the emitter's
    # corner) lie on one line, the normal through that corner: as read, the plane
    # through them is m = 0, no event; turned and moved, m is rounding's, a plane through
    # the line at random, whose event line passed 1.4e-4 from the corner and cut it away
    # from the cell whose collapsed rule takes it (pair (17, 6): 0.0530048 against
    # 0.0530061, 1.25e-6 off, twice the estimates of 6.6e-7; pair (6, 22): 5.3e-7 off
    # against 4.0e-7). Against the file as read, within the two estimates and what
    # rounding the move moves (32 u R / L); the references at 1e-10 agree with the file
    # as read to 4e-11 (docs/explanation/area-form-factors.md, "Files turned off the axes")
    scene = ef.read_vs3(os.path.join(os.path.dirname(__file__), "data", "view3d", "gunter1.vs3"))
    turned = ef.Scene.from_polygons([np.asarray(P) @ np.asarray(turn).T + move
                                     for P in scene.polygons])
    F, E = ef.area_form_factors(scene, rows=[row], tolerance=1e-6, error=True)
    G, EG = ef.area_form_factors(turned, rows=[row], tolerance=1e-6, error=True)
    rounding = 32 * np.finfo(float).eps * np.abs(turned.vertices).max() / np.ptp(
        turned.vertices, axis=0).max()
    assert F[0, column] > 0.04
    assert np.all(np.abs(F - G) <= E + EG + rounding), (np.abs(F - G) - E - EG).max()


@settings(max_examples=examples(10), deadline=None)
@example(name="test4", turn=rotation(np.array([0.0, 0, 1]), 4.822649006614105), scale=1e-3,
         shift=(0.0, 0.0, 0.0), far=(0.0, 890.6462656609042, 0.0))   # cells whose cut
#                                                   missed a kink (below)
@example(name="test4", turn=rotation(np.array([0.98702147, 0, 0.1605883182144936]) / np.linalg.norm(
    [0.98702147, 0, 0.1605883182144936]), 4.822649006614105),
         scale=1e-3, shift=(0.0, 0.0, 0.0), far=(0.0, 0.0, 258.0))   # a blocker in the
#                                                   receiver's plane dropped
@example(name="test4", turn=[[0.5768409918312185, -0.7043584731095915, -0.4136829843030784],
                             [-0.7904334475391779, -0.3535429216523971, -0.5002223181354635],
                             [0.2060811373088422, 0.6155376056003499, -0.7606865457843213]],
         scale=1e3, shift=(0.0, 0.0, 0.0), far=(0.0, 0.0, 0.0))   # a corner at the
#                                                   origin (below)
@example(name="test4", turn=rotation(np.array([0.0, 0, 1]), 1.6196483541149253e-147),
         scale=1e-3, shift=(0.0, 0.0, 0.0), far=(0.0, 0.0, 0.0))   # faces tilted 1e-150: the contour rule's
#                                                   u ln(u^2 + k^2) underflowed to -inf
@given(name=st.sampled_from(["test4", "facet", "cube"]), turn=rotations(),
       scale=st.sampled_from([1e-3, 1.0, 1e3]),
       shift=st.tuples(*[st.floats(-100, 100)] * 3), far=st.just((0.0, 0.0, 0.0)))
def test_view3d_files_turned_scaled_and_moved_within_the_estimates(name, turn, scale, shift,
                                                                   far):
    # the whole matrix of a View3D file under a rotation, a scale and a move, against
    # the file as read: within the two estimates (the faces that share edges and planes
    # there share them only to rounding here: coplanar by the band, clips that stay on
    # their edges), and what rounding the moved coordinates moved the values: each
    # vertex moved by u |x| <= u R, the values (at most 1) by about u R / L for a scene
    # of size L (seen: up to 0.7 u R / L, 3e-11 moved 961 at scale 1e-3; the defects
    # this test found were 1e-7 to 6e-2). Examples: test4 moved by 890 at scale 1e-3,
    # whose emitter's cut along the lengthened lines missed 1e-11 of its area, and the
    # cut as cut (taken instead) left a line dangling in a cell: 3.8e-6 off, 8 times its
    # estimate (AREA_CELL_COVER_ATOL_SHARE); and one where a blocker in the receiver's
    # plane dropped from the pair left the blockers' inner points one too many
    # (hidden_setup raised ValueError); and test4 turned and scaled 1000, whose wall's
    # corner at the origin was 1.9e-14 behind the floor's plane through it (a band of
    # 1e-27 there, coplanar_band's |d| being 0) and clipped to a copy of itself 3e-14
    # away (not one of its own roundoffs, 0 at the origin): pair (10, 0) 0.1093
    # against 0.0894 (front_distances' band, clip_front's copies)
    scene = ef.read_vs3(os.path.join(os.path.dirname(__file__), "data", "view3d", name + ".vs3"))
    # (the drawn shift, at most 100, is the move in units of the scale: the coordinates
    # up to about 100 times the scene's size; ``far``, only in the examples, is a move
    # in absolute units, 1e5 times the size there, where a value can take minutes)
    move = np.array(shift) * scale + np.array(far)
    moved = ef.Scene.from_polygons([scale * (np.asarray(P) @ np.asarray(turn).T) + move
                                    for P in scene.polygons])
    # (at 1e-6, where the rules stop soonest: a misplaced event line there puts a value
    # beyond the rules' difference, as a vertex on an edge's line did,
    # test_gunter1_turned_vertex_on_an_edge_line_makes_no_event)
    F, E = ef.area_form_factors(scene, tolerance=1e-6, error=True)
    G, EG = ef.area_form_factors(moved, tolerance=1e-6, error=True)
    rounding = 32 * np.finfo(float).eps * np.abs(moved.vertices).max() / np.ptp(
        moved.vertices, axis=0).max()
    gap = np.abs(F - G) - (E + EG)
    assert np.all(gap <= rounding), (gap.max(), rounding)


@pytest.mark.parametrize("case", ["facing", "far", "touching", "corner", "aside", "tilted"])
def test_unoccluded_bound_holds_at_points_of_the_emitter(case):
    # the bound the slivers' estimate takes for the hidden part (at most the unoccluded
    # point value): A_Q c_P c_Q / (pi d^2) with d the distance between the bounding
    # boxes and c_P, c_Q the cosines' bounds, and 1; against the point values (the
    # kernel) at random points and the corners of P, and not far above the largest of
    # them where the receiver is far. Aside (a square 1 above and 2 beyond P's edge, as
    # gunter2's annex floor and the hall's ceiling strips) the cosines are at most
    # 1 / sqrt(5) each: the bound is a fifth of A_Q / (pi d^2); tilted (a wall beside
    # P facing it, its normal across P's), P's cosine is at most 1.5 / sqrt(4.25), the
    # wall's 1
    from exactff.area.points import unoccluded_bound as _unoccluded_bound
    from exactff.area.points import point_values as _point_values

    P = np.array(_square(0, True), float)
    Q = {"facing": np.array(_square(0.5, False), float) + [0.3, 0.2, 0],
         "far": 0.2 * np.array(_square(0, False), float) + [0.4, 0.4, 6.0],
         "touching": np.array([[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]], float),
         # over P's corner only, close: P's corner sees about a quarter of it
         "corner": np.array(_square(0.05, False), float) + [0.9, 0.9, 0],
         "aside": np.array(_square(1.0, False), float) + [3, 0, 0],
         "tilted": np.array([[3, 0, 1.5], [3, 1, 1.5], [3, 1, 0.5], [3, 0, 0.5]], float)}[case]
    nP = np.array([0, 0, 1.0])
    a, b = np.random.default_rng(7).random((2, 400))
    X = np.vstack([P, P[0] + np.outer(a, P[1] - P[0]) + np.outer(b, P[3] - P[0])])
    U, EU = (v[0] for v in _point_values(X, nP, [Q]))
    bound = _unoccluded_bound(P, Q)
    assert np.all(U - EU <= bound) and bound <= 1.0
    if case == "far":
        assert bound <= 1.2 * U.max(), (bound, U.max())
    if case in ("aside", "tilted"):
        d2 = {"aside": 5.0, "tilted": 4.25}[case]
        cosines = {"aside": 1 / 5, "tilted": 1.5 / math.sqrt(d2)}[case]
        assert bound == pytest.approx(cosines / (np.pi * d2), rel=1e-3), bound
    # each triangle's bound (unoccluded_bounds: the distance from its own box): P cut
    # into 32 triangles, 60 random points in each and its corners against the kernel;
    # none above P's bound, and where Q is away from part of P, some below it
    from exactff.area.points import unoccluded_bounds as _unoccluded_bounds

    g = np.linspace(0.0, 1.0, 5)
    T = np.array([[[x0, y0, 0], [x1, y0, 0], [x1, y1, 0]] for x0, x1 in zip(g, g[1:])
                  for y0, y1 in zip(g, g[1:])] + [[[x0, y0, 0], [x1, y1, 0], [x0, y1, 0]]
                                                  for x0, x1 in zip(g, g[1:])
                                                  for y0, y1 in zip(g, g[1:])])
    bounds = _unoccluded_bounds(T, P, Q)
    assert bounds.shape == (32,) and np.all(bounds <= bound)
    assert (bounds.min() < 0.9 * bound) == (case in ("touching", "corner", "aside", "tilted"))
    w = np.random.default_rng(8).dirichlet(np.ones(3), size=60)
    for t, b in zip(T, bounds):
        U, EU = (v[0] for v in _point_values(np.vstack([t, w @ t]), nP, [Q]))
        assert np.all(U - EU <= b), (t, (U - EU).max(), b)


@pytest.mark.parametrize("cover", ["whole", "all but a strip", "none"])
def test_hidden_part_of_many_blockers_against_the_engine(cover):
    # many overlapping plates between two unit squares (the images are united largest
    # first, and once they cover the pyramid's base the rest is not added: View3D's
    # gunter2, row 95, 894 -> 20 us a point), and a large plate given last that hides
    # the whole receiver, all of it but a strip 1e-3 wide, or is left out: the hidden
    # part at random points of the emitter against the engine, within the estimates;
    # where the plate hides it all, the hidden part is the unoccluded value
    from exactff.area.hidden import hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values

    rng = np.random.default_rng(49)
    P, Q = np.array(_square(0, True), float), np.array(_square(3, False), float)
    B = []
    for _ in range(14):
        (x0, y0), (w, h), z = rng.uniform(-0.3, 0.9, 2), rng.uniform(0.1, 0.6, 2), rng.uniform(0.5, 2.5)
        B.append(np.array([[x0, y0, z], [x0 + w, y0, z], [x0 + w, y0 + h, z], [x0, y0 + h, z]]))
    if cover != "none":
        # (its shadow from x on Q: 2 right - x; from x = 0, a strip 1e-3 wide is left)
        right = 6.0 if cover == "whole" else 0.5 - 0.5e-3
        B.append(np.array([[-5, -5, 1.5], [right, -5, 1.5], [right, 6, 1.5], [-5, 6, 1.5]], float))
    nP = np.array([0, 0, 1.0])
    a, b = rng.random((2, 60))
    X = P[0] + np.outer(a, P[1] - P[0]) + np.outer(b, P[3] - P[0])
    H, EH = _hidden_values(X, nP, Q, B)
    F, E = ef.form_factors(ef.Scene.from_polygons([Q] + B), X, nP, error=True)
    U, EU = (v[0] for v in _point_values(X, nP, [Q]))
    assert np.all(np.abs(H - (U - F[:, 0])) <= EH + EU + E[:, 0] + 1e-16)
    assert np.all(EH <= 1e-11), EH.max()
    if cover == "whole":
        assert np.all(F[:, 0] == 0) and np.all(np.abs(H - U) <= EH + EU)
    else:
        # some points see part of Q, and (with the large plate) some see none of it,
        # the plates united covering the base
        assert F[:, 0].max() > 0.01 and (cover == "none" or np.any(F[:, 0] == 0))


@pytest.mark.parametrize("which", ["cornell", "sliced"])
def test_hidden_part_skipping_back_faces_against_the_engine(which):
    # members of a convex solid seen from behind left out of the hidden region: the
    # closed Cornell box's floor against its light past the two blocks (ten faces), and
    # a floor whose plane cuts through a closed box (points inside its hull skip none);
    # against the engine, and against the values with every blocker projected
    from exactff.area.culling import (closed_solids as _closed_solids,
                                      convex_solids as _convex_solids)
    from exactff.area.hidden import hidden_setup as _hidden_setup, hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values

    if which == "cornell":
        scene = ef.scenes.cornell_box(closed=True)
        i, j, B = 1, 0, list(range(10, 20))          # the floor, the light, the blocks
    else:
        floor = _rect_xy(0, 1, 0, 1)
        scene = ef.Scene.from_polygons([floor, floor[::-1] + [0, 0, 1]]
                                       + _closed_box([.3, .35, -.2], [.6, .7, .4]))
        i, j, B = 0, 1, list(range(2, 8))
    P, Q = (np.asarray(scene.polygons[k], float) for k in (i, j))
    solids = _convex_solids(scene)
    solid = _closed_solids(solids, np.array(B), (scene.normals[[i, j]],
                                                 scene.plane_offsets[[i, j]]))
    assert np.all(solid >= 0)
    inner = np.array([solids.centres[g] for g in solid])
    blockers = [np.asarray(scene.polygons[k], float) for k in B]
    nP = scene.normals[i]
    a, b = np.random.default_rng(7).random((2, 300))
    X = P[0] + np.outer(a, P[1] - P[0]) + np.outer(b, P[3] - P[0])
    st = AreaStats()
    H, EH = _hidden_values(X, nP, Q, blockers, st,
                           setup=_hidden_setup(Q, blockers, solid, inner))
    H0, EH0 = _hidden_values(X, nP, Q, blockers)
    # members skipped that the point would have projected (inside the pyramid over Q):
    # about one a point
    assert st.back_faces > len(X) // 2
    assert np.all(np.abs(H - H0) <= EH + EH0)
    F, E = ef.form_factors(ef.Scene.from_polygons([Q] + blockers), X, nP, error=True)
    U, EU = (v[0] for v in _point_values(X, nP, [Q]))
    assert H.max() > 0.01 and np.all(H >= 0)
    assert np.all(np.abs(H - (U - F[:, 0])) <= EH + EU + E[:, 0] + 1e-16)
    if which == "sliced":
        # the points on the box's footprint see none of the ceiling: hidden is all of it
        under = (X[:, 0] > .3) & (X[:, 0] < .6) & (X[:, 1] > .35) & (X[:, 1] < .7)
        assert under.any() and np.all(np.abs(H[under] - U[under]) <= EH[under] + EU[under])


def test_back_faces_kept_where_a_member_of_the_solid_was_culled(monkeypatch):
    # a closed box floating 3e-13 above the floor (the emitter), the wall x = 1 the
    # receiver: the shaft culls the box's bottom (within rounding of the floor's plane),
    # so no member may be skipped; skipping them let lines of sight through the gap
    # under the near face from points 1e-11 off the footprint (233 times the estimate)
    from exactff.area import adaptive, hidden as hidden_module

    floor = _rect_xy(0, 1, 0, 1)
    wall = np.array([[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0]], float)
    box = _closed_box([.3, .35, 3e-13], [.6, .7, .4])
    scene = ef.Scene.from_polygons([floor, wall] + box)
    calls, hidden = [], adaptive.hidden_values

    def record(X, nP, Qc, blockers, st=None, atol=0.0, setup=None, shortcuts=True,
               weights=None, bound_atol=None):
        calls.append((nP, Qc, blockers, setup))
        return hidden(X, nP, Qc, blockers, st, atol, setup, shortcuts, weights, bound_atol)

    # the levels by numpy, which call hidden_values (the compiled ones do its
    # work inside: test_compiled_levels_against_numpy)
    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", False)
    monkeypatch.setattr(adaptive, "hidden_values", record)
    ef.area_form_factors(scene, rows=[0], tolerance=1e-7, error=True)
    monkeypatch.setattr(adaptive, "hidden_values", hidden)
    nP, Qc, blockers, setup = calls[0]
    assert len(blockers) < 6                    # the bottom culled
    X = np.array([[0.3 - d, 0.5, 0.0] for d in (1e-11, 1e-10, 1e-9)])
    st = AreaStats()
    H, EH = hidden(X, nP, Qc, blockers, st, atol=1e-6, setup=setup)
    G, EG = hidden_module.hidden_values_by_engine(X, nP, Qc, box)
    assert not st.back_faces
    assert np.all(np.abs(H - G) <= EH + EG), np.abs(H - G) / (EH + EG)


@pytest.mark.parametrize("tilt", [0.0, 0.6, 1.4])
def test_compiled_sector_sums_of_the_hidden_pieces_against_the_kernel(tilt):
    # the compiled Eq. 3 sector sums of the hidden pieces (and their rounding estimate)
    # against the kernel's clipped_sector_sums on the same pieces: from the emitter's
    # frame, and from frames tilted so that the pieces cross the horizon (its clipping
    # and arcs, which the emitter's own frame never needs)
    from exactff.area import hidden as area
    from exactff.kernel import clipped_sector_sums
    from exactff.rings import owners, successors

    P, Q, B = list(_hidden_cases())[5]
    n = np.array([np.sin(tilt), 0.3 * np.sin(tilt), np.cos(tilt)])
    n /= np.linalg.norm(n)
    X = P[0] + np.outer(np.linspace(0.05, 0.95, 9), P[1] - P[0]) + 0.3 * (P[3] - P[0])
    nQ, q0, RQ, Kc, corners, parts, part_counts, V, counts, NK, group, lo, hi, extent, _ = (
        area.hidden_setup(Q, B))
    R = ef.geometry.receiver_frame(n)
    out = area.hidden_pieces(X, corners, q0, nQ, RQ[:2], V, counts, NK, group, 1e-12, 1e-12,
                             8.0, 4.0,
                             20000, 1e-13, extent, parts, part_counts, R, 10.0, 10.0,
                             2.0 ** -53, True, precise_atol=-1.0)
    xy, start, ring_point, H, rnd = out[0], out[1], out[2], out[9], out[10]
    owner, first = owners(start), start[:-1]
    E = ((xy - xy[first[owner]]) @ RQ[:2]) @ R.T
    A0 = ((q0 - X[ring_point]) + xy[first] @ RQ[:2]) @ R.T
    S, mags, errs = clipped_sector_sums(A0, E, successors(start), owner, len(first))
    G = np.bincount(ring_point, np.abs(S), minlength=len(X)) / (2 * np.pi)
    EG = np.bincount(ring_point, 10.0 * 2.0 ** -53 * mags + errs, minlength=len(X)) / (2 * np.pi)
    z = (A0[owner] + E)[:, 2]
    crossing = np.any(np.bincount(owner, z > 0) * np.bincount(owner, z < 0) > 0)
    assert crossing == (tilt > 0)                   # the tilted frames clip at the horizon
    assert H.max() > 0.01 and np.all(H >= 0)
    assert np.all(np.abs(H - G) <= rnd + EG), np.abs(H - G).max()
    assert np.allclose(rnd, EG, rtol=1e-6, atol=1e-18)


def _within_estimates(scene, F, E):
    """Reciprocity of every pair, within the two values' estimates (areas equal or not)."""
    A = scene.areas
    AF, AE = A[:, None] * F, A[:, None] * E
    return np.abs(AF - AF.T) <= AE + AE.T + 1e-15


def test_closed_room_rows_sum_to_one_and_reciprocity_within_the_estimates():
    # a closed unit room with a two-sided plate floating in it: every point of every
    # polygon sees the closed room, so each row sums to 1
    scene = _room_with_plate()
    tol = 1e-9
    F, E = ef.area_form_factors(scene, tolerance=tol, error=True)
    assert np.all(E <= tol)
    assert np.all(np.abs(F.sum(axis=1) - 1.0) <= E.sum(axis=1) + 1e-14)
    assert np.all(_within_estimates(scene, F, E))
    assert F[1, 7] == 0.0 and F[0, 6] == 0.0           # the faces turned away
    assert F[0, 1] < ef.polygon_form_factor(scene.polygons[0], scene.polygons[1]) - 0.05


#: found by a CI draw: a third triangle in Q's plane, back to back with it and covering
#: it (a wall of no thickness). The engine's tie rule puts Q, facing the point, first;
#: the hidden part took the third's part "in front" of Q's plane (its rounding) as a
#: blocker and hid 0.0335 more than the engine
BACK_TO_BACK = (ef.Scene.from_polygons([
    [[0.5580127018922194, 0., 0.03349364905389038],
     [0.3705127018922194, -0.21650635094610968, 0.35825317547305485],
     [0.3705127018922193, 0.2165063509461096, 0.358253175473055]],
    [[0.33034180126147955, 0., 0.09449788301796348],
     [0.26784180126147955, -0.07216878364870322, 0.2027510584910183],
     [0.26784180126147955, 0.07216878364870319, 0.20275105849101835]],
    [[0.9330127018922194, 0., -0.6160254037844386],
     [0.18301270189221946, 0.8660254037844387, 0.6830127018922192],
     [0.18301270189221913, -0.8660254037844384, 0.6830127018922199]]]),
    np.zeros(3), np.array([0.8660254037844387, 0., 0.5000000000000001]))


@settings(max_examples=examples(40), deadline=None)
@given(case=occluded_scenes(max_extra=3))
@example(case=BACK_TO_BACK)
def test_hidden_part_against_the_engine_on_drawn_scenes(case):
    # a far polygon partly hidden by a nearer one, and up to three others anywhere (not
    # convex, crossing the point's plane or Q's): the hidden part built in Q's plane
    # against the engine, within the two estimates
    from exactff.area.hidden import hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values
    from exactff.halfspace import clip_front as _clip_front

    scene, p, n = case
    polys = [np.asarray(P, float) for P in scene.polygons]
    Qc = _clip_front(polys[0], n, p)
    assert Qc is not None                           # the strategy puts it in front
    X = np.asarray(p, float)[None]
    H, EH = _hidden_values(X, n, Qc, polys[1:])
    F, E = ef.form_factors(ef.Scene.from_polygons([Qc] + polys[1:]), X, n, error=True)
    U, EU = (v[0] for v in _point_values(X, n, [Qc]))
    assert H[0] > 0                                 # the near polygon hides part of it
    assert abs(H[0] - (U[0] - F[0, 0])) <= EH[0] + EU[0] + E[0, 0] + 1e-15 * U[0]
    # the estimates within DESIGN's targets, not taken as they come
    assert EH[0] <= 1e-11 and E[0, 0] <= 1e-11 and EU[0] <= 1e-13 + 1e-12 * U[0], (
        EH[0], E[0, 0], EU[0], U[0])


def _lose_images(monkeypatch, area, which=None, length=None):
    """Make the compiled hidden regions report the images of some points (``which``,
    indices into each call's points; all by default) as lost, the way it reports images
    through infinity; with ``length``, report that as every point's pieces' perimeter.
    The levels by numpy, whose hidden_values calls it (the compiled levels call the
    compiled hidden pieces directly, and give a pair with a lost point to numpy)."""
    from exactff.area import adaptive

    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", False)
    build = area.hidden_pieces

    def lose(*args, **kwargs):
        out = list(build(*args, **kwargs))
        lost = out[3].copy()
        lost[slice(None) if which is None else which] = True
        out[3] = lost
        if length is not None:
            out[5] = np.full_like(out[5], length)
        return tuple(out)

    monkeypatch.setattr(area, "hidden_pieces", lose)


def test_hidden_part_falls_back_to_the_engine_where_its_images_are_lost(monkeypatch):
    from exactff.area import hidden as area

    P, Q, B = list(_hidden_cases())[5]
    nP = np.array([0.0, 0.0, 1.0])
    X = P[0] + np.outer(np.linspace(0.05, 0.95, 7), P[1] - P[0]) + 0.3 * (P[3] - P[0])
    H, EH = area.hidden_values(X, nP, Q, B)
    st = AreaStats()
    _lose_images(monkeypatch, area, which=[1, 4])
    G, EG = area.hidden_values(X, nP, Q, B, st)
    assert H[[1, 4]].max() > 0.01 and np.all(np.abs(G - H) <= EG + EH + 1e-16)
    assert st == AreaStats(engine_fallbacks=1, engine_fallback_points=2)


# points where the hidden part built in Q's plane was wrong, against the engine: a
# blocker whose corner is 1.6e-13 from the point, nearly edge-on (the image's vertices, rounded
# in doubles, moved it by 1 %: long double now, and a point whose images that rounding
# can still move goes to the engine); two walls meeting in a corner, whose images' short
# edges (two vertices 2.5e-16 apart) once cut along a line of no true direction (the
# union 7 % too large: every edge now carries the line it lies on); a room's corner
# where the GEOS booleans were 7.4e-6 off (4.7e-3 relative); every piece of a point's
# region a sliver (dropped: its area was left out of the estimate, 0 against 4.3e-13); a
# receiver clipped to two vertices 3e-13 apart, whose pyramid plane through that edge
# was the cross product of two long offsets (in doubles its direction was lost: 0.0004
# against 0.1166, and a closed Cornell box's pair was cut to the last level)
_ENGINE_CASES = (
    ([33.0, 66.99999999999989, 1.2307000475897438e-13], [-1.0, 0.0, 0.0],
     [[27, 47, 22], [27, 105, 22], [33, 105, 22], [33, 48, 22]],
     [[[33, 67, 0], [33, 67, 5], [0, 67, 5], [0, 67, 0]],
      [[33, 67, 5], [33, 153, 5], [-22, 153, 5], [-22, 67, 5]]]),
    ([0.0, 1.5422631245172218, 1.420236875482778], [1.0, 0.0, 0.0],
     [[1, 1, 3], [3, 1, 3], [3, 0, 3], [1, 0, 3]],
     [[[1, 1, 0], [3, 1, 0], [3, 1, 3], [1, 1, 3]], [[1, 3, 0], [1, 1, 0], [1, 1, 3], [1, 3, 3]]]),
    ([2.9694204456130047, 2.1548819667539534, 0.0], [0.0, 0.0, 1.0],
     [[27, 47, 22], [27, 105, 22], [33, 105, 22], [33, 48, 22]],
     [[[33, 67, 0], [33, 67, 5], [0, 67, 5], [0, 67, 0]],
      [[33, 67, 5], [33, 153, 5], [-22, 153, 5], [-22, 67, 5]],
      [[22, 0, 0], [22, 0, 22], [15, 45, 22], [15, 45, 0]],
      [[33, 48, 0], [15, 45, 0], [15, 45, 22], [33, 48, 22]]]),
    ([1.0, 1.0, 2.0], [0.0, 0.0, -1.0],
     [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]],
     [[[0.5, 1.000000000001, 0.5], [1.5, 1.000000000001, 0.5], [1.5, 1.000000000001, 1.5],
       [0.5, 1.000000000001, 1.5]]]),
    ([554.2179920619797, 243.1856386295061, 246.30287385543963],
     [-0.999983000713969, 0.005830804668886199, 0.0],
     [[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8000000000001, 559.2],
      [556.0, 548.7999999999998, 559.1999999999998]],
     [[[423, 330, 247], [265, 330, 296], [314, 330, 456], [472, 330, 406]],
      [[423, 0, 247], [423, 330, 247], [472, 330, 406], [472, 0, 406]],
      [[472, 0, 406], [472, 330, 406], [314, 330, 456], [314, 0, 456]],
      [[314, 0, 456], [314, 330, 456], [265, 330, 296], [265, 0, 296]],
      [[265, 0, 296], [265, 330, 296], [423, 330, 247], [423, 0, 247]]]),
)


@pytest.mark.parametrize("case", range(len(_ENGINE_CASES)))
def test_hidden_part_where_it_was_wrong_against_the_engine(case):
    from exactff.area.hidden import hidden_values as _hidden_values
    from exactff.area.points import point_values as _point_values

    x, nP, Q, B = (np.asarray(v, dtype=float) for v in _ENGINE_CASES[case])
    st = AreaStats()
    H, EH = _hidden_values(x[None], nP, Q, list(B), st)
    # the first point's images cannot be trusted (it goes to the engine, counted); the
    # others are the compiled path's own
    assert st.engine_fallback_points == (1 if case == 0 else 0)
    F, E = ef.form_factors(ef.Scene.from_polygons([Q] + list(B)), x, nP, error=True)
    U, EU = (v[0] for v in _point_values(x[None], nP, [Q]))
    assert H[0] > 1e-3 or case == 3
    assert abs(H[0] - (U[0] - F[0])) <= EH[0] + EU[0] + E[0], (H[0], U[0] - F[0], EH[0], E[0])


def test_room_with_a_box_standing_on_the_floor():
    # a unit room of 24 quarters with an open-bottomed box on the floor: a point of the
    # floor under the box sees nothing (the box's faces turn their backs to it), so a
    # floor quarter's row sums to the share of it outside the box's footprint; every
    # other row sums to 1. Touching pairs meet in T-junctions (the box's edges end
    # inside the floor quarters' edges)
    room = [np.asarray(p, float) for p in ef.scenes.subdivided_box(2).polygons]
    scene = ef.Scene.from_polygons(room + _box_faces([.2, .3, 0], [.6, .7, .35]))
    tol = 1e-9
    F, E = ef.area_form_factors(scene, tolerance=tol, error=True)
    assert np.all(E <= tol)
    want = np.ones(len(scene))
    for i in range(4):                                  # the floor's quarters
        lo, hi = np.asarray(scene.polygons[i]).min(axis=0), np.asarray(scene.polygons[i]).max(axis=0)
        covered = (max(0, min(hi[0], .6) - max(lo[0], .2)) * max(0, min(hi[1], .7) - max(lo[1], .3)))
        want[i] = 1.0 - covered / 0.25
    assert want[:4].min() < 0.8
    assert np.all(np.abs(F.sum(axis=1) - want) <= E.sum(axis=1) + 1e-14)
    assert np.all(_within_estimates(scene, F, E))


@pytest.mark.slow
def test_closed_cube_of_384_quads():
    # every pair unoccluded: the far pairs of a row integrated together, the near ones by
    # the contour rule; every row of the closed cube sums to 1 and the matrix is
    # symmetric (equal areas), each within the estimates
    scene = ef.scenes.subdivided_box(8)
    F, E = ef.area_form_factors(scene, error=True)
    assert np.all(np.abs(F.sum(axis=1) - 1.0) <= E.sum(axis=1) + 4e-16)
    assert np.all(np.abs(F - F.T) <= E + E.T + 1e-18)
    assert E.max() < 1e-12


@pytest.mark.slow
def test_closed_cornell_box_rows_sum_to_one():
    # the closed Cornell box: the light (ten block faces between it and the floor) and
    # a face of the short block see the closed box, so their rows sum to 1
    scene = ef.scenes.cornell_box(closed=True)
    F, E = ef.area_form_factors(scene, rows=[0, 10], tolerance=1e-9, error=True)
    assert np.all(E <= 1e-9)
    assert np.all(np.abs(F.sum(axis=1) - 1.0) <= E.sum(axis=1) + 1e-14)


@pytest.mark.slow
def test_hidden_parts_of_the_closed_cornell_box_against_the_engine(monkeypatch):
    # every call of the hidden parts that the rows of the light, the floor and a face of
    # each block make at 1e-6 (the blocks' faces nearly coincident in projection: the
    # 3e-13 edge of a65e74b showed up here, not on View3D's examples), eight points each
    # against the engine, within the two estimates wherever the engine decides
    st = hidden_parts_against_the_engine(monkeypatch, ef.scenes.cornell_box(closed=True),
                                         rows=[0, 1, 10, 16], seed=1)
    assert st.back_faces > 0


def hidden_parts_against_the_engine(monkeypatch, scene, rows=None, seed=0):
    """Every call of the hidden parts that the rows make at tolerance 1e-6 recorded, and
    eight of its points each computed again and against the engine (BSP tree and shadow
    tree on the hemisphere, exact predicates): within the two estimates wherever the
    engine decides (its estimate below 1e-9), and every value the compiled path's own,
    none the engine's."""
    from exactff.area import adaptive, hidden as hidden_module

    calls, hidden = [], adaptive.hidden_values

    def record(X, nP, Qc, blockers, st=None, atol=0.0, setup=None, shortcuts=True,
               weights=None, bound_atol=None):
        calls.append((X, nP, Qc, blockers, setup))
        return hidden(X, nP, Qc, blockers, st, atol, setup, shortcuts, weights, bound_atol)

    # the levels by numpy, which call hidden_values (the compiled ones do its
    # work inside: test_compiled_levels_against_numpy)
    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", False)
    monkeypatch.setattr(adaptive, "hidden_values", record)
    ef.area_form_factors(scene, rows=rows, tolerance=1e-6, error=True)
    monkeypatch.setattr(adaptive, "hidden_values", hidden)
    rng = np.random.default_rng(seed)
    decided, st = 0, AreaStats()
    for X, nP, Qc, blockers, setup in calls:
        # with the row's setup: its solids' members seen from behind skipped
        X = X[rng.choice(len(X), size=min(8, len(X)), replace=False)]
        H, EH = hidden(X, nP, Qc, blockers, st, setup=setup)
        G, EG = hidden_module.hidden_values_by_engine(X, nP, Qc, blockers)
        sure = EG < 1e-9
        decided += int(sure.sum())
        assert np.all(np.abs(H - G)[sure] <= (EH + EG)[sure]), np.abs(H - G).max()
    assert len(calls) > 20 and decided > 0.9 * 8 * len(calls) and not st.engine_fallbacks
    return st


def test_closed_cornell_box_wall_cut_into_cells_that_cover_it():
    # the right wall (8) to the back wall (20): polygonizing the event lines lengthened
    # across the wall's boundary found a ring of nearly coincident lines invalid and lost
    # 7 % of the wall (its estimate 0.073); the lines as cut are noded instead there
    scene = ef.scenes.cornell_box(closed=True)
    F, E = ef.area_form_factors(scene, rows=[8], tolerance=1e-6, error=True)
    assert np.all(E <= 1e-6), E.max()
    assert abs(F.sum() - 1.0) <= E.sum() + 1e-14


def test_convex_room_against_closed_forms():
    # a convex room: every pair unoccluded; each value against Gross et al.'s closed
    # forms (parallel and perpendicular quads, sharing edges, corners or nothing);
    # DESIGN's unoccluded target 1e-13 + 1e-12 F
    scene = ef.scenes.subdivided_box(2)
    rows = [0, 9, 23]
    F = ef.area_form_factors(scene, rows=rows)
    for k, i in enumerate(rows):
        want = np.array([0.0 if j == i else aligned_rectangles_form_factor(
            scene.polygons[i], scene.polygons[j]) for j in range(len(scene))])
        assert np.all(np.abs(F[k] - want) <= 1e-13 + 1e-12 * want), (i, F[k] - want)
        assert np.count_nonzero(want) == 20           # the quads of the other five faces
    assert np.all(np.abs(F.sum(axis=1) - 1.0) <= 1e-12)


def test_area_form_factors_rejects_bad_arguments():
    scene = ef.scenes.subdivided_box(1)
    for bad in (0, -1e-9, float("nan"), "1e-9"):
        with pytest.raises(ValueError, match="tolerance"):
            ef.area_form_factors(scene, tolerance=bad)
    with pytest.raises(ValueError, match="rows"):
        ef.area_form_factors(scene, rows=[6])


def test_cli_matrix_area(tmp_path):
    import json
    import subprocess
    import sys

    scene = ef.scenes.subdivided_box(1)
    path = tmp_path / "box.json"
    path.write_text(json.dumps({"schema": "exactff-scene/1", "surfaces": [
        {"vertices": P.tolist()} for P in scene.polygons]}))
    r = subprocess.run([sys.executable, "-m", "exactff", "matrix", str(path), "--area",
                        "--tolerance", "1e-10", "--no-progress", "-o", "a.npy"],
                       capture_output=True, text=True, cwd=tmp_path, timeout=300, env=checkout_env())
    assert r.returncode == 0, r.stderr
    F, E = np.load(tmp_path / "a.npy"), np.load(tmp_path / "a.error.npy")
    assert np.array_equal(F, ef.area_form_factors(scene))
    assert E.shape == F.shape and E.max() <= 1e-10
    r = subprocess.run([sys.executable, "-m", "exactff", "matrix", str(path), "--area",
                        "--two-sided", "--no-progress"], capture_output=True, text=True,
                       cwd=tmp_path, timeout=300, env=checkout_env())
    assert r.returncode == 2 and "--area is one-sided" in r.stderr


def test_cli_matrix_area_combine_leaves_no_record_a_later_run_would_resume(tmp_path, capsys):
    # an area run to m.npy, then --combine to the same path (the surfaces View3D
    # reports: 8 of 12 polygons; it exits 0 with its report), then an area run again:
    # the combined matrix is not taken for its own (refused, as a file of another
    # computation), and --overwrite starts afresh
    import os

    from exactff.cli import main

    path = os.path.join(os.path.dirname(__file__), "data", "view3d", "l_room_f3.vs3")
    scene = ef.read_vs3(path)
    out = str(tmp_path / "m.npy")
    base = ["matrix", path, "--area", "--tolerance", "1e-6", "--no-progress", "-o", out]
    assert main(base) == 0 and np.load(out).shape == (12, 12)
    assert main(base + ["--combine"]) == 0
    n = len(ef.combined_surfaces(scene))
    assert n == 8 and np.load(out).shape == (n, n)
    capsys.readouterr()
    assert main(base) == 2
    assert "not written by this computation" in capsys.readouterr().err
    assert main(base + ["--overwrite"]) == 0 and np.load(out).shape == (12, 12)
    # a record left beside a file written over otherwise: refused, not resumed
    np.save(out, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="holds an array of shape"):
        ef.area_form_factors(scene, tolerance=1e-6, error=True, out=out)


def test_cli_matrix_area_sparse_jobs_and_a_killed_run_resumed(tmp_path, capsys, monkeypatch):
    # the matrix driver of the point rows: --sparse (values and bounds in .npz), --jobs,
    # and a run killed after its first blocks resumed from what it wrote, computing the
    # other rows only
    import scipy.sparse as sp

    from exactff.cli import main
    from exactff.formfactors import AreaRows

    scene = ef.scenes.subdivided_box(3)                 # 54 quads: blocks of 16 rows
    F, E = ef.area_form_factors(scene, tolerance=1e-9, error=True)
    out = str(tmp_path / "s.npz")
    assert main(["matrix", "box:3", "--area", "--tolerance", "1e-9", "--sparse", "--jobs", "2",
                 "--no-progress", "-o", out]) == 0
    S, SE = sp.load_npz(out), sp.load_npz(str(tmp_path / "s.error.npz"))
    assert np.array_equal(S.toarray(), F) and np.array_equal(SE.toarray(), E)
    assert "error bounds     max" in capsys.readouterr().out

    computed, call = [], AreaRows.__call__

    def killed_after_two_blocks(self, scene, rows):
        if len(computed) == 2:
            raise KeyboardInterrupt
        computed.append(len(rows))
        return call(self, scene, rows)

    monkeypatch.setattr(AreaRows, "__call__", killed_after_two_blocks)
    out = str(tmp_path / "d.npy")
    with pytest.raises(KeyboardInterrupt):
        main(["matrix", "box:3", "--area", "--tolerance", "1e-9", "--no-progress", "-o", out])
    assert computed == [16, 16]
    computed.clear()
    monkeypatch.setattr(AreaRows, "__call__", lambda self, scene, rows: (
        computed.append(len(rows)), call(self, scene, rows))[1])
    assert main(["matrix", "box:3", "--area", "--tolerance", "1e-9", "--no-progress",
                 "-o", out]) == 0
    assert "resuming" in capsys.readouterr().out
    assert sum(computed) == 54 - 32
    assert np.array_equal(np.load(out), F)
    assert np.array_equal(np.load(str(tmp_path / "d.error.npy")), E)


# ---------------------------------------------------------------------------------------
# shortcuts (issue 33): each off under shortcuts=False, counted in stats, and neutral
# ---------------------------------------------------------------------------------------
SHORTCUT_COUNTERS = ("enclosure_unoccluded_pairs", "hull_unoccluded_pairs", "hull_culled_blockers", "shaft_culled_blockers",
                     "shaft_unoccluded_pairs", "far_pairs",
                     "culled_events", "solid_events", "back_faces", "bounded_points",
                     "wall_hidden_pairs")


def _far_squares():
    """A unit square facing up and three small squares about five above it, facing
    down: every pair far (beyond AREA_FAR diameters), nothing between."""
    def sq(x, y, z, a, up):
        return np.array([[x, y, z], [x + a, y, z], [x + a, y + a, z], [x, y + a, z]][::1 if up else -1], float)
    return ef.Scene.from_polygons([sq(0, 0, 0, 1, True), sq(0, 0, 5, .2, False),
                                   sq(.6, .3, 5, .2, False), sq(-.5, .8, 4.8, .3, False)])


def _box_on_a_floor():
    """A quarter of a room's floor, a quarter of its back wall and the open-bottomed
    box of test_room_with_a_box_standing_on_the_floor (its faces hide one another)."""
    return ef.Scene.from_polygons(
        [_rect_xy(0, 0.5, 0, 0.5), np.array([[0, 1, 0], [.5, 1, 0], [.5, 1, .5], [0, 1, .5]], float)]
        + _box_faces([.2, .3, 0], [.6, .7, .35])[1:])


def _closed_box(lo, hi):
    """The six faces of a closed box, facing outwards."""
    (x0, y0, z0), (x1, y1, _) = lo, hi
    bottom = np.array([[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]], float)
    return _box_faces(lo, hi) + [bottom]


def _floating_box():
    """The unit room (six faces, facing in) with a closed box floating inside it."""
    room = [np.asarray(p, float) for p in ef.scenes.subdivided_box(1).polygons]
    return ef.Scene.from_polygons(room + _closed_box([.3, .35, .3], [.6, .7, .55]))


def _shortcut_scene(name):
    """(scene, rows, tolerance, the counters that must fire with shortcuts on)."""
    if name.startswith("reference"):
        plate = OCCLUDED_REFERENCES[int(name[-1])][0]
        return (ef.Scene.from_polygons([_square(0, True), _square(2, False), plate]), [0], 1e-10, ())
    if name == "cube":
        # a closed cube: a convex enclosure, every pair unoccluded without a shaft
        return ef.scenes.subdivided_box(1), [0, 3], 1e-7, ("enclosure_unoccluded_pairs",)
    if name == "room":
        # (the plate's two faces, back to back, are a flat solid: no events between them;
        # no back face is skipped, as no point is inside it)
        return _room_with_plate(), [0], 1e-7, ("hull_unoccluded_pairs", "hull_culled_blockers",
                                               "solid_events")
    if name == "box":
        return _box_on_a_floor(), [0], 1e-7, ("hull_unoccluded_pairs", "hull_culled_blockers", "culled_events")
    if name == "floating":
        # a closed box inside a room: between two of its faces no event but their planes
        return _floating_box(), [0], 1e-7, ("hull_unoccluded_pairs", "hull_culled_blockers",
                                            "shaft_culled_blockers", "solid_events",
                                            "back_faces")
    if name in ("straddling", "hanging"):
        # a closed box straddling the receiver's plane (its part behind the receiver
        # clipped away), and a box open at the top hanging from the receiver's plane
        # (its open face there, the emitter's plane meeting it in no area)
        floor = _rect_xy(0, 1, 0, 1)
        ceiling = _rect_xy(0, 1, 0, 1)[::-1] + [0, 0, 1]
        box = (_closed_box([.3, .35, .7], [.6, .7, 1.2]) if name == "straddling" else
               _box_faces([.3, .35, 1], [.6, .7, .6])[1:] + [_closed_box([.3, .35, .6],
                                                                         [.6, .7, 1])[-1]])
        fire = ("hull_unoccluded_pairs", "hull_culled_blockers", "solid_events", "back_faces")
        return (ef.Scene.from_polygons([floor, ceiling] + box), [0], 1e-7,
                fire + (("shaft_culled_blockers", "wall_hidden_pairs") if name == "hanging"
                        else ()))
    if name == "walled":
        # a floor and a wall piece on either side of a two-sided wall in two pieces,
        # both with an edge in its plane: the wall hides one from the other whole
        floor = _rect_xy(0, 2, 0, 1)
        piece = np.array([[-1, 1, 0], [0, 1, 0], [0, 1, 1], [-1, 1, 1]], float)
        low = np.array([[0, 0, 0], [0, 1, 0], [0, 1, .5], [0, 0, .5]], float)
        high = low + [0, 0, .5]
        return (ef.Scene.from_polygons([floor, piece, low, high, low[::-1], high[::-1]]),
                [0, 1], 1e-6, ("wall_hidden_pairs", "hull_unoccluded_pairs",
                               "hull_culled_blockers"))
    if name == "sliced":
        # a closed box the emitter's plane cuts through: the points of the floor inside
        # its hull see every member from behind, and none may be skipped there
        floor = _rect_xy(0, 1, 0, 1)
        ceiling = _rect_xy(0, 1, 0, 1)[::-1] + [0, 0, 1]
        box = _closed_box([.3, .35, -.2], [.6, .7, .4])
        return (ef.Scene.from_polygons([floor, ceiling] + box), [0], 1e-7,
                ("hull_unoccluded_pairs", "hull_culled_blockers", "solid_events", "back_faces"))
    if name == "facet":
        # View3D's facet box (a plate inside a unit box): row 5, the wall behind the
        # plate, whose pairs with the side walls have the plate in their boxes but
        # outside their shafts
        import os
        scene = ef.read_vs3(os.path.join(os.path.dirname(__file__), "data", "view3d", "facet.vs3"))
        # (and the plate's two faces, back to back, are a flat solid)
        return scene, [5], 1e-7, ("hull_unoccluded_pairs", "hull_culled_blockers",
                                  "shaft_culled_blockers", "shaft_unoccluded_pairs",
                                  "solid_events")
    if name == "window":
        # the wall a window covers (the tie rule), a closed box floating in front of it:
        # the wall emits from its uncovered triangles, each through the shortcuts
        scene = _room_with_a_window(True, block=True)[0]
        return scene, [3], 1e-7, ("hull_unoccluded_pairs", "hull_culled_blockers",
                                  "shaft_culled_blockers", "shaft_unoccluded_pairs",
                                  "solid_events", "back_faces")
    # far squares at a tolerance the closed form's rounding misses (its estimate there
    # is 3e-12): the far rule takes them (off: mpmath)
    return _far_squares(), [0, 1], 1e-13, ("far_pairs", "hull_unoccluded_pairs", "hull_culled_blockers")


@pytest.mark.parametrize("name", ["reference0", "reference1", "cube", "room", "box", "far",
                                  "facet", "floating", "straddling", "hanging", "sliced",
                                  "window", "walled"])
def test_area_shortcuts_are_neutral_and_counted(name, monkeypatch):
    # with shortcuts=False (every other polygon a blocker of every pair, the contour
    # integral for far pairs, every blocker-blocker event cut along) the values agree
    # with the shortcuts' within the two estimates; a shortcut's counter is > 0 only
    # where it skipped work, and 0 with shortcuts off
    # (the walls' proof first, whatever the blockers)
    monkeypatch.setattr(ef._tolerances, "AREA_WALL_MIN_BLOCKERS", 0)
    scene, rows, tol, fire = _shortcut_scene(name)
    on, off = {}, {}
    F, E = ef.area_form_factors(scene, rows=rows, tolerance=tol, error=True, stats=on)
    G, EG = ef.area_form_factors(scene, rows=rows, tolerance=tol, error=True, stats=off,
                                 shortcuts=False)
    assert np.all(E <= tol) and np.all(EG <= tol)
    assert np.all(np.abs(F - G) <= E + EG), np.abs(F - G).max()
    for k in SHORTCUT_COUNTERS:
        assert off[k] == 0, (k, off)
        assert (on[k] > 0) == (k in fire), (k, on)
    assert on["engine_fallbacks"] == off["engine_fallbacks"] == 0
    # shortcuts off did the work they skip: more pairs through the occluded path
    # (walled: its pairs with a blocker are the wall's, proven 0 without integration)
    assert off["occluded_pairs"] >= on["occluded_pairs"] > 0 or name in ("far", "cube",
                                                                          "walled")
    if fire:
        assert off["occluded_pairs"] > on["occluded_pairs"]


def test_convex_solids_are_the_closed_convex_groups_of_faces():
    from exactff.area.culling import (closed_solids as _closed_solids,
                                      convex_solids as _convex_solids)

    # the Cornell box: each block (five faces, open at the floor) is a group
    label = _convex_solids(ef.scenes.cornell_box(closed=True)).label
    assert len(set(label[10:15])) == len(set(label[15:20])) == 1
    assert -1 < label[10] != label[15] > -1
    # a zigzag of three quads (the middle one's plane between the others) is none, nor
    # are three quads on one edge
    zig = ef.Scene.from_polygons([
        np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], float),
        np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float),
        np.array([[0, 1, 1], [1, 1, 1], [1, 1, 2], [0, 1, 2]], float)])
    assert _convex_solids(zig)[0].tolist() == [-1, -1, -1]
    fan = ef.Scene.from_polygons([
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float),
        np.array([[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]], float),
        np.array([[0, 1, 0], [0, 0, 0], [-1, 0, 0.5], [-1, 1, 0.5]], float)])
    assert _convex_solids(fan)[0].tolist() == [-1, -1, -1]

    def solid(box, planes):
        scene = ef.Scene.from_polygons(box)
        n = np.array([p[0] for p in planes], float)
        d = np.array([p[1] for p in planes], float)
        return _closed_solids(_convex_solids(scene), np.arange(len(box)), (n, d)).tolist()

    floor, ceiling, back = ((0, 0, 1), 0), ((0, 0, -1), -1), ((0, -1, 0), -1)
    # a closed box away from both planes is a solid; so is one open at the floor, between
    # the floor and the ceiling (its open face in the floor's plane, which it stands on)
    assert solid(_closed_box([.3, .3, .3], [.6, .7, .5]), [floor, ceiling]) == [0] * 6
    assert solid(_box_faces([.3, .3, 0], [.6, .7, .5]), [floor, ceiling]) == [0] * 5
    # but not between the floor and the back wall if also open at the top (its open
    # edges at z = 0.5 lie in neither plane), nor as a chimney from the floor to the
    # ceiling (open at both: a line of sight may pass through it from end to end)
    assert solid(_box_faces([.3, .3, 0], [.6, .7, .5])[1:], [floor, back]) == [-1] * 4
    assert solid(_box_faces([.3, .3, 0], [.6, .7, 1])[1:], [floor, ceiling]) == [-1] * 4


@pytest.mark.parametrize("which", ["room", "cornell"])
def test_closed_solids_from_the_scene_table_are_the_pairs_own(which):
    # closed_solids with keys (each group's facts against every plane of the scene, built
    # once) against the rule evaluated here for the pair's two planes alone (the per-pair
    # code it replaced), for every ordered pair with every other polygon a blocker, the
    # table filled as the pairs ask; planted: the emitter's column for both planes
    # fails
    from exactff.area.culling import (closed_solids as _closed_solids,
                                      convex_solids as _convex_solids)
    from exactff.predicates import coplanar_band_sides

    def pair_own(solids, B, N2, D2):
        # the rule as closed_solids' docstring states it, for the pair's two planes
        out = np.full(len(B), -1)
        ids = solids.label[B]
        for g in set(ids[ids >= 0].tolist()):
            if np.count_nonzero(ids == g) < 2:
                continue
            sign, _ = coplanar_band_sides(solids.vertices[g], N2, D2)
            supports = ~((sign > 0).any(axis=0) & (sign < 0).any(axis=0))
            if not (supports & ((sign == 0).sum(axis=0) < 3)).any():
                continue                   # no plane meets the hull in no area
            E = solids.open_edges[g]
            if len(E):
                on, _ = coplanar_band_sides(E.reshape(-1, 3), N2, D2)
                on = (on == 0).reshape(len(E), 2, 2).all(axis=1) & supports
                if not on.any(axis=1).all():
                    continue               # an open edge in neither supporting plane
            out[ids == g] = g
        return out

    scene = (ef.scenes.unit_squares_room() if which == "room"
             else ef.scenes.cornell_box(closed=True))
    solids = _convex_solids(scene)
    N, D = scene.normals, scene.plane_offsets
    n = len(scene)
    found = set()
    for i in range(n):
        for j in range(n):
            if i == j:
                continue
            B = np.array([k for k in range(n) if k not in (i, j)])
            got = _closed_solids(solids, B, (N[[i, j]], D[[i, j]]), keys=[i, j])
            assert got.tolist() == pair_own(solids, B, N[[i, j]], D[[i, j]]).tolist(), (i, j)
            found.add(bool(np.any(got >= 0)))
    assert found == {True, False}          # pairs with solids and pairs without
    assert set(solids.facts) == {g for g in solids.members}


def test_closed_box_in_a_room_rows_sum_to_one():
    # the vertex-edge events between the floating box's faces are not cut along (its
    # faces' images united are its hull's): every row of the closed scene still sums to 1
    # within its estimates, and reciprocity holds
    scene = _floating_box()
    st = {}
    F, E = ef.area_form_factors(scene, tolerance=1e-8, error=True, stats=st)
    assert st["solid_events"] > 0
    assert np.all(E <= 1e-8)
    assert np.all(np.abs(F.sum(axis=1) - 1.0) <= E.sum(axis=1) + 1e-14)
    assert np.all(_within_estimates(scene, F, E))


def test_area_stats_from_worker_processes_and_the_options_in_the_record(tmp_path):
    # the counters come back from worker processes (AreaRows is pickled: its options
    # travel, the caller's dict does not), summed over the rows; shortcuts is part of
    # what a resumable output records
    import pickle

    from exactff.formfactors import AreaRows

    scene = _far_squares()
    serial, pooled = {}, {}
    F = ef.area_form_factors(scene, tolerance=1e-13, stats=serial)
    G = ef.area_form_factors(scene, tolerance=1e-13, stats=pooled, jobs=2, chunk_rows=1)
    assert np.array_equal(F, G) and serial == pooled and serial["far_pairs"] == 6
    # and from threads: each row counts its own (no counter shared between calls)
    from concurrent.futures import ThreadPoolExecutor

    threaded = {}
    with ThreadPoolExecutor(2) as pool:
        H = ef.area_form_factors(scene, tolerance=1e-13, stats=threaded, executor=pool,
                                 chunk_rows=1)
    assert np.array_equal(F, H) and threaded == serial
    rows = pickle.loads(pickle.dumps(AreaRows(1e-9, shortcuts=False, stats={"far_pairs": 1})))
    assert rows.shortcuts is False and rows.stats is None
    assert AreaRows(1e-9).record() != AreaRows(1e-9, shortcuts=False).record()
    out = tmp_path / "a.npy"
    ef.area_form_factors(scene, rows=[1], out=out)
    with pytest.raises(ValueError):
        ef.area_form_factors(scene, rows=[1], out=out, shortcuts=False)


def test_area_engine_fallbacks_are_counted(monkeypatch):
    # where a point's images are lost the engine computes the hidden part: counted (0
    # otherwise), and the value agrees within the estimates
    from exactff.area import area_row, hidden as area

    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), OCCLUDED_REFERENCES[0][0]])
    st = AreaStats()
    f, e = area_row(scene, 0, 1e-6, stats=st)
    assert st.engine_fallbacks == st.engine_fallback_points == 0

    _lose_images(monkeypatch, area)
    fst = AreaStats()
    g, eg = area_row(scene, 0, 1e-6, stats=fst)
    assert fst.engine_fallbacks > 0 and fst.engine_fallback_points == fst.point_values
    assert abs(g[1] - f[1]) <= e[1] + eg[1] and abs(g[1] - OCCLUDED_REFERENCES[0][1]) <= eg[1] + 1e-13


# ---------------------------------------------------------------------------------------
# no silent clamp (issue 33): below 0 within a value's own estimate is 0, beyond it raises
# ---------------------------------------------------------------------------------------
def test_nonnegative_clamps_only_within_the_estimate():
    from exactff.errors import nonnegative

    assert nonnegative(-1e-17, 1e-16) == 0.0 and nonnegative(0.25, 0.0) == 0.25
    assert np.array_equal(nonnegative(np.array([-1e-17, 0.5]), np.array([1e-16, 0.0])), [0.0, 0.5])
    for value, estimate in ((-1e-15, 1e-16), (-1e-300, 0.0), (np.nan, 1.0), (0.1, np.nan)):
        with pytest.raises(ef.NumericalError):
            nonnegative(value, estimate)
    with pytest.raises(ef.NumericalError, match=r"\[1\]|-0.5"):
        nonnegative(np.array([0.0, -0.5]), np.array([0.0, 1e-9]))


def test_area_row_raises_on_a_negative_beyond_its_estimate(monkeypatch):
    # an occluded pair coming out -1e-6 with an estimate of 1e-9 was set to 0 (max(f, 0));
    # within its estimate it is 0 and keeps the estimate
    from exactff.area import area_row, row

    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), OCCLUDED_REFERENCES[0][0]])
    monkeypatch.setattr(row, "occluded_pair", lambda *a, **k: (-1e-6, 1e-9, 0))
    with pytest.raises(ef.NumericalError, match="below 0 beyond"):
        area_row(scene, 0, 1e-9)
    monkeypatch.setattr(row, "occluded_pair", lambda *a, **k: (-1e-10, 1e-9, 0))
    f, e = area_row(scene, 0, 1e-9)
    assert f[1] == 0.0 and e[1] == 1e-9


def test_contour_and_far_rule_raise_on_a_negative_beyond_the_estimate(monkeypatch):
    from exactff.area import closed_form, contour_rule, far_field

    P, Q = parallel_pair(1, 1, 1)
    # the closed form's edge integrals negated (the sums then come out -F)
    sums = closed_form.edge_pair_sums

    def negated(*args):
        v, ev, owner, ip, iq, ef_, J, c = sums(*args)
        return -v, ev, owner, ip, iq, ef_, -J, c

    monkeypatch.setattr(closed_form, "edge_pair_sums", negated)
    with pytest.raises(ef.NumericalError, match="below 0 beyond"):
        closed_form.unoccluded_pair(P, Q)
    monkeypatch.undo()
    # and the tanh-sinh oracle's
    log_integral = contour_rule._segment_log_integral
    monkeypatch.setattr(contour_rule, "_segment_log_integral", lambda W, E: -log_integral(W, E))
    with pytest.raises(ef.NumericalError, match="below 0 beyond"):
        contour_rule.contour_tanh_sinh(P, Q)
    monkeypatch.undo()
    far = Q + [0, 0, 10]
    nodes = far_field.emitter_nodes(P, np.array([0.0, 0.0, 1.0]))
    monkeypatch.setattr(far_field, "point_values", lambda X, n, Qs: (-np.ones((len(Qs), len(X))),) * 2)
    with pytest.raises(ef.NumericalError, match="below 0 beyond"):
        far_field.far_values(nodes, np.array([0.0, 0.0, 1.0]), 1.0, [far])


def test_hidden_part_raises_on_a_nan_estimate_and_a_negative_beyond_it(monkeypatch):
    # the booleans' part of the estimate came out NaN: it was made 0 (nan_to_num), an
    # understated bound; and the engine's hidden part U - F was clamped with no check
    from exactff.area import hidden as area

    P, Q, B = list(_hidden_cases())[5]
    nP = np.array([0.0, 0.0, 1.0])
    X = P[0] + np.outer(np.linspace(0.05, 0.95, 7), P[1] - P[0]) + 0.3 * (P[3] - P[0])
    with monkeypatch.context() as m:
        _lose_images(m, area, which=[], length=np.nan)
        with pytest.raises(ef.NumericalError, match="NaN error estimate"):
            area.hidden_values(X, nP, Q, B)
    monkeypatch.setattr(area, "point_values", lambda X, n, Qs: (np.zeros((1, len(X))),) * 2)
    with pytest.raises(ef.NumericalError, match="below 0 beyond"):
        area.hidden_values_by_engine(X, nP, Q, B)


def test_area_estimates_use_the_unit_roundoff_of_the_tolerances_module():
    # C1 and the ulps constants are calibrated for u = 2**-53 (tol.EPS); np.finfo's eps
    # is 2**-52: no module of the area code takes its own
    import pathlib

    import exactff.area

    for path in pathlib.Path(exactff.area.__file__).parent.glob("*.py"):
        assert "finfo" not in path.read_text(), path.name


@pytest.mark.parametrize("plate, reference", OCCLUDED_REFERENCES)
@pytest.mark.parametrize("tolerance, rtol", [(1e-6, None), (1e-12, None), (1e-15, 1e-6),
                                             (1e-15, 1e-9), (1e-7, 1e-12)])
def test_each_estimate_within_its_requested_bound(plate, reference, tolerance, rtol):
    # tolerance is absolute per value; with rtol the bound is max(tolerance, rtol |F|):
    # every value's estimate within it, and the value within its estimate of the
    # reference (17 digits)
    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
    F, E = ef.area_form_factors(scene, rows=[0], tolerance=tolerance, rtol=rtol, error=True)
    allowed = np.maximum(tolerance, (rtol or 0.0) * np.abs(F))
    assert np.all(E <= allowed), (E, allowed)
    assert abs(F[0, 1] - reference) <= E[0, 1]
    if rtol == 1e-6:            # the relative bound, not the absolute one, was the target
        assert tolerance < E[0, 1]


def test_rtol_is_checked_and_recorded():
    from exactff.formfactors import AreaRows

    scene = ef.scenes.subdivided_box(1)
    for bad in (0, -1e-9, float("nan"), "1e-9"):
        with pytest.raises(ValueError, match="rtol"):
            ef.area_form_factors(scene, rtol=bad)
    assert AreaRows(1e-9).record() != AreaRows(1e-9, rtol=1e-6).record()
    assert np.array_equal(ef.area_form_factors(scene, rtol=1e-6), ef.area_form_factors(scene))


def _room_with_a_window(window_first, block=False):
    """A 4 x 3 x 2.5 room (fronts inward) with a window lying on its wall y = 0 (the
    same plane, facing the same way), given before or after the wall, optionally with a
    closed box floating above the floor, in front of that wall; and the wall cut
    around the window by hand (four rectangles), the construction the tie rule must
    agree with."""
    faces = ef.scenes.box_polygons([0, 0, 0], [4, 3, 2.5])
    wall = faces[2]
    n = np.cross(wall[1] - wall[0], wall[2] - wall[0])

    def rect(x0, x1, z0, z1):
        R = np.array([[x0, 0, z0], [x1, 0, z0], [x1, 0, z1], [x0, 0, z1]], float)
        return R if np.cross(R[1] - R[0], R[2] - R[0]) @ n > 0 else R[::-1]

    win = rect(1, 2.5, 0.8, 1.8)
    pieces = [rect(0, 1, 0, 2.5), rect(2.5, 4, 0, 2.5), rect(1, 2.5, 0, 0.8),
              rect(1, 2.5, 1.8, 2.5)]
    extra = ef.scenes.box_polygons([1.2, 0.5, 0.3], [2.2, 1.3, 0.9], facing="out") if block else []
    polys = ([win] + faces if window_first else faces[:3] + [win] + faces[3:]) + extra
    return ef.Scene.from_polygons(polys), faces, win, pieces, extra


@pytest.mark.parametrize("block", [False, True])
def test_window_on_its_wall_follows_the_tie_rule(block):
    # a window given first covers its part of the wall (the tie rule: of coplanar
    # polygons facing the same way, the first in input order is in front), so the wall
    # receives, and emits, only around it: against the wall cut around the window by
    # hand (a scene without overlaps), every row but the wall's summing to 1, the
    # wall's to its uncovered share, and every pair reciprocal. Before, the overlap was
    # counted twice (the floor's row summed to 1 + F(floor -> window)), and then the
    # wall emitted from the window's part too (A_i F_ij != A_j F_ji)
    scene, faces, win, pieces, extra = _room_with_a_window(True, block)
    tol = 1e-9
    F, E = ef.area_form_factors(scene, tolerance=tol, error=True)
    assert np.all(E <= tol)
    A = scene.areas
    full = np.ones(len(scene))
    full[3] = 1.0 - A[0] / A[3]
    assert np.all(np.abs(F.sum(axis=1) - full) <= E.sum(axis=1) + 1e-13), F.sum(axis=1) - full
    AF, AE = A[:, None] * F, A[:, None] * E
    assert np.all(np.abs(AF - AF.T) <= AE + AE.T + 1e-13)
    # the reference: the wall replaced by its four pieces around the window (scene:
    # window 0, floor 1, ceiling 2, wall 3, faces 4-6, box 7...; cut: window 0, floor 1,
    # ceiling 2, pieces 3-6, faces 7-9, box 10...)
    cut = ef.Scene.from_polygons([win] + faces[:2] + pieces + faces[3:] + extra)
    G, EG = ef.area_form_factors(cut, tolerance=tol, error=True)
    at = {c: [c] for c in range(3)} | {3: [3, 4, 5, 6]} | {c: [c + 3] for c in range(4, len(scene))}
    for r in range(len(scene)):
        for c in range(len(scene)):
            if r == 3:
                # the wall emits as its pieces (by area), not from under the window
                Ac = cut.areas
                g = Ac[3:7] @ G[3:7][:, at[c]].sum(axis=1) / A[3]
                eg = Ac[3:7] @ EG[3:7][:, at[c]].sum(axis=1) / A[3]
            else:
                g, eg = G[at[r][0], at[c]].sum(), EG[at[r][0], at[c]].sum()
            assert abs(F[r, c] - g) <= E[r, c] + eg + 1e-14, (r, c, F[r, c], g)
    if not block:
        # unoccluded: the floor's values in closed form
        floor = faces[0]
        ref = sum(ef.polygon_form_factor(floor, p) for p in pieces)
        assert abs(F[1, 3] - ref) <= E[1, 3] + 1e-15
        assert abs(F[1, 0] - ef.polygon_form_factor(floor, win)) <= E[1, 0] + 1e-15


def test_covered_wall_estimates_cover_its_errors_at_a_coarse_tolerance():
    # the wall a window covers emits from its uncovered triangles, its estimates their
    # area-weighted sum: at 1e-3 its occluded values (the box in the room) lie up to
    # 8e-10 from the wall's four pieces cut by hand at 1e-13 (whose own estimates are
    # 1e-13 at most), so the estimates must carry that error themselves (planted: the
    # covered emitter's estimates zeroed, this fails; the window tests above do not)
    scene, faces, win, pieces, extra = _room_with_a_window(True, True)
    F, E = ef.area_form_factors(scene, tolerance=1e-3, error=True)
    cut = ef.Scene.from_polygons(list(scene.polygons[:3]) + pieces + list(scene.polygons[4:]))
    G, EG = ef.area_form_factors(cut, tolerance=1e-13, error=True)
    A, Ac = scene.areas, cut.areas
    at = [[0], [1], [2], [3, 4, 5, 6]] + [[k + 3] for k in range(4, len(scene))]
    g = np.array([Ac[3:7] @ G[3:7][:, at[c]].sum(axis=1) / A[3] for c in range(len(scene))])
    eg = np.array([Ac[3:7] @ EG[3:7][:, at[c]].sum(axis=1) / A[3] for c in range(len(scene))])
    d = np.abs(F[3] - g)
    assert np.any(d > 10 * eg), (d, eg)                    # the check has teeth
    assert np.all(d <= E[3] + eg + 1e-15), (d, E[3], eg)


@pytest.mark.parametrize("masks_first", [True, False])
def test_masks_on_a_base_against_the_closed_form(masks_first):
    # a unit base square (z = 0, facing up) with two coplanar masks on it, one partly
    # over the other and sticking out of the base, and a square above facing down:
    # each polygon emits and receives through its part uncovered by the tie rule, by
    # superposition of aligned rectangles (gross_parallel, mpmath); masks given after
    # the base are covered whole (within it) or to their part outside it
    h, tol = 0.7, 1e-10
    base, top = ((0, 1), (0, 1)), ((-0.2, 1.1), (0.1, 0.9))
    m1, m2 = ((0.2, 0.5), (0.3, 0.8)), ((0.4, 1.3), (0.6, 0.9))
    rect = lambda r, z, up: [[x, y, z] for x, y in ((r[0][0], r[1][0]), (r[0][1], r[1][0]),  # noqa: E731
                                                     (r[0][1], r[1][1]), (r[0][0], r[1][1]))][::1 if up else -1]
    area = lambda r: (r[0][1] - r[0][0]) * (r[1][1] - r[1][0])                                # noqa: E731
    AF = lambda r: area(r) * gross_parallel(*r, *top, h)                                      # noqa: E731
    # A F(part -> top) of each polygon's uncovered part, by inclusion-exclusion
    m12 = ((0.4, 0.5), (0.6, 0.8))                  # m1 and m2 overlap
    m2in = ((0.4, 1.0), (0.6, 0.9))                 # m2 within the base
    if masks_first:
        order = [m1, m2, base]
        seen = [AF(m1), AF(m2) - AF(m12), AF(base) - AF(m1) - AF(m2in) + AF(m12)]
    else:
        order = [base, m1, m2]
        m2out = ((1.0, 1.3), (0.6, 0.9))           # m2 outside the base
        seen = [AF(base), 0.0, AF(m2out)]
    scene = ef.Scene.from_polygons([rect(r, 0, True) for r in order] + [rect(top, h, False)])
    F, E = ef.area_form_factors(scene, tolerance=tol, error=True)
    ref = np.zeros((4, 4))
    for k, (r, v) in enumerate(zip(order, seen)):
        ref[k, 3], ref[3, k] = v / area(r), v / area(top)
    assert np.all(np.abs(F - ref) <= E + 1e-15), F - ref
    assert ref[3].sum() > 0.2 and np.count_nonzero(ref[:3, 3]) >= 2


def test_window_after_its_wall_receives_nothing():
    # given after the wall, the window is covered whole: 0 from every emitter and 0 to
    # every receiver (it emitted its full unoccluded row before), and the wall
    # receives as if the window were not there
    scene, faces, win, _, _ = _room_with_a_window(False)
    F, E = ef.area_form_factors(scene, tolerance=1e-9, error=True)
    assert np.all(F[:, 3] == 0.0)
    assert np.all(F[3] == 0.0)
    rest = np.arange(len(scene)) != 3
    assert np.all(np.abs(F[rest].sum(axis=1) - 1.0) <= E[rest].sum(axis=1) + 1e-13)
    floor = faces[0]
    assert abs(F[0, 2] - ef.polygon_form_factor(floor, faces[2])) <= E[0, 2] + 1e-15
