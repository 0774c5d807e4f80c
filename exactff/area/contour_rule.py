"""The tanh-sinh contour rule: Eq. 1's double contour integral with the inner integral
in closed form (``_segment_log_integral``) and the outer one by the tanh-sinh rule
along each edge of the emitter, cut where the inner integral loses smoothness. Slower
than the closed form of both integrals (:mod:`exactff.area.closed_form`) but free of its
cancellation for edges parallel only to rounding, thin or far polygons: the closed form
takes it where its own estimate misses an absolute tolerance, and the tests use it as an
independent oracle.
"""

import numpy as np
from scipy.special import xlogy

from .. import _tolerances as tol
from ..errors import nonnegative
from ..geometry import area_vector, cross
from ..halfspace import clip_front

__all__ = ["contour_tanh_sinh"]


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
        # u ln(u^2 + k^2) as 2 u ln hypot(u, k): u^2 + k^2 underflows to 0 where u and k
        # are 1e-160 (faces tilted by 1e-150), and u ln 0 is -inf
        return 2.0 * xlogy(u, np.hypot(u, k)) - 2.0 * u + 2.0 * at

    return 0.5 * np.log(a) + 0.5 * (prim(u1) - prim(u0))



def contour_tanh_sinh(P, Q, parts=None):
    """F(P -> Q) of two validated polygons, unoccluded, by the tanh-sinh contour rule, and
    its estimate: the rounding of the contour sum (``AREA_ROUNDING_ULPS`` units of its
    absolute terms) plus the difference from the tanh-sinh rule one level coarser.

    ``parts``, optional: the pair's parts in front of each other's planes, ``(Pc, Qc)``,
    as the caller decided them (:func:`~exactff.area.closed_form.front_parts`, with the
    near-coplanar band); None: each polygon clipped here to the front of the other's
    plane, by the distances' signs alone (a vertex that rounding put 1e-18 behind a
    plane it lies in is cut off, leaving a copy of itself 1e-16 away).

    Examples
    --------
    Two parallel unit squares one apart (Howell's C-11: 0.19982489570):

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> f, e = contour_tanh_sinh(P, P[::-1] + [0, 0, 1])
    >>> abs(f - 0.19982489569838739) <= e < 1e-12
    True
    """
    AP, AQ = area_vector(P), area_vector(Q)
    area_P = float(np.linalg.norm(AP))
    nP, nQ = AP / area_P, AQ / np.linalg.norm(AQ)
    cP, cQ = P.mean(axis=0), Q.mean(axis=0)
    # one-sided: each polygon's part in front of the other's plane
    Pc, Qc = (clip_front(P, nQ, Q[0]), clip_front(Q, nP, P[0])) if parts is None else parts
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
