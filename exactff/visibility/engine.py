"""Exact visibility: occluded form factors from a point to every polygon of a scene.

The engine (``docs/explanation/visibility.md``): a BSP tree orders the fragments front
to back from the point; the area-sorting clipper keeps the covered region in five
gnomonic charts and cuts each new fragment's image against it; every visible piece is
integrated exactly with the sector form. Shortcuts leave out what a row does not need;
each is reported in ``stats`` and tested to be neutral.
"""

import numpy as np
import shapely
from scipy.spatial import ConvexHull, QhullError

from .. import _tolerances as tol
from ..checks import as_receiver
from ..errors import check_finite, misses_tolerance, nonnegative, tolerance_missed
from ..geometry import receiver_frame, to_local
from ..kernel import eq3_form_factor, flat_polygons, unoccluded_row
from ..predicates import coplanar_band_sides, engine_sides
from ..prepared import prepared
from .bsp import coplanar_overlaps, front_to_back, node_first_charges, node_sides, scene_bsp
from .charts import CHARTS, chart_clip
from .clipper import visible_pieces
from .pieces import pieces_form_factors, pieces_solid_angles
from .refine import Refiner

__all__ = ["visible_form_factors", "visible_solid_angles", "visible_graph",
           "is_convex_enclosure"]


def is_convex_enclosure(scene):
    """True when every vertex of the scene lies on the front side (or in the plane) of
    every polygon and no two coplanar polygons overlap, so that from any point in front
    of all of them no polygon can hide another (a convex room seen from inside).
    Computed once per scene.

    Coplanar overlaps (a light on a ceiling, the two faces of a zero-thickness wall)
    hide one another by the tie rule (``exactff.predicates.tie_priority``): such a
    scene goes through the clipper."""
    return prepared(scene).get("convex", _is_convex_enclosure)


def _is_convex_enclosure(scene):
    V = scene.vertices
    try:
        V = V[ConvexHull(V).vertices]      # Qhull merges repeated points itself
    except (QhullError, ValueError):
        V = np.unique(V, axis=0)           # flat or tiny scenes: test every vertex
    sign, _ = coplanar_band_sides(V, scene.normals, scene.plane_offsets)
    if np.any(sign < 0):
        return False
    back_to_back, same_facing = coplanar_overlaps(scene)
    return len(back_to_back) == 0 and len(same_facing) == 0


