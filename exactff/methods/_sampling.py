"""The shared sampling core of the discrete methods: cells as directions, a z-buffer.

Every discrete method (discrete PPBH, hemicube, cubic tetrahedron, single plane, polar
plane, Monte Carlo) is a *cell layout*: unit directions in the local frame of the
receiving point (z along its normal) and a delta form factor per cell. Visibility is the
same for all: for each cell direction, the nearest polygon along it (exact depth along
the direction). The row is the sum of the delta form factors per polygon.

The z-buffer is evaluated without a Python loop over cells: cell directions are sorted
into the five gnomonic charts of the engine (where polygon images are straight-edged),
bucketed on a uniform grid per chart; each polygon's image is clipped to the chart
(the engine's ``chart_clip``), its bounding box selects candidate cells bucket by
bucket, a vectorised crossing-number test over its edges keeps the cells inside it, and
the depth ``t = (n . (c - p)) / (n . d)`` picks the nearest polygon per cell. Depth
ties (the nearest hit point lies in several polygons' planes to rounding: coplanar
overlaps, zero-thickness walls) go by the engine's rule,
:func:`exactff.predicates.tie_priority`.
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..geometry import receiver_frame
from ..checks import as_receiver
from ..kernel import flat_polygons
from ..predicates import coplanar_pairs, plane_sides, polygon_coplanar_bands, tie_priority
from ..prepared import prepared
from ..rings import padded_buckets
from ..scene import as_scene
from ..visibility.charts import CHARTS, chart_clip, chart_planes
from ._base import FormFactorMethod
from ._zbuffer import ZBuffer, live_local, ray_charts, row_sums

__all__ = ["CellLayout", "SampledMethod", "ZBufferRow", "nearest_polygons", "zbuffer_of",
           "resolve_depths",
           "samples_to_resolution", "PAIR_CHUNK", "check_resolution", "resolution_from"]

#: candidate (polygon, cell) pairs examined at once; bounds the memory of a row
PAIR_CHUNK = 2_000_000




class CellLayout:
    """Cells of a discrete method in the local frame of the receiving point.

    Attributes
    ----------
    directions : ndarray of shape (C, 3)
        Cell directions (unit vectors, z >= 0 along the receiver normal).
    weights : ndarray of shape (C,)
        Delta form factor of each cell.
    covered : float
        Exact form factor of the region the cells cover (1 for the whole hemisphere).

    Parameters
    ----------
    directions, weights, covered
        As the attributes; the directions of any length (normalised here, ``D / |D|``).
    norms : ndarray of shape (C,), optional
        Given: the directions are normalised already (as here) and these are their
        norms as :attr:`direction_norms` computes them (Monte Carlo's compiled rays,
        ``exactff.methods._zbuffer.cosine_directions``); both taken as they are.
    """

    def __init__(self, directions, weights, covered, norms=None):
        D = np.asarray(directions, dtype=float)
        if norms is None:
            self.directions = D / np.linalg.norm(D, axis=1, keepdims=True)
        else:
            # directions normalised already (``D / |D|``, as above) and their norms
            # (as direction_norms computes them)
            self.directions = D
            self._norms = np.asarray(norms, dtype=float)
        self.weights = np.asarray(weights, dtype=float)
        self.covered = float(covered)

    def __len__(self):
        return len(self.weights)

    @property
    def direction_norms(self):
        """Norms of the directions (1 to rounding; cached), for the depth-tie slack."""
        if getattr(self, "_norms", None) is None:
            self._norms = np.linalg.norm(self.directions, axis=1)
        return self._norms

    @property
    def missed(self):
        """Form factor of the part of the hemisphere no cell covers."""
        return 1.0 - self.covered


def samples_to_resolution(samples, cells_per_resolution_squared, even=False, name="samples"):
    """Resolution r with about ``samples`` cells when a layout has ``c r^2`` cells."""
    if not (isinstance(samples, (int, np.integer)) and samples > 0):
        raise ValueError(f"{name} must be a positive integer, got {samples!r}")
    r = max(1, int(round(np.sqrt(samples / cells_per_resolution_squared))))
    if even:
        r = max(2, r + (r % 2))
    return r


def resolution_from(resolution, samples, cells_per_resolution_squared, even=False):
    """The resolution given, or the one with about ``samples`` cells (default 65,536)."""
    if resolution is None:
        resolution = samples_to_resolution(samples if samples is not None else 65536,
                                           cells_per_resolution_squared, even=even)
    return check_resolution(resolution, even=even)


def check_resolution(value, name="resolution", even=False):
    if not (isinstance(value, (int, np.integer)) and value > 0):
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    if even and value % 2:
        raise ValueError(f"{name} must be even, got {value!r}")
    return int(value)


#: the charts' axes as components of a direction (5, 3): e_u, e_v, e_w; and the sign
#: of e_w (5,)
_CHART_AXIS = np.array([[int(np.argmax(np.abs(e))) for e in ch[:3]] for ch in CHARTS])
_CHART_SIGN_W = np.array([ch[2][_CHART_AXIS[ci, 2]] for ci, ch in enumerate(CHARTS)])


def _chart_of(D):
    """Chart index and chart coordinates (u, v) of each direction.

    The charts' axes are coordinate axes (``e_w`` possibly negated), so ``D . e`` is
    one component of D, its sign set: u = (D . e_u) / (D . e_w) picks components
    (the values a matrix product with the axes gives, bit for bit)."""
    ax, ay, az = np.abs(D[:, 0]), np.abs(D[:, 1]), D[:, 2]
    top = az >= np.maximum(ax, ay)
    xside = ~top & (ax >= ay)
    chart = np.where(top, 0, np.where(xside, np.where(D[:, 0] > 0, 1, 2),
                                      np.where(D[:, 1] > 0, 3, 4)))
    axis, sign_w = _CHART_AXIS, _CHART_SIGN_W
    rows = np.arange(len(D))
    w = D[rows, axis[chart, 2]] * sign_w[chart]
    u = D[rows, axis[chart, 0]] / w
    v = D[rows, axis[chart, 1]] / w
    return chart, u, v


def _scene_bands(scene):
    """The near-coplanar band of each polygon's plane over the polygon (cached)."""
    return prepared(scene).get("coplanar_bands", lambda s: polygon_coplanar_bands(
        s.vertices, s.offsets, s.normals, s.plane_offsets))


