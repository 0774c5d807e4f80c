"""The emitter cut along its visibility events: the lines of the emitter's plane across
which the hidden part of a receiver may lose smoothness (vertex-edge events between the
receiver and its blockers, and the planes of the polygons), and the cells between them,
triangulated, on which the adaptive rules integrate a smooth function
(docs/explanation/area-form-factors.md).
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..geometry import cross, plane_frame, rotate
from ..rings import successors
from ._pair import cut_cells as _compiled_cut_cells
from ._pair import event_lines as _compiled_event_lines

__all__ = ["event_lines", "cut_cells", "distinct_lines"]


def _dot(a, b):
    """``a . b`` over the last axis (of length 3), elementwise: ``(a0 b0 + a1 b1) + a2
    b2``, the rounding of ``_core/vec.h``'s dot for every row (a matrix product may
    fuse or reorder; the compiled events are tested against these to the bit)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _solve3(A, r):
    """x with ``A x = r`` for each system, A (l, 3, 3) and r (l, 3), by Gaussian
    elimination with partial pivoting (the first largest pivot), the operations of
    ``_core/pair.cpp``'s solve3 in the same order."""
    A, r = np.array(A, dtype=float), np.array(r, dtype=float)
    rows = np.arange(len(A))
    for k in range(3):
        p = k + np.argmax(np.abs(A[:, k:, k]), axis=1)
        Ak, Ap, rk, rp = A[rows, k].copy(), A[rows, p].copy(), r[rows, k].copy(), r[rows, p].copy()
        A[rows, k], A[rows, p], r[rows, k], r[rows, p] = Ap, Ak, rp, rk
        for i in range(k + 1, 3):
            f = A[:, i, k] / A[:, k, k]
            for j in range(k, 3):
                A[:, i, j] -= f * A[:, k, j]
            r[:, i] -= f * r[:, k]
    x = np.empty_like(r)
    for k in (2, 1, 0):
        s_ = r[:, k].copy()
        for j in range(k + 1, 3):
            s_ -= A[:, k, j] * x[:, j]
        x[:, k] = s_ / A[:, k, k]
    return x


def _on_edge_line(v, e0, e1, m):
    """Per row, whether the vertex v lies on the line of the edge (e0, e1) to rounding
    (or the edge is a point): its plane's normal ``m = (e0 - v) x (e1 - v)`` within what
    moving the three points by ``AREA_EVENT_LINE_ULPS`` units of rounding of their
    largest coordinate X moves it, ``u X (|e1 - e0| + min(|e0 - v|, |e1 - v|))`` (each
    length its largest component: nothing squared underflows). There the plane is only
    rounding's, any plane through the line, and so is its event line: exactly collinear,
    m is 0 and every line of sight from v meets the edge's line, no event (View3D's
    gunter1 turned and moved by 1000: a blocker's vertex and another's edge both above
    the emitter's corner drew a line 1.4e-4 off that corner, which cut the corner away
    from the cell whose collapsed rule took it; 1.25e-6 off, 4 times the estimate).
    ``_core/pair.cpp`` takes the same rows."""
    big = lambda a: np.abs(a).max(axis=1)                            # noqa: E731
    X = np.maximum(np.maximum(big(v), big(e0)), big(e1))
    band = (tol.AREA_EVENT_LINE_ULPS * tol.EPS * X
            * (big(e1 - e0) + np.minimum(big(e0 - v), big(e1 - v))))
    return big(m) <= band


