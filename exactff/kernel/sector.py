"""The sector (Lambert) form, vectorised over edges: the sums of
``docs/explanation/ppbh-method.md`` ("The sector form") for many horizon-clipped
polygons at once, in offset form, with their rounding-error model
(``docs/explanation/robustness.md``, "The estimate"). Every exact path integrates with
these sums: point rows, the visible pieces of the engine, refinement and the area code's
hidden parts."""

import math

import numpy as np

from .. import _tolerances as tol
from ..errors import nonnegative

__all__ = ["TWO_PI", "TWO_PI_LONG", "clipped_sector_sums", "sector_values", "offset_edge_planes"]

TWO_PI = 2.0 * math.pi
#: 2 pi to long double precision, for the second tier's sums: the double constant is
#: 3.9e-17 relative off, thousands of long double ulps
TWO_PI_LONG = 8 * np.arctan(np.longdouble(1))


def clipped_sector_sums(A0, E, nxt, owner, m, eps=tol.EPS, rounded_offsets=False):
    """Sector sums of horizon-clipped polygons, with their rounding-error estimates.

    The polygons are given in *offset form* (``docs/explanation/robustness.md``): ``A0``
    (m, 3) is a reference
    vertex of each polygon relative to the point, in the local frame, and ``E`` (V, 3)
    are the vertices' offsets from it. The edge plane ``m = a x b`` is evaluated as
    ``A0 x (e_b - e_a) + e_a x e_b``, which stays accurate for polygons small next to
    their distance (the plain cross product loses ``log10(distance / size)`` digits).

    Returns ``(S, mags, errs)``: per polygon the sum of the sector terms, the sum of
    their absolute values, and the estimated error of the plane directions. Works in the
    dtype of ``A0`` and ``E`` (float64, or longdouble for the second tier), with unit
    roundoff ``eps``; ``owner`` must be sorted (each polygon's vertices contiguous).

    With ``rounded_offsets``, ``A0`` and ``E`` are taken as computed from the float input
    in this precision (differences from the point and from the first vertex, rotated to
    the local frame), and ``errs`` also holds what their rounding can move the value
    (:func:`_offset_rounding`): near an edge's line that is the largest error.
    """
    dt = A0.dtype
    n_e = len(owner)
    Ax, Ay, Az = (A0[owner, k] for k in range(3))
    Eax, Eay, Eaz = (E[:, k].copy() for k in range(3))
    Ebx, Eby, Ebz = Eax[nxt], Eay[nxt], Eaz[nxt]
    moved = (_offset_rounding(A0, E, nxt, owner, eps) if rounded_offsets
             else np.zeros(n_e, dtype=dt))
    za = Az + Eaz
    zb = Az + Ebz
    above_a, above_b = za > 0, zb > 0
    ci = np.flatnonzero(above_a != above_b)
    # horizon crossing of the edge, as an offset (its height is exactly 0)
    t = za[ci] / (za[ci] - zb[ci])
    EX = np.column_stack([Ea[ci] + t * (Eb[ci] - Ea[ci])
                          for Ea, Eb in ((Eax, Ebx), (Eay, Eby), (Eaz, Ebz))])
    enter = ~above_a[ci]
    ce, cx = ci[enter], ci[~enter]
    for k, (Ea, Eb) in enumerate(((Eax, Ebx), (Eay, Eby), (Eaz, Ebz))):
        Ea[ce] = EX[enter, k]
        Eb[cx] = EX[~enter, k]
    keep = above_a | above_b
    if not keep.all():
        kk = np.flatnonzero(keep)
        Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz = (
            v[kk] for v in (Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz))
    else:
        kk = slice(None)
    (Mx, My, Mz), s, (ax, ay, az), (bx, by, bz), theta, Z = offset_edge_planes(
        Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz)
    ok = s > 0
    terms = np.zeros(n_e, dtype=dt)
    terms[kk] = np.divide(theta * Mz, s, out=np.zeros_like(s), where=ok)
    # rounding error of each term theta m_z / |m| (first order): for small theta the term
    # is about m_z / (a . b), so the error of m_z dominates, bounded componentwise by the
    # magnitudes of its summands (Z); the error of |m| enters at relative order theta^2,
    # bounded by |a| |b| (at least the cross product's condition)
    Nm = np.sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(ok, tol.C2 * eps * (Z + theta * theta * Nm) / s,
                       np.where(Nm > 0, np.inf, 0.0))
    err = np.zeros(n_e, dtype=dt)
    err[kk] = theta * np.minimum(2.0, rel)
    # horizon arcs: each runs from an exit point to the next entry point along the line
    # where the polygon's plane meets z = 0; its term is the signed angle between them,
    # phi(entry) - phi(exit). phi is measured from the polygon's first crossing point:
    # the crossing points lie on one line not through the origin, so their angles from
    # any one of them stay within (-pi, pi), and short horizon arcs give small angles
    # (no cancellation between large ones)
    oc = owner[ci]
    X = A0[oc] + EX
    first_of = np.full(m, -1)
    first_of[oc[::-1]] = np.arange(len(ci))[::-1]
    f = X[first_of[oc], :2]
    phi = np.arctan2(f[:, 0] * X[:, 1] - f[:, 1] * X[:, 0], f[:, 0] * X[:, 0] + f[:, 1] * X[:, 1])
    terms[ci] += np.where(enter, phi, -phi)
    # per-polygon sums over contiguous blocks (reduceat keeps the dtype; bincount
    # would round longdouble to double)
    starts = np.searchsorted(owner, np.arange(m))
    sums = np.add.reduceat(terms, starts)
    mags = np.add.reduceat(np.abs(terms), starts)
    errs = np.add.reduceat(err + moved, starts)
    return sums, mags, errs