def _polygon_buckets(scene):
    """The scene's polygons padded bucket by bucket of vertex counts (cached)."""
    return prepared(scene).get("padded_buckets", lambda s: padded_buckets(s.polygons))


class ZBufferRow:
    """What every z-buffer needs for one row: the live polygons (front or back facing,
    not edge-on, reaching above the horizon) in the local frame, bucket by bucket, and
    their depth-test data.

    Attributes
    ----------
    local : list of (ndarray of int, ndarray of shape (M, K, 3), ndarray of shape (M,))
        Live polygons (indices 0, 1, ... across the buckets), local vertices, counts.
    ids : ndarray of int
        Scene index of each live polygon.
    nl, dl : ndarray
        Local unit normals and ``n . (c - p)``: the depth along a direction d is
        ``dl / (nl . d)``.
    scene : Scene
        The scene (its planes decide the coplanar ties).
    side : ndarray of int
        Per scene polygon, the side of its plane the point is on (+1 in front, -1
        behind, 0 in its band: edge-on), as the row's receivers need it.
    band, prio : ndarray
        Depth-tie band (the near-coplanar band of each polygon's plane,
        :func:`exactff.predicates.polygon_coplanar_bands`, the BSP tree's, plus the
        rounding of ``n . c`` in the local frame) and priority
        (:func:`exactff.predicates.tie_priority`).

    Methods
    -------
    coplanar(i, j)
        Pair by pair (live indices): whether the polygons are coplanar by the BSP
        tree's rule (:func:`exactff.predicates.coplanar_pairs`): the depth buffer's
        ties, so that a face flush with another is a tie over the whole overlap or
        nowhere, as in the exact engine.
    """

    def __init__(self, scene, point, normal):
        p = np.asarray(point, dtype=float)
        flat = flat_polygons(scene)
        side, _ = plane_sides(flat, p, exact=False)  # in the band: edge-on, as the engine
        R = receiver_frame(normal)
        # bucket by bucket of vertex counts (one long polygon pads only its own bucket);
        # the live polygons get indices 0, 1, ... across the buckets
        local, ids = [], []
        start = 0
        for b_ids, Vb, cb in _polygon_buckets(scene):
            # not edge-on, a vertex above the horizon; the vertices in the local frame
            # (compiled: to_local's expression, bit for bit)
            live, V = live_local(Vb, cb, side[b_ids] != 0, p, R)
            if len(live):
                n_live = len(live)
                local.append((start + np.arange(n_live), V, cb[live]))
                ids.append(b_ids[live])
                start += n_live
        self.local = local
        self.ids = ids = np.concatenate(ids) if ids else np.zeros(0, dtype=int)
        self.nl = flat.normals[ids] @ R.T
        rel = flat.centroids[ids] - p
        self.dl = np.einsum("ij,ij->i", flat.normals[ids], rel)  # n . (c - p)
        # depth ties: a polygon ties with the nearest hit X when X lies in its plane
        # within the near-coplanar band of the input magnitudes (the BSP tree's, one
        # definition: exactff.predicates.coplanar_band), up to the rounding of
        # n . (X - c) in the local frame (ZBUFFER_ROUNDING_ULPS; the hit point's part
        # is added per cell, _ties)
        self.band = (_scene_bands(scene)[ids]
                     + tol.ZBUFFER_ROUNDING_ULPS * tol.EPS * np.linalg.norm(rel, axis=1))
        self.prio = tie_priority(side)[ids]
        self.scene = scene
        self.side = side

    def coplanar(self, i, j):
        """Whether live polygons ``i[k]`` and ``j[k]`` are coplanar (the BSP's rule)."""
        s = self.scene
        return coplanar_pairs(s.vertices, s.offsets, s.normals, s.plane_offsets,
                              self.ids[i], self.ids[j])

    def hits(self, best):
        """Scene indices of the polygons shown (-1: none) from live indices."""
        if len(self.ids) == 0:          # the point sees no polygon at all
            return np.full(np.shape(best), -1)
        return np.where(best >= 0, self.ids[np.maximum(best, 0)], -1)


