"""The curved visibility events of an occluded pair: where, seen from a point of the
emitter, the images of two blockers' edges cross on an edge of the receiver (three
mutually skew edges, whose common transversals form a quadric: a conic in the emitter's
plane), traced and cut along as chords (docs/explanation/area-form-factors.md). The
straight events are :mod:`exactff.area.events`'. The curves are traced compiled
(:mod:`exactff.area._pair`, ``_core/curved.cpp``, the GIL released); the numpy path here
is their reference (``compiled=False``, tests/test_area_pair_compiled.py).
"""

import numpy as np

from .. import _tolerances as tol
from ..geometry import cross, rotate, unit_normal
from ._pair import curved_event_lines as _compiled_curved_event_lines

__all__ = ["curved_event_lines"]

#: the tolerances the compiled curves take (_core/curved.cpp)
_CURVED_TOLERANCES = ("AREA_HULL_RTOL", "AREA_EVENT_PARALLEL", "AREA_CUT_EXTEND_RTOL",
                      "AREA_CURVED_EVENT_RTOL", "AREA_CURVED_EVENT_SAMPLES",
                      "AREA_CURVED_EVENT_BISECTIONS", "AREA_CURVED_MAX_TRIPLES",
                      "AREA_CURVED_CHORD_SPLIT", "AREA_CURVED_CHORD_HALVINGS",
                      "AREA_EVENT_ROWS_PER_CALL")


def _inner(a, b):
    """``a . b`` over the last axis (of length 3)."""
    return np.einsum("...i,...i->...", a, b)


def _transversal(y, a0, da, b0, db, nP, dP):
    """For points y (..., 3) and lines a0 + v da, b0 + v db: the line through y meeting
    both (the two planes through y and each line meet in it), where it meets P's plane
    ``nP . x = dP`` (x, NaN where parallel), and whether it meets both segments
    (``0 <= v <= 1``) between x and y."""
    d = cross(cross(a0 - y, da), cross(b0 - y, db))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (dP - _inner(y, nP)) / _inner(d, nP)
        x = y + t[..., None] * d
        ok = np.isfinite(t)
        for e0, de in ((a0, da), (b0, db)):
            # the points of closest approach of y + u d and e0 + v de (they meet)
            w = y - e0
            A, B, C, D, E = _inner(d, d), _inner(d, de), _inner(de, de), _inner(d, w), _inner(de, w)
            den = A * C - B * B
            u, v = (B * E - C * D) / den, (A * E - B * D) / den
            ok &= (v >= 0) & (v <= 1) & (u / t > 0) & (u / t < 1)
    return x, ok


def _skew(p0, dp, r0, dr, near):
    """Whether the lines ``p0 + u dp`` and ``r0 + v dr`` (..., 3) are skew: their
    distance ``|(r0 - p0) . (dp x dr)| / |dp x dr|`` more than ``near`` (parallel lines:
    never)."""
    n = cross(dp, dr)
    return np.abs(_inner(r0 - p0, n)) > near * np.sqrt(_inner(n, n))


