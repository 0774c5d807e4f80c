"""Area-to-area form factors (the paper's Eq. 1), unoccluded: the contour integral and
the far-field rule.

For two planar polygons P and Q, Stokes' theorem turns the double area integral of
Eq. 1 into a double contour integral (Mitalas & Stephenson 1966; Sparrow 1963):

    A_P F(P -> Q) = (1 / 2 pi) sum_i sum_j (e_i . e_j) int_0^1 int_0^1 ln |p_i(s) - q_j(t)| dt ds

over the edges ``p_i(s) = a_i + s e_i`` of P and ``q_j(t) = b_j + t e_j`` of Q, each
counter-clockwise seen from its front. Both integrals are in closed form
(``_edge_log_integrals``: elementary for parallel edges, dilogarithms for skew ones; see
the notes before it), evaluated for all edge pairs of one emitter and many receivers at
once (:func:`unoccluded_pairs`), each pair scaled by a power of 2 near its centroids'
distance (the scale's ``ln L`` drops out: ``(sum e_i) . (sum e_j) = 0``). The error
estimate is the rounding of the terms' magnitudes (``AREA_CLOSED_ULPS``).

The contour terms cancel as (distance / size)^2 when the polygons are far apart, and for
thin polygons: where the estimate misses its target (``AREA_CLOSED_RTOL``, or an area
row's tolerance) the double integral is taken, for pairs beyond ``AREA_FAR`` diameters,
as the area integral over P of the exact point form factors (smooth there) by a
Gauss-Legendre rule on P's triangles, then (area rows) by the tanh-sinh rule below, and
where it still misses, the costliest edge pairs are evaluated again in mpmath.

The tanh-sinh outer quadrature of the inner closed form (``_segment_log_integral``), the
production path before, is kept as a fallback and a test oracle (``_contour_tanh_sinh``).

One-sided, as the point form factors: only the part of Q in front of P's plane and
the part of P in front of Q's plane take part.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
from numpy.typing import ArrayLike
import shapely
from scipy.special import roots_legendre, spence, xlogy

from .. import _tolerances as tol
from ..errors import NumericalError, check_finite
from ..geometry import area_vector, cross, polygon_diameter, receiver_frame
from ..halfspace import clip_halfspace
from ..kernel import clipped_sector_sums
from ..rings import owners, padded, successors
from ..scene import validate_polygon

__all__ = ["polygon_form_factor", "clip_front", "front_parts", "triangle_rule",
           "symmetric_triangle_rule", "SYMMETRIC_RULES", "point_values",
           "emitter_nodes", "far_values", "unoccluded_pair", "unoccluded_pairs", "nonnegative",
           "is_far", "CLOSED_FORM_COUNTS"]


def nonnegative(value, estimate, what="area form factor"):
    """``value`` (a float or an array) with what rounding left below 0 set to 0, where
    it lies within its own error ``estimate`` (the estimate still covers it:
    ``0 <= exact <= value + estimate <= estimate``); a value below 0 beyond it, or NaN,
    raises :class:`~exactff.NumericalError` instead of being hidden.

    Examples
    --------
    >>> float(nonnegative(-1e-17, 1e-16))
    0.0
    >>> nonnegative(-1e-15, 1e-16)
    Traceback (most recent call last):
    ...
    exactff.NumericalError: area form factor -1e-15 below 0 beyond its error estimate 1e-16
    """
    v, e = np.asarray(value, dtype=float), np.asarray(estimate, dtype=float)
    bad = ~(v >= -e)
    if np.any(bad):
        bad = np.broadcast_to(bad, np.broadcast(v, e).shape)
        k = int(np.flatnonzero(bad.ravel())[0])
        vk = float(np.broadcast_to(v, bad.shape).ravel()[k])
        ek = float(np.broadcast_to(e, bad.shape).ravel()[k])
        why = "is NaN" if np.isnan(vk) else (
            "has a NaN error estimate" if np.isnan(ek) else "below 0 beyond its error estimate")
        raise NumericalError(f"{what} {vk!r} {why} {ek!r}")
    out = np.maximum(v, 0.0)
    return float(out) if out.ndim == 0 else out


def is_far(P, Q):
    """True when P and Q are far enough apart for the far-field rule: their centroids
    more than ``AREA_FAR`` diameters of the larger one apart."""
    r0 = float(np.linalg.norm(Q.mean(axis=0) - P.mean(axis=0)))
    return r0 > tol.AREA_FAR * max(polygon_diameter(P), polygon_diameter(Q))


def clip_front(P, n, c, d=None):
    """The part of polygon P with ``n . (x - c) > 0`` (None when nothing is left): the
    engine's half-space clipping, about the point c. ``d``: the distances
    ``(P - c) @ n`` where the caller has them (:func:`front_parts`), else computed."""
    if d is None:
        d = (P - c) @ n
    if np.all(d >= 0) and np.any(d > 0):
        return P
    if np.all(d <= 0):
        return None
    V, k = clip_halfspace((P - c)[None], np.array([len(P)]), n)
    C = V[0, :k[0]] + c
    # a cut through a vertex repeats it: no edge of zero length
    C = C[np.any(C != np.roll(C, 1, axis=0), axis=1)]
    return C if len(C) >= 3 else None



def _tanh_sinh(level=tol.TANH_SINH_LEVEL, t_max=tol.TANH_SINH_T_MAX):
    """Tanh-sinh nodes on [0, 1] as (distance to the nearer end, which end, weight, the
    weight of the rule one level coarser: twice as wide a step, on every other node):
    the distance to the end is computed without cancellation."""
    h = 2.0 ** -level
    k = np.arange(-int(t_max / h), int(t_max / h) + 1)
    t = k * h
    u = 0.5 * np.pi * np.sinh(np.abs(t))
    e = np.exp(-2.0 * u)
    d = e / (1.0 + e)                       # (1 - |tanh u|) / 2: distance to the end
    w = h * 0.5 * np.pi * np.cosh(t) * 4.0 * e / (1.0 + e) ** 2 / 2.0
    coarse = np.where(k % 2 == 0, 2.0 * w, 0.0)
    keep = d > 0
    return d[keep], (t >= 0)[keep], w[keep], coarse[keep]


_NODES = _tanh_sinh()


def _segment_log_integral(W, E):
    """``int_0^1 ln |W + t E| dt`` for arrays of vectors W (..., 3) and E (..., 3), in
    closed form: with ``a = |E|^2``, ``u = t + (W . E) / a`` and ``k = |W x E| / a``,
    ``ln |W + t E| = (ln a + ln(u^2 + k^2)) / 2`` and
    ``int ln(u^2 + k^2) du = u ln(u^2 + k^2) - 2 u + 2 k atan(u / k)``."""
    a = np.einsum("...i,...i->...", E, E)
    b = np.einsum("...i,...i->...", W, E) / a
    k = np.linalg.norm(cross(W, E), axis=-1) / a
    u0, u1 = b, b + 1.0

    def prim(u):
        with np.errstate(divide="ignore", invalid="ignore"):
            at = np.where(k > 0, k * np.arctan2(u, k), 0.0)
        return xlogy(u, u * u + k * k) - 2.0 * u + 2.0 * at

    return 0.5 * np.log(a) + 0.5 * (prim(u1) - prim(u0))


_GL = roots_legendre(tol.AREA_GAUSS_ORDER)
_GL_LOW = roots_legendre(tol.AREA_GAUSS_LOW_ORDER)


def _triangles(P, n):
    """Triangles covering a planar polygon (constrained Delaunay in its plane)."""
    R = receiver_frame(n)
    uv = (P - P[0]) @ R[:2].T
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(uv)))
    out = []
    for t in tris:
        c = np.asarray(t.exterior.coords)[:3]
        out.append(P[0] + c @ R[:2])
    return out


def triangle_rule(tri, rule=_GL):
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


#: Fully symmetric rules on the triangle (Dunavant, IJNME 21 (1985) 1129-1148): degree 4
#: in 6 points and degree 8 in 16, every point inside and every weight positive. The
#: published 15 digits refined to 20 by Newton's method on the moment equations of the
#: S3-invariant polynomials (mpmath, 40 digits); tests/test_area.py checks the degrees.
SYMMETRIC_RULES = {
    4: _orbits([(0.22338158967801146570, (0.44594849091596488632,)),
                (0.10995174365532186764, (0.09157621350977074346,))]),
    8: _orbits([(0.14431560767778716825, ()),
                (0.095091634267284624794, (0.45929258829272315603,)),
                (0.10321737053471825028, (0.17056930775176020662,)),
                (0.032458497623198080311, (0.050547228317030975458,)),
                (0.027230314174434994265, (0.26311282963463811342, 0.0083947774099576053372))]),
}


def symmetric_triangle_rule(tri, degree):
    """Nodes and weights of a fully symmetric rule (:data:`SYMMETRIC_RULES`) on a
    triangle, or on each of a batch: exact for polynomials of ``degree`` (4: 6 nodes, 8:
    16), with fewer nodes than :func:`triangle_rule` for the same degree (9 and 25), but
    no vertex of its own (the collapsed rule integrates functions of the direction from
    its first vertex alone).

    Parameters
    ----------
    tri : ndarray of shape (3, 3), or (t, 3, 3) for a batch
    degree : {4, 8}

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


