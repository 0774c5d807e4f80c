"""An occluded pair's umbras (docs/explanation/area-form-factors.md, "Umbras"): those
of one blocker (:func:`pair_umbras`, regions cut out of the arrangement,
:mod:`exactff.area.umbra`), and first those of several blockers (:func:`split_pair`):
pieces of the emitter from every point of which the blockers together hide the whole
receiver, each part of the receiver by one blocker,
proven with margins. Such a piece contributes exactly 0 (or, where a thin part of the
receiver is left uncovered, half its unoccluded bound within as much); the pieces left
are integrated as pairs of their own.

The proof: for a convex blocker K, a point v of the emitter and a point y of the
receiver, the segment v -> y meets K where v and y are on opposite sides of K's plane
and y is on K's side of each plane through v and an edge (p, q) of K. Each condition
is ``f(v, y) > 0`` for an f affine in y for a fixed v and affine in v for a fixed y
(``((p - v) x (q - v)) . (y - v) = (p - y) . ((q - p) x (v - p))``), so where it holds
at every corner of a convex piece of the emitter and every vertex of a convex piece of
the receiver, it holds on both pieces whole. The receiver is cut into triangles until
each is so hidden by one blocker (the seams between blockers that meet at an edge are
left as thin uncovered triangles, bounded).
"""

import numpy as np

from .. import _tolerances as tol
from ..geometry import area_vector, cross, polygon_area, receiver_frame
from ..rings import padded
from .points import unoccluded_bound
from .umbra import (blocker_frame, clip_half_plane, merged_blockers, outside_umbras,
                    signed_area, umbra_edges, umbras, unoccluded_parts)

__all__ = ["blocker_frames", "hiding_rows", "uncovered_area", "hidden_pieces", "split_pair",
           "pair_umbras"]


def blocker_frames(blockers):
    """The blockers (joined as :func:`merged_blockers` does) that are strictly convex,
    padded: vertices (b, k, 3) and each vertex's successor (b, k, 3) (a padded vertex's
    edge is of no length, its row always holds, :func:`hiding_rows`), unit normals
    (b, 3), offsets (b,), distances from the mean plane (b,) and vertex counts (b,);
    None where none is.

    Examples
    --------
    >>> K = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    >>> V, W, n, d, flat, counts = blocker_frames([K, K[:3] + [3, 0, 0]])
    >>> V.shape, n[0].tolist(), d.tolist(), counts.tolist()
    ((2, 4, 3), [0.0, 0.0, 1.0], [1.0, 1.0], [4, 3])
    """
    Ks, frames = [], []
    for K in merged_blockers(blockers):
        f = blocker_frame(K)
        if f is not None:
            Ks.append(K)
            frames.append(f)
    if not Ks:
        return None
    V, counts = padded(Ks)
    k = np.arange(V.shape[1])
    nxt = np.where(k[None, :] + 1 < counts[:, None], k[None, :] + 1, 0)
    nxt = np.where(k[None, :] < counts[:, None], nxt, k[None, :])
    W = np.take_along_axis(V, nxt[:, :, None], axis=1)
    return (V, W, np.array([f[0] for f in frames]), np.array([f[1] for f in frames]),
            np.array([f[2] for f in frames]), counts)


