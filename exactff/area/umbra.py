"""The umbras of an occluded pair: convex regions of the emitter from every point of which
one blocker hides the whole receiver, proven with a margin. There the hidden part is the
unoccluded point form factor itself (smooth: no visibility event inside changes it), so
the event lines are cut away from them and their cells are integrated in closed form
(docs/explanation/area-form-factors.md, "Umbras").

The test behind the proof: for a convex blocker K, the points x of the emitter's plane
from which the segment to a point q meets K form the central image of K from q, a convex
region; so the points that see every vertex of the receiver through K, the intersection
of those images over the receiver's vertices, see the whole receiver through K (the
segments from x to the receiver's points lie in the convex cone from x over K where those
to its vertices do). That region is convex: where its corners pass the test, so does the
whole of it.
"""

import numpy as np

from .. import _tolerances as tol
from ..geometry import area_vector, cross, receiver_frame
from ..rings import padded
from .points import point_values, unoccluded_bound
from .rule_check import triangle_unoccluded
from .rules import GAUSS_LOW_RULE, GAUSS_RULE, triangle_areas, triangle_rule

__all__ = ["merged_blockers", "sees_through", "umbras", "outside_umbras", "in_umbra", "umbra_edges",
           "umbra_cells", "unoccluded_parts", "blocker_frame",
           "clip_half_plane", "signed_area"]


def blocker_frame(K):
    """A polygon's unit normal (Newell's, its vertices counter-clockwise about it), its
    plane's offset (the mean over its vertices) and their largest distance from it; None
    where it is not strictly convex about that normal (every turn positive)."""
    a = area_vector(K)
    norm = float(np.linalg.norm(a))
    if not norm > 0:
        return None
    nK = a / norm
    K1, K2 = np.concatenate([K[1:], K[:1]]), np.concatenate([K[2:], K[:2]])  # K rolled
    turns = cross(K1 - K, K2 - K1) @ nK
    if not (turns > 0).all():
        return None
    h = K @ nK
    dK = float(h.mean())
    return nK, dK, float(np.abs(h - dK).max())


def _edges(K):
    """K's edges, each the bytes of its two vertices (bit for bit), in K's order."""
    data = np.ascontiguousarray(K, dtype=float).tobytes()
    w = 8 * K.shape[1]
    rows = [data[i:i + w] for i in range(0, len(data), w)]
    return list(zip(rows, rows[1:] + rows[:1]))


def _merge_two(A, B, nK, edges_A, edges_B):
    """A and B (coplanar, normal nK) joined along an edge they share (the same two
    vertices, bit for bit, run the other way), its straight vertices dropped; None where
    they share no edge. ``edges_A``, ``edges_B``: their :func:`_edges`."""
    ends = {e: i for i, e in enumerate(edges_A)}
    for j, (a, b) in enumerate(edges_B):
        i = ends.get((b, a))
        if i is None:
            continue
        # A from the shared edge's far end round to its near end, then B's other vertices
        ring = np.concatenate([np.roll(A, -(i + 1), 0), np.roll(B, -(j + 2), 0)[:len(B) - 2]])
        e = np.roll(ring, -1, 0) - ring
        turn = cross(np.roll(e, 1, 0), e) @ nK
        size = np.linalg.norm(np.roll(e, 1, 0), axis=1) * np.linalg.norm(e, axis=1)
        # straight vertices dropped (convexity: the caller's _blocker_frame)
        return ring[~(np.abs(turn) <= tol.AREA_HULL_RTOL * size)]
    return None


def merged_blockers(blockers):
    """The blockers with those that lie in one plane (unit normals and offsets within
    ``AREA_HULL_RTOL``) and share an edge joined where their union is convex, as often
    as that goes (a wall given in several pieces hides as one polygon). The union of two
    closed polygons along a common edge is the joined polygon; where their planes differ
    by rounding, :func:`sees_through` counts the joined one's distance from its mean
    plane in its margin. Returns a list of (k, 3) arrays.

    Examples
    --------
    >>> A = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> [K.tolist() for K in merged_blockers([A, A + [1, 0, 0]])]
    [[[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]]]
    """
    Ks = [np.asarray(K, dtype=float) for K in blockers]
    frames = [blocker_frame(K) for K in Ks]
    out, groups = [], {}
    scale = 1.0 + max((float(np.abs(K).max()) for K in Ks), default=0.0)
    for K, f in zip(Ks, frames):
        if f is None:
            out.append(K)
            continue
        # the plane, coarsely, as a key; neighbours in the key are compared exactly below
        groups.setdefault(tuple(np.round(np.append(f[0], f[1] / scale), 6)), []).append(
            (K, f, _edges(K)))
    for members in groups.values():
        merged = True
        while merged and len(members) > 1:
            merged = False
            for a in range(len(members)):
                A, fa, edges_A = members[a]
                shared = set((v, u) for u, v in edges_A)     # A's edges run the other way
                for b in range(a + 1, len(members)):
                    B, fb, edges_B = members[b]
                    if (shared.isdisjoint(edges_B)
                            or np.abs(fa[0] - fb[0]).max() > tol.AREA_HULL_RTOL
                            or abs(fa[1] - fb[1]) > tol.AREA_HULL_RTOL * scale):
                        continue
                    M = _merge_two(A, B, fa[0], edges_A, edges_B)
                    f = None if M is None else blocker_frame(M)
                    if f is None:
                        continue
                    members[a] = (M, f, _edges(M))
                    del members[b]
                    merged = True
                    break
                if merged:
                    break
        out.extend(K for K, _, _ in members)
    return out


