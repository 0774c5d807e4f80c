"""Native z-buffers of the discrete methods: each method's own projection and grid.

The shared core (:func:`exactff.methods._sampling.nearest_polygons`) finds the nearest
polygon along any set of directions; it is the test oracle. Here each method
rasterises the way its paper describes it: polygons projected onto the method's own
image plane or disk and scan-converted there, row by row of its own grid, vectorised
over (polygon, row) pairs: every row's crossings with the polygon's edges, sorted, give
the spans of cells inside (even-odd rule; a crossing counts where an edge goes from
"at or below" the row to "above" it, so a cell on an edge shared by two polygons lies
in exactly one). The depth test is the shared depth buffer
(:func:`exactff.methods._sampling.resolve_depths`).

- :func:`rasterise_face`: a planar image face (the hemicube's five faces), straight
  edges (central projection keeps lines straight), polygons clipped to the face's
  frustum first.
- :func:`rasterise_disk`: the base of the hemisphere (discrete PPBH): polygons clipped
  to the horizon and projected once; every edge's image is an ellipse arc (Eq. 2),
  split at its extreme in y (monotone-span splitting, as for Eq. 3, here across rows)
  so that each piece crosses a row at most once; the crossing solves a quadratic.
- :func:`rasterise_polar`: the polar plane's grid, scanned along each sector's ray.

Each has a compiled backend (:func:`compiled_zbuffer`, ``exactff/_core/zbuffer.cpp``):
the same clipping (a chart's, a :class:`FaceClip`'s, the horizon's), scanlines, spans,
chunks and depth rule in C++, cell for cell (the numpy code here is its oracle).
"""

import numpy as np

from .. import _tolerances as tol
from ..halfspace import clip_halfspace
from ..visibility.charts import chart_clip, chart_planes
from ._sampling import PAIR_CHUNK, resolve_depths, zbuffer_of

__all__ = ["rasterise_face", "rasterise_disk", "rasterise_polar", "face_clipper",
           "plane_clipper", "FaceClip", "cell_table", "DEPTH_CHUNK", "compiled_zbuffer", "BACKENDS",
           "check_backend"]

#: Where the native rasterisers scan-convert and depth-test: "compiled" (the C++
#: z-buffer, exactff.methods._zbuffer) or "numpy" (vectorised numpy; its oracle)
BACKENDS = ("compiled", "numpy")


def check_backend(backend):
    """The backend name, checked against :data:`BACKENDS`."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {list(BACKENDS)}, got {backend!r}")
    return backend


def compiled_zbuffer(z, layout):
    """The compiled z-buffer (``exactff.methods._zbuffer.ZBuffer``) of one row: the
    layout's cell directions and the live polygons' depth data of ``z``
    (:class:`ZBufferRow`), with the scene's planes for the coplanar rule."""
    return zbuffer_of(z, layout.directions, layout.direction_norms)


def cell_table(cell_of, nu, nv):
    """``cell_of`` over the whole grid: an int64 array of shape (nu, nv), which the
    rasterisers take in its place (a method builds it once)."""
    if isinstance(cell_of, np.ndarray):
        return cell_of
    return np.ascontiguousarray(np.broadcast_to(
        cell_of(np.arange(nu)[:, None], np.arange(nv)[None, :]), (nu, nv)), dtype=np.int64)


def _cell_function(cell_of):
    """``cell_of(i, j)`` from a function or a :func:`cell_table`."""
    if isinstance(cell_of, np.ndarray):
        return lambda i, j: cell_of[i, j]
    return cell_of


def _first_at_or_above(centres, x):
    """Index of the first centre >= x (``len(centres)`` if none), exactly."""
    return np.searchsorted(centres, x, side="left")


def _spans_to_cells(X, uc):
    """Cells inside each (pair)'s spans: ``X`` (P, C) crossings (NaN for none), sorted
    per row, pairs (x1, x2), (x3, x4), ...: centres in [x1, x2) and so on.

    Returns (pair index, column) of every cell inside."""
    X = np.sort(X, axis=1)
    n = np.sum(~np.isnan(X), axis=1)
    npairs = n // 2
    C = X.shape[1] // 2 * 2
    a = X[:, 0:C:2]
    b = X[:, 1:C:2]
    k = np.arange(a.shape[1])[None, :] < npairs[:, None]
    pair = np.broadcast_to(np.arange(len(X))[:, None], a.shape)[k]
    ia = _first_at_or_above(uc, a[k])
    ib = _first_at_or_above(uc, b[k])
    cnt = np.maximum(ib - ia, 0)
    pair = np.repeat(pair, cnt)
    col = np.repeat(ia, cnt) + np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    return pair, col


