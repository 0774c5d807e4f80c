"""Area-to-area form factors with occlusion: a pair with blockers between is the contour
integral less the integral of the hidden part, cut along the vertex-edge visibility
events and integrated adaptively by collapsed Gauss rules; a row of them.

The hidden part at a point x of the emitter is built in the receiver's plane: each
blocker projected from x onto that plane, the images united as disjoint convex pieces
and cut by the receiver (compiled, :mod:`exactff.area._hidden`), and integrated by the
sector sums (``docs/explanation/area-form-factors.md``).
"""

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError
from scipy.special import roots_legendre

from .. import _tolerances as tol
from ..errors import NumericalError, misses_tolerance
from ..geometry import area_vector, cross, receiver_frame, unit_normal
from ..methods import Exact
from ..predicates import coplanar_band_sides, coplanar_pairs
from ..prepared import prepared
from ..visibility import convex_pieces, is_convex_enclosure
from ..rings import padded, successors
from ..scene import Scene
from ._hidden import hidden_pieces
from .contour import (CLOSED_FORM_COUNTS, clip_front, front_parts, nonnegative, point_values,
                      symmetric_triangle_rule, triangle_rule, unoccluded_pairs)

__all__ = ["area_row", "STATS"]

#: The counters :func:`area_row` fills in ``stats`` (each 0 where its shortcut is off or
#: did not apply): pairs of a convex enclosure, where nothing can come between
#: (``enclosure_unoccluded_pairs``: no shaft or hull test at all;
#: :func:`exactff.visibility.is_convex_enclosure`), pairs taken by the closed form
#: because shaft culling and
#: the hull test left no blocker (``hull_unoccluded_pairs``; the polygons they left out:
#: ``hull_culled_blockers``), polygons in a pair's bounding box that the shaft's planes
#: rejected before the hull test (``shaft_culled_blockers``) and pairs whose box held
#: polygons but the shaft none, so that no hull was built (``shaft_unoccluded_pairs``),
#: far pairs by the far-field rule (``far_pairs``),
#: blocker-blocker events not cut along because their lines of sight miss the receiver
#: (``culled_events``), vertex-edge pairs of two faces of one convex solid, whose
#: images united change only at the faces' planes (``solid_events``), members of such a
#: solid that a point sees from behind, skipped in its hidden region as the members it
#: sees from the front cover their images (``back_faces``, per point), calls whose
#: hidden parts the engine computed at some points, where a point's images did not
#: stay finite or could not be trusted
#: (``engine_fallbacks``, their points ``engine_fallback_points``), such points of
#: little weight given the bound 0 <= hidden <= unoccluded instead
#: (``bounded_points``), pairs whose emitter
#: was cut along the events another way (GEOS failed, or the cells did not cover it:
#: the lines as cut, or on a fine grid; ``cell_fallbacks``); and what was done:
#: ``occluded_pairs``, ``point_values``
#: (hidden parts evaluated); and the check of the rules' differences (not a shortcut):
#: triangles checked one by one against their closed form where a pair's sum missed
#: (``checked_triangles``), and those the check sent back to be refined
#: (``refined_triangles``).
STATS = ("enclosure_unoccluded_pairs", "hull_unoccluded_pairs", "hull_culled_blockers",
         "shaft_culled_blockers",
         "shaft_unoccluded_pairs", "far_pairs", "culled_events", "solid_events",
         "back_faces", "bounded_points", "engine_fallbacks", "engine_fallback_points", "cell_fallbacks", "occluded_pairs",
         "point_values", "checked_triangles", "refined_triangles")


def _padded(polys):
    """The scene's polygons as one array (n, kmax, 3), short ones padded by repeating
    their last vertex, with their bounding boxes and unit normals (Newell, relative to
    the first vertex as :func:`area_vector`; the repeats add nothing)."""
    V, _ = padded(polys)
    W = V - V[:, :1]
    A = 0.5 * cross(W, np.roll(W, -1, axis=1)).sum(axis=1)
    return V, V.min(axis=1), V.max(axis=1), A / np.linalg.norm(A, axis=1)[:, None]


def _hull_blockers(V, cand, Pc, Qc, near):
    """The candidates (indices into V) reaching into the interior of the convex hull of
    Pc and Qc: a polygon on or outside one face of the hull hides nothing of positive
    measure (the exact test; no hull, as for a flat pair: none)."""
    if len(cand) == 0:
        return []
    try:
        H = ConvexHull(np.vstack([Pc, Qc])).equations      # a . x + b <= 0 inside
    except QhullError:
        return []
    outside = np.all(V[cand] @ H[:, :3].T + H[:, 3] >= -near, axis=1)      # (c, faces)
    return [int(k) for k in np.asarray(cand)[~outside.any(axis=1)]]


def _blockers(padded, i, j, Pc, Qc, scale, shortcuts=True):
    """Polygons (indices) that may hide part of Qc from part of Pc: those reaching into
    the interior of the convex hull of both (the hull test alone, for one pair: what
    :func:`_shaft` decides for a whole row before the hull test). ``padded`` is
    :func:`_padded` of the scene. Without ``shortcuts``, every polygon but i and j."""
    V, lo_k, hi_k = padded[:3]
    if not shortcuts:
        return [k for k in range(len(V)) if k not in (i, j)]
    pts = np.vstack([Pc, Qc])
    near = tol.AREA_HULL_RTOL * scale
    lo, hi = pts.min(axis=0) - near, pts.max(axis=0) + near
    cand = np.all((hi_k >= lo) & (lo_k <= hi), axis=1)
    cand[[i, j]] = False
    return _hull_blockers(V, np.flatnonzero(cand), Pc, Qc, near)


#: The box edges the shaft's side planes join: two axes and a direction along each.
_SHAFT_EDGES = tuple((a, b, sa, sb) for a, b in ((0, 1), (0, 2), (1, 2))
                     for sa in (1.0, -1.0) for sb in (1.0, -1.0))


