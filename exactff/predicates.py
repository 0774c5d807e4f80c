"""Exact-sign predicates: float evaluation with an error bound, exact rational fallback.

The only place where exactff decides on which side of a plane a point lies.
"""

from fractions import Fraction

import numpy as np

from ._tolerances import BSP_COPLANAR_ULPS, EPS, ON_PLANE_ULPS, PLANE_SIDE_ULPS

__all__ = ["side_of_plane", "gamma", "tie_priority", "exact_side", "polygon_side",
           "plane_distances", "plane_sides", "point_plane_offsets", "sides_of_point", "coplanar_band",
           "polygon_coplanar_bands", "coplanar_pairs", "coplanar_band_sides",
           "engine_sides", "collinear", "in_plane_band", "orient2d", "polygons_apart"]


def gamma(n):
    """Higham's bound ``n u / (1 - n u)`` on the relative error of n roundings."""
    return n * EPS / (1 - n * EPS)


def side_of_plane(points, normal, offset):
    """Exact sign of ``normal @ x - offset`` for each point ``x``.

    The plane is the one the float numbers ``normal`` and ``offset`` describe exactly.
    The value is computed in float with the bound ``gamma(4) (|n| . |x| + |offset|)``;
    only inside that bound is it recomputed with :class:`fractions.Fraction`, which is
    exact for floats.

    Parameters
    ----------
    points : array_like of shape (M, 3)
    normal : array_like of shape (3,)
    offset : float

    Returns
    -------
    ndarray of shape (M,), dtype int8
        +1 in front (the side ``normal`` points to), -1 behind, 0 exactly on the plane.

    Examples
    --------
    >>> side_of_plane([[0.1, 0, 0], [0.3, 0, 0], [0.2, 0, 0]], [1.0, 0, 0], 0.2).tolist()
    [-1, 1, 0]
    >>> side_of_plane([[0.1 + 0.2, 0, 0]], [1.0, 0, 0], 0.3).tolist()  # 0.30000000000000004
    [1]
    """
    X = np.asarray(points, dtype=float).reshape(-1, 3)
    nv = np.asarray(normal, dtype=float)
    v = X @ nv - offset
    bound = gamma(4) * (np.abs(X) @ np.abs(nv) + abs(offset))
    out = np.sign(v).astype(np.int8)
    unsure = np.flatnonzero(np.abs(v) <= bound)
    if len(unsure):
        nf = [Fraction(float(c)) for c in nv]
        of = Fraction(float(offset))
        for i in unsure:
            out[i] = _rational_sign(X[i], nf, of)
    return out


def _rational_sign(x, nf, of):
    """The exact sign of ``nf . x - of`` for one point ``x`` (floats, exact as
    rationals), ``nf`` and ``of`` the plane's normal and offset as Fractions."""
    e = (nf[0] * Fraction(float(x[0])) + nf[1] * Fraction(float(x[1]))
         + nf[2] * Fraction(float(x[2])) - of)
    return (e > 0) - (e < 0)


def tie_priority(facing, index=None):
    """Which of several coplanar overlapping polygons is in front: lower is nearer.

    The one rule for depth ties, shared by the visibility engine (the order of a BSP
    node's coplanar fragments) and the discrete methods' z-buffer: a polygon whose front
    faces the point comes before one whose back faces it (the back of a zero-thickness
    wall is inside the wall), and among polygons facing the point the same way the
    first in input order is in front (a light on a ceiling).

    Parameters
    ----------
    facing : array_like of shape (N,), int
        Side of the point for each polygon, in input order: > 0 when its front faces
        the point, < 0 when its back does (0, seen edge-on, sorts with the fronts).
    index : array_like of shape (N,), int, optional
        The polygons' indices in input order (default ``0 .. N-1``), for a subset or
        for fragments that carry their source polygon's index.

    Returns
    -------
    ndarray of shape (N,), int
        A priority per polygon; among tied polygons the lowest is in front.

    Examples
    --------
    >>> tie_priority([1, -1, 1, -1]).tolist()
    [0, 5, 2, 7]
    """
    s = np.asarray(facing).reshape(-1)
    i = np.arange(len(s)) if index is None else np.asarray(index).reshape(-1)
    big = int(i.max(initial=-1)) + 1
    return i + big * (s < 0)