def visible_form_factors(scene, point, normal, *, two_sided=False, stats=None,
                         shortcuts=True, tolerance=None, integrator="sector", error=False):
    """Exact form factors with occlusion from one point to every polygon of a scene.

    Parameters
    ----------
    scene : Scene
    point : ndarray of shape (3,)
    normal : ndarray of shape (3,)
        Unit receiver normal.
    two_sided : bool, default False
        Let polygons receive on their back side too. Every polygon occludes whichever
        way it faces.
    stats : dict, optional
        Filled with what the row did: ``path`` (``"unoccluded"`` when the convex-scene
        shortcut applied, else ``"clipper"``), ``fragments``, ``culled_edge_on``,
        ``culled_below_horizon``, the clipper's counters, and the refinement's
        (``refined_rings``, ``refined_rings_mp``, ``unrefined_rings``,
        ``refine_disagreements``, ``refine_mp_unconverged``).
    tolerance : float or None
        Relative accuracy requested of every value: unoccluded values (convex-scene
        path) whose estimate exceeds it are re-evaluated in higher precision; visible
        pieces of polygons whose bound exceeds it are refined (vertices recomputed
        from the input, :mod:`exactff.visibility.refine`) and integrated in long double
        or mpmath. A value whose bound still exceeds ``tolerance`` times the larger of
        the value and ``VALUE_FLOOR`` (1e-4; :func:`exactff.errors.misses_tolerance`)
        afterwards, mpmath's evaluations at their precision limit included, raises
        :class:`exactff.NumericalError` naming the polygon, its bound and the
        tolerance, on every path and with either integrator; with ``error=True`` it is
        returned with that bound instead. None: no refinement, no escalation, no
        check.
    shortcuts : bool, default True
        False disables every shortcut: the convex-scene path, the culling of fragments
        below the horizon, the tiled clipper (full tiles, predicates instead of
        overlays, bounding-box rejection) and the early stop on full charts (for
        testing that they never change a result).
    integrator : {"sector", "eq3"}, default "sector"
        How visible pieces (and, on the convex-scene path, whole polygons) are
        integrated: Lambert's sector form or the paper's Eq. 3, corrected, with
        monotone-span splitting, in its stable form
        (:func:`exactff.kernel.eq3_ring_sums`). Both are vectorised, refined and
        escalated alike (long double, then mpmath: Eq. 3 at every tier) and checked
        against ``tolerance``.

    error : bool, default False
        Also return a bound on each value's error: the rounding of its integration
        plus its visible pieces' geometry (the clipper's vertices, or the refined
        ones), given the clipper's topology (``docs/explanation/robustness.md``).
        Values that miss ``tolerance`` are then returned with their bounds instead of
        raising.

    Returns
    -------
    ndarray of shape (len(scene),), or a pair of them with ``error=True``

    Raises
    ------
    NumericalError
        A value missed ``tolerance`` after refinement and escalation, and ``error`` is
        False; a value fell
        below 0 beyond its bound; a value or bound came out NaN.
    """
    st = stats if stats is not None else {}
    flat = flat_polygons(scene)
    p = np.asarray(point, dtype=float)
    # the side of p decided exactly in the rounding band, as on the unoccluded path;
    # seen edge-on only where p lies in the plane to the rounding of its coordinates
    side, band = engine_sides(flat, p)
    # shortcut: a convex enclosure seen from inside has no occlusion at all
    if shortcuts and is_convex_enclosure(scene) and np.all(side >= 0):
        st["path"] = "unoccluded"
        if integrator == "eq3":
            FE = np.array([(0.0, 0.0) if s == 0 else eq3_form_factor(
                p, normal, P, two_sided=two_sided, tolerance=tolerance, error=True)
                for P, s in zip(scene.polygons, side)])
            if not error:
                _require_tolerance(FE[:, 0], FE[:, 1], tolerance, integrator, st)
            return (FE[:, 0], FE[:, 1]) if error else FE[:, 0]
        return unoccluded_row(flat, p, normal, two_sided=two_sided, tolerance=tolerance,
                              sides=(side, band), return_error=error, strict=not error)
    st["path"] = "clipper"
    tree, order, src, kept, world, receives = _row_fragments(scene, p, normal, side, two_sided,
                                                             shortcuts, st)
    charts = []
    pieces = visible_pieces(kept, receives, stats=st, shortcuts=shortcuts, charts=charts)
    refiner = Refiner(scene, tree, order, p, normal, kept, world, charts)
    Ff, ef_ = pieces_form_factors(pieces, len(order), tolerance=tolerance, owner=src,
                                  integrator=integrator, refiner=refiner, stats=st)
    crossing = _crossing_charges(tree, order, p, normal, charts, st)
    F, E = _per_polygon(src, Ff, ef_ + crossing, len(scene), "form factor", stats)
    if "polygon_crossing" in st:
        # asked for (the compiled core's shaft, visibility.compiled._settle_in_shaft):
        # each polygon's part of its bound from the rounded crossings
        st["polygon_crossing"] = np.bincount(src, weights=crossing, minlength=len(scene))
    if not error:
        # the pieces' rounding and geometry against the tolerance; what the BSP's rounded
        # crossings may move against the accuracy target of occluded values, as in the
        # compiled core (compiled_form_factors): no tolerance narrows the input's own
        # rounding
        moved = np.bincount(src, weights=crossing, minlength=len(scene))
        _require_tolerance(F, np.bincount(src, weights=ef_, minlength=len(scene)), tolerance,
                           integrator, st)
        if tolerance is not None and np.any(moved > tol.OCCLUDED_ATOL):
            i = int(np.argmax(moved))
            raise tolerance_missed(f"polygon {i}", F[i], E[i], tolerance,
                                   f"({moved[i]:.3g} of the estimate from the BSP's rounded "
                                   f"crossings, above the accuracy target "
                                   f"{tol.OCCLUDED_ATOL:g})", "")
    # what visiting a node's fragments before its near subtree may misplace (a topology
    # bound, as the compiled core's band: no precision narrows it, so it is not checked)
    misorder = 4 * node_first_charges(tree, p, node_sides(tree, p, side),
                                      _receiving(side, two_sided), side)
    if "polygon_misorder" in st:
        st["polygon_misorder"] = misorder      # (asked for with polygon_crossing)
    E = E + misorder
    return (F, E) if error else F


