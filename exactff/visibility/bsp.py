"""BSP tree (autopartition) of a scene, and its front-to-back traversal from a point."""

import math
import weakref
from fractions import Fraction

import numpy as np
import shapely

from .. import _tolerances as tol
from ..geometry import point_polygon_distance
from ..halfspace import split_polygon
from ..predicates import (coplanar_band_sides, coplanar_pairs, gamma, point_plane_offsets,
                          sides_of_point, tie_priority)
from ..prepared import prepared
from ..rings import padded_buckets

__all__ = ["BSPTree", "build_bsp", "scene_bsp", "front_to_back", "node_sides", "node_first_charges",
           "coplanar_overlaps"]


class BSPTree:
    """A binary space partition of a scene's polygons, built once and reused per point.

    Attributes
    ----------
    normals : ndarray of shape (M, 3)
        Splitting plane of each node: ``normals[k] . x = offsets[k]``.
    offsets : ndarray of shape (M,)
    front, back : ndarray of shape (M,), int
        Child node indices, -1 for none.
    node_fragments : list of list of int
        Fragments lying in each node's plane, in the order they are in front when the
        point is on the node's front side (:func:`exactff.predicates.tie_priority`).
    node_fragments_behind : list of list of int
        The same fragments in their order for a point behind the node's plane.
    fragments : list of ndarray of shape (K, 3)
        Polygons and pieces of polygons cut by splitting planes.
    source : ndarray of shape (F,), int
        The scene polygon each fragment comes from.
    splits : int
        Number of fragment splits made while building.
    whole : ndarray of shape (F,), bool
        Whether each fragment is its source polygon, uncut (the same vertices in the
        same order).
    vertex_errors : list of ndarray of shape (K,), or None
        Per fragment vertex, a bound on its distance from the exact point it stands for:
        0 for an input vertex, the rounding of a split's crossing (and of the splitting
        plane, or the snap to an end point) for the others. Both builds give them (the
        Python engine charges them to its values: ``engine._crossing_charges``).
    node_members : tuple of 4 ndarrays
        The nodes' own fragments as flat arrays, node by node: each one's node, source
        polygon, facing along the node's normal (+1, -1), and each node's start in them
        (length M + 1).
    """

    def __init__(self, normals, offsets, front, back, node_fragments, fragments, source, splits,
                 source_normals, whole=None, vertex_errors=None):
        self.normals = normals
        self.vertex_errors = vertex_errors
        self._offsets_cache = None      # fragment_offsets, once asked
        self._subtrees_cache = None     # subtree_fragments, once asked
        self._magnitudes_cache = None   # plane_magnitudes, once asked
        self.whole = (np.ones(len(fragments), dtype=bool) if whole is None
                      else np.asarray(whole, dtype=bool))
        self.offsets = offsets
        self.front = front
        self.back = back
        self.fragments = fragments
        self.source = source
        self.splits = splits
        # coplanar ties (one rule, exactff.predicates.tie_priority): fragments whose
        # front faces the point first, then input order of their source polygons
        sizes = np.array([len(here) for here in node_fragments], dtype=np.int64)
        flat = np.fromiter((f for here in node_fragments for f in here), dtype=np.int64,
                           count=int(sizes.sum()))
        node = np.repeat(np.arange(len(sizes)), sizes)
        orient = np.sign(np.einsum("ij,ij->i", source_normals[self.source[flat]],
                                   normals[node])) if len(flat) else np.zeros(0)
        # each node's fragments' sources and their facing along the node's normal, by
        # node (node_sides reads them every row)
        self.node_members = (node, self.source[flat], orient.astype(np.int8),
                              np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64))
        self.node_member_fragments = flat
        bounds = np.concatenate([[0], np.cumsum(sizes)]).tolist()
        for facing, dest in ((orient, "node_fragments"), (-orient, "node_fragments_behind")):
            # tie_priority's order (facing away last, then source) within each node,
            # stable; a lone fragment keeps its place
            order = np.lexsort((tie_priority(facing, self.source[flat]) if len(flat) else flat,
                                node))
            ordered = flat[order].tolist()
            setattr(self, dest, [ordered[a:b] for a, b in zip(bounds[:-1], bounds[1:])])

    def fragment_offsets(self):
        """Per node, how far its own fragments reach off its plane on either side.

        The largest signed offset ``n @ v - d`` of their vertices less its rounding, and
        the smallest plus it (the rounding of the float offset, ``gamma(4)`` times
        ``|n| @ |v| + |d|``, and the vertex's own bound from a split,
        ``self.vertex_errors``). The polygons
        coplanar with the node's by the band's rule
        (:func:`exactff.predicates.coplanar_band`) lie in the node on either side of its
        plane. Computed once (cached).

        Returns
        -------
        (ndarray of shape (len(self),), ndarray of shape (len(self),))
            ``hi`` and ``lo`` (-inf and +inf for a node without fragments): a vertex lies
            surely beyond a point at offset ``o`` (with its own rounding ``r``) on the front
            side where ``hi > o + r``, on the back side where ``lo < o - r``.
        """
        if self._offsets_cache is not None:
            return self._offsets_cache
        sizes = np.array([len(here) for here in self.node_fragments], dtype=np.int64)
        flat = np.fromiter((f for here in self.node_fragments for f in here), dtype=np.int64,
                           count=int(sizes.sum()))
        hi, lo = np.full(len(self), -np.inf), np.full(len(self), np.inf)
        if len(flat):
            frags = flat.tolist()
            counts = np.array([len(self.fragments[f]) for f in frags], dtype=np.int64)
            V = np.concatenate([self.fragments[f] for f in frags])
            node = np.repeat(np.repeat(np.arange(len(self)), sizes), counts)
            N, D = self.normals[node], self.offsets[node]
            off = np.einsum("ij,ij->i", N, V) - D
            r = gamma(4) * (np.einsum("ij,ij->i", np.abs(N), np.abs(V)) + np.abs(D))
            if self.vertex_errors is not None:
                r = r + np.concatenate([self.vertex_errors[f] for f in frags]) * np.linalg.norm(N, axis=1)
            np.maximum.at(hi, node, off - r)
            np.minimum.at(lo, node, off + r)
        self._offsets_cache = (hi, lo)
        return hi, lo

    def plane_magnitudes(self):
        """``abs(normals)`` and ``abs(offsets)``: the scale of the rounding of a point's
        offsets from the nodes' planes (:func:`exactff.predicates.point_plane_offsets`),
        asked every row. Computed once (cached).

        Returns
        -------
        (ndarray of shape (len(self), 3), ndarray of shape (len(self),))
        """
        if self._magnitudes_cache is None:
            self._magnitudes_cache = (np.abs(self.normals), np.abs(self.offsets))
        return self._magnitudes_cache

    def subtree_fragments(self):
        """The tree's nodes in preorder (each subtree a run), its fragments by node in that
        order, and the fragments' boxes; cached on the self. Returns ``(pre, end, by_pre,
        start, lo, hi)``: node c's subtree holds the fragments
        ``by_pre[start[pre[c]]:start[end[c]]]``."""
        if self._subtrees_cache is not None:
            return self._subtrees_cache
        M = len(self)
        pre, end = np.zeros(M, dtype=np.int64), np.zeros(M, dtype=np.int64)
        order, stack = [], [(0, False)]
        while stack:
            k, done = stack.pop()
            if done:
                end[k] = len(order)
                continue
            pre[k] = len(order)
            order.append(k)
            stack.append((k, True))
            for c in (self.back[k], self.front[k]):
                if c >= 0:
                    stack.append((int(c), False))
        sizes = np.array([len(self.node_fragments[k]) for k in order], dtype=np.int64)
        start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        by_pre = np.fromiter((f for k in order for f in self.node_fragments[k]), dtype=np.int64,
                             count=int(sizes.sum()))
        counts = np.array([len(P) for P in self.fragments], dtype=np.int64)
        V = np.concatenate(self.fragments) if len(counts) else np.zeros((0, 3))
        at = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        lo = np.minimum.reduceat(V, at) if len(counts) else np.zeros((0, 3))
        hi = np.maximum.reduceat(V, at) if len(counts) else np.zeros((0, 3))
        self._subtrees_cache = (pre, end, by_pre, start, lo, hi)
        return self._subtrees_cache

    def __len__(self):
        return len(self.offsets)

    def depth(self):
        """Number of nodes on the longest path from the root to a leaf.

        Examples
        --------
        >>> from exactff.scenes import subdivided_box
        >>> build_bsp(subdivided_box(2)).depth()
        6
        """
        best, stack = 0, [(0, 1)]
        while stack:
            k, d = stack.pop()
            best = max(best, d)
            stack += [(int(c), d + 1) for c in (self.front[k], self.back[k]) if c >= 0]
        return best

    def __repr__(self):
        return (f"<BSPTree: {len(self)} nodes, {len(self.fragments)} fragments from "
                f"{len(set(self.source.tolist()))} polygons, {self.splits} splits>")



