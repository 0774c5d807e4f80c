"""A row of area-to-area form factors with occlusion: the receivers in front of the
emitter, each pair's blockers (:mod:`~exactff.area.culling`), the unoccluded pairs in
closed form together (:mod:`~exactff.area.closed_form`), the occluded ones one by one
as their unoccluded value less the integral of the hidden part
(:mod:`~exactff.area.adaptive`), and the counts of what was done (:class:`AreaStats`).

Every error allowed here is absolute: ``atol`` per value (the public
``area_form_factors(tolerance=...)``), unlike the point functions' relative
``tolerance`` (docs/explanation/area-form-factors.md).
"""

from dataclasses import asdict, dataclass, fields

import numpy as np

from .. import _tolerances as tol
from ..errors import NumericalError, misses_tolerance, nonnegative
from ..geometry import area_vector
from ..prepared import prepared
from ..visibility import is_convex_enclosure
from .adaptive import occluded_pair
from .closed_form import ClosedFormCounts, unoccluded_pairs
from .culling import (closed_solids, convex_solids, front_pairs, padded_polygons,
                      row_blockers, tie_covers, uncovered)
from .rules import triangle_areas
from .walls import hidden_by_walls

__all__ = ["AreaStats", "area_row"]


@dataclass
class AreaStats:
    """The counters of area rows (each 0 where its shortcut is off or did not apply),
    per call: :func:`area_row` adds a row's to the one it is given, and
    :func:`exactff.area_form_factors` returns their sums as a dict with these keys. An
    emitter the tie rule covers counts once per triangle of its uncovered part (each
    is the emitter of its own row).

    Attributes
    ----------
    enclosure_unoccluded_pairs : int
        Pairs of a convex enclosure, where nothing can come between: no shaft or hull
        test at all (:func:`exactff.visibility.is_convex_enclosure`).
    hull_unoccluded_pairs, hull_culled_blockers : int
        Pairs taken by the closed form because shaft culling and the hull test left no
        blocker, and the polygons they left out.
    shaft_culled_blockers, shaft_unoccluded_pairs : int
        Polygons in a pair's bounding box that the shaft's planes rejected before the
        hull test, and pairs whose box held polygons but the shaft none (no hull built).
    far_pairs, contour_rule_pairs, escalated_pairs : int
        Unoccluded values (of unoccluded pairs, or of occluded ones before the hidden
        part is subtracted) whose closed form's estimate missed: taken by the far-field
        rule (a shortcut), by the tanh-sinh contour rule, or with edge pairs
        re-evaluated in mpmath.
    culled_events, solid_events : int
        Blocker-blocker events not cut along because their lines of sight miss the
        receiver, and vertex-edge pairs of two faces of one convex solid, whose images
        united change only at the faces' planes.
    curved_events, curved_skipped : int
        Curved events cut along (not a shortcut): where the images of two blockers'
        edges cross on the receiver's edge
        (:func:`~exactff.area.curved.curved_event_lines`); and pairs with too many
        triples of edges to trace them (``AREA_CURVED_MAX_TRIPLES``), left uncut.
    back_faces : int
        Members of such a solid that a point sees from behind, skipped in its hidden
        region as the members it sees from the front cover their images (per point).
    bounded_points : int
        Points whose hidden part could not be trusted, of little weight, given the
        bound ``0 <= hidden <= unoccluded`` instead.
    engine_fallbacks, engine_fallback_points : int
        Calls whose hidden parts the engine computed at some points (where a point's
        images did not stay finite or could not be trusted), and those points.
    umbra_pairs, umbra_cells : int
        Pairs with umbras (regions of the emitter from which one blocker hides the whole
        receiver, :func:`~exactff.area.umbra.umbras`: their event lines cut away, their
        cells taken by the closed form), and those cells' triangles.
    umbra_pieces : int
        Pieces of emitters from which several blockers together hide the whole receiver
        (or all but a part whose bound is within the tolerance's share),
        :func:`~exactff.area.joint_umbra.hidden_pieces` (their pairs count in ``umbra_pairs``).
    unevaluated_triangles : int
        A pair's triangles (cells) of least bound times area left unevaluated, each at
        half its bound on the unoccluded point values times its area, within as much,
        while they take at most ``AREA_UNEVALUATED_SHARE`` of the pair's tolerance
        (:func:`~exactff.area.points.unevaluated`).
    wall_hidden_pairs : int
        Pairs that walls between them (blockers in one plane, or in up to
        ``AREA_WALL_PLANES`` planes one behind the other) hide whole, proven in
        rationals (:func:`~exactff.area.walls.hidden_by_walls`): exactly 0 (a
        shortcut). Tried before the integral on pairs of at least
        ``AREA_WALL_MIN_BLOCKERS`` blockers (not integrated), after it on the others
        where its estimate misses the tolerance (those count in ``occluded_pairs``
        too).
    cell_fallbacks : int
        Pairs whose emitter was cut along the events another way (GEOS failed, or the
        cells did not cover it: the lines as cut, or on a fine grid).
    occluded_pairs, point_values : int
        What was done: pairs integrated with occlusion, hidden parts evaluated.
    checked_triangles, refined_triangles : int
        The check of the rules' differences (not a shortcut): triangles checked one by
        one against their closed form where a pair's sum missed, and those the check
        sent back to be refined.

    Examples
    --------
    >>> import exactff as ef
    >>> st = AreaStats()
    >>> _ = area_row(ef.scenes.subdivided_box(1), 0, 1e-9, stats=st)
    >>> st.enclosure_unoccluded_pairs, st.as_dict()["occluded_pairs"]
    (5, 0)
    """

    enclosure_unoccluded_pairs: int = 0
    hull_unoccluded_pairs: int = 0
    hull_culled_blockers: int = 0
    shaft_culled_blockers: int = 0
    shaft_unoccluded_pairs: int = 0
    far_pairs: int = 0
    contour_rule_pairs: int = 0
    escalated_pairs: int = 0
    culled_events: int = 0
    solid_events: int = 0
    curved_events: int = 0
    curved_skipped: int = 0
    back_faces: int = 0
    bounded_points: int = 0
    engine_fallbacks: int = 0
    engine_fallback_points: int = 0
    umbra_pairs: int = 0
    umbra_cells: int = 0
    umbra_pieces: int = 0
    unevaluated_triangles: int = 0
    wall_hidden_pairs: int = 0
    cell_fallbacks: int = 0
    occluded_pairs: int = 0
    point_values: int = 0
    checked_triangles: int = 0
    refined_triangles: int = 0

    def add(self, other):
        """Add ``other``'s counts (an AreaStats) to these."""
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))

    def as_dict(self):
        """The counts as a dict, keyed by the attributes' names."""
        return asdict(self)


