"""Area-to-area form factors (the paper's Eq. 1), unoccluded, by the contour integral.

For two planar polygons P and Q, Stokes' theorem turns the double area integral of
Eq. 1 into a double contour integral (Mitalas & Stephenson 1966; Sparrow 1963):

    A_P F(P -> Q) = (1 / 2 pi) sum_i sum_j (e_i . e_j) int_0^1 int_0^1 ln |p_i(s) - q_j(t)| dt ds

over the edges ``p_i(s) = a_i + s e_i`` of P and ``q_j(t) = b_j + t e_j`` of Q, each
counter-clockwise seen from its front. The inner integral is in closed form (``_segment_log_integral``); the outer one is a tanh-sinh
(double-exponential) quadrature, which keeps full accuracy when the integrand has
logarithmic singularities at the ends of an edge (polygons sharing an edge or a
vertex). ``ln r`` is measured against the distance between the centroids (the shift
contributes ``(sum e_i) . (sum e_j) = 0``), which keeps the terms small when the
polygons are far apart.

The contour terms cancel as (distance / size)^2 when the polygons are far apart: beyond
``FAR`` diameters the double integral is taken instead as the area integral over P of
the exact point form factors (smooth there), by a Gauss-Legendre rule on P's triangles.

One-sided, as the point form factors: only the part of Q in front of P's plane and
the part of P in front of Q's plane take part.
"""

import numpy as np
import shapely
from scipy.special import roots_legendre, xlogy

from . import _tolerances as tol
from .geometry import area_vector, polygon_diameter, receiver_frame
from .scene import validate_polygon
from .visibility.clipper import _polygon_rings, clip_halfspace

__all__ = ["polygon_form_factor", "area_form_factors"]


def _tanh_sinh(level=6, t_max=3.6):
    """Tanh-sinh nodes on [0, 1] as (distance to the nearer end, which end, weight, the
    weight of the rule one level coarser: twice as wide a step, on every other node):
    the distance to the end is computed without cancellation."""
    h = 2.0 ** -level
    k = np.arange(-int(t_max / h), int(t_max / h) + 1)
    t = k * h
    u = 0.5 * np.pi * np.sinh(np.abs(t))
    e = np.exp(-2.0 * u)
    d = e / (1.0 + e)                       # (1 - |tanh u|) / 2: distance to the end
    w = h * 0.5 * np.pi * np.cosh(t) * 4.0 * e / (1.0 + e) ** 2 / 2.0
    coarse = np.where(k % 2 == 0, 2.0 * w, 0.0)
    keep = d > 0
    return d[keep], (t >= 0)[keep], w[keep], coarse[keep]


_NODES = _tanh_sinh()


def _segment_log_integral(W, E):
    """``int_0^1 ln |W + t E| dt`` for arrays of vectors W (..., 3) and E (..., 3), in
    closed form: with ``a = |E|^2``, ``u = t + (W . E) / a`` and ``k = |W x E| / a``,
    ``ln |W + t E| = (ln a + ln(u^2 + k^2)) / 2`` and
    ``int ln(u^2 + k^2) du = u ln(u^2 + k^2) - 2 u + 2 k atan(u / k)``."""
    a = np.einsum("...i,...i->...", E, E)
    b = np.einsum("...i,...i->...", W, E) / a
    k = np.linalg.norm(np.cross(W, E), axis=-1) / a
    u0, u1 = b, b + 1.0

    def prim(u):
        with np.errstate(divide="ignore", invalid="ignore"):
            at = np.where(k > 0, k * np.arctan2(u, k), 0.0)
        return xlogy(u, u * u + k * k) - 2.0 * u + 2.0 * at

    return 0.5 * np.log(a) + 0.5 * (prim(u1) - prim(u0))


def _clip_front(P, n, c):
    """The part of polygon P with ``n . (x - c) > 0`` (None when nothing is left): the
    engine's half-space clipping, about the point c."""
    d = (P - c) @ n
    if np.all(d >= 0) and np.any(d > 0):
        return P
    if np.all(d <= 0) and np.any(d < 0):
        return None
    V, k = clip_halfspace((P - c)[None], np.array([len(P)]), n)
    C = V[0, :k[0]] + c
    # a cut through a vertex repeats it: no edge of zero length
    C = C[np.any(C != np.roll(C, 1, axis=0), axis=1)]
    return C if len(C) >= 3 else None


#: beyond this distance between centroids (in diameters of the larger polygon) the area
#: integral of exact point values replaces the contour integral, whose terms cancel as
#: (distance / size)^2 (measured: 4e-12 relative for squares 100 diameters apart)
FAR = 3.0

_GL = roots_legendre(12)
_GL_LOW = roots_legendre(8)


def _triangles(P, n):
    """Triangles covering a planar polygon (constrained Delaunay in its plane)."""
    R = receiver_frame(n)
    uv = (P - P[0]) @ R[:2].T
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(uv)))
    out = []
    for t in tris:
        c = np.asarray(t.exterior.coords)[:3]
        out.append(P[0] + c @ R[:2])
    return out


