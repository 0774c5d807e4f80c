"""The half-space clipper: the part of polygons on the positive side of a plane.

One algorithm (Sutherland-Hodgman against one plane), in the variants the package
needs: a batch over padded polygons and any planes (:func:`clip_halfspace`: chart
frusta, the area code's fronts), one polygon split in two by a plane
(:func:`split_polygon`: the BSP tree), and horizon clipping in the receiver's frame
(:func:`clip_above_horizon`, in floats or mpmath numbers: ``z > 0`` kept, crossings put
exactly on ``z = 0``), and one polygon's part in front of a plane through a point
(:func:`clip_front`: the area code's one-sided pairs; :func:`clip_fronts` for many at
once). Every module clips through these.
"""

import numpy as np

from . import _tolerances as tol
from .geometry import cross
from .rings import padded

__all__ = ["clip_halfspace", "split_polygon", "clip_above_horizon", "clip_front",
           "clip_fronts", "NORMAL_FLOOR"]

#: Far above the subnormals: a meet of planes whose products stay normal numbers
#: (clip_halfspace; the compiled set-up of the area pairs reads it too).
NORMAL_FLOOR = float(np.finfo(float).tiny) / tol.EPS


def clip_halfspace(V, counts, h):
    """Clip a batch of polygons to the open half-space in front of a plane through the
    origin: ``dot(h, x) > 0`` (points on it kept).

    Parameters
    ----------
    V : ndarray of shape (M, K, 3)
        Padded vertices; polygon m uses ``V[m, :counts[m]]``.
    counts : ndarray of shape (M,)
    h : ndarray of shape (3,) or (M, 3)
        One plane for all, or one per polygon.

    Returns
    -------
    (ndarray of shape (M, K', 3), ndarray of shape (M,))
        The clipped polygons, padded; a count below 3 means nothing is left.

    Examples
    --------
    >>> V = np.array([[[-1, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0]]], dtype=float)
    >>> W, k = clip_halfspace(V, np.array([4]), np.array([1.0, 0, 0]))
    >>> W[0, :k[0]].tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    """
    M, K, _ = V.shape
    slot = np.arange(K)
    valid = slot[None, :] < counts[:, None]
    nxt = (slot[None, :] + 1) % np.maximum(counts[:, None], 1)
    W = np.take_along_axis(V, nxt[:, :, None], axis=1)
    s = V @ h if h.ndim == 1 else np.einsum("mkj,mj->mk", V, h)
    sn = np.take_along_axis(s, nxt, axis=1)
    inside = (s > 0) & valid
    inside_n = (sn > 0) & valid
    crosses = (inside != inside_n) & valid
    # crossing point computed from the inside end point, whichever way the edge runs:
    # an edge shared by two polygons gets bit-identical clip points in both (GEOS then
    # sees exactly shared vertices instead of rounding-thin slivers)
    A = np.where(inside[:, :, None], V, W)
    B = np.where(inside[:, :, None], W, V)
    sa = np.where(inside, s, sn)
    sb = np.where(inside, sn, s)
    # X = A + sa / (sa - sb) (B - A) as the meet of the edge's plane through the origin
    # with the clipping plane, ((A x e) x h) / (sa - sb) with e = B - A (the same point:
    # (A x e) x h = sa e + (sa - sb) A). Each coordinate then carries rounding relative
    # to its own terms, not to |A|, so the point's direction stays exact to a few ulps
    # where the point is small next to the end points (a plane met 1e-6 above the
    # origin by an edge 1 away: the interpolated form's direction was off by 1e-10).
    # Either form's error is at most a few eps |A| |e| |h| / |h . e|. The interpolated
    # form stays where the edge's line runs through the origin (m = 0 to its rounding: the
    # crossing is then the origin itself, and only rounding says which way it points).
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(crosses, sa / (sa - sb), 0.0)
    X = A + t[:, :, None] * (B - A)
    pm, pk = np.nonzero(crosses)
    if len(pm):
        a, e, d = A[pm, pk], B[pm, pk] - A[pm, pk], (sa - sb)[pm, pk]
        hc = h[pm] if h.ndim == 2 else np.broadcast_to(h, a.shape)
        m = cross(a, e)
        x = X[pm, pk]
        la, le = np.abs(a).sum(axis=1), np.abs(e).sum(axis=1)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            meet = cross(m, hc) / d[:, None]
            cond = 1.0 + np.abs(hc).sum(axis=1) * le / np.abs(d)
            # the meet where it is the same point as the interpolated one within the
            # latter's error, the crossing is well conditioned and no product underflows
            # (not so where the planes' rounding dominates: subnormal heights, say)
            # and the meet on the edge's line to rounding, |(meet - a) x e| within the
            # interpolated point's u (|a| + |e|) |e| (an edge in the plane but for
            # rounding, cond 1e14: the meet's error, u |a| cond, left the line by a
            # third of the edge, the interpolated point's stays along it)
            use = ((np.abs(meet - x).sum(axis=1) <= tol.CLIP_MEET_ULPS * tol.EPS * (la + le) * cond)
                   & (np.abs(cross(meet - a, e)).sum(axis=1)
                      <= tol.CLIP_MEET_ULPS * tol.EPS * (la + le) * le)
                   & (cond * tol.CLIP_MEET_ULPS * tol.EPS < 1.0)
                   & (np.abs(m).sum(axis=1) > tol.CLIP_MEET_ULPS * tol.EPS * la * le)
                   & (np.abs(d) > NORMAL_FLOOR) & (la * le > NORMAL_FLOOR))
        X[pm[use], pk[use]] = meet[use] + 0.0                 # + 0: no signed zeros
    out = np.empty((M, 2 * K, 3))
    out[:, 0::2] = V
    out[:, 1::2] = X
    keep = np.empty((M, 2 * K), dtype=bool)
    keep[:, 0::2] = inside
    keep[:, 1::2] = crosses
    new_counts = keep.sum(axis=1)
    Kn = max(int(new_counts.max(initial=0)), 1)
    order = np.argsort(~keep, axis=1, kind="stable")[:, :Kn]
    return np.take_along_axis(out, order[:, :, None], axis=1), new_counts