def _unoccluded_values(polys, i, pairs, shortcuts, st, atol, rtol):
    """The values and estimates of a row's unoccluded pairs ``(j, Pc, Qc)``, all at once
    by the closed form (:func:`~exactff.area.closed_form.unoccluded_pairs`), with the far
    rule (only with ``shortcuts``) and mpmath where its estimate misses the error allowed,
    ``max(atol, rtol * F)``. The one place where a row's unoccluded pairs
    are computed.

    Returns
    -------
    (list of int, ndarray, ndarray)
        The receivers, their values and their estimates.
    """
    js = [j for j, _, _ in pairs]
    counts = ClosedFormCounts()
    f, e = unoccluded_pairs(polys[i], [polys[j] for j in js], shortcuts=shortcuts,
                            rtol=max(rtol or 0.0, tol.AREA_CLOSED_RTOL), atol=atol,
                            parts=[(Pc, Qc) for _, Pc, Qc in pairs], counts=counts)
    st.far_pairs += counts.far_rule
    st.contour_rule_pairs += counts.contour_rule
    st.escalated_pairs += counts.escalated_pairs
    return js, f, e


def area_row(scene, i, atol, *, rtol=None, shortcuts=True, stats=None):
    """Row i of :func:`exactff.area_form_factors` and its estimates.

    The pairs of the row are decided together: the receivers in front of P (and P in
    front of them, :func:`~exactff.area.culling.front_pairs`), then each pair's blockers
    by shaft culling and the hull test on what survives, all pairs and polygons in one
    compiled call (:func:`~exactff.area.culling.row_blockers`);
    occluded pairs are integrated one by one (:func:`~exactff.area.adaptive.occluded_pair`),
    after their unoccluded values are taken together, and the unoccluded pairs together
    at the end.

    Parameters
    ----------
    scene : Scene
    i : int
        The emitter.
    atol : float
        Absolute error allowed per value (the adaptive rules' target):
        ``area_form_factors``' ``tolerance``.
    rtol : float, optional
        Also allowed: this share of the value; the bound is ``max(atol, rtol * F)``.
    shortcuts : bool, default True
        False disables every shortcut (for testing that they never change a result
        beyond the estimates): shaft culling and the hull test (every other polygon is
        then a blocker of every pair), the far-field rule (the contour integral for
        every pair) and the cull of blocker-blocker events whose lines of sight miss
        the receiver or that join two faces of one convex solid
        (:func:`~exactff.area.culling.closed_solids`).
    stats : AreaStats, optional
        This row's counters are added to it.

    Returns
    -------
    (ndarray of shape (len(scene),), ndarray of shape (len(scene),))
        The values and their error estimates.

    Examples
    --------
    Unit squares one apart with a 0.5 x 0.5 plate halfway between (0.0314026942480,
    ``tests/test_area.py``):

    >>> import exactff as ef
    >>> sq = lambda z, up: [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]][::1 if up else -1]
    >>> plate = [[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]]
    >>> f, e = area_row(ef.Scene.from_polygons([sq(0, True), sq(2, False), plate]), 0, 1e-8)
    >>> round(float(f[1]), 8), bool(e[1] <= 1e-8)
    (0.03140269, True)
    """
    covers = prepared(scene).get("area_tie_covers", tie_covers)
    if i not in covers:
        return _part_row(scene, i, None, covers, atol, rtol, shortcuts, stats)
    # an emitter that coplanar polygons earlier in input order partly cover (the tie
    # rule) emits from its uncovered part only, as triangles T: F(i, j) is the sum of
    # A_T F(T, j) / A_i, as the receivers' covering counts A_j F(j, i), so that
    # A_i F(i, j) = A_j F(j, i); each part's estimate is within atol, their weights sum
    # to at most 1 (the parts are held to atol alone: a weighted sum of
    # max(atol, rtol F_T) may exceed max(atol, rtol F))
    P = np.asarray(scene.polygons[i], dtype=float)
    parts = uncovered(P, [np.asarray(scene.polygons[k], dtype=float) for k in covers[i]])
    weights = triangle_areas(parts) / float(np.linalg.norm(area_vector(P)))
    f, e = np.zeros(len(scene)), np.zeros(len(scene))
    for T, w in zip(parts, weights):
        fT, eT = _part_row(scene, i, T, covers, atol, None, shortcuts, stats)
        f += w * fT
        e += w * eT
    return f, e


