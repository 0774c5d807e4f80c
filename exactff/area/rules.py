"""Quadrature on triangles: the collapsed Gauss-Legendre rules, the fully symmetric
rules, a polygon cut into triangles and a triangle cut in four, the pairs of rules
the adaptive integration of the hidden part compares (:mod:`exactff.area.adaptive`), its
ladder (:func:`refined`) and its global error budget (:func:`budget_refined`).
"""

import numpy as np
import shapely
from scipy.special import roots_legendre

from .. import _tolerances as tol
from ..errors import NumericalError
from ..geometry import cross, receiver_frame

__all__ = ["triangle_rule", "symmetric_triangle_rule", "SYMMETRIC_RULES",
           "SYMMETRIC_NULL_RULES", "symmetric_null_spread", "GAUSS_RULE",
           "GAUSS_LOW_RULE", "CORNER_MIDDLE_RULE", "RULE_PAIRS", "rule_pair", "quarter",
           "refined", "budget_refined", "far_triangles", "symmetric_degrees", "triangle_areas",
           "triangulate"]

#: Gauss-Legendre nodes and weights on [-1, 1]: the far-field rule's pair (12 and 8
#: points a side) and the third rule at a corner on the adaptive rules' lower pair.
GAUSS_RULE = roots_legendre(tol.AREA_GAUSS_ORDER)
GAUSS_LOW_RULE = roots_legendre(tol.AREA_GAUSS_LOW_ORDER)
CORNER_MIDDLE_RULE = roots_legendre(tol.AREA_CORNER_MIDDLE_ORDER)

#: The adaptive rules' collapsed pairs, lower then higher: rung 0 and rung 1.
RULE_PAIRS = tuple(tuple(roots_legendre(k) for k in orders) for orders in
                   (tol.AREA_RULE_ORDERS_MANY_CELLS, tol.AREA_RULE_ORDERS))


def triangle_rule(tri, rule=GAUSS_RULE):
    """Nodes and weights of the collapsed (Duffy) Gauss-Legendre rule on a triangle, or
    on each of a batch: ``n^2`` nodes, exact for polynomials of degree ``2n - 2`` in the
    triangle.

    Parameters
    ----------
    tri : ndarray of shape (3, 3), or (t, 3, 3) for a batch
    rule : (ndarray, ndarray)
        Gauss-Legendre nodes and weights on [-1, 1] (``scipy.special.roots_legendre``).

    Returns
    -------
    (ndarray of shape (n^2, 3), ndarray of shape (n^2,)), with a leading axis of t for
    a batch

    Examples
    --------
    >>> X, W = triangle_rule(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float))
    >>> X.shape, round(float(W.sum()), 15)          # the weights add up to the area
    ((144, 3), 0.5)
    """
    T = np.asarray(tri, dtype=float)
    batch = T[None] if T.ndim == 2 else T
    x, w = rule
    x, w = 0.5 * (x + 1.0), 0.5 * w
    U, V = np.meshgrid(x, x, indexing="ij")
    WW = (np.outer(w, w) * U).ravel()          # the collapse's Jacobian u
    U, UV = U.ravel()[None, :, None], (U * V).ravel()[None, :, None]
    a, b, c = batch[:, None, 0], batch[:, None, 1], batch[:, None, 2]
    X = a + U * (b - a) + UV * (c - b)
    # twice each triangle's area, |(b - a) x (c - a)|
    J = np.linalg.norm(cross(batch[:, 1] - batch[:, 0], batch[:, 2] - batch[:, 0]), axis=1)
    W = WW[None] * J[:, None]
    return (X[0], W[0]) if T.ndim == 2 else (X, W)


def _orbits(rule):
    """The barycentric points and weights (summing to 1) of a fully symmetric rule given
    by its orbits: ``(w, ())`` the centroid, ``(w, (a,))`` the three points
    ``(a, a, 1 - 2a)``, ``(w, (a, b))`` the six permutations of ``(a, b, 1 - a - b)``."""
    B, W = [], []
    for w, orbit in rule:
        if not orbit:
            pts = [(1 / 3, 1 / 3, 1 / 3)]
        elif len(orbit) == 1:
            a = orbit[0]
            pts = [(a, a, 1 - 2 * a), (a, 1 - 2 * a, a), (1 - 2 * a, a, a)]
        else:
            a, b = orbit
            c = 1 - a - b
            pts = [(a, b, c), (a, c, b), (b, a, c), (b, c, a), (c, a, b), (c, b, a)]
        B += pts
        W += [w] * len(pts)
    return np.array(B), np.array(W)


