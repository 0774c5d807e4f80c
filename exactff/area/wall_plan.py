"""The plan for the walls' proof (:mod:`exactff.area.walls`): the search for walls that
hide a pair whole, in doubles with GEOS, whose nodes the exact search then follows
(docs/explanation/area-form-factors.md, "Walls between the pair"). Nothing here is a
proof: the scores only order the exact search's tries, and a plane the plan does not
try, or tries in another order, only costs the proof a try or makes it fail.
"""

import numpy as np
import shapely

from .. import _tolerances as tol

__all__ = ["Plan", "float_scores", "float_pieces", "wall_sides"]


class Plan(list):
    """The nodes of the search in doubles, for the exact search to follow.

    Each node is ``[depth, box of P, box of Q, scored walls, wall that hid it or
    None]``, the depth the planes left behind it, the boxes as ``(x min, y min, z min,
    x max, y max, z max)``; ``sides`` keeps the
    polygons' sides on the walls by identity (:func:`wall_sides`: P and Q come down to
    their pieces' nodes as they are).

    Examples
    --------
    >>> plan = Plan()
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> Q = P + [0, 0, 2]
    >>> a, b = "wall a", "wall b"
    >>> node = plan.add(2, P, Q, [(0.0, 0, a, None, None), (0.5, 1, b, None, None)])
    >>> node[-1] = b                            # the plan found b hid the pair
    >>> [s[2] for s in plan.find(2, P + 1e-12, Q, 1e-9)], plan.find(2, P + 1e-6, Q, 1e-9)
    (['wall b', 'wall a'], None)
    >>> plan.find(1, P, Q, 1e-9) is None        # another depth
    True
    """

    def __init__(self):
        super().__init__()
        self.sides = {}

    def add(self, depth, Pf, Qf, scored):
        """Record a node of the search in doubles: its depth, the pair (Pf, Qf), (k, 3)
        arrays, and its scored walls (:func:`float_scores`); returns the node, whose
        last item the search sets to the wall that hid it."""
        node = [depth, _box(Pf), _box(Qf), scored, None]
        self.append(node)
        return node

    def find(self, depth, Pf, Qf, band):
        """The scored walls of a node of that depth whose pair's boxes are within
        ``band`` of those of (Pf, Qf), the wall that hid it first (a node that was hidden
        before one that was not); None where no node is. The exact search takes from
        here which walls it tries and in what order (each decided in rationals), so a
        node matched wrongly costs tries, never a wrong proof."""
        boxes = _box(Pf), _box(Qf)
        found = None
        for at, Pbox, Qbox, scored, proved_by in self:
            if (at == depth and np.abs(Pbox - boxes[0]).max() <= band
                    and np.abs(Qbox - boxes[1]).max() <= band):
                found = scored, proved_by
                if proved_by is not None:
                    break
        if found is None:
            return None
        scored, proved_by = found
        return sorted(scored, key=lambda s: (s[2] is not proved_by,) + s[:2])


def _box(X):
    return np.concatenate([X.min(axis=0), X.max(axis=0)])