def _scene_padded(scene):
    """The scene's polygons padded (:func:`~exactff.area.culling.padded_polygons`),
    read-only (kept for the scene's rows)."""
    arrays = padded_polygons([np.asarray(p, dtype=float) for p in scene.polygons])
    for a in arrays:
        a.flags.writeable = False
    return arrays


def _part_row(scene, i, part, covers, atol, rtol, shortcuts, stats):
    """Row i of :func:`area_row` from emitter ``part`` (a part of polygon i in its
    plane; None: the whole polygon), its values per unit area of the part; ``covers``
    the scene's :func:`~exactff.area.culling.tie_covers`."""
    st = AreaStats()
    polys = [np.asarray(p, dtype=float) for p in scene.polygons]
    if part is not None:
        polys[i] = np.asarray(part, dtype=float)
        padded = padded_polygons(polys)
    else:               # the scene's own, built once for it
        padded = prepared(scene).get("area_padded", _scene_padded)
    P = polys[i]
    scale = float(np.ptp(scene.vertices, axis=0).max()) or 1.0
    near = tol.AREA_HULL_RTOL * scale
    AP = area_vector(P)
    area_P = float(np.linalg.norm(AP))
    nP = AP / area_P
    n = len(polys)
    f, e = np.zeros(n), np.zeros(n)
    pairs = front_pairs(polys, i, nP, padded)
    # a receiver that coplanar polygons earlier in input order partly cover (the tie
    # rule) receives only its uncovered part, as triangles: receivers n, n + 1, ... of
    # the row, each adding to its polygon's value (owner)
    owner = list(range(n))
    receivers = list(polys)
    if covers and any(j in covers for j, _, _ in pairs):
        tied = []
        for j, Pc, Qc in pairs:
            if j not in covers:
                tied.append((j, Pc, Qc))
                continue
            for T in uncovered(Qc, [polys[k] for k in covers[j]]):
                tied.append((len(receivers), Pc, T))
                receivers.append(T)
                owner.append(j)
        pairs = tied
    owner = np.array(owner)
    fx, ex = np.zeros(len(receivers)), np.zeros(len(receivers))
    # the atol of a value shared among its receiver's parts (atol_all: the least share,
    # for the pairs taken together)
    share = 1.0 / np.bincount(owner, minlength=n)[owner]
    atol_all = atol * float(share.min())

    def result():
        # each receiver's parts added up
        if stats is not None:
            stats.add(st)
        return (np.bincount(owner, fx, minlength=n)[:n], np.bincount(owner, ex, minlength=n)[:n])

    if not pairs:
        return result()
    # a convex enclosure (every vertex in front of or on every polygon's plane, no
    # coplanar overlaps): nothing can come between any pair
    enclosure = shortcuts and is_convex_enclosure(scene)
    if enclosure:
        st.enclosure_unoccluded_pairs += len(pairs)
        js, fx[js], ex[js] = _unoccluded_values(receivers, i, pairs, shortcuts, st,
                                                atol_all, rtol)
        return result()
    if shortcuts:
        # every pair's blockers: shaft culling, then the hull test (compiled, the GIL
        # released)
        blockers = row_blockers(padded, i, owner[[j for j, _, _ in pairs]],
                                [(Pc, Qc) for _, Pc, Qc in pairs], nP, P[0], near, st)
        solids = prepared(scene).get("area_convex_solids", convex_solids)
        N, D = scene.normals, scene.plane_offsets
        # whether polygon k is on or behind P's plane, as the solids' inner points ask
        # (each member's once a row)
        behind_P = {}
    walls = {}                    # the walls' proofs' walls, kept for the row's pairs
    unoccluded = []               # (j, Pc, Qc): computed together at the end
    occluded = []                 # ((j, Pc, Qc), blockers, solid, inner): one by one
    for a, (j, Pc, Qc) in enumerate(pairs):
        if shortcuts:
            B = blockers[a].tolist()
            st.hull_culled_blockers += len(polys) - 2 - len(B)
        else:
            B = [k for k in range(len(polys)) if k not in (i, owner[j])]
        if B:
            # walls between the two hiding all of one from the other (blockers in one
            # plane, or in a few one behind the other): exactly 0 (fx, ex stay 0); tried
            # first on pairs of many blockers, whose integral costs more than the proof
            # (on fewer, where the integral's estimate misses the tolerance)
            if (shortcuts and len(B) >= tol.AREA_WALL_MIN_BLOCKERS
                    and hidden_by_walls(Pc, Qc, [polys[k] for k in B], scale, walls)):
                st.wall_hidden_pairs += 1
                continue
            st.occluded_pairs += 1
            solid = inner = None
            if shortcuts:
                jj = owner[j]
                solid = np.concatenate([[-1], closed_solids(
                    solids, np.array(B), (N[[i, jj]], D[[i, jj]]), keys=[i, jj])])
                # a point inside each solid's hull, the mean of its vertices, where every
                # member is a blocker, the emitter, the receiver, or on or behind one's
                # plane (no line of sight meets it): one culled otherwise, as within
                # rounding of the shaft's planes, would not hide what the members seen
                # from behind hide, and they are skipped
                inner = np.full((len(solid), 3), np.nan)
                kept = set(B) | {i, jj}
                # (each solid's members and centre stored once for the scene:
                # ConvexSolids; no scan of the scene per pair)
                for g in set(solid[solid >= 0].tolist()):
                    for k in solids.members[g].tolist():
                        if k in kept:
                            continue
                        if k not in behind_P:
                            behind_P[k] = (polys[k] @ N[i] - D[i]).max() <= 0
                        if not (behind_P[k] or (polys[k] @ N[jj] - D[jj]).max() <= 0):
                            break
                    else:
                        inner[solid == g] = solids.centres[g]
            occluded.append(((j, Pc, Qc), B, solid, inner))
            continue
        if len(polys) > 2 and shortcuts:
            st.hull_unoccluded_pairs += 1
        unoccluded.append((j, Pc, Qc))
    if occluded:
        # the occluded pairs unoccluded, together: each estimate may take a share of
        # atol
        _, whole, whole_err = _unoccluded_values(
            receivers, i, [pair for pair, _, _, _ in occluded], shortcuts, st,
            tol.AREA_WHOLE_TOLERANCE_SHARE * atol_all, None)
    for ((j, Pc, Qc), B, solid, inner), w, we in zip(occluded, whole if occluded else [],
                                                    whole_err if occluded else []):
        try:
            fx[j], ex[j], points = occluded_pair([receivers[j]] + [polys[k] for k in B], Pc,
                                                 Qc, nP, atol * share[j], area_P,
                                                 (float(w), float(we)),
                                                 shortcuts, st, rtol, solid, inner)
        except NumericalError as exc:
            raise NumericalError(f"area form factor ({i}, {owner[j]}): {exc}") from exc
        st.point_values += points
        if (shortcuts and len(B) < tol.AREA_WALL_MIN_BLOCKERS
                and misses_tolerance(fx[j], ex[j], rtol, atol=atol * share[j])
                and hidden_by_walls(Pc, Qc, [polys[k] for k in B], scale, walls)):
            fx[j] = ex[j] = 0.0
            st.wall_hidden_pairs += 1
    if occluded:
        # the occluded values clamped at 0 within their estimates, together
        done = np.zeros(len(fx), dtype=bool)
        done[[j for (j, _, _), _, _, _ in occluded]] = True
        fx[:] = nonnegative(fx, ex, unchecked=~done, item="receiver")
    if unoccluded:
        js, fx[js], ex[js] = _unoccluded_values(receivers, i, unoccluded, shortcuts, st,
                                                atol_all, rtol)
    return result()