#: Fully symmetric rules on the triangle (Dunavant, IJNME 21 (1985) 1129-1148): degree 2
#: in 3 points (the points (2/3, 1/6, 1/6), weights 1/3), degree 4 in 6 points and degree
#: 8 in 16, every point inside and every weight positive. The published 15 digits refined
#: to 20 by Newton's method on the moment equations of the S3-invariant polynomials
#: (mpmath, 40 digits); tests/test_area.py checks the degrees.
SYMMETRIC_RULES = {
    2: _orbits([(1 / 3, (1 / 6,))]),
    4: _orbits([(0.22338158967801146570, (0.44594849091596488632,)),
                (0.10995174365532186764, (0.09157621350977074346,))]),
    8: _orbits([(0.14431560767778716825, ()),
                (0.095091634267284624794, (0.45929258829272315603,)),
                (0.10321737053471825028, (0.17056930775176020662,)),
                (0.032458497623198080311, (0.050547228317030975458,)),
                (0.027230314174434994265, (0.26311282963463811342, 0.0083947774099576053372))]),
}


def _symmetric_null_rules():
    """The fully symmetric null rules of degree ``low + 1`` on the nodes of the symmetric
    pair's rules (``AREA_SYMMETRIC_DEGREES``: degrees 4 and 8, 22 nodes, degree 5)
    together (:data:`SYMMETRIC_NULL_RULES`)."""
    low, high = tol.AREA_SYMMETRIC_DEGREES
    (B_low, w_low), (B_high, w_high) = SYMMETRIC_RULES[low], SYMMETRIC_RULES[high]
    B = np.concatenate([B_low, B_high])
    # the nodes' orbits: _orbits gives every node of an orbit its orbit's weight
    keys = [(0, w) for w in w_low] + [(1, w) for w in w_high]
    orbit = np.array([sorted(set(keys), key=keys.index).index(k) for k in keys])
    # a symmetric rule integrates f as it does f's mean over the triangle's symmetries,
    # so that the moment equations are those of the S3-invariant polynomials of degree
    # at most low + 1: e2^p e3^q (2p + 3q <= low + 1) of the barycentrics, against 0
    e2 = B[:, 0] * B[:, 1] + B[:, 1] * B[:, 2] + B[:, 2] * B[:, 0]
    e3 = B.prod(axis=1)
    moments = np.stack([e2 ** p * e3 ** q for p in range(low) for q in range(low)
                        if 2 * p + 3 * q <= low + 1])
    A = np.stack([moments[:, orbit == o].sum(axis=1) for o in range(orbit.max() + 1)], axis=1)
    # the solutions: the right singular vectors past the moments' count
    null = np.linalg.svd(A)[2][len(A):]                    # (2, orbits)
    if len(null) != 2:
        raise RuntimeError(f"the symmetric pair's null rules: {len(null)} solutions, not 2")
    # per node, orthonormal in the nodes' weights, each as long as the degree-8 rule's
    N, _ = np.linalg.qr(null[:, orbit].T)
    return N.T * np.linalg.norm(w_high)


#: Two null rules (weights summing to 0 that integrate every polynomial of degree 5
#: exactly to 0, per unit area) on the 22 nodes of the symmetric rules of degree 4 and
#: 8, in that order: the directions of degree 5 and above that the two rules' difference
#: alone can miss. Fully symmetric, orthonormal in the weights and scaled to the
#: degree-8 rule's weights, as Berntsen & Espelid's null rules (Algorithm 706: DCUTRI, ACM
#: TOMS 18 (1992) 329-342): their root sum of squares does not depend on the basis. Shape (2, 22).
SYMMETRIC_NULL_RULES = _symmetric_null_rules()