def plane_distances(flat, p):
    """Signed distances of ``p`` from each polygon's plane (> 0: in front), and the
    tolerance below which their float value cannot decide the side."""
    p = np.asarray(p, dtype=float)
    # -n . (c - p) over the coordinates (FlatPolygons' by-coordinate copies: three
    # whole-array steps, not a 3-long sum per polygon), summed in the order of numpy's
    # einsum("ij,ij->i") that computed it before, (x + z) + y, so that the side and the
    # band come out the same to the bit
    t = flat.normals_t * (flat.centroids_t - p[:, None])
    d = -((t[0] + t[2]) + t[1])
    scale = np.abs(p).max() + flat.vmax
    return d, PLANE_SIDE_ULPS * EPS * scale


def exact_side(P, p):
    """Exact sign of ``dot(A, p - c)`` with ``A`` the Newell area vector and ``c`` the
    vertex mean of polygon ``P``, in rational arithmetic (the float input is exact):
    +1 when ``p`` is in front of the polygon's plane, -1 behind, 0 in it."""
    Q = [[Fraction(float(c)) for c in v] for v in P]
    q0 = Q[0]
    A = [Fraction(0)] * 3
    for a, b in zip(Q[1:-1], Q[2:]):
        u = [a[i] - q0[i] for i in range(3)]
        w = [b[i] - q0[i] for i in range(3)]
        A[0] += u[1] * w[2] - u[2] * w[1]
        A[1] += u[2] * w[0] - u[0] * w[2]
        A[2] += u[0] * w[1] - u[1] * w[0]
    k = len(Q)
    val = sum(A[i] * (Fraction(float(p[i])) - sum(v[i] for v in Q) / k) for i in range(3))
    return (val > 0) - (val < 0)


def plane_sides(flat, p, exact=True, distances=None):
    """Side of ``p`` for every polygon (+1 front, -1 back, 0 in the plane), and the mask
    of polygons whose plane passes within rounding of ``p`` (the band).

    Beyond the band the float value decides. Inside it, ``exact=True`` decides in
    rational arithmetic (the double-precision form factor is then unreliable), and
    ``exact=False`` gives 0: seen edge-on, as the visibility engine counts them.
    ``distances``: :func:`plane_distances` of ``p``, when the caller has them."""
    d, dtol = plane_distances(flat, p) if distances is None else distances
    side = np.sign(d).astype(np.int8)
    band = np.abs(d) <= dtol
    side[band] = 0
    if exact and band.any():
        # exactly coplanar and axis-aligned (all vertices share p's coordinate on some
        # axis): side 0 without rational arithmetic, the common case in rooms
        same = np.zeros(len(band), dtype=bool)
        for k in range(3):
            same |= np.logical_and.reduceat(flat.V[:, k] == p[k], flat.offsets[:-1])
        for i in np.flatnonzero(band & ~same):
            side[i] = exact_side(flat.V[flat.offsets[i]:flat.offsets[i + 1]], p)
    return side, band

def polygon_side(P, p, normal):
    """Side of ``p`` for one polygon ``P`` with unit normal ``normal``: +1 in front, -1
    behind, 0 in its plane; decided from floats beyond the rounding band of the
    coordinates, exactly (:func:`exact_side`) within it.

    Examples
    --------
    >>> sq = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]], dtype=float)
    >>> polygon_side(sq, np.zeros(3), np.array([0, 0, -1.0])), polygon_side(sq, np.array([0, 0, 1.0]), np.array([0, 0, -1.0]))
    (1, 0)
    """
    d = float(normal @ (P.mean(axis=0) - p))  # < 0: p is in front of the polygon
    dtol = PLANE_SIDE_ULPS * EPS * (np.abs(p).max() + np.abs(P).max())
    if abs(d) <= dtol:
        return exact_side(P, p)
    return 1 if d < 0 else -1