def split_polygon(P, sign, s, crossing=None, snap=None):
    """Split polygon P by a plane: ``sign`` (-1, 0, +1) and ``s`` (signed values) per
    vertex; returns ``(front, back)``, each None when fewer than 3 vertices are left.
    Vertices on the plane (sign 0) go to both; a crossing is interpolated from its
    edge's front end point, so that an edge shared by two polygons splits identically,
    or taken from ``crossing(a, b)`` (front and back end points' indices) where that
    returns one (the BSP tree's exact crossings). With ``snap``, a crossing within
    ``snap`` times the double roundoff of an end point's largest coordinate (in every
    coordinate) of that end point is that end point, in both parts: no edge an ulp long.

    Examples
    --------
    >>> P = np.array([[-1, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0]], dtype=float)
    >>> front, back = split_polygon(P, np.sign(P[:, 0]), P[:, 0])
    >>> front.tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    """
    front, back = [], []
    k = len(P)
    for i in range(k):
        j = (i + 1) % k
        if sign[i] >= 0:
            front.append(P[i])
        if sign[i] <= 0:
            back.append(P[i])
        if sign[i] * sign[j] < 0:
            # from the front end point, so that a shared edge splits identically
            a, b = (i, j) if sign[i] > 0 else (j, i)
            X = None if crossing is None else crossing(a, b)
            if X is None:
                X = P[a] + (s[a] / (s[a] - s[b])) * (P[b] - P[a])
            near = _snapped(X, P[i], P[j], snap)
            if near is None:
                front.append(X)
                back.append(X)
            elif near == 0:
                # the crossing is vertex i: it ends the part it is on and starts the other
                (back if sign[i] > 0 else front).append(P[i])
            else:
                (front if sign[i] > 0 else back).append(P[j])
    if snap is not None:
        # a vertex equal to the one before it (two crossings snapped to one end point)
        front, back = _without_repeats(front), _without_repeats(back)
    f = np.array(front) if len(front) >= 3 else None
    b = np.array(back) if len(back) >= 3 else None
    return f, b


def _without_repeats(ring):
    """The ring without a vertex equal to the one before it (the first, where the last
    equals it), as the compiled build drops them."""
    out = []
    for v in ring:
        if not (out and np.array_equal(out[-1], v)):
            out.append(v)
    if len(out) > 1 and np.array_equal(out[0], out[-1]):
        out = out[1:]
    return out


def _snapped(X, A, B, snap):
    """0 or 1 where crossing X lies within ``snap`` roundoffs of end point A or B (every
    coordinate, of the point's largest), else None (as the compiled build's split)."""
    if snap is None:
        return None
    for which, E in ((0, A), (1, B)):
        if np.all(np.abs(X - E) <= snap * _EPS_DOUBLE * np.abs(E).max()):
            return which
    return None


#: the double precision machine epsilon (2 roundoffs): the snap of split_polygon
_EPS_DOUBLE = float(np.finfo(float).eps)