def visible_solid_angles(scene, point, normal, *, two_sided=False, stats=None,
                         shortcuts=True):
    """Visible solid angles with occlusion from one point to every polygon of a scene,
    within the hemisphere around ``normal``: one half of a spherical factor.

    The same fragments, BSP order and clipper as :func:`visible_form_factors`; every
    visible piece is measured by its solid angle instead of its cosine-weighted one
    (:func:`exactff.visibility.pieces.pieces_solid_angles`). There is no convex-scene
    path here (it integrates the cosine-weighted measure): a caller with an unoccluded
    scene measures whole polygons (:func:`exactff.kernel.polygon_solid_angles`).

    Parameters
    ----------
    scene : Scene
    point : ndarray of shape (3,)
    normal : ndarray of shape (3,)
        The hemisphere's axis (unit).
    two_sided : bool, default False
        Let polygons receive on their back side too (every polygon occludes).
    stats : dict, optional
        Filled as by :func:`visible_form_factors` (``path`` is ``"clipper"``).
    shortcuts : bool, default True
        As for :func:`visible_form_factors` (the culling and the tiled clipper).

    Returns
    -------
    (ndarray of shape (len(scene),), ndarray of shape (len(scene),))
        Solid angles in steradians (at most 2 pi in all) and a bound on each one's
        error: the rounding of its pieces' fans plus their vertices' (the clipper's,
        not refined), given the clipper's topology, and what the BSP's rounded
        crossings can move (as for the form factors: ``stats["crossing_bound"]``).

    Examples
    --------
    From the centre of a closed box, the upper hemisphere's pieces add up to 2 pi:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> W, E = visible_solid_angles(box, [0.5, 0.5, 0.5], [0, 0, 1])
    >>> bool(abs(W.sum() - 2 * np.pi) < 1e-12), bool(E.max() < 1e-12)
    (True, True)
    """
    st = stats if stats is not None else {}
    flat = flat_polygons(scene)
    p = np.asarray(point, dtype=float)
    side, _ = engine_sides(flat, p)
    st["path"] = "clipper"
    tree, order, src, kept, world, receives = _row_fragments(scene, p, normal, side, two_sided,
                                                             shortcuts, st)
    charts = []
    pieces = visible_pieces(kept, receives, stats=st, shortcuts=shortcuts, charts=charts)
    Wf, Ef = pieces_solid_angles(pieces, len(order))
    crossing = _crossing_charges(tree, order, p, normal, charts, st, solid_angle=True)
    W, E = _per_polygon(src, Wf, Ef + crossing, len(scene), "solid angle", stats)
    return W, E + 4 * np.pi * node_first_charges(tree, p, node_sides(tree, p, side),
                                                 _receiving(side, two_sided), side)


def _receiving(side, two_sided):
    """Which polygons receive, by the row's sides (+1 front, -1 back, 0 edge-on)."""
    return (side > 0) | (two_sided & (side != 0))


