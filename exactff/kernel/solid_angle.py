"""Solid angles of planar polygons seen from a point, vectorised over edges: Van Oosterom
and Strackee's triangle formula summed over a fan, in offset form, with a rounding-error
bound. The measure of the spherical (4 pi) factors, beside the cosine-weighted sector
sums (:mod:`exactff.kernel.sector`)."""

import numpy as np

from .. import _tolerances as tol
from .ladder import mp_converge

__all__ = ["solid_angle_sums", "polygon_solid_angles", "offset_error", "mp_solid_angle"]


def solid_angle_sums(A0, E, nxt, owner, m, eps=tol.EPS):
    """Signed solid angles of planar polygons seen from the origin, with error bounds.

    Each polygon is a fan of triangles ``(a, b, c) = (A0, A0 + E_k, A0 + E_k+1)`` over
    its edges ``k -> nxt[k]``; each triangle's signed solid angle is Van Oosterom and
    Strackee's::

        tan(Omega / 2) = a . (b x c) / (|a||b||c| + (a.b)|c| + (a.c)|b| + (b.c)|a|),

    evaluated as ``2 atan2(N, D)`` (the right branch for any triangle), with the
    numerator in offset form, ``N = A0 . (E_k x E_k+1)``, which stays accurate for
    polygons small next to their distance. For a polygon in a plane that misses the
    origin the fan's sum is the polygon's signed solid angle (positive when its vertices
    run counter-clockwise seen from the origin), holes and non-convex rings included.

    Parameters
    ----------
    A0 : ndarray of shape (m, 3)
        A reference vertex of each polygon (relative to the viewpoint).
    E : ndarray of shape (V, 3)
        Every vertex's offset from its polygon's reference vertex (the reference
        vertex's own offset 0 gives degenerate triangles, which add exactly 0).
    nxt : ndarray of shape (V,)
        Each vertex's successor in its polygon.
    owner : ndarray of shape (V,)
        Each vertex's polygon, sorted (each polygon's vertices contiguous).
    m : int
        Number of polygons.
    eps : float
        Unit roundoff of the working precision.

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,))
        Signed solid angles (steradians) and bounds on their rounding errors, for the
        inputs taken as exact: per triangle the rounding of ``N`` and ``D`` (``C1 eps``
        times the sums of their terms' magnitudes) carried through the atan2, plus the
        atan2's and the sum's own rounding.

    References
    ----------
    A. van Oosterom and J. Strackee, "The solid angle of a plane triangle", IEEE Trans.
    Biomed. Eng. BME-30 (2), 125-126, 1983, doi:10.1109/TBME.1983.325207.

    Examples
    --------
    A unit square at height 1/2 centred over the origin subtends 2 pi / 3 (a face of a
    cube from its centre):

    >>> A0 = np.array([[-0.5, -0.5, 0.5]])
    >>> E = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> S, err = solid_angle_sums(A0, E, np.array([1, 2, 3, 0]), np.zeros(4, int), 1)
    >>> bool(abs(S[0] - 2 * np.pi / 3) < 1e-15), bool(err[0] < 1e-14)
    (True, True)
    """
    A = A0[owner]
    B = E
    C = E[nxt]
    # N = a . (b x c) = A0 . (E_k x E_k+1)
    p = (B[:, 1] * C[:, 2], B[:, 2] * C[:, 1], B[:, 2] * C[:, 0], B[:, 0] * C[:, 2],
         B[:, 0] * C[:, 1], B[:, 1] * C[:, 0])
    N = A[:, 0] * (p[0] - p[1]) + A[:, 1] * (p[2] - p[3]) + A[:, 2] * (p[4] - p[5])
    TN = (np.abs(A[:, 0]) * (np.abs(p[0]) + np.abs(p[1]))
          + np.abs(A[:, 1]) * (np.abs(p[2]) + np.abs(p[3]))
          + np.abs(A[:, 2]) * (np.abs(p[4]) + np.abs(p[5])))
    b, c = A + B, A + C
    la = np.sqrt(np.einsum("ij,ij->i", A, A))
    lb = np.sqrt(np.einsum("ij,ij->i", b, b))
    lc = np.sqrt(np.einsum("ij,ij->i", c, c))
    D = (la * lb * lc + np.einsum("ij,ij->i", A, b) * lc + np.einsum("ij,ij->i", A, c) * lb
         + np.einsum("ij,ij->i", b, c) * la)
    TD = 4.0 * la * lb * lc          # |a.b| <= |a||b|: a bound on the terms' magnitudes
    theta = np.arctan2(N, D)
    eN, eD = tol.C1 * eps * TN, tol.C1 * eps * TD
    r2 = N * N + D * D
    with np.errstate(divide="ignore", invalid="ignore"):
        dtheta = np.where(r2 > 0, (np.abs(D) * eN + np.abs(N) * eD) / r2, 0.0)
    # a perturbation too large for the first-order bound: the whole range of the angle
    dtheta = np.minimum(dtheta, np.pi)
    omega = 2.0 * theta
    err = 2.0 * dtheta + 4.0 * eps * np.abs(theta)
    starts = np.searchsorted(owner, np.arange(m))
    S = np.add.reduceat(omega, starts) if len(owner) else np.zeros(m)
    mags = np.add.reduceat(np.abs(omega), starts) if len(owner) else np.zeros(m)
    errs = np.add.reduceat(err, starts) if len(owner) else np.zeros(m)
    counts = np.diff(np.append(starts, len(owner)))
    # empty polygons (no vertex) add nothing; reduceat repeats a neighbour there
    empty = counts == 0
    S[empty] = mags[empty] = errs[empty] = 0.0
    # the sum's rounding: at most (count - 1) eps of its magnitudes
    return S, errs + counts * eps * mags


