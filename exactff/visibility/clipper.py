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


def clip_halfspace(V, counts, h):
    """Clip a batch of polygons to the half-space ``h . x > 0`` (points on it kept).

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
    if margin == 0.0:
        # points clipped onto the chart's edges u = +-1 (and v = +-1, v = 1) land a few
        # ulps off them; two images meeting there then had vertices 1e-15 apart, and
        # GEOS got every overlay and predicate of the pair wrong (an image beside
        # another came back inside it, consistently, so no area check could tell):
        # snap them onto the edge, where they belong
        for val in (-1.0, 1.0):
            near = np.abs(UV - val) <= tol.CHART_EDGE_ULPS * np.spacing(1.0)
            UV[near] = val
        # a side chart's bottom edge v = 0 is the horizon: points clipped onto it come
        # out with v of about 1e-17 (the crossing's height, rounded), and GEOS got the
        # overlay of two images meeting there wholly wrong (an image adjacent to
        # another returned as inside it: a floor lost 17 % of its value)
        edges = {0: (-1.0, 1.0), 1: (-1.0, 1.0)}
        if chart[3]:
            near = np.abs(UV[:, :, 1]) <= tol.CHART_EDGE_ULPS * np.spacing(1.0)
            UV[:, :, 1][near] = 0.0
            edges[1] = (-1.0, 0.0, 1.0)
        # and along the edge: the same point of two images (the end of an edge they
        # share, clipped in each) came out an ulp apart on it, with the same failures;
        # points of one edge within a few ulps of each other are merged (isolated
        # points do not move)
        for k in (0, 1):
            for val in edges[1 - k]:
                on_edge = UV[:, :, 1 - k] == val
                if on_edge.sum() > 1:
                    UV[:, :, k][on_edge] = _merge_close(UV[:, :, k][on_edge])
    return live, UV, cl


def _merge_close(x):
    """Values within ``CHART_EDGE_ULPS`` ulps of their neighbour (sorted) replaced by the
    first of their run: near-coincident points collapse to one, others stay."""
    u, inv = np.unique(x, return_inverse=True)
    new_run = np.r_[True, np.diff(u) > tol.CHART_EDGE_ULPS * np.spacing(np.abs(u[1:]))]
    first = np.flatnonzero(new_run)
    return u[first[np.cumsum(new_run) - 1]][inv]


def chart_polygons(buckets, chart):
    """Clip polygons (local frame) to a chart's frustum and project them into the chart.

    Parameters
    ----------
    buckets : list of (ndarray of int, ndarray of shape (M_b, K_b, 3), ndarray of shape (M_b,))
        Positions, padded vertices and counts of the polygons, bucket by bucket (as
        :func:`exactff.geometry.padded_buckets`, in the local frame of the point).
    chart : one of CHARTS

    Returns
    -------
    (ndarray of int, ndarray of shapely.Polygon, ndarray of shape (M', 4), int)
        Positions of the polygons that reach the chart (increasing), their images,
        their bounds, and how many images were invalid (rounding-thin or self-touching)
        and repaired with ``make_valid`` (keeping their areal parts).
    """
    idx, polys = [], []
    for pos, V, counts in buckets:
        live, UV, cl = chart_clip(V, counts, chart)
        if len(live) == 0:
            continue
        mask = np.arange(UV.shape[1])[None, :] < cl[:, None]
        rings = shapely.linearrings(UV[mask], indices=np.repeat(np.arange(len(live)), cl))
        idx.append(pos[live])
        polys.append(shapely.polygons(rings))
    if not idx:
        return np.zeros(0, dtype=int), np.empty(0, object), np.zeros((0, 4)), 0
    idx, polys = np.concatenate(idx), np.concatenate(polys)
    order = np.argsort(idx, kind="stable")
    idx, polys = idx[order], polys[order]
    bad = ~shapely.is_valid(polys)
    if bad.any():
        # rounding-thin slivers or self-touching images: repair, keep only areas (the
        # parts dropped are lines and points, of zero area; counted by the caller)
        fixed = []
        for g in shapely.make_valid(polys[bad]):
            parts = shapely.get_parts(g)
            fixed.append(shapely.union_all(parts[shapely.get_type_id(parts) >= 3]))
        polys[bad] = fixed
    return idx, polys, shapely.bounds(polys), int(bad.sum())


def _repair(geom):
    """Repair a region with union semantics (overlapping or nested shells are merged, not
    turned into holes): GEOS's ``make_valid`` with the "structure" method, or the union
    of the parts on shapely < 2.1."""
    try:
        return shapely.make_valid(geom, method="structure")
    except TypeError:
        return shapely.union_all(shapely.get_parts(geom))


def _cut(g, covered, stats):
    """The visible part of image ``g`` behind ``covered``, and the grown covered region.

    Checked by area conservation, ``area(covered | g) = area(covered) + area(g - covered)``
    to rounding: GEOS's floating-point overlay has been seen to return a wrong
    difference, or a union with nested shells, on near-degenerate input without raising.
    When the check fails, both are recomputed with snap-rounding on a grid of 2**-50
    chart units (vertices move by less than 1e-15); recomputations count in
    ``stats["overlay_repairs"]``. The check runs when nothing is visible too: GEOS has
    been seen to return an empty difference for an image that shares one edge with the
    covered region and lies outside it (its union then had the area of both).
    """
    vis = _overlay(shapely.difference, g, covered, stats)
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
    if b is None:  # the union of a list
        try:
            return shapely.union_all(a)
        except shapely.errors.GEOSException:
            stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
        return _polygonal(shapely.union_all([_snap(x) for x in a],
                                            grid_size=tol.OVERLAY_SNAP_GRID))
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
    """The covered region of one chart, kept as a grid of tiles with a region each, and
    grown by batches of fragments taken front to back.

    A single covered region grows with everything visible, and every overlay with it
    costs in proportion (DESIGN 3, measured: 26 s for 4,000 quads with one region, 0.67 s
    with 16 x 16 tiles). Here each tile has its own small region, and fragments are
    decided a batch at a time with vectorised shapely calls (one C call per step for the
    whole batch, not one Python round per fragment):

    1. a fragment whose tiles are all full is hidden, without geometry (a tile is full
       when its region covers it, an exact predicate asked once its uncovered area is
       below ``COVERED_RTOL`` of the tile);
    2. the others are cut into one part per tile they overlap (checked by area
       conservation);
    3. each part is decided against its tile's region: empty tile or bounds apart,
       visible whole; then one exact DE-9IM predicate (``relate``): covered, hidden
       (confirmed by a prepared ``covers``); interiors disjoint, visible whole; only the
       rest is differenced (one vectorised GEOS call);
    4. a part whose interior meets an earlier part of the same batch (an STRtree over
       the batch) then loses those earlier parts too;
    5. decided parts wait in their tile's list and are unioned into the tile's region
       when a later part needs it, when the tile may be full, or at the end; every
       merge checks all the decisions since the last one by area conservation, and a
       tile that fails is redone part by part with the checked, snap-rounding overlays
       of :func:`_cut` (the caller's output is corrected).

    Tile seams are straight lines of the chart, hence great-circle arcs: the parts of a
    visible piece are closed regions that the integration adds up.

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
        self.scale = np.array([n / (u1 - u0), n / (v1 - v0)])
        self.origin = np.array([u0, v0])
        self.full_area = (u1 - u0) * (v1 - v0) / n**2 * (1.0 - tol.COVERED_RTOL)
        self.region = np.full(n * n, None, dtype=object)    # each tile's checked region
        # (part, visible part or None, output slot, fragment, receives, merge checks it)
        self.pending = [[] for _ in range(n * n)]
        self.area = np.zeros(n * n)                 # covered area, region + pending
        self.bounds = np.tile([np.inf, np.inf, -np.inf, -np.inf], (n * n, 1))
        self.full = np.zeros(n * n, dtype=bool)
        self.out = None                               # the caller's output list
        self.chart_index = None

    def is_full(self):
        return bool(self.full.all())

    def box(self, t):
        """Tile t as a polygon."""
        n = self.n
        return shapely.box(self.u[t // n], self.v[t % n], self.u[t // n + 1], self.v[t % n + 1])

    def tile_ranges(self, bounds):
        """Tile index ranges ``(ix0, ix1, iy0, iy1)`` of images with these bounds
        (``(M, 4)``; conservative at tile edges)."""
        b = np.nan_to_num(np.asarray(bounds, dtype=float).reshape(-1, 4))  # empty: NaN
        lo = np.floor((b[:, :2] - self.origin) * self.scale)
        hi = np.floor((b[:, 2:] - self.origin) * self.scale)
        r = np.clip(np.column_stack([lo[:, 0], hi[:, 0], lo[:, 1], hi[:, 1]]), 0, self.n - 1)
        return r.astype(int)

    def hidden(self, ranges):
        """Whether every tile of each range is full (summed-area table of the flags)."""
        n = self.n
        S = np.zeros((n + 1, n + 1), dtype=int)
        S[1:, 1:] = self.full.reshape(n, n).cumsum(0).cumsum(1)
        r = ranges
        total = (S[r[:, 1] + 1, r[:, 3] + 1] - S[r[:, 0], r[:, 3] + 1]
                 - S[r[:, 1] + 1, r[:, 2]] + S[r[:, 0], r[:, 2]])
        return total == (r[:, 1] - r[:, 0] + 1) * (r[:, 3] - r[:, 2] + 1)

    def split(self, images, ranges, stats):
        """Cut images into their parts per tile (non-full tiles only).

        Returns (owner, tile, parts): the image (position in ``images``) and tile of
        every part, and the parts."""
        n = self.n
        nx = ranges[:, 1] - ranges[:, 0] + 1
        ny = ranges[:, 3] - ranges[:, 2] + 1
        count = nx * ny
        owner = np.repeat(np.arange(len(images)), count)
        k = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
        ix = ranges[owner, 0] + k // ny[owner]
        iy = ranges[owner, 2] + k % ny[owner]
        tile = ix * n + iy
        parts = images[owner].copy()
        multi = count[owner] > 1
        if multi.any():
            m = np.flatnonzero(multi)
            boxes = shapely.box(self.u[ix[m]], self.v[iy[m]], self.u[ix[m] + 1], self.v[iy[m] + 1])
            try:
                parts[m] = shapely.intersection(images[owner[m]], boxes)
            except shapely.errors.GEOSException:
                parts[m] = [_overlay(shapely.intersection, g, b, stats)
                            for g, b in zip(images[owner[m]], boxes)]
            # the parts of an image must tile it (GEOS overlays can fail silently)
            area = shapely.area(parts)
            split_area = np.bincount(owner, weights=area, minlength=len(images))
            whole = shapely.area(images)
            bad = np.flatnonzero((count > 1) & (np.abs(split_area - whole)
                                                > tol.AREA_CONSERVATION_RTOL * whole))
            for i in bad:
                stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
                sel = np.flatnonzero(owner == i)
                gs = _snap(images[i])
                parts[sel] = [_polygonal(shapely.intersection(gs, b, grid_size=tol.OVERLAY_SNAP_GRID))
                              for b in shapely.box(self.u[ix[sel]], self.v[iy[sel]],
                                                   self.u[ix[sel] + 1], self.v[iy[sel] + 1])]
            parts[m] = [_polygonal(q) for q in parts[m]]
        keep = ~self.full[tile] & (shapely.area(parts) > 0.0)
        return owner[keep], tile[keep], parts[keep]

    def decide(self, tile, parts, stats):
        """Visible part of each part (in batch order), or None, and whether a hidden
        part still needs the merge's check (an empty difference where a predicate saw
        area outside the region).

        The caller records the decisions with :meth:`record` (which grows the covered
        region) before the next batch."""
        m = len(parts)
        vis = np.full(m, None, dtype=object)
        check = np.zeros(m, dtype=bool)   # hidden by an empty difference: merge checks it
        # parts whose interiors meet an earlier part's (same tile) wait for it
        a, b = shapely.STRtree(parts).query(parts)     # bounds meet
        sel = (b < a) & (tile[a] == tile[b])
        a, b = a[sel], b[sel]
        pb = shapely.bounds(parts)
        sel = ((pb[a, 0] < pb[b, 2]) & (pb[b, 0] < pb[a, 2]) & (pb[a, 1] < pb[b, 3])
               & (pb[b, 1] < pb[a, 3]))               # bounds overlap in area
        a, b = a[sel], b[sel]
        if len(a):
            meet = shapely.relate_pattern(parts[b], parts[a], "T********")
            a, b = a[meet], b[meet]
        waits = np.zeros(m, dtype=bool)
        waits[a] = True
        # every part against its tile's region as it was before the batch (parts that
        # meet earlier parts of the batch lose those afterwards)
        cb = self.bounds[tile]
        apart = ((pb[:, 0] >= cb[:, 2]) | (pb[:, 2] <= cb[:, 0]) | (pb[:, 1] >= cb[:, 3])
                 | (pb[:, 3] <= cb[:, 1]))     # includes empty tiles (inf bounds)
        stats["bbox_rejections"] += int((apart & ~waits).sum())
        vis[apart] = parts[apart]
        rel = np.flatnonzero(~apart)
        for t in np.unique(tile[rel]):
            self._merge(int(t), stats)
        if len(rel):
            M = shapely.relate(self.region[tile[rel]], parts[rel])
            M = np.array(M, dtype="U9").view("U1").reshape(-1, 9)
            covered = M[:, 6] == "F"      # no interior point of the part outside the region
            if covered.any():
                # confirmed by another code path (a relate has been seen to hide a part
                # of which 3 % lay in a hole of the region; prepared covers was right)
                c = np.flatnonzero(covered)
                covered[c] = shapely.covers(self.region[tile[rel[c]]], parts[rel[c]])
            apart = (M[:, 0] == "F") & ~covered             # interiors do not meet
            stats["covered_rejections"] += int(covered.sum())
            stats["disjoint_accepts"] += int((apart & ~waits[rel]).sum())
            vis[rel[apart]] = parts[rel[apart]]
            cut = rel[~covered & ~apart]
            if len(cut):
                stats["differences"] += len(cut)
                try:
                    vis[cut] = shapely.difference(parts[cut], self.region[tile[cut]])
                except shapely.errors.GEOSException:
                    vis[cut] = [_overlay(shapely.difference, q, r, stats)
                                for q, r in zip(parts[cut], self.region[tile[cut]])]
                # the predicate found interior points outside the region: an empty
                # difference may be a GEOS failure (seen) or a rounding sliver; the part
                # joins the merge's area check, which tells the two apart
                check[cut[shapely.area(vis[cut]) == 0.0]] = True
        # parts that meet earlier parts of the batch: minus those (the earlier parts
        # are wholly in front, whatever of them is visible)
        for k in np.flatnonzero(waits):
            if vis[k] is None or vis[k].is_empty:
                continue
            earlier = list(parts[b[a == k]])
            E = earlier[0] if len(earlier) == 1 else _fill_cracks(_polygonal(
                _overlay(shapely.union_all, earlier, None, stats)))
            inside = shapely.relate(E, vis[k])[6] == "F"
            if inside and shapely.covers(E, vis[k]):   # hidden by earlier parts
                stats["covered_rejections"] += 1
                vis[k] = None
                continue
            stats["differences"] += 1
            v = _overlay(shapely.difference, vis[k], E, stats)
            if v.area == 0.0 and not inside:
                check[k] = True
            vis[k] = v
        vis = np.array([None if (v is None or v.is_empty or v.area == 0.0) else v for v in vis],
                       dtype=object)
        return vis, check

    def record(self, tile, parts, vis, check, slots, frags, receives, stats):
        """Record the batch's decisions: every part (hidden or not) joins its tile's
        pending list, with its visible part, where that stands in the caller's output
        list (``slots``, -1 for none), its fragment and whether it receives. They are
        unioned into the tile's region when the region is needed, and every decision
        is checked then (:meth:`_merge`)."""
        for t, q, v, sl, f, r, c in zip(tile.tolist(), parts, vis, slots.tolist(),
                                        frags.tolist(), receives.tolist(), check.tolist()):
            self.pending[t].append((q, v, sl, f, r, c))
        seen = np.flatnonzero(vis != None)  # noqa: E711 (object array)
        if len(seen) == 0:
            return
        ts = tile[seen]
        np.add.at(self.area, ts, shapely.area(vis[seen]))
        vb = shapely.bounds(vis[seen])
        for col, ufunc in ((0, np.minimum), (1, np.minimum), (2, np.maximum), (3, np.maximum)):
            ufunc.at(self.bounds[:, col], ts, vb[:, col])
        # a tile is declared full only from a checked region
        for t in np.unique(ts[(self.area[ts] >= self.full_area) & ~self.full[ts]]):
            self._merge(int(t), stats)
            # full only when the region covers the whole tile (an exact predicate): a
            # tile nearly full by area may still show a tiny polygon through a tiny gap
            self.full[t] = self.region[t] is not None and bool(
                shapely.covers(self.region[t], self.box(t)))

    def finish(self, stats):
        """Check the decisions still pending (every tile with pending parts is merged);
        corrects the caller's output where a check fails."""
        for t in range(len(self.pending)):
            if self.pending[t]:
                self._merge(t, stats)

    def _merge(self, t, stats):
        """Union tile t's pending parts into its region, checking every decision taken
        for them since the last merge by area conservation: the new region must have
        the old region's area plus the visible parts'.

        Parts found hidden add nothing: those hidden by predicates were checked then
        (a prepared ``covers`` confirms every ``relate`` that hides a part), those
        hidden by an empty difference where a predicate saw area outside the region
        join the union here.

        The decisions come from exact predicates and floating-point overlays, and GEOS
        has been seen to get both wrong on near-degenerate input without raising (a
        ``relate`` that put an image inside a region with a hole where part of it was
        visible; differences that came back empty). When the check fails, the pending
        parts are decided again one by one with the checked, snap-rounding overlays of
        :func:`_cut`, and the caller's output is corrected."""
        pend = self.pending[t]
        if not pend:
            return
        old = self.region[t]
        # the region grows by the parts with a visible part (whole, not just the visible
        # part: that checks the differences too) and by the parts hidden by an empty
        # difference (they must add nothing); the others were checked when hidden
        geoms = ([q for q, v, *_, chk in pend if v is not None or chk]
                 + ([old] if old is not None else []))
        if not geoms:
            grown = None
            ok = False   # hidden parts in an empty tile: a wrong decision
        else:
            grown = geoms[0] if len(geoms) == 1 else _overlay(shapely.union_all, geoms, None,
                                                              stats)
            ok = (abs(grown.area - self.area[t]) <= tol.AREA_CONSERVATION_RTOL * self.area[t]
                  and (shapely.get_type_id(grown) != 6 or shapely.is_valid(grown)))
        if not ok:
            stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
            grown = old
            for q, _, slot, frag, rec, _ in pend:
                if grown is None:
                    v, grown = q, q
                else:
                    v, grown = _cut(q, grown, stats)
                if slot >= 0:
                    self.out[slot] = (frag, self.chart_index, v)
                elif rec and not v.is_empty and v.area > 0.0:
                    self.out.append((frag, self.chart_index, v))
        grown = _fill_cracks(_polygonal(grown))
        shapely.prepare(grown)
        self.region[t] = grown
        self.area[t] = grown.area
        self.pending[t] = []


def visible_pieces(buckets, receives, stats=None, shortcuts=True, charts=None):
    """Visible pieces of polygons given front to back, per chart.

    Parameters
    ----------
    buckets : list of (ndarray of int, ndarray of shape (M_b, K_b, 3), ndarray of shape (M_b,))
        The fragments bucket by bucket: their positions in the front-to-back order
        (0 is nearest), padded vertices in the local frame of the point, and counts.
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
        ``bbox_rejections`` (parts visible whole: bounds apart, or an empty tile),
        ``disjoint_accepts`` (visible whole by a predicate), ``covered_rejections``
        (hidden by a predicate), ``tile_rejections`` (fragments hidden by full tiles, no
        geometry), ``hidden`` (fragments with nothing visible), ``charts_full``,
        ``skipped_after_full``,
        ``overlay_repairs``, ``repaired_images`` (invalid images repaired, keeping their
        areal parts).
    charts : list, optional
        Filled with, per chart, the positions of the fragments that reach it, their
        images and the tiles per side (what :class:`exactff.visibility.refine.Refiner`
        needs).

    Returns
    -------
    list of (int, int, shapely geometry)
        ``(fragment index, chart index, visible part)`` for receiving fragments; a
        fragment may have several parts in one chart (one per tile).
    """
    out = []
    st = stats if stats is not None else {}
    for key in ("chart_fragments", "differences", "bbox_rejections", "tile_rejections",
                "covered_rejections", "disjoint_accepts", "hidden", "charts_full",
                "skipped_after_full", "overlay_repairs", "repaired_images"):
        st.setdefault(key, 0)
    for ci, chart in enumerate(CHARTS):
        idx, polys, bounds, repaired = chart_polygons(buckets, chart)
        st["chart_fragments"] += len(idx)
        st["repaired_images"] += repaired
        if charts is not None:
            charts.append((idx, polys, tiles_per_side(len(idx)) if shortcuts else 1))
        if shortcuts:
            _tiled_chart(ci, chart, idx, polys, bounds, receives, st, out)
        else:
            # GEOS raises the floating-point flags on its own (benign) divisions
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                _single_region_chart(ci, idx, polys, receives, st, out)
    return out


def _tiled_chart(ci, chart, idx, polys, bounds, receives, st, out):
    region = TiledRegion(chart, tiles_per_side(len(idx)))
    region.out, region.chart_index = out, ci
    ranges = region.tile_ranges(bounds)
    live = ~shapely.is_empty(polys)
    for j0 in range(0, len(idx), tol.CLIP_BATCH):
        # early stop: once every tile is full, nothing behind can be seen in this chart
        if region.is_full():
            st["charts_full"] += 1
            st["skipped_after_full"] += len(idx) - j0
            break
        sel = np.arange(j0, min(j0 + tol.CLIP_BATCH, len(idx)))
        sel = sel[live[sel]]
        hid = region.hidden(ranges[sel])
        st["tile_rejections"] += int(hid.sum())
        st["hidden"] += int(hid.sum())
        sel = sel[~hid]
        if len(sel) == 0:
            continue
        # GEOS raises the floating-point flags on its own (benign) divisions
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            owner, tile, parts = region.split(polys[sel], ranges[sel], st)
            if len(parts) == 0:
                st["hidden"] += len(sel)
                continue
            vis, check = region.decide(tile, parts, st)
            seen = vis != None  # noqa: E711 (object array)
            st["hidden"] += len(sel) - len(np.unique(owner[seen]))
            frag = idx[sel[owner]]
            rec = receives[frag]
            slots = np.full(len(parts), -1)
            for k in np.flatnonzero(seen & rec):
                slots[k] = len(out)
                out.append((int(frag[k]), ci, vis[k]))
            region.record(tile, parts, vis, check, slots, frag, rec, st)
    else:
        if region.is_full():
            st["charts_full"] += 1
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        region.finish(st)


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


def _polygon_rings(polys):
    """The rings of shapely polygons as flat vertex arrays, for the sector sums.

    Parameters
    ----------
    polys : ndarray of shapely Polygons

    Returns
    -------
    coords : ndarray of shape (V, 2)
        Every ring's vertices, its closing point dropped; rings contiguous, each
        polygon's exterior first, then its holes.
    ring_of : ndarray of shape (V,)
        Each vertex's ring (sorted).
    start, count : ndarray of shape (rings,)
        Each ring's first vertex and number of vertices.
    nxt : ndarray of shape (V,)
        Each vertex's successor in its ring.
    is_hole : ndarray of bool, shape (rings,)
    ring_poly : ndarray of shape (rings,)
        Each ring's polygon.
    """
    rings, ring_poly = shapely.get_rings(polys, return_index=True)
    is_hole = np.ones(len(rings), dtype=bool)
    n_rings = shapely.get_num_interior_rings(polys) + 1
    is_hole[np.concatenate([[0], np.cumsum(n_rings)[:-1]])] = False
    coords, ring_of = shapely.get_coordinates(rings, return_index=True)
    last = np.ones(len(ring_of), dtype=bool)
    last[:-1] = ring_of[1:] != ring_of[:-1]
    coords, ring_of = coords[~last], ring_of[~last]
    start = np.searchsorted(ring_of, np.arange(len(rings)))
    count = np.diff(np.append(start, len(ring_of)))
    nxt = np.arange(len(ring_of)) + 1
    nxt[start + count - 1] = start
    return coords, ring_of, start, count, nxt, is_hole, ring_poly


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


def pieces_form_factors(pieces, m, tolerance=None, owner=None, integrator="sector",
                        refiner=None, stats=None):
    """Form factors of visible pieces, summed per fragment, with error estimates.

    Every ring of a piece is a closed chain of great-circle arcs (its chart coordinates
    lifted to directions ``u e_u + v e_v + e_w``). Its sector sum, evaluated in offset
    form by the kernel's own ``_clipped_sector_sums`` (an edge on the horizon becomes its
    horizon arc), is twice the signed area of its image on the base disk. Exterior rings
    add and holes subtract the absolute values, so the result does not depend on ring
    orientation.

    ``integrator="eq3"`` integrates every ring with the paper's Eq. 3 (corrected, with
    monotone-span splitting; :func:`exactff.integrate.eq3_ring_area`) instead, one ring
    at a time; it is neither refined nor escalated.

    Each estimate is the rounding of the ring's sum (``C1 u`` times its absolute terms,
    as in the kernel) plus the clipper's geometry: the ring's perimeter in chart units
    times ``CHART_VERTEX_ERROR`` over pi.

    With a ``tolerance`` and a ``refiner``
    (:class:`exactff.visibility.refine.Refiner`): where the summed estimate of a polygon
    (fragments grouped by ``owner``, default one group per fragment) exceeds
    ``tolerance`` times its value, its pieces that carry a share of that error are
    refined (their vertices recomputed from the input) and integrated in long double,
    then, where still needed, in mpmath. A refined ring must agree with the clipper's
    value within the latter's estimate; where it does not, the clipper's value is kept
    and the difference added to its estimate (``stats["refine_disagreements"]``).
    Rings whose edges cannot all be traced to the input keep the clipper's value and
    estimate (``stats["unrefined_rings"]``).

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,))
        Form factors and error estimates per fragment.
    """
    import mpmath

    from .. import _tolerances as tol
    from ..integrate import _C1, _clipped_sector_sums, eq3_ring_area

    st = stats if stats is not None else {}
    for key in ("refined_rings", "refined_rings_mp", "unrefined_rings",
                "refine_disagreements"):
        st.setdefault(key, 0)
    F = np.zeros(m)
    err = np.zeros(m)
    if not pieces:
        return F, err
    charts = []
    for ci, chart in enumerate(CHARTS):
        sel = [(k, g) for k, c, g in pieces if c == ci]
        if not sel:
            continue
        frag = np.array([k for k, _ in sel])
        geoms = np.array([g for _, g in sel], dtype=object)
        parts, part_of = shapely.get_parts(geoms, return_index=True)
        areal = (shapely.get_type_id(parts) == 3) & ~shapely.is_empty(parts)
        polys, poly_of = parts[areal], part_of[areal]
        if len(polys) == 0:
            continue
        coords, ring_of, start, count, nxt, is_hole, ring_poly = _polygon_rings(polys)
        D = _lift(coords, chart)
        if integrator == "eq3":
            res = np.array([eq3_ring_area(D[a:a + c]) for a, c in zip(start, count)])
            val = np.abs(res[:, 0]) / np.pi
            e_ring = _C1 * tol.EPS * res[:, 1] / np.pi
        else:
            A0 = D[start]
            S, mags, errs = _clipped_sector_sums(A0, D - A0[ring_of], nxt, ring_of, len(start))
            val = np.abs(S) / TWO_PI
            e_ring = (_C1 * tol.EPS * mags + errs) / TWO_PI
        # the clipper's geometry: every vertex within CHART_VERTEX_ERROR of its place
        perimeter = np.bincount(ring_of, weights=np.hypot(*(coords[nxt] - coords).T),
                                minlength=len(start))
        e_ring = e_ring + perimeter * tol.CHART_VERTEX_ERROR / np.pi + 4 * tol.EPS * val
        charts.append(dict(ci=ci, chart=chart, frag=frag, n=len(geoms), coords=coords,
                           nxt=nxt, ring_of=ring_of, start=start, count=count,
                           is_hole=is_hole, geom=poly_of[ring_poly], val=val, err=e_ring,
                           over=np.zeros(len(geoms), dtype=bool), over_val=np.zeros(len(geoms)),
                           over_err=np.zeros(len(geoms))))

    def per_geom(c):
        sign = np.where(c["is_hole"], -c["val"], c["val"])
        v = np.bincount(c["geom"], weights=sign, minlength=c["n"])
        e = np.bincount(c["geom"], weights=c["err"], minlength=c["n"])
        o = c["over"]
        return np.where(o, c["over_val"], v), np.where(o, c["over_err"], e)

    def accept(c, g, total, est, stats):
        """Pieces' refined values (their rings summed in the working precision, then
        rounded): taken where within the current values' estimates of them; elsewhere
        the current values are kept, their estimates widened by the difference."""
        v, e = per_geom(c)
        diff = np.abs(total - v[g])
        agree = diff <= e[g] + est
        stats["refine_disagreements"] += int((~agree).sum())
        c["over"][g] = True
        c["over_val"][g] = np.where(agree, total, v[g])
        c["over_err"][g] = np.where(agree, est, e[g] + diff)

    if tolerance is not None and integrator != "eq3" and refiner is not None and charts:
        group = np.arange(m) if owner is None else np.asarray(owner)
        ng = group.max() + 1

        def flagged():
            Fg, Eg = np.zeros(ng), np.zeros(ng)
            for c in charts:
                v, e = per_geom(c)
                np.add.at(Fg, group[c["frag"]], v)
                np.add.at(Eg, group[c["frag"]], e)
            out = []
            for c in charts:
                v, e = per_geom(c)
                g_of = group[c["frag"]]
                # the pieces of polygons that miss the tolerance, where the piece
                # carries at least a tenth of the allowed error
                out.append(np.flatnonzero((Eg[g_of] > tolerance * Fg[g_of])
                                          & (e > 0.1 * tolerance * Fg[g_of])))
            return out

        # second tier: refined rings in long double, chart by chart, all at once; a
        # piece's rings (exterior and holes, which may nearly cancel) summed before
        # rounding
        labels = []
        for c, bad in zip(charts, flagged()):
            rsel = np.flatnonzero(np.isin(c["geom"], bad))
            labels.append((rsel, None))
            if len(rsel) == 0:
                continue
            vsel = np.concatenate([np.arange(c["start"][r], c["start"][r] + c["count"][r])
                                   for r in rsel])
            ring_sub = np.repeat(np.arange(len(rsel)), c["count"][rsel])
            st_sub = np.concatenate([[0], np.cumsum(c["count"][rsel])[:-1]])
            nxt_sub = np.arange(len(vsel)) + 1
            nxt_sub[st_sub + c["count"][rsel] - 1] = st_sub
            frag_v = c["frag"][c["geom"][rsel]][ring_sub]
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                rv, re, ok, lab = refiner.refine_ld(c["ci"], c["chart"], c["coords"][vsel],
                                                    nxt_sub, ring_sub, len(rsel), frag_v)
            labels[-1] = (rsel, None if lab is None else (vsel, st_sub, lab, ok))
            st["refined_rings"] += int(ok.sum())
            st["unrefined_rings"] += int((~ok).sum())
            g_r = c["geom"][rsel]
            geoms, inv = np.unique(g_r, return_inverse=True)
            total = np.zeros(len(geoms), dtype=rv.dtype)
            np.add.at(total, inv, np.where(c["is_hole"][rsel], -rv, rv))
            est = np.bincount(inv, weights=np.where(ok, re, np.inf), minlength=len(geoms))
            tf = total.astype(float)
            est = est + tol.EPS * np.abs(tf)
            done = np.isfinite(est)
            accept(c, geoms[done], tf[done], est[done], st)
        # last tier: mpmath, for the pieces still missing the tolerance, their rings
        # summed at the working precision
        for c, bad, (rsel, info) in zip(charts, flagged(), labels):
            if info is None or len(bad) == 0:
                continue
            vsel, st_sub, (label, statics, point, drop, cut), ok = info
            g_r = c["geom"][rsel]
            for g in np.intersect1d(bad, g_r):
                ks = np.flatnonzero(g_r == g)
                if not ok[ks].all():
                    continue
                terms, est = [], 0.0
                for k in ks:
                    r = rsel[k]
                    a, cnt = st_sub[k], c["count"][r]
                    sl = slice(a, a + cnt)
                    rv, re = refiner.refine_mp(c["chart"], c["coords"][vsel[sl]], label[sl],
                                               statics, point[sl], drop[sl], cut[k],
                                               tolerance)
                    terms.append((-1 if c["is_hole"][r] else 1, rv))
                    est += re
                    st["refined_rings_mp"] += 1
                # summed exactly (not at mpmath's default 15 digits), then rounded once
                with mpmath.workdps(tol.MP_MAX_DPS + 100):
                    tf = float(mpmath.fsum(sg * rv for sg, rv in terms))
                accept(c, np.array([g]), np.array([tf]), np.array([est + 2 * tol.EPS * abs(tf)]),
                       st)
    for c in charts:
        v, e = per_geom(c)
        F += np.bincount(c["frag"], weights=v, minlength=m)
        err += np.bincount(c["frag"], weights=e, minlength=m)
    return F, err