def _crossing_charges(tree, order, p, normal, charts, st, solid_angle=False):
    """Per fragment of the row (clipper positions), a bound on what the BSP's rounded
    crossings can move in its value (its form factor, or with ``solid_angle`` its solid
    angle in steradians): the pieces are cut from the fragments as built,
    whose vertices made by a split stand within ``tree.vertex_errors`` of the exact
    points (rounded once, or snapped to an end point), while the value is that of the
    exact geometry.

    Moving a fragment's vertex ``V`` by at most ``r`` changes the fragment by the two
    triangles ``(V-, V, V')`` and ``(V, V+, V')`` (``V-``, ``V+`` its neighbours, ``|V'
    - V| <= r``): 3-D area at most ``r (|V - V-| + |V+ - V|) / 2``, at least ``d - r``
    from the point (``d``: its distance from the two edges), whose image on the base
    disk is at most the area over ``pi (d - r)^2`` in form factor units (``cos cos /
    (pi r^2)`` with both cosines at most 1), and its solid angle at most the area over
    ``(d - r)^2``. That measure is charged to the fragment and
    to every fragment behind it whose image (in any chart) meets the image of the two
    edges ``V- V V+`` (of the triangle's outline where the chart clips it) widened by
    three times the angle ``r / (d - r)`` (a chart's coordinates move by at most 3 per
    radian): what the moved edges may uncover or hide. The charges are summed in ``stats["crossing_bound"]`` (the largest)."""
    charge = np.zeros(len(order))
    errors = tree.vertex_errors
    st["crossing_bound"] = 0.0
    if errors is None:
        return charge
    pos, prv, cur, nxt, r = [], [], [], [], []
    for k, f in enumerate(order.tolist()):
        e = errors[f]
        if not e.any():
            continue
        P = tree.fragments[f]
        j = np.flatnonzero(e > 0)
        pos.append(np.full(len(j), k))
        prv.append(P[j - 1])
        cur.append(P[j])
        nxt.append(P[(j + 1) % len(P)])
        r.append(e[j])
    if not pos:
        return charge
    pos, A, V, B, r = (np.concatenate(x) for x in (pos, prv, cur, nxt, r))
    o = np.asarray(p, dtype=float)

    def distance(X, Y):
        # from the point to the segment X-Y
        d = Y - X
        dd = (d * d).sum(1)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(np.where(dd > 0, ((o - X) * d).sum(1) / dd, 0.0), 0.0, 1.0)
        return np.linalg.norm(X + t[:, None] * d - o, axis=1)

    # a margin of 1e-12 relative for the rounding of the distances and lengths
    near = np.minimum(distance(A, V), distance(V, B)) * (1 - 1e-12) - r
    area = 0.5 * r * (np.linalg.norm(V - A, axis=1) + np.linalg.norm(B - V, axis=1))
    with np.errstate(divide="ignore"):
        per = 1.0 if solid_angle else np.pi   # the measure's kernel: cos / r^2, or cos cos / pi r^2
        c = np.where(near > 0, area * (1 + 1e-12) / (per * np.maximum(near, 0.0) ** 2),
                     np.inf)
        widen = np.where(near > 0, 3.0 * r / np.maximum(near, 0.0), np.inf)
    np.add.at(charge, pos, c)
    # the fragments behind whose images meet the triangle's image
    R = receiver_frame(normal)
    T = to_local(np.stack([A, V, B], axis=1), o, R)
    pairs = []
    for ci, chart in enumerate(CHARTS):
        if ci >= len(charts) or len(charts[ci][0]) == 0:
            continue
        idx, images, _ = charts[ci]
        live, UV, cl = chart_clip(T, np.full(len(T), 3), chart)
        if len(live) == 0:
            continue
        # each triangle's clipped outline (padded by its last vertex), closed by its first
        outline = shapely.linestrings(np.concatenate([UV, UV[:, :1]], axis=1))
        grown = shapely.buffer(outline, np.minimum(widen[live], 1e3))
        whole = cl == 3          # unclipped: the two edges at V only, not V- to V+
        if whole.any():
            grown[whole] = shapely.buffer(shapely.linestrings(UV[whole, :3]),
                                          np.minimum(widen[live[whole]], 1e3))
        a, b = shapely.STRtree(images).query(grown, predicate="intersects")
        behind = idx[b] > pos[live[a]]
        pairs.append(np.stack([live[a][behind], idx[b][behind]], axis=1))
    if pairs:
        pairs = np.unique(np.concatenate(pairs), axis=0)
        np.add.at(charge, pairs[:, 1], c[pairs[:, 0]])
    st["crossing_bound"] = float(charge.max(initial=0.0))
    return charge


def _per_polygon(src, Vf, Ef, n, what, stats):
    """Fragments' values and bounds summed per polygon, checked: never NaN, and below 0
    by no more than the bound (holes subtract: rounding may take a value below 0; within
    its bound it is clamped to 0, still covered: 0 <= exact <= V + E <= E)."""
    V = np.bincount(src, weights=Vf, minlength=n)
    E = np.bincount(src, weights=Ef, minlength=n)
    check_finite(V, E)
    V = nonnegative(V, E, f"occluded {what}", item="polygon")
    if stats is not None:
        stats["max_error_estimate"] = float(E.max(initial=0.0))
    return V, E


def _require_tolerance(F, E, tolerance, integrator, st):
    """Raise :class:`NumericalError` for the first polygon of a row whose bound misses
    ``tolerance`` (:func:`exactff.errors.misses_tolerance`, the criterion of the
    unoccluded path's last tier), after everything the row could do: refinement and
    escalation, with either integrator."""
    if tolerance is None:
        return
    bad = np.flatnonzero(misses_tolerance(F, E, tolerance))
    if not len(bad):
        return
    i = int(bad[0])
    if st.get("path") == "clipper":
        why = "after refining its visible pieces"
        if st.get("unrefined_rings"):
            why += f" ({st['unrefined_rings']} ring(s) of the row could not be refined)"
        if st.get("refine_mp_unconverged"):
            why += (f" ({st['refine_mp_unconverged']} ring(s) of the row: mpmath did not "
                    f"converge at {tol.MP_MAX_DPS} digits)")
        hint = ""
    else:
        why, hint = "", ""
    if integrator == "eq3":
        why += " (integrator='eq3')"
    raise tolerance_missed(f"polygon {i}", F[i], E[i], tolerance, why, hint)