def _split_plane(scene, s, cache):
    """The plane polygon ``s`` splits along, exactly (as the compiled build's
    ``SplitPlane``): for an exactly planar polygon (every triangle) its own plane, as
    ``(N, c)`` with ``N . x = c`` through three of its vertices; for one planar only
    within the validation tolerance its plane ``(n, d)`` as the scene stores it."""
    if s not in cache:
        P = [tuple(Fraction(float(c)) for c in v) for v in scene.polygons[s]]
        V = scene.polygons[s]
        b = int(np.argmax(((V - V[0]) ** 2).sum(axis=1)))
        c = int(np.argmax((np.cross(V[b] - V[0], V - V[0]) ** 2).sum(axis=1)))
        u = [x - y for x, y in zip(P[b], P[0])]
        w = [x - y for x, y in zip(P[c], P[0])]
        N = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        off = sum(x * y for x, y in zip(N, P[0]))
        if N != (0, 0, 0) and all(sum(x * y for x, y in zip(N, v)) == off for v in P):
            if sum(x * float(y) for x, y in zip(N, scene.normals[s])) < 0:
                N, off = tuple(-x for x in N), -off
            cache[s] = (N, off)
        else:
            cache[s] = (tuple(Fraction(float(x)) for x in scene.normals[s]),
                        Fraction(float(scene.plane_offsets[s])))
    return cache[s]


