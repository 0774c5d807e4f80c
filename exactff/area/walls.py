"""Pairs of an area row that walls between them hide whole, proven exactly
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

Where they leave convex pieces U of the slice uncovered, every segment they let through
passes through one: its part from P to U is a segment from P to U, and its part from U
to Q one from U to Q, so the pair is hidden where, for each piece, (P, U) or (U, Q) is
hidden in turn (by another plane: an annex's ceiling, then the wall between it and the
hall), down to ``AREA_WALL_PLANES`` planes in all.

The test is decided in rational arithmetic from the input's doubles (the blockers'
coplanarity, the sides, the crossings, the hull, the cover and the pieces), so that it
holds for walls assembled from pieces that share edges, and for P and Q with an edge in
H (a floor against the wall that stands on it). Only blockers whose vertices lie exactly
in one plane, and are convex there, take part: scenes turned off the axes, where the
pieces are coplanar only to rounding, are left to the integration. Doubles only choose
what to try: a pair is refused where a segment between inner points of the two misses
every blocker; the planes are grouped within AREA_WALL_BAND; the search runs first in
doubles (GEOS, :mod:`exactff.area.wall_plan`), and only where it finds the pair hidden
in rationals, which takes the order of its tries from the search in doubles.
"""

from fractions import Fraction

import numpy as np
import shapely

from .. import _tolerances as tol
from ..geometry import cross
from .culling import padded_polygons
from .rational_polygons import ccw, crossing, has_area, hull, minus_convex
from .wall_plan import Plan, float_pieces, float_scores

__all__ = ["hidden_by_walls"]


def hidden_by_walls(Pc, Qc, blockers, reach, cache=None):
    """Whether walls (blockers in one plane, or in a few planes one behind the other)
    hide all of Qc from all of Pc: the pair's form factor is then exactly 0 (module
    docstring).

    Parameters
    ----------
    Pc, Qc : ndarray of shape (k, 3)
        The emitter and the receiver (convex, each clipped to the front of the other).
    blockers : list of ndarray of shape (m, 3)
        The pair's possible blockers.
    reach : float
        The size of the coordinates (the prefilter's band for "on the plane" is
        ``AREA_WALL_BAND`` of it; the decision itself is exact).
    cache : dict, optional
        Walls kept between calls whose blockers are the same arrays (a row's pairs: its
        polygons), keyed by their plane and the blockers' identities, with what each
        has computed (its union, its exact covers). The caller keeps the arrays alive
        while the cache lives.

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
    >>> hidden_by_walls(floor, piece, [low, high], 2.0)
    True
    >>> hidden_by_walls(floor, piece, [low], 2.0)
    False
    """
    if not len(blockers):
        return False
    band, depth = tol.AREA_WALL_BAND * reach, tol.AREA_WALL_PLANES - 1
    blockers = [np.asarray(K, dtype=float) for K in blockers]
    with np.errstate(invalid="ignore", divide="ignore"):
        V, _, _, N = padded_polygons(blockers)
    keep = np.isfinite(N).all(axis=1)
    V, N = V[keep], N[keep]
    D = np.einsum("bx,bx->b", N, V[:, 0])
    # a segment between inner points of the two that misses every blocker (by more
    # than the band): not hidden, nothing else tried
    if not len(V) or _a_segment_passes(Pc, Qc, V, N, D, band):
        return False
    walls = _walls([blockers[k] for k in np.flatnonzero(keep)], N, D, reach, cache)
    # a plan in doubles first; only where it finds the pair hidden, the proof, which
    # follows the plan: its walls scored at the plan's nodes, the plane that hid each
    # node first
    plan = Plan()
    return (_hidden(Pc, Qc, walls, band, depth, [tol.AREA_WALL_NODES], False, plan)
            and _hidden(_rational(Pc), _rational(Qc), walls, band, depth,
                        [tol.AREA_WALL_NODES], True, plan))


