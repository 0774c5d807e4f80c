"""Unoccluded point form factors from many points of an emitter's plane to many
polygons, vectorised (the integrand of the area rules: the far field, the hidden part's
bound and the check of the adaptive rules' differences).
"""

import math

import numpy as np

from .. import _tolerances as tol
from ..geometry import area_vector, receiver_frame
from ..kernel._sector import row_sums

__all__ = ["point_values", "unoccluded_bound", "unoccluded_bounds", "unevaluated"]


def point_values(X, nP, Qs):
    """Unoccluded point form factors from the points X (normal nP) to each polygon of
    Qs (in front of them), in offset form, vectorised over points and polygons.

    Parameters
    ----------
    X : ndarray of shape (m, 3)
        The points.
    nP : ndarray of shape (3,)
        Their unit normal.
    Qs : sequence of ndarray of shape (K_j, 3)
        The polygons, each wholly in front of every point.

    Returns
    -------
    (ndarray of shape (len(Qs), m), ndarray of shape (len(Qs), m))
        The values and their rounding error estimates (the sector sums' error model).

    Examples
    --------
    A unit square one above the point under its corner (Howell's B-3 at a = b = c = 1:
    ``atan(1 / sqrt 2) / (pi sqrt 2)`` = 0.138531605994893):

    >>> Q = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]], float)
    >>> F, E = point_values(np.zeros((1, 3)), np.array([0, 0, 1.0]), [Q])
    >>> bool(abs(F[0, 0] - 0.138531605994893) <= E[0, 0] + 1e-15 < 1e-14)
    True
    """
    R = receiver_frame(nP)
    nX, m = len(X), len(Qs)
    # polygon (j, p): receiver j seen from point p, numbered j * nX + p, its sector sum
    # in offset form (compiled, _core/sector_sums.h: kernel/sector.py's
    # clipped_sector_sums with the offsets' rounding, the same arithmetic)
    V = np.concatenate([np.asarray(Q, dtype=float) for Q in Qs])
    offsets = np.concatenate([[0], np.cumsum([len(Q) for Q in Qs])]).astype(np.int64)
    ids = np.repeat(np.arange(m, dtype=np.int64), nX)
    rows = np.tile(np.arange(nX, dtype=np.int64), m)
    frames = np.broadcast_to(R, (nX, 3, 3))
    S, mags, errs, _ = row_sums(V=V, offsets=offsets, ids=ids, rows=rows,
                                P=np.asarray(X, dtype=float), frames=frames, eps=tol.EPS,
                                ulps=tol.OFFSET_ROUNDING_ULPS, c2eps=tol.C2 * tol.EPS)
    # the sector sums' own error model (C1 is calibrated for the unit roundoff 2**-53)
    return (np.abs(S).reshape(m, nX) / (2.0 * np.pi),
            ((tol.C1 * tol.EPS * mags + errs) / (2.0 * np.pi)).reshape(m, nX))


def unoccluded_bound(Pc, Qc, area=None):
    """An upper bound on the point form factor F(x -> Qc) at every point x of Pc: 1, and
    ``A_Q c_P c_Q / (pi d^2)`` with d the distance between the two polygons' bounding
    boxes and c_P, c_Q bounds on the two cosines (the kernel ``cos cos / (pi r^2)``
    with ``r >= d``); with ``area``, the same for a part of Qc of that area.

    Each cosine is ``|n . (y - x)| / r`` for n the unit normal of its polygon (either
    side), so at most ``h / d`` (and 1), h the largest of ``|n . (y - x)|`` over the
    two polygons' vertices (a linear function: its extremes over a polygon are at
    vertices; the products' rounding added, ``AREA_BOUND_SPREAD_ULPS``), and
    ``AREA_BOUND_COS_SLACK`` more for a
    normal that the kernel takes from the whole polygon. Two parallel polygons far apart
    sideways (View3D's gunter2: a floor and a ceiling strip 7 above it and 12.5 aside,
    cosines at most 0.49) get 0.24 of ``A_Q / (pi d^2)``.

    Examples
    --------
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> round(unoccluded_bound(P, P[::-1] + [0, 0, 2]), 6)        # 1 / (4 pi)
    0.079577
    >>> round(unoccluded_bound(P, P[::-1] + [3, 0, 1]), 4)        # 1 / (25 pi), d^2 = 5
    0.0127
    """
    gap = np.maximum(0.0, np.maximum(Pc.min(axis=0) - Qc.max(axis=0),
                                     Qc.min(axis=0) - Pc.max(axis=0)))
    d2 = float(gap @ gap)
    aQ = area_vector(Qc)
    norm_Q = float(np.linalg.norm(aQ))
    area_Q = norm_Q if area is None else float(area)
    if not d2 > 0:
        return 1.0
    c_P, c_Q = (float(_cosine(s, math.sqrt(d2))) for s in _spreads(Pc, Qc, aQ))
    return min(1.0, area_Q * c_P * c_Q / (np.pi * d2))


