"""Which polygons matter to a pair of an area row: the receivers in front of the
emitter, each pair's possible blockers (shaft culling, then the exact hull test), the
scene's convex solids (between whose faces there is no visibility event), and the
coplanar polygons that cover part of a receiver by the tie rule.
"""

from typing import NamedTuple

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from .. import _tolerances as tol
from ..geometry import cross, hull_blockers, plane_frame
from ..predicates import coplanar_band_sides, coplanar_pairs
from ..rings import concatenated, padded
from ._row_culling import row_blockers as _compiled_row_blockers
from .closed_form import front_distances, front_parts
from .rules import triangle_areas

__all__ = ["ConvexSolids", "padded_polygons", "front_pairs", "hull_blockers", "pair_blockers",
           "shaft", "row_blockers",
           "convex_solids", "closed_solids", "tie_covers", "uncovered"]


def padded_polygons(polys):
    """The scene's polygons as one array (n, kmax, 3), short ones padded by repeating
    their last vertex, with their bounding boxes and unit normals (Newell, relative to
    the first vertex as :func:`area_vector`; the repeats add nothing)."""
    V, _ = padded(polys)
    W = V - V[:, :1]
    A = 0.5 * cross(W, np.roll(W, -1, axis=1)).sum(axis=1)
    return V, V.min(axis=1), V.max(axis=1), A / np.linalg.norm(A, axis=1)[:, None]


def pair_blockers(padded, i, j, Pc, Qc, scale, shortcuts=True):
    """Polygons (indices) that may hide part of Qc from part of Pc: those reaching into
    the interior of the convex hull of both (the hull test alone, for one pair: what
    :func:`shaft` decides for a whole row before the hull test). ``padded`` is
    :func:`padded_polygons` of the scene. Without ``shortcuts``, every polygon but i and j."""
    V, lo_k, hi_k = padded[:3]
    if not shortcuts:
        return [k for k in range(len(V)) if k not in (i, j)]
    pts = np.vstack([Pc, Qc])
    near = tol.AREA_HULL_RTOL * scale
    lo, hi = pts.min(axis=0) - near, pts.max(axis=0) + near
    cand = np.all((hi_k >= lo) & (lo_k <= hi), axis=1)
    cand[[i, j]] = False
    return hull_blockers(V, np.flatnonzero(cand), Pc, Qc, near)


#: The box edges the shaft's side planes join: two axes and a direction along each.
_SHAFT_EDGES = tuple((a, b, sa, sb) for a, b in ((0, 1), (0, 2), (1, 2))
                     for sa in (1.0, -1.0) for sb in (1.0, -1.0))