def _vertex_edge_rows(pa, pb, k, start, W, nxt, shortcuts, nQ, q0, RQ, seen, st):
    """:func:`event_lines`' rows for the ordered polygon pairs (pa, pb): every vertex v
    of polygon pa against every edge (e0, e1) of pb, its plane's normal m (rows of no
    plane dropped) and pa, less the blocker-blocker events whose lines of sight miss Qc
    (``seen``, in Qc's frame ``RQ`` about q0) with ``shortcuts``."""
    # every vertex of A against every edge of B, (kA * kB) rows per pair in loop order
    size = k[pa] * k[pb]
    row_pair = np.repeat(np.arange(len(pa)), size)
    off = np.arange(int(size.sum())) - np.repeat(np.cumsum(size) - size, size)
    ra, kb = pa[row_pair], k[pb[row_pair]]
    vi = start[ra] + off // kb
    ei = start[pb[row_pair]] + off % kb
    v, e0, e1 = W[vi], W[ei], W[nxt[ei]]
    m = cross(e0 - v, e1 - v)
    keep = ~_on_edge_line(v, e0, e1, m)
    if shortcuts:
        # an edge (v, w) of pa in the plane (coplanar with the edge, typically parallel):
        # the event is the two edges' (their images collinear), its lines of sight pass
        # through every point of (v, w), not through v alone: its images of the edge
        # from the points of (v, w) lie on one line and sweep the interval between those
        # from v and from w (the four segments joining their ends), culled only where
        # all of that misses Qc (unbounded, or both of pa's edges at v in the plane: kept)
        n_in = np.zeros(len(v), dtype=int)
        wi = vi.copy()
        for w in (start[ra] + (vi - start[ra] - 1) % k[ra], nxt[vi]):
            vw = W[w] - v
            inplane = (np.abs(_dot(m, vw)) <= tol.AREA_EVENT_PARALLEL * np.sqrt(_dot(m, m))
                       * np.sqrt(_dot(vw, vw)))
            n_in += inplane
            wi = np.where(inplane & (n_in == 1), w, wi)
        edge_event = n_in > 0
        # between two blockers, the lines through v and the points of the edge meet Qc's
        # plane along the edge's central image from v: does it cross Qc? (unbounded: kept)
        d0, d1 = _dot(e0 - v, nQ), _dot(e1 - v, nQ)
        wv = W[wi]
        dw0, dw1 = _dot(e0 - wv, nQ), _dot(e1 - wv, nQ)
        both = keep & (ra > 0) & (pb[row_pair] > 0) & (d0 * d1 > 0)
        bounded = both & ~edge_event
        swept = both & (n_in == 1) & (dw0 * dw1 > 0) & (d0 * dw0 > 0)
        test = bounded | swept
        if test.any():
            def image(p, d0_, d1_):
                # the edge's central image from p on Qc's plane, in Qc's frame
                pb_, h = p[test], _dot(q0 - p[test], nQ)
                ia = pb_ + (h / d0_[test])[:, None] * (e0[test] - pb_) - q0
                ib = pb_ + (h / d1_[test])[:, None] * (e1[test] - pb_) - q0
                return rotate(ia, RQ)[:, :2], rotate(ib, RQ)[:, :2]

            va, vb_ = image(v, d0, d1)
            miss = ~shapely.intersects(seen, shapely.linestrings(np.stack([va, vb_], axis=1)))
            sw = swept[test]
            if sw.any():
                with np.errstate(divide="ignore", invalid="ignore"):
                    wa, wb = image(wv, dw0, dw1)
                for p0, p1 in ((wa, wb), (va, wa), (vb_, wb)):
                    segs = shapely.linestrings(np.stack([p0[sw], p1[sw]], axis=1))
                    miss[sw] &= ~shapely.intersects(seen, segs)
            if st is not None:
                st.culled_events += int(miss.sum())
            keep[np.flatnonzero(test)[miss]] = False
    return v[keep], e0[keep], e1[keep], m[keep], ra[keep]


