"""Area-sorting clipper in projected space: gnomonic charts, covered regions, pieces.

The upper hemisphere of the receiver is covered by five charts, the faces of the
hemicube frustum. In a chart the central projection maps every great-circle arc to a
straight segment, so straight-line clipping in the chart (shapely, full double
precision) gives the exact topology of the visible graph; each boundary segment of a
visible piece is the image of an exact great-circle arc, which the sector form
integrates exactly.
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..integrate import TWO_PI

__all__ = ["CHARTS", "clip_halfspace", "chart_clip", "chart_polygons", "visible_pieces",
           "pieces_form_factors", "TiledRegion", "tiles_per_side"]

_X, _Y, _Z = np.eye(3)

#: Charts as (e_u, e_v, e_w, side): a direction d maps to (e_u.d / e_w.d, e_v.d / e_w.d);
#: the chart is |u| <= 1 and |v| <= 1 (top), or |u| <= 1 and 0 <= v <= 1 (sides, v = z).
CHARTS = (
    (_X, _Y, _Z, False),
    (_Y, _Z, _X, True),
    (_Y, _Z, -_X, True),
    (_X, _Z, _Y, True),
    (_X, _Z, -_Y, True),
)


def _chart_planes(chart, margin=0.0):
    """Inward normals of the half-spaces (through the origin) bounding a chart's frustum,
    widened by ``margin`` in chart units (0: the exact frustum)."""
    eu, ev, ew, side = chart
    g = 1.0 + margin
    return [g * ew - eu, g * ew + eu, g * ew - ev, ev + margin * ew if side else g * ew + ev]


def chart_area(chart):
    return 2.0 if chart[3] else 4.0


def clip_halfspace(V, counts, h):
    """Clip a batch of polygons to the half-space ``h . x > 0`` (points on it kept).

    Parameters
    ----------
    V : ndarray of shape (M, K, 3)
        Padded vertices; polygon m uses ``V[m, :counts[m]]``.
    counts : ndarray of shape (M,)
    h : ndarray of shape (3,)

    Returns
    -------
    (ndarray of shape (M, K', 3), ndarray of shape (M,))
        The clipped polygons, padded; a count below 3 means nothing is left.
    """
    M, K, _ = V.shape
    slot = np.arange(K)
    valid = slot[None, :] < counts[:, None]
    nxt = (slot[None, :] + 1) % np.maximum(counts[:, None], 1)
    W = np.take_along_axis(V, nxt[:, :, None], axis=1)
    s = V @ h
    sn = np.take_along_axis(s, nxt, axis=1)
    inside = (s > 0) & valid
    inside_n = (sn > 0) & valid
    cross = (inside != inside_n) & valid
    # crossing point computed from the inside end point, whichever way the edge runs:
    # an edge shared by two polygons gets bit-identical clip points in both (GEOS then
    # sees exactly shared vertices instead of rounding-thin slivers)
    A = np.where(inside[:, :, None], V, W)
    B = np.where(inside[:, :, None], W, V)
    sa = np.where(inside, s, sn)
    sb = np.where(inside, sn, s)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(cross, sa / (sa - sb), 0.0)
    X = A + t[:, :, None] * (B - A)
    out = np.empty((M, 2 * K, 3))
    out[:, 0::2] = V
    out[:, 1::2] = X
    keep = np.empty((M, 2 * K), dtype=bool)
    keep[:, 0::2] = inside
    keep[:, 1::2] = cross
    new_counts = keep.sum(axis=1)
    Kn = max(int(new_counts.max(initial=0)), 1)
    order = np.argsort(~keep, axis=1, kind="stable")[:, :Kn]
    return np.take_along_axis(out, order[:, :, None], axis=1), new_counts


def chart_clip(V, counts, chart, margin=0.0):
    """Clip polygons (local frame) to a chart's frustum; project them into the chart.

    Parameters
    ----------
    V : ndarray of shape (M, K, 3)
        Padded polygons in the local frame of the point.
    counts : ndarray of shape (M,)
    chart : one of CHARTS
    margin : float, default 0
        Widen the frustum by this much in chart units. The exact engine needs the exact
        frustum (its pieces tile the hemisphere); the sampling z-buffer widens it a little
        so that a cell on a chart's edge is strictly inside the images that cover it.

    Returns
    -------
    live : ndarray of int
        Indices (into V) of the polygons that reach the chart.
    UV : ndarray of shape (len(live), K', 2)
        Their chart coordinates, padded by repeating the last vertex.
    cl : ndarray of shape (len(live),)
        Vertex counts.
    """
    planes = np.array(_chart_planes(chart, margin))
    slot = np.arange(V.shape[1])[None, :] < counts[:, None]
    S = V @ planes.T  # (M, K, 4); with margin 0, differences of two coordinates: exact signs
    outside = np.any(np.all((S <= 0) | ~slot[:, :, None], axis=1), axis=1)
    inside = np.all((S > 0) | ~slot[:, :, None], axis=(1, 2))
    # only fragments that straddle a frustum plane need clipping
    reach = np.flatnonzero(~outside & (counts >= 3))
    straddle = reach[~inside[reach]]
    Vc, cc = V[straddle], counts[straddle]
    for h in planes:
        if not np.any(cc >= 3):
            break
        Vc, cc = clip_halfspace(Vc, np.where(cc >= 3, cc, 0), h)
    K = max(V.shape[1], Vc.shape[1])
    Vr = np.zeros((len(reach), K, 3))
    cr = counts[reach].copy()
    pos = np.searchsorted(reach, straddle)
    whole = np.flatnonzero(inside[reach])
    Vr[whole, : V.shape[1]] = V[reach[whole]]
    Vr[pos, : Vc.shape[1]] = Vc
    cr[pos] = cc
    live_r = np.flatnonzero(cr >= 3)
    live = reach[live_r]
    Vl, cl = Vr[live_r], cr[live_r]
    eu, ev, ew, _ = chart
    K = Vl.shape[1]
    # pad by repeating each polygon's last vertex (zero-length closing edges)
    last = np.take_along_axis(Vl, np.maximum(cl - 1, 0)[:, None, None].repeat(3, axis=2), axis=1)
    mask = np.arange(K)[None, :] < cl[:, None]
    Vl = np.where(mask[:, :, None], Vl, last)
    w = Vl @ ew
    UV = np.stack([(Vl @ eu) / w, (Vl @ ev) / w], axis=-1)
    # flush subnormal chart coordinates to zero: GEOS mishandles them (a wrong overlay
    # was seen with a receiver normal of component 5e-324), and they move an image by
    # less than 2.2e-308
    UV[np.abs(UV) < np.finfo(float).tiny] = 0.0
    return live, UV, cl


def chart_polygons(V, counts, chart):
    """Clip polygons (local frame) to a chart's frustum and project them into the chart.

    Returns
    -------
    (ndarray of int, ndarray of shapely.Polygon, ndarray of shape (M', 4))
        Indices (into V) of the polygons that reach the chart, their images, and
        their bounds.
    """
    live, UV, cl = chart_clip(V, counts, chart)
    if len(live) == 0:
        return live, np.empty(0, object), np.zeros((0, 4))
    mask = np.arange(UV.shape[1])[None, :] < cl[:, None]
    coords = UV[mask]
    ring_index = np.repeat(np.arange(len(live)), cl)
    rings = shapely.linearrings(coords, indices=ring_index)
    polys = shapely.polygons(rings)
    bad = ~shapely.is_valid(polys)
    if bad.any():
        # rounding-thin slivers or self-touching images: repair, keep only areas
        fixed = []
        for g in shapely.make_valid(polys[bad]):
            parts = shapely.get_parts(g)
            fixed.append(shapely.union_all(parts[shapely.get_type_id(parts) >= 3]))
        polys[bad] = fixed
    return live, polys, shapely.bounds(polys)


def _repair(geom):
    """Repair a region with union semantics (overlapping or nested shells are merged, not
    turned into holes): GEOS's ``make_valid`` with the "structure" method, or the union
    of the parts on shapely < 2.1."""
    try:
        return shapely.make_valid(geom, method="structure")
    except TypeError:
        return shapely.union_all(shapely.get_parts(geom))


def _cut(g, covered, stats, disjoint=False):
    """The visible part of image ``g`` behind ``covered``, and the grown covered region.

    Checked by area conservation, ``area(covered | g) = area(covered) + area(g - covered)``
    to rounding: GEOS's floating-point overlay has been seen to return a wrong
    difference, or a union with nested shells, on near-degenerate input without raising.
    When the check fails, both are recomputed with snap-rounding on a grid of 2**-50
    chart units (vertices move by less than 1e-15); recomputations count in
    ``stats["overlay_repairs"]``. The check runs when nothing is visible too: GEOS has
    been seen to return an empty difference for an image that shares one edge with the
    covered region and lies outside it (its union then had the area of both).
    ``disjoint``: the bounds do not overlap, so the difference is ``g`` itself.
    """
    vis = g if disjoint else _overlay(shapely.difference, g, covered, stats)
    grown = _overlay(shapely.union, covered, g, stats)
    a_cov, a_vis, a_new = covered.area, vis.area, grown.area
    if abs(a_new - a_cov - a_vis) > tol.AREA_CONSERVATION_RTOL * (a_cov + g.area) + 1e-300 or not (
            shapely.get_type_id(grown) != 6 or shapely.is_valid(grown)):
        stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
        cs, gs = _snap(covered), _snap(g)
        vis = _polygonal(shapely.difference(gs, cs, grid_size=tol.OVERLAY_SNAP_GRID))
        grown = _polygonal(shapely.union(cs, gs, grid_size=tol.OVERLAY_SNAP_GRID))
        if not shapely.is_valid(grown):
            grown = _repair(grown)
    if vis.is_empty or vis.area == 0.0:
        return vis, covered  # nothing new: keep the region as it was
    return vis, _fill_cracks(grown)


def _fill_cracks(region):
    """The covered region without its rounding cracks: holes thinner (twice their area
    over their perimeter) than the snap-rounding grid ``OVERLAY_SNAP_GRID``, which
    snap-rounding would collapse too. Abutting images leave such cracks where their
    shared edges differ in the last bits, and GEOS has been seen to get a later overlay
    wholly wrong next to one: an image inside the region, crossed by a hole of area
    4e-21, came back as visible from both the difference and the union (so area
    conservation held)."""
    kind = shapely.get_type_id(region)
    if kind not in (3, 6) or (kind == 3 and shapely.get_num_interior_rings(region) == 0):
        return region
    parts = shapely.get_parts(region)
    if not np.any(shapely.get_num_interior_rings(parts)):
        return region
    out = []
    for P in parts:
        holes = P.interiors
        if len(holes) == 0:
            out.append(P)
            continue
        rings = np.array([shapely.Polygon(h) for h in holes])
        width = 2.0 * shapely.area(rings) / shapely.length(rings)
        keep = [h for h, w in zip(holes, width) if w >= tol.OVERLAY_SNAP_GRID]
        out.append(P if len(keep) == len(holes) else shapely.Polygon(P.exterior, keep))
    return out[0] if len(out) == 1 else shapely.MultiPolygon(out)


def _polygonal(geom):
    """The areal part of a geometry (snapping can collapse slivers to lines or points)."""
    if shapely.get_type_id(geom) in (3, 6):
        return geom
    parts = shapely.get_parts(geom)
    return shapely.union_all(parts[np.isin(shapely.get_type_id(parts), (3, 6))])


def _snap(geom):
    return _polygonal(shapely.set_precision(geom, tol.OVERLAY_SNAP_GRID))


def _overlay(op, a, b, stats):
    """A shapely overlay with a fallback for GEOS's robustness failures.

    GEOS can throw (``TopologyException``) on near-degenerate input, typically after an
    earlier overlay returned a region with nested shells. The operands are then repaired
    with union semantics (:func:`_repair`) and, failing that, snapped to a grid of
    2**-50 chart units, which moves vertices by less than 1e-15. Repairs are counted in
    ``stats["overlay_repairs"]``.
    """
    try:
        return op(a, b)
    except shapely.errors.GEOSException:
        stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
    a, b = _repair(a), _repair(b)
    try:
        return op(a, b)
    except shapely.errors.GEOSException:
        return _polygonal(op(_snap(a), _snap(b), grid_size=tol.OVERLAY_SNAP_GRID))


def _chart_rect(chart):
    """The chart's square in chart units: (u0, v0, u1, v1)."""
    return (-1.0, 0.0, 1.0, 1.0) if chart[3] else (-1.0, -1.0, 1.0, 1.0)


def tiles_per_side(fragments):
    """Tiles per side of a chart's grid for this many fragment images: about
    ``TILE_FRAGMENTS`` images per tile, between 1 and ``MAX_TILES``."""
    return int(min(tol.MAX_TILES, max(1, round(np.sqrt(fragments / tol.TILE_FRAGMENTS)))))


class TiledRegion:
    """The covered region of one chart, kept as a grid of tiles with a region each.

    A single covered region grows with everything visible, and every overlay with it
    costs in proportion (DESIGN 3, measured: 26 s for 4,000 quads with one region, 0.67 s
    with 16 x 16 tiles). Here a fragment's image is cut into the tiles it overlaps
    (``clip_by_rect``, checked by area conservation), and each part is differenced
    with and unioned into its own tile's small region. Parts in an empty tile are
    visible whole (no overlay); a fragment whose tiles are all full is hidden without
    any geometry (a tile is full when its uncovered area is below ``COVERED_RTOL`` of
    the tile). Tile seams are straight lines of the chart, hence great-circle arcs: the
    parts of a visible piece are closed regions that the integration adds up.

    Parameters
    ----------
    chart : one of CHARTS
    n : int
        Tiles per side.
    """

    def __init__(self, chart, n):
        self.n = n
        u0, v0, u1, v1 = _chart_rect(chart)
        self.u = np.linspace(u0, u1, n + 1)
        self.v = np.linspace(v0, v1, n + 1)
        self.u[-1], self.v[-1] = u1, v1
        self.scale = (n / (u1 - u0), n / (v1 - v0))
        self.origin = (u0, v0)
        self.full_area = (u1 - u0) * (v1 - v0) / n**2 * (1.0 - tol.COVERED_RTOL)
        self.geoms = [None] * (n * n)
        self.bounds = np.zeros((n * n, 4))
        self.full = np.zeros(n * n, dtype=bool)
        self.n_full = 0

    def is_full(self):
        return self.n_full == self.n * self.n

    def _range(self, b):
        n = self.n
        ix0 = min(max(int((b[0] - self.origin[0]) * self.scale[0]), 0), n - 1)
        ix1 = min(max(int((b[2] - self.origin[0]) * self.scale[0]), 0), n - 1)
        iy0 = min(max(int((b[1] - self.origin[1]) * self.scale[1]), 0), n - 1)
        iy1 = min(max(int((b[3] - self.origin[1]) * self.scale[1]), 0), n - 1)
        return ix0, ix1, iy0, iy1

    def hidden(self, b):
        """True when every tile that bounds ``b`` overlap is full."""
        ix0, ix1, iy0, iy1 = self._range(b)
        n = self.n
        return all(self.full[ix * n + iy] for ix in range(ix0, ix1 + 1)
                   for iy in range(iy0, iy1 + 1))

    def _parts(self, g, b, stats):
        """(tile, part of g in the tile) for the tiles g's bounds overlap."""
        ix0, ix1, iy0, iy1 = self._range(b)
        n = self.n
        if ix0 == ix1 and iy0 == iy1:
            return [(ix0 * n + iy0, g)]
        tiles = [ix * n + iy for ix in range(ix0, ix1 + 1) for iy in range(iy0, iy1 + 1)]
        # clip_by_rect is fast but not guaranteed (it may raise, or return invalid
        # output): the parts must be valid and tile g, else the robust overlay
        try:
            parts = [_polygonal(shapely.clip_by_rect(g, self.u[t // n], self.v[t % n],
                                                     self.u[t // n + 1], self.v[t % n + 1]))
                     for t in tiles]
            areas = shapely.area(parts)
            ok = (abs(areas.sum() - g.area) <= tol.AREA_CONSERVATION_RTOL * g.area
                  and np.all(shapely.is_valid(parts)))
        except shapely.errors.GEOSException:
            ok = False
        if not ok:
            stats["clip_repairs"] = stats.get("clip_repairs", 0) + 1
            t = np.array(tiles)
            boxes = shapely.box(self.u[t // n], self.v[t % n], self.u[t // n + 1],
                                self.v[t % n + 1])
            parts = [_polygonal(_overlay(shapely.intersection, g, box, stats)) for box in boxes]
            areas = shapely.area(parts)
        return [(t, q) for t, q, a in zip(tiles, parts, areas) if a > 0.0]

    def cut(self, g, b, stats, shortcuts=True):
        """The visible parts of image ``g`` (bounds ``b``) behind the covered region,
        which grows by ``g``. Returns a list of geometries (possibly empty)."""
        out = []
        for t, q in self._parts(g, b, stats):
            if self.full[t]:
                continue
            cov = self.geoms[t]
            qb = q.bounds if q is not g else b
            if cov is None:
                stats["tile_accepts"] += 1
                vis, grown, cb = q, q, qb
            else:
                cb = self.bounds[t]
                disjoint = shortcuts and (qb[0] >= cb[2] or qb[2] <= cb[0] or qb[1] >= cb[3]
                                          or qb[3] <= cb[1])
                stats["bbox_rejections" if disjoint else "differences"] += 1
                vis, grown = _cut(q, cov, stats, disjoint)
                cb = (min(cb[0], qb[0]), min(cb[1], qb[1]), max(cb[2], qb[2]), max(cb[3], qb[3]))
            self.geoms[t] = grown
            self.bounds[t] = cb
            if shortcuts and grown.area >= self.full_area:
                self.full[t] = True
                self.n_full += 1
            if not vis.is_empty and vis.area > 0.0:
                out.append(vis)
        return out


def visible_pieces(order_V, order_counts, receives, stats=None, shortcuts=True):
    """Visible pieces of polygons given front to back, per chart.

    Parameters
    ----------
    order_V : ndarray of shape (M, K, 3)
        Fragments in front-to-back order, in the local frame of the point.
    order_counts : ndarray of shape (M,)
    receives : ndarray of shape (M,), bool
        Whether each fragment's visible part is wanted (it occludes either way).
    shortcuts : bool, default True
        Keep the covered region of each chart as tiles (:class:`TiledRegion`): reject a
        fragment whose tiles are all full without geometry, accept parts in empty
        tiles without an overlay, skip the difference where bounds miss, and stop
        filling a chart once every tile is full. False keeps one region per chart and
        overlays every fragment with it (the baseline the shortcuts are tested against).
    stats : dict, optional
        Filled with counters: ``chart_fragments``, ``differences`` (overlays),
        ``bbox_rejections``, ``tile_accepts`` (parts visible whole in empty tiles),
        ``tile_rejections`` (fragments hidden by full tiles, no overlay), ``hidden``
        (fragments with nothing visible), ``charts_full``, ``skipped_after_full``,
        ``overlay_repairs``.

    Returns
    -------
    list of (int, int, shapely geometry)
        ``(fragment index, chart index, visible part)`` for receiving fragments; a
        fragment may have several parts in one chart (one per tile).
    """
    out = []
    st = stats if stats is not None else {}
    for key in ("chart_fragments", "differences", "bbox_rejections", "tile_accepts",
                "tile_rejections", "hidden", "charts_full", "skipped_after_full",
                "overlay_repairs"):
        st.setdefault(key, 0)
    for ci, chart in enumerate(CHARTS):
        idx, polys, bounds = chart_polygons(order_V, order_counts, chart)
        st["chart_fragments"] += len(idx)
        if shortcuts:
            _tiled_chart(ci, chart, idx, polys, bounds, receives, st, out)
        else:
            _single_region_chart(ci, idx, polys, receives, st, out)
    return out


def _tiled_chart(ci, chart, idx, polys, bounds, receives, st, out):
    region = TiledRegion(chart, tiles_per_side(len(idx)))
    for j in range(len(idx)):
        g = polys[j]
        if g.is_empty:
            continue
        if region.hidden(bounds[j]):
            st["tile_rejections"] += 1
            st["hidden"] += 1
            continue
        vis = region.cut(g, bounds[j], st)
        if not vis:
            st["hidden"] += 1
        elif receives[idx[j]]:
            out.extend((int(idx[j]), ci, v) for v in vis)
        # early stop: once every tile is full, nothing behind can be seen in this chart
        if region.is_full():
            st["charts_full"] += 1
            st["skipped_after_full"] += len(idx) - j - 1
            break


def _single_region_chart(ci, idx, polys, receives, st, out):
    covered = None
    for j in range(len(idx)):
        g = polys[j]
        if g.is_empty:
            continue
        if covered is None:
            vis, covered = g, g
        else:
            st["differences"] += 1
            vis, covered = _cut(g, covered, st)
            if vis.is_empty or vis.area == 0.0:
                st["hidden"] += 1
                continue
        if receives[idx[j]]:
            out.append((int(idx[j]), ci, vis))


def _lift(coords, chart):
    """Chart coordinates (u, v) back to directions ``u e_u + v e_v + e_w``."""
    eu, ev, ew, _ = chart
    return coords[:, :1] * eu + coords[:, 1:2] * ev + ew


def _rings_long_double(D, start, count):
    """Absolute image areas / pi (form factors) of closed rings of directions, and their
    error estimates, in long double arithmetic."""
    from ..integrate import _C1, _LONGDOUBLE_EPS as u, _clipped_sector_sums

    owner = np.repeat(np.arange(len(start)), count)
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    idx = start[owner] + np.arange(len(owner)) - first[owner]
    nxt = np.arange(len(owner)) + 1
    nxt[first + count - 1] = first
    Dl = D[idx].astype(np.longdouble)
    A0 = Dl[first]
    S, mags, errs = _clipped_sector_sums(A0, Dl - A0[owner], nxt, owner, len(start), eps=u)
    val = (np.abs(S) / (2 * np.pi)).astype(float)
    return val, ((_C1 * u * mags + errs) / (2 * np.pi)).astype(float)


def pieces_form_factors(pieces, m, tolerance=None, owner=None):
    """Form factors of visible pieces, summed per fragment, with error estimates.

    Every ring of a piece is a closed chain of great-circle arcs (its chart coordinates
    lifted to directions ``u e_u + v e_v + e_w``, exactly). Its sector sum, evaluated in
    offset form by the kernel's own ``_clipped_sector_sums`` (an edge on the horizon
    becomes its horizon arc), is twice the signed area of its image on the base disk.
    Exterior rings add and holes subtract the absolute values, so the result does not
    depend on ring orientation.

    With a ``tolerance``: where the summed estimate of a polygon (fragments grouped by
    ``owner``, default one group per fragment) exceeds ``tolerance`` times its value,
    its pieces that carry a share of that error are re-evaluated with mpmath from their
    (float, exact) lifted coordinates.

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,))
        Form factors and error estimates per fragment.
    """
    from .. import _tolerances as tol
    from ..integrate import _C1, _LONGDOUBLE_EPS, _clipped_sector_sums, mp_form_factor

    F = np.zeros(m)
    err = np.zeros(m)
    if not pieces:
        return F, err
    vals, errs_, frags, ring_sets = [], [], [], []
    for ci, chart in enumerate(CHARTS):
        sel = [(k, g) for k, c, g in pieces if c == ci]
        if not sel:
            continue
        frag = np.array([k for k, _ in sel])
        geoms = np.array([g for _, g in sel], dtype=object)
        parts, part_of = shapely.get_parts(geoms, return_index=True)
        polys = parts[shapely.get_type_id(parts) == 3]
        poly_of = part_of[shapely.get_type_id(parts) == 3]
        if len(polys) == 0:
            continue
        # rings of each polygon: the exterior first, then its holes
        rings, ring_poly = shapely.get_rings(polys, return_index=True)
        is_hole = np.ones(len(rings), dtype=bool)
        n_rings = shapely.get_num_interior_rings(polys) + 1
        is_hole[np.concatenate([[0], np.cumsum(n_rings)[:-1]])] = False
        coords, ring_of = shapely.get_coordinates(rings, return_index=True)
        # drop each ring's closing point; offsets from its first point
        last = np.ones(len(ring_of), dtype=bool)
        last[:-1] = ring_of[1:] != ring_of[:-1]
        coords, ring_of = coords[~last], ring_of[~last]
        D = _lift(coords, chart)
        start = np.searchsorted(ring_of, np.arange(len(rings)))
        count = np.diff(np.append(start, len(ring_of)))
        nxt = np.arange(len(ring_of)) + 1
        nxt[start + count - 1] = start
        A0 = D[start]
        S, mags, errs = _clipped_sector_sums(A0, D - A0[ring_of], nxt, ring_of, len(rings))
        val = np.abs(S) / TWO_PI
        e_ring = (_C1 * tol.EPS * mags + errs) / TWO_PI
        geom_of_ring = poly_of[ring_poly]
        vals.append(np.bincount(geom_of_ring, weights=np.where(is_hole, -val, val),
                                minlength=len(geoms)))
        errs_.append(np.bincount(geom_of_ring, weights=e_ring, minlength=len(geoms)))
        frags.append(frag)
        ring_sets.append((D, start, count, is_hole, geom_of_ring))
    if not vals:
        return F, err
    if tolerance is not None:
        group = np.arange(m) if owner is None else np.asarray(owner)
        Fg = np.zeros(group.max() + 1)
        Eg = np.zeros(group.max() + 1)
        for v, e, fr in zip(vals, errs_, frags):
            np.add.at(Fg, group[fr], v)
            np.add.at(Eg, group[fr], e)
        for v, e, fr, (D, start, count, is_hole, geom_of_ring) in zip(vals, errs_, frags,
                                                                      ring_sets):
            g_of = group[fr]
            # escalate the pieces of polygons that miss the tolerance, where the piece
            # carries at least a tenth of the allowed error
            bad = np.flatnonzero((Eg[g_of] > tolerance * Fg[g_of])
                                 & (e > 0.1 * tolerance * Fg[g_of]))
            if len(bad) == 0:
                continue
            # second tier: the flagged pieces' rings in long double, all at once
            rsel = np.flatnonzero(np.isin(geom_of_ring, bad))
            if _LONGDOUBLE_EPS < tol.EPS / 100:
                rv, re = _rings_long_double(D, start[rsel], count[rsel])
                signed = np.where(is_hole[rsel], -rv, rv)
                gv = np.zeros(len(v))
                ge = np.zeros(len(v))
                np.add.at(gv, geom_of_ring[rsel], signed)
                np.add.at(ge, geom_of_ring[rsel], re)
                good = bad[ge[bad] <= 0.1 * tolerance * Fg[g_of[bad]]]
                v[good], e[good] = gv[good], ge[good]
                bad = np.setdiff1d(bad, good)
            # last tier: mpmath, ring by ring
            for g in bad:
                total = e_total = 0.0
                for r in np.flatnonzero(geom_of_ring == g):
                    ring = D[start[r]:start[r] + count[r]]
                    rv1, re1 = mp_form_factor(np.zeros(3), np.array([0.0, 0.0, 1.0]), ring,
                                              one_sided=False, tolerance=tolerance,
                                              error=True)
                    total += -rv1 if is_hole[r] else rv1
                    e_total += re1
                v[g], e[g] = total, e_total
    for v, e, fr in zip(vals, errs_, frags):
        F += np.bincount(fr, weights=v, minlength=m)
        err += np.bincount(fr, weights=e, minlength=m)
    return F, err