def point_values(X, nP, Qs):
    """Unoccluded point form factors from the points X (normal nP) to each polygon of
    Qs (in front of them), in offset form, vectorised over points and polygons: arrays
    of shape (len(Qs), len(X)) of the values and of their rounding error estimates."""
    R = receiver_frame(nP)
    nX, m = len(X), len(Qs)
    ks = np.array([len(Q) for Q in Qs])
    # polygon (j, p): receiver j seen from point p, numbered j * nX + p; its vertices'
    # offsets from its first vertex are the same for every point
    A0 = ((np.array([Q[0] for Q in Qs])[:, None, :] - X[None]) @ R.T).reshape(-1, 3)
    E = np.concatenate([np.tile((Q - Q[0]) @ R.T, (nX, 1)) for Q in Qs])
    lens = np.repeat(ks, nX)
    offsets = np.concatenate([[0], np.cumsum(lens)])
    owner, nxt = owners(offsets), successors(offsets)
    S, mags, errs = clipped_sector_sums(A0, E, nxt, owner, m * nX, rounded_offsets=True)
    # the sector sums' own error model (C1 is calibrated for the unit roundoff 2**-53)
    return (np.abs(S).reshape(m, nX) / (2.0 * np.pi),
            ((tol.C1 * tol.EPS * mags + errs) / (2.0 * np.pi)).reshape(m, nX))


def emitter_nodes(Pc, nP):
    """The 12- and 8-point collapsed Gauss-Legendre rules on P's triangles, as one set
    of nodes and the two weight vectors (each zero on the other rule's nodes)."""
    tris = _triangles(Pc, nP)
    hi = [triangle_rule(t, _GL) for t in tris]
    lo = [triangle_rule(t, _GL_LOW) for t in tris]
    X = np.concatenate([x for x, _ in hi] + [x for x, _ in lo])
    n_hi = sum(len(w) for _, w in hi)
    W_hi, W_lo = np.zeros(len(X)), np.zeros(len(X))
    W_hi[:n_hi] = np.concatenate([w for _, w in hi])
    W_lo[n_hi:] = np.concatenate([w for _, w in lo])
    return X, W_hi, W_lo