def hiding_rows(Cv, frames, q0, RQ, reach, margin, row_margin):
    """For a convex region of the emitter with corners Cv (m, 3), the half-planes of the
    receiver's plane (2-D coordinates u in the frame RQ (2, 3) about q0, ``y = q0 + u
    RQ``) whose intersection, per blocker K, is the set of points y that K hides from
    every corner, by margins: rows (a0, a1, b) with ``a . u + b >= 0`` inside, as an
    array (b', h, 3) over the blockers b' that have all of Cv strictly on one side of
    their plane. Per corner v: y beyond K's plane (``sigma (n_K . y - d_K)``, sigma
    the side away from v), and for each edge (p, q) of K (counter-clockwise about n_K)
    ``sigma ((p - v) x (q - v)) . (y - v)``, which is positive where y is on K's side
    of the plane through v and the edge. The plane's row is less ``margin`` times the
    coordinates' size ``reach`` and K's distance from its mean plane (as Cv's distances
    from it, on their side); each edge's row less ``row_margin`` times the size of its
    terms (``|p - v| |q - v| |y - v|``, and ``reach (|p - v| + |q - v|) |y - v|`` for
    the rounding of v and y: the computed value is within some ten roundings of that).

    Each row is affine in y for a fixed v and affine in v for a fixed y (``((p - v) x
    (q - v)) . (y - v) = (p - y) . ((q - p) x (v - p))``), so where it holds at every
    corner of a convex region of the emitter and every vertex of a convex piece of the
    receiver, it holds on all of both: every segment from the region to the piece
    meets K (its line meets K's plane inside K's edges, beyond v, before y)."""
    V, W, nK, dK, flat, counts = frames
    sv = Cv @ nK.T - dK                                       # (m, b)
    mu1 = margin * reach + flat
    side = ((sv > mu1).all(axis=0) | (sv < -mu1).all(axis=0))
    if not side.any():
        return np.zeros((0, 0, 3))
    V, W, nK, dK, flat, sv = V[side], W[side], nK[side], dK[side], flat[side], sv[:, side]
    sig = -np.sign(sv[0])                                      # (b,), the side away from C
    plane = np.empty((len(sig), 1, 3))
    plane[:, 0, :2] = sig[:, None] * (nK @ RQ.T)
    plane[:, 0, 2] = sig * (nK @ q0 - dK) - (margin * reach + flat)
    D1 = V[None] - Cv[:, None, None]                          # (m, b, k, 3)
    D2 = W[None] - Cv[:, None, None]
    M = cross(D1, D2)
    a = sig[None, :, None, None] * (M @ RQ.T)                 # (m, b, k, 2)
    b = sig[None, :, None] * np.einsum("mbkx,mx->mbk", M, q0[None] - Cv)
    n1, n2 = np.linalg.norm(D1, axis=3), np.linalg.norm(D2, axis=3)
    far = np.linalg.norm(q0[None] - Cv, axis=1)[:, None, None] + reach
    b = b - row_margin * (n1 * n2 + reach * (n1 + n2)) * far
    edges = np.concatenate([a, b[..., None]], axis=3)           # (m, b, k, 3)
    # a padded vertex's edge (p = q) gives a zero row: made to hold
    edges[..., 2] = np.where((M == 0).all(axis=3), 1.0, edges[..., 2])
    edges = np.moveaxis(edges, 1, 0).reshape(len(sig), -1, 3)
    return np.concatenate([plane, edges], axis=1)