def sees_through(X, Qv, K, margin=None):
    """Whether, from each point x of X (n, 3), every segment to a point of Qv (q, 3)
    meets the convex polygon K (k, 3) in its interior, by at least a margin: x and q on
    opposite sides of K's plane by at least ``mu``, and the crossing at least ``mu (1 +
    |q - x| / |(q - x) . nK|)`` inside each edge of K (the crossing's rounding, and
    K's own distance from its mean plane, are magnified by that grazing factor), for
    ``mu = margin`` (default ``AREA_UMBRA_MARGIN`` times the points' and K's largest
    coordinate, some 1e5 units of rounding of every term) plus K's distance from its
    mean plane. Returns a bool array (n,); all False where K is not strictly convex.

    Where every vertex of Qv passes for a point x, the segments from x to the whole of
    their convex hull meet K (they lie in the convex cone from x over K); and the points
    x that pass for one q form a convex region (the central image of K, shrunk by the
    margin), so where the corners of a convex region of x pass, all its points do.

    Examples
    --------
    A square receiver at height 2, a larger plate at height 1: the point below the
    middle sees the receiver through the plate, one far to the side does not.

    >>> Q = np.array([[0, 0, 2], [1, 0, 2], [1, 1, 2], [0, 1, 2]], float)
    >>> K = np.array([[-1, -1, 1], [2, -1, 1], [2, 2, 1], [-1, 2, 1]], float)
    >>> sees_through(np.array([[.5, .5, 0], [9, .5, 0]]), Q, K).tolist()
    [True, False]
    """
    X, Qv, K = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (X, Qv, K))
    frame = blocker_frame(K)
    if frame is None:
        return np.zeros(len(X), dtype=bool)
    nK, dK, flat = frame
    if margin is None:
        scale = max(float(np.abs(X).max()), float(np.abs(Qv).max()), float(np.abs(K).max()))
        margin = tol.AREA_UMBRA_MARGIN * scale
    mu = margin + flat
    sx = X @ nK - dK                                         # (n,)
    sq = Qv @ nK - dK                                        # (q,)
    ok = ((sx[:, None] * sq[None, :] < 0) & (np.abs(sx)[:, None] >= mu)
          & (np.abs(sq)[None, :] >= mu))
    D = Qv[None, :, :] - X[:, None, :]                       # (n, q, 3)
    den = sx[:, None] - sq[None, :]                          # -(q - x) . nK
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(ok, sx[:, None] / np.where(ok, den, 1.0), 0.0)
        grazing = 1.0 + np.linalg.norm(D, axis=2) / np.abs(np.where(ok, den, 1.0))
    Y = X[:, None, :] + t[:, :, None] * D                    # the crossings with K's plane
    E = np.roll(K, -1, 0) - K                                # K's edges
    inward = cross(nK[None, :], E)                           # pointing into K (counter-clockwise)
    inward /= np.linalg.norm(inward, axis=1)[:, None]
    depth = np.einsum("nqx,ex->nqe", Y, inward) - (inward * K).sum(axis=1)
    ok &= (depth >= (mu * grazing)[:, :, None]).all(axis=2)
    return ok.all(axis=1)


def clip_half_plane(poly, a, b):
    """The convex polygon poly (k, 2) where ``a . u + b >= 0`` (Sutherland-Hodgman, one
    half-plane)."""
    if not len(poly):
        return poly
    f = poly @ a + b
    out = []
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        if f[i] >= 0:
            out.append(poly[i])
        if (f[i] >= 0) != (f[j] >= 0):
            s = f[i] / (f[i] - f[j])
            out.append(poly[i] + s * (poly[j] - poly[i]))
    return np.array(out).reshape(-1, 2)