def point_plane_offsets(N, D, p, magnitudes=None):
    """The float offsets ``N[k] @ p - D[k]`` of one point ``p`` from many planes, and
    their rounding's scale ``abs(N[k]) @ abs(p) + abs(D[k])`` (times ``gamma(4)``, a
    bound on the offset's error).

    Parameters
    ----------
    N, D : ndarray of shape (K, 3) and (K,)
        The planes ``dot(N[k], x) = D[k]``.
    p : ndarray of shape (3,)
    magnitudes : (ndarray of shape (K, 3), ndarray of shape (K,)), optional
        ``abs(N)`` and ``abs(D)``, where the caller keeps them (a BSP tree's planes:
        :meth:`exactff.visibility.BSPTree.plane_magnitudes`); the same values.

    Returns
    -------
    (ndarray of shape (K,), ndarray of shape (K,))

    Examples
    --------
    >>> v, scale = point_plane_offsets(np.array([[1.0, 0, 0]]), np.array([-0.5]),
    ...                                np.array([2.0, 1, 1]))
    >>> v.tolist(), scale.tolist()
    ([2.5], [2.5])
    """
    absN, absD = (np.abs(N), np.abs(D)) if magnitudes is None else magnitudes
    return N @ p - D, absN @ np.abs(p) + absD


def sides_of_point(N, D, p, offsets=None):
    """Exact side of one point ``p`` for many planes ``dot(N[k], x) = D[k]``: +1 in
    front, -1 behind, 0 exactly on the plane.

    Floats decide beyond the bound ``gamma(4) * (dot(abs(N[k]), abs(p)) + abs(D[k]))``;
    rational arithmetic within it (as :func:`side_of_plane`'s). ``offsets``:
    :func:`point_plane_offsets` of ``p``, when the caller has them.

    Examples
    --------
    >>> sides_of_point(np.array([[1.0, 0, 0], [0, 1.0, 0]]), np.array([0.3, 0.0]),
    ...                np.array([0.1 + 0.2, 0, 0])).tolist()
    [1, 0]
    """
    v, scale = point_plane_offsets(N, D, p) if offsets is None else offsets
    bound = gamma(4) * scale
    side = np.sign(v).astype(np.int8)
    unsure = np.flatnonzero(np.abs(v) <= bound)
    if len(unsure):
        # each distinct plane decided once: a point in a floor sees the planes of its
        # coplanar fragments, one plane repeated at every node that holds one (by the
        # plane's bits: a few, where numpy's unique rows cost a sort's set-up), in
        # rationals (the floats could not decide it)
        planes = np.column_stack([N[unsure], D[unsure]])
        decided = {}
        for k, q in enumerate(planes):
            key = q.tobytes()
            if key not in decided:
                decided[key] = _rational_sign(p, [Fraction(float(c)) for c in q[:3]],
                                              Fraction(float(q[3])))
            side[unsure[k]] = decided[key]
    return side


