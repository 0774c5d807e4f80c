"""Area-to-area form factors (the paper's Eq. 1), unoccluded, in closed form: one emitter
and many receivers at once, with error estimates and the fallbacks where the closed
form's terms cancel.

For two planar polygons P and Q, Stokes' theorem turns the double area integral of
Eq. 1 into a double contour integral (Mitalas & Stephenson 1966; Sparrow 1963):

    A_P F(P -> Q) = (1 / 2 pi) sum_i sum_j (e_i . e_j) int_0^1 int_0^1 ln |p_i(s) - q_j(t)| dt ds

over the edges ``p_i(s) = a_i + s e_i`` of P and ``q_j(t) = b_j + t e_j`` of Q, each
counter-clockwise seen from its front. Both integrals are in closed form
(:func:`~exactff.area.edge_integrals.edge_log_integrals`: elementary for parallel edges,
dilogarithms for skew ones), evaluated for all edge pairs of one emitter and many
receivers in one compiled call with the GIL released
(:func:`~exactff.area.edge_integrals.edge_pair_sums`; :func:`unoccluded_pairs`), each
pair scaled by a power of 2 near its centroids' distance (the scale's ``ln L`` drops out:
``(sum e_i) . (sum e_j) = 0``). The error estimate is the rounding of the terms'
magnitudes (``AREA_CLOSED_ULPS``).

The contour terms cancel as (distance / size)^2 when the polygons are far apart, and for
thin polygons: where the estimate misses its target (``AREA_CLOSED_RTOL``, or an area
row's absolute tolerance ``atol``) the double integral is taken, for pairs beyond
``AREA_FAR`` diameters, by the far-field rule (:mod:`exactff.area.far_field`), then (with
an absolute tolerance) by the tanh-sinh contour rule (:mod:`exactff.area.contour_rule`),
and where it still misses, the costliest edge pairs are evaluated again in mpmath.

One-sided, as the point form factors: only the part of Q in front of P's plane and
the part of P in front of Q's plane take part.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath as mp
import numpy as np
from numpy.typing import ArrayLike

from .. import _tolerances as tol
from ..errors import check_finite, nonnegative
from ..geometry import area_vector, cross
from ..halfspace import clip_fronts
from ..predicates import coplanar_band
from ..rings import concatenated, padded, successors
from ..scene import validate_polygon
from .contour_rule import contour_tanh_sinh
from .edge_integrals import edge_pair_sums, mp_edge_log_integral
from .far_field import emitter_nodes, far_values, is_far

__all__ = ["polygon_form_factor", "unoccluded_pair", "unoccluded_pairs", "front_parts", "front_distances",
           "ClosedFormCounts"]


@dataclass
class ClosedFormCounts:
    """What :func:`unoccluded_pairs` did, counted per call (pass one to ``counts=``;
    each call adds to the one it is given, so a caller's threads each keep their own):
    ``pairs`` (receivers evaluated), ``far_rule`` (taken by the far-field rule instead,
    its estimate the smaller), ``contour_rule`` (by the tanh-sinh contour rule, its
    estimate the smaller), ``escalated_pairs`` and ``escalated_edge_pairs`` (re-evaluated
    in mpmath, and how many of their edge pairs).

    Examples
    --------
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> counts = ClosedFormCounts()
    >>> _ = unoccluded_pairs(P, [P[::-1] + [0, 0, 1]], counts=counts)
    >>> counts
    ClosedFormCounts(pairs=1, far_rule=0, contour_rule=0, escalated_pairs=0, escalated_edge_pairs=0)
    """

    pairs: int = 0
    far_rule: int = 0
    contour_rule: int = 0
    escalated_pairs: int = 0
    escalated_edge_pairs: int = 0


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



def _rings(polys):
    """Concatenated vertices (V, 3), offsets, and each vertex's successor's index."""
    V, offsets = concatenated(polys)
    return V, offsets, successors(offsets)


def front_parts(P, nP, Qs, nQs, dP, dQ):
    """Each pair's parts in front of the other's plane (one-sided: rays leave P's front
    and reach Q's front), decided from signed distances the caller computed for all
    pairs at once: a polygon whose distances are all >= 0 and one > 0 is whole, one with
    none > 0 has nothing in front, and only one with distances of both signs is clipped
    (:func:`~exactff.halfspace.clip_fronts`, all of them together; the decision is
    taken from the distances given: one decision, however they round).

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
    # the straddling parts clipped together, P against each receiver's plane and each
    # receiver against P's (clip_fronts: one clip_halfspace call each)
    cut_P = np.flatnonzero(~none & ~whole_P)
    cut_Q = np.flatnonzero(~none & ~whole_Q)
    parts_P = dict(zip(cut_P.tolist(), clip_fronts(
        [P] * len(cut_P), nQs[cut_P], np.array([Qs[j][0] for j in cut_P]).reshape(-1, 3))))
    parts_Q = dict(zip(cut_Q.tolist(), clip_fronts(
        [Qs[j] for j in cut_Q], np.broadcast_to(nP, (len(cut_Q), 3)),
        np.broadcast_to(P[0], (len(cut_Q), 3)))))
    none, whole_P, whole_Q = none.tolist(), whole_P.tolist(), whole_Q.tolist()
    Pcs = [None if none[j] else P if whole_P[j] else parts_P[j] for j in range(len(Qs))]
    Qcs = [None if none[j] else Q if whole_Q[j] else parts_Q[j] for j, Q in enumerate(Qs)]
    return Pcs, Qcs


def front_distances(P, nP, V, N):
    """The signed distances :func:`front_parts` decides from, for all receivers at
    once, 0 within the near-coplanar band (:func:`exactff.predicates.coplanar_band`):
    a polygon within the band of the other's plane is coplanar with it (F = 0), one
    with vertices within it and the rest in front is whole, not clipped to a sliver.

    Parameters
    ----------
    P : ndarray of shape (K, 3)
        The emitter.
    nP : ndarray of shape (3,)
        Its unit normal.
    V : ndarray of shape (m, K', 3)
        The receivers, padded by repeats (:func:`exactff.rings.padded`).
    N : ndarray of shape (m, 3)
        Their unit normals.

    Returns
    -------
    (ndarray of shape (m, K), ndarray of shape (m, K'))
        ``dP[j] = (P - V[j, 0]) @ N[j]`` and ``dQ[j] = (V[j] - P[0]) @ nP``, each 0
        within the band.

    Examples
    --------
    Squares facing the unit square at z = 15 from 1e-13 above (within the band there,
    2.1e-13) and from 1e-3 above:

    >>> P = np.array([[0, 0, 15], [1, 0, 15], [1, 1, 15], [0, 1, 15]], float)
    >>> V = np.stack([P[::-1] + [0, 0, 1e-13], P[::-1] + [0, 0, 1e-3]])
    >>> dP, dQ = front_distances(P, np.array([0, 0, 1.0]), V, np.array([[0, 0, -1.0]] * 2))
    >>> dQ[:, 0].round(12).tolist(), dP[:, 0].round(12).tolist()
    ([0.0, 0.001], [0.0, 0.001])
    """
    dQ = (V - P[0]) @ nP                                    # (m, K')
    dP = np.einsum("mkj,mj->mk", P[None] - V[:, :1], N)     # (m, K)
    # the band of P's plane at the receivers' vertices and theirs at P's: coplanar_band
    # with |n| . |x0| for |n . x0| (0 for a plane through the origin, where (x - x0) . n
    # still rounds at u |x0|: test4 turned, a corner at the origin 1.9e-14 behind)
    bandQ = coplanar_band(V.reshape(-1, 3), nP[None], np.abs(nP[None]) @ np.abs(P[0])
                          ).reshape(dQ.shape)
    bandP = coplanar_band(P, N, np.einsum("mj,mj->m", np.abs(V[:, 0]), np.abs(N)))  # (K, m)
    dQ[np.abs(dQ) <= bandQ] = 0.0
    dP[np.abs(dP) <= bandP.T] = 0.0
    return dP, dQ


def _front_parts(P, nP, Qs, nQs):
    """:func:`front_parts` of one emitter and its receivers, the distances computed
    here."""
    V, _ = padded(Qs)
    return front_parts(P, nP, Qs, nQs, *front_distances(P, nP, V, nQs))


def _mp_vector(x):
    return [mp.mpf(float(v)) for v in x]


def _mp_escalate(c, ef, J, edges, L, area_s, atol):
    """One receiver's value and estimate with its costliest edge pairs re-evaluated in
    mpmath: the fewest (by decreasing rounding estimate ``c``) that bring the rest within
    half of ``atol`` (the absolute error allowed). The rest are summed in floats; the
    re-evaluated ones in mpmath, from the float vertices (``edges``: for each pair, the vertices a, a', b, b' of its
    edges ``a -> a'`` and ``b -> b'``, unscaled), with ln L taken out as in the floats,
    at ``AREA_CLOSED_MP_DPS`` digits, doubled (up to ``MP_MAX_DPS``) while their rounding
    (``AREA_CLOSED_MP_ULPS`` units of the precision of the closed form's terms) misses
    the other half."""
    order = np.argsort(-c)
    rest = np.concatenate([np.cumsum(c[order][::-1])[::-1][1:], [0.0]])
    n_esc = int(np.argmax(rest <= 0.5 * atol)) + 1
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
                Jk, Mk = mp_edge_log_integral(a, e, b, f)
                acc += efk * (Jk - lnL)
                mag += abs(efk) * (Mk + abs(lnL))
            denom = 2 * mp.pi * mp.mpf(area_s)
            value = float((acc + mp.mpf(float_part)) / denom)
            mp_err = float(tol.AREA_CLOSED_MP_ULPS * mag * mp.mpf(2) ** -mp.mp.prec / denom)
        if mp_err <= 0.5 * atol or 2 * dps > tol.MP_MAX_DPS:
            break
        dps *= 2
    # the float part's rounding, the conversion to a float and the mpmath rounding
    est = float(c[kept].sum()) + tol.EPS * abs(value) + mp_err
    return value, est, n_esc


def unoccluded_pairs(P, Qs, shortcuts=True, rtol=None, atol=0.0, parts=None, counts=None):
    """F(P -> Q) unoccluded for one emitter and many receivers, in closed form, with
    error estimates: the batch form of :func:`unoccluded_pair`.

    Each polygon is clipped here to the front of the other's plane (one-sided, as
    :func:`unoccluded_pair`); pass them whole. The edge pairs of all receivers are
    evaluated together (:func:`~exactff.area.edge_integrals.edge_pair_sums`, the
    closed form of the Mitalas-Stephenson contour integral, compiled). A receiver whose
    estimate misses ``rtol * max(F, AREA_CLOSED_FLOOR)`` is taken, with ``shortcuts`` and when it is far
    (:func:`~exactff.area.far_field.is_far`), by the far-field rule if that estimate is
    the smaller, then (with
    ``atol``) by the tanh-sinh contour rule
    (:func:`~exactff.area.contour_rule.contour_tanh_sinh`) if that one's is; a
    receiver still
    missing it has its costliest edge pairs re-evaluated in mpmath
    (``AREA_CLOSED_MP_DPS`` digits). ``counts`` counts each.

    Parameters
    ----------
    P : ndarray of shape (K, 3)
        The emitter, validated (:func:`~exactff.scene.validate_polygon`), as floats.
    Qs : sequence of ndarray of shape (K_j, 3)
        The receivers, each validated; not clipped.
    shortcuts : bool, default True
        Allow the far-field rule for far receivers that miss the target (the one
        shortcut here; False: the tanh-sinh rule or mpmath instead).
    rtol : float, optional
        The relative target of the estimates (default ``AREA_CLOSED_RTOL``).
    atol : float, default 0
        The absolute error allowed per value: an estimate up to this is accepted; the
        error allowed is then ``max(atol, rtol * max(F, AREA_CLOSED_FLOOR))`` (the area
        rows pass their absolute tolerance: a value within it needs no fallback).
    counts : ClosedFormCounts, optional
        Adds what this call did (per call: safe under threads, one per thread).
    parts : sequence of (ndarray or None, ndarray or None), optional
        Each pair's parts in front of the other's plane, ``(Pc, Qc)``, where the caller
        has them (:func:`exactff.halfspace.clip_front`; ``Pc`` the emitter itself where
        it is whole): not decided again here.

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
    if counts is not None:
        counts.pairs += m
    AP = area_vector(P)
    area_P = float(np.linalg.norm(AP))
    nP = AP / area_P
    # the emitter's area rounded (geometry.area_vector, a Newell sum about its first
    # vertex): a cross product's component x1 y2 - x2 y1 of rounded differences is off
    # by at most 4 u (|x1 y2| + |x2 y1|) (the differences, the products, the
    # subtraction), the partial sums by K u of those magnitudes T, the norm by 3 u of
    # the area: a relative error of (K + 4) u T / 2A + 3 u, which every value divided by
    # it carries (T / 2A is about 1 / sin of a thin triangle's angle)
    D = P - P[0]
    a, b = np.abs(D[1:-1]), np.abs(D[2:])
    T = float(np.sum(a[:, [1, 2, 0]] * b[:, [2, 0, 1]] + a[:, [2, 0, 1]] * b[:, [1, 2, 0]]))
    area_rel = (len(P) + 4) * tol.EPS * 0.5 * T / area_P + 3 * tol.EPS
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
    # A_P F = (1 / 2 pi) sum (e . f) J over every edge pair, in the scaled units, and its
    # rounding (compiled, the GIL released): per pair, and per edge pair kept
    area_s = area_P / L ** 2
    v, ev, owner, ip, iq, ef, J, c = edge_pair_sums(VP, po, VQ, qo, 1.0 / L,
                                                    2.0 * np.pi * area_s)
    live = np.array(live)
    values[live], est[live] = v, ev
    # the error allowed per value: atol, or the share rtol of the value if larger
    allowed = np.maximum(float(atol), rtol * np.maximum(np.abs(values), tol.AREA_CLOSED_FLOOR))
    miss = [k for k in range(len(live)) if est[live[k]] > allowed[live[k]]]
    if shortcuts and miss:
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
            if counts is not None:
                counts.far_rule += int(better.sum())
        miss = [k for k in miss if est[live[k]] > allowed[live[k]]]
    # with an absolute target (area rows), the tanh-sinh contour rule next (about a
    # millisecond a pair; edges parallel only to rounding, thin or far polygons, where
    # the closed form's terms cancel); polygon_form_factor's relative target goes to
    # mpmath
    for k in (list(miss) if atol > 0 else []):
        j = live[k]
        fv, fe = contour_tanh_sinh(P, Qs[j], (Pcs[j], Qcs[j]))
        if fe < est[j]:
            values[j], est[j] = fv, fe
            if counts is not None:
                counts.contour_rule += 1
    miss = [k for k in miss if est[live[k]] > allowed[live[k]]]
    for k in miss:
        j = live[k]
        sel = np.flatnonzero(owner == k)
        edges = np.stack([VP[ip[sel]], VP[nextP[ip[sel]]], VQ[iq[sel]], VQ[nextQ[iq[sel]]]],
                         axis=1)
        values[j], est[j], n_esc = _mp_escalate(c[sel], ef[sel], J[sel], edges, L[k],
                                                area_s[k], allowed[j])
        if counts is not None:
            counts.escalated_pairs += 1
            counts.escalated_edge_pairs += n_esc
    # the emitter's area (above) and the last divisions (2 u) round the value further,
    # on every path
    est += (area_rel + 2 * tol.EPS) * np.abs(values)
    check_finite(values, est, "area form factor")
    return nonnegative(values, est), est


def unoccluded_pair(P, Q, shortcuts=True, atol=0.0):
    """F(P -> Q) of two validated polygons, unoccluded, and an estimate of its error
    (:func:`unoccluded_pairs` for one receiver): the closed form of the contour integral
    with the rounding of its terms (``AREA_CLOSED_ULPS`` units), the far-field rule
    (:func:`~exactff.area.far_field.is_far`; only with ``shortcuts``) or mpmath where that
    misses
    ``AREA_CLOSED_RTOL`` (and ``atol``, when given). A value below 0 within its
    estimate is 0; beyond it, NumericalError."""
    f, e = unoccluded_pairs(P, [Q], shortcuts=shortcuts, atol=atol)
    return float(f[0]), float(e[0])
