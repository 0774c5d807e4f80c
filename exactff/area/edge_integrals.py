"""The edge-pair integral of the contour form of Eq. 1,
``J = int_0^1 int_0^1 ln |a + s e - b - t f| ds dt``, in closed form: for skew edges by
dilogarithms, for parallel ones by elementary functions; in floats for many pairs at once
with the magnitude of its terms (its rounding scale), compiled
(``exactff/_core/closed_form.cpp``, the GIL released), and in mpmath for one pair (the
escalation, and the tests' oracle).
"""

import mpmath as mp
import numpy as np

from .. import _tolerances as tol
from ._closed import edge_log_integrals as _compiled_edge_log_integrals
from ._closed import row_pairs as _compiled_row_pairs

__all__ = ["edge_log_integrals", "edge_pair_sums", "mp_edge_log_integral"]

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
#
# Nearly parallel edges (a sine of at most AREA_CLOSED_NEAR_PARALLEL): the skew form's
# terms grow as 1 / sin (the lines' nearest points, the origin of its triangles, recede
# as 1 / sin), so the parallel form is also taken, about the longer edge with the shorter
# turned onto its direction: each point of the shorter moves by at most
# delta = |e x f| / F (F the longer's length), ln r by at most ln(1 + delta / min(r, r')),
# and the (s, t) where r < x measure at most 2 x / F (a chord of a ball of radius x, along
# the longer edge), so J moves by at most 4 (delta / F) (1 + ln(1 + F / (2 delta))),
# added to its magnitude (in units of its rounding). The form of the smaller estimate is
# kept. (mp_edge_log_integral keeps the skew form: its digits cover the 1 / sin.)


def edge_log_integrals(a, e, b, f):
    """``J = int_0^1 int_0^1 ln |a + s e - b - t f| ds dt`` for many edge pairs at once, in
    closed form (see the notes above; compiled, ``exactff/_core/closed_form.cpp``, with
    the dilogarithm of ``dilog.h``), and the sum of its terms' magnitudes.

    Parameters
    ----------
    a, e, b, f : ndarray of shape (N, 3)
        The edges ``a + s e`` (``s`` in [0, 1]) and ``b + t f``, of nonzero length.

    Returns
    -------
    (ndarray of shape (N,), ndarray of shape (N,))
        J, and the magnitudes whose rounding bounds its error (the caller's
        ``AREA_CLOSED_ULPS`` units of EPS of them; at least ``|J|``).

    Examples
    --------
    Two unit edges along x and y whose midpoints are 1 apart in z (the double integral
    by mpmath.quad: 0.07507018996444746):

    >>> x, y = np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]])
    >>> J, M = edge_log_integrals(-0.5 * x, x, [[0, -0.5, 1.0]], y)
    >>> round(float(J[0]), 14), bool(abs(J[0] - 0.07507018996444746) <= 4 * 2**-53 * M[0])
    (0.07507018996445, True)
    """
    a, e, b, f = (np.ascontiguousarray(x, dtype=float).reshape(-1, 3) for x in (a, e, b, f))
    return _compiled_edge_log_integrals(a, e, b, f, tol.AREA_CLOSED_THIN, tol.DOUBLE_TINY,
                                        tol.AREA_CLOSED_ULPS, tol.EPS,
                                        tol.AREA_CLOSED_NEAR_PARALLEL)


def edge_pair_sums(VP, po, VQ, qo, inv, scale):
    """A row's pairs summed in closed form, ``A_P F = (1 / 2 pi) sum (e . f) J`` over every
    edge pair, and each sum's rounding (``AREA_CLOSED_ULPS`` units of EPS of its terms'
    magnitudes), in one compiled call with the GIL released
    (``exactff/_core/closed_form.cpp``; :func:`edge_log_integrals` per edge pair).

    Parameters
    ----------
    VP, VQ : ndarray of shape (N, 3) and (N', 3)
        The pairs' emitter parts and receiver parts, concatenated rings.
    po, qo : ndarray of shape (m + 1,)
        Their offsets: pair p is ``VP[po[p]:po[p + 1]]`` and ``VQ[qo[p]:qo[p + 1]]``.
    inv : ndarray of shape (m,)
        Each pair's scale 1 / L (a power of 2): the edges are taken times it.
    scale : ndarray of shape (m,)
        Each pair's divisor, ``2 pi A_P / L^2``.

    Returns
    -------
    tuple
        ``(values, estimates)`` of shape (m,), and per edge pair kept (``e . f`` not 0,
        P's edges outer, Q's inner): ``owner`` (its pair), ``ip`` and ``iq`` (its edges'
        first vertices, rows of VP and VQ), ``ef`` (the scaled ``e . f``), ``J`` and ``c``
        (its rounding, ``AREA_CLOSED_ULPS EPS |e . f| M / scale``).

    Examples
    --------
    Unit squares facing each other 1 apart (Howell's C-11: 0.19982489570):

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = P[::-1] + [0, 0, 1]
    >>> out = edge_pair_sums(P, [0, 4], Q, [0, 4], [1.0], [2 * np.pi])
    >>> round(float(out[0][0]), 11), len(out[2])
    (0.1998248957, 8)
    """
    as_float = lambda x: np.ascontiguousarray(x, dtype=float)      # noqa: E731
    as_int = lambda x: np.ascontiguousarray(x, dtype=np.int64)      # noqa: E731
    return _compiled_row_pairs(as_float(VP), as_int(po), as_float(VQ), as_int(qo), as_float(inv),
                             as_float(scale), tol.AREA_CLOSED_THIN, tol.DOUBLE_TINY,
                             tol.AREA_CLOSED_ULPS, tol.EPS, tol.AREA_CLOSED_NEAR_PARALLEL)


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