def far_values(nodes, nP, area_P, Qs):
    """F(P -> Q) for far receivers Qs (each in front of P's nodes) by the area integral
    of exact point values, and its estimate: the difference between the 12- and 8-point
    rules plus rounding."""
    X, W_hi, W_lo = nodes
    hi, lo = np.empty(len(Qs)), np.empty(len(Qs))
    per = max(1, tol.AREA_EDGE_TERMS_PER_CALL // (len(X) * max(len(Q) for Q in Qs)))
    for s in range(0, len(Qs), per):
        V = point_values(X, nP, Qs[s:s + per])[0]
        hi[s:s + per], lo[s:s + per] = V @ W_hi / area_P, V @ W_lo / area_P
    est = np.abs(hi - lo) + tol.AREA_ROUNDING_ULPS * tol.EPS * np.abs(hi)
    # a sum of non-negative point values with positive weights: below 0 only by rounding
    return nonnegative(hi, est), est


def polygon_form_factor(P: ArrayLike, Q: ArrayLike, error: bool = False):
    """The area-to-area form factor F(P -> Q), unoccluded, exact to rounding.

    The paper's Eq. 1: ``(1 / A_P) int_P int_Q cos(theta_P) cos(theta_Q) / (pi r^2)
    dA_Q dA_P``, one-sided (only the parts of each polygon in front of the other's
    plane), by the contour integral of Mitalas and Stephenson with both integrals in
    closed form (:func:`unoccluded_pairs`; see the module's notes), the far-field rule
    or mpmath where the closed form's rounding estimate misses ``AREA_CLOSED_RTOL``.

    Parameters
    ----------
    P, Q : array_like of shape (K, 3)
        Planar polygons, counter-clockwise seen from their fronts.
    error : bool, default False
        Also return the error estimate: a bound on ``|F - exact|``, from the rounding of
        the closed form's terms (or the far-field rule's, or the mpmath evaluation's).

    Returns
    -------
    float, or (float, float) with ``error=True``
        F(P -> Q), and its error estimate.

    Raises
    ------
    SceneError
        A polygon is ill-formed (as for scenes; P is polygon 0, Q polygon 1).
    NumericalError
        The value or its estimate came out NaN or infinite, or the value below 0 beyond
        its estimate (never returned).

    Examples
    --------
    Two parallel unit squares one apart, facing each other (Howell's catalogue,
    C-11: 0.19982489570):

    >>> P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> Q = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]
    >>> round(polygon_form_factor(P, Q), 12)
    0.199824895698
    >>> f, e = polygon_form_factor(P, Q, error=True)
    >>> abs(f - 0.19982489569838739) <= e < 1e-14
    True
    """
    if not isinstance(error, (bool, np.bool_)):
        raise ValueError(f"error must be True or False, not {error!r}")
    P = np.array(validate_polygon(P, 0), dtype=float)
    Q = np.array(validate_polygon(Q, 1), dtype=float)
    f, e = check_finite(*unoccluded_pair(P, Q))
    return (f, e) if error else f


def _edge_pieces(P, eP, Q, eQ):
    """Each edge of P cut at the points nearest to the lines of Q's edges and to Q's
    vertices, where those come within the edge's length of it: there the inner integral
    of the contour form has its kinks (an edge of Q met in its interior, a vertex of Q
    on the edge) or steep stretches, and the tanh-sinh rule wants them at the ends of
    its intervals. Returns ``(owner, s0, s1)``: the pieces' edges (sorted) and their
    ends as parameters along the edge."""
    ee = np.einsum("ij,ij->i", eP, eP)
    # nearest points to Q's vertices, and to the lines of Q's edges (not when parallel)
    at_vertex = np.einsum("pqj,pj->pq", Q[None] - P[:, None], eP) / ee[:, None]
    c = cross(eP[:, None, :], eQ[None, :, :])                          # (KP, KQ, 3)
    cc = np.einsum("pqj,pqj->pq", c, c)
    crossing = np.einsum("pqj,pqj->pq", cross(Q[None] - P[:, None], eQ[None]), c)
    ok = cc > tol.AREA_EVENT_PARALLEL * ee[:, None] * np.einsum("qj,qj->q", eQ, eQ)[None]
    at_line = np.where(ok, crossing / np.where(ok, cc, 1.0), -1.0)
    S = np.concatenate([at_vertex, at_line], axis=1)                      # (KP, 2 KQ)
    # only where Q comes within the edge's length of the point
    X = P[:, None, :] + S[..., None] * eP[:, None, :]
    D = X[:, :, None, :] - Q[None, None]                                  # (KP, 2KQ, KQ, 3)
    t = np.clip(np.einsum("pcqj,qj->pcq", D, eQ) / np.einsum("qj,qj->q", eQ, eQ), 0.0, 1.0)
    near = np.linalg.norm(D - t[..., None] * eQ, axis=-1).min(axis=2)
    keep = (S > tol.AREA_EDGE_CUT) & (S < 1.0 - tol.AREA_EDGE_CUT) & (near < np.sqrt(ee)[:, None])
    owner, s0, s1 = [], [], []
    for k in range(len(P)):
        cut = np.sort(S[k, keep[k]])
        if cut.size:
            cut = cut[np.r_[True, np.diff(cut) > tol.AREA_EDGE_CUT]]
        ends = np.r_[0.0, cut, 1.0]
        owner += [k] * (len(ends) - 1)
        s0 += list(ends[:-1])
        s1 += list(ends[1:])
    return np.array(owner), np.array(s0), np.array(s1)


# ---------------------------------------------------------------------------------------
# the edge-pair integral J = int_0^1 int_0^1 ln |a + s e - b - t f| ds dt in closed form
# ---------------------------------------------------------------------------------------
#
# Skew (non-parallel) edges. With n = (e x f) / |e x f|, the difference of the two points
# splits into a constant part d n across (d = (a - b) . n, the lines' distance) and the
# point X(s, t) = w + s e - t f of their common plane (w: the part of a - b in that
# plane), which sweeps a parallelogram of area |e x f|. So
#     J = (1 / |e x f|) int_parallelogram (1/2) ln(d^2 + |X|^2) dX,
# a radial function over a polygon: the signed sum of its integrals over the triangles
# (0, A, B) on the parallelogram's edges A -> B. For an edge at distance h from the origin,
# with t the position along it from the foot of the perpendicular, phi = atan(t / h),
# m^2 = h^2 + d^2 and rho = (m - h) / (m + h) = d^2 / (m + h)^2, the triangle's integral is
#     T = (1/4) [h Phi(t) - h t + d^2 K(phi)]  between the edge's ends,
#     Phi(t) = t ln(t^2 + m^2) - 2 t + 2 m atan(t / m),
#     K(phi) = -phi ln rho - Im Li2(-rho e^{2 i phi}) + Im Li2(-e^{2 i phi}),
# from int_0^R (1/2) ln(d^2 + r^2) r dr = (1/4) [(d^2 + R^2) ln(d^2 + R^2) - R^2 - d^2 ln d^2]
# with R = h / cos(phi), and ln(d^2 cos^2 phi + h^2) = ln((m + h)^2 / 4)
# + ln(1 + 2 rho cos 2phi + rho^2), whose Fourier series integrates to the dilogarithm
# (-Im Li2(-rho e^{i psi}) / 2 per unit of psi = 2 phi), and -2 ln |2 cos phi| to
# Im Li2(-e^{2 i phi}) (Clausen's function Cl2(pi + 2 phi)). This is the dilogarithm
# form of Schroeder & Hanrahan ("On the form factor between two polygons", SIGGRAPH 1993)
# and Narayanaswamy (IJHMT 2015), derived here through the parallelogram: d = 0 (edges on
# intersecting lines) leaves only elementary terms, and an edge through the origin
# (h = 0: the lines' common point on the parallelogram's boundary, touching edges)
# contributes 0, so shared vertices and edges need no limits but xlogy's 0 ln 0 = 0.
#
# Parallel edges (e x f = 0, f = sigma |f| e / |e|): with z the position along the common
# direction and delta the lines' distance, ln r = (1/2) ln(z^2 + delta^2) has the double
# antiderivative G2(z) = (1/4) (z^2 - delta^2) ln(z^2 + delta^2) - (3/4) z^2
# + delta z atan(z / delta), and
#     J = [G2(w + X) - G2(w) - G2(w + X - Y) + G2(w - Y)] / (X Y),  X = |e|, Y = sigma |f|,
# w the offset of a from b along the direction.


def _li2(x):
    """The dilogarithm ``Li2(x)`` of complex ``x`` in the closed unit disk, by scipy's
    ``spence`` (``Li2(x) = spence(1 - x)``), except within ``AREA_LI2_AXIS`` of the
    real axis left of 1/2. There scipy's complex ``spence`` is wrong near
    ``x = -(2 - sqrt 3)``: at ``x = -0.2679491924311228 - 8.4e-17 i`` it returned an
    imaginary part of 0.028 for 7.5e-17. So the value there is the real ``spence`` plus
    the first-order term ``i Im(x) Li2'(Re x)``, with ``Li2'(a) = -ln(1 - a) / a``. The
    second-order term is below ``AREA_LI2_AXIS^2``.

    Examples
    --------
    >>> z = np.array([-0.2679491924311228 - 8.41410012693027e-17j, 0.5 + 0.5j])
    >>> np.round(_li2(z), 12).tolist()
    [(-0.251862018609-0j), (0.45398526915+0.643767332889j)]
    """
    x = np.asarray(x, dtype=complex)
    out = spence(1.0 - x)
    a, b = x.real, x.imag
    axis = (np.abs(b) <= tol.AREA_LI2_AXIS) & (a <= 0.5)
    if np.any(axis):
        aa, bb = a[axis], b[axis]
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.where(aa != 0, -np.log1p(-aa) / np.where(aa != 0, aa, 1.0), 1.0)
        out[axis] = spence(1.0 - aa) + 1j * bb * slope
    return out


def _skew_edge_integrals(a, e, b, f):
    """J and the sum of its terms' magnitudes (its rounding scale) for skew edges.

    Parameters
    ----------
    a, e, b, f : ndarray of shape (N, 3)
        The edges ``a + s e`` and ``b + t f``, ``e x f`` nonzero.

    Returns
    -------
    (ndarray of shape (N,), ndarray of shape (N,))
    """
    c = cross(e, f)
    cn = np.sqrt(np.einsum("ij,ij->i", c, c))
    n = c / cn[:, None]
    w = a - b
    d = np.einsum("ij,ij->i", w, n)
    wp = w - d[:, None] * n                         # the parallelogram's corner, in plane
    d2 = d * d
    V = (wp, wp + e, wp + e - f, wp - f)
    S, M = np.zeros(len(a)), np.zeros(len(a))
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(4):
            A, D = V[k], V[(k + 1) % 4] - V[k]
            L = np.sqrt(np.einsum("ij,ij->i", D, D))
            u = D / L[:, None]
            tA = np.einsum("ij,ij->i", A, u)
            tB = tA + L
            hs = np.einsum("ij,ij->i", cross(A, u), n)     # signed: the triangle's side
            absA = np.sqrt(np.einsum("ij,ij->i", A, A))
            # a triangle thinner than AREA_CLOSED_THIN of its size is of no area (its
            # terms, below that share of the magnitudes counted, would only underflow)
            h = np.where(np.abs(hs) > tol.AREA_CLOSED_THIN * (absA + L), np.abs(hs), 0.0)
            m2 = h * h + d2
            m = np.sqrt(m2)
            mh = m + h
            q = np.where(mh > 0, np.abs(d) / np.where(mh > 0, mh, 1.0), 0.0)   # sqrt(rho)
            lq = np.where(q > 0, np.log(np.where(q > 0, q, 1.0)), 0.0)
            # h and t carry the rounding of the corner A (of its size, not of h's): the
            # elementary part's magnitude is taken with h + |A| + L for h
            H = h + absA + L
            tri, mag = -h * L, H * L
            for t, sgn in ((tB, 1.0), (tA, -1.0)):
                # Phi(t): the elementary part
                # (a logarithm's rounding is absolute: t ln(...) is off by |t| ulps)
                lg = np.log(np.where(t * t + m2 > 0, t * t + m2, 1.0))
                p1, p2 = t * lg, 2.0 * m * np.arctan2(t, m)
                tri = tri + sgn * h * (p1 - 2.0 * t + p2)
                mag = mag + H * (np.abs(t) * (np.abs(lg) + 4.0) + np.abs(p2) + 2.0 * m)
                # K(phi): the dilogarithms, e^{2 i phi} = ((h^2 - t^2) + 2 i h t) / (h^2 + t^2),
                # with h and t scaled by the larger (h^2 + t^2 in [1, 2]: never under- or
                # overflows); only where h > 0 (where h = 0 the triangle is dropped below)
                live = h > 0
                sc = np.maximum(h, np.abs(t))
                sc = np.where(sc > 0, sc, 1.0)
                hn, tn = h / sc, t / sc
                z = ((hn * hn - tn * tn) + 2j * hn * tn) / (hn * hn + tn * tn)
                phi = np.arctan2(t, h)
                k1 = -2.0 * phi * lq
                k2 = -_li2(-(q * q) * z).imag                   # -Im Li2(-rho e^{2 i phi})
                k3 = _li2(-z).imag                              # Im Li2(-e^{2 i phi})
                kk = np.where(live, k1 + k2 + k3, 0.0)
                tri = tri + sgn * d2 * kk
                # the dilogarithms' rounding: of their values, and of their arguments
                # times the derivative, ln |1 - w| / |w|, near w = 1 logarithmic
                # (|1 + z| = 0: the logarithm of the smallest normal number)
                dl = (np.abs(np.log(np.maximum(np.abs(1.0 + (q * q) * z), tol.DOUBLE_TINY)))
                      + np.abs(np.log(np.maximum(np.abs(1.0 + z), tol.DOUBLE_TINY))))
                km = 2.0 * np.abs(phi) * (np.abs(lq) + 2.0) + np.abs(k2) + np.abs(k3) + dl + 4.0
                mag = mag + d2 * np.where(live, km, 0.0)
            # an edge through the origin (h = 0) bounds a triangle of no area
            tri = np.where(h > 0, tri, 0.0)
            S += np.sign(hs) * tri
            M += mag
    # the parallelogram w + s e - t f is traversed clockwise about n
    return -0.25 * S / cn, 0.25 * M / cn


def _parallel_edge_integrals(a, e, b, f):
    """J and the sum of its terms' magnitudes for parallel edges (``e x f = 0``).

    Parameters and returns as :func:`_skew_edge_integrals`.
    """
    X = np.sqrt(np.einsum("ij,ij->i", e, e))
    u = e / X[:, None]
    Y = np.einsum("ij,ij->i", f, u)                 # sigma |f|
    w = a - b
    z0 = np.einsum("ij,ij->i", w, u)
    perp = w - z0[:, None] * u
    delta = np.sqrt(np.einsum("ij,ij->i", perp, perp))
    dd = delta * delta
    J, M = np.zeros(len(a)), np.zeros(len(a))
    with np.errstate(divide="ignore", invalid="ignore"):
        for z, sgn in ((z0 + X, 1.0), (z0, -1.0), (z0 + X - Y, -1.0), (z0 - Y, 1.0)):
            zz = z * z
            g1 = 0.25 * xlogy(zz - dd, zz + dd)
            g3 = np.where(delta > 0, delta * z * np.arctan2(z, delta), 0.0)
            J += sgn * (g1 - 0.75 * zz + g3)
            # a logarithm's rounding is absolute: (z^2 - delta^2) ln(...) is off by
            # |z^2 - delta^2| ulps
            lg = np.log(np.where(zz + dd > 0, zz + dd, 1.0))
            M += 0.25 * np.abs(zz - dd) * (np.abs(lg) + 4.0) + zz + np.abs(g3) + dd
    XY = np.abs(X * Y)
    return J / (X * Y), M / XY


def _edge_log_integrals(a, e, b, f):
    """``J = int_0^1 int_0^1 ln |a + s e - b - t f| ds dt`` for many edge pairs at once, in
    closed form (see the notes above), and the sum of its terms' magnitudes.

    Parameters
    ----------
    a, e, b, f : ndarray of shape (N, 3)
        The edges ``a + s e`` (``s`` in [0, 1]) and ``b + t f``, of nonzero length.

    Returns
    -------
    (ndarray of shape (N,), ndarray of shape (N,))
        J, and the magnitudes whose rounding bounds its error (the caller's
        ``AREA_CLOSED_ULPS`` units of EPS of them; at least ``|J|``).
    """
    c = cross(e, f)
    par = np.einsum("ij,ij->i", c, c) == 0     # (a cross product below 1e-154 is 0)
    J, M = np.empty(len(a)), np.empty(len(a))
    if np.any(par):
        J[par], M[par] = _parallel_edge_integrals(a[par], e[par], b[par], f[par])
    if not np.all(par):
        s = ~par
        J[s], M[s] = _skew_edge_integrals(a[s], e[s], b[s], f[s])
    return J, np.maximum(M, np.abs(J))


def _mp_edge_log_integral(a, e, b, f):
    """J of one edge pair (mpmath vectors of 3), in mpmath at its working precision, and
    the magnitude of its terms (what its rounding is relative to): the same closed form as
    :func:`_edge_log_integrals` (``mp.polylog`` for the dilogarithm inside the unit disk,
    ``mp.clsin`` for Clausen's function on the circle)."""
    dot = lambda x, y: x[0] * y[0] + x[1] * y[1] + x[2] * y[2]        # noqa: E731
    cross = lambda x, y: [x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2],  # noqa: E731
                          x[0] * y[1] - x[1] * y[0]]
    w = [a[k] - b[k] for k in range(3)]
    c = cross(e, f)
    cn = mp.sqrt(dot(c, c))
    if cn == 0:
        X = mp.sqrt(dot(e, e))
        u = [v / X for v in e]
        Y, z0 = dot(f, u), dot(w, u)
        perp = [w[k] - z0 * u[k] for k in range(3)]
        delta = mp.sqrt(dot(perp, perp))
        total, mag = mp.mpf(0), mp.mpf(0)
        for z, sgn in ((z0 + X, 1), (z0, -1), (z0 + X - Y, -1), (z0 - Y, 1)):
            s2 = z * z + delta * delta
            g = (z * z - delta * delta) * mp.log(s2) / 4 if s2 > 0 else mp.mpf(0)
            g += -3 * z * z / 4 + (delta * z * mp.atan2(z, delta) if delta > 0 else 0)
            total += sgn * g
            mag += abs(g) + z * z
        return total / (X * Y), mag / abs(X * Y)
    n = [v / cn for v in c]
    d = dot(w, n)
    wp = [w[k] - d * n[k] for k in range(3)]
    V = [wp, [wp[k] + e[k] for k in range(3)], [wp[k] + e[k] - f[k] for k in range(3)],
         [wp[k] - f[k] for k in range(3)]]
    S, mag = mp.mpf(0), mp.mpf(0)
    for k in range(4):
        A, B = V[k], V[(k + 1) % 4]
        D = [B[i] - A[i] for i in range(3)]
        L = mp.sqrt(dot(D, D))
        u = [v / L for v in D]
        tA = dot(A, u)
        hs = dot(cross(A, u), n)
        h = abs(hs)
        if h == 0:
            continue
        m2 = h * h + d * d
        m = mp.sqrt(m2)
        rho = (d / (m + h)) ** 2
        tri = -h * L
        H = h + mp.sqrt(dot(A, A)) + L
        mag += H * L
        for t, sgn in ((tA + L, 1), (tA, -1)):
            p = (t * mp.log(t * t + m2) if t != 0 else 0) - 2 * t + 2 * m * mp.atan2(t, m)
            tri += sgn * h * p
            mag += H * (abs(p) + 4 * abs(t) + 4 * m)
            if d != 0:
                phi = mp.atan2(t, h)
                K = (-phi * mp.log(rho) - mp.im(mp.polylog(2, -rho * mp.expj(2 * phi)))
                     + mp.clsin(2, mp.pi + 2 * phi))
                tri += sgn * d * d * K
                mag += d * d * (abs(phi * mp.log(rho)) + 4)
        S += mp.sign(hs) * tri
    return -S / (4 * cn), mag / (4 * cn)