def signed_area(poly):
    """The signed area of a 2-D polygon (k, 2)."""
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _image_half_planes(K, Qv, R, c):
    """The half-planes ``a . u + b >= 0`` of the emitter's plane (2-D coordinates u in
    the frame R about c, ``x = c + u R[:2]``), unit ``a``, whose intersection is the set of
    points that see every vertex of Qv through the convex polygon K (the central images
    of K from each vertex: beyond K's plane and inside the planes through the vertex and
    each edge). None where K is not strictly convex."""
    frame = blocker_frame(K)
    if frame is None:
        return None
    nK, dK, _ = frame
    g = K.mean(axis=0)
    planes = []
    for q in Qv:
        side = np.sign(float(nK @ q - dK))
        if side == 0:
            return None
        planes.append((-side * nK, side * dK))                 # beyond K's plane from q
        for a, b in zip(K, np.roll(K, -1, 0)):
            m = cross(a - q, b - q)
            s = np.sign(float(m @ (g - q)))                     # K's side of the plane
            planes.append((s * m, -s * float(m @ q)))
    out = []
    for m, off in planes:
        a2 = R[:2] @ m
        n = float(np.linalg.norm(a2))
        if not n > 0:
            if m @ c + off < 0:
                return []                                      # parallel, and outside
            continue
        out.append((a2 / n, (float(m @ c) + off) / n))
    return out


def umbras(Pc, Qc, blockers, R, c, limit=None):
    """The umbras of the pair: for each blocker K (convex; coplanar blockers that share
    an edge joined first, :func:`merged_blockers`), the convex region of the
    emitter Pc (in its 2-D frame R about c) from every point of which K hides all of Qc,
    shrunk by ``AREA_UMBRA_SHRINK`` of Pc's size (``eps``) and proven: the region
    shrunk by ``eps`` alone, and Pc grown by ``eps``, has every corner pass
    :func:`sees_through`, so that every point within ``eps`` of the returned region sees
    Qc wholly hidden (a cell's corner noded within rounding of it included). Candidates
    are the blockers that hide Qc from one of a few sample points of Pc; the largest
    ``limit`` (default ``AREA_UMBRA_LIMIT``) of at least ``AREA_UMBRA_MIN_SHARE`` of
    Pc's area are returned, as a list of ``(region (k, 2) counter-clockwise, half-planes
    (h, 3): rows (a0, a1, b) with a . u + b >= 0 inside)``, largest first.

    Examples
    --------
    Unit squares two apart and a large plate between: the plate hides the receiver from
    all of the emitter.

    >>> from exactff.geometry import receiver_frame
    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> Q = P[::-1] + [0, 0, 2]
    >>> K = np.array([[-2, -2, 1], [3, -2, 1], [3, 3, 1], [-2, 3, 1]], float)
    >>> R, c = receiver_frame(np.array([0, 0, 1.0])), P.mean(axis=0)
    >>> [np.ptp(r, axis=0).round(6).tolist() for r, _ in umbras(P, Q, [K], R, c)]
    [[1.0, 1.0]]
    """
    limit = tol.AREA_UMBRA_LIMIT if limit is None else limit
    blockers = [np.asarray(K, dtype=float) for K in blockers]
    P2 = (Pc - c) @ R[:2].T
    if signed_area(P2) < 0:
        P2 = P2[::-1]
    area = signed_area(P2)
    size = float(np.ptp(P2, axis=0).max())
    eps = tol.AREA_UMBRA_SHRINK * size
    # sample points of Pc: its corners, its centroid and the midpoints between them
    mid = P2.mean(axis=0)
    samples = np.concatenate([P2, [mid], 0.5 * (P2 + mid), 0.5 * (P2 + np.roll(P2, -1, 0))])
    X = c + samples @ R[:2]
    found = []
    # a blocker whose plane has the receiver's vertices on both sides, or every sample
    # of P on the receiver's side, hides it from no sample (all blockers at once)
    merged = merged_blockers(blockers)
    if not merged:
        return []
    Ks, counts = padded(merged)
    normals = np.array([area_vector(K) for K in merged])
    offsets = np.einsum("kx,kx->k", normals, Ks[:, 0])
    sq = Qc @ normals.T - offsets                             # (q, k)
    sx = X @ normals.T - offsets                              # (s, k)
    apart = (((sq > 0).all(axis=0) & (sx < 0).any(axis=0))
             | ((sq < 0).all(axis=0) & (sx > 0).any(axis=0)))
    for K in (merged[k] for k in np.flatnonzero(apart)):
        if not sees_through(X, Qc, K).any():
            continue
        H = _image_half_planes(K, Qc, R, c)
        if not H:
            continue
        # the region shrunk by 2 eps (returned) and by eps (proven, P grown by eps)
        region = P2
        for a, b in H:
            region = clip_half_plane(region, a, b - 2 * eps)
        if signed_area(region) < tol.AREA_UMBRA_MIN_SHARE * area:
            continue
        grown = P2
        for p, q in zip(P2, np.roll(P2, -1, 0)):
            e = q - p
            a = np.array([-e[1], e[0]]) / np.linalg.norm(e)      # inward normal
            grown = clip_half_plane(grown, a, -float(a @ p) + eps)
        for a, b in H:
            grown = clip_half_plane(grown, a, b - eps)
        if len(grown) < 3 or not sees_through(c + grown @ R[:2], Qc, K).all():
            continue
        rows = np.array([[a[0], a[1], b - 2 * eps] for a, b in H]
                        + [[-(q - p)[1], (q - p)[0], 0.0] for p, q in zip(P2, np.roll(P2, -1, 0))])
        # P's edges as half-planes too (the region lies in P)
        for r, (p, q) in zip(rows[len(H):], zip(P2, np.roll(P2, -1, 0))):
            r[:2] /= np.linalg.norm(r[:2])
            r[2] = -float(r[:2] @ p)
        found.append((signed_area(region), region, rows))
    found.sort(key=lambda f: -f[0])
    kept = []
    for _, r, h in found:
        # a region within one kept already adds nothing
        if not any(in_umbra(r, [k], eps)[0].all() for k in kept):
            kept.append((r, h))
    return kept[:limit]