def _shaft(padded, i, J, boxes, nP, p0, near, st):
    """The blockers of each pair (i, J[a]) of a row that survive shaft culling (Haines &
    Wallace 1991), decided for all pairs and all polygons at once: a polygon stays a
    candidate only if it reaches into the open interior of the pair's bounding box, is
    not on or behind P's plane nor on or behind the receiver's (rays leave P's front and
    reach Q's front), and is not on or outside one of the shaft's side planes, the
    planes through an edge of each of the two polygons' boxes where one box extends
    beyond the other along one axis and the other along a second (each is a supporting
    plane of both boxes, so the shaft holds the convex hull of the pair: a polygon it
    rejects lies outside that hull, to ``near / 2``, and hides nothing). What survives
    goes to the hull test (:func:`_hull_blockers`).

    Parameters
    ----------
    padded : tuple
        :func:`_padded` of the scene.
    i : int
        The emitter.
    J : ndarray of shape (m,)
        The receivers.
    boxes : ndarray of shape (m, 4, 3)
        Per pair, the clipped emitter's box (lo, hi) and the clipped receiver's (lo, hi).
    nP, p0 : ndarray of shape (3,)
        P's unit normal and a point of its plane.
    near : float
        The hull test's distance (``AREA_HULL_RTOL`` of the scene's size).
    st : dict
        Counts ``shaft_culled_blockers`` (polygons in a pair's box the planes rejected:
        the hull test never sees them) and ``shaft_unoccluded_pairs`` (pairs whose box
        held polygons, none left: no hull built).

    Returns
    -------
    list of ndarray
        Per pair, the candidates for the hull test.
    """
    V, lo_k, hi_k, N = padded
    m = len(J)
    loP, hiP, loQ, hiQ = boxes[:, 0], boxes[:, 1], boxes[:, 2], boxes[:, 3]
    lo, hi = np.minimum(loP, loQ), np.maximum(hiP, hiQ)
    # polygons reaching into the open interior of each pair's box (m, n)
    inbox = np.all((hi_k[None] > lo[:, None]) & (lo_k[None] < hi[:, None]), axis=2)
    inbox[:, i] = False
    inbox[np.arange(m), J] = False
    a, k = np.nonzero(inbox)                        # sorted by pair
    boxed = np.bincount(a, minlength=m)
    # on or behind P's plane: for every pair of the row at once
    keep = ((V - p0) @ nP).max(axis=1)[k] > 0.5 * near
    a, k = a[keep], k[keep]
    # on or behind the receiver's plane
    q0 = V[J, 0]
    keep = np.einsum("ckx,cx->ck", V[k] - q0[a][:, None], N[J][a]).max(axis=1) > 0.5 * near
    a, k = a[keep], k[keep]
    # the side planes: through the edge of box A extreme in direction sa along axis ax
    # and the edge of box B extreme in direction sb along axis bx (A != B), parallel to
    # the third axis; the outward normal (sa |d_b|, sb |d_a|) is in the quadrant (sa, sb)
    for ax, bx, sa, sb in _SHAFT_EDGES:
        if a.size == 0:
            break
        eP = np.stack([np.where(sa > 0, hiP[:, ax], loP[:, ax]),
                       np.where(sb > 0, hiP[:, bx], loP[:, bx])], axis=1)
        eQ = np.stack([np.where(sa > 0, hiQ[:, ax], loQ[:, ax]),
                       np.where(sb > 0, hiQ[:, bx], loQ[:, bx])], axis=1)
        sign = np.array([sa, sb])
        p_ahead = (sign * eP > sign * eQ)           # P's box beyond Q's along ax, bx
        q_ahead = (sign * eQ > sign * eP)
        active = (p_ahead[:, 0] & q_ahead[:, 1]) | (q_ahead[:, 0] & p_ahead[:, 1])
        d = eQ - eP
        n2 = sign * np.abs(d[:, ::-1])
        # normalised after scaling by its largest component: the boxes' offsets may be
        # tiny (1e-217 apart: their squares underflow, and a normal of 0 put every
        # candidate on the plane, dropped though it hid 2.7 % of the receiver)
        big = np.abs(n2).max(axis=1)[:, None]
        active &= big[:, 0] > 0
        n2 = np.divide(n2, big, out=np.zeros_like(n2), where=big > 0)
        size = np.linalg.norm(n2, axis=1)[:, None]                         # >= 1 or 0
        n2 = np.divide(n2, size, out=np.zeros_like(n2), where=size > 0)
        off = np.einsum("mx,mx->m", n2, eP)
        on = active[a]
        if not on.any():
            continue
        dist = np.einsum("ckx,cx->ck", V[k[on]][:, :, [ax, bx]], n2[a[on]]).min(axis=1) - off[a[on]]
        drop = np.zeros(a.size, dtype=bool)
        drop[np.flatnonzero(on)[dist >= -0.5 * near]] = True
        a, k = a[~drop], k[~drop]
    left = np.bincount(a, minlength=m)
    st["shaft_culled_blockers"] += int(boxed.sum() - left.sum())
    st["shaft_unoccluded_pairs"] += int(np.count_nonzero((boxed > 0) & (left == 0)))
    return np.split(k, np.cumsum(left)[:-1])


def _convex_solids(scene):
    """The scene's polygons grouped into convex solids: connected by shared edges (equal
    coordinates), no edge shared by more than two of them, and every vertex of the group
    on or behind each member's plane or on or in front of it (the coplanar band of
    :func:`~exactff.predicates.coplanar_band_sides`): each member on the boundary of the
    group's convex hull. Returns ``(label, open_edges, vertices)``: the group of each
    polygon (-1: none, or alone), and per group the ends of its edges that only one
    member has, shape (m, 2, 3), and its vertices. A group whose open edges all lie in a
    plane that supports it (the emitter's or the receiver's, :func:`_closed_solids`) is
    the boundary of its hull less a face in that plane."""
    polys = [np.asarray(p, dtype=float) for p in scene.polygons]
    faces_of = {}
    for f, P in enumerate(polys):
        for a, b in zip(P + 0.0, np.roll(P, -1, axis=0) + 0.0):   # -0.0 is 0.0
            ka, kb = tuple(a), tuple(b)
            if ka != kb:
                faces_of.setdefault((min(ka, kb), max(ka, kb)), []).append(f)
    shared = [fs for fs in faces_of.values() if len(fs) > 1]
    n = len(polys)
    rows = [f for fs in shared for f in fs[:1] * (len(fs) - 1)]
    cols = [g for fs in shared for g in fs[1:]]
    _, label = connected_components(coo_matrix((np.ones(len(rows)), (rows, cols)),
                                               shape=(n, n)), directed=False)
    label = np.asarray(label)
    size = np.bincount(label, minlength=n)
    bad = {int(label[fs[0]]) for fs in shared if len(fs) > 2}     # three faces on an edge
    N, D = scene.normals, scene.plane_offsets
    # each group's members and its edges that only one member has, in one pass each
    members_of, edges_of = {}, {}
    for f, g in enumerate(label.tolist()):
        members_of.setdefault(g, []).append(f)
    for k, fs in faces_of.items():
        if len(fs) == 1:
            edges_of.setdefault(int(label[fs[0]]), []).append(k)
    open_edges, vertices = {}, {}
    for g in np.flatnonzero(size > 1):
        members = np.array(members_of[int(g)])
        if int(g) in bad:
            continue
        V = np.unique(np.vstack([polys[f] for f in members]), axis=0)
        sign, _ = coplanar_band_sides(V, N[members], D[members])
        if np.any((sign > 0).any(axis=0) & (sign < 0).any(axis=0)):
            continue                                     # a member's plane cuts the group
        open_edges[int(g)] = np.array(edges_of.get(int(g), []), dtype=float).reshape(-1, 2, 3)
        vertices[int(g)] = V
    label = np.where(np.isin(label, list(open_edges)), label, -1)
    return label, open_edges, vertices


def _closed_solids(solids, blockers, planes):
    """The group (:func:`_convex_solids`) of each blocker where the group is a solid for
    the pair, -1 elsewhere. ``planes`` are the emitter's and the receiver's, as
    ``(normals (2, 3), offsets (2,))``. A group is a solid for the pair where two or
    more of its members are blockers, each of its open edges lies in one of the planes
    and that plane has the whole group on one side, and one of the planes meets the
    group's hull in no area (at most two of its vertices in the plane).

    Then a line of sight from x on the emitter to y on the receiver crosses the
    blockers of the group exactly where it crosses their hull: its open part misses both
    planes, and the hull's boundary off them is the members'; and the segment cannot lie
    in the hull from end to end, as x and y would both be in it, which one plane rules
    out (up to points of no area). So from x the members' images united are the hull's
    image, whose outline changes only where x crosses a member's plane: a vertex-edge
    event between two members is no event. The emitter and the receiver may be members
    (their faces lie in the planes)."""
    label, open_edges, vertices = solids
    ids = label[blockers]
    out = np.full(len(blockers), -1)
    N, D = planes
    for g in set(ids[ids >= 0].tolist()):
        if np.count_nonzero(ids == g) < 2:
            continue
        sign, _ = coplanar_band_sides(vertices[g], N, D)
        supports = ~((sign > 0).any(axis=0) & (sign < 0).any(axis=0))        # (2,)
        no_area = supports & ((sign == 0).sum(axis=0) < 3)
        if not no_area.any():
            continue
        E = open_edges[g]
        if len(E):
            on, _ = coplanar_band_sides(E.reshape(-1, 3), N, D)
            on = (on == 0).reshape(len(E), 2, len(D)).all(axis=1) & supports
            if not on.any(axis=1).all():
                continue
        out[ids == g] = g
    return out


def _plane_frame(Q):
    """A planar polygon's unit normal, origin (its first vertex), frame (rows t1, t2, n:
    :func:`receiver_frame`) and 2-D coordinates in that frame."""
    nQ = area_vector(Q)
    nQ = nQ / np.linalg.norm(nQ)
    RQ = receiver_frame(nQ)
    return nQ, Q[0], RQ, (Q - Q[0]) @ RQ[:2].T