class _Wall:
    """The blockers in one plane (to the prefilter's rounding): unit normal n, offset
    d, the blockers (doubles), their union in the plane's projection (GEOS, made when
    first asked) and the exact plane and convex covers (rationals, likewise)."""

    def __init__(self, n, d, Ks):
        self.n, self.d, self.Ks = n, d, Ks
        self.keep = [a for a in range(3) if a != int(np.argmax(np.abs(n)))]
        V = np.vstack(Ks)[:, self.keep]
        self.lo, self.hi = V.min(axis=0), V.max(axis=0)
        self._union = self._exact = None

    def union(self):
        if self._union is None:
            self._union = shapely.union_all([shapely.Polygon(K[:, self.keep])
                                             for K in self.Ks])
        return self._union

    def exact(self):
        """(normal, offset, projection axis, the two axes kept, covers): the plane of
        the first blocker whose vertices lie exactly in one plane (the normal of its
        first vertex and the next two not collinear with it), and the blockers exactly
        in it, convex, projected along the axis of the normal's largest component
        (counter-clockwise); None where none is."""
        if self._exact is None:
            self._exact = False
            Ks = [_rational(K) for K in self.Ks]
            for K0 in Ks:
                nf = _exact_normal(K0)
                if nf is None:
                    continue
                d = sum(x * y for x, y in zip(nf, K0[0]))
                if any(_side(nf, d, v)[0] for v in K0):
                    continue
                axis = max(range(3), key=lambda a: abs(nf[a]))
                keep = [a for a in range(3) if a != axis]
                covers = []
                for K in Ks:
                    if any(_side(nf, d, v)[0] for v in K):
                        continue
                    K2 = ccw([(v[keep[0]], v[keep[1]]) for v in K])
                    if K2 is not None:
                        box = np.array([[float(x), float(y)] for x, y in K2])
                        covers.append((K2, (box.min(axis=0), box.max(axis=0))))
                if covers:
                    self._exact = (nf, d, axis, keep, covers)
                break
        return self._exact or None


def _walls(blockers, N, D, reach, cache=None):
    """The blockers grouped by plane (unit normals N, offsets D; normal and offset
    rounded to AREA_WALL_BAND, the normal's sign made that of its first component
    above AREA_WALL_SLIVER); with ``cache``, a wall of the same plane and the same
    blocker arrays as one made before is that one."""
    first = np.argmax(np.abs(N) > tol.AREA_WALL_SLIVER, axis=1)
    flip = np.where(N[np.arange(len(N)), first] < 0, -1.0, 1.0)
    N, D = N * flip[:, None], D * flip
    groups = {}
    for K, n, d in zip(blockers, N, D):
        key = (tuple(np.round(n / tol.AREA_WALL_BAND)), round(d / reach / tol.AREA_WALL_BAND))
        if key not in groups:
            groups[key] = (n, d, [])
        groups[key][2].append(K)
    cache = {} if cache is None else cache
    out = []
    for key, (n, d, Ks) in groups.items():
        ident = (key, tuple(id(K) for K in Ks))
        if ident not in cache:
            cache[ident] = _Wall(n, d, Ks)
        out.append(cache[ident])
    return _Walls(out)


class _Walls(list):
    """The walls (a list of :class:`_Wall`) with their axes kept and boxes as arrays, so
    that a pair's walls are scored together (:func:`~exactff.area.wall_plan.float_scores`)."""

    def __init__(self, walls):
        super().__init__(walls)
        self.keep = np.array([w.keep for w in walls], dtype=np.intp).reshape(-1, 2)
        self.lo = np.array([w.lo for w in walls], dtype=float).reshape(-1, 2)
        self.hi = np.array([w.hi for w in walls], dtype=float).reshape(-1, 2)