#: Counters of the closed form's fallbacks, since import (a caller may reset them):
#: ``pairs`` (receivers evaluated by :func:`unoccluded_pairs`), ``far_rule`` (taken by the
#: far-field rule instead, its estimate the smaller), ``contour_rule`` (by the tanh-sinh
#: contour rule, its estimate the smaller), ``escalated_pairs`` and
#: ``escalated_edge_pairs`` (re-evaluated in mpmath, and how many of their edge pairs).
CLOSED_FORM_COUNTS = {"pairs": 0, "far_rule": 0, "contour_rule": 0, "escalated_pairs": 0,
                      "escalated_edge_pairs": 0}


def _rings(polys):
    """Concatenated vertices (V, 3), offsets, and each vertex's successor's index."""
    V = np.concatenate(polys)
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in polys])])
    return V, offsets, successors(offsets)


def front_parts(P, nP, Qs, nQs, dP, dQ):
    """Each pair's parts in front of the other's plane (one-sided: rays leave P's front
    and reach Q's front), decided from signed distances the caller computed for all
    pairs at once: a polygon whose distances are all >= 0 and one > 0 is whole, one with
    none > 0 has nothing in front, and only one with distances of both signs is clipped
    (:func:`clip_front`, with the same distances: one decision, however they round).

    Parameters
    ----------
    P : ndarray of shape (K, 3)
        The emitter.
    nP : ndarray of shape (3,)
        Its unit normal.
    Qs : sequence of ndarray of shape (K_j, 3)
        The receivers.
    nQs : ndarray of shape (len(Qs), 3)
        Their unit normals.
    dP : ndarray of shape (len(Qs), K)
        ``(P - Q_j[0]) @ nQs[j]``.
    dQ : ndarray of shape (len(Qs), K')
        ``(Q_j - P[0]) @ nP`` in row j's first K_j entries, padded by repeats (as
        :func:`exactff.rings.padded`).

    Returns
    -------
    (list, list)
        The clipped P and Q of each pair (the polygon itself where it is whole, None
        where nothing is left).

    Examples
    --------
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = np.array([[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]], float)   # x = 0
    >>> nP, nQ = np.array([0, 0, 1.0]), np.array([[1.0, 0, 0]])
    >>> Pcs, Qcs = front_parts(P, nP, [Q], nQ, ((P - Q[0]) @ nQ.T).T, ((Q - P[0]) @ nP)[None])
    >>> Pcs[0] is P, Qcs[0] is Q            # touching along an edge: both whole
    (True, True)
    """
    none = (dP.max(axis=1) <= 0) | (dQ.max(axis=1) <= 0)
    whole_P, whole_Q = dP.min(axis=1) >= 0, dQ.min(axis=1) >= 0
    Pcs = [None if none[j] else P if whole_P[j] else clip_front(P, nQs[j], Q[0], dP[j])
           for j, Q in enumerate(Qs)]
    Qcs = [None if none[j] else Q if whole_Q[j] else clip_front(Q, nP, P[0], dQ[j, :len(Q)])
           for j, Q in enumerate(Qs)]
    return Pcs, Qcs