def _vertex_edge_rows(pa, pb, k, start, W, nxt, shortcuts, nQ, q0, RQ, seen, st):
    """:func:`_event_lines`' rows for the ordered polygon pairs (pa, pb): every vertex v
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
    keep = np.any(m != 0, axis=1)
    if shortcuts:
        # between two blockers, the lines through v and the points of the edge meet Qc's
        # plane along the edge's central image from v: does it cross Qc? (unbounded: kept)
        d0, d1 = (e0 - v) @ nQ, (e1 - v) @ nQ
        bounded = keep & (ra > 0) & (pb[row_pair] > 0) & (d0 * d1 > 0)
        if bounded.any():
            vb, h = v[bounded], (q0 - v[bounded]) @ nQ
            ia = vb + (h / d0[bounded])[:, None] * (e0[bounded] - vb) - q0
            ib = vb + (h / d1[bounded])[:, None] * (e1[bounded] - vb) - q0
            segs = shapely.linestrings(np.stack([ia @ RQ[:2].T, ib @ RQ[:2].T], axis=1))
            miss = ~shapely.intersects(seen, segs)
            st["culled_events"] = st.get("culled_events", 0) + int(miss.sum())
            keep[np.flatnonzero(bounded)[miss]] = False
    return v[keep], e0[keep], e1[keep], m[keep], ra[keep]


def _event_lines(S, nP, dP, R, c, radius, Qc, shortcuts=True, st=None, solid=None):
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
    polygon of S, -1 for none, :func:`_closed_solids`) there is no event but the faces'
    planes: the faces' images united are the solid's, whose outline changes only there.
    Without ``shortcuts`` every blocker-blocker event is kept; the ones culled are
    counted in ``st["culled_events"]``, the vertex-edge pairs of one solid in
    ``st["solid_events"]``."""
    st = {} if st is None else st
    nQ, q0, RQ, Q2 = _plane_frame(Qc)
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
        if same.any():
            st["solid_events"] = st.get("solid_events", 0) + int((k[pa] * k[pb])[same].sum())
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
    den0, den1 = (e0 - v) @ nP, (e1 - v) @ nP
    ok = ((np.abs(den0) >= tol.AREA_RAY_PARALLEL * np.linalg.norm(e0 - v, axis=1))
          & (np.abs(den1) >= tol.AREA_RAY_PARALLEL * np.linalg.norm(e1 - v, axis=1))
          & (den0 * den1 > 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        x0 = v + ((dP - v @ nP) / den0)[:, None] * (e0 - v)
        x1 = v + ((dP - v @ nP) / den1)[:, None] * (e1 - v)
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
    dn = np.linalg.norm(d, axis=1)
    live = dn >= tol.AREA_EVENT_PARALLEL * np.linalg.norm(m, axis=1)
    m, v, span, spanned, d = m[live], v[live], span[live], spanned[live], d[live] / dn[live, None]
    A = np.stack([np.broadcast_to(nP, m.shape), m, d], axis=1)
    rhs = np.stack([np.full(len(m), dP), np.einsum("lx,lx->l", m, v), d @ c], axis=1)
    x0 = np.linalg.solve(A, rhs[:, :, None])[:, :, 0]
    h2 = radius * radius - np.einsum("lx,lx->l", x0 - c, x0 - c)
    live = h2 > 0
    x0, d, span, spanned, half = x0[live], d[live], span[live], spanned[live], np.sqrt(h2[live])
    ends = np.stack([x0 - half[:, None] * d, x0 + half[:, None] * d], axis=1)
    # the span's ends where they lie on the chord (as computed: segments that meet there
    # join exactly), else the chord's ends
    t = np.einsum("lex,lx->le", span - x0[:, None], d)
    swap = t[:, 1] < t[:, 0]
    t = np.where(swap[:, None], t[:, ::-1], t)
    span = np.where(swap[:, None, None], span[:, ::-1], span)
    inside = ~spanned | ((t[:, 0] < half) & (t[:, 1] > -half))
    use = spanned[:, None] & (np.stack([t[:, 0] > -half, t[:, 1] < half], axis=1))
    ends = np.where(use[:, :, None], span, ends)[inside]
    E2 = (ends - c) @ R[:2].T
    # one copy of each segment (the same plane through a vertex and an edge comes from
    # several vertex-edge pairs: three in four of the closed Cornell box's lines were
    # exact copies, and noding them cost GEOS as much as distinct ones)
    swap = (E2[:, 0, 0] > E2[:, 1, 0]) | ((E2[:, 0, 0] == E2[:, 1, 0]) & (E2[:, 0, 1] > E2[:, 1, 1]))
    E2 = np.unique(np.where(swap[:, None, None], E2[:, ::-1], E2) + 0.0, axis=0)
    return [(p0, p1) for p0, p1 in E2]


def _cells(Pc, nP, lines, R, c, grid=None, lengthen=True):
    """P (clipped) cut along the event lines, as triangles (t, 3, 3) in the world (the
    lines are cut to P first, so every cell lies in P; with ``grid``, the noding snaps
    the vertices to a grid of that size, and the cells lie in P to that size).

    With ``lengthen``, an end of a cut line within ``AREA_CUT_EXTEND_RTOL`` of P's size
    of P's boundary is moved out by as much, across the boundary; what sticks out is a
    dangle, dropped. (GEOS rounds a line's crossing with the boundary, which may leave
    the end a few ulps inside: a dangle that polygonizing drops, and the cell it should
    have cut left whole, with a kink of the hidden part across it; a line through a
    corner of gunter1's ceiling did that.)"""
    poly = shapely.Polygon((Pc - c) @ R[:2].T)
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


def _hidden_setup(Qc, blockers, solid=None, inner=None):
    """What :func:`_hidden_values` needs of a receiver and its blockers whatever the
    points (computed once per pair): Qc's frame, the blockers' parts in front of its
    plane as convex pieces with their unit normals and convex solids, the pyramid's
    base (Qc where it is strictly convex, else a rectangle around it, with Qc's convex
    parts), the box of the blockers and Qc, and Qc's size in its plane. None where no
    blocker is in front.

    ``solid``: the convex solid of each blocker for the pair (:func:`_closed_solids`),
    -1 for none, and ``inner`` a point inside its hull (NaN where not every member of
    the solid is a blocker of the pair: a member culled within rounding of a line of
    sight could not stand in for one skipped): a solid's members get their outward
    normals, and from a point outside the hull those it sees from behind are skipped
    (their images lie in those of the members it sees from the front). A member whose
    plane passes within ``AREA_HULL_RTOL`` of the hull's size of the inner point leaves
    its solid as a whole (which side is out is not certain)."""
    nQ, q0, RQ, Q2 = _plane_frame(Qc)
    clipped = [clip_front(np.asarray(K), nQ, q0) for K in blockers]
    kept = [k for k, K in enumerate(clipped) if K is not None]
    Kc = [clipped[k] for k in kept]
    if not Kc:
        return None
    # the pyramid's base: Qc itself where it is strictly convex (the images then lie in
    # it), else a rectangle around it (the pieces then cut by Qc's convex parts)
    if _strictly_convex(Q2):
        corners, parts = np.asarray(Qc, dtype=float), np.zeros((0, 3, 2))
        part_counts = np.zeros(0, dtype=np.int64)
    else:
        lo, hi = Q2.min(axis=0), Q2.max(axis=0)
        pad = tol.AREA_HIDDEN_PAD * float((hi - lo).max())
        lo, hi = lo - pad, hi + pad
        corners = q0 + np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]],
                                 [lo[0], hi[1]]]) @ RQ[:2]
        Qparts = [(Qp - q0) @ RQ.T for Qp in convex_pieces(np.asarray(Qc, float), nQ)]
        parts, part_counts = padded(Qparts)
        parts = parts[:, :, :2]
    pieces = [[Kp for Kp in convex_pieces(K, unit_normal(K))] for K in Kc]
    owner = np.repeat(kept, [len(p) for p in pieces])
    pieces = [Kp for p in pieces for Kp in p]
    V, counts = padded(pieces)
    NK = np.array([unit_normal(K) for K in pieces])
    group = np.full(len(pieces), -1, dtype=np.int64)
    if solid is not None:
        # outward: the inner point behind the plane
        solid, inner = np.asarray(solid), np.asarray(inner, dtype=float)
        # (no inner point: the solid's members are not all blockers)
        group = np.where(np.isnan(inner[owner]).any(axis=1), -1, solid[owner]).astype(np.int64)
        mine = group >= 0
        depth = np.einsum("kx,kx->k", inner[owner[mine]] - V[mine, 0], NK[mine])
        NK[mine] *= np.where(depth > 0, -1.0, 1.0)[:, None]
        size = float(np.ptp(np.vstack(Kc), axis=0).max())
        unsure = np.unique(group[mine][np.abs(depth) <= tol.AREA_HULL_RTOL * size])
        group[np.isin(group, unsure)] = -1
        # labels 0, 1, ... (the compiled call keeps a flag per label at every point)
        live = group >= 0
        group[live] = np.unique(group[live], return_inverse=True)[1]
    allv = np.vstack(Kc + [Qc])
    extent = float(np.ptp(Q2, axis=0).max())          # the pieces lie within Qc (or its box)
    return (nQ, q0, RQ, Kc, corners, parts, part_counts, V, counts, NK, group,
            allv.min(axis=0), allv.max(axis=0), extent)