def shaft(padded, i, J, boxes, nP, p0, near, st):
    """The blockers of each pair (i, J[a]) of a row that survive shaft culling (Haines &
    Wallace 1991), decided for all pairs and all polygons at once: a polygon stays a
    candidate only if it reaches into the open interior of the pair's bounding box, is
    not on or behind P's plane nor on or behind the receiver's (rays leave P's front and
    reach Q's front), and is not on or outside one of the shaft's side planes, the
    planes through an edge of each of the two polygons' boxes where one box extends
    beyond the other along one axis and the other along a second (each is a supporting
    plane of both boxes, so the shaft holds the convex hull of the pair: a polygon it
    rejects lies outside that hull, to ``near / 2``, and hides nothing). What survives
    goes to the hull test (:func:`hull_blockers`). Rows take both compiled
    (:func:`row_blockers`); this is their reference (tests/test_area_shaft.py).

    Parameters
    ----------
    padded : tuple
        :func:`padded_polygons` of the scene.
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
        # so small that their squares underflow, and a normal of 0 would put every
        # candidate on the plane and drop it (pinned in tests/test_area_shaft.py:
        # test_shaft_planes_of_tiny_box_offsets_keep_their_blockers)
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
    st.shaft_culled_blockers += int(boxed.sum() - left.sum())
    st.shaft_unoccluded_pairs += int(np.count_nonzero((boxed > 0) & (left == 0)))
    return np.split(k, np.cumsum(left)[:-1])


def row_blockers(padded, i, J, parts, nP, p0, near, st):
    """The blockers of each pair (i, J[a]) of a row: :func:`shaft` and then
    :func:`hull_blockers` on what it leaves, in one compiled call with the GIL released
    (``exactff/_core/row_culling.cpp``; those two are its reference). The hull's faces
    are the planes through three of the pair's vertices with all of them on one side (a
    face whose plane its rounding does not fix to a tenth of ``near`` is left out, which
    only keeps more blockers); a pair of more than ``AREA_HULL_MAX_POINTS`` vertices
    keeps every polygon the shaft leaves.

    Parameters
    ----------
    padded : tuple
        :func:`padded_polygons` of the scene.
    i : int
        The emitter.
    J : ndarray of shape (m,)
        The receivers.
    parts : sequence of (ndarray, ndarray)
        Per pair, the clipped emitter and the clipped receiver (:func:`front_pairs`).
    nP, p0 : ndarray of shape (3,)
        P's unit normal and a point of its plane.
    near : float
        The hull test's distance (``AREA_HULL_RTOL`` of the scene's size).
    st : AreaStats
        Counts ``shaft_culled_blockers`` and ``shaft_unoccluded_pairs`` as :func:`shaft`.

    Returns
    -------
    list of ndarray
        Per pair, its blockers (polygon indices, increasing).

    Examples
    --------
    Two unit squares facing each other 1 apart, a plate between them and one beside:

    >>> from exactff.area.row import AreaStats
    >>> sq = lambda z, up: np.array([[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]][::1 if up else -1],
    ...                             float)
    >>> polys = [sq(0, True), sq(1, False), sq(0.5, True) * [0.5, 0.5, 1] + [0.25, 0.25, 0],
    ...          sq(0.5, True) + [3, 0, 0]]
    >>> pad = padded_polygons(polys)
    >>> (j, Pc, Qc), = [t for t in front_pairs(polys, 0, pad[3][0], pad) if t[0] == 1]
    >>> row_blockers(pad, 0, np.array([j]), [(Pc, Qc)], pad[3][0], polys[0][0], 1e-12, AreaStats())
    [array([2])]
    """
    V, lo_k, hi_k, N = padded
    J = np.asarray(J, dtype=np.int64)
    if len(J) == 0:
        return []
    VP, po = concatenated([Pc for Pc, _ in parts])
    VQ, qo = concatenated([Qc for _, Qc in parts])
    # each pair's boxes (m, 4, 3): P's least and greatest corners, then Q's
    boxes = np.stack([np.minimum.reduceat(VP, po[:-1]), np.maximum.reduceat(VP, po[:-1]),
                      np.minimum.reduceat(VQ, qo[:-1]), np.maximum.reduceat(VQ, qo[:-1])],
                     axis=1)
    blockers, start, boxed, left = _compiled_row_blockers(
        V, lo_k, hi_k, N, int(i), np.asarray(nP, dtype=float), np.asarray(p0, dtype=float), J,
        boxes, VP, po, VQ, qo, float(near), tol.EPS, tol.AREA_HULL_MAX_POINTS)
    st.shaft_culled_blockers += int(boxed.sum() - left.sum())
    st.shaft_unoccluded_pairs += int(np.count_nonzero((boxed > 0) & (left == 0)))
    return np.split(blockers, start[1:-1])


class ConvexSolids(NamedTuple):
    """A scene's convex solids (:func:`convex_solids`), computed once per scene."""

    #: The group of each polygon (-1: none, or alone).
    label: np.ndarray
    #: Per group: the ends of its edges that only one member has (m, 2, 3).
    open_edges: dict
    #: Per group: its vertices, each once (v, 3).
    vertices: dict
    #: Per group: its members (polygon indices), in order.
    members: dict
    #: Per group: the mean of its vertices, a point inside its hull.
    centres: dict
    #: The scene's planes ``(normals (n, 3), offsets (n,))``, for :func:`closed_solids`'
    #: ``keys``.
    planes: tuple = None
    #: Per group: its facts against every plane of the scene (:func:`_plane_facts`),
    #: filled where a pair first asks for them.
    facts: dict = None


