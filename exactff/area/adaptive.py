"""The adaptive integral of the hidden part over the emitter: an occluded pair's value
is its unoccluded value (closed form) less the integral of the hidden part over the
cells between visibility events, by pairs of triangle rules; the triangles whose rules
differ most are refined (the higher pair, then cut in four) while the pair's sum of
differences exceeds half of the absolute tolerance ``atol``, and the sum is checked
against the unoccluded values' integral, known exactly (see
docs/explanation/area-form-factors.md). The levels run compiled (:mod:`exactff.area._pair`,
``_core/levels.cpp``, the GIL released); :func:`_adaptive_levels` is their numpy
reference, :func:`_hidden_integral` that of the whole pair in one call (:mod:`.compiled_pair`).
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..errors import NumericalError, misses_tolerance
from ..geometry import area_vector, cross, receiver_frame
from ._pair import adaptive_levels as _compiled_adaptive_levels
from ._pair import corner_first as _compiled_corner_first
from .compiled_pair import LEVEL_RULES, LEVEL_TOLERANCES
from .compiled_pair import hidden_integral_in_one_call as _hidden_integral_in_one_call
from .curved import curved_event_lines
from .events import cut_cells, distinct_lines, event_lines
from .hidden import hidden_setup, hidden_values
from .points import point_values, unevaluated, unoccluded_bound, unoccluded_bounds
from .joint_umbra import pair_umbras, split_pair
from .rule_check import checked_rules, missed_unoccluded
from .umbra import umbra_cells
from .rules import (CORNER_MIDDLE_RULE, budget_refined, far_triangles, quarter, refined, rule_pair,
                    symmetric_degrees, symmetric_null_spread, triangle_areas, triangle_rule)

__all__ = ["COMPILED_LEVELS", "COMPILED_PAIR", "occluded_pair"]


def _split(S, Pc, Qc, nP, atol, area_P, shortcuts, st, solid, inner):
    """:func:`~exactff.area.joint_umbra.split_pair`, the pieces left by these steps."""
    return split_pair(S, Pc, Qc, nP, atol, area_P, st, lambda L, a, A, w: _hidden_integral(
        S, L, Qc, nP, a, A, w, shortcuts, st, solid, inner, split=False))


def _corner_first(T, blockers, nP, dP, reach=0.0, compiled=True):
    """The triangles T (t, 3, 3), each with first a vertex where a blocker's vertex
    touches the emitter's plane, if it has one (within ``AREA_HULL_RTOL`` of the
    triangle's size of the plane, and of that vertex or within ``reach`` of it: the
    cells' corners may lie as far from the events' crossing as the cut lines were
    lengthened, :func:`~exactff.area.events.cut_cells`; the first such blocker vertex, in
    order). Near such a point the hidden part depends on the direction from it (to first
    order), and the collapsed rule, whose collapsed vertex is the first, integrates
    functions of that direction alone without cutting towards the point. A triangle with
    two or three such vertices is first cut in four at its edges' midpoints (so that
    each of its corner quarters has one): returns as many triangles or more, and per
    triangle whether its first vertex is such a corner. ``compiled`` (default): by
    :mod:`exactff.area._pair` (``_core/levels.cpp``), else here, the reference."""
    if compiled:
        Vb = np.vstack(blockers) if len(blockers) else np.zeros((0, 3))
        return _compiled_corner_first(T, Vb, nP, float(dP), float(reach), tol.AREA_HULL_RTOL)
    none = np.zeros(len(T), dtype=bool)
    if not len(T) or not blockers:
        return T, none
    Vb = np.vstack(blockers)                                        # (m, 3)
    off = np.abs(Vb @ nP - dP)
    # only the blocker vertices that may be on the plane for some triangle (in order)
    keep = off <= tol.AREA_HULL_RTOL * np.ptp(T, axis=1).max()
    if not keep.any():
        return T, none
    Vb, off = Vb[keep], off[keep]

    def touching(T):
        """Per triangle and vertex, whether a blocker's vertex touches it on the plane,
        and the index (into Vb) of the first that does."""
        near = tol.AREA_HULL_RTOL * np.ptp(T, axis=1).max(axis=1)   # (t,)
        d = np.linalg.norm(T[:, :, None, :] - Vb[None, None, :, :], axis=3)   # (t, 3, m)
        hit = (d <= np.maximum(near, reach)[:, None, None]) & (off <= near[:, None])[:, None, :]
        return hit.any(axis=2), np.where(hit.any(axis=2), np.argmax(hit, axis=2), len(Vb))

    touched, _ = touching(T)
    several = touched.sum(axis=1) > 1
    if several.any():
        T = np.concatenate([T[~several], quarter(T[several])])
    touched, first = touching(T)
    # the vertex touched by the earliest blocker vertex first
    shift = np.where(touched.any(axis=1), np.argmin(first, axis=1), 0)
    return (T[np.arange(len(T))[:, None], (np.arange(3)[None, :] + shift[:, None]) % 3],
            touched.any(axis=1))


def occluded_pair(S, Pc, Qc, nP, atol, area_P, whole, shortcuts=True, st=None,
                  rtol=None, solid=None, inner=None):
    """``(1 / A_P) int_Pc F_occ(x -> S[0]) dA`` with S = [receiver, blockers...], as the
    unoccluded value (the contour integral, exact) less the integral of the hidden part
    ``F(x -> Qc) - F_occ(x -> S[0])`` (exact point values of the hidden region, built in
    Qc's plane: :func:`~exactff.area.hidden.hidden_values`). The hidden part is smooth
    where the polygons touch (the unoccluded part carries the edge singularities), so it
    is integrated over the cells of Pc between visibility events, each cell's triangles
    by two collapsed Gauss-Legendre rules (6 and 10 points a side), the triangles whose
    rules differ most cut in four while the differences' sum exceeds half of ``atol``
    (:func:`~exactff.area.rules.budget_refined`). Where the events cut Pc into more than
    ``AREA_MANY_CELLS`` triangles (small ones), or the target is at least
    ``AREA_LOW_RULES_TOLERANCE``, each starts with a lower pair (degrees 4 and 8: the
    symmetric rules of 6 and 16 points, with their null rules of degree 5, or the
    collapsed ones of 3 and 5 points a side where a blocker touches its first vertex;
    :func:`~exactff.area.rules.rule_pair`) and takes the higher pair where the budget
    refines it (small triangles far from the blockers a pair lower, degrees 2 and 4).
    Returns the value, its error estimate (the contour sum's, the rules' differences,
    the point values' bounds) and the number of point values used.

    The rules' target is the absolute error ``atol`` allowed the value, or with
    ``rtol`` the bound ``max(atol, rtol * F)``: first with the unoccluded value for F
    (the value is at most that), and where the estimate then misses
    ``max(atol, rtol * |value|)`` once more with ``value - estimate`` for F (a lower
    bound where the estimate holds).
    ``whole``: the pair's unoccluded value and estimate, per unit area of P (the
    row's occluded pairs take theirs together, the estimate within
    ``AREA_WHOLE_TOLERANCE_SHARE`` of the row's ``atol``). ``solid``: as for
    :func:`~exactff.area.events.event_lines`; ``inner``: for each polygon of S with a
    solid, a point inside the solid's hull (NaN elsewhere;
    :func:`~exactff.area.hidden.hidden_setup`)."""
    # with rtol, the value's share where it is the larger: max(atol, rtol * F)
    relative = rtol is not None and rtol * whole[0] > atol
    value, err, points = _hidden_integral(S, Pc, Qc, nP, rtol * whole[0] if relative else atol,
                                          area_P, whole, shortcuts, st, solid, inner)
    if relative and misses_tolerance(value, err, rtol, atol=atol):
        value, err, more = _hidden_integral(S, Pc, Qc, nP,
                                           max(atol, rtol * max(value - err, 0.0)), area_P,
                                           whole, shortcuts, st, solid, inner)
        points += more
    return value, err, points


def _hidden_integral(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, st, solid=None,
                     inner=None, split=True):
    """The adaptive integral of :func:`occluded_pair` to the absolute error ``atol``,
    with ``whole`` the pair's unoccluded value and estimate (per unit area
    of P): in one compiled call (:mod:`.compiled_pair`) where it takes the pair, else
    (or without :data:`COMPILED_PAIR`) by the steps below, its reference; where it has
    umbras to look for, first several blockers' (``split``, :func:`_split`)."""
    if COMPILED_PAIR and COMPILED_LEVELS:
        r = _hidden_integral_in_one_call(S, Pc, Qc, nP, atol, area_P, whole, shortcuts,
                                         solid, inner)
        if r[0] == 0:
            for k, v in zip(("culled_events", "solid_events", "curved_events", "curved_skipped",
                             "back_faces", "unevaluated_triangles"), r[4:] if st is not None else ()):
                setattr(st, k, getattr(st, k) + v)
            return r[1:4]
        split = split and r[0] == 1          # the umbras to look for: first several blockers'
        if split and (done := _split(S, Pc, Qc, nP, atol, area_P, shortcuts, st, solid, inner)):
            return done
    R = receiver_frame(nP)
    c = Pc.mean(axis=0)
    dP = float(nP @ Pc[0])
    radius = (1.0 + tol.AREA_HIDDEN_PAD) * float(np.linalg.norm(Pc - c, axis=1).max())
    lines = event_lines(S, nP, dP, R, c, radius, Qc, shortcuts, st, solid)
    # and the curved events (two blockers' edges seen crossing on Qc's edge), as chords
    lines = np.concatenate([lines, curved_event_lines(
        S, Qc, nP, dP, R, c, radius, atol, solid if shortcuts else None, st)])
    if (split and not (COMPILED_PAIR and COMPILED_LEVELS) and shortcuts
            and len(lines) > tol.AREA_UMBRA_MIN_LINES
            and (done := _split(S, Pc, Qc, nP, atol, area_P, shortcuts, st, solid, inner))):
        return done
    # the umbras of one blocker: regions whose event lines are cut away (pair_umbras)
    regions, lines, done = pair_umbras(lines, S, Pc, Qc, R, c, atol, area_P, shortcuts, st)
    if done is not None:
        return done
    # the arrangement's cost and cells grow with the square of its distinct lines: too
    # many raise (the row names the pair)
    many = distinct_lines(lines, 2.0 * radius, (Pc - c) @ R[:2].T)
    if many > tol.AREA_MAX_EVENT_LINES:
        raise NumericalError(
            f"its visibility events lie on {many} distinct lines, more than "
            f"AREA_MAX_EVENT_LINES = {tol.AREA_MAX_EVENT_LINES} (the emitter would be cut "
            f"into up to {many * many // 2:,} cells): split the emitter or the blockers "
            f"into smaller polygons, use the point engine (form_factor_matrix), or raise "
            f"exactff._tolerances.AREA_MAX_EVENT_LINES where memory allows")
    # the emitter cut along the events: in floating point with the lines lengthened
    # across its boundary, else as cut, else noded on a grid of AREA_HULL_RTOL of P's
    # size (the cuts move by that much), each way with and without lengthening; the
    # first whose cells cover P (to AREA_CELL_COVER_RTOL, or missing no more than the
    # estimate's charge for it keeps within AREA_CELL_COVER_ATOL_SHARE of atol) is
    # taken, else the one that covers most (the area missing is in the estimate). GEOS
    # may give up noding, or polygonizing drop a ring of nearly coincident lines it
    # finds invalid and the cell inside it: counted
    # (test_closed_cornell_box_wall_cut_into_cells_that_cover_it)
    area_Pc = float(np.linalg.norm(area_vector(Pc)))
    cover_slack = max(tol.AREA_CELL_COVER_RTOL * area_Pc,
                      tol.AREA_CELL_COVER_ATOL_SHARE * atol * area_P)
    cells, failure = None, None
    for k, (grid, lengthen) in enumerate(((None, True), (None, False),
                                          (tol.AREA_HULL_RTOL * radius, True),
                                          (tol.AREA_HULL_RTOL * radius, False))):
        try:
            T = cut_cells(Pc, nP, lines, R, c, grid=grid, lengthen=lengthen)
        except shapely.errors.GEOSException as exc:
            failure = exc
            continue
        if cells is None or len(T) and triangle_areas(T).sum() > triangle_areas(cells).sum():
            cells = T
        if triangle_areas(cells).sum() >= area_Pc - cover_slack:
            break
    if k and st is not None:
        st.cell_fallbacks += 1
    if cells is None:
        raise NumericalError(f"could not cut the emitter along its {len(lines)} "
                             f"visibility events: {failure}") from failure
    # a blocker's vertex on the emitter is where the hidden part depends on the direction
    # alone; a cell's corner may lie as far from it as the cut lines were lengthened
    # (twice AREA_CUT_EXTEND_RTOL of P's size: both lines through it moved), and is
    # still that point for the collapsed rule (else no vertex of the cell is, and the
    # rules' differences there shrink only as the triangles do: pinned in
    # tests/test_regressions.py)
    # the cells in an umbra take the unoccluded value for their hidden part, the strips
    # along them the bound (umbra_cells)
    umbra_U = umbra_E = umbra_area = strip_slivers = 0.0
    bound = unoccluded_bound(Pc, Qc)
    if regions:
        cells, umbra_U, umbra_E, umbra_area, strip_slivers, n_umbra = umbra_cells(
            cells, regions, R, c, nP, Qc, area_P, area_Pc, atol, bound)
        if st is not None and n_umbra:
            st.umbra_pairs += 1
            st.umbra_cells += n_umbra
    # the value is then the unoccluded one over the rest of P less the rest's hidden part
    whole = (whole[0] - umbra_U, whole[1] + umbra_E)
    T, corner = _corner_first(cells, S[1:], nP, dP, 2.0 * tol.AREA_CUT_EXTEND_RTOL * np.sqrt(area_Pc))
    # many cells (small ones) start with the low pair of rules, few with the high pair
    # (and so do the triangles they are cut into); at a coarse target, all start low
    start = int(len(T) <= tol.AREA_MANY_CELLS and atol < tol.AREA_LOW_RULES_TOLERANCE)
    # the least triangles left unevaluated within a share of atol (points.unevaluated)
    skip, skipped, weight = (
        unevaluated(triangle_areas(T), unoccluded_bounds(T, Pc, Qc), area_P, atol, st)
        if shortcuts and len(T) else (np.zeros(len(T), dtype=bool), 0.0, 0.0))
    T, corner = T[~skip], corner[~skip]
    area_Pc -= umbra_area + strip_slivers + skipped
    depth = np.zeros(len(T), dtype=int)
    rung = np.full(len(T), start)
    setup = (hidden_setup(Qc, S[1:]) if solid is None or inner is None
             else hidden_setup(Qc, S[1:], solid[1:], inner[1:]))
    # what the bound 0 <= hidden <= unoccluded may cost the pair (hidden_values)
    bound_atol = [tol.AREA_IMAGE_BUDGET_SHARE * atol]
    total_area = float(triangle_areas(T).sum())
    slivers, points = strip_slivers, 0
    # the triangles accepted: vertices, level, rung; per unit area of P, the high rule's
    # integral of the hidden part H, the rules' difference on H, the point values'
    # estimates, and the same two rules' integrals of U (the unoccluded point values)
    acc = {k: [] for k in ("T", "depth", "rung", "corner", "hi", "diff", "rnd", "hiU", "loU",
                           "lo", "rndU", "checked")}
    while True:
        T, depth, rung, corner, sl, pts = _levels(
            T, depth, rung, corner, nP, Qc, S, st, setup, atol, area_P, total_area,
            start, shortcuts, bound_atol, acc)
        slivers += sl
        points += pts
        # the rules' errors on U add up to the error of their sum over the emitter,
        # known exactly (the pair's closed form less the slivers', at most their area):
        # where the differences bounded every triangle's errors on H and on F_occ = U -
        # H, that sum is within the differences' (missed_U <= 0 below); where it is
        # not, the triangles are checked one by one against their own closed forms, and
        # those whose differences prove too small (or, while the sum still misses,
        # whose check cannot tell) are refined (rule_check.checked_rules)
        cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in acc.items()}
        lost = (slivers + max(area_Pc - total_area, 0.0)) / area_P + weight / area_P
        missed_U, dF = missed_unoccluded(cat, whole, lost)
        todo = np.flatnonzero(~cat["checked"].astype(bool))
        if missed_U <= 0 or not len(todo):
            break
        Ta = np.concatenate(acc["T"])
        again = checked_rules(Ta, cat, todo, missed_U, dF, nP, Qc, area_P, atol, total_area)
        a_rung, a_depth = cat["rung"].astype(int), cat["depth"].astype(int)
        if st is not None:
            st.checked_triangles += len(todo)
            st.refined_triangles += int(again.sum())
        keep = ~again
        for k in acc:
            acc[k] = [cat[k][keep] if k != "T" else Ta[keep]]
        if not again.any():
            break
        # the suspects start again: rung 0 takes the high pair, rung 1 is cut in four
        T, depth, rung, corner = refined(Ta[again], a_depth[again], a_rung[again],
                                          cat["corner"][again].astype(bool), start)
    cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in acc.items()}
    # what the checks leave unexplained (triangles at the last level): at least that much
    # of the rules' error is not in their differences, so it is added (a correction by
    # what is shown, not a bound: gunter2, pair (42, 15))
    missed_U = missed_unoccluded(cat, whole, lost)[0] if len(cat["hi"]) else 0.0
    # the slivers and the triangles unevaluated: the hidden part is between 0 and the
    # unoccluded point value, at most its bound (points.unoccluded_bound), so that its
    # integral over them is half that bound times their area, within as much (at 1, a
    # gunter2 pair's slivers took 1.66e-6, above the tolerance of 1e-6)
    half = 0.5 * (bound * slivers + weight) / area_P
    hidden = half + float(cat["hi"].sum())
    err = half + float((cat["diff"] + cat["rnd"]).sum())
    value = whole[0] - hidden
    err += max(area_Pc - total_area, 0.0) / area_P + max(missed_U, 0.0)   # cells lost
    if setup is not None and setup.sliver_area > 0:
        # Qc's slivers of rounding, left out of the hidden part (hidden_setup): theirs
        # is between 0 and their unoccluded point values
        err += unoccluded_bound(Pc, Qc, setup.sliver_area)
    return value, err + whole[1], points