def _a_segment_passes(Pc, Qc, V, N, D, band):
    """Whether one of the segments between inner points of Pc and Qc (the centroids and
    the points halfway from them to the vertices) misses every blocker (padded
    vertices V, unit normals N, offsets D) by more than ``band``: a cheap refusal, in
    doubles (it may only refuse a pair that walls hide, never take one)."""
    def inner(X):
        c = X.mean(axis=0)
        return np.vstack([c, 0.5 * (X + c)])
    x, y = inner(Pc), inner(Qc)
    x, y = np.repeat(x, len(y), axis=0), np.tile(y, (len(x), 1))           # (m, 3)
    sx, sy = x @ N.T - D, y @ N.T - D                                        # (m, b)
    crosses = (sx * sy <= 0) & (sx != sy)
    t = np.where(crosses, sx, 0.0) / np.where(crosses, sx - sy, 1.0)
    z = x[:, None] + t[..., None] * (y - x)[:, None]                         # (m, b, 3)
    E = np.roll(V, -1, axis=1) - V                                           # (b, k, 3)
    side = np.einsum("mbkx,bx->mbk", cross(E[None], z[:, :, None] - V[None]), N)
    inside = (side >= -band * np.linalg.norm(E, axis=2)[None]).all(axis=2)
    return bool((~(crosses & inside)).all(axis=1).any())


def _rational(V):
    return [tuple(Fraction(float(c)) for c in v) for v in np.asarray(V, dtype=float)]


def _floats(V):
    return np.array([[float(c) for c in v] for v in V])


def _side(nf, d, v):
    """``nf . v - d`` for rationals (Fraction or int) as an integer numerator and a
    positive denominator, no Fraction made (its sign is the numerator's)."""
    num, den = -d.numerator, d.denominator
    for x, y in zip(nf, v):
        term, per = x.numerator * y.numerator, x.denominator * y.denominator
        num, den = num * per + term * den, den * per
    return num, den