def _row_pairs(lo, hi, vc):
    """(polygon, row) pairs: the rows whose centre lies in [lo, hi] per polygon."""
    j0 = np.searchsorted(vc, lo, side="left")
    j1 = np.searchsorted(vc, hi, side="right")
    cnt = np.maximum(j1 - j0, 0)
    poly = np.repeat(np.arange(len(lo)), cnt)
    row = np.repeat(j0, cnt) + np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    return poly, row


#: (cell, polygon) candidates depth-tested at once: large gathers of random rows cost far
#: more per element than cache-sized ones (measured: 2.7 M at once 5 times the time per
#: pair of 0.5 M)
DEPTH_CHUNK = 1 << 19


def _depth_test(z, cell, src, D, best_t, best):
    for a in range(0, len(cell), DEPTH_CHUNK):
        resolve_depths(cell[a:a + DEPTH_CHUNK], src[a:a + DEPTH_CHUNK], D, z.nl, z.dl,
                       z.band, z.prio, best_t, best, coplanar=z.coplanar)


def _chunks(n_pairs, width):
    step = max(1, PAIR_CHUNK // max(width, 1))
    return [(s, min(s + step, n_pairs)) for s in range(0, n_pairs, step)]


def _frame_dot(V, r):
    """``V . r`` over the last axis, the products added first to second, then the
    third: the order the compiled clipper uses (a matrix product may fuse them)."""
    return (V[..., 0] * r[0] + V[..., 1] * r[1]) + V[..., 2] * r[2]


class FaceClip:
    """A planar face's frustum clipping and projection for :func:`rasterise_face` and
    :func:`rasterise_polar`, with the contract of
    :func:`exactff.visibility.charts.chart_clip`: ``clip(V, counts) -> (live, UV, cl)``.

    The polygons (local frame) are taken into the face's frame ``W = R x`` (rows of
    ``R``; each product added in a fixed order, so that the compiled clipper,
    ``exactff.methods._zbuffer.face_clip``, gives the same bits), clipped there to the
    half-spaces ``h . W > 0`` of ``planes`` (entries 0 and +-1: the side tests are
    exact), and projected: ``u = (scale W_0) / W_2``, ``v = (scale W_1) / W_2``.
    """

    def __init__(self, R, planes, scale=1.0):
        self.R = np.ascontiguousarray(R, dtype=float)
        self.planes = np.ascontiguousarray(planes, dtype=float)
        self.scale = float(scale)
        if self.R.shape != (3, 3) or self.planes.ndim != 2 or self.planes.shape[1] != 3:
            raise ValueError("R must have shape (3, 3) and planes (P, 3)")
        if not np.all(np.isin(self.planes, (-1.0, 0.0, 1.0))):
            raise ValueError(f"planes' entries must be 0, 1 or -1, got {self.planes!r}")

    def __call__(self, V, counts):
        W = np.stack([_frame_dot(V, r) for r in self.R], axis=-1)
        slot = np.arange(W.shape[1])[None, :] < counts[:, None]
        S = np.stack([_frame_dot(W, h) for h in self.planes], axis=-1)
        reach = np.flatnonzero(~np.any(np.all((S <= 0) | ~slot[:, :, None], axis=1), axis=1)
                               & (counts >= 3))
        Wc, cc = W[reach], counts[reach]
        for h in self.planes:
            if not np.any(cc >= 3):
                break
            Wc, cc = clip_halfspace(Wc, np.where(cc >= 3, cc, 0), h)
        ok = np.flatnonzero(cc >= 3)
        Wc, cc = Wc[ok], cc[ok]
        K = Wc.shape[1]
        last = np.take_along_axis(Wc, np.maximum(cc - 1, 0)[:, None, None].repeat(3, axis=2),
                                  axis=1)
        Wc = np.where((np.arange(K)[None, :] < cc[:, None])[:, :, None], Wc, last)
        UV = np.stack([(self.scale * Wc[:, :, 0]) / Wc[:, :, 2],
                       (self.scale * Wc[:, :, 1]) / Wc[:, :, 2]], axis=-1)
        return reach[ok], UV, cc


def face_clipper(R, planes, scale=1.0):
    """A :class:`FaceClip`: the face's frame ``R`` (rows), its frustum's planes in that
    frame (entries 0 and +-1), and the scale of its coordinates."""
    return FaceClip(R, planes, scale)


def plane_clipper(extent):
    """The frustum of the plane ``z = 1`` over ``[-E, E]^2`` (the single and polar
    planes): in the frame ``(x, y, E z)`` the planes ``E z -+ x > 0``, ``E z -+ y > 0``
    have entries 0 and +-1; coordinates ``u = (E x) / (E z)``."""
    E = float(extent)
    return FaceClip(np.diag([1.0, 1.0, E]),
                    [[-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, -1.0, 1.0], [0.0, 1.0, 1.0]], E)


def rasterise_face(z, chart, uc, vc, cell_of, D, best_t, best, clip=None, zbuffer=None):
    """Scan-convert every live polygon on one planar face; depth-test into the buffer.

    Parameters
    ----------
    z : ZBufferRow
    chart : (e_u, e_v, e_w, side)
        The face's plane ``w = 1`` and axes (one of the engine's charts), when ``clip``
        is not given.
    uc, vc : ndarray
        Cell centres along u and v, increasing.
    cell_of : callable or ndarray
        ``cell_of(i, j)`` -> the index in the layout of the cell at ``(uc[i], vc[j])``
        (consecutive along j), -1 for a grid cell the layout does not have; or its
        :func:`cell_table`.
    D : ndarray of shape (C, 3)
        The layout's cell directions (for the depths).
    best_t, best : ndarray of shape (C,)
        The depth buffer (updated in place).
    clip : callable, optional
        ``clip(V, counts) -> (live, UV, counts)``: the face's frustum clipping and
        projection (:func:`face_clipper`); default the chart's.
    zbuffer : exactff.methods._zbuffer.ZBuffer, optional
        The row's compiled z-buffer (:func:`compiled_zbuffer`): scan conversion and
        depth test in C++, cell for cell as here; default the numpy code below.
    """
    if zbuffer is not None:
        table = cell_table(cell_of, len(uc), len(vc))
        if clip is None:
            planes = np.array(chart_planes(chart))
    cell_of = _cell_function(cell_of)
    for g_ids, V, counts in z.local:
        if zbuffer is not None and clip is None:
            # the chart's clipping (chart_clip, bit for bit) compiled too
            zbuffer.chart_face(V, counts, g_ids, planes, *chart, uc, vc, table, best_t, best,
                               PAIR_CHUNK, DEPTH_CHUNK)
            continue
        if zbuffer is not None and isinstance(clip, FaceClip):
            # the face's clipping (FaceClip, bit for bit) compiled too
            zbuffer.clipped_face(V, counts, g_ids, clip.R, clip.planes, clip.scale, uc, vc,
                                 table, best_t, best, PAIR_CHUNK, DEPTH_CHUNK)
            continue
        live, UV, cl = chart_clip(V, counts, chart) if clip is None else clip(V, counts)
        if len(live) == 0:
            continue
        if zbuffer is not None:
            # the same scanlines (along u), spans (along v), chunks and depth rule
            zbuffer.face(UV, cl, g_ids[live], uc, vc, table, best_t, best, PAIR_CHUNK,
                         DEPTH_CHUNK)
            continue
        # scanlines u = const, spans along v: the layout's fast axis (cell index
        # ``cell_of(i, j)`` grows by one along v), so a span is a run of cells
        UV = UV[:, :, ::-1]
        poly, row = _row_pairs(UV[:, :, 1].min(axis=1), UV[:, :, 1].max(axis=1), uc)
        K = UV.shape[1]
        for s0, s1 in _chunks(len(poly), K):
            P, r = poly[s0:s1], row[s0:s1]
            y = uc[r]
            X = np.full((len(P), K), np.nan)
            for e in range(K):
                a = UV[P, e]
                c = UV[P, (e + 1) % K]
                straddles = (a[:, 1] > y) != (c[:, 1] > y)
                # from the lower end point, whichever way the edge runs (a shared edge
                # gives the same crossing in both polygons)
                swap = (a[:, 1] > c[:, 1])[:, None]
                a, c = np.where(swap, c, a), np.where(swap, a, c)
                with np.errstate(divide="ignore", invalid="ignore"):
                    ux = a[:, 0] + (y - a[:, 1]) * (c[:, 0] - a[:, 0]) / (c[:, 1] - a[:, 1])
                X[straddles, e] = ux[straddles]
            pair, col = _spans_to_cells(X, vc)
            cell = cell_of(r[pair], col)
            keep = cell >= 0
            _depth_test(z, cell[keep], g_ids[live[P[pair[keep]]]], D, best_t, best)


def _passes_near_origin(V, counts):
    """Whether an edge of each padded polygon passes within ``RASTER_NEAR_ORIGIN``
    (relative) of the origin."""
    K = V.shape[1]
    nxt = (np.arange(K)[None, :] + 1) % counts[:, None]
    B = np.take_along_axis(V, nxt[:, :, None].repeat(3, axis=2), axis=1)
    d = B - V
    dd = (d * d).sum(2)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.clip(-(V * d).sum(2) / dd, 0.0, 1.0)
    s = np.nan_to_num(s)
    closest = np.linalg.norm(V + s[:, :, None] * d, axis=2)
    scale = np.maximum(np.linalg.norm(V, axis=2), np.linalg.norm(B, axis=2))
    slot = np.arange(K)[None, :] < counts[:, None]
    return np.any(slot & (closest <= tol.RASTER_NEAR_ORIGIN * scale), axis=1)


def _cast_rays(z, live_index, P, D, best_t, best):
    """Depth-test one polygon (local vertices ``P``) by casting every cell's ray: the
    hit point ``t d`` with ``t = (n . a) / (n . d) > 0``, inside the polygon (in the
    coordinate plane most parallel to it, boundary included)."""
    import shapely

    n = z.nl[live_index]
    t_num = z.dl[live_index]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = t_num / (D @ n)
        X = t[:, None] * D
    cand = np.flatnonzero(np.isfinite(t) & (t > 0))
    if len(cand) == 0:
        return
    drop = int(np.argmax(np.abs(n)))
    axes = [k for k in range(3) if k != drop]
    g = shapely.Polygon(P[:, axes])
    if not g.is_valid:
        g = g.buffer(0)
    inside = shapely.intersects_xy(g, X[cand, axes[0]], X[cand, axes[1]])
    cells = cand[inside]
    _depth_test(z, cells, np.full(len(cells), live_index), D, best_t, best)


def _arc_y(a, d, s):
    """y of the unit direction along ``a + s d`` (its image on the base disk)."""
    q = a + s[..., None] * d
    return q[..., 1] / np.sqrt((q * q).sum(-1))


def rasterise_disk(z, xc, yc, cell_of, D, best_t, best, zbuffer=None):
    """Scan-convert every live polygon's image on the base of the hemisphere.

    Each polygon is clipped to the horizon and its edges taken as great-circle arcs
    ``a + s (b - a)``, ``s`` in [0, 1] (normalised), whose images are ellipse arcs. An
    arc's y is unimodal in s: it is split at its extreme, and each monotone piece
    crosses a row y = y_j at most once, where ``(a_y + s d_y)^2 = y_j^2 |a + s d|^2``.

    Parameters
    ----------
    z : ZBufferRow
    xc, yc : ndarray
        Cell centres along x and y of the square grid on the disk.
    cell_of : callable or ndarray
        ``cell_of(i, j)`` -> the index in the layout of the cell at ``(xc[i], yc[j])``
        (consecutive along j), -1 for a grid cell outside the disk; or its
        :func:`cell_table`.
    D, best_t, best, zbuffer : as :func:`rasterise_face` (the compiled disk: the same
        clipping, arcs, crossings, spans and depth rule).
    """
    ez = np.array([0.0, 0.0, 1.0])
    if zbuffer is not None:
        table = cell_table(cell_of, len(xc), len(yc))
    cell_of = _cell_function(cell_of)
    for g_ids, V, counts in z.local:
        if zbuffer is not None:
            # the arcs scan-converted in C++; if polygons pass through the point to
            # rounding, those first, ray by ray, as below, then the others' arcs
            near = zbuffer.disk(V, counts, g_ids, xc, yc, table, best_t, best, PAIR_CHUNK,
                                DEPTH_CHUNK, tol.RASTER_NEAR_ORIGIN)
            if len(near):
                for k in near:
                    _cast_rays(z, int(g_ids[k]), V[k, :counts[k]], D, best_t, best)
                zbuffer.disk(V, counts, g_ids, xc, yc, table, best_t, best, PAIR_CHUNK,
                             DEPTH_CHUNK, tol.RASTER_NEAR_ORIGIN, after_near=True)
            continue
        V0 = V
        # scanlines x = const, spans along y (the layout's fast axis): swap x and y
        V = V[:, :, [1, 0, 2]]
        Vc, cc = clip_halfspace(V, counts, ez)
        live = np.flatnonzero(cc >= 3)
        if len(live) == 0:
            continue
        Vc, cc = Vc[live], cc[live]
        K = Vc.shape[1]
        slot = np.arange(K)[None, :] < cc[:, None]
        # a polygon whose edge passes within rounding of the point (its plane nearly
        # through the point, the point nearly on it): its arcs' parametrisation breaks
        # down there; such polygons are cast ray by ray instead
        near = _passes_near_origin(Vc, cc)
        if near.any():
            for k in np.flatnonzero(near):
                _cast_rays(z, int(g_ids[live[k]]), V0[live[k], :counts[live[k]]], D,
                           best_t, best)
            keep_k = np.flatnonzero(~near)
            if len(keep_k) == 0:
                continue
            Vc, cc, live, slot = Vc[keep_k], cc[keep_k], live[keep_k], slot[keep_k]
        last = np.take_along_axis(Vc, (cc - 1)[:, None, None].repeat(3, axis=2), axis=1)
        Vc = np.where(slot[:, :, None], Vc, last)
        nxt = (np.arange(K)[None, :] + 1) % cc[:, None]
        A = Vc
        B = np.take_along_axis(Vc, nxt[:, :, None].repeat(3, axis=2), axis=1)
        B = np.where(slot[:, :, None], B, A)            # padding: zero-length edges
        ya = A[:, :, 1] / np.linalg.norm(A, axis=2)     # each vertex's y, computed once
        yb = np.where(slot, np.take_along_axis(ya, nxt, axis=1), ya)
        # every edge from its lower end point (y, then x, then z), whichever way the
        # polygon runs: an edge shared by two polygons is then computed identically in
        # both, and a cell on it lies in exactly one
        swap = (yb < ya) | ((yb == ya) & ((B[:, :, 0] < A[:, :, 0])
                                         | ((B[:, :, 0] == A[:, :, 0]) & (B[:, :, 2] < A[:, :, 2]))))
        A, B = np.where(swap[:, :, None], B, A), np.where(swap[:, :, None], A, B)
        yv, yb = np.where(swap, yb, ya), np.where(swap, ya, yb)
        d = B - A
        # the arc's extreme in y: d/ds y(s) = 0 is linear in s
        ad = (A * d).sum(2)
        aa = (A * A).sum(2)
        dd = (d * d).sum(2)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_ext = (A[:, :, 1] * ad - d[:, :, 1] * aa) / (d[:, :, 1] * ad - A[:, :, 1] * dd)
        inner = (s_ext > 0) & (s_ext < 1) & slot
        s_ext = np.where(inner, s_ext, 1.0)
        y_ext = np.where(inner, _arc_y(A, d, s_ext), yb)
        # monotone pieces: [0, s_ext] from yv to y_ext, [s_ext, 1] from y_ext to yb
        S0 = np.concatenate([np.zeros_like(s_ext), s_ext], axis=1)
        S1 = np.concatenate([s_ext, np.ones_like(s_ext)], axis=1)
        Y0 = np.concatenate([yv, y_ext], axis=1)
        Y1 = np.concatenate([y_ext, yb], axis=1)
        ok = np.concatenate([slot, inner], axis=1)
        lo = np.where(ok, np.minimum(Y0, Y1), np.inf).min(axis=1)
        hi = np.where(ok, np.maximum(Y0, Y1), -np.inf).max(axis=1)
        poly, row = _row_pairs(lo, hi, xc)
        # per monotone piece, the scalars the crossings need (gathered per row below)
        two = lambda v: np.concatenate([v, v], axis=1)
        ax, ay, dx, dy = two(A[:, :, 0]), two(A[:, :, 1]), two(d[:, :, 0]), two(d[:, :, 1])
        a2, v2, av = two(aa), two(dd), two(ad)
        for c0, c1 in _chunks(len(poly), 2 * K):
            P, r = poly[c0:c1], row[c0:c1]
            y = xc[r][:, None]
            cross = ((Y0[P] > y) != (Y1[P] > y)) & ok[P]
            # the crossings only (most pieces miss a given scanline)
            q, e = np.nonzero(cross)
            Pe, yq = P[q], y[q, 0]
            pay, pdy, pa2, pv2, pav = ay[Pe, e], dy[Pe, e], a2[Pe, e], v2[Pe, e], av[Pe, e]
            yy = yq * yq
            q2 = pdy * pdy - yy * pv2
            q1 = 2.0 * (pay * pdy - yy * pav)
            q0 = pay * pay - yy * pa2
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                disc = np.sqrt(np.maximum(q1 * q1 - 4.0 * q2 * q0, 0.0))
                # the two roots, in the cancellation-free forms
                big = -0.5 * (q1 + np.copysign(disc, q1))
                r1 = big / q2
                r2 = q0 / big
                lin = -q0 / q1                              # q2 = 0: one root
            s0, s1 = S0[Pe, e], S1[Pe, e]
            # the root on the monotone piece and on the row's side (y_j, not -y_j); near
            # the piece's ends (a double root at the arc's extreme) rounding may put it
            # just outside: the candidate nearest the piece, clipped to it
            best_s = np.full(s0.shape, 0.5 * (s0 + s1))
            best_d = np.full(s0.shape, np.inf)
            for cand in (r1, r2, lin):
                with np.errstate(invalid="ignore", over="ignore"):
                    side = (np.sign(pay + cand * pdy) == np.sign(yq)) | (yq == 0)
                    dist = np.maximum(np.maximum(s0 - cand, cand - s1), 0.0)
                    dist = np.where(np.isfinite(cand), dist, np.inf) + np.where(side, 0.0, 1.0)
                take = dist < best_d
                best_s = np.where(take, cand, best_s)
                best_d = np.where(take, dist, best_d)
            s = np.clip(best_s, s0, s1)
            X = np.full(cross.shape, np.nan)
            X[q, e] = (ax[Pe, e] + s * dx[Pe, e]) / np.sqrt(pa2 + s * (2.0 * pav + s * pv2))
            pair, col = _spans_to_cells(X, yc)
            cell = cell_of(r[pair], col)
            keep = cell >= 0
            _depth_test(z, cell[keep], g_ids[live[P[pair[keep]]]], D, best_t, best)


def rasterise_polar(z, radii, angles, cell_of, D, best_t, best, clip, zbuffer=None):
    """Scan-convert every live polygon on a plane's polar grid (the polar plane).

    The polygon's image on the plane (straight edges, clipped by ``clip``) is scanned
    along every sector's ray from the centre, ``(cos phi, sin phi) rho``, rho > 0: its
    edges' crossings with the ray, sorted, give the spans of radii inside (even-odd,
    counted outwards to infinity: with an odd number of crossings the centre is inside
    and the first span starts at 0). Only the sectors within the image's angular extent
    are scanned (all of them when its bounding box holds the centre).

    Parameters
    ----------
    z : ZBufferRow
    radii, angles : ndarray
        Ring radii and sector angles of the cell centres, increasing (angles in
        ``[0, 2 pi)``).
    cell_of : callable
        ``cell_of(ring, sector)`` -> the cell's index in the layout.
    D, best_t, best : as :func:`rasterise_face`.
    clip : FaceClip
        The plane's frustum clipping and projection (:func:`plane_clipper`).
    zbuffer : exactff.methods._zbuffer.ZBuffer, optional
        The compiled z-buffer (:func:`compiled_zbuffer`): the same clipping, sectors,
        crossings, spans and depth rule in C++; ``cell_of(ring, sector)`` must then be
        ``ring * len(angles) + sector``.
    """
    S = len(angles)
    step = 2.0 * np.pi / S
    cos, sin = np.cos(angles), np.sin(angles)
    for g_ids, V, counts in z.local:
        if zbuffer is not None:
            zbuffer.polar(V, counts, g_ids, clip.R, clip.planes, clip.scale, radii, cos, sin,
                          best_t, best, PAIR_CHUNK, DEPTH_CHUNK)
            continue
        live, UV, cl = clip(V, counts)
        if len(live) == 0:
            continue
        K = UV.shape[1]
        # every edge from its lower end point (y, then x): computed identically in the
        # polygons that share it
        A = UV
        B = np.roll(UV, -1, axis=1)
        B = np.where((np.arange(K)[None, :] < cl[:, None] - 1)[:, :, None], B,
                     np.take_along_axis(UV, np.zeros((len(UV), 1, 1), dtype=int).repeat(2, 2),
                                        axis=1))
        slot = np.arange(K)[None, :] < cl[:, None]
        B = np.where(slot[:, :, None], B, A)
        swap = (B[:, :, 1] < A[:, :, 1]) | ((B[:, :, 1] == A[:, :, 1]) & (B[:, :, 0] < A[:, :, 0]))
        A, B = np.where(swap[:, :, None], B, A), np.where(swap[:, :, None], A, B)
        # sectors within each image's angular extent
        lo, hi = UV.min(axis=1), UV.max(axis=1)
        holds = (lo[:, 0] <= 0) & (hi[:, 0] >= 0) & (lo[:, 1] <= 0) & (hi[:, 1] >= 0)
        corners = np.stack([lo, np.column_stack([lo[:, 0], hi[:, 1]]), hi,
                            np.column_stack([hi[:, 0], lo[:, 1]])], axis=1)
        ang = np.arctan2(corners[:, :, 1], corners[:, :, 0])
        mid = np.arctan2((lo[:, 1] + hi[:, 1]) / 2, (lo[:, 0] + hi[:, 0]) / 2)
        off = (ang - mid[:, None] + np.pi) % (2 * np.pi) - np.pi
        k0 = np.ceil((mid + off.min(axis=1)) / step - 0.5).astype(int) - 1
        k1 = np.floor((mid + off.max(axis=1)) / step - 0.5).astype(int) + 1
        k0 = np.where(holds, 0, k0)
        k1 = np.where(holds, S - 1, np.minimum(k1, k0 + S - 1))
        cnt = k1 - k0 + 1
        poly = np.repeat(np.arange(len(live)), cnt)
        sector = (np.repeat(k0, cnt) + np.arange(int(cnt.sum()))
                  - np.repeat(np.cumsum(cnt) - cnt, cnt)) % S
        for s0, s1 in _chunks(len(poly), K):
            P, k = poly[s0:s1], sector[s0:s1]
            cx, sy = cos[k][:, None], sin[k][:, None]
            a, b = A[P], B[P]
            sa = cx * a[:, :, 1] - sy * a[:, :, 0]
            sb = cx * b[:, :, 1] - sy * b[:, :, 0]
            # (edges parallel to the ray give 0 / 0: they do not straddle it)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                t = sa / (sa - sb)
                xx = a[:, :, 0] + t * (b[:, :, 0] - a[:, :, 0])
                yy = a[:, :, 1] + t * (b[:, :, 1] - a[:, :, 1])
                rho = cx * xx + sy * yy
            cross = ((sa > 0) != (sb > 0)) & slot[P] & (rho > 0)
            X = np.where(cross, rho, np.nan)
            # an odd count: the centre is inside, the first span starts at 0
            odd = (np.sum(cross, axis=1) % 2) == 1
            X = np.column_stack([np.where(odd, -np.inf, np.nan), X])
            pair, ring = _spans_to_cells(X, radii)
            _depth_test(z, cell_of(ring, k[pair]), g_ids[live[P[pair]]], D, best_t, best)