def _hidden_values(X, nP, Qc, blockers, st=None, budget=0.0, setup=None, weights=None,
                   bound_budget=None):
    """``F(x -> Qc) - F_occ(x -> Qc)`` for each point x of X (normal nP): the point form
    factor of the part of Qc that the blockers hide from x, and its error estimate.

    Built in Qc's plane (compiled, :mod:`exactff.area._hidden`): each blocker, clipped
    to the front of that plane, cut into convex pieces and clipped to the pyramid from x
    over Qc where Qc is strictly convex (else over a rectangle around it), is projected
    from x onto the plane (a projective map: its image stays convex, within the
    pyramid's base); each image less the images before it is added as disjoint convex
    pieces by half-plane splits alone, along the lines the edges lie on (traced from the
    planes through x, not from the rounded vertices), which over a rectangle are then
    cut by Qc's convex parts; the pieces are integrated by the sector sums (Eq. 3's
    kernel) from x. A point on Qc's plane sees nothing of it (0), nor does a blocker
    whose plane passes through x (seen edge-on).

    The estimate adds to the sector sums' rounding the effect of moving the pieces'
    boundaries by the splits' rounding (a few units of the largest coordinate per
    line) and by the clipped vertices' own rounding as the projection magnifies it
    (``moved``; the 3-D work is in doubles, and again in long double at a point where
    that is more than ``AREA_IMAGE_PRECISE_RTOL`` of Qc's size), through the kernel's
    largest value over the region's bounding box, ``h / (pi r^3)``. Where a point's
    images do not stay finite, or that rounding can move them by more than
    ``AREA_IMAGE_RTOL`` of Qc's size (a crossing or a blocker's vertex at the point, to
    rounding) and more of the value than ``budget`` (absolute; the caller's share of its
    tolerance), the engine computes that point's value
    (:func:`_hidden_values_by_engine`), counted in ``st["engine_fallbacks"]`` (and the
    points in ``st["engine_fallback_points"]``). With ``weights`` (each point's weight
    in the caller's rules, per unit area of the emitter) and ``bound_budget`` (a list
    of one number, what the caller's pair has left for this), such points whose bound
    ``0 <= hidden <= F(x -> Qc)`` costs the weighted sum at most that take it instead
    (``U / 2`` within ``U / 2`` and U's own estimate; the cost is taken off the
    budget; counted in ``st["bounded_points"]``): thin cells along a blocker that
    touches the emitter hold such points by the hundred, at a thousandth of the
    engine's cost each.
    ``setup``: :func:`_hidden_setup` of Qc and the blockers, where the caller has it.

    Returns
    -------
    (ndarray of shape (len(X),), ndarray of shape (len(X),))
    """
    nX = len(X)
    zero = np.zeros(nX)
    setup = _hidden_setup(Qc, blockers) if setup is None else setup
    if setup is None:
        return zero, zero
    if nX > tol.AREA_POINTS_PER_CALL:
        # in chunks: a point's pieces hold tens of vertices, and the sector sums'
        # temporaries a few dozen bytes each of them
        parts_ = [_hidden_values(X[k:k + tol.AREA_POINTS_PER_CALL], nP, Qc, blockers, st,
                                 budget, setup, None if weights is None else
                                 weights[k:k + tol.AREA_POINTS_PER_CALL], bound_budget)
                  for k in range(0, nX, tol.AREA_POINTS_PER_CALL)]
        return np.concatenate([h for h, _ in parts_]), np.concatenate([e for _, e in parts_])
    nQ, q0, RQ, Kc, corners, parts, part_counts, V, counts, NK, group, lo, hi, extent = setup
    # the scene's size here: the box of the blockers, Qc and the points
    size = float((np.maximum(hi, X.max(axis=0)) - np.minimum(lo, X.min(axis=0))).max())
    # the pieces, and their point form factors by the sector sums (Eq. 3's kernel) with
    # their own rounding (C1, C2 calibrated for the unit roundoff 2**-53), compiled
    (_, _, _, lost, reach, length, box, moved, dropped, H, rnd, back) = hidden_pieces(
        X, corners, q0, nQ, RQ[:2], V, counts, NK, group, tol.AREA_BACK_FACE_RTOL * size,
        tol.AREA_EDGE_ON_RTOL * size,
        tol.AREA_IMAGE_ULPS, tol.AREA_SLIVER_ULPS, tol.AREA_MAX_PIECES,
        tol.AREA_IMAGE_PRECISE_RTOL, extent, parts, part_counts, receiver_frame(nP),
        tol.C1, tol.C2, tol.EPS, False)
    if st is not None and back:
        st["back_faces"] = st.get("back_faces", 0) + int(back)
    # the clipping's rounding: each piece's boundary within delta of the exact one (a
    # few units of the largest coordinate for each clipping line a vertex may descend
    # from), through the kernel's bound h / (pi r^3) over the region's bounding box (r >=
    # the box's distance from x; the box holds the slivers dropped too, so this holds
    # for points that kept no piece at all)
    lines = int(counts.sum()) + len(corners) + int(part_counts.sum()) + 1
    delta = tol.AREA_BOOLEAN_ULPS * lines * tol.EPS * reach
    h = (X - q0) @ nQ
    foot = (X - q0) @ RQ[:2].T
    dx = np.maximum(0.0, np.maximum(box[:, 0] - foot[:, 0], foot[:, 0] - box[:, 2]))
    dy = np.maximum(0.0, np.maximum(box[:, 1] - foot[:, 1], foot[:, 1] - box[:, 3]))
    r = np.sqrt(h ** 2 + dx * dx + dy * dy)
    bound = np.divide(h, np.pi * r ** 3, out=np.zeros_like(r), where=(r > 0) & (h > 0))
    geo = moved * length * bound
    # and the slivers dropped (thinner than rounding), at the kernel's bound
    EH = rnd + (delta * length + dropped) * bound + geo
    # an image the vertices' rounding can move by more than AREA_IMAGE_RTOL of Qc's size
    # (a crossing near x, magnified by the projection), unless what that moves of the
    # value is within the caller's budget, is not to be trusted: that point goes to the
    # engine, as one through infinity
    lost |= ((moved > tol.AREA_IMAGE_RTOL * np.maximum(reach, extent))
             & ((length == 0) | (geo > budget)))
    if lost.any() and weights is not None and bound_budget is not None:
        # the hidden part lies between 0 and the unoccluded value: where the weights
        # make that cheap enough, it is the value
        U, EU = (v[0] for v in point_values(X[lost], nP, [Qc]))
        cost = float((weights[lost] * (0.5 * U + EU)).sum())
        if cost <= bound_budget[0]:
            bound_budget[0] -= cost
            H[lost], EH[lost] = 0.5 * U, 0.5 * U + EU
            if st is not None:
                st["bounded_points"] = st.get("bounded_points", 0) + int(lost.sum())
            lost[:] = False
    if lost.any():
        # an image through infinity or not to be trusted: the engine
        if st is not None:
            st["engine_fallbacks"] = st.get("engine_fallbacks", 0) + 1
            st["engine_fallback_points"] = st.get("engine_fallback_points", 0) + int(lost.sum())
        H[lost], EH[lost] = _hidden_values_by_engine(X[lost], nP, Qc, Kc)
    return nonnegative(H, EH, "hidden part"), EH


def _strictly_convex(Q2):
    """True where the 2-D polygon Q2 (counter-clockwise) turns left at every vertex by
    more than ``AREA_STRICT_TURN`` radians (no three vertices nearly on a line)."""
    e = np.roll(Q2, -1, axis=0) - Q2
    f = np.roll(e, -1, axis=0)
    turn = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    return bool(np.all(turn > tol.AREA_STRICT_TURN * np.linalg.norm(e, axis=1)
                       * np.linalg.norm(f, axis=1)))


