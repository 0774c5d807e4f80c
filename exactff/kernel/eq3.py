"""The paper's Eq. 3 (corrected), integrated with monotone-span splitting.

The image of a great-circle arc on the base disk lies on the ellipse of Eq. 2; each
arc is split at its x-extremes into monotone spans, each integrated on its own branch
with the corrected antiderivative (DESIGN 2, ``tools/derive_eq3.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .. import _tolerances as tol
from ..checks import check_sides
from ..errors import NumericalError, check_finite
from .point import local_clipped

__all__ = ["eq3_edge_integral", "arc_x_extremes", "eq3_form_factor", "eq3_ring_area"]


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
                    error: bool = False) -> float | tuple[float, float]:
    """Unoccluded form factor by the paper's Eq. 3 (corrected), with span splitting.

    The frame is first rotated about ``n`` (which changes no area) so that no edge
    plane is close to ``x = 0``, where ``eta -> 0`` makes Eq. 3 ill-conditioned.

    Parameters and return value as :func:`point_polygon_form_factor`; ``error=True``
    also returns a rounding-error estimate (``C1 u`` times the sum of the absolute
    terms of Eq. 3 over the edges, over pi).

    Examples
    --------
    >>> sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]
    >>> round(eq3_form_factor([0, 0, 0], [0, 0, 1], sq), 12)
    0.239456470461
    """
    one_sided = check_sides(two_sided, one_sided)
    C, sign = local_clipped(point, normal, polygon, one_sided)
    if not sign or len(C) < 2:
        return (0.0, 0.0) if error else 0.0
    area, mag = eq3_ring_area(np.array(C))
    # a polygon whose front faces p has a clockwise image (seen from above the disk)
    F = -sign * area / math.pi
    est = tol.C1 * tol.EPS * mag / math.pi
    check_finite(F, est, "Eq. 3 form factor")
    # below 0 by at most its own estimate: clamped to 0, which the estimate covers;
    # beyond it, a defect
    if not F >= -est:
        raise NumericalError(f"Eq. 3 gave the form factor {F!r}, below 0 beyond its "
                             f"rounding error estimate {est:.3g}")
    return (max(F, 0.0), est) if error else max(F, 0.0)


def eq3_ring_area(ring: ArrayLike) -> tuple[float, float]:
    """Signed area (counter-clockwise positive) of the image on the base disk of a closed
    chain of great-circle arcs, by Eq. 3 (corrected) with monotone-span splitting.

    The frame is rotated about z (which changes no area) so that no arc's plane is
    close to ``x = 0``, where ``eta -> 0`` makes Eq. 3 ill-conditioned.

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
        The signed area and the sum of the absolute values of the terms of Eq. 3 that
        make it up (the scale of its rounding error; see :func:`eq3_edge_integral`).

    Examples
    --------
    The quarter of the upper hemisphere over the first quadrant projects onto a
    quarter of the unit disk:

    >>> a, m = eq3_ring_area(np.array([[0, 0, 1.0], [1, 0, 0], [0, 1, 0]]))
    >>> round(a / (math.pi / 4), 12)
    1.0
    """
    Q = np.array(ring, dtype=float)
    M = np.cross(Q, np.roll(Q, -1, axis=0))
    Ml = np.linalg.norm(M, axis=1)
    M = M[Ml > 0] / Ml[Ml > 0, None]
    if len(M) == 0:
        return 0.0, 0.0
    # rotation about z maximising the smallest eta = sqrt(1 - m_x^2) over the edges
    k = 2 * len(Q) + 2
    phis = np.arange(k) * math.pi / k
    mx = np.cos(phis)[:, None] * M[None, :, 0] + np.sin(phis)[:, None] * M[None, :, 1]
    phi = phis[int(np.argmin(np.abs(mx).max(axis=1)))]
    c, s = math.cos(phi), math.sin(phi)
    Rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    z = Q[:, 2].copy()
    Q = Q @ Rz.T
    Q[:, 2] = z
    parts = [eq3_edge_integral(Q[i], Q[(i + 1) % len(Q)], scale=True)
             for i in range(len(Q))]
    # image area (counter-clockwise positive) = - sum of y dx
    return -math.fsum(v for v, _ in parts), math.fsum(m for _, m in parts)