def triangle_rule(tri, rule=_GL):
    """Nodes and weights of the collapsed (Duffy) Gauss-Legendre rule on a triangle:
    ``n^2`` nodes, exact for polynomials of degree ``2n - 2`` in the triangle.

    Parameters
    ----------
    tri : ndarray of shape (3, 3)
    rule : (ndarray, ndarray)
        Gauss-Legendre nodes and weights on [-1, 1] (``scipy.special.roots_legendre``).

    Returns
    -------
    (ndarray of shape (n^2, 3), ndarray of shape (n^2,))
    """
    a, b, c = tri
    x, w = rule
    x, w = 0.5 * (x + 1.0), 0.5 * w
    U, V = np.meshgrid(x, x, indexing="ij")
    WW = np.outer(w, w) * U                  # the collapse's Jacobian u
    J = np.linalg.norm(np.cross(b - a, c - a))
    X = a + U[..., None] * (b - a) + (U * V)[..., None] * (c - b)
    return X.reshape(-1, 3), (WW * J).ravel()


def _point_values(X, nP, Qs):
    """Unoccluded point form factors from the points X (normal nP) to each polygon of
    Qs (in front of them), in offset form, vectorised over points and polygons: arrays
    of shape (len(Qs), len(X)) of the values and of their rounding error estimates."""
    from .integrate import _C1, _clipped_sector_sums

    R = receiver_frame(nP)
    nX, m = len(X), len(Qs)
    ks = np.array([len(Q) for Q in Qs])
    # polygon (j, p): receiver j seen from point p, numbered j * nX + p; its vertices'
    # offsets from its first vertex are the same for every point
    A0 = ((np.array([Q[0] for Q in Qs])[:, None, :] - X[None]) @ R.T).reshape(-1, 3)
    E = np.concatenate([np.tile((Q - Q[0]) @ R.T, (nX, 1)) for Q in Qs])
    lens = np.repeat(ks, nX)
    owner = np.repeat(np.arange(m * nX), lens)
    first = np.cumsum(lens) - lens                          # each polygon's first vertex
    nxt = np.arange(len(owner)) + 1
    nxt[first + lens - 1] = first
    S, mags, errs = _clipped_sector_sums(A0, E, nxt, owner, m * nX)
    eps = np.finfo(float).eps
    return (np.abs(S).reshape(m, nX) / (2.0 * np.pi),
            ((_C1 * eps * mags + errs) / (2.0 * np.pi)).reshape(m, nX))


def _emitter_nodes(Pc, nP):
    """The 12- and 8-point collapsed Gauss-Legendre rules on P's triangles, as one set
    of nodes and the two weight vectors (each zero on the other rule's nodes)."""
    tris = _triangles(Pc, nP)
    hi = [triangle_rule(t, _GL) for t in tris]
    lo = [triangle_rule(t, _GL_LOW) for t in tris]
    X = np.concatenate([x for x, _ in hi] + [x for x, _ in lo])
    n_hi = sum(len(w) for _, w in hi)
    W_hi, W_lo = np.zeros(len(X)), np.zeros(len(X))
    W_hi[:n_hi] = np.concatenate([w for _, w in hi])
    W_lo[n_hi:] = np.concatenate([w for _, w in lo])
    return X, W_hi, W_lo


#: receivers per call of the vectorised point values (bounds the temporaries: about
#: 2e5 edge terms per call)
_EDGE_TERMS_PER_CALL = 200_000