def uncovered_area(rows, Q2, depth, enough=None):
    """The area of the convex polygon Q2 (k, 2) not proven hidden: Q2 fanned into
    triangles, a triangle covered where one blocker's rows (:func:`hiding_rows`) hold at
    its three vertices, an uncovered one cut in four (at its edges' midpoints) down to
    ``depth`` levels (while the pairs of a triangle and a blocker whose region may meet
    it are at most ``AREA_UMBRA_COVER_PAIRS``, and from the third level on while the
    uncovered area falls below ``AREA_UMBRA_COVER_STALL`` of the last level's); returns
    the area of the uncovered triangles (0.0 where every point of Q2 is proven hidden),
    early where that is at most ``enough``. A blocker one of
    whose rows fails at all three vertices of a triangle (its region misses the
    triangle) is no candidate for the triangle's quarters."""
    T = np.stack([np.broadcast_to(Q2[0], (len(Q2) - 2, 2)), Q2[1:-1], Q2[2:]], axis=1)
    # the candidate (blocker, triangle) pairs
    bi = np.repeat(np.arange(len(rows)), len(T))
    ti = np.tile(np.arange(len(T)), len(rows))
    left = 0.0
    for level in range(depth + 1):
        area = 0.5 * np.abs((T[:, 1, 0] - T[:, 0, 0]) * (T[:, 2, 1] - T[:, 0, 1])
                            - (T[:, 2, 0] - T[:, 0, 0]) * (T[:, 1, 1] - T[:, 0, 1]))
        ok = (np.einsum("phc,pvc->pvh", rows[bi, :, :2], T[ti])
              + rows[bi, None, :, 2]) >= 0                                 # (p, 3, h)
        covered = np.zeros(len(T), dtype=bool)
        covered[ti[ok.all(axis=(1, 2))]] = True
        before, left = left, float(area[~covered].sum())
        # stopped where done, or where the uncovered area no longer halves (a part of
        # the receiver seen, not a thin seam between blockers)
        if (level == depth or left == 0.0 or (enough is not None and left <= enough)
                or (level >= 2 and left > tol.AREA_UMBRA_COVER_STALL * before)):
            return left
        # the pairs left: uncovered triangles, blockers whose region may meet them
        keep = ~covered[ti] & ok.any(axis=1).all(axis=1)
        bi, ti = bi[keep], ti[keep]
        if 4 * len(bi) > tol.AREA_UMBRA_COVER_PAIRS:
            return left
        # the uncovered triangles cut in four, the pairs with them
        new = np.cumsum(~covered) - 1
        T = T[~covered]
        m = 0.5 * (T + np.roll(T, -1, axis=1))
        T = np.concatenate([np.stack([T[:, 0], m[:, 0], m[:, 2]], 1),
                            np.stack([m[:, 0], T[:, 1], m[:, 1]], 1),
                            np.stack([m[:, 2], m[:, 1], T[:, 2]], 1),
                            np.stack([m[:, 0], m[:, 1], m[:, 2]], 1)])
        n = len(T) // 4
        ti = np.concatenate([new[ti] + k * n for k in range(4)])
        bi = np.tile(bi, 4)
        if not len(bi):
            return float(area[~covered].sum())
    return left