def symmetric_null_spread(H, area):
    """The degree-5 null rules' spread on triangles that took the symmetric rules of
    degree 4 and 8: ``area * sqrt(N1^2 + N2^2)`` for the null rules
    (:data:`SYMMETRIC_NULL_RULES`) applied to the hidden part's values at the 22 nodes,
    the degree-4 rule's first.

    Where the degree-8 rule's error is near the size of the triangle's terms of degree 5
    and above, its difference from the degree-4 rule, one null rule of degree 4, can be
    far below it by chance (a needle 89 long and 0.1 wide on gunter2, 24 times), while
    two more of degree 5 would have to vanish with it (:func:`rule_pair`).

    Parameters
    ----------
    H : ndarray of shape (t, 22)
    area : ndarray of shape (t,)

    Returns
    -------
    ndarray of shape (t,)

    Examples
    --------
    A polynomial of degree 5 has no spread; one of degree 6 does:

    >>> T = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    >>> X = np.concatenate([symmetric_triangle_rule(T, d)[0] for d in (4, 8)], axis=1)
    >>> x, y = X[..., 0], X[..., 1]
    >>> float(symmetric_null_spread(x ** 2 * y ** 3, np.array([0.5]))[0]) < 1e-16
    True
    >>> float(symmetric_null_spread(x ** 3 * y ** 3, np.array([0.5]))[0]) > 1e-5
    True
    """
    return np.sqrt(((H @ SYMMETRIC_NULL_RULES.T) ** 2).sum(axis=1)) * area


def symmetric_triangle_rule(tri, degree):
    """Nodes and weights of a fully symmetric rule (:data:`SYMMETRIC_RULES`) on a
    triangle, or on each of a batch: exact for polynomials of ``degree`` (2: 3 nodes, 4: 6,
    8: 16), with fewer nodes than :func:`triangle_rule` for the same degree (4, 9 and 25), but
    no vertex of its own (the collapsed rule integrates functions of the direction from
    its first vertex alone).

    Parameters
    ----------
    tri : ndarray of shape (3, 3), or (t, 3, 3) for a batch
    degree : {2, 4, 8}

    Returns
    -------
    (ndarray of shape (n, 3), ndarray of shape (n,)), with a leading axis of t for a
    batch

    Examples
    --------
    The unit triangle's area, and its integral of ``x^8`` (``8! / 10! = 1 / 90``):

    >>> X, W = symmetric_triangle_rule(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), 8)
    >>> X.shape, round(float(W.sum()), 15), round(float(W @ X[:, 0] ** 8), 15)
    ((16, 3), 0.5, 0.011111111111111)
    """
    T = np.asarray(tri, dtype=float)
    batch = T[None] if T.ndim == 2 else T
    B, w = SYMMETRIC_RULES[degree]
    X = np.einsum("nk,tkx->tnx", B, batch)
    # the triangle's area, |(b - a) x (c - a)| / 2
    A = 0.5 * np.linalg.norm(cross(batch[:, 1] - batch[:, 0], batch[:, 2] - batch[:, 0]), axis=1)
    W = w[None] * A[:, None]
    return (X[0], W[0]) if T.ndim == 2 else (X, W)


def rule_pair(T, rung, corner, atol, small=False):
    """The nodes and weights of the two rules of rung ``rung`` on the triangles T (t, 3,
    3): at rung 0 the symmetric rules of degree 4 and 8 (6 and 16 nodes), or where the
    first vertex is a corner that a blocker touches, the collapsed rules of the same
    degrees (3 and 5 points a side, 9 and 25 nodes: their collapsed vertex integrates
    functions of the direction from it); at rung 1 the collapsed rules of 6 and 10
    points a side. The symmetric pair only for a coarse absolute tolerance ``atol``
    (at least ``AREA_LOW_RULES_TOLERANCE``): with no vertex of their own, both miss a
    peak of the kernel near a corner alike, so that at a fine tolerance their
    difference can fall below the degree-8 rule's error, and the triangles would rest
    on the check against the closed form alone.

    ``small`` triangles (each at most ``AREA_SMALL_TRIANGLE_SHARE`` of the emitter's area
    and as far from the receiver's part and the blockers as ``AREA_SMALL_TRIANGLE_REACH``
    asks: :func:`far_triangles`) off a corner take,
    at such a tolerance, the symmetric rules of degrees 2 and 4 (3 and 6 nodes) on rung 0
    and those of degrees 4 and 8 on rung 1: where the hidden part is smooth on the
    triangle's scale the lower degrees' difference still bounds the error of the higher,
    for 9 nodes instead of 22, and 22 instead of 136 where refined."""
    degrees = symmetric_degrees(rung, corner, atol, small)
    if degrees is not None:
        return tuple(symmetric_triangle_rule(T, d) for d in degrees)
    return tuple(triangle_rule(T, rule) for rule in RULE_PAIRS[rung])