def visible_graph(scene, point, normal, *, two_sided=False, max_segment=0.02):
    """The visible graph of one row, drawn on the base of the hemisphere: every visible
    piece of every polygon, as the clipper keeps it, projected onto the unit disk.

    A visible piece is a region of one gnomonic chart bounded by straight images of
    great-circle arcs; on the disk those arcs are the ellipse arcs of the paper's Eq. 2.
    Each chart edge is cut into pieces of at most ``max_segment`` chart units before it
    is projected, so the rings follow the arcs closely; their areas approximate
    (from inside, to about ``max_segment**2``) pi times the form factors.

    Parameters
    ----------
    scene : Scene
    point : array_like of shape (3,)
    normal : array_like of shape (3,)
        Receiver normal; the disk's x and y axes are those of
        :func:`exactff.receiver_frame` (z along the normal).
    two_sided : bool, default False
        As for :func:`exactff.form_factors`.
    max_segment : float, default 0.02
        Longest chart-space segment before projection.

    Returns
    -------
    list of (int, shapely.Polygon or shapely.MultiPolygon)
        ``(polygon index, visible piece on the unit disk)``; a polygon may have several
        pieces (one per chart and tile it crosses). Pieces of different polygons do not
        overlap; in a closed room they tile the disk.

    Examples
    --------
    >>> import exactff as ef
    >>> scene = ef.scenes.cornell_box(closed=True)
    >>> graph = visible_graph(scene, [278, 0.5, 279.6], [0, 1, 0])
    >>> total = sum(g.area for _, g in graph)      # the whole disk: pi
    >>> abs(total - np.pi) < 1e-3
    True
    """
    p, n = as_receiver(point, normal)
    if not (np.isfinite(max_segment) and max_segment > 0):
        raise ValueError(f"max_segment must be a positive number, got {max_segment!r}")
    flat = flat_polygons(scene)
    side, _ = engine_sides(flat, p)
    _, _, src, kept, _, receives = _row_fragments(scene, p, n, side, two_sided, True, {})
    pieces = visible_pieces(kept, receives)

    def on_disk(chart):
        eu, ev, ew, _ = chart

        def project(uv):
            d = uv[:, :1] * eu + uv[:, 1:2] * ev + ew
            return d[:, :2] / np.linalg.norm(d, axis=1, keepdims=True)
        return project

    return [(int(src[f]), shapely.transform(shapely.segmentize(g, max_segment),
                                             on_disk(CHARTS[ci])))
            for f, ci, g in pieces]


def _row_fragments(scene, p, normal, side, two_sided, shortcuts, st):
    """The fragments a row's clipper takes, front to back from ``p``: those seen edge-on
    and (with shortcuts) those wholly below the horizon culled; their vertices in the
    local frame of the point and in the world, bucket by bucket; whether each
    receives. Returns ``(tree, order, src, kept, world, receives)``."""
    tree, buckets = scene_bsp(scene)
    order = np.array(front_to_back(tree, p, side), dtype=int)
    position = np.empty(len(order), dtype=int)
    position[order] = np.arange(len(order))
    src = tree.source[order]
    # cull: fragments seen edge-on have no image and hide nothing
    edge_on = side[src] == 0
    R = receiver_frame(normal)  # normalises
    # local coordinates bucket by bucket (one long polygon pads only its own bucket)
    local, below = [], np.zeros(len(order), dtype=bool)
    for ids, Vb, cb in buckets:
        Vl = to_local(Vb, p, R)
        slot = np.arange(Vl.shape[1])[None, :] < cb[:, None]
        below[position[ids]] = np.where(slot, Vl[:, :, 2], -np.inf).max(axis=1) <= 0
        local.append((position[ids], Vl, cb))
    keep = ~edge_on & ~below if shortcuts else ~edge_on
    st["fragments"] = len(order)
    st["culled_edge_on"] = int(edge_on.sum())
    st["culled_below_horizon"] = int((below & ~edge_on).sum()) if shortcuts else 0
    new_position = np.full(len(order), -1)
    new_position[keep] = np.arange(int(keep.sum()))
    kept, world = [], []
    for (pos, Vl, cb), (_, Vw, _) in zip(local, buckets):
        k = keep[pos]
        if k.any():
            kept.append((new_position[pos[k]], Vl[k], cb[k]))
            world.append((new_position[pos[k]], Vw[k], cb[k]))
    order, src = order[keep], src[keep]
    receives = side[src] > 0
    if two_sided:
        receives |= side[src] < 0
    return tree, order, src, kept, world, receives