def _unhidden(X, Y, B, near, own=None):
    """Per point pair, whether the open segment from X to Y (n, 3) crosses none of the
    polygons B in its interior by more than ``near`` (then the two edges the line
    touches may bound what is hidden there), but for each pair's own polygons ``own``
    (n, k) of indices into B (the polygons whose edges the line touches: it meets their
    planes on those edges, and any crossing of their interiors is rounding, as where
    the line grazes a plane)."""
    free = np.ones(len(X), dtype=bool)
    for i, A in enumerate(B):
        n = unit_normal(A)
        hX, hY = _inner(X - A[0], n), _inner(Y - A[0], n)
        hit = (hX * hY < 0) & (np.minimum(np.abs(hX), np.abs(hY)) > near)
        if own is not None:
            hit &= np.all(own != i, axis=1)
        if not hit.any():
            continue
        p = X[hit] + (hX[hit] / (hX[hit] - hY[hit]))[:, None] * (Y[hit] - X[hit])
        keep = [a for a in range(3) if a != int(np.argmax(np.abs(n)))]
        p2, A2 = p[:, keep], A[:, keep]
        B2 = np.roll(A2, -1, axis=0)
        # crossing number of a ray in +u, and the distance to the nearest edge
        u, v = p2[:, None, 0], p2[:, None, 1]
        spans = (A2[None, :, 1] > v) != (B2[None, :, 1] > v)
        with np.errstate(divide="ignore", invalid="ignore"):
            at_u = A2[None, :, 0] + (v - A2[None, :, 1]) * (B2[None, :, 0] - A2[None, :, 0]) / (
                B2[None, :, 1] - A2[None, :, 1])
        inside = (spans & (at_u > u)).sum(axis=1) % 2 == 1
        e = B2 - A2
        w = p2[:, None, :] - A2[None]
        t = np.clip((w * e[None]).sum(axis=2) / np.maximum((e * e).sum(axis=1), 1e-300), 0, 1)
        dist = np.linalg.norm(w - t[..., None] * e[None], axis=2).min(axis=1)
        idx = np.flatnonzero(hit)
        free[idx[inside & (dist > near)]] = False
    return free