def umbra_edges(regions, P2, near):
    """The lines of the regions' edges to cut the emitter P2 (k, 2) along, as segments
    (m, 2, 2) across all of P2 (a region inside P whose edges ended at its corners would
    leave the arrangement in two pieces, a cell with a hole), less those on P2's boundary
    (both ends within ``near`` of one of its edges' lines: P's edges are cut along
    already) and those of no length."""
    E = np.concatenate([np.stack([r, np.roll(r, -1, axis=0)], axis=1) for r, _ in regions])
    d = E[:, 1] - E[:, 0]
    length = np.linalg.norm(d, axis=1)
    E, d, length = E[length > near], d[length > near], length[length > near]
    on = np.zeros(len(E), dtype=bool)
    for p, q in zip(P2, np.roll(P2, -1, axis=0)):
        n = np.array([-(q - p)[1], (q - p)[0]]) / np.linalg.norm(q - p)
        on |= (np.abs((E - p) @ n) <= near).all(axis=1)
    E, d, length = E[~on], d[~on], length[~on]
    # each edge lengthened both ways by P's diameter (cut_cells cuts it to P)
    reach = 2.0 * float(np.ptp(P2, axis=0).max())
    u = d / length[:, None] * reach
    return np.stack([E[:, 0] - u, E[:, 1] + u], axis=1)


def in_umbra(U2, regions, slack):
    """Whether each point u of U2 (..., 2) lies within ``slack`` of one of the regions
    (their half-planes, :func:`umbras`): a bool array of U2's leading shape, and the
    index of the first such region (-1: none)."""
    U2 = np.asarray(U2, dtype=float)
    which = np.full(U2.shape[:-1], -1)
    for k, (_, H) in reversed(list(enumerate(regions))):
        inside = ((U2 @ H[:, :2].T + H[:, 2]) >= -slack).all(axis=-1)
        which = np.where(inside, k, which)
    return which >= 0, which


def outside_umbras(lines, regions):
    """The parts of the segments ``lines`` (m, 2, 2) outside every region (convex,
    :func:`umbras`), as segments (m', 2, 2): each segment less the interval of its
    parameter inside a region (Cyrus-Beck), so one segment gives none, one or two."""
    S = np.asarray(lines, dtype=float).reshape(-1, 2, 2)
    for _, H in regions:
        if not len(S):
            break
        a, d = S[:, 0], S[:, 1] - S[:, 0]
        f0 = a @ H[:, :2].T + H[:, 2]                          # (m, h) at t = 0
        g = d @ H[:, :2].T                                     # its rate along t
        lo, hi = np.zeros(len(S)), np.ones(len(S))
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -f0 / g
        lo = np.maximum(lo, np.where(g > 0, t, -np.inf).max(axis=1))
        hi = np.minimum(hi, np.where(g < 0, t, np.inf).min(axis=1))
        parallel_out = ((g == 0) & (f0 < 0)).any(axis=1)
        cut = (lo < hi) & ~parallel_out                        # a part inside the region
        keep = [S[~cut]]
        before = cut & (lo > 0)
        after = cut & (hi < 1)
        keep.append(np.stack([a[before], a[before] + lo[before, None] * d[before]], axis=1))
        keep.append(np.stack([a[after] + hi[after, None] * d[after], S[after, 1]], axis=1))
        S = np.concatenate(keep)
    return S


