"""Pairs of an area row that blockers in one plane hide whole, proven exactly
(docs/explanation/area-form-factors.md, "Walls between the pair").

Where the emitter P and the receiver Q lie on opposite closed sides of a plane H, every
segment from a point of P to a point of Q meets H inside the slice ``conv(P u Q) n H``,
which is the convex hull of the points where the segments between vertices of P and
of Q on strictly opposite sides cross H, and of the vertices on H (the slice of a
polytope is the hull of its edges' crossings, and every edge of ``conv(P u Q)`` joins
two of those vertices). Where the (closed) blockers lying in H cover that slice but for
a set of no area, the pair's form factor is exactly 0: the segments that cross H
elsewhere join points of P and Q of which at least one lies in H, or cross it in a set
of no area, whose preimage under the central projection ``x -> crossing`` from a point
of Q off H is of no area in P either.

The test is decided in rational arithmetic from the input's doubles (the blockers'
coplanarity, the sides, the crossings, the hull and the cover), so that it holds for
walls assembled from pieces that share edges, and for P and Q with an edge in H (a
floor against the wall that stands on it). Only blockers whose vertices lie exactly in
one plane, and are convex there, take part; scenes turned off the axes, where the
pieces are coplanar only to rounding, are left to the integration.
"""

from fractions import Fraction

import numpy as np
import shapely

__all__ = ["hidden_by_a_plane"]


def hidden_by_a_plane(Pc, Qc, blockers, reach):
    """Whether blockers in one plane hide all of Qc from all of Pc (the pair's form
    factor is then exactly 0; module docstring).

    Parameters
    ----------
    Pc, Qc : ndarray of shape (k, 3)
        The emitter and the receiver (convex, each clipped to the front of the other).
    blockers : list of ndarray of shape (m, 3)
        The pair's possible blockers.
    reach : float
        The size of the coordinates (the prefilter's band for "on the plane" is
        1e-9 of it; the decision itself is exact).

    Returns
    -------
    bool

    Examples
    --------
    A floor and a wall piece on either side of a wall made of two pieces, each touching
    the wall's plane along an edge:

    >>> floor = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], float)
    >>> piece = np.array([[0, 1, 0], [0, 1, 1], [-1, 1, 1], [-1, 1, 0]], float)
    >>> low = np.array([[0, 0, 0], [0, 1, 0], [0, 1, 0.5], [0, 0, 0.5]], float)
    >>> high = np.array([[0, 0, 0.5], [0, 1, 0.5], [0, 1, 1], [0, 0, 1]], float)
    >>> hidden_by_a_plane(floor, piece, [low, high], 2.0)
    True
    >>> hidden_by_a_plane(floor, piece, [low], 2.0)
    False
    """
    band = 1e-9 * reach
    candidates = {}
    for k, K in enumerate(blockers):
        K = np.asarray(K, dtype=float)
        n = np.cross(K[1] - K[0], K[2] - K[0])
        if not np.linalg.norm(n) > 0:
            n = _newell(K)
        norm = np.linalg.norm(n)
        if not norm > 0:
            continue
        n, d = n / norm, float(n @ K[0]) / norm
        sP, sQ = Pc @ n - d, Qc @ n - d
        if sP.min() < -band:
            n, d, sP, sQ = -n, -d, -sP, -sQ
        # P on the closed positive side, Q on the closed negative one, neither in H
        if (sP.min() < -band or sQ.max() > band or sP.max() <= band
                or sQ.min() >= -band):
            continue
        key = (tuple(np.round(n, 9)), round(d / reach, 9))
        candidates.setdefault(key, []).append(k)
    for (n, _), ks in candidates.items():
        Ks = [np.asarray(blockers[k], dtype=float) for k in ks]
        if _float_cover(Pc, Qc, Ks, np.array(n), band) and _covered_exactly(Pc, Qc, Ks):
            return True
    return False


def _newell(K):
    """Newell's area vector of polygon K (twice its area along its normal)."""
    return np.cross(K, np.roll(K, -1, axis=0)).sum(axis=0)