def symmetric_degrees(rung, corner, atol, small=False):
    """The degrees of the symmetric pair :func:`rule_pair` takes on triangles of rung
    ``rung`` (``corner``, ``small`` as there) at the target ``atol``, or None where it
    takes the collapsed rules.

    Examples
    --------
    >>> symmetric_degrees(0, False, 1e-6), symmetric_degrees(0, False, 1e-6, small=True)
    ((4, 8), (2, 4))
    >>> symmetric_degrees(1, False, 1e-6) is None, symmetric_degrees(0, True, 1e-6) is None
    (True, True)
    """
    if corner or atol < tol.AREA_LOW_RULES_TOLERANCE or not (rung == 0 or small):
        return None
    return (tol.AREA_SMALL_SYMMETRIC_DEGREES if small and rung == 0
            else tol.AREA_SYMMETRIC_DEGREES)


def far_triangles(T, pieces):
    """Per triangle of T (t, 3, 3): whether its box's diagonal is at most
    ``AREA_SMALL_TRIANGLE_REACH`` times the distance from its box to the nearest box of
    the ``pieces`` (arrays (k, 3): the receiver's part and the blockers' pieces), where
    the hidden part is smooth on the triangle's scale (:func:`rule_pair`'s small
    triangles). The sums and squares in the order of ``_core/levels.cpp``'s
    ``far_from``: the same decisions.

    Examples
    --------
    >>> T = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    >>> far_triangles(T, [T[0] + [0, 0, 2]]).tolist()      # 2 away, the diagonal sqrt(2)
    [True]
    >>> far_triangles(T, [T[0] + [0, 0, 1]]).tolist()
    [False]
    """
    lo, hi = T.min(axis=1), T.max(axis=1)                              # (t, 3)
    d2 = np.full(len(T), np.inf)
    # piece by piece (memory in the triangles alone: a pair may have 100,000 of them)
    for K in pieces:
        gap = np.maximum(np.maximum(K.min(axis=0) - hi, lo - K.max(axis=0)), 0.0)
        gap = gap * gap
        d2 = np.minimum(d2, (gap[:, 0] + gap[:, 1]) + gap[:, 2])
    h = (hi - lo) * (hi - lo)
    reach = tol.AREA_SMALL_TRIANGLE_REACH
    return (h[:, 0] + h[:, 1]) + h[:, 2] <= (reach * reach) * d2


def quarter(T):
    """Each triangle of T (t, 3, 3) cut in four at its edges' midpoints: (4 t, 3, 3), per
    triangle ``(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)`` (the first keeps the
    first vertex; the last is the middle one, turned as the triangle).

    Examples
    --------
    >>> Q = quarter(np.array([[[0, 0, 0], [2, 0, 0], [0, 2, 0]]], float))
    >>> Q.shape, triangle_areas(Q).tolist()
    ((4, 3, 3), [0.5, 0.5, 0.5, 0.5])
    """
    a_, b_, c_ = T[:, 0], T[:, 1], T[:, 2]
    ab, bc, ca = (a_ + b_) / 2, (b_ + c_) / 2, (c_ + a_) / 2
    return np.stack([np.stack(t, axis=1) for t in
                     ((a_, ab, ca), (ab, b_, bc), (ca, bc, c_), (ab, bc, ca))],
                    axis=1).reshape(-1, 3, 3)


def refined(T, depth, rung, corner, start):
    """The adaptive rules' next step for triangles T (t, 3, 3) at levels ``depth`` and
    rungs ``rung`` (t,): at rung 0 (the lower pair) the same triangle at rung 1 (the
    higher pair); at rung 1 its four quarters (:func:`quarter`; the first keeps the
    ``corner`` flag, the first vertex) one level down, on rung ``start``. The re-ruled
    ones first. Returns ``(T, depth, rung, corner)``.

    Examples
    --------
    >>> T = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]] * 2, float)
    >>> T2, d, r, c = refined(T, np.array([0, 2]), np.array([0, 1]),
    ...                       np.array([True, True]), 0)
    >>> T2.shape, d.tolist(), r.tolist(), c.tolist()
    ((5, 3, 3), [0, 3, 3, 3, 3], [1, 0, 0, 0, 0], [True, True, False, False, False])
    """
    again, split = rung == 0, rung == 1
    T = np.concatenate([T[again], quarter(T[split])])
    depth = np.concatenate([depth[again], np.repeat(depth[split] + 1, 4)])
    corner = np.concatenate([corner[again], np.stack(
        [corner[split]] + [np.zeros(int(split.sum()), dtype=bool)] * 3, axis=1).ravel()])
    rung = np.concatenate([np.ones(int(again.sum()), dtype=int),
                           np.full(4 * int(split.sum()), start)])
    return T, depth, rung, corner