def offset_edge_planes(Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz):
    """Each edge's plane through the point in offset form, ``m = A x (Eb - Ea) + Ea x Eb``
    (``A`` the ring's first direction, ``Ea``, ``Eb`` the edge's ends' offsets from it,
    componentwise), and what the sector form and Eq. 3 take from it: ``m``, ``|m|``, the
    ends' directions ``a = A + Ea`` and ``b = A + Eb``, the arc's angle
    ``theta = atan2(|m|, a . b)`` and the magnitude ``Z`` of ``m_z``'s summands (its
    rounding's scale).

    Returns
    -------
    ((Mx, My, Mz), s, (ax, ay, az), (bx, by, bz), theta, Z), arrays of the edges' shape

    Examples
    --------
    >>> one, zero = np.ones(1), np.zeros(1)
    >>> (Mx, My, Mz), s, a, b, theta, Z = offset_edge_planes(
    ...     one, zero, zero, zero, zero, zero, -one, one, zero)
    >>> float(Mz[0]), round(float(theta[0] / (math.pi / 2)), 12)
    (1.0, 1.0)
    """
    Dx, Dy, Dz = Ebx - Eax, Eby - Eay, Ebz - Eaz
    p1, p2, p3, p4 = Ax * Dy, Ay * Dx, Eax * Eby, Eay * Ebx
    Mz = (p1 - p2) + (p3 - p4)
    Mx = (Ay * Dz - Az * Dy) + (Eay * Ebz - Eaz * Eby)
    My = (Az * Dx - Ax * Dz) + (Eaz * Ebx - Eax * Ebz)
    s = np.sqrt(Mx * Mx + My * My + Mz * Mz)
    ax, ay, az = Ax + Eax, Ay + Eay, Az + Eaz
    bx, by, bz = Ax + Ebx, Ay + Eby, Az + Ebz
    theta = np.arctan2(s, ax * bx + ay * by + az * bz)
    Z = np.abs(p1) + np.abs(p2) + np.abs(p3) + np.abs(p4)
    return (Mx, My, Mz), s, (ax, ay, az), (bx, by, bz), theta, Z


