"""Refinement of visible pieces: the clipper's topology, the input's geometry.

The clipper (:mod:`exactff.visibility.clipper`) finds the visible pieces with straight
images in gnomonic charts, in double precision: every vertex of a piece is rounded there
(to a few ulps of the chart's unit), which costs a small or thin piece its relative
accuracy (a piece 1e-12 wide keeps about four digits). Here each piece keeps the
clipper's topology and gets its geometry back from the input
(``docs/explanation/robustness.md``, "Visible pieces: approximated, then refined"):

1. **Labels.** Every edge of a piece lies on a great circle through the point: the plane
   of an edge of its own fragment or of a fragment in front of it, a chart's edge or a
   tile seam (artificial edges, which cancel between the pieces on either side), or the
   horizon. The plane is found as the candidate through both end points of the edge with
   the least residual (candidates: the fragment's own edges, the seams and chart edges
   nearest to the edge, and the edges of the images whose boundary passes through the
   edge's midpoint; of a fragment longer than ``LONG_POLYGON``, only its edges whose
   image passes within ``REFINE_QUERY`` of the edge's, found with an STRtree).
2. **Planes from the input.** A fragment's edge is traced back to the scene polygon's
   edge it lies on (a BSP cut keeps the edge's line) and its plane is computed from
   the two input vertices, ``(a - p) x (b - a)``; an edge made by a BSP cut keeps the
   fragment's own end points (both sides of the cut use the same ones).
3. **Vertices.** Where two labelled edges meet: the input vertex they share, if any;
   else the intersection of their planes, ``m_in x m_out``. Where the two planes are
   the same great circle the vertex is dropped; where they are too close to parallel for
   their intersection to be trusted (``REFINE_PARALLEL``) the clipper's vertex is kept
   and its error counted.
4. **Integration.** The refined rings are integrated with the sector form in long
   double (a second tier, vectorised) and, where that still misses the tolerance, in
   mpmath with the same labels, planes computed from the input at the working precision.

Error estimates: rounding of the sector sum (as in the kernel) plus, for each vertex, its
position error (a few units of the working precision over the sine of the angle between
its planes; the clipper's ``CHART_VERTEX_ERROR`` for a kept vertex) times the lengths of
its edges. They rest on the topology being right: the labels the clipper's pieces give.
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..geometry import mp_receiver_frame, receiver_frame
from ..kernel import TWO_PI_LONG, clipped_sector_sums, eq3_ring_sums
from ..kernel.eq3 import mp_eq3_sum
from ..kernel.flat import flat_polygons
from ..kernel.ladder import mp_converge, mp_sector_sum
from ..rings import successors

__all__ = ["Refiner"]

_LD = np.longdouble


def _unit(X):
    n = np.sqrt((X * X).sum(axis=-1, keepdims=True))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(n > 0, X / n, np.nan)


class Refiner:
    """What a row's refinement needs, built lazily: the fragments' edge planes, the
    charts' images, and the receiver's frames.

    Parameters
    ----------
    scene : Scene
    tree : BSPTree
    fragment : ndarray of int
        The BSP fragment at each position of the clipper's order.
    point, normal : ndarray of shape (3,)
    buckets : list of (ndarray of int, ndarray of shape (M, K, 3), ndarray of shape (M,))
        The clipper's input: positions, local (double) vertices and counts.
    world : list of (ndarray of int, ndarray of shape (M, K, 3), ndarray of shape (M,))
        The same fragments' world vertices (positions, vertices, counts).
    charts : list
        Filled by :func:`exactff.visibility.clipper.visible_pieces`: per chart, the
        positions of the fragments that reach it, their images and the tiles per side.
    """

    def __init__(self, scene, tree, fragment, point, normal, buckets, world, charts):
        self.scene, self.tree, self.fragment = scene, tree, np.asarray(fragment)
        self.p = np.asarray(point, dtype=float)
        self.n = np.asarray(normal, dtype=float)
        self.buckets, self.world, self.charts = buckets, world, charts
        self._edges = self._world = self._local = None
        self._trees = {}
        self._edge_trees = {}
        self._poly_trees = {}
        self._segment_trees = {}
        self._mp_frames = {}
        self.R_ld = receiver_frame(self.n, dtype=_LD)

    # -- candidates -------------------------------------------------------------------
    def _edge_table(self):
        """Every fragment's edges as unit plane normals in the (double) local frame:
        ``(offset, count, planes)``, fragment at position f owning rows
        ``offset[f]:offset[f] + count[f]``."""
        if self._edges is None:
            m = sum(len(pos) for pos, _, _ in self.buckets)
            count = np.zeros(m, dtype=int)
            for pos, _, c in self.buckets:
                count[pos] = c
            offset = np.concatenate([[0], np.cumsum(count)[:-1]])
            planes = np.full((int(count.sum()), 3), np.nan)
            for pos, V, c in self.buckets:
                K = V.shape[1]
                slot = np.arange(K)
                nxt = (slot[None, :] + 1) % np.maximum(c[:, None], 1)
                W = np.take_along_axis(V, nxt[:, :, None], axis=1)
                M = _unit(np.cross(V, W))
                valid = slot[None, :] < c[:, None]
                rows = offset[pos][:, None] + slot[None, :]
                planes[rows[valid]] = M[valid]
            self._edges = offset, count, planes
        return self._edges

    def _local_table(self):
        """The fragments' local (double) vertices, laid out as the edge table."""
        if self._local is None:
            offset, count, _ = self._edge_table()
            L = np.full((int(count.sum()), 3), np.nan)
            for pos, V, c in self.buckets:
                slot = np.arange(V.shape[1])
                valid = slot[None, :] < c[:, None]
                L[(offset[pos][:, None] + slot[None, :])[valid]] = V[valid]
            self._local = L
        return self._local

    def _fragment_edge_tree(self, ci, chart, f):
        """A long fragment's edges as segments in chart ``ci``: an STRtree and the edge
        table row of each of its geometries. Each edge is clipped to the part whose
        image lies within ``REFINE_CHART_REACH`` of the chart's centre (finite: in
        front of the chart's plane) and projected; edges outside are left out."""
        key = (ci, int(f))
        if key not in self._edge_trees:
            eu, ev, ew, _ = chart
            offset, count, _ = self._edge_table()
            o, c = int(offset[f]), int(count[f])
            L = self._local_table()[o:o + c]
            a, b = L, np.roll(L, -1, axis=0)
            t0, t1 = np.zeros(c), np.ones(c)
            for e in (eu, -eu, ev, -ev):
                h = tol.REFINE_CHART_REACH * ew - e
                fa, fb = a @ h, b @ h
                with np.errstate(divide="ignore", invalid="ignore"):
                    t = fa / (fa - fb)
                t0 = np.where((fa < 0) & (fb >= 0), np.maximum(t0, t), t0)
                t1 = np.where((fb < 0) & (fa >= 0), np.minimum(t1, t), t1)
                t1 = np.where((fa < 0) & (fb < 0), -1.0, t1)
            d = b - a
            A, B = a + t0[:, None] * d, a + t1[:, None] * d
            with np.errstate(divide="ignore", invalid="ignore"):
                xy = np.stack([np.stack([X @ eu / (X @ ew), X @ ev / (X @ ew)], axis=1)
                               for X in (A, B)], axis=1)              # (c, 2, 2)
            keep = np.flatnonzero((t0 <= t1) & np.isfinite(xy).all(axis=(1, 2)))
            self._edge_trees[key] = (shapely.STRtree(shapely.linestrings(xy[keep])),
                                     o + keep)
        return self._edge_trees[key]

    def _boundary_tree(self, ci):
        """The images' boundaries in chart ``ci``: an STRtree, the boundaries and their
        vertex counts."""
        if ci not in self._trees:
            idx, polys, _ = self.charts[ci]
            b = shapely.boundary(polys)
            self._trees[ci] = (shapely.STRtree(b), b, shapely.get_num_coordinates(b))
        return self._trees[ci]

    def _boundary_segment_tree(self, ci, t):
        """A long image boundary of chart ``ci`` as an STRtree of its segments."""
        key = (ci, int(t))
        if key not in self._segment_trees:
            parts = shapely.get_parts(self._boundary_tree(ci)[1][t])
            xy, part = shapely.get_coordinates(parts, return_index=True)
            j = np.flatnonzero(part[1:] == part[:-1])
            self._segment_trees[key] = shapely.STRtree(
                shapely.linestrings(np.stack([xy[j], xy[j + 1]], axis=1)))
        return self._segment_trees[key]

    def _boundaries_near(self, ci, xy):
        """Pairs (point, image) with the image's boundary within ``REFINE_QUERY`` of the
        point, as ``STRtree.query(predicate="dwithin")`` gives them and in its order
        (the candidates of the distance's envelope, in the tree's order), but a long
        boundary is searched by its segments rather than measured whole."""
        tree, bounds, ncoord = self._boundary_tree(ci)
        d = tol.REFINE_QUERY
        q, t = tree.query(shapely.box(xy[:, 0] - d, xy[:, 1] - d, xy[:, 0] + d, xy[:, 1] + d))
        keep = np.zeros(len(q), dtype=bool)
        pts = shapely.points(xy)
        short = ncoord[t] <= tol.LONG_POLYGON
        keep[short] = shapely.dwithin(pts[q[short]], bounds[t[short]], d)
        for b in np.unique(t[~short]):
            j = np.flatnonzero(~short & (t == b))
            hit, _ = self._boundary_segment_tree(ci, b).query(pts[q[j]], predicate="dwithin",
                                                             distance=d)
            keep[j[np.unique(hit)]] = True
        return q[keep], t[keep]

    def match(self, ci, chart, coords, nxt, frag):
        """Label every edge of the pieces' rings in chart ``ci``.

        Parameters
        ----------
        coords : ndarray of shape (V, 2)
            Ring vertices in chart coordinates (closing points dropped).
        nxt : ndarray of shape (V,)
            Index of the next vertex of the same ring.
        frag : ndarray of shape (V,)
            Position of the fragment each vertex's piece belongs to.

        Returns
        -------
        (ndarray of int, ndarray of shape (V, 3), ndarray, (ndarray, ndarray))
            Per edge (from vertex i to ``nxt[i]``): its label (>= 0: a row of the
            fragment edge table; < 0: ``-1 - s`` for the static plane ``s``), the static
            planes as local vectors, the edge's residual (inf: no plane found); and the
            candidates within ``REFINE_AMBIGUOUS`` of both its end points (edge, label
            pairs, the label's own among them): the planes the clipper's edge may stand
            for, given its vertices' accuracy.

        Every edge is searched among its own fragment's edges, the seams and the edges
        of the images in front whose boundary passes through its midpoint (images
        behind cannot bound a visible piece), and takes the least residual: an edge of
        the fragment's own polygon within 2e-14 of an occluder's (a mullion flush with a
        curtain wall's plate) was taken before the occluder's was looked at, and the
        refined value moved by the width between them (1.2e-15 beyond its bound).
        """
        eu, ev, ew, _ = chart
        D = _unit(coords[:, :1] * eu + coords[:, 1:2] * ev + ew)
        Dn = D[nxt]
        nv = len(coords)
        best = np.full(nv, np.inf)
        label = np.full(nv, -1, dtype=np.int64)
        statics = []
        alt_e, alt_l = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
        # seams and chart edges: the grid lines u = c and v = c nearest to the edge's
        # first end point (plane e_u - c e_w or e_v - c e_w; v = 0 is the horizon)
        _, _, n_tiles = self.charts[ci]
        u0, v0, u1, v1 = (-1.0, 0.0, 1.0, 1.0) if chart[3] else (-1.0, -1.0, 1.0, 1.0)
        for k, (e, lo, hi) in enumerate(((eu, u0, u1), (ev, v0, v1))):
            grid = np.linspace(lo, hi, n_tiles + 1)
            grid[-1] = hi
            j = np.clip(np.searchsorted(grid, coords[:, k]), 1, n_tiles)
            j = np.where(np.abs(grid[j - 1] - coords[:, k]) <= np.abs(grid[j] - coords[:, k]),
                         j - 1, j)
            Ms = e[None, :] - grid[:, None] * ew[None, :]
            Mu = _unit(Ms)[j]
            r = np.maximum(np.abs((Mu * D).sum(1)), np.abs((Mu * Dn).sum(1)))
            better = r < best
            best[better] = r[better]
            label[better] = -1 - (len(statics) + j[better])
            near = np.flatnonzero(r <= tol.REFINE_AMBIGUOUS)
            alt_e.append(near)
            alt_l.append(-1 - (len(statics) + j[near]))
            statics.extend(Ms)
        statics = np.array(statics)
        offset, count, planes = self._edge_table()

        def consider(rows, fr):
            # candidate pairs (ring edge, fragment edge table row), in the order of the
            # pairs (ring edge, fragment) and of the fragment's edges: every edge of a
            # short fragment; of a long one, the edges whose image passes within
            # REFINE_QUERY of the ring edge's (a few, not all of them)
            short = count[fr] <= tol.LONG_POLYGON
            lp, lg = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
            for f in np.unique(fr[~short]):
                j = np.flatnonzero(~short & (fr == f))
                tree, grow = self._fragment_edge_tree(ci, chart, f)
                segs = shapely.linestrings(np.stack([coords[rows[j]], coords[nxt[rows[j]]]],
                                                    axis=1))
                q, t = tree.query(segs, predicate="dwithin", distance=tol.REFINE_QUERY)
                lp.append(j[q])
                lg.append(grow[t])
            lp, lg = np.concatenate(lp), np.concatenate(lg)
            for a in range(0, len(rows), 1 << 16):
                sp = a + np.flatnonzero(short[a:a + (1 << 16)])
                c = count[fr[sp]]
                pr = np.repeat(sp, c)
                g = np.repeat(offset[fr[sp]] - np.cumsum(c) + c, c) + np.arange(int(c.sum()))
                inl = (lp >= a) & (lp < a + (1 << 16))
                pr, g = np.concatenate([pr, lp[inl]]), np.concatenate([g, lg[inl]])
                if len(pr) == 0:
                    continue
                o = np.lexsort((g, pr))
                e, g = rows[pr[o]], g[o]
                P = planes[g]
                res = np.maximum(np.abs((P * D[e]).sum(1)), np.abs((P * Dn[e]).sum(1)))
                res = np.where(np.isnan(res), np.inf, res)
                # the least residual per ring edge
                o = np.lexsort((res, e))
                first = np.r_[True, e[o][1:] != e[o][:-1]]
                e1, g1, r1 = e[o][first], g[o][first], res[o][first]
                better = r1 < best[e1]
                best[e1[better]] = r1[better]
                label[e1[better]] = g1[better]
                near = res <= tol.REFINE_AMBIGUOUS
                alt_e.append(e[near])
                alt_l.append(g[near])

        consider(np.arange(nv), frag)
        # every edge: the edges of the images in front whose boundary passes through it
        every = np.arange(nv)
        q, t = self._boundaries_near(ci, 0.5 * (coords + coords[nxt]))
        front = self.charts[ci][0][t] < frag[q]
        if front.any():
            consider(every[q[front]], self.charts[ci][0][t[front]])
        best[best > tol.REFINE_MATCH] = np.inf
        return label, statics, best, (np.concatenate(alt_e), np.concatenate(alt_l))

    # -- planes from the input --------------------------------------------------------
    def segments(self, rows):
        """World end points ``(a, b)`` (float input) of the lines of fragment edge table
        rows: the scene polygon's edge the fragment edge lies on, or the fragment's own
        end points for an edge made by a BSP cut."""
        offset, count, _ = self._edge_table()
        W = self._world_table()
        rows = np.asarray(rows)
        # fragments without edges share the next one's offset: side="right" skips them
        f = np.searchsorted(offset, rows, side="right") - 1
        j = rows - offset[f]
        A = W[rows]
        B = W[offset[f] + (j + 1) % count[f]]
        cut = np.flatnonzero(~self.tree.whole[self.fragment[f]])
        if len(cut):
            A[cut], B[cut] = self._polygon_edges(self.tree.source[self.fragment[f[cut]]],
                                                 A[cut], B[cut])
        return A, B

    def _polygon_edges(self, src, a, b):
        """For fragment edges ``a -> b`` of cut fragments: the end points of their scene
        polygon's edge through both (a BSP cut keeps an edge's line), or ``a, b``
        themselves for an edge the cut made."""
        flat = flat_polygons(self.scene)
        offset, count, V, nxt = flat.offsets[:-1], flat.counts, flat.V, flat.nxt
        src = np.asarray(src)
        # candidate pairs (fragment edge q, polygon edge k): every edge of a short
        # polygon; of a long one, those within the test's distance of the fragment edge
        # (in the polygon's plane projected along its normal's largest axis, which
        # shortens no distance more than it keeps: a superset)
        short = np.flatnonzero(count[src] <= tol.LONG_POLYGON)
        c = count[src[short]]
        qs = [np.repeat(short, c)]
        ks = [np.repeat(offset[src[short]] - np.cumsum(c) + c, c) + np.arange(int(c.sum()))]
        long_ = np.flatnonzero(count[src] > tol.LONG_POLYGON)
        for s in np.unique(src[long_]):
            qq = long_[src[long_] == s]
            tree, axes, vmax = self._polygon_edge_tree(s)
            reach = tol.BSP_COPLANAR_ULPS * tol.EPS * (
                vmax + np.maximum(np.abs(a[qq]), np.abs(b[qq])).max(axis=1))
            segs = shapely.linestrings(np.stack([a[qq][:, axes], b[qq][:, axes]], axis=1))
            i, t = tree.query(segs, predicate="dwithin", distance=reach)
            qs.append(qq[i])
            ks.append(offset[s] + t)
        q, k = np.concatenate(qs), np.concatenate(ks)
        o = np.lexsort((k, q))
        q, k = q[o], k[o]
        E = V[nxt[k]] - V[k]
        L = np.linalg.norm(E, axis=1)
        ra = np.linalg.norm(np.cross(E, a[q] - V[k]), axis=1) / L
        rb = np.linalg.norm(np.cross(E, b[q] - V[k]), axis=1) / L
        r = np.maximum(ra, rb)
        scale = np.abs(V[k]).max(axis=1) + np.maximum(np.abs(a[q]), np.abs(b[q])).max(axis=1)
        on = r <= tol.BSP_COPLANAR_ULPS * tol.EPS * scale
        # the first polygon edge through both end points, per fragment edge
        hit = np.flatnonzero(on)
        first = np.unique(q[hit], return_index=True)
        A, B = a.copy(), b.copy()
        A[first[0]] = V[k[hit[first[1]]]]
        B[first[0]] = V[nxt[k[hit[first[1]]]]]
        return A, B

    def _polygon_edge_tree(self, s):
        """A long scene polygon's edges as 2-d segments (its plane projected along the
        largest axis of its normal): an STRtree, the two axes kept, and the largest
        coordinate magnitude of its vertices."""
        s = int(s)
        if s not in self._poly_trees:
            flat = flat_polygons(self.scene)
            o, c = int(flat.offsets[s]), int(flat.counts[s])
            k = np.arange(o, o + c)
            axes = np.delete(np.arange(3), np.argmax(np.abs(self.scene.normals[s])))
            seg = np.stack([flat.V[k][:, axes], flat.V[flat.nxt[k]][:, axes]], axis=1)
            self._poly_trees[s] = (shapely.STRtree(shapely.linestrings(seg)), axes,
                                   float(np.abs(flat.V[k]).max()))
        return self._poly_trees[s]

    def _world_table(self):
        """The fragments' world vertices, laid out as the edge table."""
        if self._world is None:
            offset, count, _ = self._edge_table()
            W = np.full((int(count.sum()), 3), np.nan)
            for pos, V, c in self.world:
                slot = np.arange(V.shape[1])
                valid = slot[None, :] < c[:, None]
                W[(offset[pos][:, None] + slot[None, :])[valid]] = V[valid]
            self._world = W
        return self._world

    def local_planes_ld(self, labels, statics):
        """Plane normals of labels in the long-double local frame, and the condition of
        each (``|a - p| |b - a| / |m|``, 1 for the exact static planes): the relative
        error of a plane's direction is a few units of the working precision times it."""
        out = np.empty((len(labels), 3), dtype=_LD)
        cond = np.ones(len(labels))
        st = labels < 0
        out[st] = statics[-1 - labels[st]].astype(_LD)
        fr = np.flatnonzero(~st)
        if len(fr):
            A, B = self.segments(labels[fr])
            p = self.p.astype(_LD)
            a = A.astype(_LD) - p
            d = B.astype(_LD) - A.astype(_LD)
            m = np.cross(a, d)
            with np.errstate(divide="ignore", invalid="ignore"):
                cond[fr] = (np.sqrt((a * a).sum(1) * (d * d).sum(1))
                            / np.sqrt((m * m).sum(1))).astype(float)
            out[fr] = m @ self.R_ld.T
        return out, cond

    # -- refined rings ----------------------------------------------------------------
    def _vertex_rules(self, label, nxt):
        """Per vertex (incoming edge ``prev``, outgoing edge ``i``): whether it is dropped
        (both edges on one great circle), the input point it is (shared end point of two
        input edges; NaN for none), and the input end points of every edge's line."""
        prev = np.empty_like(nxt)
        prev[nxt] = np.arange(len(nxt))
        li, lo = label[prev], label
        fr = label >= 0
        A = np.full((len(label), 3), np.nan)
        B = np.full((len(label), 3), np.nan)
        if fr.any():
            A[fr], B[fr] = self.segments(label[fr])
        Ai, Bi, Ao, Bo = A[prev], B[prev], A, B
        eq = lambda X, Y: np.all(X == Y, axis=1)
        same = (li == lo) | (eq(Ai, Ao) & eq(Bi, Bo)) | (eq(Ai, Bo) & eq(Bi, Ao))
        point = np.full((len(label), 3), np.nan)
        for X, Y in ((Bi, Ao), (Bi, Bo), (Ai, Ao), (Ai, Bo)):
            hit = eq(X, Y) & np.isnan(point[:, 0])
            point[hit] = X[hit]
        return prev, same, point, A, B

    def refine_ld(self, ci, chart, coords, nxt, ring_of, n_rings, frag, integrator="sector"):
        """Refined rings of chart ``ci`` in long double, integrated by the sector form or
        (``integrator="eq3"``) Eq. 3's stable form.

        Parameters
        ----------
        coords : ndarray of shape (V, 2)
            The rings' vertices in chart coordinates, ring by ring (``ring_of`` sorted).
        nxt : ndarray of shape (V,)
        ring_of : ndarray of shape (V,)
        n_rings : int
        frag : ndarray of shape (V,)

        Returns
        -------
        (ndarray, ndarray, ndarray of bool, labels)
            Per ring the absolute form factor of its image (long double, to be summed
            per piece before rounding), its error estimate, and
            whether it was refined (every edge labelled); and the labels (reused by the
            mpmath tier).
        """
        eu, ev, ew, _ = chart
        label, statics, res, alts = self.match(ci, chart, coords, nxt, frag)
        ok_ring = np.ones(n_rings, dtype=bool)
        ok_ring[ring_of[~np.isfinite(res)]] = False
        val = np.zeros(n_rings, dtype=_LD)
        est = np.full(n_rings, np.inf)
        if not ok_ring.any():
            return val, est, ok_ring, None
        use = ok_ring[ring_of]
        lab = np.where(use, label, -1 - 0)  # unused edges: any static label
        prev, same, point, SA, SB = self._vertex_rules(np.where(use, label, -1), nxt)
        M, cond = self.local_planes_ld(lab, statics)
        Mi, Mo = M[prev], M
        d = np.cross(Mi, Mo)
        nd = np.sqrt((d * d).sum(1))
        sin = (nd / np.sqrt((Mi * Mi).sum(1) * (Mo * Mo).sum(1))).astype(float)
        Dflt = coords[:, :1] * eu + coords[:, 1:2] * ev + ew          # local, double
        has_point = ~np.isnan(point[:, 0])
        Du = _unit(Dflt)
        # two planes closer to parallel than REFINE_PARALLEL: collinear input edges (a
        # T-junction, overlapping segments) or a turn too small to place. Where an input
        # end point of either edge is the clipper's vertex (within REFINE_MATCH), the
        # vertex is that point; elsewhere it is dropped, at most the triangle it cuts
        # off: half its edges' product times the sine of the turn (that of the planes,
        # up to their rounding)
        parallel = use & ~same & ~has_point & ~(sin >= tol.REFINE_PARALLEL)
        if parallel.any():
            v = np.flatnonzero(parallel)
            C = np.stack([SA[prev[v]], SB[prev[v]], SA[v], SB[v]], axis=1)   # (n, 4, 3)
            Cd = _unit((C - self.p) @ self.R_ld.astype(float).T)
            dist = np.nan_to_num(np.linalg.norm(Cd - Du[v][:, None, :], axis=2), nan=np.inf)
            best = np.argmin(dist, axis=1)
            near = dist[np.arange(len(v)), best] <= tol.REFINE_MATCH
            w = v[near]
            point[w] = C[near, best[near]]
            has_point[w] = True
            parallel[w] = False
        X = d
        if has_point.any():
            X[has_point] = (point[has_point].astype(_LD) - self.p.astype(_LD)) @ self.R_ld.T
        # the intersection of two planes is a pair of antipodes: the one near the clipper's
        X = np.where(((X.astype(float) * Dflt).sum(1) < 0)[:, None], -X, X)
        X = X / np.sqrt((X * X).sum(1))[:, None]
        cut = np.zeros(n_rings)
        if parallel.any():
            v = np.flatnonzero(parallel)
            tri = 0.5 * (np.linalg.norm(Du[v] - Du[prev[v]], axis=1)
                         * np.linalg.norm(Du[nxt[v]] - Du[v], axis=1)
                         * (np.nan_to_num(sin[v]) + tol.REFINE_VERTEX_ULPS * tol.LONGDOUBLE_EPS))
            cut = np.bincount(ring_of[v], weights=tri, minlength=n_rings) / np.pi
        same = same | parallel
        # a refined vertex must stand where the clipper's does, within what the clipper's
        # accuracy allows (an input point: REFINE_MATCH; two planes' intersection: their
        # ambiguity over the sine of their angle): where it does not, the labels do not
        # describe the clipper's ring (a sliver whose closing edge rounded to nothing took
        # its neighbour's label, and the shared input point of the two long edges became
        # the far vertex too: the ring collapsed to 0 with a bound of 1e-19, 4.8e-16 off),
        # and the ring keeps the clipper's value and estimate
        moved = np.linalg.norm(X.astype(float) - Du, axis=1)
        reach = tol.REFINE_MATCH + np.where(
            has_point, 0.0, 2.0 * tol.REFINE_AMBIGUOUS / np.maximum(np.nan_to_num(sin), 1e-300))
        astray = use & ~same & ~(moved <= reach)
        if astray.any():
            ok_ring[ring_of[astray]] = False
            use = ok_ring[ring_of]
        cut = cut + self._ambiguity(label, res, alts, statics, M, Du, nxt, prev, sin, same,
                                    use, ring_of, n_rings)
        labels = (label, statics, point, same, cut)
        keep = use & ~same
        # compress: the kept vertices of each ring, in order
        kv = np.flatnonzero(keep)
        r = ring_of[kv]
        cnt = np.bincount(r, minlength=n_rings)
        good = ok_ring & (cnt >= 3)
        kv = kv[good[r]]
        r = ring_of[kv]
        if len(kv) == 0:
            val[ok_ring] = 0.0
            est[ok_ring] = cut[ok_ring]
            return val, est, ok_ring, labels
        rings = np.flatnonzero(good)
        ridx = np.searchsorted(rings, r)
        st = np.searchsorted(ridx, np.arange(len(rings)))
        nx2 = successors(np.append(st, len(kv)))
        Xk = X[kv]
        A0 = Xk[st]
        ring_sums = eq3_ring_sums if integrator == "eq3" else clipped_sector_sums
        S, mags, errs = ring_sums(A0, Xk - A0[ridx], nx2, ridx, len(rings),
                                  eps=tol.LONGDOUBLE_EPS)
        v = np.abs(S) / TWO_PI_LONG                 # long double: summed per piece
        # the vertices' geometry: each refined edge (the arc through its two computed
        # end points) is off its input plane by its end points' residuals (measured),
        # their evaluation and the plane's own rounding; the area between the two arcs
        # is at most the edge's length times their mean
        Mk = M[kv]
        Mk = Mk / np.sqrt((Mk * Mk).sum(1))[:, None]
        res = (np.abs((Mk * Xk).sum(1)) + np.abs((Mk * Xk[nx2]).sum(1))).astype(float)
        Xf = Xk.astype(float)
        seg = np.linalg.norm(Xf[nx2] - Xf, axis=1)
        g = 0.5 * seg * (res + tol.REFINE_VERTEX_ULPS * tol.LONGDOUBLE_EPS * (1.0 + cond[kv]))
        geom = np.bincount(ridx, weights=g, minlength=len(rings)) / np.pi
        e = ((tol.C1 * tol.LONGDOUBLE_EPS * mags + errs) / TWO_PI_LONG).astype(float) + geom \
            + 4 * tol.LONGDOUBLE_EPS * v.astype(float) + cut[rings]
        val[rings], est[rings] = v, e
        deg = ok_ring & ~good
        val[deg], est[deg] = 0.0, cut[deg]
        return val, est, ok_ring, labels

    def _ambiguity(self, label, res, alts, statics, M, Du, nxt, prev, sin, same, use,
                   ring_of, n_rings):
        """Per ring, a bound on what its labels' choice can move (form factor units):
        the clipper's vertices are within ``CHART_VERTEX_ERROR`` of their places, so the
        plane an edge truly lies on is among the candidates within ``REFINE_AMBIGUOUS``
        of both its end points (:meth:`match`); where another candidate than the label
        is there (not the same input segment), the true edge may be that plane's arc.

        The region between the label's arc and another plane's arc over an edge of arc
        length ``phi`` (chord ``c``) whose end points are within ``h`` of the other
        plane (``h``: the larger of the two planes' separations at the clipper's end
        points, ``|(m' - s m) . d|`` for unit normals ``m, m'`` with ``s`` the sign of
        ``m . m'``) lies within ``h / cos(phi / 2)`` of the arc (the separation of two
        great circles is a sine of the arc length, largest between the ends at most by
        that factor), and its ends run along the neighbouring edges, at most ``h / sin
        theta`` beyond the vertex where the turn is ``theta``: its area is at most
        ``h / cos(phi / 2) (phi + h / sin theta_a + h / sin theta_b)``, and its image on
        the base disk at most that (the projection's density is at most 1), over pi in
        form factor units. A label with a residual above ``REFINE_AMBIGUOUS`` (no
        candidate stands for the clipper's edge within its accuracy) is charged as if
        its plane were ``h`` = its residual plus ``CHART_VERTEX_ERROR`` away."""
        e_alt, l_alt = alts
        keep = use[e_alt] & (l_alt != label[e_alt])
        e_alt, l_alt = e_alt[keep], l_alt[keep]
        # the same input segment as the label: the same plane
        fr = np.flatnonzero((l_alt >= 0) & (label[e_alt] >= 0))
        if len(fr):
            A1, B1 = self.segments(l_alt[fr])
            A0, B0 = self.segments(label[e_alt[fr]])
            eq = lambda X, Y: np.all(X == Y, axis=1)
            one = (eq(A0, A1) & eq(B0, B1)) | (eq(A0, B1) & eq(B0, A1))
            drop = np.zeros(len(e_alt), dtype=bool)
            drop[fr[one]] = True
            e_alt, l_alt = e_alt[~drop], l_alt[~drop]
        h = np.zeros(len(label))
        if len(e_alt):
            Ma, _ = self.local_planes_ld(l_alt, statics)
            Ma = (Ma / np.sqrt((Ma * Ma).sum(1))[:, None]).astype(float)
            Ml = M[e_alt]
            Ml = (Ml / np.sqrt((Ml * Ml).sum(1))[:, None]).astype(float)
            s = np.where((Ma * Ml).sum(1) < 0, -1.0, 1.0)
            Dm = Ma - s[:, None] * Ml
            sep = np.maximum(np.abs((Dm * Du[e_alt]).sum(1)),
                             np.abs((Dm * Du[nxt[e_alt]]).sum(1)))
            np.maximum.at(h, e_alt, np.nan_to_num(sep, nan=np.inf))
        far = use & np.isfinite(res) & (res > tol.REFINE_AMBIGUOUS)
        h[far] = np.maximum(h[far], res[far] + tol.CHART_VERTEX_ERROR)
        e = np.flatnonzero(use & (h > 0))
        if not len(e):
            return np.zeros(n_rings)
        c = np.linalg.norm(Du[nxt[e]] - Du[e], axis=1)
        phi = 2.0 * np.arcsin(np.minimum(0.5 * c, 1.0))
        # the turns at the edge's end points (none where the vertex is dropped: the
        # next edge is on the same great circle and carries its own candidates)
        turn = lambda v: np.where(same[v], 0.0, 1.0 / np.maximum(np.nan_to_num(sin[v]),
                                                                 tol.REFINE_PARALLEL))
        he = h[e] / np.cos(0.5 * phi)
        area = he * (phi + h[e] * (turn(e) + turn(nxt[e])))
        return np.bincount(ring_of[e], weights=area, minlength=n_rings) / np.pi

    def refine_mp(self, chart, coords, label, statics, point, drop, cut, tolerance,
                  integrator="sector"):
        """One refined ring in mpmath (labels from :meth:`refine_ld`), integrated by the
        sector form or (``integrator="eq3"``) Eq. 3's stable form: planes and
        vertices from the input at the working precision, evaluated at two precisions
        20 digits apart, raised until they agree to ``tolerance``. Returns the absolute
        form factor of its image (an mpf, to be summed per piece before rounding), its
        error estimate, and whether the two evaluations agreed (False: mpmath stopped
        at ``MP_MAX_DPS`` digits; the estimate is then their difference, which the
        caller counts and checks with the others). ``point``, ``drop`` and ``cut``
        are the long-double tier's decisions (input points, dropped vertices, the
        triangles they may cut off), kept here."""
        import mpmath as mp

        eu, ev, ew, _ = chart
        k = len(coords)
        nxt = (np.arange(k) + 1) % k
        prev, _, _, A, B = self._vertex_rules(label, nxt)
        same = drop
        Dflt = coords[:, :1] * eu + coords[:, 1:2] * ev + ew

        # the input as mpf values (exact, whatever the working precision)
        mpf = mp.mpf
        pv = [mpf(float(c)) for c in self.p]
        plane_in = []
        for i in range(k):
            if label[i] < 0:
                plane_in.append(None)
            else:
                a = [mpf(float(A[i, j])) for j in range(3)]
                b = [mpf(float(B[i, j])) for j in range(3)]
                plane_in.append((a, b))
        pts = [None if np.isnan(point[i, 0]) else [mpf(float(c)) for c in point[i]]
               for i in range(k)]

        def cross(a, b):
            return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0]]

        def evaluate(dps):
            with mp.workdps(dps):
                frame = self._mp_frames.get(dps)
                if frame is None:
                    frame = self._mp_frames[dps] = mp_receiver_frame(self.n)

                def local(w):
                    return [mp.fdot(ax, w) for ax in frame]

                M = []
                for i in range(k):
                    if plane_in[i] is None:
                        M.append([mpf(float(c)) for c in statics[-1 - label[i]]])
                    else:
                        a, b = plane_in[i]
                        M.append(local(cross([a[j] - pv[j] for j in range(3)],
                                             [b[j] - a[j] for j in range(3)])))
                X = []
                for i in range(k):
                    if same[i]:
                        continue
                    if pts[i] is not None:
                        x = local([pts[i][j] - pv[j] for j in range(3)])
                    else:
                        x = cross(M[prev[i]], M[i])
                        nx = mp.sqrt(mp.fdot(x, x))
                        na = mp.sqrt(mp.fdot(M[prev[i]], M[prev[i]]) * mp.fdot(M[i], M[i]))
                        if nx <= mp.mpf(10) ** (tol.REFINE_MP_ZERO_DIGITS - dps) * na:
                            continue   # one great circle (collinear input edges)
                    if sum(float(x[j]) * Dflt[i, j] for j in range(3)) < 0:
                        x = [-c for c in x]
                    X.append(x)
                ring_sum = mp_eq3_sum if integrator == "eq3" else mp_sector_sum
                return abs(ring_sum(X)) / (2 * mp.pi) if len(X) >= 3 else mp.mpf(0)

        hi, diff, converged = mp_converge(evaluate, tolerance)
        return hi, float(diff) + cut, converged