#: False: the levels by numpy (:func:`_adaptive_levels`), the reference the compiled
#: ones are tested against (tests/test_area_pair_compiled.py).
COMPILED_LEVELS = True
#: False: every pair by :func:`_hidden_integral`'s steps, :mod:`.compiled_pair`'s reference.
COMPILED_PAIR = True


def _levels(T, depth, rung, corner, nP, Qc, S, st, setup, atol, area_P, total_area, start,
            shortcuts, bound_atol, acc):
    """:func:`_adaptive_levels`, compiled (``_core/levels.cpp``, the GIL released) where
    it can be: a set-up of blockers in front of Qc, and no point lost nor below 0 beyond
    its estimate on the way (the bound and the engine are the reference's); else, and
    without :data:`COMPILED_LEVELS`, the reference itself, from the same triangles.
    Returns the same."""
    if COMPILED_LEVELS and setup is not None and len(T):
        symmetric = atol >= tol.AREA_LOW_RULES_TOLERANCE
        rules_err = float(sum(float(d.sum()) for d in acc["diff"]))
        r = _compiled_adaptive_levels(
            T, depth.astype(np.int64), rung.astype(np.int64), corner.astype(bool), nP,
            receiver_frame(nP), area_P, total_area, atol, rules_err, start, LEVEL_RULES,
            symmetric, Qc, setup.corners, setup.q0, setup.nQ, setup.RQ, setup.V,
            setup.counts, setup.NK, setup.group, setup.extent, setup.parts,
            setup.part_counts, setup.lo, setup.hi,
            {k: getattr(tol, k) for k in LEVEL_TOLERANCES})
        if r[0]:
            Ta, da, ra, ca, hi, lo, diff, rnd, hiU, loU, rndU, slivers, points, back = r[1:]
            if st is not None and back:
                st.back_faces += int(back)
            for k, v in (("T", Ta), ("depth", da), ("rung", ra), ("corner", ca), ("hi", hi),
                         ("lo", lo), ("diff", diff), ("rnd", rnd), ("hiU", hiU), ("loU", loU),
                         ("rndU", rndU), ("checked", np.zeros(len(hi), dtype=bool))):
                acc[k].append(v)
            empty = np.zeros(0, dtype=int)
            return np.zeros((0, 3, 3)), empty, empty, np.zeros(0, dtype=bool), slivers, points
    return _adaptive_levels(T, depth, rung, corner, nP, Qc, S, st, setup, atol, area_P,
                            total_area, start, shortcuts, bound_atol, acc)


