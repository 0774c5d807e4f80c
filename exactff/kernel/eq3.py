"""The paper's Eq. 3 (corrected), integrated with monotone-span splitting.

The image of a great-circle arc on the base disk lies on the ellipse of Eq. 2; each
arc is split at its x-extremes into monotone spans, each integrated on its own branch
with the corrected antiderivative (``docs/explanation/ppbh-method.md``,
``tools/derive_eq3.py``):
:func:`eq3_edge_integral` evaluates it as printed (corrected), span by span.

The integrators evaluate the same spans in the *stable form* (proved in
``tools/derive_eq3.py``): on a span the branch is the sign of ``sin t`` (``t`` the arc's
angle from its x-maximum), ``asin`` differences are ``-sigma (t1 - t0)``, and the spans'
differences add up, over an arc of angle ``theta`` with ends ``u0``, ``u1`` and unit plane
normal ``m = (A, B, C)``, to

``int y dx = (1/2) [ -C theta + sin(theta) (C cos(t0 + t1) + A B sin(t0 + t1)) ]``

where the factor is ``v_x u_y + u_x v_y`` at the arc's midpoint ``u`` (``v = m x u``): every
term is O(theta), the large ``C asin`` terms having been subtracted analytically, and no
eta or rotation of the frame enters (:func:`eq3_ring_sums`, :func:`mp_eq3_sum`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .. import _tolerances as tol
from ..checks import check_sides
from ..errors import NumericalError, check_finite, nonnegative
from .ladder import mp_converge, mp_sector_value
from .point import local_clipped
from .sector import offset_edge_planes

__all__ = ["eq3_edge_integral", "arc_x_extremes", "eq3_form_factor", "eq3_ring_area",
           "eq3_ring_sums", "mp_eq3_sum"]


def eq3_edge_integral(a: ArrayLike, b: ArrayLike, *,
                      scale: bool = False) -> float | tuple[float, float]:
    """Integral of ``y dx`` along the image of the great-circle arc ``a -> b``.

    The image of the arc on the base disk lies on the ellipse of Eq. 2,
    ``y(x) = (-A B x +- C sqrt(eta^2 - kappa^2 x^2)) / eta^2`` with ``(A, B, C) = a x b``,
    ``eta^2 = B^2 + C^2`` and ``kappa^2 = A^2 + B^2 + C^2``. The arc is split at its
    x-extremes (``x = +- eta / kappa``) into monotone spans, each integrated on its own
    branch ``s = +-1`` with the corrected Eq. 3,

    ``Area_s(x) = (1 / 2 kappa) [ s C asin(kappa x / eta)
    + s (kappa C x / eta^2) sqrt(eta^2 - kappa^2 x^2) - (kappa A B / eta^2) x^2 ]``.

    ``asin(kappa x / eta)`` and ``sqrt(eta^2 - kappa^2 x^2)`` are evaluated from the
    point's coordinates in the arc's own plane (``kappa x / eta = cos t`` and
    ``sqrt(...) = eta |sin t|``), which keeps them accurate next to the x-extremes.

    Parameters
    ----------
    a, b : array_like of shape (3,)
        End points in the local frame, ``z >= 0``; only their directions matter.
    scale : bool, optional
        Also return the sum of the absolute values of the terms of Eq. 3 that make up
        the integral, the scale of its rounding error. The terms (``C asin`` is up to
        ``pi / 2``) can be much larger than the integral they add up to: an arc near
        the horizon whose image runs almost parallel to the y axis.

    Returns
    -------
    float, or (float, float) with ``scale=True``
        The signed integral; minus the sum over a closed contour is the signed
        (counter-clockwise positive) area of its image.

    Examples
    --------
    The image of the quarter horizon from x to y is the quarter circle, and the
    integral of ``y dx`` along it (x from 1 to 0) is ``-pi / 4``:

    >>> round(eq3_edge_integral([1, 0, 0], [0, 1, 0]), 12)
    -0.785398163397
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    m = np.cross(a, b)
    kappa = float(np.linalg.norm(m))
    if kappa == 0.0:
        # a and b parallel: a point (or an edge through p, excluded upstream)
        return (0.0, 0.0) if scale else 0.0
    A, B, C = m / kappa  # normalised so that kappa = 1 below
    eta = math.hypot(B, C)
    if eta == 0.0:
        # B = C = 0: the plane x = 0, a vertical segment on the disk, dx = 0
        return (0.0, 0.0) if scale else 0.0
    if C == 0.0:
        # C = 0: the plane holds the zenith; the image is the segment y = -A x / B
        xa = a[0] / np.linalg.norm(a)
        xb = b[0] / np.linalg.norm(b)
        value = float(-A / B * (xb * xb - xa * xa) / 2.0)
        return (value, abs(A / B) * (xb * xb + xa * xa) / 2.0) if scale else value
    w, w_perp, ta, theta, extremes = arc_x_extremes(a, b)
    ua = a / np.linalg.norm(a)
    ub = b / np.linalg.norm(b)
    # span ends as (t, x, cos t, |sin t|): the arc's end points, and its x-extremes
    # t = k pi (x = +- eta, cos t = +- 1, sin t = 0) where the arc passes them
    ends = [(ta, float(ua[0]), float(ua @ w), abs(float(ua @ w_perp)))]
    for t in extremes:
        c = 1.0 if round(t / math.pi) % 2 == 0 else -1.0
        ends.append((t, eta * c, c, 0.0))
    ends.append((ta + theta, float(ub[0]), float(ub @ w), abs(float(ub @ w_perp))))

    def area_terms(s, x, cos_t, abs_sin_t):
        # the three terms of the corrected Eq. 3 with kappa = 1 (halved):
        # asin(x / eta) = atan2(cos t, |sin t|), sqrt(eta^2 - x^2) = eta |sin t|
        return (0.5 * s * C * math.atan2(cos_t, abs_sin_t),
                0.5 * s * (C * x / eta) * abs_sin_t,
                -0.5 * (A * B / eta ** 2) * x * x)

    total, magnitude = [], 0.0
    for (t0, *P0), (t1, *P1) in zip(ends[:-1], ends[1:]):
        # branch of this span, from its midpoint: s C sqrt(...) = eta^2 y + A B x
        tm = 0.5 * (t0 + t1)
        um = math.cos(tm) * w + math.sin(tm) * w_perp
        s = 1.0 if C * (eta ** 2 * um[1] + A * B * um[0]) >= 0 else -1.0
        end, start = area_terms(s, *P1), area_terms(s, *P0)
        total.append(math.fsum(end) - math.fsum(start))
        magnitude += math.fsum(abs(v) for v in end + start)
    value = math.fsum(total)
    return (value, magnitude) if scale else value


