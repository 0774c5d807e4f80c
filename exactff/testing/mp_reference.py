"""Independent high-precision reference values (mpmath), written apart from the kernels.

``boundary_form_factor``: Green's theorem on the image in the base disk, the line
integral 1/2 (x dy - y dx) along each edge's image evaluated by mpmath quadrature
(for a straight edge P(t) = a + t (b - a) it reduces to (a x b)_z / |P(t)|^2 dt).

``area_form_factor``: the defining double integral (1 / pi) cos(theta_p) cos(theta_j) / r^2
over the (horizon-clipped) polygon, by mpmath 2-D quadrature on a triangle fan.

``solid_angle``: the solid angle of a polygon, Van Oosterom and Strackee's triangle
formula (IEEE Trans. Biomed. Eng. 30, 1983, doi:10.1109/TBME.1983.325207) summed with
signs over a fan from the mean of the vertices (not from a vertex, as the kernel's).
"""

import mpmath as mp

from ..checks import check_sides

__all__ = ["boundary_form_factor", "area_form_factor", "solid_angle"]


def _frame(n):
    n = [mp.mpf(c) for c in n]
    ln = mp.sqrt(sum(c * c for c in n))
    n = [c / ln for c in n]
    # any vector not parallel to n, Gram-Schmidt
    k = min(range(3), key=lambda i: abs(n[i]))
    e = [mp.mpf(0)] * 3
    e[k] = mp.mpf(1)
    d = sum(e[i] * n[i] for i in range(3))
    t1 = [e[i] - d * n[i] for i in range(3)]
    l1 = mp.sqrt(sum(c * c for c in t1))
    t1 = [c / l1 for c in t1]
    t2 = [n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]]
    return t1, t2, n


def _local(point, normal, polygon):
    t1, t2, n = _frame(normal)
    p = [mp.mpf(float(c)) for c in point]
    Q = []
    for v in polygon:
        r = [mp.mpf(float(v[i])) - p[i] for i in range(3)]
        Q.append([sum(r[i] * e[i] for i in range(3)) for e in (t1, t2, n)])
    return Q


def _newell(Q):
    N = [mp.mpf(0)] * 3
    k = len(Q)
    for i in range(k):
        a, b = Q[i], Q[(i + 1) % k]
        N[0] += (a[1] - b[1]) * (a[2] + b[2])
        N[1] += (a[2] - b[2]) * (a[0] + b[0])
        N[2] += (a[0] - b[0]) * (a[1] + b[1])
    return N


def _clip(Q):
    out = []
    k = len(Q)
    for i in range(k):
        a, b = Q[i], Q[(i + 1) % k]
        if a[2] > 0:
            out.append(a)
        if (a[2] > 0) != (b[2] > 0):
            t = a[2] / (a[2] - b[2])
            out.append([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), mp.mpf(0)])
    return out


def _side(Q):
    N = _newell(Q)
    c = [sum(v[i] for v in Q) / len(Q) for i in range(3)]
    return sum(N[i] * c[i] for i in range(3)), N


def boundary_form_factor(point, normal, polygon, two_sided=False, dps=40, *, one_sided=None):
    """F by mpmath quadrature of the image's boundary integral, at ``dps`` digits; with
    ``two_sided`` the polygon's back receives too (``one_sided=``: its deprecated old
    name, ``one_sided = not two_sided``)."""
    two_sided = check_sides(two_sided, one_sided)
    with mp.workdps(dps):
        Q = _local(point, normal, polygon)
        d, _ = _side(Q)  # < 0: p in front
        if d == 0 or (not two_sided and d > 0):
            return mp.mpf(0)
        C = _clip(Q)
        area = mp.mpf(0)
        for i in range(len(C)):
            a, b = C[i], C[(i + 1) % len(C)]
            cz = a[0] * b[1] - a[1] * b[0]
            if cz == 0:
                continue

            def f(t, a=a, b=b):
                P = [a[j] + t * (b[j] - a[j]) for j in range(3)]
                return 1 / (P[0] ** 2 + P[1] ** 2 + P[2] ** 2)

            # the integrand peaks where the edge passes closest to p: split there, and
            # at a geometric ladder of widths around it, so that tanh-sinh resolves it
            e = [b[j] - a[j] for j in range(3)]
            ee = sum(x * x for x in e)
            ts = -sum(a[j] * e[j] for j in range(3)) / ee
            h = mp.sqrt(max(sum(x * x for x in a) - ts * ts * ee, mp.mpf(0)) / ee)
            cuts = {mp.mpf(0), mp.mpf(1)}
            for k in range(-2, 40):
                for c in (ts - h * 2 ** k, ts, ts + h * 2 ** k):
                    if 0 < c < 1:
                        cuts.add(c)
            area += cz * mp.quad(f, sorted(cuts)) / 2
        F = -area / mp.pi if d < 0 else area / mp.pi
        return F


def area_form_factor(point, normal, polygon, dps=20):
    """F by 2-D mpmath quadrature of cos cos / (pi r^2) over the clipped polygon
    (front-facing side only; a fan triangulation, so the polygon must be convex)."""
    with mp.workdps(dps):
        Q = _local(point, normal, polygon)
        d, N = _side(Q)
        if d >= 0:
            return mp.mpf(0)
        lN = mp.sqrt(sum(c * c for c in N))
        dist = -d / lN  # distance of p from the polygon's plane
        C = _clip(Q)
        total = mp.mpf(0)
        for i in range(1, len(C) - 1):
            a, b, c = C[0], C[i], C[i + 1]
            e1 = [b[j] - a[j] for j in range(3)]
            e2 = [c[j] - b[j] for j in range(3)]
            cr = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                  e1[0] * e2[1] - e1[1] * e2[0]]
            jac = mp.sqrt(sum(x * x for x in cr))

            def f(u, v, a=a, e1=e1, e2=e2, jac=jac):
                x = [a[j] + u * e1[j] + u * v * e2[j] for j in range(3)]
                r2 = x[0] ** 2 + x[1] ** 2 + x[2] ** 2
                return x[2] * dist / (mp.pi * r2 * r2) * u * jac

            total += mp.quad(f, [0, 1], [0, 1])
        return total


def solid_angle(point, polygon, dps=40):
    """The solid angle of a planar polygon seen from ``point``, whichever way it faces,
    at ``dps`` digits: ``tan(Omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b|
    + (b.c)|a|)`` for each triangle (apex: the mean of the vertices, in the polygon's
    plane), signed, summed, the absolute value taken. Any simple polygon whose plane
    misses the point."""
    with mp.workdps(dps):
        p = [mp.mpf(float(c)) for c in point]
        Q = [[mp.mpf(float(v[i])) - p[i] for i in range(3)] for v in polygon]
        k = len(Q)
        a = [sum(v[i] for v in Q) / k for i in range(3)]

        def dot(x, y):
            return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]

        la = mp.sqrt(dot(a, a))
        total = mp.mpf(0)
        for j in range(k):
            b, c = Q[j], Q[(j + 1) % k]
            bxc = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2], b[0] * c[1] - b[1] * c[0]]
            lb, lc = mp.sqrt(dot(b, b)), mp.sqrt(dot(c, c))
            den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la
            total += 2 * mp.atan2(dot(a, bxc), den)
        return abs(total)
