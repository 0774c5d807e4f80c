"""Area-to-area form factors, unoccluded (issue 15, item 1): ``polygon_form_factor``.

References: Howell's catalogue (C-11, parallel opposed rectangles; C-14, perpendicular
rectangles with a common edge), evaluated here in mpmath at 40 digits (the double
closed forms cancel badly for small or far rectangles); reciprocity; splitting.
"""

import mpmath as mp
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import exactff as ef

from common import examples, random_rotation


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


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=examples(40), deadline=None)
def test_reciprocity_on_random_pairs(seed):
    rng = np.random.default_rng(seed)
    # two random convex quads facing each other roughly, at a random distance
    def quad(z, flip):
        t = np.sort(rng.uniform(0, 2 * np.pi, 4))
        r = rng.uniform(0.3, 1.5, 4)
        Pq = np.column_stack([r * np.cos(t), r * np.sin(t), np.full(4, z)])
        from scipy.spatial import ConvexHull
        Pq = Pq[ConvexHull(Pq[:, :2]).vertices]
        return Pq[::-1].copy() if flip else Pq
    P = quad(0.0, False)
    Q = quad(rng.uniform(0.05, 8.0), True) + [*rng.uniform(-1, 1, 2), 0]
    M = random_rotation(rng)
    P, Q = P @ M.T, Q @ M.T
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


def test_bad_polygons_raise_scene_errors():
    P, Q = parallel_pair(1, 1, 1)
    with pytest.raises(ef.SceneError, match="polygon 1"):
        ef.polygon_form_factor(P, [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