def _front_parts(P, nP, Qs, nQs):
    """:func:`front_parts` of one emitter and its receivers, the distances computed
    here."""
    V, _ = padded(Qs)
    dQ = (V - P[0]) @ nP
    dP = np.einsum("mkj,mj->mk", P[None] - V[:, :1], nQs)
    return front_parts(P, nP, Qs, nQs, dP, dQ)


def _mp_vector(x):
    return [mp.mpf(float(v)) for v in x]


def _mp_escalate(c, ef, J, edges, L, area_s, target):
    """One receiver's value and estimate with its costliest edge pairs re-evaluated in
    mpmath: the fewest (by decreasing rounding estimate ``c``) that bring the rest within
    half the ``target``. The rest are summed in floats; the re-evaluated ones in mpmath,
    from the float vertices (``edges``: for each pair, the vertices a, a', b, b' of its
    edges ``a -> a'`` and ``b -> b'``, unscaled), with ln L taken out as in the floats,
    at ``AREA_CLOSED_MP_DPS`` digits, doubled (up to ``MP_MAX_DPS``) while their rounding
    (``AREA_CLOSED_MP_ULPS`` units of the precision of the closed form's terms) misses
    the other half."""
    order = np.argsort(-c)
    rest = np.concatenate([np.cumsum(c[order][::-1])[::-1][1:], [0.0]])
    n_esc = int(np.argmax(rest <= 0.5 * target)) + 1
    esc, kept = order[:n_esc], order[n_esc:]
    float_part = float(np.dot(ef[kept], J[kept]))
    dps = tol.AREA_CLOSED_MP_DPS
    while True:
        with mp.workdps(dps):
            lnL, L2 = mp.log(mp.mpf(L)), mp.mpf(L) ** 2
            acc, mag = mp.mpf(0), mp.mpf(0)
            for k in esc:
                a, a1, b, b1 = (_mp_vector(x) for x in edges[k])
                e = [a1[i] - a[i] for i in range(3)]
                f = [b1[i] - b[i] for i in range(3)]
                efk = (e[0] * f[0] + e[1] * f[1] + e[2] * f[2]) / L2
                Jk, Mk = _mp_edge_log_integral(a, e, b, f)
                acc += efk * (Jk - lnL)
                mag += abs(efk) * (Mk + abs(lnL))
            denom = 2 * mp.pi * mp.mpf(area_s)
            value = float((acc + mp.mpf(float_part)) / denom)
            mp_err = float(tol.AREA_CLOSED_MP_ULPS * mag * mp.mpf(2) ** -mp.mp.prec / denom)
        if mp_err <= 0.5 * target or 2 * dps > tol.MP_MAX_DPS:
            break
        dps *= 2
    # the float part's rounding, the conversion to a float and the mpmath rounding
    est = float(c[kept].sum()) + tol.EPS * abs(value) + mp_err
    return value, est, n_esc