def coplanar_band(V, N, D, rows=False):
    """The near-coplanar band: how far from a plane a point may lie and still be in it.

    A point ``x`` lies in the plane ``dot(n, x) = d`` when
    ``abs(dot(n, x) - d) <= coplanar_band(x, n, d)``.

    The one definition of "coplanar / flush" for every method: the BSP tree's side
    tests (:func:`coplanar_band_sides`) and the discrete methods' depth ties
    (:func:`polygon_coplanar_bands`) both use it. It is ``BSP_COPLANAR_ULPS`` units of
    rounding of the input magnitudes in ``n . x - d``: ``u (|n| . |x| + |d|)``. A face
    flush with another within it is coplanar with it (a depth tie, resolved by
    :func:`tie_priority`); beyond it the geometry orders them, in the exact engine and
    the z-buffers alike (a rafter 3.5e-13 below a slab at 15 m, with a band of 2.1e-13
    there, is in front of it).

    Parameters
    ----------
    V : ndarray of shape (M, 3)
        Points.
    N, D : ndarray of shape (K, 3) and (K,)
        Planes ``dot(N[k], x) = D[k]``.
    rows : bool, default False
        False: every point against every plane, shape (M, K). True: row by row
        (``K == M``), shape (M,).

    Examples
    --------
    >>> coplanar_band(np.array([[0.0, 0, 15.0]]), np.array([[0, 0, -1.0]]),
    ...               np.array([-15.0])).round(16).tolist()
    [[2.132e-13]]
    """
    if rows:
        mag = np.einsum("ij,ij->i", np.abs(V), np.abs(N)) + np.abs(D)
    else:
        mag = np.abs(V) @ np.abs(N).T + np.abs(D)
    return BSP_COPLANAR_ULPS * EPS * mag


def polygon_coplanar_bands(V, offsets, N, D):
    """Per polygon, the largest :func:`coplanar_band` of its own plane over its
    vertices: the band of its plane at every point of the polygon.

    The band grows with ``sum(abs(n) * abs(x))``, convex in ``x``, so its maximum over
    the polygon is at a vertex; for an axis-aligned polygon it is the same everywhere.

    Parameters
    ----------
    V : ndarray of shape (M, 3)
        Vertices of all polygons, concatenated.
    offsets : ndarray of shape (P + 1,)
        Polygon ``i`` is ``V[offsets[i]:offsets[i + 1]]``.
    N, D : ndarray of shape (P, 3) and (P,)
        The polygons' planes.

    Examples
    --------
    >>> sq = np.array([[0, 0, 15.0], [0, 1, 15], [1, 1, 15], [1, 0, 15]])
    >>> polygon_coplanar_bands(sq, np.array([0, 4]), np.array([[0, 0, -1.0]]),
    ...                        np.array([-15.0])).round(16).tolist()
    [2.132e-13]
    """
    owner = np.repeat(np.arange(len(N)), np.diff(offsets))
    return np.maximum.reduceat(coplanar_band(V, N[owner], D[owner], rows=True),
                               offsets[:-1])


def coplanar_pairs(V, offsets, N, D, a, b):
    """Pair by pair: whether polygons ``a[k]`` and ``b[k]`` are coplanar by the BSP
    tree's rule: every vertex of one lies within the near-coplanar band
    (:func:`coplanar_band`) of the other's plane. Such a pair is one depth tie over
    its whole overlap (:func:`tie_priority` decides); any other pair is ordered by its
    geometry, as the BSP tree puts a polygon with a vertex beyond the band wholly on
    that vertex's side.

    Parameters
    ----------
    V : ndarray of shape (M, 3)
        Vertices of all polygons, concatenated.
    offsets : ndarray of shape (P + 1,)
        Polygon ``i`` is ``V[offsets[i]:offsets[i + 1]]``.
    N, D : ndarray of shape (P, 3) and (P,)
        The polygons' planes ``dot(N[i], x) = D[i]``.
    a, b : ndarray of shape (K,), int
        The pairs.

    Examples
    --------
    >>> sq = lambda z: [[0, 0, z], [0, 1, z], [1, 1, z], [1, 0, z]]
    >>> V = np.array(sq(15.0) + sq(15.0 - 1e-13) + sq(15.0 - 3.5e-13))
    >>> N = np.array([[0, 0, -1.0]] * 3); D = -V[[0, 4, 8], 2]
    >>> coplanar_pairs(V, np.array([0, 4, 8, 12]), N, D, np.array([0, 0]), np.array([1, 2])).tolist()
    [True, False]
    """
    a = np.asarray(a, dtype=int).reshape(-1)
    b = np.asarray(b, dtype=int).reshape(-1)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    # each distinct pair tested once: a z-buffer asks about the same pair in many cells,
    # and the test walks every vertex of both polygons (a 5,000-vertex table top in 122
    # pairs, 17 distinct, was 610,000 vertices a face)
    key, inverse = np.unique(a * (len(offsets) - 1) + b, return_inverse=True)
    if len(key) < len(a):
        one = np.empty(len(key), dtype=int)
        one[inverse] = np.arange(len(a))      # an occurrence of each distinct pair
        return coplanar_pairs(V, offsets, N, D, a[one], b[one])[inverse.reshape(-1)]

    def within(p, q):           # every vertex of q in the band of p's plane
        cnt = np.diff(offsets)[q]
        first = np.cumsum(cnt) - cnt
        owner = np.repeat(np.arange(len(q)), cnt)
        X = V[np.repeat(offsets[q], cnt) + np.arange(int(cnt.sum())) - np.repeat(first, cnt)]
        n, d = N[p][owner], D[p][owner]
        ok = np.abs(np.einsum("ij,ij->i", X, n) - d) <= coplanar_band(X, n, d, rows=True)
        return np.logical_and.reduceat(ok, first)

    return within(a, b) | within(b, a)