def event_lines(S, nP, dP, R, c, radius, Qc, shortcuts=True, st=None, solid=None,
                compiled=True):
    """The segments of P's plane (in its 2-D frame ``R`` about ``c``) across which the
    integrand may lose smoothness: for a vertex ``v`` of one polygon of S and an edge of
    another, the image of the edge through ``v`` on P's plane (the points from which
    ``v`` is seen on the edge: vertex-edge visibility events); and the lines where the
    planes of the polygons of S meet P's plane. An event between two blockers (S[1:])
    counts only where its lines of sight go on to meet Qc, the part of the receiver S[0]
    in front of P (elsewhere it changes nothing that is seen of Qc). Each is kept
    within ``radius`` of ``c``
    (a disk that holds P) as a segment ``(point, point)``, its ends placed on the exact
    line (the intersection of two planes), so that events through one point (a corner
    of a blocker on P) cross there to rounding; an image through infinity is kept as the
    whole chord. Between two faces of one convex solid (``solid``: the group of each
    polygon of S, -1 for none, :func:`~exactff.area.culling.closed_solids`) there is no
    event but the faces' planes: the faces' images united are the solid's, whose outline
    changes only there. Without ``shortcuts`` every blocker-blocker event is kept; the
    ones culled are counted in ``st.culled_events``, the vertex-edge pairs of one solid
    in ``st.solid_events`` (``st``: an :class:`~exactff.area.row.AreaStats`,
    optional).

    ``compiled`` (default): computed by :mod:`exactff.area._pair` (``_core/pair.cpp``);
    else by numpy and GEOS, the reference the compiled path is tested against
    (``tests/test_area_pair_compiled.py``: the same segments to rounding). Returns an
    array (m, 2, 2) of the segments, each once, in lexicographic order.

    Examples
    --------
    A unit square one above the emitter's plane and a blocker square between: the
    blocker's vertex-edge events with the receiver, and both planes' lines (the
    receiver's plane is parallel to the emitter's: none).

    >>> from exactff.geometry import receiver_frame
    >>> Q = np.array([[0, 0, 2], [0, 1, 2], [1, 1, 2], [1, 0, 2]], float)
    >>> K = np.array([[.4, .4, 1], [.6, .4, 1], [.6, .6, 1], [.4, .6, 1]], float)
    >>> nP, c = np.array([0, 0, 1.0]), np.array([.5, .5, 0])
    >>> lines = event_lines([Q, K], nP, 0.0, receiver_frame(nP), c, 1.0, Q)
    >>> lines.shape[1:], bool(np.allclose(lines, event_lines([Q, K], nP, 0.0,
    ...     receiver_frame(nP), c, 1.0, Q, compiled=False), atol=1e-15))
    ((2, 2), True)
    """
    if compiled:
        nQ, q0, RQ, Q2 = plane_frame(Qc)
        W = np.concatenate([np.asarray(A, dtype=float) for A in S])
        start = np.concatenate([[0], np.cumsum([len(A) for A in S])])
        sol = (np.zeros(0, dtype=np.int64) if solid is None or not shortcuts
               else np.asarray(solid, dtype=np.int64))
        segments, culled, same = _compiled_event_lines(
            W=W, start=start, solid=sol, nP=nP, dP=float(dP), frame=R, c=c,
            radius=float(radius), nQ=nQ, q0=q0, RQ=RQ[:2], Q2=Q2, shortcuts=shortcuts,
            ray_parallel=tol.AREA_RAY_PARALLEL, event_parallel=tol.AREA_EVENT_PARALLEL,
            line_ulps=tol.AREA_EVENT_LINE_ULPS, eps=tol.EPS)
        if st is not None:
            st.culled_events += culled
            st.solid_events += same
        return segments
    nQ, q0, RQ, Q2 = plane_frame(Qc)
    seen = shapely.Polygon(Q2)
    shapely.prepare(seen)
    # the events in order (per polygon A: its plane, then per other polygon B, vertex v
    # of A and edge of B): the plane m . (x - v) = 0 through v, and the span's ends
    n = len(S)
    k = np.array([len(A) for A in S])
    start = np.concatenate([[0], np.cumsum(k)])
    W = np.concatenate([np.asarray(A, dtype=float) for A in S])
    nxt = successors(start)
    # the ordered pairs (a, b) of different polygons, a-major, less those within one
    # convex solid
    pa, pb = (g.ravel() for g in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    pair = pa != pb
    if shortcuts and solid is not None:
        sol = np.asarray(solid)
        same = pair & (sol[pa] >= 0) & (sol[pa] == sol[pb])
        if same.any() and st is not None:
            st.solid_events += int((k[pa] * k[pb])[same].sum())
        pair &= ~same
    pa, pb = pa[pair], pb[pair]
    # in batches of pairs (the rows' temporaries bounded), in order
    size = k[pa] * k[pb]
    per = tol.AREA_EVENT_ROWS_PER_CALL
    cut = np.searchsorted(np.cumsum(size), per * np.arange(1, int(size.sum()) // per + 1))
    parts_ = [_vertex_edge_rows(a, b, k, start, W, nxt, shortcuts, nQ, q0, RQ, seen, st)
              for a, b in zip(np.split(pa, cut), np.split(pb, cut)) if len(a)]
    v, e0, e1, m, ra = ((np.concatenate([q[t] for q in parts_]) if parts_ else
                         np.zeros((0, 3)) if t < 4 else np.zeros(0, dtype=int)) for t in range(5))
    # where the lines from v through the edge's ends meet P's plane (not spanned:
    # parallel, or the image passes through infinity: the whole chord)
    den0, den1 = _dot(e0 - v, nP), _dot(e1 - v, nP)
    ok = ((np.abs(den0) >= tol.AREA_RAY_PARALLEL * np.sqrt(_dot(e0 - v, e0 - v)))
          & (np.abs(den1) >= tol.AREA_RAY_PARALLEL * np.sqrt(_dot(e1 - v, e1 - v)))
          & (den0 * den1 > 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = v + ((dP - _dot(v, nP)) / den0)[:, None] * (e0 - v)
        x1 = v + ((dP - _dot(v, nP)) / den1)[:, None] * (e1 - v)
    # each polygon's own plane, through its first vertex, before its vertex-edge events
    first = W[start[:-1]]
    planes = cross(W[start[:-1] + 1] - first, W[start[:-1] + 2] - first)
    order = np.argsort(np.concatenate([2 * np.arange(n), 2 * ra + 1]), kind="stable")
    m = np.concatenate([planes, m])[order]
    v = np.concatenate([first, v])[order]
    span = np.concatenate([np.zeros((n, 2, 3)), np.stack([x0, x1], axis=1)])[order]
    spanned = np.concatenate([np.zeros(n, dtype=bool), ok])[order]
    # each normal scaled by its largest component (one of tiny coordinates, 1e-217,
    # would underflow in its norm); a normal of 0 (no plane) has no event
    big = np.abs(m).max(axis=1)
    nz = big > 0
    m, v, span, spanned = m[nz] / big[nz, None], v[nz], span[nz], spanned[nz]
    # the plane meets P's plane n . x = dP in a line; x0 is its point nearest to c, d
    # its direction; the chord of the disk, or the span's part of it
    first = m[np.arange(len(m)), np.argmax(m != 0, axis=1)]
    m = np.where((first > 0)[:, None], m, -m)          # one line for either orientation
    d = cross(nP, m)
    dn = np.sqrt(_dot(d, d))
    live = dn >= tol.AREA_EVENT_PARALLEL * np.sqrt(_dot(m, m))
    m, v, span, spanned, d = m[live], v[live], span[live], spanned[live], d[live] / dn[live, None]
    A = np.stack([np.broadcast_to(nP, m.shape), m, d], axis=1)
    rhs = np.stack([np.full(len(m), dP), _dot(m, v), _dot(d, c)], axis=1)
    x0 = _solve3(A, rhs)
    h2 = radius * radius - _dot(x0 - c, x0 - c)
    live = h2 > 0
    x0, d, span, spanned, half = x0[live], d[live], span[live], spanned[live], np.sqrt(h2[live])
    ends = np.stack([x0 - half[:, None] * d, x0 + half[:, None] * d], axis=1)
    # the span's ends where they lie on the chord (as computed: segments that meet there
    # join exactly), else the chord's ends
    t = _dot(span - x0[:, None], d[:, None])
    swap = t[:, 1] < t[:, 0]
    t = np.where(swap[:, None], t[:, ::-1], t)
    span = np.where(swap[:, None, None], span[:, ::-1], span)
    inside = ~spanned | ((t[:, 0] < half) & (t[:, 1] > -half))
    use = spanned[:, None] & (np.stack([t[:, 0] > -half, t[:, 1] < half], axis=1))
    ends = np.where(use[:, :, None], span, ends)[inside]
    E2 = rotate(ends - c, R)[..., :2]
    # one copy of each segment: the plane through a vertex and an edge is the same for
    # every pair of polygons sharing them (a vertex of k faces against an edge of two
    # gives up to 2k copies), and GEOS nodes a copy at the cost of a distinct line; the ends
    # are computed alike for each copy, so the copies are equal to the bit
    swap = (E2[:, 0, 0] > E2[:, 1, 0]) | ((E2[:, 0, 0] == E2[:, 1, 0]) & (E2[:, 0, 1] > E2[:, 1, 1]))
    return np.unique(np.where(swap[:, None, None], E2[:, ::-1], E2) + 0.0, axis=0)


def cut_cells(Pc, nP, lines, R, c, grid=None, lengthen=True, compiled=True):
    """P (clipped) cut along the event lines, as triangles (t, 3, 3) in the world (the
    lines are cut to P first, so every cell lies in P; with ``grid``, the noding snaps
    the vertices to a grid of that size, and the cells lie in P to that size).

    With ``lengthen``, an end of a cut line within ``AREA_CUT_EXTEND_RTOL`` of P's size
    of P's boundary is moved out by as much, across the boundary; what sticks out is a
    dangle, dropped. (GEOS rounds a line's crossing with the boundary, which may leave
    the end a few ulps inside: a dangle that polygonizing drops, and the cell it should
    have cut left whole, with a kink of the hidden part across it; pinned in
    tests/test_area_view3d.py: a line through a corner of the emitter.)

    ``compiled`` (default), without ``grid`` and with ``lengthen``: the arrangement of
    the lines in P is built by :mod:`exactff.area._pair` (``_core/pair.cpp``: the lines
    cut to P, an end within the lengthening of P's boundary moved onto it, noded at
    their crossings and T-junctions, crossings within ``AREA_HULL_RTOL`` of P's size
    one node, dangles removed, the faces traced and clipped into ears) where it builds
    one: P convex, one connected arrangement (no cell with a hole), the cells tiling P
    to 1e-12 of its area; else GEOS, as without ``compiled``. The cells are GEOS's up
    to slivers and a few cells the compiled noding cuts further
    (``tests/test_area_pair_compiled.py``)."""
    P2 = (Pc - c) @ R[:2].T
    if compiled and grid is None and lengthen:
        # the arrangement compiled (_core/pair.cpp), where it builds one: P convex, no
        # cell with a hole, every face clipped into ears; else GEOS below
        A2 = 0.5 * float(np.sum(P2[:, 0] * np.roll(P2[:, 1], -1) - np.roll(P2[:, 0], -1) * P2[:, 1]))
        ring = P2 if A2 > 0 else P2[::-1]
        size = float(np.ptp(P2, axis=0).max())
        tris, _, _, ok = _compiled_cut_cells(
            P2=np.ascontiguousarray(ring), segments=np.asarray(lines, dtype=float).reshape(-1, 2, 2),
            step=tol.AREA_CUT_EXTEND_RTOL * np.sqrt(abs(A2)), merge=tol.AREA_HULL_RTOL * size,
            sliver=tol.AREA_SLIVER_CELL * abs(A2))
        if ok:
            return c + tris @ R[:2]
    poly = shapely.Polygon(P2)
    cut = (shapely.intersection(shapely.linestrings(np.asarray(lines, dtype=float)), poly)
           if len(lines) else np.empty(0, dtype=object))
    pieces = shapely.get_parts(shapely.get_parts(cut[~shapely.is_empty(cut)]))
    pieces = pieces[shapely.get_type_id(pieces) == 1]                   # line strings

    def faces_of(segments):
        # the union nodes the segments (already cut to P) and P's boundary; cutting the
        # union to P again would lose nodes on the boundary, and with them whole cells
        return shapely.get_parts(shapely.polygonize(shapely.get_parts(
            shapely.union_all([poly.boundary, *segments], grid_size=grid))))

    if len(pieces) and lengthen:
        ends = shapely.get_coordinates(pieces).reshape(-1, 2, 2)   # a cut line is straight
        step = tol.AREA_CUT_EXTEND_RTOL * np.sqrt(poly.area)
        d = ends[:, 1] - ends[:, 0]
        length = np.linalg.norm(d, axis=1)
        d = np.divide(d * step, length[:, None], out=np.zeros_like(d), where=length[:, None] > 0)
        on = shapely.distance(shapely.points(ends), poly.boundary) <= step    # (n, 2)
        faces = faces_of(shapely.linestrings(ends + np.stack([-d * on[:, :1], d * on[:, 1:]],
                                                            axis=1)))
    else:
        faces = faces_of(pieces)
    # cells of P thinner than rounding are dropped (their area is counted in the estimate)
    faces = faces[shapely.area(faces) > tol.AREA_SLIVER_CELL * poly.area]
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(faces))
    uv = shapely.get_coordinates(shapely.get_exterior_ring(tris)).reshape(-1, 4, 2)[:, :3]
    return c + uv @ R[:2]


def distinct_lines(lines, size, P2=None):
    """How many distinct lines the segments ``lines`` (m, 2, 2) that meet the polygon P2
    (k, 2; default: all of them) lie on, each line taken
    as its direction (an angle in [0, pi)) and its offset from the origin, both rounded
    to ``AREA_EVENT_LINE_KEY`` (of ``size`` for the offset): about the lines the compiled
    arrangement nodes after joining collinear ones (``_core/pair.cpp``, merge_collinear),
    whose cost and cells grow with their square.

    Examples
    --------
    Two segments on the x axis and one across it:

    >>> distinct_lines(np.array([[[0, 0], [1, 0]], [[2, 0], [3, 0]], [[0, 0], [0, 1]]], float), 3.0)
    2
    """
    S = np.asarray(lines, dtype=float).reshape(-1, 2, 2)
    if P2 is not None and len(S):
        S = S[shapely.intersects(shapely.linestrings(S), shapely.Polygon(P2))]
    d = S[:, 1] - S[:, 0]
    length = np.hypot(d[:, 0], d[:, 1])
    S, d, length = S[length > 0], d[length > 0], length[length > 0]
    angle = np.mod(np.arctan2(d[:, 1], d[:, 0]), np.pi)
    offset = S[:, 0, 0] * np.sin(angle) - S[:, 0, 1] * np.cos(angle)
    key = np.stack([np.round(angle / tol.AREA_EVENT_LINE_KEY),
                    np.round(offset / (tol.AREA_EVENT_LINE_KEY * size))], axis=1)
    return int(len(np.unique(key, axis=0)))