def _hidden_values_by_engine(X, nP, Qc, blockers):
    """:func:`_hidden_values` by the engine instead (exact occluded point values on the
    sub-scene of Qc and the blockers, subtracted from the unoccluded ones): about a
    thousand times slower, used where a point's images cannot be trusted."""
    sub = Scene.from_polygons([Qc] + list(blockers))
    exact = Exact()
    FE = [exact.point_form_factors(sub, x, nP, error=True) for x in np.atleast_2d(X)]
    F = np.array([f for f, _ in FE])
    E = np.array([e for _, e in FE])
    U, EU = (v[0] for v in point_values(X, nP, [Qc]))
    est = EU + E[:, 0]
    return nonnegative(U - F[:, 0], est, "hidden part"), est


_RULE_PAIRS = tuple(tuple(roots_legendre(k) for k in orders) for orders in
                    (tol.AREA_RULE_ORDERS_MANY_CELLS, tol.AREA_RULE_ORDERS))
_CORNER_MIDDLE_RULE = roots_legendre(tol.AREA_CORNER_MIDDLE_ORDER)


def _rule_pair(T, rung, corner, tolerance):
    """The nodes and weights of the two rules of rung ``rung`` on the triangles T (t, 3,
    3): at rung 0 the symmetric rules of degree 4 and 8 (6 and 16 nodes), or where the
    first vertex is a corner that a blocker touches, the collapsed rules of the same
    degrees (3 and 5 points a side, 9 and 25 nodes: their collapsed vertex integrates
    functions of the direction from it); at rung 1 the collapsed rules of 6 and 10
    points a side."""
    # (symmetric only at coarse targets: at 1e-9 their difference missed the closed
    # Cornell box's back-to-right-wall error, 4.2e-10 against 1.8e-10)
    if rung == 0 and not corner and tolerance >= tol.AREA_LOW_RULES_TOLERANCE:
        return tuple(symmetric_triangle_rule(T, d) for d in tol.AREA_SYMMETRIC_DEGREES)
    return tuple(triangle_rule(T, rule) for rule in _RULE_PAIRS[rung])


def _triangle_unoccluded(T, nP, Qc):
    """``int_T F(x -> Qc) dA_x`` for each triangle T (t, 3, 3) in the plane of normal nP,
    unoccluded (Qc wholly in front of that plane, each T in front of Qc's), and its
    rounding estimate: by reciprocity ``A_Qc F(Qc -> T)``, the closed form
    (:func:`~exactff.area.contour.unoccluded_pairs`, no fallback: where its terms cancel
    the estimate says so)."""
    if not len(T):
        return np.zeros(0), np.zeros(0)
    # counter-clockwise seen from nP's side
    flip = np.einsum("tx,x->t", cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), nP) < 0
    T = np.where(flip[:, None, None], T[:, ::-1], T)
    f, e = unoccluded_pairs(Qc, list(T), far=False, atol=np.inf,
                            parts=[(Qc, t) for t in T])
    area_Q = float(np.linalg.norm(area_vector(Qc)))
    return area_Q * f, area_Q * e


def _triangle_areas(T):
    """The areas of triangles T (t, 3, 3)."""
    return 0.5 * np.linalg.norm(cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)


def _corner_first(T, blockers, nP, dP, reach=0.0):
    """The triangles T (t, 3, 3), each with first a vertex where a blocker's vertex
    touches the emitter's plane, if it has one (within ``AREA_HULL_RTOL`` of the
    triangle's size of the plane, and of that vertex or within ``reach`` of it: the
    cells' corners may lie as far from the events' crossing as the cut lines were
    lengthened, :func:`_cells`; the first such blocker vertex, in order). Near such a point the hidden part depends on the direction from it (to first
    order), and the collapsed rule, whose collapsed vertex is the first, integrates
    functions of that direction alone without cutting towards the point. A triangle with
    two or three such vertices is first cut in four at its edges' midpoints (so that
    each of its corner quarters has one): returns as many triangles or more, and per
    triangle whether its first vertex is such a corner."""
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
        a_, b_, c_ = T[several, 0], T[several, 1], T[several, 2]
        ab, bc, ca = (a_ + b_) / 2, (b_ + c_) / 2, (c_ + a_) / 2
        quarters = np.stack([np.stack(t, axis=1) for t in
                             ((a_, ab, ca), (ab, b_, bc), (ca, bc, c_), (ab, bc, ca))],
                            axis=1).reshape(-1, 3, 3)
        T = np.concatenate([T[~several], quarters])
    touched, first = touching(T)
    # the vertex touched by the earliest blocker vertex first
    shift = np.where(touched.any(axis=1), np.argmin(first, axis=1), 0)
    return (T[np.arange(len(T))[:, None], (np.arange(3)[None, :] + shift[:, None]) % 3],
            touched.any(axis=1))


def _occluded_pair(S, Pc, Qc, nP, tolerance, area_P, whole, shortcuts=True, st=None,
                   rtol=None, solid=None, inner=None):
    """``(1 / A_P) int_Pc F_occ(x -> S[0]) dA`` with S = [receiver, blockers...], as the
    unoccluded value (the contour integral, exact) less the integral of the hidden part
    ``F(x -> Qc) - F_occ(x -> S[0])`` (exact point values of the hidden region, built
    in Qc's plane: :func:`_hidden_values`). The hidden part is smooth where the polygons
    touch (the unoccluded part carries the edge singularities), so it is integrated over
    the cells of Pc between visibility events, each cell's triangles by two collapsed
    Gauss-Legendre rules (6 and 10 points a side), a triangle cut in four where the two
    differ by more than its share of the tolerance. Where the events cut Pc into more
    than ``AREA_MANY_CELLS`` triangles (small ones), or the target is at least
    ``AREA_LOW_RULES_TOLERANCE``, each starts with a lower pair (degrees 4 and 8: the
    symmetric rules of 6 and 16 points, or the collapsed ones of 3 and 5 points a side
    where a blocker touches its first vertex; :func:`_rule_pair`) and takes the higher
    pair where that pair misses its share.
    Returns the value, its error estimate (the contour sum's, the rules' differences,
    the point values' bounds) and the number of point values used.

    The rules' target is the absolute ``tolerance``, or with ``rtol`` the bound
    ``max(tolerance, rtol * F)``: first with the unoccluded value for F (the value is
    at most that), and where the estimate then misses ``max(tolerance, rtol * |value|)``
    once more with ``value - estimate`` for F (a lower bound where the estimate holds).
    ``whole``: the pair's unoccluded value and estimate, per unit area of P (the
    row's occluded pairs take theirs together, :func:`_unoccluded_values`, the estimate
    within ``AREA_WHOLE_TOLERANCE_SHARE`` of the tolerance). ``solid``: as for
    :func:`_event_lines`; ``inner``: for each polygon of S with a solid, a point inside
    the solid's hull (NaN elsewhere; :func:`_hidden_setup`)."""
    target = tolerance if rtol is None else max(tolerance, rtol * whole[0])
    value, err, points = _hidden_integral(S, Pc, Qc, nP, target, area_P, whole, shortcuts, st,
                                          solid, inner)
    if rtol is not None and target > tolerance and misses_tolerance(value, err, rtol,
                                                                     atol=tolerance):
        target = max(tolerance, rtol * max(value - err, 0.0))
        value, err, more = _hidden_integral(S, Pc, Qc, nP, target, area_P, whole, shortcuts,
                                           st, solid, inner)
        points += more
    return value, err, points