def coplanar_band_sides(V, N, D):
    """Side of every vertex ``V[i]`` for every plane ``dot(N[k], x) = D[k]``, with the
    near-coplanar band (:func:`coplanar_band`; the BSP tree's): -1 / +1 beyond
    ``BSP_COPLANAR_ULPS`` ulps of the magnitudes, 0 within (the vertex counts as in the
    plane). Returns the signs and the signed values, both of shape (len(V), len(N)).

    Examples
    --------
    >>> sign, s = coplanar_band_sides(np.array([[1 + 2.0 ** -52, 0, 0], [2.0, 0, 0]]),
    ...                               np.array([[1.0, 0, 0]]), np.array([1.0]))
    >>> sign.ravel().tolist()
    [0, 1]
    """
    s = V @ N.T - D
    out = np.sign(s).astype(np.int8)
    # the band only where a point may be in it: within the band of the points' largest
    # coordinates (|n| . |x| <= |n| . max |x|), the plane's widest band
    widest = coplanar_band(np.abs(V).max(axis=0, initial=0.0)[None], N, D)[0]
    i, k = np.nonzero(np.abs(s) <= widest)
    if len(i):
        inside = np.abs(s[i, k]) <= coplanar_band(V[i], N[k], D[k], rows=True)
        out[i[inside], k[inside]] = 0
    return out, s


def engine_sides(flat, p):
    """Side of ``p`` for every polygon as the engine takes it (+1 front, -1 back, 0 seen
    edge-on), and the mask of polygons in the rounding band.

    The side is decided exactly in the band (:func:`exact_side`, as
    on the unoccluded path), with one convention on top: a point within the rounding of
    its own coordinates (and of the polygon's centroid) of a polygon's plane lies in
    it, ``|d| <= ON_PLANE_ULPS u (|n| . |p| + |n| . |c|) + PLANE_SIDE_ULPS u |c - p|``
    with ``d`` the float distance: the polygon is seen edge-on (no value, hides
    nothing). That is the surface a row from a polygon's centroid lies on, and its
    coplanar neighbours and back-to-back twin, whose exact sides are rounding noise (a
    centroid of a rotated polygon lies off its plane by up to an ulp). Beyond it the
    input is taken as exact: a unit square at 1e8 seen from 1e-7 below it (7 ulps)
    has F = 1 - 4e-14 (pinned: test_point_within_rounding_of_a_far_plane_is_decided_exactly).

    Returns
    -------
    (ndarray of int8, ndarray of bool), each of shape (len(flat.normals),)
    """
    d, dtol = plane_distances(flat, p)
    side, band = plane_sides(flat, p, exact=False, distances=(d, dtol))   # 0 in the band
    ids = np.flatnonzero(band)
    if len(ids):
        nrm, c = np.abs(flat.normals[ids]), flat.centroids[ids]
        on_plane = np.abs(d[ids]) <= EPS * (
            ON_PLANE_ULPS * (nrm @ np.abs(p) + np.einsum("ij,ij->i", nrm, np.abs(c)))
            + PLANE_SIDE_ULPS * np.linalg.norm(c - p, axis=1))
        for i in ids[~on_plane]:
            side[i] = exact_side(flat.V[flat.offsets[i]:flat.offsets[i + 1]], p)
    return side, band