def float_scores(Pf, Qf, walls, band, sides=None):
    """The walls that may hide part of Q from P, best first (doubles, GEOS).

    The walls whose plane has P on one closed side and Q on the other, neither in it,
    that cover part of the slice: the hull of the crossings of the segments between
    their vertices, less the wall's union. All the walls are scored together: their
    sides, the crossings and the slices' boxes in arrays, the hulls and their
    differences in one vectorized GEOS call each.

    Parameters
    ----------
    Pf, Qf : ndarray of shape (k, 3)
        The pair (convex).
    walls : list of walls
        ``exactff.area.walls``'s walls: each with a unit normal ``n``, an offset ``d``
        and ``union()`` (its blockers' union in the two axes it keeps); the list with
        ``keep`` (walls, 2) those axes and ``lo``, ``hi`` (walls, 2) their boxes.
    band : float
        Within it of a plane is in the plane.
    sides : dict, optional
        :func:`wall_sides`' kept sides, for calls on the same walls.

    Returns
    -------
    list of (share, position, wall, hull, uncovered part)
        Sorted by the share of the slice GEOS finds uncovered, then by the walls'
        order; only walls that leave less than ``1 - AREA_WALL_BAND`` of it.

    Examples
    --------
    The wall x = 0 (y, z in [0, 1]) between two squares facing each other across it:

    >>> from types import SimpleNamespace
    >>> wall = SimpleNamespace(n=np.array([1.0, 0, 0]), d=0.0, keep=[1, 2],
    ...                        union=lambda: shapely.box(0, 0, 1, 1))
    >>> walls = type("Walls", (list,), {})([wall])
    >>> walls.keep, walls.lo, walls.hi = np.array([[1, 2]]), np.zeros((1, 2)), np.ones((1, 2))
    >>> square = np.array([[0.0, 0.25, 0.25], [0, 0.75, 0.25], [0, 0.75, 0.75], [0, 0.25, 0.75]])
    >>> scored = float_scores(square + [1, 0, 0], square - [1, 0, 0], walls, 1e-9)
    >>> [(float(share), w is wall) for share, _, w, _, _ in scored]
    [(0.0, True)]
    """
    if not len(walls):
        return []
    # each vertex's distance from each wall's plane, P's side made positive (each wall's
    # product as its own, `P @ n - d`: a matrix product may fuse other roundings)
    sP, sQ = wall_sides(Pf, walls, sides), wall_sides(Qf, walls, sides)
    flip = np.where(sP.min(axis=0) < -band, -1.0, 1.0)
    sP, sQ = sP * flip, sQ * flip
    c = np.flatnonzero(~(sP.min(axis=0) < -band) & ~(sQ.max(axis=0) > band)
                       & (sP.max(axis=0) > band) & (sQ.min(axis=0) < -band))
    if not len(c):
        return []
    a, b = sP[:, c], sQ[:, c]                                          # (kP, C), (kQ, C)
    # the crossings of the vertex pairs on strictly opposite sides, (kP, kQ, C, 3), and
    # the vertices in the plane
    crosses = (a > band)[:, None] & (b < -band)[None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[:, None] / (a[:, None] - b[None]))[..., None]
        pts = Pf[:, None, None] + t * (Qf[None, :, None] - Pf[:, None, None])
    keep = walls.keep[c]                                               # (C, 2)
    cols = np.arange(len(c))
    X = np.concatenate([pts.reshape(-1, len(c), 3),                    # (m, C, 3)
                        np.broadcast_to(Pf[:, None], (len(Pf), len(c), 3)),
                        np.broadcast_to(Qf[:, None], (len(Qf), len(c), 3))])
    valid = np.concatenate([crosses.reshape(-1, len(c)), np.abs(a) <= band,
                            np.abs(b) <= band])
    uv = np.stack([X[:, cols, keep[:, 0]], X[:, cols, keep[:, 1]]], axis=-1)  # (m, C, 2)
    lo = np.where(valid[..., None], uv, np.inf).min(axis=0)
    hi = np.where(valid[..., None], uv, -np.inf).max(axis=0)
    near = ~(np.any(lo > walls.hi[c], axis=1) | np.any(hi < walls.lo[c], axis=1))
    # (a slice of fewer than three points has no area, and GEOS makes no line string of
    # one point)
    near &= valid.sum(axis=0) >= 3
    if not near.any():
        return []
    c, uv, valid = c[near], uv[:, near], valid[:, near]
    wall, point = np.nonzero(valid.T)                 # points grouped by wall, in order
    # each slice's hull: GEOS's hull of a line string through the points is that of the
    # points (the same coordinates in the same order), and is made without a geometry
    # a point
    hulls = shapely.convex_hull(shapely.linestrings(uv[point, wall], indices=wall))
    areas = shapely.area(hulls)
    live = np.flatnonzero(areas > 0)
    unions = np.empty(len(live), dtype=object)
    unions[:] = [walls[int(c[k])].union() for k in live]
    lefts = shapely.difference(hulls[live], unions)
    scored = []
    for k, left, left_area in zip(live.tolist(), lefts, shapely.area(lefts).tolist()):
        if left_area < (1.0 - tol.AREA_WALL_BAND) * areas[k]:
            scored.append((left_area / areas[k], len(scored), walls[int(c[k])], hulls[k],
                           left))
    scored.sort(key=lambda s: s[:2])
    return scored


def wall_sides(X, walls, sides=None):
    """Each vertex's signed distance from each wall's plane, ``X @ n - d``.

    Each wall's product is its own (a matrix product of all the walls at once may fuse
    other roundings).

    Parameters
    ----------
    X : ndarray of shape (k, 3)
    walls : list of walls (each with ``n`` and ``d``)
    sides : dict, optional
        The sides kept by the identity of X, with X (so that the identity stays its
        own).

    Returns
    -------
    ndarray of shape (k, walls)

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> walls = [SimpleNamespace(n=np.array([1.0, 0, 0]), d=0.5)]
    >>> wall_sides(np.array([[0.0, 0, 0], [2, 0, 0]]), walls).tolist()
    [[-0.5], [1.5]]
    """
    kept = sides.get(id(X)) if sides is not None else None
    if kept is not None:
        return kept[1]
    S = np.stack([X @ w.n - w.d for w in walls], axis=1)
    if sides is not None:
        sides[id(X)] = X, S
    return S


def float_pieces(hull, left, w):
    """The plan's pieces past a wall: the convex hulls of the uncovered part's
    components (doubles) lifted into the wall's plane.

    Parameters
    ----------
    hull, left : shapely geometry
        The slice and its part the wall leaves uncovered (:func:`float_scores`), in the
        wall's two axes kept.
    w : wall
        With ``n``, ``d`` and ``keep``.

    Returns
    -------
    list of ndarray of shape (k, 3)
        Those above ``AREA_WALL_SLIVER`` of the slice's area; none where the uncovered
        part is within ``AREA_WALL_BAND`` of that area.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> wall = SimpleNamespace(n=np.array([1.0, 0, 0]), d=0.0, keep=[1, 2])
    >>> hull = shapely.box(0, 0, 1, 1)
    >>> (X,) = float_pieces(hull, hull.difference(shapely.box(0, 0, 1, 0.5)), wall)
    >>> X.min(axis=0).tolist(), X.max(axis=0).tolist()         # x = 0, the upper half
    ([0.0, 0.0, 0.5], [0.0, 1.0, 1.0])
    """
    if left.area <= tol.AREA_WALL_BAND * hull.area:
        return []
    axis = [a for a in range(3) if a not in w.keep][0]
    pieces = []
    for g in getattr(left, "geoms", [left]):
        if g.area > tol.AREA_WALL_SLIVER * hull.area:
            uv = np.asarray(g.convex_hull.exterior.coords)[:-1]
            X = np.empty((len(uv), 3))
            X[:, w.keep] = uv
            X[:, axis] = (w.d - uv @ w.n[w.keep]) / w.n[axis]
            pieces.append(X)
    return pieces