def budget_refined(diff, area, depth, rung, before, atol, total_area):
    """Which triangles of an occluded pair to refine so that the rules' differences fit
    half of ``atol``: the global error budget of adaptive cubature (Genz & Malik 1980;
    QUADPACK's ``qag``), the largest difference first, as many as bring the others'
    sum within it.

    A triangle at rung 1 on the last level (``AREA_MAX_DEPTH``) cannot be refined: its
    difference counts against the budget, and the others share what is left, never
    less than their share by area (``atol / 2`` of the cells' ``total_area``), so that
    one such triangle does not send all the others to the last level. Sums are
    sequential (cumulative, in the given order), as the compiled levels take them
    (``_core/levels.cpp``).

    Parameters
    ----------
    diff, area : ndarray of shape (t,)
        The triangles' rules' differences (per unit area of the emitter) and areas.
    depth, rung : ndarray of shape (t,)
        Their levels and rungs (:func:`refined`).
    before : float
        The differences accepted before (an earlier call's triangles).
    atol : float
        The pair's absolute tolerance.
    total_area : float
        The area of the pair's cells.

    Returns
    -------
    ndarray of int
        The indices to refine, increasing.

    Raises
    ------
    NumericalError
        A difference is not finite (NaN or infinite: no order of the triangles, no
        budget); the compiled levels decline the pair there (``_core/levels.cpp``), so
        that it comes here.

    Examples
    --------
    Four triangles of equal area, their differences summing to 1.0 against a budget of
    0.5: the two largest are refined.

    >>> budget_refined(np.array([0.1, 0.4, 0.2, 0.3]), np.ones(4), np.zeros(4, int),
    ...                np.zeros(4, int), 0.0, 1.0, 4.0).tolist()
    [1, 3]
    """
    bad = np.flatnonzero(~np.isfinite(diff))
    if len(bad):
        raise NumericalError(f"the adaptive rules' difference on triangle {int(bad[0])} "
                             f"is {diff[bad[0]]}: not finite")
    target = 0.5 * atol
    refinable = (rung == 0) | (depth < tol.AREA_MAX_DEPTH)
    stuck = float(np.cumsum(diff[~refinable])[-1]) if (~refinable).any() else 0.0
    mine = np.flatnonzero(refinable)
    if not len(mine):
        return mine
    room = float(np.cumsum(area[mine])[-1])
    budget = max(target - before - stuck, target * room / total_area)
    # largest first (ties in the given order), while what is left exceeds the budget
    order = mine[np.argsort(-diff[mine], kind="stable")]
    left = float(np.cumsum(diff[mine])[-1]) - np.concatenate([[0.0], np.cumsum(diff[order])[:-1]])
    return np.sort(order[left > budget])


def triangle_areas(T):
    """The areas of triangles T (t, 3, 3): ``|(b - a) x (c - a)| / 2``, shape (t,)."""
    return 0.5 * np.linalg.norm(cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)


def triangulate(P, n):
    """Triangles covering a planar polygon P (K, 3) of unit normal n (constrained
    Delaunay in its plane), as a list of (3, 3) arrays.

    Examples
    --------
    >>> P = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 0.5, 0], [0, 1, 0]], float)
    >>> T = np.array(triangulate(P, np.array([0, 0, 1.0])))
    >>> len(T), float(triangle_areas(T).sum())           # the polygon's area, 1.5
    (3, 1.5)
    """
    R = receiver_frame(n)
    uv = (P - P[0]) @ R[:2].T
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(uv)))
    out = []
    for t in tris:
        c = np.asarray(t.exterior.coords)[:3]
        out.append(P[0] + c @ R[:2])
    return out