def hidden_pieces(Pc, Qc, blockers, R, c, nP, atol, area_P):
    """The emitter Pc cut into convex pieces (squares of its frame R about c, clipped to
    it, cut in four down to ``AREA_UMBRA_SPLIT_DEPTH`` levels) from each of which
    several blockers together hide all of Qc, or all but a part of it small enough:
    per piece, the receiver's points proven hidden from every corner of the piece by
    one blocker (:func:`hiding_rows`, :func:`uncovered_area`: the receiver cut into
    triangles down to ``AREA_UMBRA_COVER_DEPTH`` levels) cover Qc, so that the piece
    contributes exactly 0; or they leave uncovered an area ``a`` of Qc whose unoccluded
    bound over the piece, ``A_piece * unoccluded_bound(piece, Qc, a) / area_P``, is
    within its share (by area) of ``AREA_UMBRA_CLOSED_SHARE`` of ``atol``: the piece
    contributes half of it within as much. Returns the pieces left to integrate (a list
    of (k, 3) arrays, whose union with the pieces taken is Pc), the pieces' value and
    estimate per unit area of P, the number of pieces taken, and the area taken; None
    where Qc or Pc is not strictly convex, none of the first squares has its bound within its
    share, more than
    ``AREA_UMBRA_MAX_LEFT`` are left (each would be a pair of its own), or a level has
    more than ``AREA_UMBRA_MAX_SQUARES`` squares to test.

    Examples
    --------
    A strip at height 0, a unit square at height 10 facing it, and two plates near the
    square, at heights 9 and 9.2, overlapping in x: together, not alone, they hide the
    square from all of the strip.

    >>> P = np.array([[-6, 0, 0], [6, 0, 0], [6, 1, 0], [-6, 1, 0]], float)
    >>> Q = np.array([[0, 0, 10], [0, 1, 10], [1, 1, 10], [1, 0, 10]], float)
    >>> K1 = np.array([[-3, -3, 9], [0.5, -3, 9], [0.5, 4, 9], [-3, 4, 9]], float)
    >>> K2 = np.array([[0.3, -3, 9.2], [4, -3, 9.2], [4, 4, 9.2], [0.3, 4, 9.2]])
    >>> nP = np.array([0, 0, 1.0])
    >>> left, value, err, n, taken = hidden_pieces(P, Q, [K1, K2], receiver_frame(nP),
    ...                                            P.mean(axis=0), nP, 1e-9, 12.0)
    >>> left, taken, value == err == 0.0
    ([], 12.0, True)
    """
    frames = blocker_frames(blockers)
    if frames is None or blocker_frame(Qc) is None or blocker_frame(Pc) is None:
        return None
    RQ = receiver_frame(blocker_frame(Qc)[0])[:2]
    q0 = Qc.mean(axis=0)
    Q2 = (Qc - q0) @ RQ.T
    if signed_area(Q2) < 0:
        Q2 = Q2[::-1]
    area_Q = signed_area(Q2)
    P2 = (Pc - c) @ R[:2].T
    if signed_area(P2) < 0:
        P2 = P2[::-1]
    area_Pc = signed_area(P2)
    reach = max(float(np.abs(Pc).max()), float(np.abs(Qc).max()),
                float(np.abs(frames[0]).max()))
    lo, hi = P2.min(axis=0), P2.max(axis=0)
    side = float(np.ptp(P2, axis=0).min())
    n = np.maximum(1, np.ceil((hi - lo) / side - tol.AREA_UMBRA_SQUARE_SLACK).astype(int))
    side = (hi - lo) / n
    # the squares: (lower corner, sides, parent's index); per square its piece and
    # whether it is left to integrate (None: cut in four)
    squares = [(lo + side * [i, j], side, -1) for i in range(n[0]) for j in range(n[1])]
    # the edges of P in a blocker's plane (both ends within AREA_HULL_RTOL of the
    # coordinates' size of it) as half-planes a . u + b >= 0, moved in by
    # AREA_UMBRA_SHRINK of P's size
    eps = tol.AREA_UMBRA_SHRINK * float(np.ptp(P2, axis=0).max())
    off = np.abs((c + P2 @ R[:2]) @ frames[2].T - frames[3])     # (k, b), P2's order
    near = off <= tol.AREA_HULL_RTOL * reach + frames[4]
    inward = []
    for i, (p, q) in enumerate(zip(P2, np.roll(P2, -1, 0))):
        if (near[i] & near[(i + 1) % len(P2)]).any():
            a = np.array([-(q - p)[1], (q - p)[0]]) / np.linalg.norm(q - p)
            inward.append((a, -float(a @ p) - eps))
    nodes, within = [], False
    value, err, taken, count = 0.0, 0.0, 0.0, 0
    # the first squares in an order that spreads the first AREA_UMBRA_PROBE of them over
    # P: where none of those is within its share, the pair is integrated whole
    step = max(1, len(squares) // tol.AREA_UMBRA_PROBE)
    probe = list(range(0, len(squares), step))[:tol.AREA_UMBRA_PROBE]
    probed = set(probe)
    squares = ([squares[i] for i in probe]
               + [sq for i, sq in enumerate(squares) if i not in probed])
    for level in range(tol.AREA_UMBRA_SPLIT_DEPTH + 1):
        todo = []
        for k, (corner, s, parent) in enumerate(squares):
            if level == 0 and k == len(probe) and not within:
                return None
            piece = P2
            for a, b in (([1.0, 0.0], -corner[0]), ([-1.0, 0.0], corner[0] + s[0]),
                         ([0.0, 1.0], -corner[1]), ([0.0, -1.0], corner[1] + s[1])):
                piece = clip_half_plane(piece, np.array(a), b)
            a_piece = signed_area(piece)
            if len(piece) < 3 or not a_piece > 0:
                continue
            Cv = c + piece @ R[:2]
            # proven on the piece less a strip along P's edges in a blocker's plane (the
            # blocker seen edge-on there), the strip bounded below
            inner = piece
            for a, b in inward:
                inner = clip_half_plane(inner, a, b)
            a_inner = signed_area(inner)
            if len(inner) < 3 or not a_inner > 0:
                inner, a_inner = piece, 0.0
            rows = hiding_rows(c + inner @ R[:2], frames, q0, RQ, reach, tol.AREA_UMBRA_MARGIN,
                               tol.AREA_UMBRA_ROW_MARGIN)
            share = tol.AREA_UMBRA_CLOSED_SHARE * atol * a_piece / area_Pc
            # the area of Qc whose unoccluded bound over the piece is AREA_UMBRA_TAKE_SHARE
            # of its share (the receiver is cut no finer than that)
            per_area = a_piece * unoccluded_bound(Cv, Qc, 1.0) / area_P
            enough = (tol.AREA_UMBRA_TAKE_SHARE * share / per_area if per_area > 0
                      else np.inf)
            if len(rows):
                # only blockers that may hide part of Qc: no row outside all of it
                some = ((rows[:, :, None, :2] @ Q2.T[None, None]).squeeze(2)
                        + rows[:, :, 2:] >= 0).any(axis=2).all(axis=1)
                rows = rows[some]
            a_left = (uncovered_area(rows, Q2, tol.AREA_UMBRA_COVER_DEPTH, enough)
                      if len(rows) else area_Q)
            bound = ((a_inner * unoccluded_bound(Cv, Qc, a_left) if a_left > 0 else 0.0)
                     + (a_piece - a_inner) * unoccluded_bound(Cv, Qc)) / area_P
            nodes.append([Cv, parent, False])
            within = within or bound <= share
            # taken where proven, or bounded by AREA_UMBRA_TAKE_SHARE of its share; else cut in
            # four where the receiver is mostly covered; else taken where bounded by its
            # share, else left
            split = (level < tol.AREA_UMBRA_SPLIT_DEPTH
                     and a_left <= tol.AREA_UMBRA_SPLIT_LEFT * area_Q)
            if (bound <= tol.AREA_UMBRA_TAKE_SHARE * share
                    or ((a_left == 0.0 or not split) and bound <= share)):
                value += 0.5 * bound
                err += 0.5 * bound
                taken += a_piece
                count += 1
            elif split:
                nodes[-1][2] = None
                todo.extend((corner + 0.5 * s * [i, j], 0.5 * s, len(nodes) - 1)
                            for i in (0, 1) for j in (0, 1))
            else:
                nodes[-1][2] = True
                # left beyond the limit: the pair is integrated whole (at once)
                if tol.AREA_UMBRA_MAX_LEFT == 0:
                    return None
        squares = todo
        # none of the first squares within its share, too many squares to test, or left
        # already: the pair is integrated whole
        if ((level == 0 and not within) or len(squares) > tol.AREA_UMBRA_MAX_SQUARES
                or sum(1 for node in nodes if node[2]) > tol.AREA_UMBRA_MAX_LEFT):
            return None
    # a square cut in four none of whose quarters was taken is left whole (fewer,
    # larger pieces to integrate): the latest squares first, so that it goes up
    children = {}
    for k, (_, parent, _) in enumerate(nodes):
        children.setdefault(parent, []).append(k)
    for k in range(len(nodes) - 1, -1, -1):
        if nodes[k][2] is None and all(nodes[i][2] for i in children.get(k, [])):
            nodes[k][2] = True
            for i in children.get(k, []):
                nodes[i][2] = False
    left = [Cv for Cv, parent, is_left in nodes if is_left]
    if len(left) > tol.AREA_UMBRA_MAX_LEFT:
        return None
    if not count:
        return None
    return left, value, err, count, taken


def split_pair(S, Pc, Qc, nP, atol, area_P, st, integrate):
    """An occluded pair (S = [receiver Qc, blockers...], emitter Pc of normal nP) by the
    umbras of several blockers (:func:`hidden_pieces`): the pieces of Pc taken
    contribute 0 (or half their bound, within as much); each piece left is a pair of
    its own, integrated per unit area of the piece by ``integrate(L, piece_atol,
    area_L, whole_L)`` (:func:`~exactff.area.adaptive._hidden_integral`'s steps, its
    unoccluded value ``whole_L`` by the closed form or, where its terms cancel, the Gauss
    rules, :func:`~exactff.area.umbra.unoccluded_parts`) to what the pieces taken leave
    of ``atol`` per unit area of those left (at least ``atol``: the rules and their
    thresholds as the pair's). Returns the value per unit area of P, its estimate and the
    points, or None where no piece is taken or the pair has fewer than
    ``AREA_UMBRA_SPLIT_MIN_BLOCKERS`` blockers (counted in ``st``: ``umbra_pairs``,
    ``umbra_pieces``)."""
    if len(S) - 1 < tol.AREA_UMBRA_SPLIT_MIN_BLOCKERS:
        return None
    found = hidden_pieces(Pc, Qc, S[1:], receiver_frame(nP), Pc.mean(axis=0), nP, atol,
                          area_P)
    if found is None:
        return None
    left, value, err, count, _ = found
    if st is not None:
        st.umbra_pairs += 1
        st.umbra_pieces += count
    points = 0
    if left:
        areas = np.array([polygon_area(L) for L in left])
        piece_atol = ((1.0 - tol.AREA_UMBRA_CLOSED_SHARE) * atol * area_P
                      / float(areas.sum()))
        for L, a in zip(left, areas):
            T = np.stack([np.broadcast_to(L[0], (len(L) - 2, 3)), L[1:-1], L[2:]], axis=1)
            U, E, _ = unoccluded_parts(T, nP, Qc, np.zeros(len(T)))
            v, e, p = integrate(L, piece_atol, a, (float(U.sum()) / a, float(E.sum()) / a))
            value, err, points = value + v * a / area_P, err + e * a / area_P, points + p
    return value, err, points


def pair_umbras(lines, S, Pc, Qc, R, c, atol, area_P, shortcuts, st):
    """The umbras of one blocker of a pair (:func:`~exactff.area.umbra.umbras`) whose
    event segments ``lines`` are more than ``AREA_UMBRA_MIN_LINES``: regions from every
    point of which one blocker hides all of Qc (the hidden part there is the unoccluded
    point value: no event inside changes it), the event lines cut away from them and
    their edges cut along instead. Returns the regions, the lines, and the pair's value,
    estimate and points where one region holds all of P but strips along its boundary
    (the proof's margin: the value is the strips', between 0 and their area times the
    point values' bound), else None."""
    regions = []
    if shortcuts and len(lines) > tol.AREA_UMBRA_MIN_LINES:
        regions = umbras(Pc, Qc, S[1:], R, c)
        area_Pc = float(np.linalg.norm(area_vector(Pc)))
        left = area_Pc - max((polygon_area(c + r @ R[:2]) for r, _ in regions), default=0.0)
        half = 0.5 * unoccluded_bound(Pc, Qc) * max(left, 0.0) / area_P
        if regions and half <= tol.AREA_UMBRA_CLOSED_SHARE * atol:
            if st is not None:
                st.umbra_pairs += 1
            return regions, lines, (half, half, 0)
        if regions:
            P2 = (Pc - c) @ R[:2].T
            lines = np.concatenate([outside_umbras(lines, regions), umbra_edges(
                regions, P2, tol.AREA_HULL_RTOL * float(np.ptp(P2, axis=0).max()))])
    return regions, lines, None