def _integer_plane(plane):
    """A plane of :func:`_split_plane` as integers ``(M, e)``: ``M . x = e`` is
    ``N . x = c`` times a positive power of two (its coefficients are dyadic, sums of
    products of doubles)."""
    N, c = plane
    D = max(f.denominator for f in (*N, c))
    return [f.numerator * (D // f.denominator) for f in N], c.numerator * (D // c.denominator)


def _homogeneous_value(plane, X):
    """``M . x - e w`` for an integer plane ``(M, e)`` (:func:`_integer_plane`) and a
    point in homogeneous integers ``(x, w)`` (the point ``x / w``): ``w`` times the
    plane's value there, up to the plane's positive factor."""
    (M, e), (x, w) = plane, X
    return M[0] * x[0] + M[1] * x[1] + M[2] * x[2] - e * w


class _ExactPoints:
    """The exact points the build's vertices stand for: an input vertex is its floats;
    a crossing, recorded at the split that made it (its edge's end points and the plane),
    is the exact crossing of the exact edge with the exact plane, computed when asked
    for (the side of a vertex within the near-coplanar band, a crossing of an edge
    between crossings), as the compiled build keeps its crossings in quadruple
    precision or exactly. Keyed by the rounded point (two crossings that round alike
    stand for one point, as a shared edge splits identically). A key stands for the
    point it stood for when first asked about (an input vertex then stays one: the set
    ``inputs``).

    The points are rationals in homogeneous integers ``(x, w)``, the point ``x / w``:
    an input vertex's doubles over one power of two, a crossing's from its ends' without
    a common divisor taken out (rationals' greatest common divisors cost more than they
    save here); the planes are integer planes (:func:`_integer_plane`)."""

    def __init__(self):
        self.defined, self.known, self.inputs = {}, {}, set()

    def record(self, X, A, B, plane):
        self.defined.setdefault(tuple(X.tolist()), (tuple(A.tolist()), tuple(B.tolist()), plane))

    def is_input(self, key):
        """Whether ``key`` stands for its own floats (an input vertex, or a point first
        asked about before any crossing rounded to it)."""
        if key in self.inputs:
            return True
        if key in self.known or key in self.defined:
            return False
        self.inputs.add(key)
        return True

    def point(self, key):
        """The exact point ``key`` stands for, in homogeneous integers ``(x, w)``."""
        if key in self.known:
            return self.known[key]
        if self.is_input(key):
            ratios = [c.as_integer_ratio() for c in key]
            w = max(q for _, q in ratios)
            value = [a * (w // q) for a, q in ratios], w
        else:
            A, B, plane = self.defined[key]
            value = self.crossing(self.point(A), self.point(B), plane)
        self.known[key] = value
        return value

    def side(self, plane, key):
        """The exact side (-1, 0, +1) of the point ``key`` stands for of an integer
        plane."""
        X = self.point(key)
        value = _homogeneous_value(plane, X)     # w > 0: the side's sign
        return (value > 0) - (value < 0)

    @staticmethod
    def crossing(A, B, plane):
        """The crossing ``(o_A B - o_B A) / (o_A - o_B)`` (``o``: the plane's values) of
        the segment between homogeneous points ``A = a / u``, ``B = b / v`` (``u, v >
        0``) with an integer plane: ``(O_A b - O_B a) / (O_A v - O_B u)``,
        ``O = M . x - e w``, its signs taken so that the divisor is positive."""
        oa, ob = _homogeneous_value(plane, A), _homogeneous_value(plane, B)
        if oa * B[1] - ob * A[1] < 0:
            oa, ob = -oa, -ob                    # w > 0 (a zero coordinate rounds to +0)
        x, w = [oa * y - ob * x for x, y in zip(A[0], B[0])], oa * B[1] - ob * A[1]
        g = math.gcd(*x, w)         # in lowest terms: a crossing of crossings stays small
        return [c // g for c in x], w // g

    @staticmethod
    def rounded(X):
        """A homogeneous point rounded to the nearest doubles (an integer division is
        correctly rounded, as ``float`` of the rational)."""
        x, w = X
        return np.array([c / w for c in x])


class _RuleCache:
    """What the Python build's exact sides (:func:`_rule_sides`) reuse from node to node:
    the exact split planes (``planes``, :func:`_split_plane`) and their nearest doubles,
    the exact points (``points``, :class:`_ExactPoints`), the coplanar verdicts of
    (source polygon, plane polygon) pairs and the exact sides of (plane, point) pairs
    already decided, and the scene's plane offsets (computed once)."""

    def __init__(self, scene):
        self.planes, self.points = {}, _ExactPoints()
        self.rounded, self.integers, self.coplanar, self.signs = {}, {}, {}, {}
        self.plane_offsets = scene.plane_offsets

    def integer_plane(self, key, plane):
        """``plane`` (:func:`_split_plane`) as integers (:func:`_integer_plane`)."""
        if key not in self.integers:
            self.integers[key] = _integer_plane(plane)
        return self.integers[key]

    def rounded_plane(self, key, plane):
        """``plane`` (:func:`_split_plane`) rounded to doubles ``(n, d)``, or None where a
        coefficient overflows or falls below the normal range (no float filter then)."""
        if key not in self.rounded:
            try:
                n = np.array([float(x) for x in plane[0]])
                d = float(plane[1])
            except OverflowError:
                n = None
            tiny = np.finfo(float).tiny
            ok = (n is not None and np.all(np.isfinite(n)) and np.isfinite(d)
                  and not np.any((n != 0) & (np.abs(n) < tiny)) and not 0 < abs(d) < tiny)
            self.rounded[key] = (n, d) if ok else None
        return self.rounded[key]


def _rule_sides(scene, sign, V, vertex_source, planes, cache):
    """The sides of vertices ``V`` (their fragments' source polygons ``vertex_source``)
    for node planes (columns of ``sign``, the near-coplanar band's: 0 within it), by the
    rule of docs/explanation/conventions.md: a vertex within the band lies in the plane
    where its polygon is coplanar with the plane's (every vertex of one within the
    other's band, :func:`exactff.predicates.coplanar_pairs`); else the exact side of the
    point it stands for (:class:`_ExactPoints`) of the plane it is split along
    (:func:`_split_plane`; an axis plane ``("axis", k, c)``). ``planes``: per column, a
    source polygon or an axis plane; ``cache``: the build's :class:`_RuleCache`. Changes
    ``sign`` in place (as the compiled build, ``Builder::sides``).

    The exact side of an input vertex is the sign of ``N . x - c`` computed in doubles
    where it exceeds that computation's error bound (the plane rounded to doubles and
    four roundings, ``gamma(8) (|n| . |x| + |d|)`` of the rounded plane: a float
    filter), else exactly (:meth:`_ExactPoints.side`), once per plane and point."""
    columns = [(col, plane, np.flatnonzero(sign[:, col] == 0))
               for col, plane in enumerate(planes)]
    columns = [(col, plane, rows) for col, plane, rows in columns if len(rows)]
    # the coplanar verdicts not yet known, every column's at once
    need = {}
    for col, plane, rows in columns:
        if not isinstance(plane, tuple):
            for src in np.unique(vertex_source[rows]).tolist():
                if (src, plane) not in cache.coplanar:
                    need[src, plane] = True
    if need:
        a, b = np.array(list(need), dtype=np.int64).T
        verdict = coplanar_pairs(scene.vertices, scene.offsets, scene.normals,
                                 cache.plane_offsets, a, b) | (a == b)
        cache.coplanar.update(zip(need, verdict.tolist()))
    points, known = cache.points, cache.signs
    for col, plane, rows in columns:
        if isinstance(plane, tuple):
            P = _axis_plane(plane[1], plane[2])
        else:
            coplanar = np.array([cache.coplanar[src, plane]
                                 for src in vertex_source[rows].tolist()], dtype=bool)
            rows = rows[~coplanar]
            if not len(rows):
                continue
            P = _split_plane(scene, int(plane), cache.planes)
        rounded = cache.rounded_plane(plane, P)
        X = V[rows]
        if rounded is None:
            sure = np.zeros(len(rows), dtype=bool)
            value = sure
        else:
            n, d = rounded
            value = X @ n - d
            sure = np.abs(value) > gamma(8) * (np.abs(X) @ np.abs(n) + abs(d))
        integer = cache.integer_plane(plane, P)
        for r, x, filtered, v in zip(rows.tolist(), X.tolist(), sure.tolist(),
                                     value.tolist()):
            key = tuple(x)
            if filtered and points.is_input(key):
                sign[r, col] = 1 if v > 0 else -1
                continue
            side = known.get((plane, key))
            if side is None:
                side = known[plane, key] = points.side(integer, key)
            sign[r, col] = side
    return sign


def _axis_plane(axis, c):
    """The axis plane ``x_axis = c`` as an exact plane of :func:`_split_plane`."""
    return tuple(Fraction(int(i == axis)) for i in range(3)), Fraction(float(c))


def _crossings(plane, P, exact, errors):
    """A crossing function for :func:`exactff.halfspace.split_polygon` along the exact
    plane ``plane`` (:func:`_split_plane`): the exact crossing of the points the edge's
    ends stand for (``exact``, :class:`_ExactPoints`), rounded once to the nearest
    double, and recorded. The compiled build rounds the same point (from quadruple
    precision where that rounds it unambiguously, else exactly): the two builds place
    every crossing alike, which the exact sides of later planes need (a vertex an ulp
    off a plane is on one side of it).

    ``errors`` (a dict, rounded point -> bound) gets each crossing's distance from the
    exact point it stands for: the rounding, ``|X - X*| <= u |X|`` (``u = 2**-53``, each
    coordinate within half an ulp), or, where the split snaps it to an end point ``E``
    (``BSP_SPLIT_SNAP_EPS``, as :func:`exactff.halfspace.split_polygon` decides), ``|E -
    X| + u |X|`` at ``E``. Keyed by the point, over the whole tree: a vertex that rounds
    alike elsewhere is charged there too (conservative)."""

    integer = _integer_plane(plane)
    reach = tol.BSP_SPLIT_SNAP_EPS * float(np.finfo(float).eps)

    def crossing(a, b):
        X = exact.rounded(exact.crossing(exact.point(tuple(P[a].tolist())),
                                         exact.point(tuple(P[b].tolist())), integer))
        exact.record(X, P[a], P[b], integer)
        # its distance from the exact point (a margin of 4 roundings for this sum)
        rounding = _UNIT_ROUNDOFF * float(np.linalg.norm(X))
        at = [(tuple(E.tolist()), float(np.linalg.norm(X - E)) + rounding)
              for E in (P[a], P[b]) if np.all(np.abs(X - E) <= reach * np.abs(E).max())]
        for key, bound in at or [(tuple(X.tolist()), rounding)]:
            errors[key] = max(errors.get(key, 0.0), bound * (1 + 4 * _UNIT_ROUNDOFF))
        return X

    return crossing


#: the unit roundoff of doubles (half the machine epsilon)
_UNIT_ROUNDOFF = 2.0 ** -53


def _vertex_means(V, starts, counts):
    """Each fragment's mean vertex, its sum taken vertex by vertex from 0 as the compiled
    build takes it (``np.add.reduceat`` sums in another order: the axis planes' medians
    would differ by an ulp, and a vertex on one build's plane be off the other's)."""
    total = np.zeros((len(counts), 3))
    for j in range(int(counts.max(initial=0))):
        live = counts > j
        total[live] += V[starts[:-1][live] + j]
    return total / counts[:, None]


def _plane_scores(sign, starts):
    """Per plane (column of ``sign``): which fragments (runs of ``starts``) have
    vertices in front and behind, and the score ``5 splits + |front - back| - 2
    coplanar`` (fewer cuts, balanced, many fragments settled at once)."""
    pos = np.add.reduceat(sign > 0, starts[:-1], axis=0) > 0      # (fragments, planes)
    neg = np.add.reduceat(sign < 0, starts[:-1], axis=0) > 0
    nsplit = (pos & neg).sum(axis=0)
    imbalance = np.abs((pos & ~neg).sum(axis=0) - (neg & ~pos).sum(axis=0))
    ncop = len(starts) - 1 - (pos | neg).sum(axis=0)
    return 5 * nsplit + imbalance - 2 * ncop, imbalance, pos, neg


def build_bsp(scene, *, candidates=8, seed=0, engine="python"):
    """Build an autopartition BSP tree: split planes are the polygons' own planes.

    At each node up to ``candidates`` planes of the node's fragments are scored by
    ``5 * splits + |front - back| - 2 * coplanar`` and the best is taken (fewer cuts,
    balanced, many fragments settled at once); a node with more than
    ``BSP_SCORE_SAMPLE`` fragments scores them on a random sample of that many, and one
    left badly unbalanced (``BSP_AXIS_IMBALANCE``) also tries a plane through the median
    of its fragments' vertex means along their widest axis. Sides are taken with the
    near-coplanar band (:func:`exactff.predicates.coplanar_band`) where a fragment's
    polygon is coplanar with the plane's by the rule of docs/explanation/conventions.md,
    else exactly (a fragment flush with the plane but not coplanar with its polygon is
    split where it crosses it); crossings are exact, rounded once. Fragments keep their
    source polygon.

    ``engine="compiled"`` builds the same partition in compiled code (``_core/bsp_build.cpp``,
    without the GIL; the compiled visibility core's tree): only its random draws differ,
    so that with every candidate tried (``candidates`` at least the scene's size) and a
    scene of at most ``BSP_SCORE_SAMPLE`` polygons the two trees are the same. Its exact
    tests are expansions of doubles, exact only while no product underflows: a scene
    with a nonzero coordinate below ``BSP_COMPILED_MIN_MAGNITUDE`` in magnitude (a
    subnormal next to 0.1, say) is built by the Python build, whose integers are exact
    at any magnitude (a drawn enclosure with a coordinate of 2.2e-309 came out with a
    fragment on the wrong side of a node).

    Parameters
    ----------
    scene : Scene
    candidates : int
        Planes tried per node.
    seed : int
        Seed of the candidate sampling (the tree is deterministic for a given seed).
    engine : {"python", "compiled"}
        Which build: the Python engine's (numpy, the default) or the compiled one.

    Returns
    -------
    BSPTree

    Examples
    --------
    >>> from exactff.scenes import subdivided_box
    >>> t = build_bsp(subdivided_box(2))
    >>> len(t), len(t.fragments), t.splits
    (6, 24, 0)
    >>> t = build_bsp(subdivided_box(2), engine="compiled")
    >>> len(t), len(t.fragments), t.splits
    (6, 24, 0)
    """
    if engine not in ("python", "compiled"):
        raise ValueError(f"engine must be 'python' or 'compiled', got {engine!r}")
    if not isinstance(candidates, (int, np.integer)) or candidates < 1:
        raise ValueError(f"candidates must be a positive integer, got {candidates!r}")
    if engine == "compiled" and not np.any(
            (scene.vertices != 0) & (np.abs(scene.vertices) < tol.BSP_COMPILED_MIN_MAGNITUDE)):
        return _build_bsp_compiled(scene, candidates, seed)
    rng = np.random.default_rng(seed)
    sampler = np.random.default_rng([seed, 1])    # its own stream: the same candidates
    normals_src = scene.normals
    offsets_src = scene.plane_offsets
    fragments = [np.array(P, dtype=float) for P in scene.polygons]
    source = np.arange(len(scene))          # grows with the split parts (doubling)
    n_frag = len(scene)
    nodes_n, nodes_d, front, back, node_frags = [], [], [], [], []
    splits = 0
    # work items: (fragment ids, their concatenated vertices, their counts, parent node,
    # which child); a node's fragments are classified and distributed with array
    # operations, only the fragments it splits go through Python
    counts0 = np.array([len(P) for P in fragments])
    stack = [(np.arange(n_frag), np.concatenate(fragments), counts0, -1, 0)]
    rules = _RuleCache(scene)
    errors = {}                 # the crossings' distances from their exact points
    while stack:
        ids, V, counts, parent, child = stack.pop()
        node = len(nodes_d)
        if parent >= 0:
            (front if child > 0 else back)[parent] = node
        m = len(ids)
        if m == 1:
            # a leaf: the one fragment's own plane holds it (as the scoring below would)
            c = int(ids[0])
            nodes_n.append(normals_src[source[c]])
            nodes_d.append(offsets_src[source[c]])
            front.append(-1)
            back.append(-1)
            node_frags.append([c])
            continue
        owner = np.repeat(np.arange(m), counts)
        pool = ids.tolist() if m <= candidates else [int(ids[0])] + [
            int(x) for x in rng.choice(ids, size=candidates - 1, replace=False)]
        pool = list(dict.fromkeys(pool))
        starts = np.concatenate([[0], np.cumsum(counts)])
        # the candidates are scored on every fragment of the node, or on a sample of
        # BSP_SCORE_SAMPLE of them at a larger node (the score estimates proportions)
        if m > tol.BSP_SCORE_SAMPLE:
            scored = np.zeros(m, dtype=bool)
            scored[sampler.choice(m, size=tol.BSP_SCORE_SAMPLE, replace=False)] = True
            Vs, cs = V[scored[owner]], counts[scored]
            starts_s = np.concatenate([[0], np.cumsum(cs)])
        else:
            Vs, cs, starts_s = V, counts, starts
        ms = len(cs)
        # every candidate plane at once
        Nc, Dc = normals_src[source[pool]], offsets_src[source[pool]]
        sign_c, s_c = coplanar_band_sides(Vs, Nc, Dc)
        vsrc = np.repeat(source[ids], counts)
        vsrc_s = vsrc if ms == m else vsrc[scored[owner]]
        _rule_sides(scene, sign_c, Vs, vsrc_s, source[pool].tolist(), rules)
        score, imbalance, pos_c, neg_c = _plane_scores(sign_c, starts_s)
        j = int(np.argmin(score))        # the first of equal scores
        c, n, d = pool[j], Nc[j], Dc[j]
        chosen = None if ms < m else (sign_c[:, j], s_c[:, j], pos_c[:, j], neg_c[:, j])
        if m > tol.BSP_AXIS_CANDIDATE_MIN and imbalance[j] > tol.BSP_AXIS_IMBALANCE * ms:
            # the polygons' own planes leave this node badly unbalanced (a convex
            # tessellation has every other facet on one side of each facet, and the
            # tree becomes a chain as deep as the object has facets): also try a plane
            # through the median of the fragments' vertex means along their widest axis
            cen = _vertex_means(V, starts, counts)
            axis = int(np.argmax(np.ptp(cen, axis=0)))
            na, da = np.eye(3)[axis:axis + 1], np.array([np.median(cen[:, axis])])
            a_sign = _rule_sides(scene, coplanar_band_sides(Vs, na, da)[0], Vs, vsrc_s,
                                 [("axis", axis, float(da[0]))], rules)
            a_score, _, _, _ = _plane_scores(a_sign, starts_s)
            if a_score[0] < score[j]:
                c, n, d = None, na[0], da[0]
                chosen = None
                axis_plane = ("axis", axis, float(da[0]))
        if chosen is None:
            # the chosen plane against every fragment (scored on a sample, or the axis)
            sign, s = coplanar_band_sides(V, n[None], np.array([d]))
            _rule_sides(scene, sign, V, vsrc, [source[c] if c is not None else axis_plane],
                        rules)
            _, _, has_pos, has_neg = _plane_scores(sign, starts)
            chosen = sign[:, 0], s[:, 0], has_pos[:, 0], has_neg[:, 0]
        sign, s, has_pos, has_neg = chosen
        nodes_n.append(n)
        nodes_d.append(d)
        front.append(-1)
        back.append(-1)
        # in the plane (or the splitter's own pieces), wholly in front, behind, split
        here = ~has_pos & ~has_neg
        if c is not None:
            here |= source[ids] == source[c]
        to_front = has_pos & ~has_neg & ~here
        to_back = has_neg & ~has_pos & ~here
        cut = has_pos & has_neg & ~here
        node_frags.append(ids[here].tolist())
        parts = {1: [], -1: []}
        split_plane = (_split_plane(scene, int(source[c]), rules.planes) if c is not None
                       else _axis_plane(int(np.argmax(n)), d))
        for k in np.flatnonzero(cut).tolist():
            a, b = starts[k], starts[k + 1]
            f, bk = split_polygon(V[a:b], sign[a:b], s[a:b],
                                  _crossings(split_plane, V[a:b], rules.points, errors),
                                  snap=tol.BSP_SPLIT_SNAP_EPS)
            splits += 1
            for part, side in ((f, 1), (bk, -1)):
                if part is not None:
                    if n_frag == len(source):
                        source = np.concatenate([source, np.zeros(len(source), dtype=int)])
                    fragments.append(part)
                    source[n_frag] = source[ids[k]]
                    parts[side].append((n_frag, part))
                    n_frag += 1
        for mask, side in ((to_front, 1), (to_back, -1)):
            if not mask.any() and not parts[side]:
                continue
            child_ids = ids[mask]
            child_V = V[mask[owner]]
            child_counts = counts[mask]
            if parts[side]:
                child_ids = np.concatenate([child_ids, [i for i, _ in parts[side]]])
                child_V = np.concatenate([child_V] + [P for _, P in parts[side]])
                child_counts = np.concatenate([child_counts, [len(P) for _, P in parts[side]]])
            stack.append((child_ids, child_V, child_counts, node, side))
    # keep only the fragments the nodes hold (a split fragment is replaced by its parts)
    live = [i for here in node_frags for i in here]
    new_id = {old: new for new, old in enumerate(live)}
    node_frags = [[new_id[i] for i in here] for here in node_frags]
    kept = [fragments[i] for i in live]
    vertex_errors = [np.array([errors.get(v, 0.0) for v in map(tuple, P.tolist())])
                     for P in kept] if errors else [np.zeros(len(P)) for P in kept]
    return BSPTree(np.array(nodes_n), np.array(nodes_d), np.array(front), np.array(back),
                   node_frags, kept, source[np.array(live, dtype=int)],
                   splits, normals_src, whole=np.array(live, dtype=int) < len(scene),
                   vertex_errors=vertex_errors)


def _build_bsp_compiled(scene, candidates, seed):
    from ._svbsp import build_bsp_arrays      # the compiled module imports after this one

    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    # the scene's polygons, concatenated (scene.offsets: polygon i's vertices start)
    (normals, offsets, front, back, here_start, here, Vf, frag_start, source, whole,
     splits, Ef) = build_bsp_arrays(
        V=scene.vertices, start=scene.offsets, normals=scene.normals,
        offsets=scene.plane_offsets, candidates=int(candidates), sample=tol.BSP_SCORE_SAMPLE,
        axis_min=tol.BSP_AXIS_CANDIDATE_MIN, axis_imbalance=tol.BSP_AXIS_IMBALANCE,
        band_ulps=tol.BSP_COPLANAR_ULPS, snap=tol.BSP_SPLIT_SNAP_EPS, seed=int(seed))
    flat, bounds = here.tolist(), here_start.tolist()
    node_frags = [flat[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    fragments = np.split(Vf, frag_start[1:-1]) if len(source) else []
    errors = np.split(Ef, frag_start[1:-1]) if len(source) else []
    return BSPTree(normals, offsets, front, back, node_frags, fragments, source, int(splits),
                   scene.normals, whole=whole, vertex_errors=errors)


def scene_bsp(scene):
    """The scene's BSP tree and its fragments as padded arrays bucketed by vertex count
    (:func:`exactff.rings.padded_buckets`; built once, cached)."""
    return prepared(scene).get("bsp", _build_bsp_buckets)


def _build_bsp_buckets(scene):
    tree = build_bsp(scene)
    return tree, padded_buckets(tree.fragments)


def _nearest_fragment(p, tree, cand, lo_box, hi_box):
    """A lower bound on the least distance from ``p`` to the fragments ``cand`` (their
    boxes ``lo_box``, ``hi_box``): nearest boxes first, each fragment's own distance
    (:func:`exactff.geometry.point_polygon_distance`; a box is only a lower bound: a long
    slanted polygon's box may hold the point), shrunk by ``FLOAT_DISTANCE_RTOL``."""
    gap = np.maximum(np.maximum(lo_box[cand] - p, p - hi_box[cand]), 0.0)
    box_dist = np.sqrt((gap * gap).sum(axis=1))
    dist = np.inf
    for i in np.argsort(box_dist, kind="stable").tolist():
        if box_dist[i] >= dist:
            break
        dist = min(dist, point_polygon_distance(p, tree.fragments[int(cand[i])]))
    return dist * (1 - tol.FLOAT_DISTANCE_RTOL)


#: per tree, the last point's _misordered_slabs (node_sides and node_first_charges each
#: ask for it per row)
_MISORDER_CACHE = weakref.WeakKeyDictionary()


def _misordered_slabs(tree, p, sides):
    """The nodes where one of the node's own fragments may stand between ``p`` and the
    near subtree (``p`` on the far side of that fragment's own plane from the near
    subtree, by the exact sides ``sides``; :func:`node_sides`), with the slab's width
    beyond ``p`` (to the farthest fragment, plus the offsets' rounding) and a lower
    bound on the distance from ``p`` to those fragments. Returns ``(side, nodes, width,
    distance, standing)``: the exact sides of ``p`` for every node's plane, and per node
    listed the fragments standing there. The last point's result is kept on the tree
    (:func:`node_sides` and :func:`node_first_charges` each ask for it per row)."""
    sides = np.asarray(sides, dtype=np.int8)
    key = (p.tobytes(), sides.tobytes())
    kept = _MISORDER_CACHE.get(tree)
    if kept is not None and kept[0] == key:
        return kept[1]
    # the point's offsets from the nodes' planes and their rounding's scale, once for
    # the sides and the slabs below
    o, scale = point_plane_offsets(tree.normals, tree.offsets, p, tree.plane_magnitudes())
    side = sides_of_point(tree.normals, tree.offsets, p, offsets=(o, scale)).astype(np.int8)
    node, src, orient, start = tree.node_members
    nodes, width, distance, standing = [], [], [], []
    if len(node):
        # only where the point lies within the node's fragments' offsets (beyond them
        # all, the point is in front of every fragment's plane on its side)
        hi, lo = tree.fragment_offsets()
        r = 2 * gamma(4) * scale
        near = np.flatnonzero((o >= lo - 2 * r) & (o <= hi + 2 * r))
        if len(near):
            # each fragment's polygon: which side of its own plane the point lies on,
            # along the node's normal (+1: on the node's front side of it; 0: edge-on)
            counts = start[near + 1] - start[near]
            at = np.repeat(start[near] - np.cumsum(counts) + counts, counts) + np.arange(
                int(counts.sum()))
            along = np.asarray(sides, dtype=np.int8)[src[at]] * orient[at]
            owner = np.repeat(np.arange(len(near)), counts)
            s = side[near][owner]
            stands = (((s > 0) & (along < 0)) | ((s < 0) & (along > 0))
                      | ((s == 0) & (along != 0)))
            if stands.any():
                _, _, _, _, lo_box, hi_box = tree.subtree_fragments()
                frag = tree.node_member_fragments[at[stands]]
                for i in np.unique(owner[stands]).tolist():
                    k = int(near[i])
                    here = frag[owner[stands] == i]
                    w = (hi[k] - o[k] if side[k] > 0 else o[k] - lo[k] if side[k] < 0
                         else max(hi[k], -lo[k])) + 2 * r[k]
                    nodes.append(k)
                    width.append(max(w, 0.0))
                    distance.append(_nearest_fragment(p, tree, here, lo_box, hi_box))
                    standing.append(here)
    out = (side, np.array(nodes, dtype=np.int64), np.array(width), np.array(distance),
           standing)
    _MISORDER_CACHE[tree] = (key, out)
    return out


def node_sides(tree, point, sides=None):
    """Per node of the tree, the side of ``point`` and the order of the node's visit.

    The side is decided exactly (:func:`exactff.predicates.sides_of_point`): +1 in
    front, -1 behind, 0 on the plane. It is doubled (+2, -2; 0 on the plane) where one
    of the node's own fragments may stand between the point and the near subtree and
    comes within twice the slab's width of the point, so that the node's fragments are
    visited before both subtrees. A fragment may stand there where the point lies on
    the far side of its own plane from the near subtree (by the exact side of the point
    for its polygon, ``sides``). The node holds the polygons coplanar with its plane
    by the band's rule (:func:`exactff.predicates.coplanar_band`), on either side of
    it: a face flush with the point's own surface, facing it from 1e-14 away, covers
    the hemisphere, and what lies behind it must not show. Neither order is exact
    inside the slab (w wide) between the point and those fragments; each misorders
    only rays within ``sin a <= w / d`` of the node's plane, d the distance to what it
    puts too early: with the node first, the near subtree's polygons reaching into the
    slab; in the usual order (near subtree, node, far subtree), the fragments standing
    between. A fragment within 2 w of the point covers most of the hemisphere (d about
    w); one farther off hides a band about the horizon only, whose shadow, nearly
    through the point, the compiled core rounds least well: the usual order then
    (SampleHouse4 row 18196: a fan of triangles 1e-14 above the point, 8e-5 m off, lost
    1.1e-3 of the hemisphere visited first). What either order may move is charged
    (:func:`node_first_charges`). A point on the plane of a node whose fragments all
    contain it (or without ``sides``) is given +1.

    Parameters
    ----------
    tree : BSPTree
    point : array_like of shape (3,)
    sides : ndarray of shape (n,), int, optional
        The exact side of the point for each of the scene's polygons, as the engines
        take it (:func:`exactff.predicates.engine_sides`: 0 seen edge-on). None: no
        node's fragments come first.

    Returns
    -------
    ndarray of int8, shape (len(tree),)
        -2, -1, 0, +1 or +2: the near subtree is the front one where it is >= 0, and
        the node's fragments come first where it is even.

    Examples
    --------
    A floor, and a face 32 ulps above it facing down over the point: from a point on
    the floor the face comes first; without the sides it would come after the floor's
    front subtree (the wall, which it hides).

    >>> import exactff as ef
    >>> from exactff.kernel import flat_polygons
    >>> from exactff.predicates import engine_sides
    >>> t = 32 * np.spacing(1.0)
    >>> floor = [[-1, 1, -1], [-1, 1, 1], [1, 1, 1], [1, 1, -1]]
    >>> face = [[-1, 1 + t, -1], [1, 1 + t, -1], [1, 1 + t, 1], [-1, 1 + t, 1]]
    >>> wall = [[-2, 1.5, -2], [2, 1.5, -2], [2, 1.5, 2], [-2, 1.5, 2]]
    >>> scene = ef.Scene.from_polygons([floor, face, wall])
    >>> tree, p = build_bsp(scene), np.array([0.0, 1.0, 0.0])
    >>> side, _ = engine_sides(flat_polygons(scene), p)
    >>> side.tolist(), node_sides(tree, p, side).tolist(), node_sides(tree, p).tolist()
    ([0, 1, 1], [0, 1], [1, 1])
    """
    p = np.asarray(point, dtype=float)
    if sides is None:
        side = sides_of_point(tree.normals, tree.offsets, p, offsets=point_plane_offsets(
            tree.normals, tree.offsets, p, tree.plane_magnitudes())).astype(np.int8)
        return side + (side == 0)             # 0 (on the plane) as +1
    side, nodes, width, distance, _ = _misordered_slabs(tree, p, sides)
    # the side, 0 as +1; doubled (0 kept) at the nodes whose fragments come first
    code = side + (side == 0)
    first = nodes[distance <= 2 * width]
    code[first] = 2 * side[first]
    return code


def node_first_charges(tree, point, code, receives, sides=None):
    """What the order of a node's visit (:func:`node_sides`) may misplace, per polygon.

    Visiting a node's fragments before its near subtree misplaces only the directions
    whose first hit is a near-subtree polygon inside the slab between the point and the
    node's fragments beyond it. A ray at elevation a off the node's plane leaves that
    slab (width w, from the point's offset to the farthest fragment beyond it) within
    w / sin(a); only a polygon of the near subtree reaching into the slab, at distance
    at least d from the point, can come first there, so only rays with sin(a) <= w / d
    can be misordered: a band about a great circle of area at most 4 pi w / d on the
    unit sphere (4 w / d in form-factor units, cosine-weighted over pi). That is charged
    to the node's fragments and to those near-subtree fragments (their first hits are
    the only ones that can change), d the least distance from the point to those
    fragments (:func:`exactff.geometry.point_polygon_distance`).

    With ``sides``, the usual order at a node where fragments may stand between the
    point and the near subtree but lie farther than twice the slab's width from it is
    charged too: only rays with sin(a) <= w / d, d now the distance to those fragments,
    can meet them first; charged to them and to the near-subtree fragments reaching
    below that elevation (their boxes), which are drawn before them.

    Parameters
    ----------
    tree : BSPTree
    point : array_like of shape (3,)
    code : ndarray of int8
        :func:`node_sides` of the point.
    receives : ndarray of shape (n,), bool
        Which of the scene's polygons receive (the others' values are 0, whatever the
        order).
    sides : ndarray of shape (n,), int, optional
        The sides :func:`node_sides` was given (None: the usual order's misorder is not
        charged).

    Returns
    -------
    ndarray of shape (n,)
        ``w / d`` per receiving polygon, the largest of its fragments' (at most 1; 0
        where nothing can be misordered): times 4 for form factors, 4 pi for solid
        angles.

    Examples
    --------
    A floor, a face 32 ulps above it facing down, and a wall standing on the floor
    1 mm from a point on it: the wall's foot may hide part of the face or not.

    >>> import exactff as ef
    >>> from exactff.kernel import flat_polygons
    >>> from exactff.predicates import engine_sides
    >>> t = 32 * np.spacing(1.0)
    >>> floor = [[-1, 1, -1], [-1, 1, 1], [1, 1, 1], [1, 1, -1]]
    >>> face = [[0.002, 1 + t, -1], [0.003, 1 + t, -1], [0.003, 1 + t, 1], [0.002, 1 + t, 1]]
    >>> wall = [[0.001, 1, -2], [0.001, 2, -2], [0.001, 2, 2], [0.001, 1, 2]]
    >>> scene = ef.Scene.from_polygons([floor, face, wall])
    >>> tree, p = build_bsp(scene), np.array([0.0, 1.0, 0.0])
    >>> side, _ = engine_sides(flat_polygons(scene), p)
    >>> c = node_first_charges(tree, p, node_sides(tree, p, side), side != 0, side)
    >>> bool(c[1] > 0 and c[2] > 0), bool(c.max() < 1e-10)
    (True, True)
    """
    receives = np.asarray(receives, dtype=bool)
    charge = np.zeros(len(receives))
    p = np.asarray(point, dtype=float)
    usual = []
    if sides is not None:
        _, nodes, width, distance, standing = _misordered_slabs(tree, p, sides)
        usual = [(int(k), w, d, frags) for k, w, d, frags in
                 zip(nodes.tolist(), width.tolist(), distance.tolist(), standing)
                 if code[k] % 2 != 0]
    # the even codes (the low bit: % 2 on int8 costs ten times as much)
    nodes = np.flatnonzero((code & 1) == 0)
    if len(nodes) == 0 and not usual:
        return charge
    pre, end, by_pre, start, lo_box, hi_box = tree.subtree_fragments()
    hi, lo = tree.fragment_offsets()
    grow = 1 + tol.FLOAT_DISTANCE_RTOL

    def near_subtree(k):
        # the fragments of node k's near subtree(s), their offsets' middle and spread
        kids = [c for c in ((tree.front[k], tree.back[k]) if code[k] == 0 else
                            (tree.front[k] if code[k] > 0 else tree.back[k],)) if c >= 0]
        cand = np.asarray(np.concatenate([by_pre[start[pre[c]]:start[end[c]]] for c in kids])
                          if kids else [], dtype=np.int64)
        n = tree.normals[k]
        centre, half = (lo_box[cand] + hi_box[cand]) / 2, (hi_box[cand] - lo_box[cand]) / 2
        return cand, centre @ n - tree.offsets[k], half @ np.abs(n)

    for k in nodes.tolist():
        n, d = tree.normals[k], tree.offsets[k]
        o = float(n @ p - d)
        r = gamma(4) * (float(np.abs(n) @ np.abs(p)) + abs(d))
        # the slab between the point and the fragments beyond it, and its width
        a, b = (min(o, lo[k]) - r, max(o, hi[k]) + r)
        w = (hi[k] - o if code[k] > 0 else o - lo[k] if code[k] < 0 else max(hi[k], -lo[k])) + 2 * r
        cand, mid, spread = near_subtree(k)
        # the candidates' boxes reaching into the slab, and their distances from p
        cand = cand[(mid + spread * grow >= a) & (mid - spread * grow <= b)]
        if len(cand) == 0:
            continue
        dist = _nearest_fragment(p, tree, cand, lo_box, hi_box)
        share = 1.0 if dist <= 0 else min(1.0, w / dist)
        hit = np.concatenate([tree.source[np.asarray(tree.node_fragments[k], dtype=np.int64)],
                              tree.source[cand]])
        charge[hit] = np.maximum(charge[hit], share)
    for k, w, dist, frags in usual:
        # the usual order: the fragments standing between, and the near subtree's
        # fragments reaching below elevation sin a = w / d (drawn before them)
        share = 1.0 if dist <= 0 else min(1.0, w / dist)
        o = float(tree.normals[k] @ p - tree.offsets[k])
        cand, mid, spread = near_subtree(k)
        far = np.linalg.norm(np.maximum(np.abs(lo_box[cand] - p), np.abs(hi_box[cand] - p)),
                             axis=1)
        rise = (mid - spread * grow - o) if code[k] > 0 else (o - mid - spread * grow)
        cand = cand[rise <= (share * far + w) * grow]
        hit = np.concatenate([tree.source[frags], tree.source[cand]])
        charge[hit] = np.maximum(charge[hit], share)
    return np.where(receives, charge, 0.0)


def front_to_back(tree, point, sides=None):
    """Fragment indices in front-to-back order as seen from ``point``.

    At each node the side holding the point is visited first, then the node's own
    fragments (coplanar: those facing the point first, then input order), then the far
    side; where one of the node's own fragments may stand between the point and the
    near side (:func:`node_sides`, from ``sides``), the node's own fragments first,
    then the two sides. The side is decided exactly
    (:func:`exactff.predicates.side_of_plane`).

    Parameters
    ----------
    tree : BSPTree
    point : array_like of shape (3,)
    sides : ndarray of shape (n,), int, optional
        The exact side of the point for each polygon, as the engines take it
        (:func:`exactff.predicates.engine_sides`); None: the usual order at every node.

    Returns
    -------
    list of int
    """
    side = node_sides(tree, point, sides)
    order = []
    stack = [(0, False)]
    front, back = tree.front, tree.back
    frags_front, frags_behind = tree.node_fragments, tree.node_fragments_behind
    while stack:
        node, emit = stack.pop()
        if emit:
            order.extend(frags_front[node] if side[node] >= 0 else frags_behind[node])
            continue
        if side[node] >= 0:
            near, far = front[node], back[node]
        else:
            near, far = back[node], front[node]
        first = side[node] % 2 == 0        # within the node's thickness
        if far >= 0:
            stack.append((far, False))
        if not first:
            stack.append((node, True))
        if near >= 0:
            stack.append((near, False))
        if first:
            stack.append((node, True))
    return order



def coplanar_overlaps(scene, tree=None):
    """Pairs of polygons that lie in one plane and overlap (share area), by facing.

    Coplanar overlapping polygons all sit in one node of the BSP tree (polygons in one
    plane but in different nodes are separated by a splitting plane), so only the
    nodes' own fragments are compared, in the node's plane.

    Parameters
    ----------
    scene : Scene
    tree : BSPTree, optional
        The scene's tree (default: built, or taken from the scene's cache).

    Returns
    -------
    back_to_back : ndarray of shape (P, 2), int
        Pairs ``i < j`` facing opposite ways: the two faces of a zero-thickness wall
        (legitimate; each side is seen from its own side).
    same_facing : ndarray of shape (Q, 2), int
        Pairs ``i < j`` facing the same way: usually a modelling mistake (a light on a
        ceiling); the first in input order is in front.

    Examples
    --------
    >>> from exactff.scenes import building
    >>> b2b, same = coplanar_overlaps(building(2, 1))
    >>> len(b2b), len(same)
    (3, 0)
    """
    if tree is None:
        tree = scene_bsp(scene)[0]
    pairs = {+1: set(), -1: set()}
    for k, here in enumerate(tree.node_fragments):
        if len(here) < 2 or len(set(tree.source[here].tolist())) < 2:
            continue
        n = tree.normals[k]
        keep = [a for a in range(3) if a != int(np.argmax(np.abs(n)))]
        polys = np.array([shapely.Polygon(tree.fragments[f][:, keep]) for f in here])
        polys = shapely.make_valid(polys)
        a, b = shapely.STRtree(polys).query(polys, predicate="intersects")
        sel = a < b
        a, b = a[sel], b[sel]
        shared = shapely.area(shapely.intersection(polys[a], polys[b]))
        src = tree.source[here]
        # more than OVERLAP_RTOL of the smaller polygon's area (its fragment's may be a
        # sliver an exact split left along a plane it nearly lies in)
        overlap = shared > tol.OVERLAP_RTOL * np.minimum(scene.areas[src[a]],
                                                         scene.areas[src[b]])
        orient = np.sign(scene.normals[src] @ n)
        for i, j in zip(a[overlap], b[overlap]):
            si, sj = int(src[i]), int(src[j])
            if si != sj:
                pairs[int(orient[i] * orient[j])].add((min(si, sj), max(si, sj)))
    as_array = lambda s: np.array(sorted(s), dtype=int).reshape(-1, 2)
    return as_array(pairs[-1]), as_array(pairs[+1])