def collinear(P):
    """Whether all vertices of ``P`` lie on one line, decided exactly (the float input
    is exact): the orientation test of every vertex against the line through the first
    vertex and the one farthest from it.

    The cross products ``(v_i - v_0) x (v_f - v_0)`` are computed in float with the
    bound ``gamma(6)`` times the sum of their terms' magnitudes (the differences'
    rounding included), so that a polygon of any size, however far from the origin, is
    told from a line without a tolerance: only cross products within the bound are
    recomputed with :class:`fractions.Fraction`. A polygon whose vertices are all equal
    is collinear.

    Parameters
    ----------
    P : array_like of shape (K, 3)

    Returns
    -------
    bool

    Examples
    --------
    A triangle whose vertices differ in y only, far from the origin, and one lifted by
    one ulp of its z coordinate:

    >>> t = [[1620.33, -0.045731, -1013.51], [1620.33, -0.045334, -1013.51],
    ...      [1620.33, 0.016953, -1013.51]]
    >>> collinear(t)
    True
    >>> t[1][2] = float(np.nextafter(-1013.51, 0))
    >>> collinear(t)
    False
    """
    X = np.asarray(P, dtype=float)
    Q = X - X[0]
    f = int(np.argmax(np.einsum("ij,ij->i", Q, Q)))
    q = Q[f]
    C = np.cross(Q, q)
    A, a = np.abs(Q), np.abs(q)
    bound = gamma(6) * np.column_stack([A[:, 1] * a[2] + A[:, 2] * a[1],
                                        A[:, 2] * a[0] + A[:, 0] * a[2],
                                        A[:, 0] * a[1] + A[:, 1] * a[0]])
    if np.any(np.abs(C) > bound):
        return False
    x0 = [Fraction(float(c)) for c in X[0]]
    e = [Fraction(float(c)) - x0[k] for k, c in enumerate(X[f])]
    for i in np.flatnonzero(np.any(C != 0, axis=1) | np.any(bound > 0, axis=1)):
        d = [Fraction(float(c)) - x0[k] for k, c in enumerate(X[i])]
        if (d[1] * e[2] != d[2] * e[1] or d[2] * e[0] != d[0] * e[2]
                or d[0] * e[1] != d[1] * e[0]):
            return False
    return True


def in_plane_band(V, N, D, rtol=BSP_COPLANAR_ULPS * EPS):
    """Row by row: whether the point ``V[k]`` lies in the band of the plane
    ``dot(N[k], x) = D[k]``; by default the BSP tree's coplanar band.

    The band is ``abs(dot(n, x) - d) <= rtol * (dot(abs(n), abs(x)) + abs(d))``, by
    default ``BSP_COPLANAR_ULPS`` ulps of the magnitudes (:func:`coplanar_band`, as
    :func:`coplanar_band_sides` and the z-buffers' depth ties).

    Examples
    --------
    >>> in_plane_band(np.array([[1 + 2.0 ** -52, 0, 0], [2.0, 0, 0]]),
    ...               np.array([[1.0, 0, 0], [1.0, 0, 0]]), np.array([1.0, 1.0])).tolist()
    [True, False]
    """
    s = np.einsum("ij,ij->i", V, N) - D
    band = coplanar_band(V, N, D, rows=True)
    if rtol != BSP_COPLANAR_ULPS * EPS:
        band = band * (rtol / (BSP_COPLANAR_ULPS * EPS))
    return np.abs(s) <= band


