"""Planar-polygon geometry: Newell area vectors, normals, centroids and receiver frames."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import ConvexHull, QhullError

from . import _tolerances as tol

__all__ = [
    "hull_blockers", "point_polygon_distance",
    "to_local",
    "rotate",
    "area_vector",
    "cross",
    "polygon_area",
    "unit_normal",
    "polygon_centroid",
    "polygon_diameter",
    "receiver_frame",
    "mp_receiver_frame",
    "plane_frame",
]


def area_vector(polygon: ArrayLike) -> np.ndarray:
    """Newell area vector of a closed polygon, computed relative to its first vertex.

    Parameters
    ----------
    polygon : array_like of shape (K, 3)
        Vertices, counter-clockwise seen from the front.

    Returns
    -------
    ndarray of shape (3,)
        Half the sum of ``(v_i - v_0) x (v_{i+1} - v_0)``: its length is the area of a
        planar polygon and its direction the front (right-hand) normal. Working relative
        to a vertex keeps the result accurate far from the origin.

    Examples
    --------
    >>> area_vector([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]]).tolist()
    [0.0, 0.0, 2.0]
    """
    P = np.asarray(polygon, dtype=float)
    Q = P - P[0]
    # (v_i - v_0) x (v_{i+1} - v_0) for i = 1 .. K-2: the two terms with v_0 are zero
    return 0.5 * cross(Q[1:-1], Q[2:]).sum(axis=0)


def cross(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Cross product over the last axis (of length 3), broadcast over the others.

    The same products and differences as :func:`numpy.cross` (bit-identical values)
    without its set-up, which costs more than the arithmetic on the short arrays of
    the area code's inner loops.

    Parameters
    ----------
    a, b : array_like of shape (..., 3)

    Returns
    -------
    ndarray of shape broadcast(a, b), float

    Examples
    --------
    >>> cross([1, 0, 0], [[0, 1, 0], [0, 0, 1]]).tolist()
    [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def polygon_area(polygon: ArrayLike) -> float:
    """Area of a planar polygon, the length of its Newell area vector.

    Examples
    --------
    >>> polygon_area([[0, 0, 5], [3, 0, 5], [0, 4, 5]])
    6.0
    """
    return float(np.linalg.norm(area_vector(polygon)))


def unit_normal(polygon: ArrayLike) -> np.ndarray:
    """Unit front normal (right-hand rule, Newell's normal for K > 3).

    Examples
    --------
    >>> unit_normal([[0, 0, 0], [0, 1, 0], [0, 0, 1]]).tolist()
    [1.0, 0.0, 0.0]
    """
    A = area_vector(polygon)
    return A / np.linalg.norm(A)


def polygon_centroid(polygon: ArrayLike) -> np.ndarray:
    """Area centroid of a planar polygon (triangle fan from the first vertex).

    For a non-convex polygon the centroid may lie outside the polygon.

    Examples
    --------
    >>> polygon_centroid([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]).tolist()
    [1.0, 1.0, 0.0]
    """
    P = np.asarray(polygon, dtype=float)
    Q = P - P[0]
    N = area_vector(P)
    # fan triangles (0, i, i+1): signed area along N, centroid (q_i + q_{i+1}) / 3
    w = cross(Q[1:-1], Q[2:]) @ N
    c = ((Q[1:-1] + Q[2:]) / 3.0 * w[:, None]).sum(axis=0) / w.sum()
    return P[0] + c


def polygon_diameter(polygon: ArrayLike) -> float:
    """Largest distance between two vertices.

    Exact (all pairs) up to 128 vertices. Beyond, in O(K log K) time and O(K) memory:
    the vertices are projected onto their best-fit plane, and the farthest pair among
    the vertices of their convex hull is found by rotating calipers (the distance is
    then measured in 3-D between the original vertices; for a planar polygon the pair
    is the diameter's, up to the vertices' distances from the plane).

    Examples
    --------
    >>> polygon_diameter([[0, 0, 0], [3, 0, 0], [3, 4, 0]])
    5.0
    >>> t = np.linspace(0, 2 * np.pi, 5000, endpoint=False)
    >>> round(polygon_diameter(np.column_stack([np.cos(t), np.sin(t), 0 * t])), 12)
    2.0
    """
    P = np.asarray(polygon, dtype=float)
    if len(P) <= 128:
        D = P[:, None, :] - P[None, :, :]
        return float(np.sqrt((D * D).sum(axis=-1)).max())
    from scipy.spatial import ConvexHull, QhullError

    c = P.mean(axis=0)
    _, _, vt = np.linalg.svd(P - c, full_matrices=False)
    Q = (P - c) @ vt[:2].T
    try:
        H = ConvexHull(Q).vertices          # counter-clockwise
    except QhullError:                      # collinear: the extreme points along vt[0]
        return float(np.linalg.norm(P[np.argmax(Q[:, 0])] - P[np.argmin(Q[:, 0])]))
    h, Qh, Ph = len(H), Q[H], P[H]
    best, j = 0.0, 1
    for i in range(h):
        e = Qh[(i + 1) % h] - Qh[i]
        # advance the antipodal vertex while it moves away from edge i
        while True:
            a = Qh[j] - Qh[i]
            b = Qh[(j + 1) % h] - Qh[i]
            if e[0] * b[1] - e[1] * b[0] > e[0] * a[1] - e[1] * a[0]:
                j = (j + 1) % h
            else:
                break
        for k in (i, (i + 1) % h):
            best = max(best, float(np.linalg.norm(Ph[k] - Ph[j])))
    return best


def receiver_frame(normal: ArrayLike, dtype=float) -> np.ndarray:
    """Orthonormal frame ``(t1, t2, n)`` with ``n`` the unit receiver normal.

    The rows of the result map world vectors into the local frame of a receiver:
    ``local = R @ v`` has z along ``n``. Uses the branch-free construction of
    Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017.

    Parameters
    ----------
    normal : array_like of shape (3,), or (R, 3) for many normals
        Normal (scaled to unit length here).
    dtype : numpy float type, default float
        Working precision (``numpy.longdouble`` for the second escalation tier).

    Returns
    -------
    ndarray of shape (3, 3), or (R, 3, 3)
        Rows t1, t2, n; a rotation (determinant +1). Many normals' frames are each
        normal's own, the same arithmetic.

    Examples
    --------
    >>> R = receiver_frame([0.0, 0.0, 1.0])
    >>> bool(np.allclose(R, np.eye(3)))
    True
    >>> receiver_frame([[0.0, 0.0, 1.0], [0.0, 0.0, -2.0]])[:, 2].tolist()
    [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    """
    nv = np.asarray(normal).astype(dtype)
    if nv.ndim == 2:
        u = nv / np.sqrt(np.sum(nv * nv, axis=1, keepdims=True))
        x, y, z = u[:, 0], u[:, 1], u[:, 2]
        one = nv.dtype.type(1)
        sign = np.where(z >= 0, one, -one)
        a = -one / (sign + z)
        b = x * y * a
        return np.stack([np.stack([one + sign * x * x * a, sign * b, -sign * x], axis=1),
                         np.stack([b, sign + y * y * a, -y], axis=1),
                         np.stack([x, y, z], axis=1)], axis=1)
    x, y, z = nv / np.sqrt(np.sum(nv * nv))
    one = nv.dtype.type(1)
    sign = one if z >= 0 else -one
    a = -one / (sign + z)
    b = x * y * a
    return np.array([[one + sign * x * x * a, sign * b, -sign * x],
                     [b, sign + y * y * a, -y],
                     [x, y, z]], dtype=dtype)


def mp_receiver_frame(normal):
    """:func:`receiver_frame` in mpmath numbers at the working precision: the same
    construction, so that charts, seams and tiles are where the float frame has them.

    Parameters
    ----------
    normal : array_like of shape (3,)
        Floats, taken as exact.

    Returns
    -------
    tuple of three lists of mpf
        The rows t1, t2, n.

    Examples
    --------
    >>> import mpmath as mp
    >>> with mp.workdps(40):
    ...     t1, t2, n = mp_receiver_frame([0.0, 0.0, 2.0])
    >>> [float(c) for c in n]
    [0.0, 0.0, 1.0]
    """
    import mpmath as mp

    nv = [mp.mpf(float(c)) for c in normal]
    ln = mp.sqrt(sum(c * c for c in nv))
    x, y, z = (c / ln for c in nv)
    sign = 1 if z >= 0 else -1
    a = -1 / (sign + z)
    b = x * y * a
    return ([1 + sign * x * x * a, sign * b, -sign * x], [b, sign + y * y * a, -y], [x, y, z])


def to_local(X: np.ndarray, p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``(X - p) @ R.T`` evaluated elementwise, the same rounding for every row.

    A matrix product may round a row differently depending on where it sits in the
    array (blocked kernels, fused multiply-adds); here a vertex shared by several
    polygons always maps to the same local coordinates.

    Parameters
    ----------
    X : ndarray of shape (..., 3)
    p : ndarray of shape (3,)
    R : ndarray of shape (3, 3)
        Rows are the local axes (see :func:`receiver_frame`).

    Examples
    --------
    >>> to_local(np.array([[1.0, 2.0, 3.0]]), np.zeros(3), np.eye(3)).tolist()
    [[1.0, 2.0, 3.0]]
    """
    return rotate(X - p, R)


def rotate(D: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``D @ R.T`` evaluated elementwise (see :func:`to_local`).

    Examples
    --------
    >>> rotate(np.array([[1.0, 2.0, 3.0]]), np.eye(3)[[1, 2, 0]]).tolist()
    [[2.0, 3.0, 1.0]]
    """
    x, y, z = D[..., 0], D[..., 1], D[..., 2]
    out = np.empty(D.shape, dtype=np.result_type(D, R))
    for k in range(3):
        out[..., k] = x * R[k, 0] + y * R[k, 1] + z * R[k, 2]
    return out


def plane_frame(Q: ArrayLike):
    """A planar polygon's unit normal, origin (its first vertex), frame (rows t1, t2, n:
    :func:`receiver_frame` of the normal) and 2-D coordinates in that frame.

    Returns
    -------
    (ndarray of shape (3,), ndarray of shape (3,), ndarray of shape (3, 3), ndarray of shape (K, 2))

    Examples
    --------
    >>> n, q0, R, Q2 = plane_frame([[0, 0, 1], [2, 0, 1], [2, 1, 1], [0, 1, 1]])
    >>> n.tolist(), q0.tolist(), R[2].tolist(), Q2.shape
    ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], (4, 2))
    """
    Q = np.asarray(Q, dtype=float)
    nQ = unit_normal(Q)
    RQ = receiver_frame(nQ)
    return nQ, Q[0], RQ, (Q - Q[0]) @ RQ[:2].T


def point_polygon_distance(p: ArrayLike, polygon: ArrayLike) -> float:
    """A lower bound on the distance from a point to a planar polygon (its closed
    region), in float.

    The distance to the plane where the point's projection lies in the polygon (by the
    winding number of its projection on the coordinate plane the normal is most nearly
    perpendicular to), else the least distance to an edge less
    ``FLOAT_DISTANCE_RTOL`` of the polygon's extent (a projection within rounding of
    the boundary may be taken as outside), and at least the distance to the plane. A
    polygon without area (its vertices on a line, as a BSP sliver's can round) is its
    edges.

    Parameters
    ----------
    p : array_like of shape (3,)
    polygon : array_like of shape (K, 3)

    Returns
    -------
    float

    Examples
    --------
    >>> sq = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]
    >>> point_polygon_distance([1, 1, 3], sq), point_polygon_distance([5, 1, 0], sq)
    (3.0, 2.999999999998)
    >>> point_polygon_distance([0, 3, 0], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    2.999999999995
    """
    P = np.asarray(polygon, dtype=float)
    x = np.asarray(p, dtype=float)
    E = np.roll(P, -1, axis=0) - P
    t = np.clip(np.einsum("ij,ij->i", x - P, E) / np.maximum(np.einsum("ij,ij->i", E, E),
                                                            np.finfo(float).tiny), 0.0, 1.0)
    edges = float(np.linalg.norm(P + t[:, None] * E - x, axis=1).min())
    extent = float(np.abs(P - P[0]).max())
    A = area_vector(P)
    size = float(np.linalg.norm(A))
    if not size > 0:
        # no area (a BSP sliver whose vertices rounded onto a line): its edges are all of it
        return max(0.0, edges * (1 - tol.FLOAT_DISTANCE_RTOL) - tol.FLOAT_DISTANCE_RTOL * extent)
    n = A / size
    height = float(n @ (x - P[0]))
    axis = int(np.argmax(np.abs(n)))
    keep = [a for a in range(3) if a != axis]
    q, R = x[keep], P[:, keep]
    S = np.roll(R, -1, axis=0)
    # winding number of q about the projected ring
    up = (R[:, 1] <= q[1]) & (S[:, 1] > q[1])
    down = (R[:, 1] > q[1]) & (S[:, 1] <= q[1])
    side = (S[:, 0] - R[:, 0]) * (q[1] - R[:, 1]) - (q[0] - R[:, 0]) * (S[:, 1] - R[:, 1])
    if int(np.sum(up & (side > 0)) - np.sum(down & (side < 0))) != 0:
        return abs(height)
    return max(abs(height), edges - tol.FLOAT_DISTANCE_RTOL * extent)


def hull_blockers(V, cand, Pc, Qc, near, *, none_if_flat=False):
    """The candidates reaching into the interior of the convex hull of two point sets.

    A polygon on or outside one face of the hull hides nothing of positive measure
    between the two sets (the lines of sight from Pc to Qc lie in the hull); the test
    takes each candidate's vertices against each face, as they are (no hull of the
    polygon), so it keeps every polygon the hull's faces do not separate. The hull is
    qhull's. Area rows take the same test compiled
    (:func:`exactff.area.culling.row_blockers`), with this as its reference; the point
    engine's shafts take it as it is (:mod:`exactff.visibility.compiled`).

    Parameters
    ----------
    V : ndarray of shape (n, k, 3)
        Polygons padded to k vertices (a short one repeats a vertex).
    cand : array_like of int
        Indices into V of the candidates.
    Pc, Qc : ndarray of shape (a, 3) and (b, 3)
        The two point sets (a point and a polygon, two polygons).
    near : float
        How far beyond a face a polygon's vertices must all lie for it to be dropped:
        0 for the exact separation, negative to keep polygons within ``-near`` of the
        hull.
    none_if_flat : bool, default False
        Where the points span no solid hull (a flat pair): None instead of no candidate.

    Returns
    -------
    list of int
        The candidates kept (None for a flat pair with ``none_if_flat``).

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],      # between
    ...                [[0, 0, 5], [1, 0, 5], [1, 1, 5], [0, 1, 5]]], float)  # beyond
    >>> ground = np.array([[-1, -1, 2], [2, -1, 2], [2, 2, 2], [-1, 2, 2]], float)
    >>> hull_blockers(sq, [0, 1], np.zeros((1, 3)), ground, 0.0)
    [0]
    """
    if len(cand) == 0:
        return []
    try:
        H = ConvexHull(np.vstack([Pc, Qc])).equations      # a . x + b <= 0 inside
    except QhullError:
        return None if none_if_flat else []
    outside = np.all(V[cand] @ H[:, :3].T + H[:, 3] >= -near, axis=1)      # (c, faces)
    return [int(k) for k in np.asarray(cand)[~outside.any(axis=1)]]