def _far_values(nodes, nP, area_P, Qs):
    """F(P -> Q) for far receivers Qs (each in front of P's nodes) by the area integral
    of exact point values, and its estimate: the difference between the 12- and 8-point
    rules plus rounding."""
    X, W_hi, W_lo = nodes
    hi, lo = np.empty(len(Qs)), np.empty(len(Qs))
    per = max(1, _EDGE_TERMS_PER_CALL // (len(X) * max(len(Q) for Q in Qs)))
    for s in range(0, len(Qs), per):
        V = _point_values(X, nP, Qs[s:s + per])[0]
        hi[s:s + per], lo[s:s + per] = V @ W_hi / area_P, V @ W_lo / area_P
    eps = np.finfo(float).eps
    return np.maximum(hi, 0.0), np.abs(hi - lo) + tol.AREA_ROUNDING_ULPS * eps * np.abs(hi)


def polygon_form_factor(P, Q):
    """The area-to-area form factor F(P -> Q), unoccluded, exact to rounding.

    The paper's Eq. 1: ``(1 / A_P) int_P int_Q cos(theta_P) cos(theta_Q) / (pi r^2)
    dA_Q dA_P``, one-sided (only the parts of each polygon in front of the other's
    plane), by the contour integral of Mitalas and Stephenson with the inner integral
    in closed form and a tanh-sinh outer quadrature (see the module's notes).

    Parameters
    ----------
    P, Q : array_like of shape (K, 3)
        Planar polygons, counter-clockwise seen from their fronts.

    Returns
    -------
    float

    Raises
    ------
    SceneError
        A polygon is ill-formed (as for scenes; P is polygon 0, Q polygon 1).

    Examples
    --------
    Two parallel unit squares one apart, facing each other (Howell's catalogue,
    C-11: 0.19982489570):

    >>> P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> Q = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]
    >>> round(polygon_form_factor(P, Q), 12)
    0.199824895698
    """
    P = np.array(validate_polygon(P, 0), dtype=float)
    Q = np.array(validate_polygon(Q, 1), dtype=float)
    return _unoccluded_pair(P, Q)[0]


def _edge_pieces(P, eP, Q, eQ):
    """Each edge of P cut at the points nearest to the lines of Q's edges and to Q's
    vertices, where those come within the edge's length of it: there the inner integral
    of the contour form has its kinks (an edge of Q met in its interior, a vertex of Q
    on the edge) or steep stretches, and the tanh-sinh rule wants them at the ends of
    its intervals. Returns ``(owner, s0, s1)``: the pieces' edges (sorted) and their
    ends as parameters along the edge."""
    ee = np.einsum("ij,ij->i", eP, eP)
    # nearest points to Q's vertices, and to the lines of Q's edges (not when parallel)
    at_vertex = np.einsum("pqj,pj->pq", Q[None] - P[:, None], eP) / ee[:, None]
    c = np.cross(eP[:, None, :], eQ[None, :, :])                          # (KP, KQ, 3)
    cc = np.einsum("pqj,pqj->pq", c, c)
    crossing = np.einsum("pqj,pqj->pq", np.cross(Q[None] - P[:, None], eQ[None]), c)
    ok = cc > tol.AREA_EVENT_PARALLEL * ee[:, None] * np.einsum("qj,qj->q", eQ, eQ)[None]
    at_line = np.where(ok, crossing / np.where(ok, cc, 1.0), -1.0)
    S = np.concatenate([at_vertex, at_line], axis=1)                      # (KP, 2 KQ)
    # only where Q comes within the edge's length of the point
    X = P[:, None, :] + S[..., None] * eP[:, None, :]
    D = X[:, :, None, :] - Q[None, None]                                  # (KP, 2KQ, KQ, 3)
    t = np.clip(np.einsum("pcqj,qj->pcq", D, eQ) / np.einsum("qj,qj->q", eQ, eQ), 0.0, 1.0)
    near = np.linalg.norm(D - t[..., None] * eQ, axis=-1).min(axis=2)
    keep = (S > tol.AREA_EDGE_CUT) & (S < 1.0 - tol.AREA_EDGE_CUT) & (near < np.sqrt(ee)[:, None])
    owner, s0, s1 = [], [], []
    for k in range(len(P)):
        cut = np.sort(S[k, keep[k]])
        if cut.size:
            cut = cut[np.r_[True, np.diff(cut) > tol.AREA_EDGE_CUT]]
        ends = np.r_[0.0, cut, 1.0]
        owner += [k] * (len(ends) - 1)
        s0 += list(ends[:-1])
        s1 += list(ends[1:])
    return np.array(owner), np.array(s0), np.array(s1)


def _unoccluded_pair(P, Q):
    """F(P -> Q) of two validated polygons, unoccluded, and an estimate of its error:
    the rounding of the contour sum (64 units of its absolute terms) plus the
    difference from the tanh-sinh rule one level coarser, or, for far pairs, the
    difference between the 12- and 8-point area rules plus rounding."""
    AP, AQ = area_vector(P), area_vector(Q)
    area_P = float(np.linalg.norm(AP))
    nP, nQ = AP / area_P, AQ / np.linalg.norm(AQ)
    cP, cQ = P.mean(axis=0), Q.mean(axis=0)
    # one-sided: each polygon's part in front of the other's plane
    Pc = _clip_front(P, nQ, Q[0])
    Qc = _clip_front(Q, nP, P[0])
    if Pc is None or Qc is None:
        return 0.0, 0.0
    r0 = float(np.linalg.norm(cQ - cP)) or 1.0
    eps = np.finfo(float).eps
    if r0 > FAR * max(polygon_diameter(P), polygon_diameter(Q)):
        f, e = _far_values(_emitter_nodes(Pc, nP), nP, area_P, [Qc])
        return float(f[0]), float(e[0])
    eP = np.roll(Pc, -1, axis=0) - Pc          # (KP, 3)
    eQ = np.roll(Qc, -1, axis=0) - Qc          # (KQ, 3)
    d, upper, w, w_coarse = _NODES
    # each edge of P in pieces, cut where the inner integral loses smoothness (where
    # the edge passes through or near an edge or a vertex of Q); outer nodes along each
    # piece from its nearer end (no cancellation there)
    owner, s0, s1 = _edge_pieces(Pc, eP, Qc, eQ)
    A, B = Pc[owner] + s0[:, None] * eP[owner], Pc[owner] + s1[:, None] * eP[owner]
    start = np.where(upper[None, :, None], B[:, None, :], A[:, None, :])
    step = np.where(upper[None, :, None], (A - B)[:, None, :], (B - A)[:, None, :])
    X = start + d[None, :, None] * step                              # (pieces, N, 3)
    Wv = Qc[None, None, :, :] - X[:, :, None, :]                     # (pieces, N, KQ, 3)
    G = _segment_log_integral(Wv, np.broadcast_to(eQ, Wv.shape)) - np.log(r0)
    G *= (s1 - s0)[:, None, None]
    first = np.searchsorted(owner, np.arange(len(Pc)))
    inner = np.add.reduceat(np.einsum("n,pnq->pq", w, G), first, axis=0)  # (KP, KQ)
    coarse = np.add.reduceat(np.einsum("n,pnq->pq", w_coarse, G), first, axis=0)
    terms = (eP @ eQ.T) * inner
    total = float(terms.sum()) / (2.0 * np.pi) / area_P
    scale = (float(np.abs(terms).sum()) + float(np.abs(w[None, :, None] * G).sum())
             * float(np.abs(eP @ eQ.T).max())) / (2.0 * np.pi) / area_P
    # the outer rule's error: at most its difference from the rule one level coarser
    # (tanh-sinh roughly squares its error from one level to the next)
    step = abs(float(((eP @ eQ.T) * (inner - coarse)).sum())) / (2.0 * np.pi) / area_P
    return max(total, 0.0), tol.AREA_ROUNDING_ULPS * eps * scale + step


# ---------------------------------------------------------------------------------------
# with occlusion: the outer integral of exact occluded point rows, split at visibility
# events, adaptive, with an error estimate
# ---------------------------------------------------------------------------------------
def _padded(polys):
    """The scene's polygons as one array (n, kmax, 3), short ones padded by repeating
    their last vertex, with their bounding boxes (for :func:`_blockers`)."""
    kmax = max(len(K) for K in polys)
    V = np.array([np.vstack([K, np.repeat(K[-1:], kmax - len(K), axis=0)]) for K in polys])
    return V, V.min(axis=1), V.max(axis=1)


def _blockers(padded, i, j, Pc, Qc, scale):
    """Polygons (indices) that may hide part of Qc from part of Pc: those reaching into
    the interior of the convex hull of both (a polygon on or outside a face of the hull
    hides nothing of positive measure). ``padded`` is :func:`_padded` of the scene."""
    from scipy.spatial import ConvexHull, QhullError

    V, lo_k, hi_k = padded
    pts = np.vstack([Pc, Qc])
    near = tol.AREA_HULL_RTOL * scale
    lo, hi = pts.min(axis=0) - near, pts.max(axis=0) + near
    cand = np.all((hi_k >= lo) & (lo_k <= hi), axis=1)
    cand[[i, j]] = False
    cand = np.flatnonzero(cand)
    if cand.size == 0:
        return []
    try:
        H = ConvexHull(pts).equations               # a . x + b <= 0 inside
    except QhullError:
        return []
    # on or outside one face of the hull: hides nothing
    outside = np.all(V[cand] @ H[:, :3].T + H[:, 3] >= -near, axis=1)      # (c, faces)
    return [int(k) for k in cand[~outside.any(axis=1)]]


def _plane_frame(Q):
    """A planar polygon's unit normal, origin (its first vertex), frame (rows t1, t2, n:
    :func:`receiver_frame`) and 2-D coordinates in that frame."""
    nQ = area_vector(Q)
    nQ = nQ / np.linalg.norm(nQ)
    RQ = receiver_frame(nQ)
    return nQ, Q[0], RQ, (Q - Q[0]) @ RQ[:2].T


def _event_lines(S, nP, dP, R, c, radius, Qc):
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
    whole chord."""
    out = []

    def line(m, v, span=None):
        # the plane m . (x - v) = 0 meets P's plane n . x = dP in a line; x0 is its point
        # nearest to c, d its direction; the chord of the disk, or the span's part of it
        m = m if m[np.flatnonzero(m)[0]] > 0 else -m    # one line for either orientation
        d = np.cross(nP, m)
        dn = np.linalg.norm(d)
        if dn < tol.AREA_EVENT_PARALLEL * np.linalg.norm(m):
            return
        d /= dn
        x0 = np.linalg.solve(np.array([nP, m, d]), np.array([dP, m @ v, d @ c]))
        h2 = radius * radius - float((x0 - c) @ (x0 - c))
        if h2 <= 0:
            return
        half = np.sqrt(h2)
        ends = [x0 - half * d, x0 + half * d]
        if span is not None:
            # the span's ends where they lie on the chord (as computed: segments that
            # meet there join exactly), else the chord's ends
            (t0, p0), (t1, p1) = sorted(((float((q - x0) @ d), q) for q in span),
                                        key=lambda tq: tq[0])
            if t0 >= half or t1 <= -half:
                return
            ends = [p0 if t0 > -half else ends[0], p1 if t1 < half else ends[1]]
        out.append(((ends[0] - c) @ R[:2].T, (ends[1] - c) @ R[:2].T))

    def through(v, q):
        # where the line from v through q meets P's plane (None: parallel, or beyond)
        den = nP @ (q - v)
        if abs(den) < tol.AREA_RAY_PARALLEL * np.linalg.norm(q - v):
            return None
        return v + (dP - nP @ v) / den * (q - v)

    nQ, q0, RQ, Q2 = _plane_frame(Qc)
    seen = shapely.Polygon(Q2)
    shapely.prepare(seen)

    def reaches_receiver(v, e0, e1):
        # the lines through v and the points of the edge meet Qc's plane along the
        # edge's central image from v: does it cross Qc? (unbounded images: kept)
        d0, d1 = nQ @ (e0 - v), nQ @ (e1 - v)
        if d0 * d1 <= 0:
            return True
        h = nQ @ (q0 - v)
        a, b = v + h / d0 * (e0 - v) - q0, v + h / d1 * (e1 - v) - q0
        return seen.intersects(shapely.LineString([a @ RQ[:2].T, b @ RQ[:2].T]))

    for a, A in enumerate(S):
        N = np.cross(A[1] - A[0], A[2] - A[0])
        line(N, A[0])
        for b, B in enumerate(S):
            if a == b:
                continue
            for v in A:
                for e0, e1 in zip(B, np.roll(B, -1, axis=0)):
                    m = np.cross(e0 - v, e1 - v)
                    if np.linalg.norm(m) == 0 or (a and b and not reaches_receiver(v, e0, e1)):
                        continue
                    x0, x1 = through(v, e0), through(v, e1)
                    s0, s1 = nP @ (e0 - v), nP @ (e1 - v)
                    if x0 is None or x1 is None or s0 * s1 <= 0:
                        line(m, v)              # the image passes through infinity
                    else:
                        line(m, v, (x0, x1))
    return out


def _cells(Pc, nP, lines, R, c):
    """P (clipped) cut along the event lines, as triangles in the world (the lines are
    cut to P first, so every cell lies in P)."""
    poly = shapely.Polygon((Pc - c) @ R[:2].T)
    segs = [g for g in (shapely.LineString([p0, p1]).intersection(poly) for p0, p1 in lines)
            if not g.is_empty]
    # the union nodes the segments (already cut to P) and P's boundary; cutting the
    # union to P again would lose nodes on the boundary, and with them whole cells
    pieces = shapely.get_parts(shapely.polygonize(
        shapely.get_parts(shapely.union_all([poly.boundary, *segs]))))
    tris = []
    for cell in pieces:
        if cell.area <= tol.AREA_SLIVER_CELL * poly.area:   # counted in the estimate
            continue
        for t in shapely.get_parts(shapely.constrained_delaunay_triangles(cell)):
            uv = np.asarray(t.exterior.coords)[:3]
            tris.append(c + uv @ R[:2])
    return tris


def _hidden_values(X, nP, Qc, blockers):
    """``F(x -> Qc) - F_occ(x -> Qc)`` for each point x of X (normal nP): the point form
    factor of the part of Qc that the blockers hide from x, and its error estimate.

    Built in Qc's plane: each blocker, clipped to the front of that plane and to the
    pyramid from x over a rectangle around Qc, is projected from x onto the plane (a
    projective map: its image stays a simple polygon within the rectangle); the images
    are united and intersected with Qc (GEOS, vectorised over the points), and the
    region's rings integrated by the sector sums (Eq. 3's kernel) from x: outer rings
    count positive, holes negative. The estimate adds to the sector sums' rounding the
    effect of moving the region's boundary by the booleans' rounding (a few units of the
    largest coordinate), through the kernel's largest value over the region's bounding
    box, ``h / (pi r^3)``.

    Returns
    -------
    (ndarray of shape (len(X),), ndarray of shape (len(X),))
    """
    from .integrate import _C1, _clipped_sector_sums

    nX = len(X)
    nQ, q0, RQ, Q2 = _plane_frame(Qc)
    qpoly = shapely.Polygon(Q2)
    lo, hi = Q2.min(axis=0), Q2.max(axis=0)
    pad = tol.AREA_HIDDEN_PAD * float((hi - lo).max())
    lo, hi = lo - pad, hi + pad
    corners = q0 + np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]],
                             [lo[0], hi[1]]]) @ RQ[:2]
    Kc = [K for K in (_clip_front(np.asarray(K), nQ, q0) for K in blockers) if K is not None]
    zero = np.zeros(nX)
    if not Kc:
        return zero, zero
    nb, kmax = len(Kc), max(len(K) for K in Kc)
    V = np.array([np.vstack([K, np.repeat(K[-1:], kmax - len(K), axis=0)]) for K in Kc])
    # the pyramid from each x over the rectangle: its four inward planes (nX, 4, 3)
    C = corners[None] - X[:, None, :]
    M = np.cross(C, np.roll(C, -1, axis=1))
    M *= np.sign(np.einsum("pai,pai->pa", M, np.roll(C, -2, axis=1)))[:, :, None]
    # (point, blocker) pairs that can reach into the pyramid: not wholly outside one of
    # its planes, and not seen edge-on (a blocker whose plane passes through x hides
    # nothing); only those are clipped
    D = V[None] - X[:, None, None, :]                                   # (nX, nb, kmax, 3)
    side = np.einsum("pbkj,paj->pbak", D, M)                            # (nX, nb, 4, kmax)
    NK = np.array([area_vector(K) for K in Kc])
    NK /= np.linalg.norm(NK, axis=1)[:, None]
    size = float(np.ptp(np.vstack(Kc + [Qc, X]), axis=0).max())
    edge_on = np.abs(np.einsum("pbj,bj->pb", D[:, :, 0, :], NK)) <= tol.AREA_EDGE_ON_RTOL * size
    pairs = np.flatnonzero(~(np.all(side <= 0, axis=3).any(axis=2) | edge_on))
    if pairs.size == 0:
        return zero, zero
    pt, blk = pairs // nb, pairs % nb
    Vb = D[pt, blk]
    cnt = np.array([len(K) for K in Kc])[blk]
    for a in range(4):
        Vb, cnt = clip_halfspace(Vb, np.where(cnt >= 3, cnt, 0), M[pt, a])
    # central projection from x onto Qc's plane: q = x + y h / (-nQ . y), y = offset
    h = (X - q0) @ nQ
    live = np.flatnonzero(cnt >= 3)
    if live.size == 0:
        return zero, zero
    slot = np.minimum(np.arange(Vb.shape[1])[None, :], cnt[live, None] - 1)
    Y = np.take_along_axis(Vb[live], slot[:, :, None], axis=1)         # padded by repeats
    pt = pt[live]                                                       # sorted
    Y = Y * (h[pt, None] / -(Y @ nQ))[:, :, None] + (X[pt] - q0)[:, None, :]
    Y2 = Y @ RQ[:2].T
    images = shapely.polygons(Y2)
    # each image's rank among its point's images: the union grows rank by rank
    rank = np.arange(len(pt)) - np.searchsorted(pt, pt)
    union = np.full(nX, shapely.Polygon(), dtype=object)
    try:
        bad = ~shapely.is_valid(images)
        if bad.any():
            images[bad] = shapely.make_valid(images[bad])
        union[pt[rank == 0]] = images[rank == 0]
        with np.errstate(all="ignore"):
            for r in range(1, int(rank.max()) + 1):
                at = rank == r
                union[pt[at]] = shapely.union(union[pt[at]], images[at])
            hidden = shapely.intersection(union, qpoly)
    except shapely.errors.GEOSException:
        # GEOS gave up on a nearly degenerate configuration: the engine instead
        return _hidden_values_by_engine(X, nP, Qc, Kc)
    # the region's rings from each point: outer rings and holes
    parts, part_of = shapely.get_parts(hidden, return_index=True)
    keep = shapely.area(parts) > 0
    parts, part_of = parts[keep], part_of[keep]
    if len(parts) == 0:
        return zero, zero
    xy, owner, first, _, nxt, is_hole, ring_part = _polygon_rings(parts)
    point = part_of[ring_part]                                           # ring -> point
    R = receiver_frame(nP)
    E = ((xy - xy[first[owner]]) @ RQ[:2]) @ R.T
    A0 = ((q0 - X[point]) + xy[first] @ RQ[:2]) @ R.T
    S, mags, errs = _clipped_sector_sums(A0, E, nxt, owner, len(first))
    sign = np.where(is_hole, -1.0, 1.0)
    value = np.bincount(point, sign * np.abs(S), minlength=nX) / (2.0 * np.pi)
    eps = np.finfo(float).eps
    rnd = np.bincount(point, _C1 * eps * mags + errs, minlength=nX) / (2.0 * np.pi)
    # the booleans' rounding: the boundary moved by delta, through the kernel's bound
    # h / (pi r^3) over the region's bounding box (r >= the box's distance from x)
    b = shapely.bounds(hidden)
    foot = (X - q0) @ RQ[:2].T
    dx = np.maximum(0.0, np.maximum(b[:, 0] - foot[:, 0], foot[:, 0] - b[:, 2]))
    dy = np.maximum(0.0, np.maximum(b[:, 1] - foot[:, 1], foot[:, 1] - b[:, 3]))
    r = np.sqrt(h * h + np.nan_to_num(dx * dx + dy * dy))
    delta = tol.AREA_BOOLEAN_ULPS * (nb + 1) * eps * float(np.abs(Y2).max())
    bound = np.divide(h, np.pi * r ** 3, out=np.zeros_like(r), where=r > 0)   # x on Qc's plane: Qc edge-on
    geo = np.where(value > 0, delta * shapely.length(hidden) * bound, 0.0)
    return np.maximum(value, 0.0), rnd + np.nan_to_num(geo)


def _hidden_values_by_engine(X, nP, Qc, blockers):
    """:func:`_hidden_values` by the engine instead (exact occluded point values on the
    sub-scene of Qc and the blockers, subtracted from the unoccluded ones): about a
    hundred times slower, used where GEOS fails."""
    from .formfactors import form_factors
    from .scene import Scene

    F, E = form_factors(Scene.from_polygons([Qc] + list(blockers)), X, nP, error=True)
    U, EU = (v[0] for v in _point_values(X, nP, [Qc]))
    return np.maximum(U - F[:, 0], 0.0), EU + E[:, 0]


_RULES = (roots_legendre(6), roots_legendre(10))
MAX_DEPTH = 7


def _corner_first(tri, blockers, nP, dP):
    """The triangle with first a vertex where a blocker's vertex touches the emitter's
    plane, if it has one. Near such a point the hidden part depends on the direction
    from it (to first order), and the collapsed rule, whose collapsed vertex is the first,
    integrates functions of that direction alone without cutting towards the point."""
    size = float(np.ptp(tri, axis=0).max())
    for K in blockers:
        on = np.abs(K @ nP - dP) <= tol.AREA_HULL_RTOL * size
        for v in K[on]:
            d = np.linalg.norm(tri - v, axis=1)
            k = int(np.argmin(d))
            if d[k] <= tol.AREA_HULL_RTOL * size:
                return np.roll(tri, -k, axis=0)
    return tri


def _occluded_pair(S, Pc, Qc, nP, tolerance, area_P):
    """``(1 / A_P) int_Pc F_occ(x -> S[0]) dA`` with S = [receiver, blockers...], as the
    unoccluded value (the contour integral, exact) less the integral of the hidden part
    ``F(x -> Qc) - F_occ(x -> S[0])`` (exact point values of the hidden region, built
    in Qc's plane: :func:`_hidden_values`). The hidden part is smooth where the polygons
    touch (the unoccluded part carries the edge singularities), so it is integrated over
    the cells of Pc between visibility events, each cell's triangles by two collapsed
    Gauss-Legendre rules (6 and 10 points a side), a triangle cut in four where the two
    differ by more than its share of the tolerance. Returns the value, its error
    estimate (the contour sum's, the rules' differences, the point values' bounds) and
    the number of point values used."""
    R = receiver_frame(nP)
    c = Pc.mean(axis=0)
    dP = float(nP @ Pc[0])
    whole, whole_err = _unoccluded_pair(np.asarray(Pc), np.asarray(S[0]))
    radius = (1.0 + tol.AREA_HIDDEN_PAD) * float(np.linalg.norm(Pc - c, axis=1).max())
    todo = [(_corner_first(t, S[1:], nP, dP), 0)
            for t in _cells(Pc, nP, _event_lines(S, nP, dP, R, c, radius, Qc), R, c)]
    total_area = sum(0.5 * np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) for t, _ in todo)
    hidden = err = 0.0
    points = 0
    while todo:
        # every triangle of this level together: its two rules' nodes, one call
        rules = [[triangle_rule(tri, r) for r in _RULES] for tri, _ in todo]
        X = np.vstack([x for (xl, _), (xh, _) in rules for x in (xl, xh)])
        H, EH = _hidden_values(X, nP, Qc, S[1:])
        points += len(X)
        nxt, at = [], 0
        for (tri, depth), ((Xl, Wl), (Xh, Wh)) in zip(todo, rules):
            Hl, Hh = H[at:at + len(Xl)], H[at + len(Xl):at + len(Xl) + len(Xh)]
            EHh = EH[at + len(Xl):at + len(Xl) + len(Xh)]
            at += len(Xl) + len(Xh)
            lo, hi = Wl @ Hl, Wh @ Hh
            area_t = 0.5 * np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0]))
            diff = abs(hi - lo) / area_P
            if area_t / area_P <= tol.AREA_SLIVER_SHARE * tolerance:
                # a sliver (between nearly coincident events): kept as it is, with the
                # largest error it can carry (the hidden part is between 0 and 1)
                hidden += hi / area_P
                err += area_t / area_P
                continue
            if diff > 0.5 * tolerance * area_t / total_area and depth < MAX_DEPTH:
                a, b, cc = tri
                ab, bc, ca = (a + b) / 2, (b + cc) / 2, (cc + a) / 2
                nxt += [(np.array(t), depth + 1) for t in
                        ((a, ab, ca), (ab, b, bc), (ca, bc, cc), (ab, bc, ca))]
                continue
            hidden += hi / area_P
            err += diff + (Wh @ EHh) / area_P
        todo = nxt
    # the contour integral over Pc is per unit area of Pc: back to P's area
    area_Pc = float(np.linalg.norm(area_vector(Pc)))
    value = whole * area_Pc / area_P - hidden
    err += max(area_Pc - total_area, 0.0) / area_P      # cells dropped as slivers
    return value, err + whole_err * area_Pc / area_P, points


def area_form_factors(scene, rows=None, *, tolerance=1e-9, error=False, executor=None,
                      progress=False):
    """Area-to-area form factors with occlusion (the paper's Eq. 1), each within a
    requested absolute tolerance.

    ``F[i, j] = (1 / A_i) int_{P_i} F_occ(x -> j) dA_x``, with ``F_occ`` the exact
    occluded point form factor from ``x`` (normal of ``P_i``) to polygon ``j`` (as
    :func:`exactff.form_factors`; here built in the receiver's plane from the blockers'
    projections), one-sided. A pair with nothing that can come
    between (no other polygon reaches into the convex hull of the two, each clipped to
    the front of the other) is computed by :func:`polygon_form_factor` (exact to
    rounding). Otherwise the emitter is cut along the lines where the integrand may lose
    smoothness (vertex-edge visibility events between the receiver and the polygons
    that may hide it, and their planes), its cells triangulated, and each triangle
    integrated by two collapsed Gauss-Legendre rules (6 and 10 points a side) and cut in
    four while they differ by more than its share of ``tolerance``.

    Parameters
    ----------
    scene : Scene
    rows : sequence of int, optional
        Emitters (default: every polygon).
    tolerance : float, default 1e-9
        Absolute error allowed per value.
    error : bool, default False
        Also return the per-value error estimates.
    executor : concurrent.futures.Executor, optional
        Rows are computed in parallel on it.
    progress : bool, default False
        Show a progress bar.

    Returns
    -------
    ndarray of shape (len(rows), len(scene)), or a pair of them with ``error=True``

    Notes
    -----
    What the estimate rests on: for unoccluded pairs, the rounding of the contour sum
    and the difference between its tanh-sinh rule and the next coarser one (tested
    against Howell's catalogue, reciprocity and splitting); for occluded pairs, that on a triangle between visibility events the
    integrand is smooth, so that the difference between the 6- and 10-point rules
    bounds the 10-point rule's error, plus the point values' own bounds. Curved events
    (three skew edges) are not cut along; the adaptive cutting resolves them, and a
    triangle still unresolved after ``MAX_DEPTH`` cuts keeps its (large) estimate, so
    that a value whose estimate exceeds ``tolerance`` says so. Cost grows with the
    events of each occluded pair: meant for scenes of up to a few hundred polygons.

    Examples
    --------
    Unit squares one apart with a 0.5 x 0.5 plate halfway between (the test's
    reference: 0.0314026942480):

    >>> import exactff as ef
    >>> sq = lambda z, up: [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]][::1 if up else -1]
    >>> plate = [[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]]
    >>> scene = ef.Scene.from_polygons([sq(0, True), sq(2, False), plate])
    >>> F, E = area_form_factors(scene, rows=[0], tolerance=1e-8, error=True)
    >>> round(float(F[0, 1]), 8), bool(E[0, 1] <= 1e-8)
    (0.03140269, True)
    """
    from .formfactors import _Progress, _row_indices
    from .integrate import as_scene

    scene = as_scene(scene)
    n = len(scene)
    rows = np.arange(n) if rows is None else _row_indices(rows)
    if rows.size and (rows.min() < 0 or rows.max() >= n):
        raise ValueError(f"rows must lie in [0, {n}), got values from {rows.min()} to {rows.max()}")
    if not (isinstance(tolerance, (int, float)) and np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be a positive number, got {tolerance!r}")
    F = np.zeros((len(rows), n))
    E = np.zeros((len(rows), n))
    bar = _Progress(len(rows), progress, "area form factors")
    try:
        if executor is None:
            results = (_area_row(scene, i, tolerance) for i in rows)
        else:
            results = executor.map(_area_row, [scene] * len(rows), rows,
                                   [tolerance] * len(rows))
        for k, (f, e) in enumerate(results):
            F[k], E[k] = f, e
            bar.update(1)
    finally:
        bar.close()
    return (F, E) if error else F


def _area_row(scene, i, tolerance):
    """Row i of :func:`area_form_factors` and its estimates."""
    polys = [np.asarray(p, dtype=float) for p in scene.polygons]
    padded = _padded(polys)
    P = polys[i]
    scale = float(np.ptp(scene.vertices, axis=0).max()) or 1.0
    AP = area_vector(P)
    area_P = float(np.linalg.norm(AP))
    nP = AP / area_P
    diam_P, cP = polygon_diameter(P), P.mean(axis=0)
    f, e = np.zeros(len(polys)), np.zeros(len(polys))
    far = []                      # far unoccluded pairs with P whole: integrated together
    for j, Q in enumerate(polys):
        if j == i:
            continue
        nQ = area_vector(Q)
        nQ = nQ / np.linalg.norm(nQ)
        Pc = _clip_front(P, nQ, Q[0])
        Qc = _clip_front(Q, nP, P[0])
        if Pc is None or Qc is None:
            continue
        B = _blockers(padded, i, j, Pc, Qc, scale)
        if B:
            f[j], e[j], _ = _occluded_pair([Q] + [polys[k] for k in B], Pc, Qc, nP,
                                           tolerance, area_P)
            f[j] = max(f[j], 0.0)
        elif (Pc is P
              and np.linalg.norm(Q.mean(axis=0) - cP) > FAR * max(diam_P, polygon_diameter(Q))):
            far.append((j, Qc))
        else:
            f[j], e[j] = _unoccluded_pair(P, Q)
    if far:
        js = [j for j, _ in far]
        f[js], e[js] = _far_values(_emitter_nodes(P, nP), nP, area_P, [Q for _, Q in far])
    return f, e