def orient2d(p, q, w):
    """Sign of the 2-D orientation ``(q - p) x (w - p)`` (+1: ``w`` to the left of the
    line from ``p`` to ``q``, -1: to the right), row by row, where floats can decide it:
    0 where the value is within Shewchuk's bound ``(3 + 16 u) u (|l| + |r|)`` of 0 (the
    sign is then not decided here; exact zeros included).

    Examples
    --------
    >>> p, q = np.array([[0.0, 0.0]] * 3), np.array([[1.0, 0.0]] * 3)
    >>> orient2d(p, q, np.array([[0.5, 1.0], [0.5, -1.0], [0.5, 0.0]])).tolist()
    [1, -1, 0]
    """
    d1, d2 = q - p, w - p
    left, right = d1[..., 0] * d2[..., 1], d1[..., 1] * d2[..., 0]
    det = left - right
    bound = (3 + 16 * EPS) * EPS * (np.abs(left) + np.abs(right))
    return np.where(np.abs(det) > bound, np.sign(det), 0).astype(np.int8)


def _side_of_line(p, q, w):
    """Side of ``w`` of the line from ``p`` to ``q``: +1 left, -1 right, where floats
    decide it (:func:`orient2d`); 0 where ``w`` is certainly on the line (it is ``p`` or
    ``q``, or a zero difference makes both products exactly 0: an axis-aligned line);
    2 where floats cannot tell."""
    d1, d2 = q - p, w - p
    left, right = d1[..., 0] * d2[..., 1], d1[..., 1] * d2[..., 0]
    det = left - right
    bound = (3 + 16 * EPS) * EPS * (np.abs(left) + np.abs(right))
    out = np.where(np.abs(det) > bound, np.sign(det), 2).astype(np.int8)
    on = (((d1[..., 0] == 0) | (d2[..., 1] == 0)) & ((d1[..., 1] == 0) | (d2[..., 0] == 0))
          | np.all(w == p, axis=-1) | np.all(w == q, axis=-1))
    out[on] = 0
    return out


def polygons_apart(T, U):
    """Whether the 2-D polygons ``T[m]`` and ``U[m]`` certainly have disjoint interiors:
    the line of an edge of one has that polygon on one side and the other polygon on
    the other (vertices on the line itself allowed where that is certain: the edge's
    ends, axis-aligned lines; polygons touching along it are apart). Decided with the
    float filter of :func:`orient2d`; False where floats cannot tell, or no edge
    separates them (the caller then overlays the two).

    Parameters
    ----------
    T : ndarray of shape (M, K, 2)
    U : ndarray of shape (M, L, 2)

    Returns
    -------
    ndarray of shape (M,), bool

    Examples
    --------
    Two halves of a square, and a triangle that overlaps the first:

    >>> a = np.array([[[0, 0], [1, 0], [1, 1]]], dtype=float)
    >>> b = np.array([[[0, 0], [1, 1], [0, 1]]], dtype=float)
    >>> c = np.array([[[0.5, 0], [1, 0], [1, 2]]], dtype=float)
    >>> polygons_apart(a, b).tolist(), polygons_apart(a, c).tolist()
    ([True], [False])
    """
    out = np.zeros(len(T), dtype=bool)
    todo = np.arange(len(T))
    for X, Y in ((T, U), (U, T)):
        k = X.shape[1]
        for i in range(k):
            if len(todo) == 0:
                return out
            Xs, Ys = X[todo], Y[todo]
            p, q = Xs[:, i], Xs[:, (i + 1) % k]
            s = _side_of_line(p, q, Xs[:, (i + 2) % k])
            apart = (s == 1) | (s == -1)
            for j in range(3, k):           # the polygon's own vertices: on one side
                t = _side_of_line(p, q, Xs[:, (i + j) % k])
                apart &= (t == s) | (t == 0)
            for j in range(Ys.shape[1]):    # the other's: on the other side (or on it)
                t = _side_of_line(p, q, Ys[:, j])
                apart &= (t == -s) | (t == 0)
            out[todo[apart]] = True
            todo = todo[~apart]
    return out