def _covered_exactly(Pc, Qc, Ks):
    """The module's test for one plane, that of ``Ks[0]``, in rationals: False where
    P and Q are not on opposite closed sides of it, or where the blockers exactly in
    it (convex) leave part of the slice of positive area uncovered."""
    # H: the plane of normal nf through Ks[0]'s first vertex (nf from doubles, the
    # plane exact from there), projected along the axis of nf's largest component
    nf = [Fraction(float(c)) for c in _exact_normal(Ks[0])]
    if not any(nf):
        return False
    axis = max(range(3), key=lambda a: abs(nf[a]))
    keep = [a for a in range(3) if a != axis]
    a0 = [Fraction(float(c)) for c in Ks[0][0]]
    d = sum(x * y for x, y in zip(nf, a0))

    def side(v):
        return sum(x * Fraction(float(y)) for x, y in zip(nf, v)) - d

    sP, sQ = [side(v) for v in Pc], [side(v) for v in Qc]
    if max(sP) <= 0:
        nf, d = [-x for x in nf], -d
        sP, sQ = [-s for s in sP], [-s for s in sQ]
    if min(sP) < 0 or max(sQ) > 0 or max(sP) == 0 or min(sQ) == 0:
        return False
    # the blockers exactly in H, convex, projected on the two other axes
    covers = []
    for K in Ks:
        Kf = [[Fraction(float(c)) for c in v] for v in K]
        if any(sum(x * y for x, y in zip(nf, v)) != d for v in Kf):
            continue
        K2 = _ccw([(v[keep[0]], v[keep[1]]) for v in Kf])
        if K2 is not None:
            covers.append(K2)
    if not covers:
        return False
    # the slice: the crossings of the vertex pairs on strictly opposite sides, and the
    # vertices on H
    Pf = [[Fraction(float(c)) for c in v] for v in Pc]
    Qf = [[Fraction(float(c)) for c in v] for v in Qc]
    pts = [(v[keep[0]], v[keep[1]]) for v, s in zip(Pf + Qf, sP + sQ) if s == 0]
    for p, a in zip(Pf, sP):
        if a == 0:
            continue
        for q, b in zip(Qf, sQ):
            if b == 0:
                continue
            t = a / (a - b)
            pts.append(tuple(p[i] + t * (q[i] - p[i]) for i in keep))
    pieces = [_hull(pts)]
    if len(pieces[0]) < 3 or _area2(pieces[0]) == 0:
        return False
    for K2 in covers:
        pieces = [r for piece in pieces for r in _minus_convex(piece, K2)]
        if not pieces:
            return True
    return False


def _exact_normal(K):
    """A normal of K from its first vertex and the next two that are not collinear
    with it, in doubles: rounded, except on planes along the axes, so that a polygon
    turned off the axes is not found exactly in the plane it defines (left to the
    integration)."""
    for j in range(2, len(K)):
        n = np.cross(K[1] - K[0], K[j] - K[0])
        if np.any(n != 0):
            return n
    return np.zeros(3)


def _float_cover(Pc, Qc, Ks, n, band):
    """False where the slice, in doubles, is clearly not covered by the blockers
    (GEOS finds more than 1e-9 of its area left): the exact test would fail, so it is
    not run. ``n``: the plane's unit normal (P on its positive side)."""
    d = float(np.concatenate([K @ n for K in Ks]).mean())
    sP, sQ = Pc @ n - d, Qc @ n - d
    a, b = sP[sP > band], sQ[sQ < -band]
    p, q = Pc[sP > band], Qc[sQ < -band]
    t = (a[:, None] / (a[:, None] - b[None, :]))[..., None]
    pts = (p[:, None] + t * (q[None, :] - p[:, None])).reshape(-1, 3)
    pts = np.vstack([pts, Pc[np.abs(sP) <= band], Qc[np.abs(sQ) <= band]])
    keep = [a for a in range(3) if a != int(np.argmax(np.abs(n)))]
    hull = shapely.MultiPoint(pts[:, keep]).convex_hull
    if hull.area == 0:
        return True
    union = shapely.union_all([shapely.Polygon(K[:, keep]) for K in Ks])
    return hull.difference(union).area <= 1e-9 * hull.area


def _cross2(o, a, b):
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _ccw(poly):
    """The polygon counter-clockwise, its repeated and collinear vertices dropped;
    None where it is not convex or of no area."""
    pts = []
    for v in poly:
        if not pts or v != pts[-1]:
            pts.append(v)
    while len(pts) > 1 and pts[0] == pts[-1]:
        pts.pop()
    turns = [_cross2(pts[i - 1], pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    if any(t > 0 for t in turns) and any(t < 0 for t in turns):
        return None
    pts = [v for v, t in zip(pts, turns) if t != 0]
    if len(pts) < 3:
        return None
    return pts if any(t > 0 for t in turns) else pts[::-1]


def _hull(pts):
    """Convex hull (Andrew's monotone chain), counter-clockwise, exact."""
    pts = sorted(set(pts))
    if len(pts) < 3:
        return pts
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and _cross2(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and _cross2(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def _clip(poly, a, b, keep_left):
    """Convex polygon ``poly`` clipped to the closed left (or right) of the line a -> b."""
    out = []
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        sp, sq = _cross2(a, b, p), _cross2(a, b, q)
        if not keep_left:
            sp, sq = -sp, -sq
        if sp >= 0:
            out.append(p)
        if (sp > 0 > sq) or (sp < 0 < sq):
            t = sp / (sp - sq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def _area2(poly):
    return sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(poly, poly[1:] + poly[:1]))


def _minus_convex(piece, K):
    """The convex pieces of positive area of ``piece`` less the convex polygon K
    (both counter-clockwise): the parts beyond each edge of K and within the ones
    before it."""
    out = []
    rest = piece
    for i, a in enumerate(K):
        b = K[(i + 1) % len(K)]
        beyond = _clip(rest, a, b, keep_left=False)
        if len(beyond) >= 3 and _area2(beyond) != 0:
            out.append(beyond)
        rest = _clip(rest, a, b, keep_left=True)
        if len(rest) < 3 or _area2(rest) == 0:
            break
    return out