def curved_event_lines(S, Qc, nP, dP, R, c, radius, atol=0.0, solid=None, st=None,
                       compiled=True):
    """The curved visibility events of P's plane as polylines: where, seen from x, the
    images of two edges of different blockers cross on an edge of Qc (three mutually
    skew edges: the lines meeting all three form a quadric, which meets P's plane in a
    conic). Across such a curve the hidden part is continuous with its gradient, and
    its second derivative jumps (the region's corner crosses Qc's edge: a triangle of
    area ~ t^2 gained or lost), as across a vertex-edge event, but
    :func:`~exactff.area.events.event_lines` gives lines only; a triangle a curve crosses
    holds a kink that two rules can agree on far closer than either is to the integral
    (on the 106-surface box of issue 49, pair (59, 20), a cube's vertical edge and
    another cube's top edge crossing on the ceiling square's edge: the degree-4 and
    degree-8 rules 1.3e-8 off, 2.4e-10 apart).

    Each curve is traced along Qc's edge, ``y = q0 + s (q1 - q0)``: the line through y
    meeting both blocker edges (the two planes through y and each edge meet in it) meets
    P's plane at x(s). Whether it is an event there (the line meets both edges between
    x and y) changes only at a few s found in closed form (the line passes through an
    edge's end, or through the point where the other edge meets P's plane, or is
    parallel to an edge or to P's plane, or y is nearest an edge's line), so it is
    decided at the midpoints between those and ``AREA_CURVED_EVENT_SAMPLES`` steps of s;
    an end where the curve stops being an event is lengthened by
    ``AREA_CUT_EXTEND_RTOL`` of ``radius`` across the line where it stops (a vertex-edge
    event; what sticks out is a dangle that the noding drops), and an end beyond 4
    ``radius`` of c is brought in to the disk's edge by bisection. Each piece is cut
    into chords within ``AREA_CURVED_EVENT_RTOL`` of ``radius`` (or ``sqrt(atol)`` of
    it, where less) of the curve (its midpoint's distance from the chord, which falls as
    the square of the steps), each step whose own midpoint lies farther from its chord
    (by more than ``AREA_CURVED_CHORD_SPLIT`` of the allowed deviation) halved, up to
    ``AREA_CURVED_CHORD_HALVINGS`` times; the chords where another blocker crosses the line of
    sight from x to y (within its rounding: the crossing is then inside what is hidden)
    are left out, but for one chord either side of those kept. Edges of one polygon, of
    one convex solid (``solid``, as for :func:`~exactff.area.events.event_lines`: their
    images united are the solid's), whose lines meet or are coplanar (within the
    scene's rounding: a shared end, a T, a crossing; the transversals then pass through
    the common point or lie in the common plane, and trace straight lines, the
    vertex-edge events) or parallel (no crossing of their images) make no curve, an
    edge two faces share is taken once (and its chords left out where, seen from x, the
    two faces' images lie either side of its image: it is then inside what they hide),
    and an edge whose line meets Qc's edge's or is parallel to it, lies wholly behind P's
    plane or outside the wedge of the planes through Qc's edge that support the square
    around the disk (the lines from P to that edge lie in it) makes none with that
    edge. Beyond
    ``AREA_CURVED_MAX_TRIPLES`` triples of edges left after that, none is traced (a
    pair behind many blockers: the rules then meet the curves uncut, as before), counted
    in ``st.curved_skipped``. ``st.curved_events`` counts the curves cut along (``st``:
    an :class:`~exactff.area.row.AreaStats`, optional).

    ``compiled`` (default): traced by :mod:`exactff.area._pair` (``_core/curved.cpp``,
    the same steps in the same order); else by numpy here, the reference the compiled
    chords are tested against (``tests/test_area_pair_compiled.py``: the same chords to
    rounding on every occluded pair of gunter1 and the 106-surface box).

    Returns the chords (m, 2, 2) in P's frame ``R`` about ``c``, as
    :func:`~exactff.area.events.event_lines`.

    Examples
    --------
    A ceiling square, a vertical edge (of a wall strip) and a horizontal one (of a
    plate), mutually skew: the curve on the wall x = 0.

    >>> from exactff.geometry import receiver_frame
    >>> Q = np.array([[2, 2, 5], [2, 3, 5], [3, 3, 5], [3, 2, 5]], float)
    >>> W = np.array([[.5, 1.5, .5], [.5, 1.5, 1.5], [.4, 1.6, 1.5], [.4, 1.6, .5]])
    >>> K = np.array([[1.4, 2.2, 3.8], [2.4, 2.2, 3.8], [2.4, 2.1, 3.8], [1.4, 2.1, 3.8]])
    >>> nP = np.array([1.0, 0, 0])
    >>> C = curved_event_lines([Q, W, K], Q, nP, 0.0, receiver_frame(nP), np.zeros(3), 2.0)
    >>> len(C) > 10
    True
    >>> C0 = curved_event_lines([Q, W, K], Q, nP, 0.0, receiver_frame(nP), np.zeros(3), 2.0,
    ...                         compiled=False)
    >>> C.shape == C0.shape and bool(np.allclose(C, C0, rtol=0, atol=1e-12))
    True
    """
    if compiled:
        W = np.concatenate([np.asarray(A, dtype=float) for A in S])
        start = np.concatenate([[0], np.cumsum([len(A) for A in S])])
        sol = (np.zeros(0, dtype=np.int64) if solid is None
               else np.asarray(solid, dtype=np.int64))
        segs, events, skipped = _compiled_curved_event_lines(
            W=W, start=start, solid=sol, Qc=np.asarray(Qc, dtype=float),
            nP=np.asarray(nP, dtype=float), dP=float(dP), frame=np.asarray(R, dtype=float),
            c=np.asarray(c, dtype=float), radius=float(radius), atol=float(atol),
            tol={k: getattr(tol, k) for k in _CURVED_TOLERANCES})
        if st is not None:
            st.curved_events += events
            st.curved_skipped += int(skipped)
        return segs
    B = [np.asarray(A, dtype=float) for A in S[1:]]
    Qc = np.asarray(Qc, dtype=float)
    none = np.zeros((0, 2, 2))
    if len(B) < 2:
        return none
    e0 = np.concatenate(B)
    e1 = np.concatenate([np.roll(A, -1, axis=0) for A in B])
    owner = np.repeat(np.arange(len(B)), [len(A) for A in B])
    group = (np.asarray(solid)[1:][owner] if solid is not None
             else np.full(len(owner), -1))
    ia, ib = np.triu_indices(len(e0), 1)
    de = e1 - e0
    size = float(np.ptp(np.concatenate([e0, Qc]), axis=0).max())
    near = tol.AREA_HULL_RTOL * size
    # two edges' lines skew (farther apart than near), not parallel: lines that meet
    # (a shared end, a T, a crossing) or are coplanar trace straight lines, the
    # vertex-edge events of event_lines
    keep = ((owner[ia] != owner[ib]) & ~((group[ia] >= 0) & (group[ia] == group[ib]))
            & _skew(e0[ia], de[ia], e0[ib], de[ib], near)
            & (np.linalg.norm(cross(de[ia], de[ib]), axis=1)
               > tol.AREA_EVENT_PARALLEL * np.linalg.norm(de[ia], axis=1)
               * np.linalg.norm(de[ib], axis=1)))
    # an edge two faces share (a box's) once: its copies would trace the same curve;
    # and of such an edge, a vertex of each face off it (where, seen from x, the two
    # faces' images lie either side of the edge's, the edge is inside what they hide)
    d = e1 - e0
    swap = d[np.arange(len(d)), np.argmax(d != 0, axis=1)] < 0   # from the least end
    rows = np.where(swap[:, None], np.hstack([e1, e0]), np.hstack([e0, e1]))
    cid = np.unique(rows, axis=0, return_inverse=True)[1].ravel()
    ia, ib = ia[keep], ib[keep]
    lo_, hi_ = np.minimum(cid[ia], cid[ib]), np.maximum(cid[ia], cid[ib])
    first = np.unique(lo_ * (int(cid.max()) + 1) + hi_, return_index=True)[1]
    first = np.sort(first[lo_[first] != hi_[first]])
    ia, ib = ia[first], ib[first]
    count = np.bincount(cid)
    start = np.concatenate([[0], np.cumsum([len(A) for A in B])[:-1]])
    nv = np.array([len(A) for A in B])
    off_edge = e0[start[owner] + (np.arange(len(e0)) - start[owner] + 2) % nv[owner]]
    order = np.argsort(cid, kind="stable")
    pos = np.concatenate([[0], np.cumsum(count)[:-1]])
    shared = count == 2
    OA = off_edge[order[pos]]
    OB = off_edge[order[np.minimum(pos + 1, len(order) - 1)]]
    q0, dq = Qc, np.roll(Qc, -1, axis=0) - Qc
    # per edge of Qc, the blocker edges that may meet a line from P to it: not wholly
    # behind P's plane (within its disk), nor outside the wedge of the planes through
    # the edge that support the disk's square around P (the lines from P to the edge
    # lie in it)
    Pr = c + radius * np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]]) @ R[:2]
    behind = np.maximum(_inner(e0, nP), _inner(e1, nP)) <= dP + near
    N = cross(dq[:, None], Pr[None] - q0[:, None])                    # (q, 4, 3)
    side = np.einsum("qcd,pd->qcp", N, Pr) - _inner(N, q0[:, None])[..., None]
    m = near * np.linalg.norm(N, axis=2)
    N = np.where(np.all(side <= m[..., None], axis=2)[..., None], -N, N)
    support = np.all(side <= m[..., None], axis=2) | np.all(side >= -m[..., None], axis=2)
    d0 = np.einsum("qcd,ed->qce", N, e0) - _inner(N, q0[:, None])[..., None]
    d1 = np.einsum("qcd,ed->qce", N, e1) - _inner(N, q0[:, None])[..., None]
    out = behind[None] | np.any(support[..., None] & (d0 < -m[..., None]) & (d1 < -m[..., None]),
                                axis=1)                                # (q, edges)
    # and a blocker edge whose line meets Qc's edge's (or is parallel to it) makes no
    # curve with it: the three lines are to be mutually skew
    out |= ~_skew(q0[:, None], dq[:, None], e0[None], de[None], near)
    triples = []
    for q in range(len(Qc)):
        sel = ~out[q, ia] & ~out[q, ib]
        triples.append((np.full(int(sel.sum()), q), ia[sel], ib[sel]))
    iq, ia, ib = (np.concatenate(v) for v in zip(*triples))
    if not len(iq):
        return none
    if len(iq) > tol.AREA_CURVED_MAX_TRIPLES:
        # too many to trace (their chords would swamp the arrangement): the rules meet
        # these kinks uncut, as before, counted
        if st is not None:
            st.curved_skipped += 1
        return none
    reach2 = (4.0 * radius) ** 2

    def at(k, s):
        """x(s), whether it is an event there (not counting the disk) and whether x lies
        within 4 radius of c, for the triples k (each a row of s)."""
        x, ok = _transversal(q0[iq[k]][:, None] + s[..., None] * dq[iq[k]][:, None],
                             e0[ia[k]][:, None], de[ia[k]][:, None],
                             e0[ib[k]][:, None], de[ib[k]][:, None], nP, dP)
        with np.errstate(invalid="ignore"):
            return x, ok, _inner(x - c, x - c) <= reach2

    def far_at(k, s):
        """The squared distance of x(s) from c (NaN where x is at infinity), for the
        triples k (one s each)."""
        y = q0[iq[k]] + s[:, None] * dq[iq[k]]
        d = cross(cross(e0[ia[k]] - y, de[ia[k]]), cross(e0[ib[k]] - y, de[ib[k]]))
        with np.errstate(divide="ignore", invalid="ignore"):
            x = y + ((dP - _inner(y, nP)) / _inner(d, nP))[:, None] * d - c
            return _inner(x, x)

    def breaks(k):
        """The s where the curve of each triple k may start or stop being an event:
        the line through y passes through an end of a blocker edge, or through the
        point where the other edge meets P's plane, or is parallel to an edge or to
        P's plane, or y is the point of Qc's edge nearest an edge's line."""
        Q0, DQ = q0[iq[k]], dq[iq[k]]
        A0, DA, B0, DB = e0[ia[k]], de[ia[k]], e0[ib[k]], de[ib[k]]
        out = []
        with np.errstate(divide="ignore", invalid="ignore"):
            def through(p, l0, dl):
                n = cross(p - l0, dl)
                out.append(-_inner(Q0 - l0, n) / _inner(DQ, n))
            for L0, DL, M0, DM in ((A0, DA, B0, DB), (B0, DB, A0, DA)):
                through(L0, M0, DM)
                through(L0 + DL, M0, DM)
                through(L0 + ((dP - _inner(L0, nP)) / _inner(DL, nP))[:, None] * DL, M0, DM)
                out.append(_inner(cross(M0 - Q0, DM), DL) / _inner(cross(DQ, DM), DL))
                w = Q0 - L0
                a_, b_, c_, d_, e_ = _inner(DQ, DQ), _inner(DQ, DL), _inner(DL, DL), _inner(DQ, w), _inner(DL, w)
                out.append((b_ * e_ - c_ * d_) / (a_ * c_ - b_ * b_))
            # the line through y parallel to P's plane: d(s) . nP = c0 + c1 s + c2 s^2
            A0v, A1v, B0v, B1v = cross(A0 - Q0, DA), cross(DQ, DA), cross(B0 - Q0, DB), cross(DQ, DB)
            c0 = _inner(cross(A0v, B0v), nP)
            c1 = -_inner(cross(A0v, B1v) + cross(A1v, B0v), nP)
            c2 = _inner(cross(A1v, B1v), nP)
            root = np.sqrt(np.maximum(c1 * c1 - 4 * c2 * c0, 0.0))
            out += [(-c1 - root) / (2 * c2), (-c1 + root) / (2 * c2), -c0 / c1]
        return np.clip(np.nan_to_num(np.stack(out, axis=1), nan=0.0), 0.0, 1.0)

    G = tol.AREA_CURVED_EVENT_SAMPLES
    grid = np.linspace(0.0, 1.0, G + 1)
    k_all = np.arange(len(iq))
    # the triples in batches (the temporaries bounded)
    per = max(1, tol.AREA_EVENT_ROWS_PER_CALL // (3 * G + 48))
    pieces = []                  # (triple, s_lo, s_hi, lengthen lo, lengthen hi)
    for k in np.array_split(k_all, max(1, len(k_all) // per)):
        # between the breaks (and the steps of the grid) the curve is an event or not
        # throughout, but for the disk
        s = np.sort(np.concatenate([np.broadcast_to(grid, (len(k), G + 1)), breaks(k)],
                                   axis=1), axis=1)
        mid = 0.5 * (s[:, :-1] + s[:, 1:])
        _, ok, inside = at(k, mid)
        ok &= inside & (s[:, 1:] > s[:, :-1])
        if not ok.any():
            continue
        t, j = np.nonzero(ok)
        # an end shared with the next event interval is a node of the polyline; any
        # other is lengthened across the line where the curve stops (or leaves the disk)
        prev = np.zeros_like(ok)
        prev[:, 1:] = ok[:, :-1]
        after = np.zeros_like(ok)
        after[:, :-1] = ok[:, 1:]
        kk, lo, hi, m = k[t], s[t, j], s[t, j + 1], mid[t, j]
        ext_lo, ext_hi = ~prev[t, j], ~after[t, j]
        # an end outside the disk: the disk's edge by bisection from the midpoint (both
        # ends of every piece at once; only x is needed)
        ends = np.concatenate([lo, hi])
        pk, pm = np.concatenate([kk, kk]), np.concatenate([m, m])
        out = ~(far_at(pk, ends) <= reach2)
        if out.any():
            good, bad, ko = pm[out], ends[out], pk[out]
            far = far_at(ko, good)
            for _ in range(tol.AREA_CURVED_EVENT_BISECTIONS):
                if np.all(far >= (2.0 * radius) ** 2):
                    break                        # every end outside the emitter
                half = 0.5 * (good + bad)
                h_far = far_at(ko, half)
                h_in = h_far <= reach2
                good, bad = np.where(h_in, half, good), np.where(h_in, bad, half)
                far = np.where(h_in, h_far, far)
            ends[out] = good
            lo, hi = ends[:len(lo)], ends[len(lo):]
            ext_lo &= ~out[:len(lo)]
            ext_hi &= ~out[len(lo):]
        pieces.append((kk, lo, hi, ext_lo, ext_hi))
    if not pieces:
        return none
    k, lo, hi, ext_lo, ext_hi = (np.concatenate(v) for v in zip(*pieces))
    # the chords: each piece cut in steps of s so that the midpoint's distance from its
    # chord (which falls as the square of the step) is within the allowed deviation
    dev_allowed = radius * min(tol.AREA_CURVED_EVENT_RTOL, float(np.sqrt(atol)) or np.inf)
    X3 = at(k, np.stack([lo, 0.5 * (lo + hi), hi], axis=1))[0]
    with np.errstate(invalid="ignore", over="ignore"):
        X2 = rotate(X3 - c, R)[..., :2]
    chord = X2[:, 2] - X2[:, 0]
    off = X2[:, 1] - X2[:, 0]
    length = np.hypot(chord[:, 0], chord[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        dev = np.abs(chord[:, 0] * off[:, 1] - chord[:, 1] * off[:, 0]) / length
    dev = np.nan_to_num(np.where(length > 0, dev, np.hypot(off[:, 0], off[:, 1])), nan=0.0)
    steps = np.clip(np.ceil(np.sqrt(dev / dev_allowed)), 1, 4096).astype(int)
    # every piece's points in one array: piece i has steps[i] + 1 of them
    first = np.concatenate([[0], np.cumsum(steps + 1)[:-1]])
    piece = np.repeat(np.arange(len(steps)), steps + 1)
    j = np.arange(len(piece)) - first[piece]
    s = lo[piece] + (hi[piece] - lo[piece]) * (j / steps[piece])
    s = np.where(j == steps[piece], hi[piece], np.where(j == 0, lo[piece], s))

    def plane_points(kk, ss):
        """x(s) of the triples kk and, in P's frame about c, its two coordinates."""
        x = at(kk, ss[:, None])[0][:, 0]
        with np.errstate(invalid="ignore", over="ignore"):
            return x, rotate(x - c, R)[..., :2]

    # the steps whose own midpoint lies farther from their chord than
    # AREA_CURVED_CHORD_SPLIT of the allowed deviation halved, up to
    # AREA_CURVED_CHORD_HALVINGS times (the piece's midpoint says little where its
    # curvature is uneven: chords were up to 2.03 times the allowed deviation from the
    # curve); a step's decision rests on its ends alone, so it is the compiled one's
    Y = plane_points(k[piece], s)[1]
    active = np.flatnonzero(piece[:-1] == piece[1:])     # each step by its first point
    for _ in range(tol.AREA_CURVED_CHORD_HALVINGS):
        if not len(active):
            break
        sm = 0.5 * (s[active] + s[active + 1])
        Ym = plane_points(k[piece[active]], sm)[1]
        chord, off = Y[active + 1] - Y[active], Ym - Y[active]
        length = np.hypot(chord[:, 0], chord[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            dev = np.abs(chord[:, 0] * off[:, 1] - chord[:, 1] * off[:, 0]) / length
        dev = np.nan_to_num(np.where(length > 0, dev, np.hypot(off[:, 0], off[:, 1])),
                            nan=0.0)
        split = np.flatnonzero(dev > tol.AREA_CURVED_CHORD_SPLIT * dev_allowed)
        if not len(split):
            break
        at_ = active[split] + 1
        s, piece = np.insert(s, at_, sm[split]), np.insert(piece, at_, piece[active[split]])
        Y = np.insert(Y, at_, Ym[split], axis=0)
        left = active[split] + np.arange(len(split))
        active = np.sort(np.concatenate([left, left + 1]))
    steps = np.bincount(piece, minlength=len(steps)) - 1
    first = np.concatenate([[0], np.cumsum(steps + 1)[:-1]])
    X, Y = plane_points(k[piece], s)
    # the chords where the line of sight from x to y crosses no blocker (and within one
    # chord of such a point, so that the curve goes on across the event where it is
    # hidden): with a blocker between, the images' crossing is not on the hidden
    # region's boundary
    # the polygons whose edges each point's line touches: each copy's (an edge two
    # faces share bounds both)
    copies = [owner[order[pos[cid[e]] + np.where(count[cid[e]] > 1, j, 0)]]
              for e in (ia[k[piece]], ib[k[piece]]) for j in (0, 1)]
    seen = _unhidden(X, q0[iq[k[piece]]] + s[:, None] * dq[iq[k[piece]]], B, near,
                     np.stack(copies, axis=1))
    for e in (ia[k[piece]], ib[k[piece]]):
        # an edge two faces share whose faces' images lie either side of its own
        n = cross(de[e], X - e0[e])
        sa, sb = _inner(OA[cid[e]] - e0[e], n), _inner(OB[cid[e]] - e0[e], n)
        m = near * np.linalg.norm(n, axis=1) * np.linalg.norm(de[e], axis=1)
        with np.errstate(invalid="ignore"):
            seen &= ~(shared[cid[e]] & (np.minimum(np.abs(sa), np.abs(sb)) > m) & (sa * sb < 0))
    last = first + steps                     # each piece's last point
    chord = np.ones(len(piece) - 1, dtype=bool)
    chord[last[:-1]] = False                 # no chord from one piece to the next
    seen_c = (seen[:-1] | seen[1:]) & chord
    grow_c = seen_c.copy()
    grow_c[1:] |= seen_c[:-1]
    grow_c[:-1] |= seen_c[1:]
    grow_c &= chord
    # an end where the curve stops being an event lengthened across that line
    step = tol.AREA_CUT_EXTEND_RTOL * radius
    for end, nxt, ext in ((first, first + 1, ext_lo), (last, last - 1, ext_hi)):
        d = Y[end] - Y[nxt]
        norm = np.hypot(d[:, 0], d[:, 1])
        grow = ext & (norm > 0)
        Y[end[grow]] += step * d[grow] / norm[grow, None]
    idx = np.flatnonzero(grow_c)
    segs = np.stack([Y[idx], Y[idx + 1]], axis=1)
    segs = segs[np.all(np.isfinite(segs), axis=(1, 2))]
    if st is not None:
        st.curved_events += len(np.unique(k[piece[idx]]))
    return segs