def _adaptive_levels(T, depth, rung, corner, nP, Qc, S, st, setup, atol, area_P,
                     total_area, start, shortcuts, bound_atol, acc):
    """:func:`_hidden_integral`'s adaptive rules: the triangles evaluated (their pairs
    of rules) and kept in a pool; while the pool's rules' differences with those accepted
    before exceed half of ``atol``, those with the largest differences are refined
    (:func:`~exactff.area.rules.budget_refined`) and their refinements evaluated and added; then the pool
    is accepted, appended to ``acc`` (see there). Returns the (empty) triangles left, the
    slivers' area (not evaluated) and the points used."""
    slivers = points = 0
    keys = ("T", "depth", "rung", "corner", "hi", "lo", "diff", "rnd", "hiU", "loU", "rndU",
            "area")
    pool = {k: [] for k in keys}
    # the differences accepted before this call
    before = float(sum(float(d.sum()) for d in acc["diff"]))
    while True:
        # a sliver (between nearly coincident events) is not evaluated: the hidden part
        # is between 0 and 1, so its integral is half the sliver's area, within as much
        area_t = triangle_areas(T) if len(T) else np.zeros(0)
        sliver = area_t / area_P <= tol.AREA_SLIVER_SHARE * atol
        slivers += float(area_t[sliver].sum())
        T, depth, rung, area_t = T[~sliver], depth[~sliver], rung[~sliver], area_t[~sliver]
        corner = corner[~sliver]
        if len(T):
            new, pts = _evaluated(T, rung, corner, nP, Qc, S, st, setup, atol, area_P,
                                  shortcuts, bound_atol)
            points += pts
            for k, v in (("T", T), ("depth", depth), ("rung", rung), ("corner", corner),
                         ("area", area_t), *new.items()):
                pool[k].append(v)
        cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in pool.items()}
        if not len(cat["diff"]):
            break
        # the refined: a triangle on the low pair takes the high pair, one on the high
        # pair is cut in four at its edges' midpoints (up to AREA_MAX_DEPTH)
        sel = budget_refined(cat["diff"], cat["area"], cat["depth"].astype(int),
                              cat["rung"].astype(int), before, atol, total_area)
        if not len(sel):
            break
        keep = np.ones(len(cat["diff"]), dtype=bool)
        keep[sel] = False
        pool = {k: [v[keep]] for k, v in cat.items()}
        T, depth, rung, corner = refined(cat["T"][sel], cat["depth"][sel].astype(int),
                                          cat["rung"][sel].astype(int),
                                          cat["corner"][sel].astype(bool), start)
    cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in pool.items()}
    if len(cat["diff"]):
        for k in keys[:-1]:
            acc[k].append(cat[k] if k != "T" else cat[k].reshape(-1, 3, 3))
        acc["checked"].append(np.zeros(len(cat["diff"]), dtype=bool))
    empty = np.zeros(0, dtype=int)
    return np.zeros((0, 3, 3)), empty, empty, np.zeros(0, dtype=bool), slivers, points