def _hidden_integral(S, Pc, Qc, nP, tolerance, area_P, whole, shortcuts, st, solid=None,
                     inner=None):
    """The adaptive integral of :func:`_occluded_pair` to the absolute target
    ``tolerance``, with ``whole`` the pair's unoccluded value and estimate (per unit area
    of P)."""
    R = receiver_frame(nP)
    c = Pc.mean(axis=0)
    dP = float(nP @ Pc[0])
    radius = (1.0 + tol.AREA_HIDDEN_PAD) * float(np.linalg.norm(Pc - c, axis=1).max())
    lines = _event_lines(S, nP, dP, R, c, radius, Qc, shortcuts, st, solid)
    # the emitter cut along the events: in floating point with the lines lengthened
    # across its boundary, else as cut, else noded on a grid of AREA_HULL_RTOL of P's
    # size (the cuts move by that much), each way with and without lengthening; the
    # first whose cells cover P (to AREA_CELL_COVER_RTOL) is taken, else the one that
    # covers most (the area missing is in the estimate). GEOS may give up noding, or
    # polygonizing drop a ring it finds invalid and the cell inside it (7 % of a wall of
    # the closed Cornell box): counted
    area_Pc = float(np.linalg.norm(area_vector(Pc)))
    cells, failure = None, None
    for k, (grid, lengthen) in enumerate(((None, True), (None, False),
                                          (tol.AREA_HULL_RTOL * radius, True),
                                          (tol.AREA_HULL_RTOL * radius, False))):
        try:
            T = _cells(Pc, nP, lines, R, c, grid=grid, lengthen=lengthen)
        except shapely.errors.GEOSException as exc:
            failure = exc
            continue
        if cells is None or len(T) and _triangle_areas(T).sum() > _triangle_areas(cells).sum():
            cells = T
        if _triangle_areas(cells).sum() >= (1 - tol.AREA_CELL_COVER_RTOL) * area_Pc:
            break
    if k and st is not None:
        st["cell_fallbacks"] = st.get("cell_fallbacks", 0) + 1
    if cells is None:
        raise NumericalError(f"could not cut the emitter along its {len(lines)} "
                             f"visibility events: {failure}") from failure
    # a corner of a cell may lie as far from the crossing of its events as the cut lines
    # were lengthened (l_room_f3a, row 8: 1.4e-9 from the walls' corner on the ceiling,
    # which the collapsed vertex then missed, and a triangle at the last level kept an
    # estimate of 1.3e-9)
    T, corner = _corner_first(cells, S[1:], nP, dP,
                              2.0 * tol.AREA_CUT_EXTEND_RTOL * np.sqrt(area_Pc))
    depth = np.zeros(len(T), dtype=int)
    # many cells (small ones) start with the low pair of rules, few with the high pair
    # (and so do the triangles they are cut into); at a coarse target, all start low
    start = int(len(T) <= tol.AREA_MANY_CELLS and tolerance < tol.AREA_LOW_RULES_TOLERANCE)
    rung = np.full(len(T), start)
    setup = (_hidden_setup(Qc, S[1:]) if solid is None or inner is None
             else _hidden_setup(Qc, S[1:], solid[1:], inner[1:]))
    # what the bound 0 <= hidden <= unoccluded may cost the pair (_hidden_values)
    bound_budget = [tol.AREA_IMAGE_BUDGET_SHARE * tolerance]
    total_area = float(_triangle_areas(T).sum())
    slivers = points = 0
    # the triangles accepted: vertices, level, rung; per unit area of P, the high rule's
    # integral of the hidden part H, the rules' difference on H, the point values'
    # estimates, and the same two rules' integrals of U (the unoccluded point values)
    acc = {k: [] for k in ("T", "depth", "rung", "corner", "hi", "diff", "rnd", "hiU", "loU",
                           "lo", "rndU", "checked")}
    while True:
        T, depth, rung, corner, sl, pts = _adaptive_levels(
            T, depth, rung, corner, nP, Qc, S, st, setup, tolerance, area_P, total_area,
            start, shortcuts, bound_budget, acc)
        slivers += sl
        points += pts
        # the rules' errors on U add up to the error of their sum over the emitter,
        # known exactly (the pair's closed form less the slivers', at most their area):
        # where the differences bounded every triangle's errors on H and on F_occ = U -
        # H, that sum is within the differences' (_checked_difference); where it is
        # not, the triangles are checked one by one against their own closed forms, and
        # those whose differences prove too small are refined
        cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in acc.items()}
        dF = np.abs((cat["hiU"] - cat["loU"]) - (cat["hi"] - cat["lo"]))
        lost = (slivers + max(area_Pc - total_area, 0.0)) / area_P
        missed_U = (abs(float(cat["hiU"].sum()) - whole[0]) - float((cat["diff"] + dF).sum())
                    - float(cat["rndU"].sum()) - whole[1] - lost)
        todo = np.flatnonzero(~cat["checked"].astype(bool))
        if missed_U <= 0 or not len(todo):
            break
        Ta = np.concatenate(acc["T"])
        exU, exE = _triangle_unoccluded(Ta[todo], nP, Qc)
        shown = (np.abs(cat["hiU"][todo] - exU / area_P) - dF[todo] - cat["rndU"][todo]
                 - exE / area_P)
        cat["diff"][todo] = np.maximum(cat["diff"][todo], shown)
        cat["checked"][todo] = True
        share = 0.5 * tolerance / total_area * _triangle_areas(Ta)
        suspect = np.zeros(len(Ta), dtype=bool)
        suspect[todo] = shown > tol.AREA_RULE_CHECK_SHARE * share[todo]
        a_rung, a_depth = cat["rung"].astype(int), cat["depth"].astype(int)
        again = suspect & ~((a_rung == 1) & (a_depth >= tol.AREA_MAX_DEPTH))
        if st is not None:
            st["checked_triangles"] = st.get("checked_triangles", 0) + len(todo)
            st["refined_triangles"] = st.get("refined_triangles", 0) + int(again.sum())
        keep = ~again
        for k in acc:
            acc[k] = [cat[k][keep] if k != "T" else Ta[keep]]
        if not again.any():
            break
        # the suspects start again: rung 0 takes the high pair, rung 1 is cut in four
        T, depth, rung, corner = _refined(Ta[again], a_depth[again], a_rung[again],
                                          cat["corner"][again].astype(bool), start)
    cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in acc.items()}
    hidden = 0.5 * slivers / area_P + float(cat["hi"].sum())
    err = 0.5 * slivers / area_P + float((cat["diff"] + cat["rnd"]).sum())
    value = whole[0] - hidden
    err += max(area_Pc - total_area, 0.0) / area_P      # cells dropped or lost
    return value, err + whole[1], points


def _refined(T, depth, rung, corner, start):
    """Triangles that missed their share: at rung 0 the same triangle at rung 1; at rung 1
    its four quarters (cut at its edges' midpoints; the first keeps a corner, the first
    vertex) at the level below, on rung ``start``. Returns ``(T, depth, rung, corner)``."""
    again, split = rung == 0, rung == 1
    a_, b_, c_ = T[split, 0], T[split, 1], T[split, 2]
    ab, bc, ca = (a_ + b_) / 2, (b_ + c_) / 2, (c_ + a_) / 2
    T = np.concatenate([T[again], np.stack([np.stack(t, axis=1) for t in
                        ((a_, ab, ca), (ab, b_, bc), (ca, bc, c_), (ab, bc, ca))],
                        axis=1).reshape(-1, 3, 3)])
    depth = np.concatenate([depth[again], np.repeat(depth[split] + 1, 4)])
    corner = np.concatenate([corner[again], np.stack(
        [corner[split]] + [np.zeros(int(split.sum()), dtype=bool)] * 3, axis=1).ravel()])
    rung = np.concatenate([np.ones(int(again.sum()), dtype=int),
                           np.full(4 * int(split.sum()), start)])
    return T, depth, rung, corner


