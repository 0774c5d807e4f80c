"""Area-to-area form factors (the paper's Eq. 1), unoccluded: the contour integral and
the far-field rule.

For two planar polygons P and Q, Stokes' theorem turns the double area integral of
Eq. 1 into a double contour integral (Mitalas & Stephenson 1966; Sparrow 1963):

    A_P F(P -> Q) = (1 / 2 pi) sum_i sum_j (e_i . e_j) int_0^1 int_0^1 ln |p_i(s) - q_j(t)| dt ds

over the edges ``p_i(s) = a_i + s e_i`` of P and ``q_j(t) = b_j + t e_j`` of Q, each
counter-clockwise seen from its front. The inner integral is in closed form (``_segment_log_integral``); the outer one is a tanh-sinh
(double-exponential) quadrature, which keeps full accuracy when the integrand has
logarithmic singularities at the ends of an edge (polygons sharing an edge or a
vertex). ``ln r`` is measured against the distance between the centroids (the shift
contributes ``(sum e_i) . (sum e_j) = 0``), which keeps the terms small when the
polygons are far apart.

The contour terms cancel as (distance / size)^2 when the polygons are far apart: beyond
``FAR`` diameters the double integral is taken instead as the area integral over P of
the exact point form factors (smooth there), by a Gauss-Legendre rule on P's triangles.

One-sided, as the point form factors: only the part of Q in front of P's plane and
the part of P in front of Q's plane take part.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
import shapely
from scipy.special import roots_legendre, xlogy

from .. import _tolerances as tol
from ..errors import NumericalError, check_finite
from ..geometry import area_vector, polygon_diameter, receiver_frame
from ..halfspace import clip_halfspace
from ..kernel import clipped_sector_sums
from ..rings import owners, successors
from ..scene import validate_polygon

__all__ = ["polygon_form_factor", "clip_front", "triangle_rule", "point_values",
           "emitter_nodes", "far_values", "unoccluded_pair", "nonnegative", "is_far"]


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


def clip_front(P, n, c):
    """The part of polygon P with ``n . (x - c) > 0`` (None when nothing is left): the
    engine's half-space clipping, about the point c."""
    d = (P - c) @ n
    if np.all(d >= 0) and np.any(d > 0):
        return P
    if np.all(d <= 0) and np.any(d < 0):
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
    k = np.linalg.norm(np.cross(W, E), axis=-1) / a
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
    """Nodes and weights of the collapsed (Duffy) Gauss-Legendre rule on a triangle:
    ``n^2`` nodes, exact for polynomials of degree ``2n - 2`` in the triangle.

    Parameters
    ----------
    tri : ndarray of shape (3, 3)
    rule : (ndarray, ndarray)
        Gauss-Legendre nodes and weights on [-1, 1] (``scipy.special.roots_legendre``).

    Returns
    -------
    (ndarray of shape (n^2, 3), ndarray of shape (n^2,))
    """
    a, b, c = tri
    x, w = rule
    x, w = 0.5 * (x + 1.0), 0.5 * w
    U, V = np.meshgrid(x, x, indexing="ij")
    WW = np.outer(w, w) * U                  # the collapse's Jacobian u
    J = np.linalg.norm(np.cross(b - a, c - a))
    X = a + U[..., None] * (b - a) + (U * V)[..., None] * (c - b)
    return X.reshape(-1, 3), (WW * J).ravel()


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
    S, mags, errs = clipped_sector_sums(A0, E, nxt, owner, m * nX)
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


def polygon_form_factor(P: ArrayLike, Q: ArrayLike) -> float:
    """The area-to-area form factor F(P -> Q), unoccluded, exact to rounding.

    The paper's Eq. 1: ``(1 / A_P) int_P int_Q cos(theta_P) cos(theta_Q) / (pi r^2)
    dA_Q dA_P``, one-sided (only the parts of each polygon in front of the other's
    plane), by the contour integral of Mitalas and Stephenson with the inner integral
    in closed form and a tanh-sinh outer quadrature (see the module's notes).

    Parameters
    ----------
    P, Q : array_like of shape (K, 3)
        Planar polygons, counter-clockwise seen from their fronts.

    Returns
    -------
    float

    Raises
    ------
    SceneError
        A polygon is ill-formed (as for scenes; P is polygon 0, Q polygon 1).
    NumericalError
        The value or its estimate came out NaN or infinite (never returned).

    Examples
    --------
    Two parallel unit squares one apart, facing each other (Howell's catalogue,
    C-11: 0.19982489570):

    >>> P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> Q = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]
    >>> round(polygon_form_factor(P, Q), 12)
    0.199824895698
    """
    P = np.array(validate_polygon(P, 0), dtype=float)
    Q = np.array(validate_polygon(Q, 1), dtype=float)
    return check_finite(*unoccluded_pair(P, Q))[0]


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
    c = np.cross(eP[:, None, :], eQ[None, :, :])                          # (KP, KQ, 3)
    cc = np.einsum("pqj,pqj->pq", c, c)
    crossing = np.einsum("pqj,pqj->pq", np.cross(Q[None] - P[:, None], eQ[None]), c)
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


def unoccluded_pair(P, Q, far=True):
    """F(P -> Q) of two validated polygons, unoccluded, and an estimate of its error:
    the rounding of the contour sum (64 units of its absolute terms) plus the
    difference from the tanh-sinh rule one level coarser, or, for far pairs (:func:`is_far`;
    only with ``far=True``), the difference between the 12- and 8-point area rules plus
    rounding. A value below 0 within its estimate is 0; beyond it, NumericalError."""
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
    if far and is_far(P, Q):
        f, e = far_values(emitter_nodes(Pc, nP), nP, area_P, [Qc])
        return float(f[0]), float(e[0])
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