def nearest_polygons(scene, point, normal, directions, *, backend="numpy", margin=None):
    """Index of the nearest polygon along each direction from ``point`` (-1 for none).

    Parameters
    ----------
    scene : Scene
    point : ndarray of shape (3,)
    normal : ndarray of shape (3,)
        Unit receiver normal.
    directions : ndarray of shape (C, 3)
        Directions in the local frame of the point (z along the normal), z > 0.
    backend : {"numpy", "compiled"}, default "numpy"
        "compiled": each chart's clipping, crossing numbers and depth buffer in C++
        (``exactff.methods._zbuffer``), the polygons clipped to the charts' exact
        frustums; bit for bit the numpy code with ``margin=0`` (images wider than
        ``LONG_POLYGON`` vertices go to the numpy code).
    margin : float, optional
        The charts' frustums widened by this much (default ``CHART_MARGIN`` for the
        numpy backend; the compiled one clips to the exact frustum, 0).

    Returns
    -------
    ndarray of shape (C,), int
        Polygons seen edge-on or wholly below the horizon are never returned.
    """
    if backend not in ("numpy", "compiled"):
        raise ValueError(f"backend must be 'numpy' or 'compiled', got {backend!r}")
    if margin is None:
        margin = tol.CHART_MARGIN if backend == "numpy" else 0.0
    elif backend == "compiled" and margin != 0.0:
        raise ValueError(f"the compiled backend clips to the exact frustum (margin 0), "
                         f"got margin={margin!r}")
    z = ZBufferRow(scene, point, normal)
    local, nl, dl, band, prio = z.local, z.nl, z.dl, z.band, z.prio
    D = np.ascontiguousarray(directions, dtype=float)
    if backend == "compiled" and len(z.ids):
        # the directions sorted into the charts and bucketed as _chart_of and
        # _cell_grid do (compiled, bit for bit), renumbered chart by chart and bucket
        # by bucket (the grid's order), so that the compiled depth buffer reads them in
        # the order it tests them; the depth test does not see the numbering
        Dp, norms, slot, charts = ray_charts(D, _CHART_AXIS, _CHART_SIGN_W, tol.CHART_MARGIN)
        best_t = np.full(len(D), np.inf)
        best = np.full(len(D), -1, dtype=np.int64)
        zb = zbuffer_of(z, Dp, norms)
        for ci, ids, cu, cv, nb, v_lo, order, starts in charts:
            ch = CHARTS[ci]
            planes = np.array(chart_planes(ch))
            grid = (nb, v_lo, order, starts)
            for g_ids, V, counts in local:
                if not zb.chart_rays(V, counts, g_ids, planes, *ch, ids, cu, cv, grid[0],
                                     grid[1], grid[2], grid[3], best_t, best, PAIR_CHUNK,
                                     tol.LONG_POLYGON):
                    live_c, UV, cl = chart_clip(V, counts, ch, margin=margin)
                    _zbuffer_chart(ids, cu, cv, grid, g_ids[live_c], UV, cl, Dp, nl, dl,
                                   band, prio, best_t, best, coplanar=z.coplanar)
        return z.hits(best[slot])
    chart, u, v = _chart_of(D)
    charts = []
    for ci, ch in enumerate(CHARTS):
        cells = np.flatnonzero(chart == ci)
        if len(cells):
            charts.append((ch, cells, _cell_grid(u[cells], v[cells], ch[3])))
    best_t = np.full(len(D), np.inf)
    best = np.full(len(D), -1, dtype=np.int64)
    for ch, cells, grid in charts:
        for g_ids, V, counts in local:
            live_c, UV, cl = chart_clip(V, counts, ch, margin=margin)
            if len(live_c) == 0:
                continue
            _zbuffer_chart(cells, u[cells], v[cells], grid, g_ids[live_c], UV, cl, D, nl,
                           dl, band, prio, best_t, best, coplanar=z.coplanar)
    return z.hits(best)