def unoccluded_parts(T, nP, Qc, share):
    """``int_T F(x -> Qc) dA_x`` for triangles T (t, 3, 3) of an umbra (where the hidden
    part is the unoccluded value) and its estimate: the closed form
    (:func:`~exactff.area.rule_check.triangle_unoccluded`), and where its estimate misses ``share`` (t,) (its
    terms cancel: a triangle with an edge of rounding's length) the 12- and 8-point
    collapsed Gauss rules of the far-field rule on the point values, their difference
    and the nodes' estimates the estimate. Returns the values, the estimates, and per
    triangle whether it is within its share."""
    U, E = triangle_unoccluded(T, nP, Qc)
    miss = np.flatnonzero(~(E <= share))
    if len(miss):
        (Xh, Wh), (Xl, Wl) = (triangle_rule(T[miss], r) for r in (GAUSS_RULE, GAUSS_LOW_RULE))
        V, EV = (v[0] for v in point_values(np.concatenate([Xh.reshape(-1, 3),
                                                             Xl.reshape(-1, 3)]), nP, [Qc]))
        n = Xh.shape[0] * Xh.shape[1]
        hi = (Wh * V[:n].reshape(Wh.shape)).sum(axis=1)
        lo = (Wl * V[n:].reshape(Wl.shape)).sum(axis=1)
        err = (np.abs(hi - lo) + (Wh * EV[:n].reshape(Wh.shape)).sum(axis=1)
               + (Wl * EV[n:].reshape(Wl.shape)).sum(axis=1))
        better = err < E[miss]
        U[miss[better]], E[miss[better]] = hi[better], err[better]
    return U, E, E <= share


def umbra_cells(cells, regions, R, c, nP, Qc, area_P, area_Pc, atol, bound):
    """The cells (t, 3, 3) of an emitter cut along the umbras' edges as well as its
    events, sorted: those in an umbra (every corner within ``AREA_UMBRA_SHRINK`` of its
    size of one region, where the proof holds) take the unoccluded value for their
    hidden part (:func:`unoccluded_parts`, each within its share by area of
    ``AREA_UMBRA_CLOSED_SHARE`` of ``atol``, else left to the rules); the strips between
    the regions and P's boundary or the regions as computed (AREA_UMBRA_SHRINK wide:
    where a blocker shares an edge with P, the rules' nodes would lie at that edge, where
    the blocker is seen edge-on) are slivers, their hidden part between 0 and ``bound``
    (the unoccluded point values' bound), where that costs at most that share of
    ``atol``. Triangles of no area (the ears' straight angles) stay with the rules.
    Returns the cells left to the rules, the umbra's part per unit area of P (``area_P``)
    and its estimate, the umbra's area, the strips' area, and the umbra's triangles."""
    uv = (cells - c) @ R[:2].T
    eps = tol.AREA_UMBRA_SHRINK * float(np.ptp(uv.reshape(-1, 2), axis=0).max())
    flat = triangle_areas(cells) <= tol.AREA_SLIVER_CELL * area_Pc
    inside = in_umbra(uv, regions, eps)[0].all(axis=1) & ~flat
    U = E = area = strip_area = 0.0
    n = 0
    if inside.any():
        at = np.flatnonzero(inside)
        share = tol.AREA_UMBRA_CLOSED_SHARE * atol * area_P / area_Pc * triangle_areas(cells[at])
        exU, exE, ok = unoccluded_parts(cells[at], nP, Qc, share)
        inside[at[~ok]] = False
        U, E = float(exU[ok].sum()) / area_P, float(exE[ok].sum()) / area_P
        area, n = float(triangle_areas(cells[inside]).sum()), int(ok.sum())
    strip = ~inside & ~flat & in_umbra(uv, regions, 4.0 * eps)[0].all(axis=1)
    if strip.any():
        strip_area = float(triangle_areas(cells[strip]).sum())
        if not 0.5 * bound * strip_area / area_P <= tol.AREA_UMBRA_CLOSED_SHARE * atol:
            strip[:], strip_area = False, 0.0
    return cells[~inside & ~strip], U, E, area, strip_area, n