def _evaluated(T, rung, corner, nP, Qc, S, st, setup, atol, area_P, shortcuts, bound_atol):
    """The triangles T's rules (their rung's pair, and at a corner on the lower pair the
    third rule), all nodes in one call: per triangle, per unit area of P, the high rule's
    integral of the hidden part H, the low rule's, their difference (the high rule's
    error estimate), the nodes' estimates, and the two rules' integrals of the
    unoccluded point values U and their estimates. Returns them by name and the points
    used."""
    X, weights, groups = [], [], []
    # the small triangles off a corner, far from Qc and the blockers (rules.rule_pair)
    small = ~corner & (triangle_areas(T) / area_P <= tol.AREA_SMALL_TRIANGLE_SHARE)
    small &= setup is not None and atol >= tol.AREA_LOW_RULES_TOLERANCE
    if small.any():
        pieces = [Qc, *(V[:c] for V, c in zip(setup.V, setup.counts))]
        small[small] = far_triangles(T[small], pieces)
    for r, at_corner, in_small in ((r, c, m) for r in (0, 1) for c in (False, True)
                                   for m in (False, True)):
        sel = np.flatnonzero((rung == r) & (corner == at_corner) & (small == in_small))
        if len(sel):
            (Xl, Wl), (Xh, Wh) = rule_pair(T[sel], r, at_corner, atol, in_small)
            # at a corner on the lower pair, a third rule between the two
            Xm, Wm = (triangle_rule(T[sel], CORNER_MIDDLE_RULE) if r == 0 and at_corner
                      else (np.zeros((len(sel), 0, 3)), np.zeros((len(sel), 0))))
            X.append(np.concatenate([Xl, Xh, Xm], axis=1).reshape(-1, 3))
            weights.append(np.concatenate([Wl, Wh, Wm], axis=1).reshape(-1) / area_P)
            groups.append((sel, Wl, Wh, Wm, symmetric_degrees(r, at_corner, atol, in_small)
                           == tol.AREA_SYMMETRIC_DEGREES))   # the null rules' nodes
    X = np.concatenate(X)
    H, EH = hidden_values(X, nP, Qc, S[1:], st, atol=tol.AREA_IMAGE_BUDGET_SHARE * atol,
                          setup=setup, shortcuts=shortcuts,
                          weights=np.concatenate(weights), bound_atol=bound_atol)
    # the unoccluded point values at the same nodes, for the check of the rules'
    # differences (_hidden_integral)
    U, EU = (v[0] for v in point_values(X, nP, [Qc]))
    hi, lo, mid, rnd, hiU, loU, rndU = (np.empty(len(T)) for _ in range(7))
    spread, at = np.zeros(len(T)), 0
    for sel, Wl, Wh, Wm, null in groups:
        nl, nh = Wl.shape[1], Wl.shape[1] + Wh.shape[1]
        n = len(sel) * (nh + Wm.shape[1])
        Hg, EHg = H[at:at + n].reshape(len(sel), -1), EH[at:at + n].reshape(len(sel), -1)
        Ug, EUg = U[at:at + n].reshape(len(sel), -1), EU[at:at + n].reshape(len(sel), -1)
        at += n
        hi[sel], lo[sel] = (Wh * Hg[:, nl:nh]).sum(axis=1), (Wl * Hg[:, :nl]).sum(axis=1)
        # the third rule's value, where there is one (else the low rule's)
        mid[sel] = (Wm * Hg[:, nh:]).sum(axis=1) if Wm.shape[1] else lo[sel]
        spread[sel] = symmetric_null_spread(Hg[:, :nh], triangle_areas(T[sel])) if null else 0
        hiU[sel], loU[sel] = (Wh * Ug[:, nl:nh]).sum(axis=1), (Wl * Ug[:, :nl]).sum(axis=1)
        # the rules' nodes' estimates: they bound what the point values' errors can
        # hide of the rules' differences
        rnd[sel] = ((Wh * EHg[:, nl:nh]).sum(axis=1) + (Wl * EHg[:, :nl]).sum(axis=1)
                    + (Wm * EHg[:, nh:]).sum(axis=1))
        rndU[sel] = (Wh * EUg[:, nl:nh]).sum(axis=1) + (Wl * EUg[:, :nl]).sum(axis=1)
    hi, lo, mid, rnd, hiU, loU, rndU, spread = (
        v / area_P for v in (hi, lo, mid, rnd, hiU, loU, rndU, spread))
    # the high rule's error: the low rule's difference from it, at a corner on the lower
    # pair also the third rule's, on the symmetric pair of degrees 4 and 8 also its null
    # rules' spread: two rules can agree by chance far closer than either is to the
    # integral (AREA_CORNER_MIDDLE_ORDER, AREA_NULL_RULE_FACTOR;
    # test_gunter1_row_17_without_shortcuts_within_its_estimates)
    diff = np.maximum(np.maximum(np.abs(hi - lo), np.abs(hi - mid)),
                      tol.AREA_NULL_RULE_FACTOR * spread)
    return dict(hi=hi, lo=lo, diff=diff, rnd=rnd, hiU=hiU, loU=loU, rndU=rndU), H.size