def _adaptive_levels(T, depth, rung, corner, nP, Qc, S, st, setup, tolerance, area_P,
                     total_area, start, shortcuts, bound_budget, acc):
    """:func:`_hidden_integral`'s adaptive rules, level by level until every triangle is
    accepted: the accepted ones appended to ``acc`` (see there). Returns the (empty)
    triangles left, the slivers' area (not evaluated) and the points used."""
    slivers = points = 0
    while len(T):
        # a sliver (between nearly coincident events) is not evaluated: the hidden part
        # is between 0 and 1, so its integral is half the sliver's area, within as much
        area_t = _triangle_areas(T)
        sliver = area_t / area_P <= tol.AREA_SLIVER_SHARE * tolerance
        slivers += float(area_t[sliver].sum())
        T, depth, rung, area_t = T[~sliver], depth[~sliver], rung[~sliver], area_t[~sliver]
        corner = corner[~sliver]
        if not len(T):
            break
        # every other triangle of this level together: its rules' nodes, one call
        X, weights, groups = [], [], []
        for r, at_corner in ((0, False), (0, True), (1, False), (1, True)):
            sel = np.flatnonzero((rung == r) & (corner == at_corner))
            if len(sel):
                (Xl, Wl), (Xh, Wh) = _rule_pair(T[sel], r, at_corner, tolerance)
                # at a corner on the lower pair, a third rule between the two
                Xm, Wm = (triangle_rule(T[sel], _CORNER_MIDDLE_RULE) if r == 0 and at_corner
                          else (np.zeros((len(sel), 0, 3)), np.zeros((len(sel), 0))))
                X.append(np.concatenate([Xl, Xh, Xm], axis=1).reshape(-1, 3))
                weights.append(np.concatenate([Wl, Wh, Wm], axis=1).reshape(-1) / area_P)
                groups.append((sel, Wl, Wh, Wm))
        X = np.concatenate(X)
        H, EH = _hidden_values(X, nP, Qc, S[1:], st,
                               budget=tol.AREA_IMAGE_BUDGET_SHARE * tolerance, setup=setup,
                               weights=np.concatenate(weights) if shortcuts else None,
                               bound_budget=bound_budget)
        # the unoccluded point values at the same nodes, for the check of the rules'
        # differences (_hidden_integral)
        U, EU = (v[0] for v in point_values(X, nP, [Qc]))
        points += H.size
        hi, lo, mid, rnd = (np.empty(len(T)) for _ in range(4))
        hiU, loU, rndU = np.empty(len(T)), np.empty(len(T)), np.empty(len(T))
        at = 0
        for sel, Wl, Wh, Wm in groups:
            nl, nh = Wl.shape[1], Wl.shape[1] + Wh.shape[1]
            n = len(sel) * (nh + Wm.shape[1])
            Hg, EHg = H[at:at + n].reshape(len(sel), -1), EH[at:at + n].reshape(len(sel), -1)
            Ug, EUg = U[at:at + n].reshape(len(sel), -1), EU[at:at + n].reshape(len(sel), -1)
            at += n
            hi[sel], lo[sel] = (Wh * Hg[:, nl:nh]).sum(axis=1), (Wl * Hg[:, :nl]).sum(axis=1)
            # the third rule's value, where there is one (else the low rule's)
            mid[sel] = (Wm * Hg[:, nh:]).sum(axis=1) if Wm.shape[1] else lo[sel]
            hiU[sel], loU[sel] = (Wh * Ug[:, nl:nh]).sum(axis=1), (Wl * Ug[:, :nl]).sum(axis=1)
            # the rules' nodes' estimates: they bound what the point values' errors can
            # hide of the rules' differences
            rnd[sel] = ((Wh * EHg[:, nl:nh]).sum(axis=1) + (Wl * EHg[:, :nl]).sum(axis=1)
                        + (Wm * EHg[:, nh:]).sum(axis=1))
            rndU[sel] = (Wh * EUg[:, nl:nh]).sum(axis=1) + (Wl * EUg[:, :nl]).sum(axis=1)
        hi, lo, mid, rnd, hiU, loU, rndU = (v / area_P for v in (hi, lo, mid, rnd, hiU, loU,
                                                                 rndU))
        # the high rule's error estimated by the low rule's difference from it, and at a
        # corner on the lower pair also by the third rule's (between the two): at a
        # corner of gunter1 the 3- and 5-point rules agreed to 6.7e-11 where the 5-point
        # one was 2.5e-10 off (3, 4, 5, 6 points: 3.2e-10, 1.9e-9, 2.5e-10, -3.2e-11)
        diff = np.maximum(np.abs(hi - lo), np.abs(hi - mid))
        # half the tolerance for the rules' differences: what the triangles accepted so
        # far left of it is shared among the others by area (at the first level, the
        # triangle's share of the emitter), never less than the triangle's share of the
        # emitter (triangles accepted at the last level above their share would
        # otherwise leave none, and every other triangle would be cut to the last level)
        rules_err = float(sum(float(d.sum()) for d in acc["diff"]))
        budget = max(0.5 * tolerance - rules_err, 0.0)
        share = np.maximum(budget / area_t.sum(), 0.5 * tolerance / total_area) * area_t
        missed = diff > share
        # a triangle the low pair missed takes the high pair; one the high pair missed
        # is cut in four at its edges' midpoints (up to AREA_MAX_DEPTH)
        again = missed & (rung == 0)
        split = missed & (rung == 1) & (depth < tol.AREA_MAX_DEPTH)
        done = ~(again | split)
        for k, v in (("T", T), ("depth", depth), ("rung", rung), ("corner", corner),
                     ("hi", hi), ("lo", lo), ("diff", diff), ("rnd", rnd), ("hiU", hiU),
                     ("loU", loU), ("rndU", rndU), ("checked", np.zeros(len(T), dtype=bool))):
            acc[k].append(v[done])
        T, depth, rung, corner = _refined(T[again | split], depth[again | split],
                                          rung[again | split], corner[again | split], start)
    return T, depth, rung, corner, slivers, points


def _front_pairs(polys, i, nP, padded):
    """The receivers j of row i with each polygon's part in front of the other's plane,
    and those parts, as a list of ``(j, Pc, Qc)``: the distances for all receivers at
    once, the decision by :func:`~exactff.area.contour.front_parts`."""
    V, _, _, N = padded
    P = polys[i]
    dQ = (V - P[0]) @ nP                                    # (n, kmax)
    dP = np.einsum("njx,nx->nj", P[None] - V[:, :1], N)     # (n, kP)
    live = (dQ.max(axis=1) > 0) & (dP.max(axis=1) > 0)
    live[i] = False
    J = np.flatnonzero(live)
    Pcs, Qcs = front_parts(P, nP, [polys[j] for j in J], N[J], dP[J], dQ[J])
    return [(int(j), Pc, Qc) for j, Pc, Qc in zip(J, Pcs, Qcs)
            if Pc is not None and Qc is not None]


def _tie_covers(scene):
    """The depth ties of coplanar overlapping polygons, for area rows: per polygon j, the
    polygons that cover part of it from any point in front of it, by the tie rule
    (:func:`exactff.predicates.tie_priority`): those coplanar with it
    (:func:`exactff.predicates.coplanar_pairs`, the BSP tree's rule), facing the same way
    and earlier in input order, whose overlap with it has an area above
    ``AREA_SLIVER_CELL`` of its own (a window on its wall, given first: the wall
    receives only around it). A polygon facing the other way shows its back to every
    point in front of j, and the rule puts j in front of it. Returns a dict of the
    covered polygons only, ``{j: [k, ...]}``."""
    polys = [np.asarray(p, dtype=float) for p in scene.polygons]
    n = len(polys)
    if n < 2:
        return {}
    N, D = scene.normals, scene.plane_offsets
    lo = np.array([p.min(axis=0) for p in polys])
    hi = np.array([p.max(axis=0) for p in polys])
    size = float(np.ptp(scene.vertices, axis=0).max()) or 1.0
    near = tol.AREA_HULL_RTOL * size
    out = {}
    for j in range(1, n):
        # earlier polygons facing the same way whose boxes overlap j's with interior
        # (coplanar ones share a flat box: its thickness is not required to overlap)
        k = np.flatnonzero((N[:j] @ N[j] > 0)
                           & np.all((hi[:j] > lo[j] - near) & (lo[:j] < hi[j] + near), axis=1))
        if not len(k):
            continue
        k = k[coplanar_pairs(scene.vertices, scene.offsets, N, D, k, np.full(len(k), j))]
        if not len(k):
            continue
        _, q0, RQ, Q2 = _plane_frame(polys[j])
        Qs = shapely.Polygon(Q2)
        K2 = shapely.polygons([(polys[m] - q0) @ RQ[:2].T for m in k])
        over = shapely.area(shapely.intersection(K2, Qs)) > tol.AREA_SLIVER_CELL * Qs.area
        if over.any():
            out[j] = [int(m) for m in k[over]]
    return out


def _uncovered(Qc, covers):
    """The part of the receiver Qc (clipped, planar) that the polygons ``covers`` do not
    cover (:func:`_tie_covers`), as triangles (t, 3, 3), counter-clockwise seen from Qc's
    front, in Qc's plane (the covers projected onto it); none where nothing is left."""
    nQ, q0, RQ, Q2 = _plane_frame(Qc)
    whole = shapely.Polygon(Q2)
    region = shapely.difference(whole, shapely.union_all(
        shapely.polygons([(K - q0) @ RQ[:2].T for K in covers])))
    parts = shapely.get_parts(region)
    parts = parts[(shapely.get_type_id(parts) == 3)
                  & (shapely.area(parts) > tol.AREA_SLIVER_CELL * whole.area)]
    if not len(parts):
        return np.zeros((0, 3, 3))
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(parts))
    uv = shapely.get_coordinates(shapely.get_exterior_ring(tris)).reshape(-1, 4, 2)[:, :3]
    T = q0 + uv @ RQ[:2]
    flip = np.einsum("tx,x->t", cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), nQ) < 0
    T = np.where(flip[:, None, None], T[:, ::-1], T)
    return T[_triangle_areas(T) > tol.AREA_SLIVER_CELL * whole.area]


