"""Integration of visible pieces: each piece's rings lifted from its chart to exact
great-circle arcs and integrated by the sector form (or Eq. 3's stable form), with
refinement, long double and mpmath where a bound misses the tolerance; or measured by their solid angles (the
spherical factors)."""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..kernel import TWO_PI, TWO_PI_LONG, clipped_sector_sums, eq3_ring_sums, solid_angle_sums
from ..rings import polygon_parts, repack, shapely_rings
from .charts import CHARTS, lift

__all__ = ["rings_long_double", "pieces_form_factors", "pieces_solid_angles"]


def rings_long_double(D, start, count):
    """Absolute image areas / pi (form factors) of closed rings of directions, and their
    error estimates, in long double arithmetic."""
    u = tol.LONGDOUBLE_EPS
    idx, owner, first, nxt = repack(start, count)
    Dl = D[idx].astype(np.longdouble)
    A0 = Dl[first]
    S, mags, errs = clipped_sector_sums(A0, Dl - A0[owner], nxt, owner, len(start), eps=u)
    val = (np.abs(S) / TWO_PI_LONG).astype(float)
    # the estimate in long double, and the value's rounding to double (u val)
    return val, ((tol.C1 * u * mags + errs) / TWO_PI_LONG).astype(float) + tol.EPS * val


def pieces_form_factors(pieces, m, tolerance=None, owner=None, integrator="sector",
                        refiner=None, stats=None):
    """Form factors of visible pieces, summed per fragment, with error estimates.

    Every ring of a piece is a closed chain of great-circle arcs (its chart coordinates
    lifted to directions ``u e_u + v e_v + e_w``). Its sector sum, evaluated in offset
    form by the kernel's own ``clipped_sector_sums`` (an edge on the horizon becomes its
    horizon arc), is twice the signed area of its image on the base disk. Exterior rings
    add and holes subtract the absolute values, so the result does not depend on ring
    orientation.

    ``integrator="eq3"`` integrates every ring with the paper's Eq. 3 (corrected, with
    monotone-span splitting) in its stable form instead
    (:func:`exactff.kernel.eq3_ring_sums`, in the same offset form), at every tier.

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
    estimate (``stats["unrefined_rings"]``). Where mpmath stops at ``MP_MAX_DPS``
    digits before two evaluations agree, the ring keeps the difference of the two as
    its estimate (``stats["refine_mp_unconverged"]``). Whether the summed values meet
    the tolerance is the caller's check (:func:`exactff.visibility.visible_form_factors`,
    by :func:`exactff.errors.misses_tolerance`).

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,))
        Form factors and error estimates per fragment.
    """
    import mpmath

    st = stats if stats is not None else {}
    for key in ("refined_rings", "refined_rings_mp", "unrefined_rings",
                "refine_disagreements", "refine_mp_unconverged"):
        st.setdefault(key, 0)
    F = np.zeros(m)
    err = np.zeros(m)
    if not pieces:
        return F, err
    # twice the signed image area of rings in offset form: the sector form or Eq. 3
    ring_sums = eq3_ring_sums if integrator == "eq3" else clipped_sector_sums
    charts = []
    for ci, chart in enumerate(CHARTS):
        sel = [(k, g) for k, c, g in pieces if c == ci]
        if not sel:
            continue
        frag = np.array([k for k, _ in sel])
        geoms = np.array([g for _, g in sel], dtype=object)
        polys, poly_of = polygon_parts(geoms)
        if len(polys) == 0:
            continue
        coords, ring_of, start, count, nxt, is_hole, ring_poly = shapely_rings(polys)
        D = lift(coords, chart)
        A0 = D[start]
        S, mags, errs = ring_sums(A0, D - A0[ring_of], nxt, ring_of, len(start))
        val = np.abs(S) / TWO_PI
        e_ring = (tol.C1 * tol.EPS * mags + errs) / TWO_PI
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

    if tolerance is not None and refiner is not None and charts:
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
            vsel, ring_sub, st_sub, nxt_sub = repack(c["start"][rsel], c["count"][rsel])
            frag_v = c["frag"][c["geom"][rsel]][ring_sub]
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                rv, re, ok, lab = refiner.refine_ld(c["ci"], c["chart"], c["coords"][vsel],
                                                    nxt_sub, ring_sub, len(rsel), frag_v,
                                                    integrator=integrator)
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
                    rv, re, converged = refiner.refine_mp(
                        c["chart"], c["coords"][vsel[sl]], label[sl], statics, point[sl],
                        drop[sl], cut[k], tolerance, integrator=integrator)
                    # stopped at MP_MAX_DPS: the difference of its last two evaluations
                    # is its estimate, which the caller checks with the others
                    st["refine_mp_unconverged"] += int(not converged)
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


def pieces_solid_angles(pieces, m):
    """Solid angles of visible pieces, summed per fragment, with error bounds.

    A piece is a straight-edged region of a gnomonic chart; lifting its vertices
    ``(u, v)`` to the directions ``u e_u + v e_v + e_w`` gives a planar polygon in the
    plane ``e_w . d = 1`` (which misses the point), whose solid angle is exactly the
    piece's. Each ring is measured in the chart's own orthonormal frame, as the points
    ``(u, v, 1)`` with offsets ``(du, dv, 0)`` from its first vertex, by Van Oosterom and
    Strackee's fan (:func:`exactff.kernel.solid_angle_sums`); exterior rings add and
    holes subtract the absolute values.

    Each bound is the rounding of the ring's fan plus the clipper's geometry: the
    ring's perimeter in chart units times ``CHART_VERTEX_ERROR`` (the solid angle per
    unit of chart area, ``(1 + u^2 + v^2)^(-3/2)``, is at most 1), and the rounding of
    the offsets (a few ulps of the chart's unit per vertex, well inside it). No
    refinement: the bounds say what the clipper's double-precision vertices allow.

    Returns
    -------
    (ndarray of shape (m,), ndarray of shape (m,))
        Solid angles (steradians) and error bounds per fragment.
    """
    W = np.zeros(m)
    err = np.zeros(m)
    if not pieces:
        return W, err
    frag = np.array([k for k, _, _ in pieces])
    geoms = np.array([g for _, _, g in pieces], dtype=object)
    polys, poly_of = polygon_parts(geoms)
    if len(polys) == 0:
        return W, err
    coords, ring_of, start, count, nxt, is_hole, ring_poly = shapely_rings(polys)
    A0 = np.column_stack([coords[start], np.ones(len(start))])
    E = np.column_stack([coords - coords[start][ring_of], np.zeros(len(coords))])
    S, e_ring = solid_angle_sums(A0, E, nxt, ring_of, len(start))
    perimeter = np.bincount(ring_of, weights=np.hypot(*(coords[nxt] - coords).T),
                            minlength=len(start))
    e_ring = e_ring + perimeter * (tol.CHART_VERTEX_ERROR + 4 * tol.EPS)
    owner = frag[poly_of[ring_poly]]
    W += np.bincount(owner, weights=np.where(is_hole, -np.abs(S), np.abs(S)), minlength=m)
    err += np.bincount(owner, weights=e_ring, minlength=m)
    return W, err
