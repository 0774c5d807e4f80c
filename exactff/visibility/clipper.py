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
from .charts import CHARTS, chart_polygons
from .overlay import TiledRegion, cut_region, tiles_per_side

__all__ = ["visible_pieces"]


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
            vis, covered = cut_region(g, covered, st)
            if vis.is_empty or vis.area == 0.0:
                st["hidden"] += 1
                continue
        if receives[idx[j]]:
            out.append((int(idx[j]), ci, vis))