def _spreads(Pc, Qc, aQ):
    """The cosines' spreads: for each polygon's unit normal n, the largest of
    ``|n . (y - x)|`` over the two polygons' vertices, its products' rounding added
    (:func:`unoccluded_bound`; products summed in one order, as occluded_pair.cpp's
    mirror sums them)."""
    scale = float(max(np.abs(Pc).sum(axis=1).max(), np.abs(Qc).sum(axis=1).max()))
    out = []
    for a, X, Y in ((area_vector(Pc), Pc, Qc), (aQ, Qc, Pc)):
        n = a / float(np.linalg.norm(a))
        sX = (X[:, 0] * n[0] + X[:, 1] * n[1]) + X[:, 2] * n[2]
        sY = (Y[:, 0] * n[0] + Y[:, 1] * n[1]) + Y[:, 2] * n[2]
        h = max(float(sY.max() - sX.min()), float(sX.max() - sY.min()))
        out.append(h + tol.AREA_BOUND_SPREAD_ULPS * tol.EPS * scale)
    return out


def _cosine(spread, d):
    """A cosine's bound at distances ``d`` (> 0): ``spread / d`` and
    ``AREA_BOUND_COS_SLACK`` more, at most 1."""
    return np.minimum(1.0, spread / d + tol.AREA_BOUND_COS_SLACK)


def unoccluded_bounds(T, Pc, Qc):
    """:func:`unoccluded_bound` for each triangle of T (t, 3, 3), parts of Pc: with d the
    distance from each triangle's bounding box to Qc's (at least Pc's), the cosines'
    spreads those of Pc and Qc; shape (t,), each at most Pc's bound.

    Examples
    --------
    A unit square and a 0.1 square 2 above its corner (1, 1): a triangle whose box
    reaches that corner takes the square's bound; one of the corner (0, 0) whose box
    ends at (0.5, 0.5) is sqrt(4.5) from it, its cosines' bounds 2 / sqrt(4.5) each
    (the spreads are 2), its bound (4 / 4.5)^2 of the square's:

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = 0.1 * P[::-1] + [1, 1, 2]
    >>> b = unoccluded_bounds(np.array([P[[0, 1, 2]], 0.5 * P[[0, 1, 3]]]), P, Q)
    >>> bool(b[0] == unoccluded_bound(P, Q)), round(float(b[1] / b[0]), 3)
    (True, 0.79)
    """
    whole = unoccluded_bound(Pc, Qc)
    gap = np.maximum(0.0, np.maximum(T.min(axis=1) - Qc.max(axis=0), Qc.min(axis=0) - T.max(axis=1)))
    # the squares summed in one order (occluded_pair.cpp's unoccluded_bounds)
    d2 = (gap[:, 0] * gap[:, 0] + gap[:, 1] * gap[:, 1]) + gap[:, 2] * gap[:, 2]
    out = np.full(len(T), whole)
    far = d2 > 0
    if far.any():
        aQ = area_vector(Qc)
        spreads, d = _spreads(Pc, Qc, aQ), np.sqrt(d2[far])
        out[far] = np.minimum(whole, float(np.linalg.norm(aQ)) * _cosine(spreads[0], d)
                              * _cosine(spreads[1], d) / (np.pi * d2[far]))
    return out


def unevaluated(area, bound, area_P, atol, st=None):
    """Which of a pair's triangles go unevaluated, their area, and their bounds times
    their areas summed: the least ``bound * area`` first (ties in the given order), while
    half that sum, per unit area of P, stays within ``AREA_UNEVALUATED_SHARE`` of
    ``atol``; the last in that order is always evaluated, and none is left out unless
    ``AREA_UNEVALUATED_LEAST`` of them (a fifth) are. ``area`` (t,) the triangles'
    areas, ``bound`` (t,) a bound on the unoccluded point values over each
    (:func:`unoccluded_bounds`). The hidden part of each is between 0
    and its bound, so that its integral over them is half that sum, within as much.
    ``st`` (an :class:`~exactff.area.row.AreaStats`) counts them in
    ``unevaluated_triangles``.

    Examples
    --------
    Four triangles under bounds of 1e-5 (the last 2e-5) and a target of 1e-6: the two
    least take 0.5 * 1e-5 * (10 + 20) / 1000 = 1.5e-7 (at most a quarter of the
    target); with the third, 4e-7 in all:

    >>> skip, area, weight = unevaluated(np.array([50.0, 10.0, 20.0, 30.0]),
    ...                                  np.array([1e-5, 1e-5, 1e-5, 2e-5]), 1000.0, 1e-6)
    >>> skip.tolist(), area, round(weight, 12)
    ([False, True, True, False], 30.0, 0.0003)
    """
    weight = bound * area
    order = np.argsort(weight, kind="stable")[:-1]
    # their running sums, in order (numpy's cumsum, as _core/occluded_pair.cpp adds)
    running, running_area = np.cumsum(weight[order]), np.cumsum(area[order])
    k = int(np.count_nonzero(0.5 * running / area_P <= tol.AREA_UNEVALUATED_SHARE * atol))
    if k < tol.AREA_UNEVALUATED_LEAST * len(area):
        k = 0
    out = np.zeros(len(area), dtype=bool)
    out[order[:k]] = True
    if st is not None:
        st.unevaluated_triangles += k
    if not k:
        return out, 0.0, 0.0
    return out, float(running_area[k - 1]), float(running[k - 1])