def _unoccluded_values(polys, i, pairs, shortcuts, st, tolerance, rtol):
    """The values and estimates of a row's unoccluded pairs ``(j, Pc, Qc)``, all at once
    by the closed form (:func:`~exactff.area.contour.unoccluded_pairs`), with the far
    rule (only with ``shortcuts``) and mpmath where its estimate misses the row's
    target, ``max(tolerance, rtol * F)``. The one place where a row's unoccluded pairs
    are computed.

    Returns
    -------
    (list of int, ndarray, ndarray)
        The receivers, their values and their estimates.
    """
    js = [j for j, _, _ in pairs]
    before = CLOSED_FORM_COUNTS["far_rule"]
    f, e = unoccluded_pairs(polys[i], [polys[j] for j in js], far=shortcuts,
                            rtol=max(rtol or 0.0, tol.AREA_CLOSED_RTOL), atol=tolerance,
                            parts=[(Pc, Qc) for _, Pc, Qc in pairs])
    st["far_pairs"] += CLOSED_FORM_COUNTS["far_rule"] - before
    return js, f, e


def area_row(scene, i, tolerance, *, rtol=None, shortcuts=True, stats=None):
    """Row i of :func:`exactff.area_form_factors` and its estimates.

    The pairs of the row are decided together: the receivers in front of P (and P in
    front of them, :func:`_front_pairs`), then each pair's blockers by shaft culling
    (:func:`_shaft`, all pairs and polygons at once) and the hull test on what survives
    (:func:`_hull_blockers`); occluded pairs are integrated one by one
    (:func:`_occluded_pair`), after their unoccluded values are taken together
    (:func:`_unoccluded_values`), and the unoccluded pairs together at the end.

    Parameters
    ----------
    scene : Scene
    i : int
        The emitter.
    tolerance : float
        Absolute error allowed per value (the adaptive rules' target).
    rtol : float, optional
        Also allowed: this share of the value; the bound is ``max(tolerance, rtol * F)``.
    shortcuts : bool, default True
        False disables every shortcut (for testing that they never change a result
        beyond the estimates): shaft culling and the hull test (every other polygon is
        then a blocker of every pair), the far-field rule (the contour integral for
        every pair) and the cull of blocker-blocker events whose lines of sight miss
        the receiver or that join two faces of one convex solid (:func:`_closed_solids`).
    stats : dict, optional
        Filled with this row's counters (:data:`STATS`).

    Returns
    -------
    (ndarray of shape (len(scene),), ndarray of shape (len(scene),))
        The values and their error estimates.
    """
    st = {k: 0 for k in STATS}
    polys = [np.asarray(p, dtype=float) for p in scene.polygons]
    padded = _padded(polys)
    V = padded[0]
    P = polys[i]
    scale = float(np.ptp(scene.vertices, axis=0).max()) or 1.0
    near = tol.AREA_HULL_RTOL * scale
    AP = area_vector(P)
    area_P = float(np.linalg.norm(AP))
    nP = AP / area_P
    n = len(polys)
    f, e = np.zeros(n), np.zeros(n)
    pairs = _front_pairs(polys, i, nP, padded)
    # a receiver that coplanar polygons earlier in input order partly cover (the tie
    # rule) receives only its uncovered part, as triangles: receivers n, n + 1, ... of
    # the row, each adding to its polygon's value (owner)
    covers = prepared(scene).get("area_tie_covers", _tie_covers)
    owner = list(range(n))
    receivers = list(polys)
    if covers and any(j in covers for j, _, _ in pairs):
        tied = []
        for j, Pc, Qc in pairs:
            if j not in covers:
                tied.append((j, Pc, Qc))
                continue
            for T in _uncovered(Qc, [polys[k] for k in covers[j]]):
                tied.append((len(receivers), Pc, T))
                receivers.append(T)
                owner.append(j)
        pairs = tied
    owner = np.array(owner)
    fx, ex = np.zeros(len(receivers)), np.zeros(len(receivers))
    # the tolerance of a value shared among its receiver's parts
    share = 1.0 / np.bincount(owner, minlength=n)[owner]
    tolerance_all = tolerance * float(share.min())

    def result():
        # each receiver's parts added up
        if stats is not None:
            stats.update(st)
        return (np.bincount(owner, fx, minlength=n)[:n], np.bincount(owner, ex, minlength=n)[:n])

    if not pairs:
        return result()
    # a convex enclosure (every vertex in front of or on every polygon's plane, no
    # coplanar overlaps): nothing can come between any pair
    enclosure = shortcuts and is_convex_enclosure(scene)
    if enclosure:
        st["enclosure_unoccluded_pairs"] += len(pairs)
        js, fx[js], ex[js] = _unoccluded_values(receivers, i, pairs, shortcuts, st,
                                                tolerance_all, rtol)
        return result()
    if shortcuts:
        J = owner[[j for j, _, _ in pairs]]
        boxes = np.array([(Pc.min(axis=0), Pc.max(axis=0), Qc.min(axis=0), Qc.max(axis=0))
                          for _, Pc, Qc in pairs])
        # the pairs in batches: each batch tests its pairs against every polygon
        per = max(1, tol.AREA_SHAFT_ENTRIES_PER_CALL // len(polys))
        cands = [c for s in range(0, len(J), per)
                 for c in _shaft(padded, i, J[s:s + per], boxes[s:s + per], nP, P[0], near, st)]
    if shortcuts:
        solids = prepared(scene).get("area_convex_solids", _convex_solids)
    unoccluded = []               # (j, Pc, Qc): computed together at the end
    occluded = []                 # ((j, Pc, Qc), blockers, solid, inner): one by one
    for a, (j, Pc, Qc) in enumerate(pairs):
        if shortcuts:
            B = _hull_blockers(V, cands[a], Pc, Qc, near)
            st["hull_culled_blockers"] += len(polys) - 2 - len(B)
        else:
            B = [k for k in range(len(polys)) if k not in (i, owner[j])]
        if B:
            st["occluded_pairs"] += 1
            solid = inner = None
            if shortcuts:
                jj = owner[j]
                solid = np.concatenate([[-1], _closed_solids(
                    solids, np.array(B), (scene.normals[[i, jj]], scene.plane_offsets[[i, jj]]))])
                # a point inside each solid's hull, the mean of its vertices, where every
                # member is a blocker, the emitter, the receiver, or on or behind one's
                # plane (no line of sight meets it): one culled otherwise, as within
                # rounding of the shaft's planes, would not hide what the members seen
                # from behind hide, and they are skipped
                inner = np.full((len(solid), 3), np.nan)
                kept = set(B) | {i, jj}
                N, D = scene.normals, scene.plane_offsets
                for g in set(solid[solid >= 0].tolist()):
                    if all(k in kept or (polys[k] @ N[i] - D[i]).max() <= 0
                           or (polys[k] @ N[jj] - D[jj]).max() <= 0
                           for k in np.flatnonzero(solids[0] == g).tolist()):
                        inner[solid == g] = solids[2][g].mean(axis=0)
            occluded.append(((j, Pc, Qc), B, solid, inner))
            continue
        if len(polys) > 2 and shortcuts:
            st["hull_unoccluded_pairs"] += 1
        unoccluded.append((j, Pc, Qc))
    if occluded:
        # the occluded pairs unoccluded, together: each estimate may take a share of the
        # tolerance
        _, whole, whole_err = _unoccluded_values(
            receivers, i, [pair for pair, _, _, _ in occluded], shortcuts, st,
            tol.AREA_WHOLE_TOLERANCE_SHARE * tolerance_all, None)
    for ((j, Pc, Qc), B, solid, inner), w, we in zip(occluded, whole if occluded else [],
                                                    whole_err if occluded else []):
        fx[j], ex[j], points = _occluded_pair([receivers[j]] + [polys[k] for k in B], Pc, Qc,
                                              nP, tolerance * share[j], area_P,
                                              (float(w), float(we)),
                                              shortcuts, st, rtol, solid, inner)
        st["point_values"] += points
        fx[j] = nonnegative(fx[j], ex[j])
    if unoccluded:
        js, fx[js], ex[js] = _unoccluded_values(receivers, i, unoccluded, shortcuts, st,
                                                tolerance_all, rtol)
    return result()
