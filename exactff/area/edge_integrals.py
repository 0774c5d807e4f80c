"""The edge-pair integral of the contour form of Eq. 1,
``J = int_0^1 int_0^1 ln |a + s e - b - t f| ds dt``, in closed form: for skew edges by
dilogarithms, for parallel ones by elementary functions; in floats for many pairs at once
with the magnitude of its terms (its rounding scale), and in mpmath for one pair.
"""

import mpmath as mp
import numpy as np
from scipy.special import spence, xlogy

from .. import _tolerances as tol
from ..geometry import cross

__all__ = ["edge_log_integrals", "mp_edge_log_integral"]

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


def edge_log_integrals(a, e, b, f):
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


def mp_edge_log_integral(a, e, b, f):
    """J of one edge pair (mpmath vectors of 3), in mpmath at its working precision, and
    the magnitude of its terms (what its rounding is relative to): the same closed form as
    :func:`edge_log_integrals` (``mp.polylog`` for the dilogarithm inside the unit disk,
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