def clip_above_horizon(Q, zero=0.0):
    """Horizon clipping of one polygon in the local frame of the point: the part with
    ``z > 0``, each crossing interpolated from its edge's first end point and put
    exactly on ``z = 0``.

    Parameters
    ----------
    Q : sequence of 3-sequences
        Vertices in the local frame, floats or mpmath numbers (the arithmetic follows
        them).
    zero : number, default 0.0
        The zero of that arithmetic (``mpmath.mpf(0)`` for mpmath input).

    Returns
    -------
    list of 3-tuples

    Examples
    --------
    >>> clip_above_horizon([(0.0, 0.0, 1.0), (1.0, 0.0, -1.0), (0.0, 1.0, 1.0)])
    [(0.0, 0.0, 1.0), (0.5, 0.0, 0.0), (0.5, 0.5, 0.0), (0.0, 1.0, 1.0)]
    """
    out = []
    k = len(Q)
    for i in range(k):
        a, b = Q[i], Q[(i + 1) % k]
        if a[2] > 0:
            out.append(tuple(a))
        if (a[2] > 0) != (b[2] > 0):
            t = a[2] / (a[2] - b[2])
            out.append((a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), zero))
    return out


def _front_part(C, c):
    """A clipped ring (about c) moved back by c, without the repeat a cut through a vertex
    leaves (no edge of zero length), nor a vertex the cut put within ``CLIP_MEET_ULPS``
    roundoffs (of the ring's largest coordinates) of the one before it (a cut along an
    edge that lies in the plane but for rounding: the copy would leave a sliver 1e-14
    wide, on which the area rules' closed forms and half-planes are rounding's); None
    with fewer than 3 vertices."""
    C = C + c
    C = C[np.any(C != np.roll(C, 1, axis=0), axis=1)]
    step = np.abs(C - np.roll(C, 1, axis=0)).sum(axis=1)
    # (roundoffs of the ring's largest coordinates: the cut rounds at the scale of the
    # edge's ends and the plane's point, not of the vertex, which may be at the origin)
    near = step <= 2 * tol.CLIP_MEET_ULPS * tol.EPS * np.abs(C).sum(axis=1).max(initial=0.0)
    if near.any() and len(C) > 3:
        C = C[~near]
    return C if len(C) >= 3 else None


def clip_fronts(polys, normals, points):
    """The parts of many polygons in front of their planes, ``n_m . (x - c_m) > 0``, in
    one :func:`clip_halfspace` call: :func:`clip_front` of each, for polygons the caller
    has found to straddle their planes (no whole or empty shortcut here).

    Parameters
    ----------
    polys : sequence of ndarray of shape (K_m, 3)
    normals, points : ndarray of shape (M, 3)
        Each polygon's plane: its normal and a point of it.

    Returns
    -------
    list of ndarray or None
        Each polygon's part (None where fewer than 3 vertices are left).

    Examples
    --------
    >>> P = np.array([[-1, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0]], float)
    >>> [C.tolist() for C in clip_fronts([P, P], np.array([[1.0, 0, 0], [0, -1.0, 0]]),
    ...                                  np.array([[0.0, 0, 0], [0, 0.5, 0]]))]
    ... # doctest: +NORMALIZE_WHITESPACE
    [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
     [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.5, 0.0], [-1.0, 0.5, 0.0]]]
    """
    if not len(polys):
        return []
    points = np.asarray(points, dtype=float)
    V, counts = padded([np.asarray(P, dtype=float) - c for P, c in zip(polys, points)])
    W, k = clip_halfspace(V, counts, np.asarray(normals, dtype=float))
    return [_front_part(W[m, :k[m]], points[m]) for m in range(len(k))]


def clip_front(P, n, c, d=None):
    """The part of polygon P (K, 3) with ``n . (x - c) > 0`` (None when nothing is
    left): :func:`clip_halfspace` about the point c. ``d``: the distances
    ``(P - c) @ n`` where the caller has them (one decision for a batch of pairs,
    however they round), else computed. A polygon with every distance >= 0 and one > 0
    is returned itself.

    Examples
    --------
    >>> P = np.array([[-1, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0]], float)
    >>> clip_front(P, np.array([1.0, 0, 0]), np.zeros(3)).tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    >>> clip_front(P, np.array([1.0, 0, 0]), np.array([2.0, 0, 0])) is None
    True
    """
    if d is None:
        d = (P - c) @ n
    if np.all(d >= 0) and np.any(d > 0):
        return P
    if np.all(d <= 0):
        return None
    V, k = clip_halfspace((P - c)[None], np.array([len(P)]), n)
    return _front_part(V[0, :k[0]], c)