def convex_solids(scene):
    """The scene's polygons grouped into convex solids: connected by shared edges (equal
    coordinates), no edge shared by more than two of them, and every vertex of the group
    on or behind each member's plane or on or in front of it (the coplanar band of
    :func:`~exactff.predicates.coplanar_band_sides`): each member on the boundary of the
    group's convex hull. Returns a :class:`ConvexSolids`: the group of each polygon
    (-1: none, or alone), and per group the ends of its edges that only one member has,
    shape (m, 2, 3), its vertices, its members and the mean of its vertices (a point
    inside its hull), each stored once for the scene. A group whose open edges all lie in a
    plane that supports it (the emitter's or the receiver's, :func:`closed_solids`) is
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
    open_edges, vertices, members_ = {}, {}, {}
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
        members_[int(g)] = members
    label = np.where(np.isin(label, list(open_edges)), label, -1)
    return ConvexSolids(label, open_edges, vertices, members_,
                        {g: V.mean(axis=0) for g, V in vertices.items()}, (N, D), {})


def _plane_facts(vertices, open_edges, N, D):
    """A group's facts against each plane ``N[k] . x = D[k]`` (:func:`closed_solids`):
    whether the plane supports it (its vertices on one side, the coplanar band's), whether
    it then meets the group's hull in no area (fewer than three vertices in it), and
    which of its open edges lie in it, both ends; shapes (K,), (K,) and (m, K)."""
    sign, _ = coplanar_band_sides(vertices, N, D)
    supports = ~((sign > 0).any(axis=0) & (sign < 0).any(axis=0))
    no_area = supports & ((sign == 0).sum(axis=0) < 3)
    on, _ = coplanar_band_sides(open_edges.reshape(-1, 3), N, D)
    on = (on == 0).reshape(len(open_edges), 2, len(D)).all(axis=1)
    return supports, no_area, on


def closed_solids(solids, blockers, planes, keys=None):
    """The group (:func:`convex_solids`) of each blocker where the group is a solid for
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
    (their faces lie in the planes).

    ``keys``: the polygons whose planes ``planes`` are (the emitter and the receiver, as
    ``solids.planes`` holds them): the facts are then taken from each group's table
    against every plane of the scene, built once for the scene where a pair first asks
    (``solids.facts``), instead of again for each pair."""
    label, open_edges, vertices = solids.label, solids.open_edges, solids.vertices
    ids = label[blockers]
    out = np.full(len(blockers), -1)
    N, D = planes
    for g in set(ids[ids >= 0].tolist()):
        if np.count_nonzero(ids == g) < 2:
            continue
        if keys is None:
            supports, no_area, on = _plane_facts(vertices[g], open_edges[g], N, D)
        else:
            table = solids.facts.get(g)
            if table is None:    # (threads may build it twice: the same table)
                table = solids.facts[g] = _plane_facts(vertices[g], open_edges[g],
                                                       *solids.planes)
            supports, no_area, on = table[0][keys], table[1][keys], table[2][:, keys]
        if not no_area.any():
            continue
        if len(on) and not (on & supports).any(axis=1).all():
            continue
        out[ids == g] = g
    return out



def front_pairs(polys, i, nP, padded):
    """The receivers j of row i with each polygon's part in front of the other's plane,
    and those parts, as a list of ``(j, Pc, Qc)``: the distances for all receivers at
    once (:func:`~exactff.area.closed_form.front_distances`, with the near-coplanar
    band), the decision by :func:`~exactff.area.closed_form.front_parts`."""
    V, _, _, N = padded
    P = polys[i]
    dP, dQ = front_distances(P, nP, V, N)                   # (n, kP), (n, kmax)
    live = (dQ.max(axis=1) > 0) & (dP.max(axis=1) > 0)
    live[i] = False
    J = np.flatnonzero(live)
    Pcs, Qcs = front_parts(P, nP, [polys[j] for j in J], N[J], dP[J], dQ[J])
    return [(int(j), Pc, Qc) for j, Pc, Qc in zip(J, Pcs, Qcs)
            if Pc is not None and Qc is not None]


def tie_covers(scene):
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
        _, q0, RQ, Q2 = plane_frame(polys[j])
        Qs = shapely.Polygon(Q2)
        K2 = shapely.polygons([(polys[m] - q0) @ RQ[:2].T for m in k])
        over = shapely.area(shapely.intersection(K2, Qs)) > tol.AREA_SLIVER_CELL * Qs.area
        if over.any():
            out[j] = [int(m) for m in k[over]]
    return out


def uncovered(Qc, covers):
    """The part of the receiver Qc (clipped, planar) that the polygons ``covers`` do not
    cover (:func:`tie_covers`), as triangles (t, 3, 3), counter-clockwise seen from Qc's
    front, in Qc's plane (the covers projected onto it); none where nothing is left."""
    nQ, q0, RQ, Q2 = plane_frame(Qc)
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
    return T[triangle_areas(T) > tol.AREA_SLIVER_CELL * whole.area]