def _exact_normal(K):
    """The normal (rationals) of K's first vertex and the next two not collinear with
    it; None where all are."""
    a = K[0]
    for j in range(2, len(K)):
        u = [K[1][i] - a[i] for i in range(3)]
        v = [K[j][i] - a[i] for i in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        if any(n):
            return n
    return None


def _hidden(P, Q, walls, band, depth, budget, exact, plan):
    """Whether the walls hide all of Q from all of P (both convex), with up to
    ``depth`` more planes behind the first; ``budget``: tests left. ``exact``: P, Q and
    the pieces in rationals, decided exactly; else in doubles, by GEOS (a plan: only
    where it finds the pair hidden is the exact search run). ``plan``: the search in
    doubles records its nodes there (:class:`~exactff.area.wall_plan.Plan`), and the
    exact search takes the order of its tries from them where it meets the same pair."""
    Pf, Qf = (_floats(P), _floats(Q)) if exact else (P, Q)
    scored = plan.find(depth, Pf, Qf, band) if exact else None
    if scored is None:
        scored = float_scores(Pf, Qf, walls, band, plan.sides)
    node = None if exact else plan.add(depth, Pf, Qf, scored)
    for share, _, w, hull, left in scored[:tol.AREA_WALL_TRIES]:
        if depth == 0 and share > tol.AREA_WALL_BAND:
            break
        budget[0] -= 1
        if budget[0] < 0:
            return False
        pieces = _uncovered_exactly(P, Q, w) if exact else float_pieces(hull, left, w)
        if pieces is None:
            continue
        if pieces and (depth == 0 or len(pieces) > tol.AREA_WALL_PIECES):
            continue
        if all(_hidden(P, U, walls, band, depth - 1, budget, exact, plan)
               or _hidden(U, Q, walls, band, depth - 1, budget, exact, plan)
               for U in pieces):
            if node is not None:
                node[-1] = w
            return True
    return False


def _uncovered_exactly(P, Q, w):
    """The slice of (P, Q) in w's exact plane less w's exact covers, in rationals: its
    convex pieces of positive area, lifted back into the plane (an empty list where it
    is covered but for a set of no area); None where w has no exact plane, or P and Q
    are not on opposite closed sides of it with neither in it."""
    exact = w.exact()
    if exact is None:
        return None
    nf, d, axis, keep, covers = exact

    # each vertex's side, nf . v - d, as (numerator, positive denominator), P's made
    # positive
    sP, sQ = [_side(nf, d, v) for v in P], [_side(nf, d, v) for v in Q]
    if not any(n > 0 for n, _ in sP):
        sP, sQ = [(-n, m) for n, m in sP], [(-n, m) for n, m in sQ]
    if (any(n < 0 for n, _ in sP) or any(n > 0 for n, _ in sQ)
            or not any(n > 0 for n, _ in sP) or not any(n < 0 for n, _ in sQ)):
        return None
    # the slice: the crossings of the vertex pairs on strictly opposite sides, and the
    # vertices in the plane, projected on the two axes kept
    pts = [(v[keep[0]], v[keep[1]]) for v, s in zip(P + Q, sP + sQ) if s[0] == 0]
    Pk = [(p[keep[0]], p[keep[1]]) for p in P]
    Qk = [(q[keep[0]], q[keep[1]]) for q in Q]
    for p, a in zip(Pk, sP):
        for q, b in zip(Qk, sQ):
            if a[0] > 0 > b[0]:
                pts.append(crossing(p, q, a, b))
    piece = hull(pts)
    if not has_area(piece):
        return None
    # each cover taken from the pieces whose boxes (doubles, made once a piece) overlap
    # its own: skipping a cover only leaves more uncovered, so the boxes need no proof
    boxed = [(piece, _float_box(piece))]
    for K2, (klo, khi) in covers:
        (kx0, ky0), (kx1, ky1) = klo.tolist(), khi.tolist()
        out = []
        for piece, box in boxed:
            x0, y0, x1, y1 = box
            if x0 >= kx1 or y0 >= ky1 or x1 <= kx0 or y1 <= ky0:
                out.append((piece, box))
            else:
                out.extend((p, _float_box(p)) for p in minus_convex(piece, K2))
        boxed = out
        if not boxed:
            return []
    pieces = _joined([piece for piece, _ in boxed])
    # lifted back into the plane: the axis dropped from nf . x = d
    lifted = []
    for piece in pieces:
        U = []
        for u in piece:
            x = [None] * 3
            x[keep[0]], x[keep[1]] = u
            x[axis] = (d - nf[keep[0]] * u[0] - nf[keep[1]] * u[1]) / nf[axis]
            U.append(tuple(x))
        lifted.append(U)
    return lifted


def _float_box(piece):
    """The box of a polygon of rationals in doubles: (x min, y min, x max, y max)."""
    xs, ys = [float(x) for x, _ in piece], [float(y) for _, y in piece]
    return min(xs), min(ys), max(xs), max(ys)


def _joined(pieces):
    """The convex hulls of the pieces that touch one another (grouped by GEOS in
    doubles: any grouping gives hulls that hold every piece, so the grouping needs no
    proof), the fewer pieces to try further; a piece of no area in doubles (a sliver
    of rationals) stays a group of its own."""
    if len(pieces) == 1:
        return pieces
    shapes = [shapely.Polygon([(float(x), float(y)) for x, y in piece]) for piece in pieces]
    merged = shapely.union_all([s.buffer(0) for s in shapes if s.area > 0])
    parts = [g for g in getattr(merged, "geoms", [merged]) if not g.is_empty]
    groups = {}
    for k, (piece, shape) in enumerate(zip(pieces, shapes)):
        point = shape.representative_point() if shape.area > 0 else None
        if point is None or point.is_empty or not parts:
            groups[-1 - k] = list(piece)
            continue
        i = min(range(len(parts)), key=lambda i: parts[i].distance(point))
        groups.setdefault(i, []).extend(piece)
    return [hull(pts) for pts in groups.values()]