def arc_x_extremes(a: ArrayLike, b: ArrayLike) -> tuple:
    """Where the image of the great-circle arc ``a -> b`` on the base disk turns in x:
    the ends of its monotone spans (Eq. 3 is integrated span by span).

    The arc is parametrised in its own plane as ``cos t w + sin t w_perp``, with ``w``
    the direction of largest x on the great circle (x = eta) and ``w_perp = m x w``
    (``m`` the unit normal of the arc's plane, ``a x b`` normalised); x is extreme at
    ``t = k pi``.

    Parameters
    ----------
    a, b : array_like of shape (3,)
        End points in the local frame; only their directions matter. The arc's plane
        must not hold the z axis's perpendicular x direction only (``eta > 0``) and
        ``a``, ``b`` must not be parallel.

    Returns
    -------
    (ndarray of shape (3,), ndarray of shape (3,), float, float, list of float)
        ``w``, ``w_perp``, the parameter of ``a``, the arc's length (in (0, pi)) and the
        parameters ``k pi`` strictly inside the arc, increasing.

    Examples
    --------
    The horizon from +y past -x turns in x once, at -x (t = pi); from +y to x it is
    monotone:

    >>> w, w_perp, ta, theta, ts = arc_x_extremes([0, 1, 0], [-1, -0.1, 0])
    >>> w.tolist(), [round(t / np.pi, 6) for t in ts]
    ([1.0, 0.0, 0.0], [1.0])
    >>> arc_x_extremes([0, 1, 0], [1, 0, 0])[4]
    []
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    m = np.cross(a, b)
    kappa = float(np.linalg.norm(m))
    mhat = m / kappa
    eta = math.hypot(mhat[1], mhat[2])
    # orthonormal basis of the arc's plane: w at the x-maximum (x = eta), w_perp = m x w
    w = (np.array([1.0, 0.0, 0.0]) - mhat[0] * mhat) / eta
    w_perp = np.cross(mhat, w)
    ua = a / np.linalg.norm(a)
    ta = math.atan2(float(ua @ w_perp), float(ua @ w))
    theta = math.atan2(kappa, float(a @ b))  # arc length, in (0, pi)
    extremes = [k * math.pi for k in range(-1, 4) if ta < k * math.pi < ta + theta]
    return w, w_perp, ta, theta, extremes


def eq3_form_factor(point: ArrayLike, normal: ArrayLike, polygon: ArrayLike, *,
                    two_sided: bool = False, one_sided: bool | None = None,
                    tolerance: float | None = None,
                    error: bool = False) -> float | tuple[float, float]:
    """Unoccluded form factor by the paper's Eq. 3 (corrected), with span splitting.

    Evaluated in the stable form (:func:`eq3_ring_sums`), which needs no rotation of
    the frame.

    Parameters and return value as :func:`point_polygon_form_factor`; ``error=True``
    also returns a rounding-error estimate (``C1 u`` times the sum of the absolute
    terms of Eq. 3 over the edges, plus their planes' and midpoints' rounding, over
    2 pi). With a ``tolerance`` (default None: double precision only), a value whose
    estimate exceeds it times the value (as :func:`sector_form_factor`) is evaluated
    again with mpmath from the float input, Eq. 3 again (:func:`mp_eq3_sum`), at two
    precisions 20 digits apart raised until they agree to ``tolerance``; where mpmath
    stops first it raises
    :class:`exactff.NumericalError`, unless ``error=True``.

    Examples
    --------
    >>> sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]
    >>> round(eq3_form_factor([0, 0, 0], [0, 0, 1], sq), 12)
    0.239456470461
    """
    two_sided = check_sides(two_sided, one_sided)
    C, sign = local_clipped(point, normal, polygon, two_sided)
    if not sign or len(C) < 2:
        return (0.0, 0.0) if error else 0.0
    R = np.array(C, dtype=float)
    S, mags, errs = eq3_ring_sums(R[:1], R - R[0], np.roll(np.arange(len(R)), -1),
                                  np.zeros(len(R), dtype=np.int64), 1)
    # a polygon whose front faces p has a clockwise image (seen from above the disk)
    F = float(-sign * S[0] / (2 * math.pi))
    est = float((tol.C1 * tol.EPS * mags[0] + errs[0]) / (2 * math.pi))
    check_finite(F, est, "Eq. 3 form factor")
    if tolerance is not None and not est <= tolerance * abs(F):
        # the last tier: Eq. 3's stable form in mpmath from the float input, clipped and
        # sided as the sector form's tier
        P = np.asarray(polygon, dtype=float)
        hi, diff, converged = mp_converge(
            lambda dps: mp_sector_value(point, normal, P, two_sided, dps, sign,
                                        ring_sum=mp_eq3_sum), tolerance)
        if not converged and not error:
            raise NumericalError(
                f"Eq. 3 in mpmath did not converge at {tol.MP_MAX_DPS} digits: two "
                f"evaluations differ by {float(diff):.3g} (value {float(hi):.3g}); ask "
                f"error=True to get the value with this estimate")
        F = max(float(hi), 0.0)
        est = float(diff) + F * tol.EPS
    # below 0 by at most its own estimate: clamped to 0, which the estimate covers;
    # beyond it, a defect
    F = nonnegative(F, est, "Eq. 3 form factor")
    return (F, est) if error else F


def eq3_ring_area(ring: ArrayLike) -> tuple[float, float]:
    """Signed area (counter-clockwise positive) of the image on the base disk of a closed
    chain of great-circle arcs, by Eq. 3 (corrected) with monotone-span splitting, in
    its stable form (:func:`eq3_ring_sums`).

    Parameters
    ----------
    ring : ndarray of shape (K, 3)
        Vertices in the local frame of the point (z along its normal), ``z >= 0``;
        consecutive vertices (and the last and first) are joined by great-circle arcs.
        Only directions matter: a polygon clipped to the upper half-space, or
        directions lifted from a gnomonic chart.

    Returns
    -------
    (float, float)
        The signed area and a bound on its rounding error.

    Examples
    --------
    The quarter of the upper hemisphere over the first quadrant projects onto a
    quarter of the unit disk:

    >>> a, e = eq3_ring_area(np.array([[0, 0, 1.0], [1, 0, 0], [0, 1, 0]]))
    >>> round(a / (math.pi / 4), 12), bool(e < 1e-13)
    (1.0, True)
    """
    Q = np.array(ring, dtype=float)
    if len(Q) < 2:
        return 0.0, 0.0
    S, mags, errs = eq3_ring_sums(Q[:1], Q - Q[0], np.roll(np.arange(len(Q)), -1),
                                  np.zeros(len(Q), dtype=np.int64), 1)
    return float(S[0] / 2), float((tol.C1 * tol.EPS * mags[0] + errs[0]) / 2)


def eq3_ring_sums(A0, E, nxt, owner, m, eps=tol.EPS):
    """Eq. 3 (corrected, monotone spans) in its stable form over rings in offset form:
    per ring twice the signed area of its image on the base disk, with the scale and
    the bound of its rounding error.

    Each edge ``a -> b`` (directions in the local frame, z along the normal, ``z >= 0``)
    adds ``C theta - sin(theta) (v_x u_y + u_x v_y)``: minus twice the integral of
    ``y dx`` along its image (module docstring; ``tools/derive_eq3.py``), with
    ``m = a x b`` evaluated in offset form as ``A0 x (e_b - e_a) + e_a x e_b`` (as
    :func:`exactff.kernel.clipped_sector_sums`, accurate for rings small next to their
    distance), ``C = m_z / |m|``, ``theta`` the arc's angle, ``sin(theta) = |m| / (|a| |b|)``,
    ``u`` the unit midpoint direction and ``v = m x u / |m|``.

    Parameters
    ----------
    A0 : ndarray of shape (m, 3)
        A reference vertex of each ring (the first), relative to the point, local frame.
    E : ndarray of shape (V, 3)
        Every vertex's offset from its ring's reference vertex.
    nxt : ndarray of shape (V,)
        Index of each vertex's successor in its ring.
    owner : ndarray of shape (V,)
        Ring of each vertex.
    m : int
        Number of rings.
    eps : float
        Unit roundoff of the working precision (``A0``'s dtype: float64 or longdouble).

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,), ndarray of shape (m,))
        ``S`` (twice the counter-clockwise signed area of each image), ``mags`` (the sum
        of the absolute values of its terms: ``C1 eps mags`` bounds the sum's rounding)
        and ``errs`` (the terms' own rounding: the planes' as in the sector form, and
        ``EQ3_FACTOR_ULPS eps 2 sin(theta / 2)`` for each midpoint factor, the constant
        in ``exactff._tolerances``).

    Examples
    --------
    The quarter of the upper hemisphere over the first quadrant: twice pi / 4.

    >>> R = np.array([[0, 0, 1.0], [1, 0, 0], [0, 1, 0]])
    >>> S, mags, errs = eq3_ring_sums(R[:1], R - R[0], np.array([1, 2, 0]), np.zeros(3, int), 1)
    >>> round(float(S[0]) / (math.pi / 2), 12)
    1.0
    """
    dt = A0.dtype
    Ax, Ay, Az = (A0[owner, k] for k in range(3))
    Eax, Eay, Eaz = E[:, 0], E[:, 1], E[:, 2]
    Ebx, Eby, Ebz = Eax[nxt], Eay[nxt], Eaz[nxt]
    # the edge's plane in offset form, as the sector form takes it
    (Mx, My, Mz), s, (ax, ay, az), (bx, by, bz), theta, Z = offset_edge_planes(
        Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz)
    la = np.sqrt(ax * ax + ay * ay + az * az)
    lb = np.sqrt(bx * bx + by * by + bz * bz)
    Nm = la * lb
    ok = s > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        # the arc's midpoint u (unit) and its tangent v = m x u / |m| there
        ux, uy, uz = ax / la + bx / lb, ay / la + by / lb, az / la + bz / lb
        lu = np.sqrt(ux * ux + uy * uy + uz * uz)
        ux, uy, uz = ux / lu, uy / lu, uz / lu
        vx, vy = (My * uz - Mz * uy) / s, (Mz * ux - Mx * uz) / s
        # d(x y)/dt at the midpoint, times sin(theta): x1 y1 - x0 y0, in O(theta) form;
        # ends that are opposite directions have no midpoint: the factor (at most 1 in
        # absolute value) is left out and sin(theta) goes to the bound
        sin_theta = s / Nm
        mid = ok & (lu > 0)
        xy = np.where(mid, sin_theta * (vx * uy + ux * vy), 0.0)
        sector = theta * Mz / s
        terms = np.where(ok, sector - xy, 0.0)
        absterms = np.where(ok, np.abs(sector) + np.abs(xy), 0.0)
        # rounding of each term: the plane's direction (as clipped_sector_sums: m_z's
        # summands, and |m| at relative order theta^2), which moves C theta and sin theta
        # alike, and the midpoint factor's
        rel = np.where(ok, tol.C2 * eps * (Z + theta * theta * Nm) / s,
                       np.where(Nm > 0, np.inf, 0.0))
        err = (2 * theta * np.minimum(2.0, rel)
               + np.where(ok, tol.EQ3_FACTOR_ULPS * eps * 2 * np.sin(theta / 2), 0.0)
               + np.where(ok & ~mid, sin_theta, 0.0))
    # summed per ring in the working precision (bincount would round to double)
    out = []
    for w in (terms, absterms, err):
        acc = np.zeros(m, dtype=dt)
        np.add.at(acc, owner, w)
        out.append(acc)
    return tuple(out)


def mp_eq3_sum(ring):
    """Eq. 3's stable form over a closed ring of directions in mpmath numbers, at the
    working precision: twice the counter-clockwise signed area of its image,
    ``sum_k C theta_k - sin(theta_k) (v_x u_y + u_x v_y)`` (:func:`eq3_ring_sums`; an mpf;
    zero-length edges add nothing).

    Examples
    --------
    >>> import mpmath as mp
    >>> ring = [[mp.mpf(0), 0, 1], [mp.mpf(1), 0, 0], [mp.mpf(0), 1, 0]]
    >>> float(mp_eq3_sum(ring) / (mp.pi / 2))
    1.0
    """
    import mpmath as mp

    total = mp.mpf(0)
    for i in range(len(ring)):
        a, b = ring[i], ring[(i + 1) % len(ring)]
        m = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        sm = mp.sqrt(sum(c * c for c in m))
        if sm == 0:
            continue
        la = mp.sqrt(sum(c * c for c in a))
        lb = mp.sqrt(sum(c * c for c in b))
        u = [a[k] / la + b[k] / lb for k in range(3)]
        lu = mp.sqrt(sum(c * c for c in u))
        u = [c / lu for c in u]
        vx = (m[1] * u[2] - m[2] * u[1]) / sm
        vy = (m[2] * u[0] - m[0] * u[2]) / sm
        theta = mp.atan2(sm, sum(a[k] * b[k] for k in range(3)))
        total += theta * m[2] / sm - sm / (la * lb) * (vx * u[1] + u[0] * vy)
    return total