def unoccluded_pairs(P, Qs, far=True, rtol=None, atol=0.0, parts=None):
    """F(P -> Q) unoccluded for one emitter and many receivers, in closed form, with
    error estimates: the batch form of :func:`unoccluded_pair`.

    Each polygon is clipped here to the front of the other's plane (one-sided, as
    :func:`unoccluded_pair`); pass them whole. The edge pairs of all receivers are
    evaluated together (:func:`_edge_log_integrals`, the closed form of the
    Mitalas-Stephenson contour integral). A receiver whose estimate misses
    ``rtol * max(F, AREA_CLOSED_FLOOR)`` is taken, with ``far=True`` and when it is far
    (:func:`is_far`), by the far-field rule if that estimate is the smaller, then (with
    ``atol``) by the tanh-sinh contour rule (``_contour_tanh_sinh``) if that one's is; a
    receiver still
    missing it has its costliest edge pairs re-evaluated in mpmath
    (``AREA_CLOSED_MP_DPS`` digits). :data:`CLOSED_FORM_COUNTS` counts each.

    Parameters
    ----------
    P : ndarray of shape (K, 3)
        The emitter, validated (:func:`~exactff.scene.validate_polygon`), as floats.
    Qs : sequence of ndarray of shape (K_j, 3)
        The receivers, each validated; not clipped.
    far : bool, default True
        Allow the far-field rule for far receivers that miss the target.
    rtol : float, optional
        The relative target of the estimates (default ``AREA_CLOSED_RTOL``).
    atol : float, default 0
        Also accepted: an estimate up to this (absolute); the target is then
        ``max(atol, rtol * max(F, AREA_CLOSED_FLOOR))`` (the area rows pass their
        tolerance: a value within it needs no fallback).
    parts : sequence of (ndarray or None, ndarray or None), optional
        Each pair's parts in front of the other's plane, ``(Pc, Qc)``, where the caller
        has them (:func:`clip_front`; ``Pc`` the emitter itself where it is whole): not
        decided again here.

    Returns
    -------
    (ndarray of shape (len(Qs),), ndarray of shape (len(Qs),))
        The values (0 for a receiver with nothing in front of the other) and their error
        estimates; never NaN, never below 0 (a value below 0 within its estimate is 0;
        beyond it, :class:`~exactff.NumericalError`).

    Examples
    --------
    Unit squares facing a unit square 1 and 2 apart (Howell's C-11: 0.19982489570 and
    0.06858958882), and one turned away:

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = P[::-1] + [0, 0, 1]
    >>> F, E = unoccluded_pairs(P, [Q, Q + [0, 0, 1], Q[::-1]])
    >>> F.round(12).tolist(), bool(np.all(E < 1e-14))
    ([0.199824895698, 0.068589588819, 0.0], True)
    """
    rtol = tol.AREA_CLOSED_RTOL if rtol is None else float(rtol)
    m = len(Qs)
    values, est = np.zeros(m), np.zeros(m)
    if m == 0:
        return values, est
    CLOSED_FORM_COUNTS["pairs"] += m
    AP = area_vector(P)
    area_P = float(np.linalg.norm(AP))
    nP = AP / area_P
    if parts is None:
        # the receivers' area vectors, (1/2) sum v_k x v_{k+1} about each first vertex
        V, offsets, nxt = _rings(Qs)
        V0 = np.repeat(V[offsets[:-1]], np.diff(offsets), axis=0)
        nQs = 0.5 * np.add.reduceat(cross(V - V0, V[nxt] - V0), offsets[:-1], axis=0)
        nQs /= np.linalg.norm(nQs, axis=1)[:, None]
        Pcs, Qcs = _front_parts(P, nP, Qs, nQs)
    else:
        Pcs, Qcs = [Pc for Pc, _ in parts], [Qc for _, Qc in parts]
    live = [j for j in range(m) if Pcs[j] is not None and Qcs[j] is not None]
    if not live:
        return values, est
    # each pair scaled by a power of 2 near its centroids' distance: ln r near 0
    cP = P.mean(axis=0)
    VQall, qo_all, _ = _rings([Qs[j] for j in live])
    centroids = np.add.reduceat(VQall, qo_all[:-1], axis=0) / np.diff(qo_all)[:, None]
    r0 = np.linalg.norm(centroids - cP, axis=1)
    L = 2.0 ** np.round(np.log2(np.where(r0 > 0, r0, 1.0)))
    Pl, Ql = [Pcs[j] for j in live], [Qcs[j] for j in live]
    VP, po, nextP = _rings(Pl)
    VQ, qo, nextQ = _rings(Ql)
    # every edge pair of each receiver: owner, P's edge ip, Q's edge iq
    kP, kQ = np.diff(po), np.diff(qo)
    counts = kP * kQ
    owner = np.repeat(np.arange(len(live)), counts)
    r = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    ip = po[:-1][owner] + r // kQ[owner]
    iq = qo[:-1][owner] + r % kQ[owner]
    inv = (1.0 / L)[owner][:, None]
    e, f = (VP[nextP] - VP)[ip] * inv, (VQ[nextQ] - VQ)[iq] * inv
    ef = np.einsum("ij,ij->i", e, f)
    keep = ef != 0                          # perpendicular edges: no term
    owner, ip, iq, e, f, ef = owner[keep], ip[keep], iq[keep], e[keep], f[keep], ef[keep]
    w = (VP[ip] - VQ[iq]) * inv[keep]
    J, M = _edge_log_integrals(w, e, np.zeros_like(w), f)
    # A_P F = (1 / 2 pi) sum (e . f) J, in the scaled units; its rounding
    area_s = area_P / L ** 2
    scale = (2.0 * np.pi * area_s)[owner]
    c = tol.AREA_CLOSED_ULPS * tol.EPS * np.abs(ef) * M / scale
    v = np.bincount(owner, ef * J / scale, minlength=len(live))
    ev = np.bincount(owner, c, minlength=len(live))
    live = np.array(live)
    values[live], est[live] = v, ev
    target = np.maximum(float(atol), rtol * np.maximum(np.abs(values), tol.AREA_CLOSED_FLOOR))
    miss = [k for k in range(len(live)) if est[live[k]] > target[live[k]]]
    if far and miss:
        far_j = [live[k] for k in miss if is_far(P, Qs[live[k]])]
        # P whole: one set of emitter nodes for all; P clipped: its own
        groups = [[j for j in far_j if Pcs[j] is P]] + [[j] for j in far_j if Pcs[j] is not P]
        for js in groups:
            if not js:
                continue
            fv, fe = far_values(emitter_nodes(Pcs[js[0]], nP), nP, area_P, [Qcs[j] for j in js])
            better = fe < est[js]
            values[np.array(js)[better]] = fv[better]
            est[np.array(js)[better]] = fe[better]
            CLOSED_FORM_COUNTS["far_rule"] += int(better.sum())
        miss = [k for k in miss if est[live[k]] > target[live[k]]]
    # with an absolute target (area rows), the tanh-sinh contour rule next (about a
    # millisecond a pair; edges parallel only to rounding, thin or far polygons, where
    # the closed form's terms cancel); polygon_form_factor's relative target goes to
    # mpmath
    for k in (list(miss) if atol > 0 else []):
        j = live[k]
        fv, fe = _contour_tanh_sinh(P, Qs[j])
        if fe < est[j]:
            values[j], est[j] = fv, fe
            CLOSED_FORM_COUNTS["contour_rule"] += 1
    miss = [k for k in miss if est[live[k]] > target[live[k]]]
    for k in miss:
        j = live[k]
        sel = np.flatnonzero(owner == k)
        edges = np.stack([VP[ip[sel]], VP[nextP[ip[sel]]], VQ[iq[sel]], VQ[nextQ[iq[sel]]]],
                         axis=1)
        values[j], est[j], n_esc = _mp_escalate(c[sel], ef[sel], J[sel], edges, L[k],
                                                area_s[k], target[j])
        CLOSED_FORM_COUNTS["escalated_pairs"] += 1
        CLOSED_FORM_COUNTS["escalated_edge_pairs"] += n_esc
    # the emitter's area (a Newell sum) and the last division round the value by a few
    # units more, on every path
    est += tol.AREA_CLOSED_ULPS * tol.EPS * np.abs(values)
    check_finite(values, est, "area form factor")
    return nonnegative(values, est), est


