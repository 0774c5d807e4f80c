"""The covered region of a chart, kept robust: GEOS overlays with repairs, snapping and
crack filling, and the tiled region that keeps each tile's part small.
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from .charts import chart_rect

__all__ = ["repair", "cut_region", "fill_cracks", "polygonal", "snap", "overlay",
           "tiles_per_side", "TiledRegion"]


def repair(geom):
    """Repair a region with union semantics (overlapping or nested shells are merged, not
    turned into holes): GEOS's ``make_valid`` with the "structure" method, or the union
    of the parts on shapely < 2.1."""
    try:
        return shapely.make_valid(geom, method="structure")
    except TypeError:
        return shapely.union_all(shapely.get_parts(geom))


def cut_region(g, covered, stats):
    """The visible part of image ``g`` behind ``covered``, and the grown covered region.

    Checked by area conservation, ``area(covered | g) = area(covered) + area(g - covered)``
    to rounding: GEOS's floating-point overlay has been seen to return a wrong
    difference, or a union with nested shells, on near-degenerate input without raising.
    When the check fails, both are recomputed with snap-rounding on a grid of 2**-50
    chart units (vertices move by less than 1e-15); recomputations count in
    ``stats["overlay_repairs"]``. The check runs when nothing is visible too: GEOS has
    been seen to return an empty difference for an image that shares one edge with the
    covered region and lies outside it (its union then had the area of both). An empty
    difference is also checked with an exact predicate (prepared ``covers``): GEOS has
    been seen to drop a whole image whose edge runs along the region's, consistently in
    the difference and the union (so that area conservation held); the two are then
    recomputed with snap-rounding too (see :func:`_dropped_difference`).
    """
    vis = overlay(shapely.difference, g, covered, stats)
    grown = overlay(shapely.union, covered, g, stats)
    a_cov, a_vis, a_new = covered.area, vis.area, grown.area
    if (abs(a_new - a_cov - a_vis) > tol.AREA_CONSERVATION_RTOL * (a_cov + g.area) + 1e-300
            or not (shapely.get_type_id(grown) != 6 or shapely.is_valid(grown))
            or (a_vis == 0.0 and not shapely.covers(covered, g))):
        stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
        cs, gs = snap(covered), snap(g)
        vis = polygonal(shapely.difference(gs, cs, grid_size=tol.OVERLAY_SNAP_GRID))
        grown = polygonal(shapely.union(cs, gs, grid_size=tol.OVERLAY_SNAP_GRID))
        if not shapely.is_valid(grown):
            grown = repair(grown)
    if vis.is_empty or vis.area == 0.0:
        return vis, covered  # nothing new: keep the region as it was
    return vis, fill_cracks(grown)


def fill_cracks(region):
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


def _dropped_difference(g, region, stats):
    """``g - region`` with snap-rounding on the grid ``OVERLAY_SNAP_GRID`` (vertices move
    by less than 1e-15), for a floating-point difference that came back empty although
    an exact predicate sees interior points of ``g`` outside ``region`` (counted in
    ``stats["overlay_repairs"]``).

    GEOS's floating-point overlays have been seen to drop a whole image whose edge runs
    along the region's (a wall's top edge along the ceiling's: the difference empty, the
    intersection the whole wall, the union the ceiling alone), consistently, so that
    area conservation over them holds. Left to the tile's merge, whose check is the
    tile's total area, such a loss was not seen when a coincident image later in the
    batch (the back face of a zero-thickness wall) gained exactly that area, its cut
    against the union of the earlier parts having dropped the same image: the total
    right, the owner wrong. Decided at once, a loss can no longer offset a gain."""
    stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
    return polygonal(shapely.difference(snap(g), snap(region),
                                        grid_size=tol.OVERLAY_SNAP_GRID))


def polygonal(geom):
    """The areal part of a geometry (snapping can collapse slivers to lines or points)."""
    if shapely.get_type_id(geom) in (3, 6):
        return geom
    parts = shapely.get_parts(geom)
    return shapely.union_all(parts[np.isin(shapely.get_type_id(parts), (3, 6))])


def snap(geom):
    return polygonal(shapely.set_precision(geom, tol.OVERLAY_SNAP_GRID))


def overlay(op, a, b, stats):
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
        return polygonal(shapely.union_all([snap(x) for x in a],
                                            grid_size=tol.OVERLAY_SNAP_GRID))
    try:
        return op(a, b)
    except shapely.errors.GEOSException:
        stats["overlay_repairs"] = stats.get("overlay_repairs", 0) + 1
    a, b = repair(a), repair(b)
    try:
        return op(a, b)
    except shapely.errors.GEOSException:
        return polygonal(op(snap(a), snap(b), grid_size=tol.OVERLAY_SNAP_GRID))


def tiles_per_side(fragments):
    """Tiles per side of a chart's grid for this many fragment images: about
    ``TILE_FRAGMENTS`` images per tile, between 1 and ``MAX_TILES``."""
    return int(min(tol.MAX_TILES, max(1, round(np.sqrt(fragments / tol.TILE_FRAGMENTS)))))


class TiledRegion:
    """The covered region of one chart, kept as a grid of tiles with a region each, and
    grown by batches of fragments taken front to back.

    A single covered region grows with everything visible, and every overlay with it
    costs in proportion (measured: 26 s for 4,000 quads with one region, 0.67 s with 16
    x 16 tiles; ``docs/explanation/visibility.md``). Here each tile has its own small
    region, and fragments are decided a batch at a time with vectorised shapely calls
    (one C call per step for the whole batch, not one Python round per fragment):

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
        u0, v0, u1, v1 = chart_rect(chart)
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
                parts[m] = [overlay(shapely.intersection, g, b, stats)
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
                gs = snap(images[i])
                parts[sel] = [polygonal(shapely.intersection(gs, b, grid_size=tol.OVERLAY_SNAP_GRID))
                              for b in shapely.box(self.u[ix[sel]], self.v[iy[sel]],
                                                   self.u[ix[sel] + 1], self.v[iy[sel] + 1])]
            parts[m] = [polygonal(q) for q in parts[m]]
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
                    vis[cut] = [overlay(shapely.difference, q, r, stats)
                                for q, r in zip(parts[cut], self.region[tile[cut]])]
                # the predicate found interior points outside the region: an empty
                # difference may be a GEOS failure (seen) or a rounding sliver; the part
                # joins the merge's area check, which tells the two apart (the other
                # face of a zero-thickness wall, later in the batch, cannot offset the
                # loss there: its cut against this region drops it too, and its cut
                # against this part is checked at once, below; snap-rounding here, on
                # the tile's whole region, cost 25 % of a cloister row)
                check[cut[shapely.area(vis[cut]) == 0.0]] = True
        # parts that meet earlier parts of the batch: minus those (the earlier parts
        # are wholly in front, whatever of them is visible)
        for k in np.flatnonzero(waits):
            if vis[k] is None or vis[k].is_empty:
                continue
            earlier = list(parts[b[a == k]])
            E = earlier[0] if len(earlier) == 1 else fill_cracks(polygonal(
                overlay(shapely.union_all, earlier, None, stats)))
            inside = shapely.relate(E, vis[k])[6] == "F"
            if inside and shapely.covers(E, vis[k]):   # hidden by earlier parts
                stats["covered_rejections"] += 1
                vis[k] = None
                continue
            stats["differences"] += 1
            v = overlay(shapely.difference, vis[k], E, stats)
            if v.area == 0.0 and not inside:
                v = _dropped_difference(vis[k], E, stats)
                check[k] = v.area == 0.0
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
            grown = geoms[0] if len(geoms) == 1 else overlay(shapely.union_all, geoms, None,
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
                    v, grown = cut_region(q, grown, stats)
                if slot >= 0:
                    self.out[slot] = (frag, self.chart_index, v)
                elif rec and not v.is_empty and v.area > 0.0:
                    self.out.append((frag, self.chart_index, v))
        grown = fill_cracks(polygonal(grown))
        shapely.prepare(grown)
        self.region[t] = grown
        self.area[t] = grown.area
        self.pending[t] = []