def zbuffer_of(z, D, norms):
    """The compiled z-buffer (``exactff.methods._zbuffer.ZBuffer``) of one row:
    directions ``D`` (C, 3) and their norms (numpy's, for the depth-tie slack), the
    live polygons' depth data of ``z`` (:class:`ZBufferRow`), the scene's planes for
    the coplanar rule."""
    s = z.scene
    return ZBuffer(D, norms, z.nl, z.dl, z.band, z.prio, s.vertices, s.offsets, s.normals,
                   s.plane_offsets, z.ids, tol.BSP_COPLANAR_ULPS,
                   tol.ZBUFFER_ROUNDING_ULPS + 1.0, tol.CLIP_MEET_ULPS, tol.CHART_EDGE_ULPS)


def _hit_rounding(t, D):
    """The rounding of a hit point ``t D`` in the depth-tie test (local frame)."""
    return tol.ZBUFFER_ROUNDING_ULPS * tol.EPS * np.abs(t) * np.linalg.norm(D, axis=1)


def _ties(src, cell, t_near, D, nl, dl, band):
    """Whether polygon ``src`` passes through the hit point ``t_near D[cell]``: the
    point lies in its plane within the near-coplanar band (``band``, the BSP tree's)
    and the rounding of the hit point."""
    X = t_near[:, None] * D[cell]
    r = np.einsum("ij,ij->i", nl[src], X) - dl[src]
    return np.abs(r) <= band[src] + _hit_rounding(t_near, D[cell])