def unoccluded_pair(P, Q, far=True, atol=0.0):
    """F(P -> Q) of two validated polygons, unoccluded, and an estimate of its error
    (:func:`unoccluded_pairs` for one receiver): the closed form of the contour integral
    with the rounding of its terms (``AREA_CLOSED_ULPS`` units), the far-field rule
    (:func:`is_far`; only with ``far=True``) or mpmath where that misses
    ``AREA_CLOSED_RTOL`` (and ``atol``, when given). A value below 0 within its
    estimate is 0; beyond it, NumericalError."""
    f, e = unoccluded_pairs(P, [Q], far=far, atol=atol)
    return float(f[0]), float(e[0])


def _contour_tanh_sinh(P, Q):
    """The tanh-sinh contour rule (the production path before the closed form; kept as a
    test oracle): F(P -> Q) of two validated polygons, unoccluded, and its estimate, the
    rounding of the contour sum (64 units of its absolute terms) plus the difference from
    the tanh-sinh rule one level coarser."""
    AP, AQ = area_vector(P), area_vector(Q)
    area_P = float(np.linalg.norm(AP))
    nP, nQ = AP / area_P, AQ / np.linalg.norm(AQ)
    cP, cQ = P.mean(axis=0), Q.mean(axis=0)
    # one-sided: each polygon's part in front of the other's plane
    Pc = clip_front(P, nQ, Q[0])
    Qc = clip_front(Q, nP, P[0])
    if Pc is None or Qc is None:
        return 0.0, 0.0
    r0 = float(np.linalg.norm(cQ - cP)) or 1.0
    eP = np.roll(Pc, -1, axis=0) - Pc          # (KP, 3)
    eQ = np.roll(Qc, -1, axis=0) - Qc          # (KQ, 3)
    d, upper, w, w_coarse = _NODES
    # each edge of P in pieces, cut where the inner integral loses smoothness (where
    # the edge passes through or near an edge or a vertex of Q); outer nodes along each
    # piece from its nearer end (no cancellation there)
    owner, s0, s1 = _edge_pieces(Pc, eP, Qc, eQ)
    A, B = Pc[owner] + s0[:, None] * eP[owner], Pc[owner] + s1[:, None] * eP[owner]
    start = np.where(upper[None, :, None], B[:, None, :], A[:, None, :])
    step = np.where(upper[None, :, None], (A - B)[:, None, :], (B - A)[:, None, :])
    X = start + d[None, :, None] * step                              # (pieces, N, 3)
    Wv = Qc[None, None, :, :] - X[:, :, None, :]                     # (pieces, N, KQ, 3)
    G = _segment_log_integral(Wv, np.broadcast_to(eQ, Wv.shape)) - np.log(r0)
    G *= (s1 - s0)[:, None, None]
    first = np.searchsorted(owner, np.arange(len(Pc)))
    inner = np.add.reduceat(np.einsum("n,pnq->pq", w, G), first, axis=0)  # (KP, KQ)
    coarse = np.add.reduceat(np.einsum("n,pnq->pq", w_coarse, G), first, axis=0)
    terms = (eP @ eQ.T) * inner
    total = float(terms.sum()) / (2.0 * np.pi) / area_P
    scale = (float(np.abs(terms).sum()) + float(np.abs(w[None, :, None] * G).sum())
             * float(np.abs(eP @ eQ.T).max())) / (2.0 * np.pi) / area_P
    # the outer rule's error: at most its difference from the rule one level coarser
    # (tanh-sinh roughly squares its error from one level to the next)
    step = abs(float(((eP @ eQ.T) * (inner - coarse)).sum())) / (2.0 * np.pi) / area_P
    est = tol.AREA_ROUNDING_ULPS * tol.EPS * scale + step
    return nonnegative(total, est), est


# ---------------------------------------------------------------------------------------
# with occlusion: the outer integral of exact occluded point rows, split at visibility
# events, adaptive, with an error estimate
# ---------------------------------------------------------------------------------------
