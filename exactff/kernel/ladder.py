"""The escalation ladder (``docs/explanation/robustness.md``, "Escalation"): a value
whose double-precision error estimate misses the tolerance is evaluated again from the
float input, first in long double (the same vectorised sums), then with mpmath at
growing precision until two evaluations agree. Point rows and the refinement of visible
pieces climb the same ladder (:func:`mp_converge`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _tolerances as tol
from ..checks import check_sides
from ..errors import NumericalError
from ..geometry import mp_receiver_frame, receiver_frame
from ..halfspace import clip_above_horizon
from ._sector import row_sums_extended
from .sector import sector_values

__all__ = ["extended_values", "mp_converge", "mp_sector_sum", "mp_sector_value",
           "mp_form_factor"]


def extended_values(flat, ids, rows, P, N, d0, two_sided):
    """Form factors and error estimates of polygons ``ids[k]`` from points ``P[rows[k]]``
    (normals ``N[rows[k]]``) in long double arithmetic: the sector sums with rounded
    offsets from the float input, in one compiled pass (``exactff/_core/sector_sums.h``,
    :func:`exactff.kernel.sector.clipped_sector_sums`'s arithmetic)."""
    frames = receiver_frame(N, dtype=np.longdouble)
    S, mags, errs, _ = row_sums_extended(
        flat.V, flat.offsets, np.asarray(ids, dtype=np.int64),
        np.asarray(rows, dtype=np.int64), P, frames, tol.LONGDOUBLE_EPS,
        tol.OFFSET_ROUNDING_ULPS, tol.C2 * tol.LONGDOUBLE_EPS)
    F, err = sector_values(S, mags, errs, d0, two_sided, eps=tol.LONGDOUBLE_EPS)
    # returned in double: the value's rounding to double (u F) joins the long double
    # estimate, which alone can be far below it
    Fd = F.astype(float)
    return Fd, err.astype(float) * (1 + 2 * tol.EPS) + tol.EPS * Fd


def mp_converge(evaluate, tolerance, dps=30):
    """Evaluate at ``dps`` digits and 20 more, raising the precision by 40 digits until
    the two agree to ``tolerance`` relative (a thousandth of it, to be safe), are equal,
    or differ by less than ``MP_VALUE_FLOOR``, or the precision reaches
    ``MP_MAX_DPS``.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(dps)`` returns the value (an mpf) computed at ``dps`` digits.
    tolerance : float
    dps : int, default 30

    Returns
    -------
    (mpf, mpf, bool)
        The higher evaluation, the difference of the two, and whether they agreed
        (False: stopped at ``MP_MAX_DPS``).

    Examples
    --------
    >>> import mpmath as mp
    >>> def third(dps):
    ...     with mp.workdps(dps):
    ...         return mp.mpf(1) / 3
    >>> value, diff, ok = mp_converge(third, 1e-12)
    >>> ok, float(diff) < 1e-29
    (True, True)
    """
    while True:
        lo = evaluate(dps)
        hi = evaluate(dps + 20)
        diff = abs(hi - lo)
        if diff <= tolerance * abs(hi) * 1e-3 or hi == lo or float(diff) < tol.MP_VALUE_FLOOR:
            return hi, diff, True
        if dps >= tol.MP_MAX_DPS:
            return hi, diff, False
        dps += 40


def mp_sector_sum(ring):
    """The sector sum of a closed ring of directions in mpmath numbers, at the working
    precision: ``sum_k theta_k m_z / norm(m)`` with ``m = cross(a, b)`` and ``theta_k``
    the angle between ``a`` and ``b`` (an mpf; zero-length edges add nothing)."""
    import mpmath as mp

    total = mp.mpf(0)
    for i in range(len(ring)):
        a, b = ring[i], ring[(i + 1) % len(ring)]
        m = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        sm = mp.sqrt(sum(c * c for c in m))
        if sm != 0:
            total += mp.atan2(sm, sum(a[j] * b[j] for j in range(3))) * m[2] / sm
    return total


def mp_sector_value(point, normal, polygon, two_sided, dps, side_hint=None,
                    ring_sum=mp_sector_sum):
    """The form factor of one polygon by the sector form at ``dps`` digits (an mpf),
    from the float input taken as exact; ``side_hint`` is the side of the point when
    it is already decided exactly (+1: in front). ``ring_sum`` integrates the clipped
    ring (twice its image's signed area): the sector form, or Eq. 3's stable form
    (:func:`exactff.kernel.eq3.mp_eq3_sum`)."""
    import mpmath as mp

    with mp.workdps(dps):
        t1, t2, nz = mp_receiver_frame(normal)
        pv = [mp.mpf(float(c)) for c in point]
        Q = []
        for v in polygon:
            r = [mp.mpf(float(v[i])) - pv[i] for i in range(3)]
            Q.append([sum(r[i] * ax[i] for i in range(3)) for ax in (t1, t2, nz)])
        # side of p: Newell normal . (centroid - p), exact up to the working precision
        K = len(Q)
        Nw = [mp.mpf(0)] * 3
        for i in range(K):
            a, b = Q[i], Q[(i + 1) % K]
            Nw[0] += (a[1] - b[1]) * (a[2] + b[2])
            Nw[1] += (a[2] - b[2]) * (a[0] + b[0])
            Nw[2] += (a[0] - b[0]) * (a[1] + b[1])
        side = sum(Nw[i] * sum(q[i] for q in Q) for i in range(3))
        if side_hint is not None:
            # the exact side (rational arithmetic): the working precision may not resolve
            # a point extremely close to the plane (side < 0 means p in front)
            side = -side_hint
        if side == 0 or (not two_sided and side > 0):
            return mp.mpf(0)
        C = clip_above_horizon(Q, zero=mp.mpf(0))
        total = ring_sum(C)
        # the image of the boundary ring, whichever way it winds: for a point within
        # rounding of a polygon that is planar only to rounding, the ring's winding can
        # disagree with the side decided from the polygon's Newell plane, and only the
        # ring's own orientation gives the image's area (pinned:
        # test_mpmath_tier_integrates_the_ring_whichever_way_it_winds); every other path
        # integrates the ring as given too
        return abs(total) / (2 * mp.pi)


def mp_form_factor(point: ArrayLike, normal: ArrayLike, polygon: ArrayLike, *,
                   two_sided: bool = False, one_sided: bool | None = None, tolerance: float = tol.DEFAULT_RTOL,
                   dps: int | None = None, error: bool = False,
                   side: int | None = None) -> float | tuple[float, float]:
    """Unoccluded form factor with mpmath, from the float input taken as exact.

    The sector form evaluated at ``dps`` decimal digits and again 20 digits higher; the
    precision grows until the two agree to ``tolerance`` (relative), up to 400 digits;
    beyond, :class:`exactff.NumericalError` (with ``error=True``: the value and the
    difference as its error estimate). This is what automatic escalation calls.

    Parameters
    ----------
    point, normal : array_like of shape (3,)
    polygon : array_like of shape (K, 3)
    two_sided : bool, default False
        As for :func:`exactff.point_polygon_form_factor` (``one_sided=``: deprecated).
    tolerance : float, default 1e-12
    dps : int, optional
        Starting precision (default 30 digits).
    error : bool, default False
        Also return the error estimate (the difference of the two evaluations).
    side : {-1, 0, 1}, optional
        The side of the point, if already decided exactly (+1: in front).

    Returns
    -------
    float, or (float, float) with ``error=True``

    Examples
    --------
    A 1e-9 square at distance 1, where double precision keeps only a few digits:

    >>> sq = np.array([[0, 0, 1], [0, 1e-9, 1], [1e-9, 1e-9, 1], [1e-9, 0, 1]])
    >>> mp_form_factor([0, 0, 0], [0, 0, 1], sq)  # F = A / pi to first order
    3.183098861837907e-19
    """
    two_sided = check_sides(two_sided, one_sided)
    P = np.asarray(polygon, dtype=float)
    hi, diff, converged = mp_converge(
        lambda prec: mp_sector_value(point, normal, P, two_sided, prec, side),
        tolerance if tolerance else 1e-15, dps=30 if dps is None else int(dps))
    if not converged and not error:
        raise NumericalError(
            f"mpmath did not converge at {tol.MP_MAX_DPS} digits: two evaluations "
            f"differ by {float(diff):.3g} (value {float(hi):.3g}); ask error=True "
            f"to get the value with this estimate")
    value = max(float(hi), 0.0)
    return (value, float(diff) + abs(value) * tol.EPS) if error else value