def polygon_solid_angles(point, polygons, *, error=False):
    """Unoccluded solid angles of polygons seen from a point, whichever way they face.

    Parameters
    ----------
    point : array_like of shape (3,)
    polygons : sequence of array_like of shape (K, 3)
        Planar polygons (each in a plane that misses ``point``).
    error : bool, default False
        Also return a bound on each value's error: the rounding of the fan's sum plus
        the rounding of the vertices' offsets from the point (each vertex moved by at
        most ``eps`` of its offset sweeps a strip along the boundary, whose solid angle
        is at most its area over the squared distance from the point to the boundary).

    Returns
    -------
    ndarray of shape (len(polygons),), or a pair of them with ``error=True``
        Solid angles in steradians, in ``[0, 2 pi)``.

    Examples
    --------
    A face of the unit cube from its centre: 4 pi / 6.

    >>> face = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> w = polygon_solid_angles([0.5, 0.5, 0.5], [face])
    >>> round(float(w[0] / (4 * np.pi)), 15)
    0.166666666666667
    """
    p = np.asarray(point, dtype=float)
    P = [np.asarray(q, dtype=float) for q in polygons]
    counts = np.array([len(q) for q in P], dtype=int)
    if len(P) == 0:
        z = np.zeros(0)
        return (z, z.copy()) if error else z
    V = np.concatenate(P)
    owner = np.repeat(np.arange(len(P)), counts)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    nxt = np.arange(len(V)) + 1
    nxt[starts + counts - 1] = starts
    A0 = V[starts] - p
    E = V - V[starts][owner]
    S, err = solid_angle_sums(A0, E, nxt, owner, len(P))
    W = np.abs(S)
    if not error:
        return W
    return W, err + offset_error(A0, E, nxt, owner, len(P))


def offset_error(A0, E, nxt, owner, m, eps=tol.EPS):
    """A bound on the solid-angle error that the rounding of the offsets brings.

    The offsets ``A0`` (from the viewpoint) and ``E`` (from the reference vertex) were
    rounded once each, so every vertex is off by at most ``eps`` of each coordinate of
    both (the 1-norms, twice); moving every vertex by at most a width ``w`` sweeps a
    strip of at most ``w`` times the perimeter along the boundary, whose solid angle is
    at most its area over the squared distance from the viewpoint to the boundary
    (``dOmega = h dA / r^3 <= dA / r^2``). Arguments as :func:`solid_angle_sums`.

    Returns
    -------
    ndarray of shape (m,)
        Infinite for a viewpoint on a polygon's boundary.

    Examples
    --------
    >>> A0 = np.array([[-0.5, -0.5, 0.5]])
    >>> E = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> e = offset_error(A0, E, np.array([1, 2, 3, 0]), np.zeros(4, int), 1)
    >>> bool(0 < e[0] < 1e-14)
    True
    """
    A = A0[owner]
    a, b = A + E, A + E[nxt]
    e = b - a
    ee = np.einsum("ij,ij->i", e, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.where(ee > 0, -np.einsum("ij,ij->i", a, e) / ee, 0.0), 0.0, 1.0)
    closest = a + t[:, None] * e
    d2 = np.einsum("ij,ij->i", closest, closest)
    starts = np.searchsorted(owner, np.arange(m))
    dmin2 = np.minimum.reduceat(d2, starts)
    perimeter = np.add.reduceat(np.sqrt(ee), starts)
    width = 2.0 * eps * (np.abs(A0).sum(axis=1)
                         + np.maximum.reduceat(np.abs(E).sum(axis=1), starts))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(dmin2 > 0, width * perimeter / dmin2, np.inf)


def mp_solid_angle(point, polygon, *, tolerance=tol.DEFAULT_RTOL):
    """The solid angle of a polygon seen from a point, in mpmath.

    Whichever way the polygon faces; the same fan as :func:`solid_angle_sums`, from the
    float input, at growing precision until two evaluations agree
    (:func:`exactff.kernel.ladder.mp_converge`): the last tier of the spherical
    factors' unoccluded values.

    Returns
    -------
    (float, float)
        The value (steradians) and a bound on its error (the two evaluations'
        difference plus the final rounding).

    Examples
    --------
    >>> w, e = mp_solid_angle([0.5, 0.5, 0.5], [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    >>> round(w / (4 * np.pi), 15), e < 1e-15
    (0.166666666666667, True)
    """
    import mpmath as mp

    P = np.asarray(polygon, dtype=float)
    p = np.asarray(point, dtype=float)

    def evaluate(dps):
        with mp.workdps(dps):
            pp = [mp.mpf(float(c)) for c in p]
            Q = [[mp.mpf(float(v[i])) - pp[i] for i in range(3)] for v in P]
            a = Q[0]
            la = mp.sqrt(sum(x * x for x in a))
            total = mp.mpf(0)
            for k in range(1, len(Q) - 1):
                b, c = Q[k], Q[k + 1]
                bc = [b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2],
                      b[0] * c[1] - b[1] * c[0]]
                N = sum(a[i] * bc[i] for i in range(3))
                lb = mp.sqrt(sum(x * x for x in b))
                lc = mp.sqrt(sum(x * x for x in c))
                D = (la * lb * lc + sum(a[i] * b[i] for i in range(3)) * lc
                     + sum(a[i] * c[i] for i in range(3)) * lb
                     + sum(b[i] * c[i] for i in range(3)) * la)
                total += 2 * mp.atan2(N, D)
            return abs(total)

    value, diff, _ = mp_converge(evaluate, tolerance)
    w = float(value)
    return w, float(diff) + tol.EPS * w
