"""Gnomonic charts of the upper hemisphere: the five faces of the hemicube frustum.

In a chart the central projection maps every great-circle arc to a straight segment, so
straight-line clipping there gives the exact topology of the visible graph. Shared by
the exact engine and the discrete methods.
"""

from fractions import Fraction

import numpy as np
import shapely

from .. import _tolerances as tol
from ..halfspace import clip_halfspace

__all__ = ["CHARTS", "chart_planes", "chart_clip", "chart_polygons", "chart_rect", "lift", "merge_close",
           "planes_near_point", "exact_chart_clip"]

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


def chart_planes(chart, margin=0.0):
    """Inward normals of the half-spaces (through the origin) bounding a chart's frustum,
    widened by ``margin`` in chart units (0: the exact frustum)."""
    eu, ev, ew, side = chart
    g = 1.0 + margin
    return [g * ew - eu, g * ew + eu, g * ew - ev, ev + margin * ew if side else g * ew + ev]


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
    planes = np.array(chart_planes(chart, margin))
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
                    UV[:, :, k][on_edge] = merge_close(UV[:, :, k][on_edge])
    return live, UV, cl


def planes_near_point(V, counts):
    """Which polygons (local frame of the point, padded) lie in planes that pass within
    ``CHART_EXACT_CLIP_RTOL`` of their size of the point (the origin), by Newell's
    normal: their clips to a chart's frustum are ill-conditioned in floating point
    (:func:`exact_chart_clip`)."""
    K = V.shape[1]
    slot = np.arange(K)[None, :] < counts[:, None]
    nxt = (np.arange(K)[None, :] + 1) % counts[:, None]
    W = np.take_along_axis(V, nxt[:, :, None].repeat(3, axis=2), axis=1)
    N = np.where(slot[:, :, None], np.cross(V - V[:, :1], W - V[:, :1]), 0.0).sum(axis=1)
    height = np.abs(np.einsum("mj,mj->m", N, V[:, 0]))
    size = np.abs(V).max(axis=(1, 2))
    return height <= tol.CHART_EXACT_CLIP_RTOL * size * np.linalg.norm(N, axis=1)


def exact_chart_clip(P, chart):
    """A polygon's image in a chart, clipped to its frustum in rational arithmetic from
    its (local) float vertices and rounded once: for a polygon whose plane passes within
    rounding of the point (:func:`planes_near_point`). Clipped in floating point, the
    frustum's edges meet such a plane a few ulps from the point, between computed
    crossings whose rounding is of the polygon's size: a face 8 ulps of 3 m in front of
    the point covers the whole top chart, and its float clip was a square with corners
    10 % off, through which what lay behind showed (0.003 of the hemisphere).

    Parameters
    ----------
    P : ndarray of shape (K, 3)
        The polygon in the local frame of the point.
    chart : one of CHARTS

    Returns
    -------
    ndarray of shape (k, 2)
        The clipped image's vertices in chart coordinates (k < 3: nothing in the chart).

    Examples
    --------
    >>> sq = np.array([[-3, -3, 1e-15], [3, -3, 1e-15], [3, 3, 1e-15], [-3, 3, 1e-15]])
    >>> exact_chart_clip(sq, CHARTS[0]).tolist()
    [[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]]
    """
    ring = [tuple(Fraction(float(x)) for x in v) for v in np.asarray(P)]
    dot = lambda a, b: a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    for h in chart_planes(chart):
        h = tuple(Fraction(float(x)) for x in h)
        out = []
        for a, b in zip(ring, ring[1:] + ring[:1]):
            sa, sb = dot(h, a), dot(h, b)
            if sa >= 0:
                out.append(a)
            if (sa > 0 and sb < 0) or (sa < 0 and sb > 0):
                t = sa / (sa - sb)
                out.append(tuple(x + t * (y - x) for x, y in zip(a, b)))
        ring = out
        if len(ring) < 3:
            return np.zeros((0, 2))
    eu, ev, ew, _ = chart
    eu, ev, ew = ([Fraction(float(x)) for x in e] for e in (eu, ev, ew))
    uv = []
    for x in ring:
        w = dot(ew, x)
        if w <= 0:          # the point itself (the apex): no direction, left out
            continue
        q = (float(dot(eu, x) / w), float(dot(ev, x) / w))
        if not uv or q != uv[-1]:
            uv.append(q)
    if len(uv) > 1 and uv[0] == uv[-1]:
        uv.pop()
    return np.array(uv).reshape(-1, 2)


def merge_close(x):
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
        :func:`exactff.rings.padded_buckets`, in the local frame of the point).
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
        images = shapely.polygons(rings)
        # a plane through the point to rounding: the clip in rational arithmetic
        for i in np.flatnonzero(planes_near_point(V[live], counts[live])).tolist():
            uv = exact_chart_clip(V[live[i], :counts[live[i]]], chart)
            images[i] = shapely.Polygon(uv) if len(uv) >= 3 else shapely.Polygon()
        idx.append(pos[live])
        polys.append(images)
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


def lift(coords, chart):
    """Chart coordinates (u, v) back to directions ``u e_u + v e_v + e_w``."""
    eu, ev, ew, _ = chart
    return coords[:, :1] * eu + coords[:, 1:2] * ev + ew


def chart_rect(chart):
    """The chart's square in chart units: (u0, v0, u1, v1)."""
    return (-1.0, 0.0, 1.0, 1.0) if chart[3] else (-1.0, -1.0, 1.0, 1.0)