def _offset_rounding(A0, E, nxt, owner, eps):
    """Per edge, a first-order bound on how far the rounding of the offsets moves its
    polygon's sector sum (the sums' error model, C1 and C2, covers their own rounding
    only).

    The offsets are differences of the float input (from the point, and from the first
    vertex), each coordinate rounded once, then rotated to the local frame by a matrix
    of unit rows: a vertex's position ``A0 + E_i`` is off its true value by at most
    ``eta_i = gamma_8 (|A0| + |E_i|)`` (8: ``OFFSET_ROUNDING_ULPS``, for the differences'
    rounding, the rotation's gamma_3 per coordinate and the frame's own rounding). A
    boundary point at distance r moved by eta turns its direction by at most
    ``arcsin(eta / r)``, at most ``1.01 eta / r`` where ``eta / r <= 0.1``,
    ``(pi / 2) eta / r`` else; an edge's image
    then sweeps a solid angle of at most that times ``int dtheta / r``. Along the edge's
    line, with h its distance from the point and phi the angle from the line's
    direction, ``r = h / sin(phi)`` and ``dtheta = dphi``, so the integral is
    ``(cos(phi_a) - cos(phi_b)) / h``. The horizon clips both polygons alike: their
    clipped difference lies in the swept bands, and the projected measure is at most
    the solid angle. In sector-sum units (``F = S / 2 pi``, F the projected measure
    over pi) an edge adds ``2 eta_e k (cos(phi_a) - cos(phi_b)) / h``, k the turn's
    factor, eta_e its ends' larger eta. Edges wholly below the horizon by more than
    eta sweep nothing above it. An edge whose line passes within eta of the point gets
    4 pi, the whole range of a sum: its value is left to the higher tiers."""
    ulps = tol.OFFSET_ROUNDING_ULPS
    g = ulps * eps / (1 - ulps * eps)          # gamma_8
    size = np.linalg.norm(E, axis=1) + np.linalg.norm(A0, axis=1)[owner]
    eta = g * np.maximum(size, size[nxt])
    a = A0[owner] + E
    b = A0[owner] + E[nxt]
    d = b - a
    la, lb, ld = (np.linalg.norm(v, axis=1) for v in (a, b, d))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.linalg.norm(np.cross(a, b), axis=1) / ld
        # the angle phi runs over the edge: cos(phi) is d . v / (|d| |v|) at its ends
        # (each to a few roundings: OFFSET_ROUNDING_ULPS more, at most 2)
        span = np.minimum(np.abs(np.einsum("ij,ij->i", d, b) / (ld * lb)
                                 - np.einsum("ij,ij->i", d, a) / (ld * la)) + ulps * eps,
                          2.0)
        turn = np.where(eta <= 0.1 * h, 1.01, np.pi / 2)
        moved = np.where(h > eta, 2 * eta * turn * span / h, 4 * np.pi)
    reach = np.maximum(a[:, 2], b[:, 2]) + eta >= 0
    moved = np.where(np.isfinite(moved), np.minimum(moved, 4 * np.pi), 4 * np.pi)
    # an edge of no length (a ring padded by repeats) is no boundary: it sweeps nothing
    return np.where(reach & (ld > 0), moved, 0.0).astype(A0.dtype)


def sector_values(S, mags, errs, d0, two_sided, eps=tol.EPS, unchecked=None):
    """Form factors and their error estimates from signed sector sums ``S``
    (front-facing polygons have S < 0; without ``two_sided`` the others receive 0).
    ``unchecked`` marks values known to be unreliable, exempt from the sign check."""
    two_pi = TWO_PI_LONG if np.asarray(S).dtype == np.longdouble else TWO_PI
    F = np.sign(d0) * S / two_pi
    err = (tol.C1 * eps * mags + errs) / two_pi
    if not two_sided:
        F[d0 >= 0] = 0.0
        err[d0 >= 0] = 0.0
    # rounding can leave a value below 0 by at most its error estimate: there it is
    # clamped to 0, which the estimate still covers (0 <= exact <= F + err <= err);
    # beyond it, the value is a defect and raises
    return nonnegative(F, err, "form factor", unchecked, item="polygon"), err