def _cell_grid(cu, cv, side):
    """A chart's cells on an nb x nb grid of buckets, in CSR order: (nb, v_lo, order,
    starts)."""
    v_lo = -tol.CHART_MARGIN if side else -1.0 - tol.CHART_MARGIN
    nb = max(1, int(np.sqrt(len(cu) / 16.0)))
    bx = np.clip(((cu + 1.0) * 0.5 * nb).astype(int), 0, nb - 1)
    by = np.clip(((cv - v_lo) / (1.0 - v_lo) * nb).astype(int), 0, nb - 1)
    bucket = bx * nb + by
    # (a stable sort is unique; of small integers numpy sorts them by radix)
    order = np.argsort(bucket.astype(np.int16 if nb * nb < 2 ** 15 else np.int64),
                       kind="stable")
    starts = np.searchsorted(bucket[order], np.arange(nb * nb + 1))
    return nb, v_lo, order, starts


def _zbuffer_chart(cells, cu, cv, grid, live, UV, cl, D, nl, dl, band, prio, best_t, best,
                   coplanar=None):
    """Nearest polygon per cell within one chart (updates best_t / best in place).

    ``grid`` is the chart's :func:`_cell_grid`. ``best_t`` is the depth of the nearest
    hit; ``best`` the polygon shown there: of the polygons through the nearest hit point
    (depth ties), the one with the lowest ``prio``."""
    nb, v_lo, order, starts = grid
    lo = UV.min(axis=1)
    hi = UV.max(axis=1)
    bx0 = np.clip(((lo[:, 0] + 1.0) * 0.5 * nb).astype(int), 0, nb - 1)
    bx1 = np.clip(((hi[:, 0] + 1.0) * 0.5 * nb).astype(int), 0, nb - 1)
    by0 = np.clip(((lo[:, 1] - v_lo) / (1.0 - v_lo) * nb).astype(int), 0, nb - 1)
    by1 = np.clip(((hi[:, 1] - v_lo) / (1.0 - v_lo) * nb).astype(int), 0, nb - 1)
    nby = by1 - by0 + 1
    nbk = (bx1 - bx0 + 1) * nby
    # (polygon, bucket) pairs
    pb_poly = np.repeat(np.arange(len(live)), nbk)
    k = np.arange(len(pb_poly)) - np.repeat(np.cumsum(nbk) - nbk, nbk)
    b = (bx0[pb_poly] + k // nby[pb_poly]) * nb + by0[pb_poly] + k % nby[pb_poly]
    ncell = starts[b + 1] - starts[b]
    # process the (polygon, cell) pairs in chunks of about PAIR_CHUNK
    cum = np.cumsum(ncell)
    total = int(cum[-1]) if len(cum) else 0
    bounds = [0] + list(np.searchsorted(cum, np.arange(PAIR_CHUNK, total, PAIR_CHUNK),
                                        side="right")) + [len(b)]
    K = UV.shape[1]
    shapes = {}   # prepared images of long polygons
    for s0, s1 in zip(bounds[:-1], bounds[1:]):
        if s1 <= s0:
            continue
        nc = ncell[s0:s1]
        poly = np.repeat(pb_poly[s0:s1], nc)
        j = np.arange(nc.sum()) - np.repeat(np.cumsum(nc) - nc, nc)
        cell_local = order[np.repeat(starts[b[s0:s1]], nc) + j]
        # bounding-box rejection
        uu, vv = cu[cell_local], cv[cell_local]
        ok = (uu >= lo[poly, 0]) & (uu <= hi[poly, 0]) & (vv >= lo[poly, 1]) & (vv <= hi[poly, 1])
        poly, cell_local, uu, vv = poly[ok], cell_local[ok], uu[ok], vv[ok]
        if len(poly) == 0:
            continue
        if K > tol.LONG_POLYGON:
            # long polygons (a bucket of its own): a prepared point-in-polygon test per
            # polygon, boundary included (a cell on a shared edge then hits both, and
            # depth decides), instead of a loop over thousands of edges
            inside = np.zeros(len(poly), dtype=bool)
            for j in np.unique(poly):
                sel = np.flatnonzero(poly == j)
                g = shapes.get(j)
                if g is None:
                    g = shapes[j] = shapely.polygons(UV[j, :cl[j]])
                    shapely.prepare(g)
                inside[sel] = shapely.intersects_xy(g, uu[sel], vv[sel])
            poly, cell_local = poly[inside], cell_local[inside]
            K_loop = 0
        else:
            K_loop = K
        # crossing number over the polygon's edges (padding repeats the last vertex)
        inside = np.zeros(len(poly), dtype=bool) if K_loop else np.ones(len(poly), dtype=bool)
        P = UV[poly] if K_loop else None
        for e in range(K_loop):
            a = P[:, e]
            c = P[:, (e + 1) % K]
            straddles = (a[:, 1] > vv) != (c[:, 1] > vv)
            # from the lower end point, whichever way the edge runs: an edge shared by
            # two polygons gives the same crossing in both, so a cell on it is inside
            # exactly one of them (the half-open rule), never in neither
            swap = (a[:, 1] > c[:, 1])[:, None]
            a, c = np.where(swap, c, a), np.where(swap, a, c)
            with np.errstate(divide="ignore", invalid="ignore"):
                ux = a[:, 0] + (vv - a[:, 1]) * (c[:, 0] - a[:, 0]) / (c[:, 1] - a[:, 1])
            inside ^= straddles & (uu < ux)
        poly, cell_local = poly[inside], cell_local[inside]
        resolve_depths(cells[cell_local], live[poly], D, nl, dl, band, prio, best_t, best,
                       coplanar=coplanar)


def resolve_depths(cell, src, D, nl, dl, band, prio, best_t, best, coplanar=None):
    """The depth buffer: merge candidate (cell, polygon) pairs into ``best_t`` (depth of
    the nearest hit per cell) and ``best`` (the polygon shown), in place.

    The depth along a cell's direction ``D[cell]`` (any length) is
    ``t = (n . (c - p)) / (n . D)``; of the polygons tied with the nearest hit, the one
    of lowest ``prio``. A polygon ties with the nearest one when ``coplanar(nearest,
    polygon)`` (:meth:`ZBufferRow.coplanar`: the BSP tree's rule, pair by pair) and
    it is within four times ``band`` of its depth; without ``coplanar``, when the
    nearest hit point lies in its plane within ``band`` (point by point)."""
    if len(cell) == 0:
        return
    den = np.einsum("ij,ij->i", nl[src], D[cell])
    # a ray along its polygon's plane (a polygon through the point to rounding, whose
    # image a rasteriser may still reach) hits nothing
    with np.errstate(divide="ignore", invalid="ignore"):
        t = dl[src] / den
    ok = np.isfinite(t)
    if not ok.all():
        cell, src, t, den = cell[ok], src[ok], t[ok], den[ok]
        if len(cell) == 0:
            return
    # the nearest depth per cell (a scatter-min over the whole buffer, linear in the
    # pairs), then of the polygons tied with it (the hit point in their planes) the one
    # of lowest priority (priorities are distinct per polygon)
    n_cells = len(best_t)
    t_min = np.full(n_cells, np.inf)
    np.minimum.at(t_min, cell, t)
    t_near = t_min[cell]
    tied = t == t_near
    # the tie test only where it can pass: n . (t_near d) - n . c = (t_near - t) (n . d)
    # up to rounding, within four times the test's own band
    # (_hit_rounding and one more ulp of the hit point, with one norm of the directions)
    slack = 4.0 * (band[src] + tol.EPS * (
        (tol.ZBUFFER_ROUNDING_ULPS + 1.0) * np.abs(t_near) * np.linalg.norm(D[cell], axis=1)
        + np.abs(dl[src])))
    k = np.flatnonzero(~tied & (np.abs(t_near - t) * np.abs(den) <= slack))
    if coplanar is None:
        tied[k] = _ties(src[k], cell[k], t_near[k], D, nl, dl, band)
    elif len(k):
        near = np.full(n_cells, -1)
        f = np.flatnonzero(tied)
        near[cell[f]] = src[f]          # one of the polygons at the nearest depth
        tied[k] = coplanar(near[cell[k]], src[k])
    p_min = np.full(n_cells, np.iinfo(np.int64).max)
    np.minimum.at(p_min, cell[tied], prio[src[tied]])
    chosen = np.flatnonzero(tied & (prio[src] == p_min[cell]))
    pick = np.full(n_cells, -1)
    pick[cell[chosen]] = src[chosen]
    cell = np.flatnonzero(pick >= 0)
    t, src = t_min[cell], pick[cell]
    # merge with the cells' best so far (other chunks): the nearer wins unless the
    # other passes through its hit point with a lower priority
    old = best[cell]
    has_old = old >= 0
    old_s = np.maximum(old, 0)
    new_nearer = t < best_t[cell]
    old_ties = np.zeros(len(cell), dtype=bool)
    new_ties = np.zeros(len(cell), dtype=bool)
    k = np.flatnonzero(has_old & new_nearer)
    if coplanar is None:
        old_ties[k] = _ties(old_s[k], cell[k], t[k], D, nl, dl, band)
    else:
        old_ties[k] = coplanar(old_s[k], src[k])
    k = np.flatnonzero(has_old & ~new_nearer)
    if coplanar is None:
        new_ties[k] = _ties(src[k], cell[k], best_t[cell[k]], D, nl, dl, band)
    else:
        new_ties[k] = coplanar(src[k], old_s[k])
    take = np.where(new_nearer, ~old_ties | (prio[src] < prio[old_s]),
                    ~has_old | (new_ties & (prio[src] < prio[old_s])))
    best_t[cell] = np.minimum(best_t[cell], t)
    best[cell[take]] = src[take]


class SampledMethod(FormFactorMethod):
    """A discrete method defined by its cell layout (built once per instance)."""

    #: the backend of the shared core (:func:`nearest_polygons`) for the method's rows
    #: when it does not rasterise natively: numpy, the oracle of the native z-buffers
    rays_backend = "numpy"

    def layout(self):
        """The method's :class:`CellLayout` in the local frame (cached)."""
        if getattr(self, "_layout", None) is None:
            self._layout = self.build_layout()
        return self._layout

    def build_layout(self):
        raise NotImplementedError

    @property
    def samples(self):
        """Number of cells (or rays)."""
        return len(self.layout())

    def native_hits(self, scene, point, normal):
        """The polygon shown in each cell by the method's own rasterisation (methods
        with ``native=True``); the shared core is the oracle it is tested against."""
        z, best = self.native_buffer(scene, point, normal)
        return z.hits(best)

    def native_buffer(self, scene, point, normal):
        """The row's :class:`ZBufferRow` and the live polygon shown in each cell (-1:
        none), by the method's own rasterisation."""
        raise NotImplementedError

    def directions_for(self, point):
        """Cell directions and weights for a row (fixed per instance by default)."""
        L = self.layout()
        return L.directions, L.weights

    def point_form_factors(self, scene, point, normal, *, two_sided=False, stats=None):
        as_scene(scene)
        point, normal = as_receiver(point, normal)
        D, w = self.directions_for(point)
        if getattr(self, "native", False) and getattr(self, "backend", None) == "compiled":
            # the weights' sum per polygon shown and receiving in C++ (np.bincount's
            # sums, in the same order)
            z, best = self.native_buffer(scene, point, normal)
            receives = z.side > 0
            if two_sided:
                receives |= z.side < 0
            F, hit = row_sums(best, z.ids, receives, w, len(scene))
            if stats is not None:
                stats["cells"] = len(w)
                stats["cells_hit"] = hit
            return F
        if getattr(self, "native", False):
            hit = self.native_hits(scene, point, normal)
        else:
            hit = nearest_polygons(scene, point, normal, D, backend=self.rays_backend)
        flat = flat_polygons(scene)
        side, _ = plane_sides(flat, np.asarray(point, dtype=float), exact=False)
        receives = side > 0
        if two_sided:
            receives |= side < 0
        ok = hit >= 0
        ok[ok] = receives[hit[ok]]
        if stats is not None:
            stats["cells"] = len(w)
            stats["cells_hit"] = int((hit >= 0).sum())
        return np.bincount(hit[ok], weights=w[ok], minlength=len(scene))
