"""The far-field rule: the area integral over the emitter of the exact unoccluded point
form factors (smooth when the receiver is far) by a pair of collapsed Gauss-Legendre
rules on the emitter's triangles, their difference the estimate. Taken where the closed
form's terms cancel (:mod:`exactff.area.closed_form`).
"""

import numpy as np

from .. import _tolerances as tol
from ..errors import nonnegative
from ..geometry import polygon_diameter
from .points import point_values
from .rules import GAUSS_LOW_RULE, GAUSS_RULE, triangle_rule, triangulate

__all__ = ["is_far", "emitter_nodes", "far_values"]


def is_far(P, Q):
    """True when P and Q are far enough apart for the far-field rule: their centroids
    more than ``AREA_FAR`` diameters of the larger one apart.

    Examples
    --------
    >>> sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> is_far(sq, sq + [0, 0, 2]), is_far(sq, sq + [0, 0, 100])
    (False, True)
    """
    r0 = float(np.linalg.norm(Q.mean(axis=0) - P.mean(axis=0)))
    return r0 > tol.AREA_FAR * max(polygon_diameter(P), polygon_diameter(Q))


def emitter_nodes(Pc, nP):
    """The 12- and 8-point collapsed Gauss-Legendre rules on P's triangles, as one set
    of nodes and the two weight vectors (each zero on the other rule's nodes)."""
    tris = triangulate(Pc, nP)
    hi = [triangle_rule(t, GAUSS_RULE) for t in tris]
    lo = [triangle_rule(t, GAUSS_LOW_RULE) for t in tris]
    X = np.concatenate([x for x, _ in hi] + [x for x, _ in lo])
    n_hi = sum(len(w) for _, w in hi)
    W_hi, W_lo = np.zeros(len(X)), np.zeros(len(X))
    W_hi[:n_hi] = np.concatenate([w for _, w in hi])
    W_lo[n_hi:] = np.concatenate([w for _, w in lo])
    return X, W_hi, W_lo


def far_values(nodes, nP, area_P, Qs):
    """F(P -> Q) for far receivers Qs (each in front of P's nodes) by the area integral
    of exact point values, and its estimate: the difference between the 12- and 8-point
    rules plus rounding.

    Parameters
    ----------
    nodes : (ndarray, ndarray, ndarray)
        :func:`emitter_nodes` of P.
    nP : ndarray of shape (3,)
        P's unit normal.
    area_P : float
        P's area (the whole emitter's, also where the nodes cover a clipped part).
    Qs : sequence of ndarray of shape (K_j, 3)
        The receivers.

    Returns
    -------
    (ndarray of shape (len(Qs),), ndarray of shape (len(Qs),))
        The values and their estimates.

    Examples
    --------
    A unit square facing one 20 above it, against Howell's C-11 (7.9445e-4, from the
    closed form :func:`exactff.polygon_form_factor`):

    >>> import exactff as ef
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q, nP = P[::-1] + [0, 0, 20], np.array([0, 0, 1.0])
    >>> F, E = far_values(emitter_nodes(P, nP), nP, 1.0, [Q])
    >>> bool(abs(F[0] - ef.polygon_form_factor(P, Q)) <= E[0] < 1e-15)
    True
    """
    X, W_hi, W_lo = nodes
    hi, lo = np.empty(len(Qs)), np.empty(len(Qs))
    per = max(1, tol.AREA_EDGE_TERMS_PER_CALL // (len(X) * max(len(Q) for Q in Qs)))
    for s in range(0, len(Qs), per):
        V = point_values(X, nP, Qs[s:s + per])[0]
        hi[s:s + per], lo[s:s + per] = V @ W_hi / area_P, V @ W_lo / area_P
    est = np.abs(hi - lo) + tol.AREA_ROUNDING_ULPS * tol.EPS * np.abs(hi)
    # a sum of non-negative point values with positive weights: below 0 only by rounding
    return nonnegative(hi, est), est
