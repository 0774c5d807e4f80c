"""The visible part of a polygon from a point, constructed in rational arithmetic, and its
form factor in mpmath: an independent reference for occluded values.

The scene's float coordinates are taken as exact rationals. The occluders are clipped to
the cone from the point over the target (planes through the point and the target's
edges) and to the slab between the point and the target's plane, projected centrally
onto that plane, and subtracted from the target one convex shadow at a time; every step
is exact, so the visible pieces are exact. Their form factor is the contour form of the
unoccluded point-to-polygon factor (Lambert), evaluated at ``dps`` digits from the
rational vertices. Nothing here calls exactff's kernels or predicates.

A target that is not exactly planar (rounded after a rotation, say) is taken as its
image, the spherical polygon of its vertices' directions, as the engines integrate it:
its vertices are projected centrally onto a plane along its Newell normal. Occluders
wholly between the point and the target's thickness hide their whole image; only one
that reaches into the target's range needs both to be exactly planar (it is clipped in
3-D). Where the construction does not apply (non-convex images, or those cases), or where
the point is so close to a polygon's plane that the engines' convention for edge-on
polygons decides instead of the exact side (NEAR_EDGE_ON_ULPS), or where two polygons
are so close to coplanar that the engines' depth tie does (NEAR_COPLANAR_ULPS), the
functions return None: undecided.
"""

import math
from fractions import Fraction

import mpmath
import numpy as np


def _rational(v):
    return tuple(Fraction(float(c)) for c in v)


def _sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _clip(poly, f):
    """The part of a convex polygon where the linear function ``f`` is >= 0
    (Sutherland-Hodgman against one half-space)."""
    out = []
    for k in range(len(poly)):
        a, b = poly[k], poly[(k + 1) % len(poly)]
        fa, fb = f(a), f(b)
        if fa >= 0:
            out.append(a)
        if (fa > 0 > fb) or (fa < 0 < fb):
            t = fa / (fa - fb)
            out.append(tuple(x + t * (y - x) for x, y in zip(a, b)))
    return out


def _area2(poly):
    """Twice the signed area of a polygon in the plane."""
    m = len(poly)
    return sum(poly[k][0] * poly[(k + 1) % m][1] - poly[(k + 1) % m][0] * poly[k][1]
               for k in range(m))


def _newell(poly):
    """Newell's normal of a polygon (exact), or None if it is zero."""
    normal = (Fraction(0),) * 3
    for k in range(len(poly)):
        normal = tuple(x + y for x, y in
                       zip(normal, _cross(poly[k], poly[(k + 1) % len(poly)])))
    return None if normal == (0, 0, 0) else normal


def _plane(poly):
    """A normal of an exactly planar polygon (Newell's), or None if it is not planar."""
    normal = _newell(poly)
    if normal is None or any(_dot(normal, _sub(v, poly[0])) != 0 for v in poly):
        return None
    return normal


#: Near edge-on, the engines follow a convention rather than the exact side: a point
#: within the rounding of its own coordinates and of the polygon's centroid of its plane
#: lies in it (a few ulps; exactff.predicates.engine_sides), so the polygon has no image
#: and hides nothing. The reference leaves every case within this many ulps undecided.
NEAR_EDGE_ON_ULPS = 256


def _near_edge_on(poly, P):
    """Whether the point lies within NEAR_EDGE_ON_ULPS units of rounding (of the sizes
    of the point, the centroid and their distance) of the polygon's plane (Newell's)."""
    m = _newell(poly)
    if m is None:
        return True
    c = tuple(sum(x) / len(poly) for x in zip(*poly))
    size = lambda v: math.sqrt(float(_dot(v, v)))
    distance = abs(float(_dot(m, _sub(P, c)))) / size(m)
    return distance <= NEAR_EDGE_ON_ULPS * 2.0 ** -53 * (size(P) + size(c) + size(_sub(c, P)))


#: Near coplanar, too: a vertex within BSP_COPLANAR_ULPS (64) units of rounding of the
#: magnitudes in ``n . x - d`` of a plane lies in it for the engines (a depth tie,
#: exactff.predicates.coplanar_band), whatever its exact side. The reference leaves a
#: pair undecided where a vertex of either lies off the other's plane, but within this
#: many such units.
NEAR_COPLANAR_ULPS = 256


def _near_coplanar(A, B):
    """Whether a vertex of polygon ``A`` or ``B`` lies off the other's plane (Newell's,
    exact) but within NEAR_COPLANAR_ULPS units of rounding of ``|n| . |x| + |n . c|``."""
    for X, Y in ((A, B), (B, A)):
        m = _newell(Y)
        if m is None:
            continue
        d = _dot(m, Y[0])
        for v in X:
            off = abs(_dot(m, v) - d)
            size = sum(abs(a * b) for a, b in zip(m, v)) + abs(d)
            if 0 < off <= NEAR_COPLANAR_ULPS * Fraction(1, 2 ** 53) * size:
                return True
    return False


def _within_band(scene, a, b, offsets):
    """Whether every vertex of polygon ``a`` lies within the near-coplanar band of polygon
    ``b``'s plane as the scene stores it (``n . x = d``, the floats taken as exact): the
    engines' rule (``exactff.predicates.coplanar_band``: 64 units of rounding ``u`` of
    ``|n| . |x| + |d|``), restated in rationals; False where a vertex lies beyond it by
    more than 4 ``u`` of those magnitudes, else None where one lies within 4 ``u`` of the
    band's edge (the engines test it in floating point). ``offsets``: the scene's
    ``plane_offsets`` (computed once per row)."""
    n = _rational(scene.normals[b])
    d = Fraction(float(offsets[b]))
    u = Fraction(1, 2 ** 53)
    edge = False
    for v in scene.polygons[a]:
        x = _rational(v)
        off = abs(_dot(n, x) - d)
        mag = sum(abs(c * y) for c, y in zip(n, x)) + abs(d)
        if off > 68 * u * mag:
            return False
        edge |= off > 60 * u * mag
    return None if edge else True


def _coplanar_by_rule(scene, j, target, offsets):
    """The engines' depth tie: True where each polygon lies within the other's band
    (a tie whichever plane the BSP tree splits by); False where neither does (the exact
    geometry orders them); None otherwise (one within the other's band only, or at a
    band's edge: the engines' BSP tree decides by which plane it splits with)."""
    a, b = _within_band(scene, j, target, offsets), _within_band(scene, target, j, offsets)
    if a is None or b is None:
        return None
    if a and b:
        return True
    return False if not (a or b) else None


def _convex(poly2):
    turns = set()
    for k in range(len(poly2)):
        a, b, c = poly2[k], poly2[(k + 1) % len(poly2)], poly2[(k + 2) % len(poly2)]
        turn = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        if turn != 0:
            turns.add(turn > 0)
    return len(turns) <= 1


def _left_of(a, b):
    """The linear function >= 0 on the left of the directed line ``a -> b``."""
    return lambda v: (b[0] - a[0]) * (v[1] - a[1]) - (b[1] - a[1]) * (v[0] - a[0])


def _separated(A, B):
    """Whether convex polygons ``A`` and ``B`` (2-D, counter-clockwise) share no interior
    point: their bounding boxes meet in no area, or an edge of one has the other wholly
    on its closed outer side (the separating axis theorem; exact)."""
    for k in range(2):
        if (max(v[k] for v in A) <= min(v[k] for v in B)
                or max(v[k] for v in B) <= min(v[k] for v in A)):
            return True
    for X, Y in ((A, B), (B, A)):
        for k in range(len(X)):
            left = _left_of(X[k], X[(k + 1) % len(X)])
            if all(left(v) <= 0 for v in Y):
                return True
    return False


def _target_frame(T, P):
    """The plane ``m . x = m . T[0]`` (Newell's normal m of the target) that images are
    projected on, the point's offset from it, and the target's half-thickness about it
    (0 for an exactly planar target); None if the point lies within that thickness."""
    m = _newell(T)
    if m is None or _near_edge_on(T, P):
        return None
    height = _dot(m, _sub(T[0], P))
    slab = max(abs(_dot(m, _sub(v, T[0]))) for v in T)
    if abs(height) <= slab:
        return None
    return m, height, slab


def _facing(scene, P, j):
    # seen edge-on sorts with the fronts, as in tie_priority
    return _dot(_rational(scene.normals[j]), _sub(P, _rational(scene.polygons[j][0]))) >= 0


def _in_front_on_a_tie(scene, P, j, target):
    a, b = _facing(scene, P, j), _facing(scene, P, target)
    return a and not b or (a == b and j < target)


def _point_and_target(scene, point, target):
    """The point and the target's vertices in rationals, and the target's frame
    (:func:`_target_frame`; None where undecided)."""
    P = _rational(point)
    T = [_rational(v) for v in scene.polygons[target]]
    return P, T, _target_frame(T, P)


def _cone_planes(P, V):
    """The planes of the cone from ``P`` over the convex polygon ``V``: per side its
    normal ``w`` (through ``P``) and the sign ``s`` with ``s w . (v - P) >= 0`` on the
    side of V's centroid."""
    centroid = tuple(sum(c) / len(V) for c in zip(*V))
    planes = []
    for k in range(len(V)):
        w = _cross(_sub(V[k], P), _sub(V[(k + 1) % len(V)], P))
        planes.append((w, 1 if _dot(w, _sub(centroid, P)) > 0 else -1))
    return planes


def _cone(P, V):
    """The cone from ``P`` over the convex polygon ``V``: one linear function a side,
    >= 0 on the side of V's centroid."""
    return [lambda v, w=w, s=s: s * _dot(w, _sub(v, P)) for w, s in _cone_planes(P, V)]


#: The unit roundoff of doubles: the float filters below bound their rounding by
#: multiples of it.
_U = 2.0 ** -53


def _float(x):
    """A rational rounded to the nearest double (relative error at most _U)."""
    return float(x)


class _Filters:
    """Float filters for the exact decisions of :func:`visible_pieces`, every polygon at
    once: each decides a predicate in doubles only where a bound on that computation's
    rounding shows the exact answer (the sign is certain), as the Python BSP build's
    float filter does for sides (``exactff.visibility.bsp._rule_sides``); elsewhere it
    says None and the caller decides in rationals. The decisions are the exact ones:
    the reference's results do not change, only its time.

    Bounds (``u = 2**-53``; each input double exact, each rational rounded once to the
    nearest double, relative error ``u``): a difference ``v - P`` of doubles has
    relative error ``u`` per coordinate, a dot product of three such terms with a
    rounded normal ``m`` is off by at most ``(2u + gamma_3) sum |m_i| |w_i| < 8u sum
    |m_i| |w_i|`` (with a margin); the plane test ``n . x - d`` of doubles by at most
    ``gamma_4 (|n| . |x| + |d|)``; a 3x3 determinant of rounded differences by at most
    ``16u`` times its permanent (Shewchuk's ``orient3d`` bound is ``7.8u`` for exact
    differences, and the differences' rounding adds ``3u`` to first order)."""

    def __init__(self, scene, P, T, m, height, slab, cone_w, target, offsets):
        V = np.asarray(scene.vertices, dtype=float)
        start = np.asarray(scene.offsets)
        self.start = start
        counts = np.diff(start)
        owner = np.repeat(np.arange(len(counts)), counts)
        Pf = np.array([_float(c) for c in P])
        W = V - Pf
        Wa = np.abs(W)
        # depth: sigma (m . (v - P)) against 0, H - slab (near) and H + slab (far)
        mf = np.array([_float(c) for c in m])
        sf = W @ mf
        Bs = 8 * _U * (Wa @ np.abs(mf)) * (1 + 1e-10) + 1e-300
        sigma = 1.0 if height > 0 else -1.0
        x = sigma * sf
        H = abs(height)
        t_near, t_far = _float(H - slab), _float(H + slab)
        lt0 = x + Bs < 0                      # depth < 0, sure
        gt0 = x - Bs > 0                      # depth > 0, sure
        above_far = x - Bs > t_far + 2 * _U * abs(t_far)
        below_far = x + Bs < t_far - 2 * _U * abs(t_far)
        below_near = x + Bs < t_near - 2 * _U * abs(t_near)
        above_near = x - Bs > t_near + 2 * _U * abs(t_near)
        per = lambda a, how: how.reduceat(a, start[:-1]) if len(a) else a
        self.behind = per(lt0, np.logical_and)           # all depths <= 0 (sure)
        self.not_behind = per(gt0, np.logical_or)        # some depth > 0 (sure)
        self.beyond = per(above_far, np.logical_and)     # all depths > far
        self.not_beyond = per(below_far, np.logical_or)
        self.in_front = per(gt0 & below_near, np.logical_and)      # all in (0, near)
        self.reaches = per(lt0 | above_near, np.logical_or)        # some outside it
        # the near-coplanar band: polygon j's vertices against the target's plane ...
        n = np.asarray(scene.normals, dtype=float)
        d = np.asarray(offsets, dtype=float)
        off = np.abs(V @ n[target] - d[target])
        mag = np.abs(V) @ np.abs(n[target]) + abs(d[target])
        self.j_in_target = self._band(per(off > 74 * _U * mag, np.logical_or),
                                      per(off < 54 * _U * mag, np.logical_and))
        # ... and the target's vertices against polygon j's plane
        Tf = np.asarray(scene.polygons[target], dtype=float)
        off = np.abs(n @ Tf.T - d[:, None])
        mag = np.abs(n) @ np.abs(Tf).T + np.abs(d)[:, None]
        self.target_in_j = self._band((off > 74 * _U * mag).any(axis=1),
                                      (off < 54 * _U * mag).all(axis=1))
        # outside the cone over the target: every vertex strictly outside one side
        out = np.zeros(len(counts), dtype=bool)
        for w, sign in cone_w:
            wf = np.array([_float(c) for c in w])
            val = sign * (W @ wf)
            B = 8 * _U * (Wa @ np.abs(wf)) * (1 + 1e-10) + 1e-300
            out |= per(val + B < 0, np.logical_and)
        self.outside_cone = out
        # triangles: the plane through the point (an image of no area) and the
        # engines' edge-on convention (_near_edge_on), decided in floats where certain
        tri = counts == 3
        self.triangle = tri
        self.flat_image = np.full(len(counts), None, dtype=object)
        self.edge_on = np.full(len(counts), None, dtype=object)
        k = np.flatnonzero(tri)
        if len(k):
            a, b, c = (V[start[k] + i] for i in range(3))
            A, Bv, C = a - Pf, b - Pf, c - Pf
            det = np.einsum("ij,ij->i", A, np.cross(Bv, C))
            perm = np.einsum("ij,ij->i", np.abs(A), _abs_cross(Bv, C))
            sure = np.abs(det) > 16 * _U * perm * (1 + 1e-10)
            self.flat_image[k[sure]] = False
            # _near_edge_on: |m . (P - c)| / |m| against 256 u (|P| + |c| + |c - P|), m
            # the Newell normal ((b - a) x (c - a) for a triangle), c the centroid;
            # decided where the two sides differ by a factor of 2 beyond the bounds
            d1, d2 = b - a, c - a
            mt = np.cross(d1, d2)
            Bm = 16 * _U * np.max(_abs_cross(np.abs(d1), np.abs(d2)), axis=1)
            g = (a + b + c) / 3
            w = Pf - g
            Bw = 8 * _U * (np.abs(Pf) + np.abs(a) + np.abs(b) + np.abs(c)).max(axis=1)
            st = np.einsum("ij,ij->i", mt, w)
            Bst = (8 * _U * np.einsum("ij,ij->i", np.abs(mt), np.abs(w))
                   + Bm * np.abs(w).sum(1) + np.abs(mt).sum(1) * Bw
                   + 3 * Bm * Bw)
            nm = np.linalg.norm(mt, axis=1)
            lo_m, hi_m = nm - 2 * Bm, nm + 2 * Bm
            size = lambda X: np.linalg.norm(X, axis=1)
            tau = 256 * _U * (size(np.broadcast_to(Pf, g.shape)) + size(g) + size(g - Pf))
            slack = 1 + 1e-6
            with np.errstate(divide="ignore", invalid="ignore"):
                far = (lo_m > 0) & ((np.abs(st) - Bst) / hi_m > 2 * tau * slack)
                near = (lo_m > 0) & ((np.abs(st) + Bst) / lo_m < 0.5 * tau / slack)
            self.edge_on[k[far]] = False
            self.edge_on[k[near]] = True

    @staticmethod
    def _band(beyond, within):
        out = np.full(len(beyond), None, dtype=object)
        out[within] = True
        out[beyond] = False
        return out


def _seen_whole_skips(scene, P, T, m, height, slab, cone_planes):
    """Per polygon, whether :func:`seen_whole` may pass it by without rationals: every
    vertex certainly off the near-coplanar band of the target's plane and the target's
    vertices certainly off its plane's (``_near_coplanar`` says False), and every vertex
    certainly outside one half-space of the pyramid (nothing of it is left after the
    clip). Float filters with the bounds of :class:`_Filters`; False where any is not
    certain (the caller decides in rationals)."""
    V = np.asarray(scene.vertices, dtype=float)
    start = np.asarray(scene.offsets)
    counts = np.diff(start)
    per = lambda a, how: how.reduceat(a, start[:-1]) if len(a) else a
    Pf = np.array([_float(c) for c in P])
    W = V - Pf
    Wa = np.abs(W)
    # the pyramid: depth < 0, depth > far, or outside a side of the cone, for every vertex
    mf = np.array([_float(c) for c in m])
    x = (1.0 if height > 0 else -1.0) * (W @ mf)
    B = 8 * _U * (Wa @ np.abs(mf)) * (1 + 1e-10) + 1e-300
    t_far = _float(abs(height) + slab)
    outside = per(x + B < 0, np.logical_and) | per(
        x - B > t_far + 2 * _U * abs(t_far), np.logical_and)
    for w, sign in cone_planes:
        wf = np.array([_float(c) for c in w])
        val = sign * (W @ wf)
        Bw = 8 * _U * (Wa @ np.abs(wf)) * (1 + 1e-10) + 1e-300
        outside |= per(val + Bw < 0, np.logical_and)
    # _near_coplanar(V, T): V's vertices against the target's plane (Newell's, exact,
    # rounded), off = |m . (v - T0)| against 256 u (|m| . |v| + |m . T0|)
    mt = _newell(T)
    if mt is None:
        return np.zeros(len(counts), dtype=bool)
    mtf = np.array([_float(c) for c in mt])
    T0 = np.array([_float(c) for c in T[0]])
    w = V - T0
    off = np.abs(w @ mtf) - 8 * _U * (np.abs(w) @ np.abs(mtf)) * (1 + 1e-10)
    size = np.abs(V) @ np.abs(mtf) + abs(float(T0 @ mtf)) + np.abs(T0) @ np.abs(mtf)
    clear = per(off > 300 * _U * size, np.logical_and)
    # and the target's vertices against V's plane (a triangle's: (b - a) x (c - a),
    # its rounding bounded per component as in _Filters)
    tri = counts == 3
    clear &= tri
    k = np.flatnonzero(clear)
    if len(k):
        a, b, c = (V[start[k] + i] for i in range(3))
        d1, d2 = b - a, c - a
        mv = np.cross(d1, d2)
        Bm = 16 * _U * np.max(_abs_cross(np.abs(d1), np.abs(d2)), axis=1)
        Tf = np.array([[_float(c) for c in v] for v in T])
        ok = np.ones(len(k), dtype=bool)
        for t in Tf:
            wt = t - a
            o = (np.abs(np.einsum("ij,ij->i", mv, wt))
                 - 8 * _U * np.einsum("ij,ij->i", np.abs(mv), np.abs(wt)) * (1 + 1e-10)
                 - Bm * np.abs(wt).sum(1))
            sz = (np.abs(mv) @ np.abs(t) + np.abs(np.einsum("ij,ij->i", mv, a))
                  + np.einsum("ij,ij->i", np.abs(mv), np.abs(a)) + Bm * (np.abs(t).sum()
                                                                          + np.abs(a).sum(1)))
            ok &= o > 300 * _U * sz
        clear[k] = ok
    return clear & outside


def _abs_cross(a, b):
    """The permanent-like bound of a cross product: |a_y b_z| + |a_z b_y|, ..."""
    a, b = np.abs(a), np.abs(b)
    return np.stack([a[:, 1] * b[:, 2] + a[:, 2] * b[:, 1],
                     a[:, 2] * b[:, 0] + a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] + a[:, 1] * b[:, 0]], axis=1)


def visible_pieces(scene, point, target, exclude=()):
    """The part of polygon ``target``'s image visible from ``point``: a list of convex
    polygons with rational 3-D vertices on the target's plane (or, for a target that is
    not exactly planar, on the plane its image is projected on: the same image), empty if
    none is visible; None if undecided.

    An occluder wholly between the point and the target (beyond the target's thickness)
    hides its whole image; one that reaches into that range is clipped to the cone over
    the target and to the near side of its plane, where both are exactly planar (its part
    in the target's plane hides by exactff's rule for depth ties); any other case is
    undecided. Polygons in ``exclude`` do not occlude."""
    P, T, frame = _point_and_target(scene, point, target)
    if frame is None:
        return None
    m, height, slab = frame
    axis = max(range(3), key=lambda i: abs(m[i]))
    keep = [i for i in range(3) if i != axis]

    def depth(v):
        # 0 at the point, 1 on the target's plane, along the plane's normal
        return _dot(m, _sub(v, P)) / height

    def image(v):
        # central projection onto the target's plane, in its 2-D coordinates
        g = depth(v)
        return tuple(p + (x - p) / g for p, x in zip(P, v))

    def flat(v):
        return (v[keep[0]], v[keep[1]])

    def lift(q):
        # the point of the target's plane over the 2-D point q
        v = [Fraction(0)] * 3
        v[keep[0]], v[keep[1]] = q
        v[axis] = (_dot(m, T[0]) - m[keep[0]] * q[0] - m[keep[1]] * q[1]) / m[axis]
        return tuple(v)

    if any(depth(v) <= 0 for v in T):
        return None
    target2 = [flat(image(v)) for v in T]
    if not _convex(target2):
        return None
    if _area2(target2) < 0:
        target2 = target2[::-1]
    near, far = 1 - slab / abs(height), 1 + slab / abs(height)
    planar = slab == 0
    # the cone from the point over the target: one half-space per edge
    cone_planes = _cone_planes(P, T)
    cone = _cone(P, T)
    pieces = [target2]
    offsets = scene.plane_offsets
    # every exact decision below first asked of a float filter (None: not certain)
    sure = _Filters(scene, P, T, m, height, slab, cone_planes, target, offsets)
    for j, polygon in enumerate(scene.polygons):
        if j == target or j in exclude or not pieces:
            continue
        if sure.behind[j]:
            continue                     # behind the point (every depth < 0)
        a, b = sure.j_in_target[j], sure.target_in_j[j]
        if a is None or b is None:
            tie = _coplanar_by_rule(scene, j, target, offsets)
        else:
            tie = True if a and b else (False if not (a or b) else None)
        if sure.not_behind[j] and tie is False:
            if sure.beyond[j]:
                continue                 # beyond the target
            if sure.in_front[j] and sure.triangle[j] and sure.flat_image[j] is False:
                # wholly between the point and the target, its image a triangle of
                # area: it hides its image; outside the cone it hides nothing here,
                # unless the engines' edge-on convention leaves the row undecided
                edge_on = sure.edge_on[j]
                if edge_on is None:
                    edge_on = _near_edge_on([_rational(v) for v in polygon], P)
                if edge_on:
                    return None
                if sure.outside_cone[j]:
                    continue             # its image is separated from every piece
        V = [_rational(v) for v in polygon]
        g = [depth(v) for v in V]
        if all(x <= 0 for x in g):
            continue                     # behind the point
        if tie is None:
            return None                  # the engines' tree decides: undecided
        if tie and not _in_front_on_a_tie(scene, P, j, target):
            continue                     # a depth tie it loses: it hides nothing
        if not tie and all(x > far for x in g):
            continue                     # beyond the target
        if not tie and not all(0 < x < near for x in g):
            # it reaches the target's range: clip it in 3-D, both planes exact
            plane = _plane(V)
            if not planar or plane is None:
                return None
            # strictly on the point's side of the target's plane
            V = _clip(V, lambda v: height * _dot(m, _sub(T[0], v)))
            for half in cone:
                if len(V) < 3:
                    break
                V = _clip(V, half)
            if len(V) < 3:
                continue
            if all(_dot(m, _sub(v, T[0])) == 0 for v in V):
                # in the target's plane: a depth tie (exactff.predicates.tie_priority's
                # rule, restated: a polygon whose front faces the point is in front of
                # one whose back does; else the first in input order)
                if not _in_front_on_a_tie(scene, P, j, target):
                    continue
            if _dot(plane, _sub(V[0], P)) == 0:
                continue                 # edge-on from the point: no image of area
        shadow = [flat(image(v)) for v in V]
        a = _area2(shadow)
        if a == 0:
            continue
        if _near_edge_on([_rational(v) for v in polygon], P):
            return None                  # the engines' convention: no image
        if not _convex(shadow):
            return None
        if a < 0:
            shadow = shadow[::-1]
        # subtract the convex shadow: for each piece, its parts outside each edge; a
        # piece the shadow does not overlap stays whole (cutting it along the shadow's
        # edges would leave the same area in more pieces, of larger rationals)
        remaining = []
        for piece in pieces:
            if _separated(piece, shadow):
                remaining.append(piece)
                continue
            rest = piece
            for k in range(len(shadow)):
                left = _left_of(shadow[k], shadow[(k + 1) % len(shadow)])
                outside = _clip(rest, lambda v, left=left: -left(v))
                if len(outside) >= 3 and _area2(outside) > 0:
                    remaining.append(outside)
                rest = _clip(rest, left)
                if len(rest) < 3 or _area2(rest) == 0:
                    break
        pieces = remaining
    return [[lift(q) for q in piece] for piece in pieces]


def polygon_form_factor_mp(point, normal, polygon, dps=60):
    """The unoccluded form factor from ``point`` (unit ``normal``) to a convex planar
    polygon in front of the point's plane, from rational vertices: the contour form
    ``F = |sum_i gamma_i n . (R_i x R_i+1) / |R_i x R_i+1|| / (2 pi)``."""
    with mpmath.workdps(dps):
        def mp(v):
            return [mpmath.mpf(c.numerator) / c.denominator for c in v]
        P, n = mp(_rational(point)), [mpmath.mpf(float(c)) for c in normal]
        length = mpmath.sqrt(sum(c * c for c in n))
        n = [c / length for c in n]      # the engines take the normal's direction
        R = [[x - p for x, p in zip(mp(v), P)] for v in polygon]
        total = mpmath.mpf(0)
        for k in range(len(R)):
            a, b = R[k], R[(k + 1) % len(R)]
            c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            norm = mpmath.sqrt(sum(x * x for x in c))
            if norm == 0:
                continue
            gamma = mpmath.atan2(norm, sum(x * y for x, y in zip(a, b)))
            total += gamma * sum(x * y for x, y in zip(n, c)) / norm
        return abs(total) / (2 * mpmath.pi)


def front_part_form_factor(point, normal, polygon, dps=60):
    """The unoccluded form factor from ``point`` (``normal``) to the part of a convex
    planar polygon (float vertices, taken as exact) in front of the point's plane,
    whichever way the polygon faces: the measure of its image on the disk, so at most
    what it can hide of anything behind it."""
    P, n = _rational(point), _rational(normal)
    piece = _clip([_rational(v) for v in polygon], lambda v: _dot(n, _sub(v, P)))
    if len(piece) < 3:
        return mpmath.mpf(0)
    return polygon_form_factor_mp(point, normal, piece, dps)


def visible_form_factor(scene, point, normal, target, two_sided=False, exclude=(), dps=60):
    """The form factor from ``point`` to the visible part of polygon ``target``, as an
    mpmath number, or None if undecided; ``two_sided`` as in exactff (else the target
    counts only where its front, by ``scene.normals``, faces the point)."""
    P, n = _rational(point), _rational(normal)
    T = [_rational(v) for v in scene.polygons[target]]
    frame = _target_frame(T, P)
    if frame is None:
        return None
    m = frame[0]
    if _dot(m, _rational(scene.normals[target])) < 0:
        m = tuple(-c for c in m)
    if _dot(m, _sub(P, T[0])) < 0 and not two_sided:
        return mpmath.mpf(0)              # the point is behind the target
    pieces = visible_pieces(scene, point, target, exclude)
    if pieces is None:
        return None
    front_of_point = lambda v: _dot(n, _sub(v, P))
    # the pieces' sum at the working precision (at mpmath's default, 53 bits, it would be
    # rounded like a double: half an ulp of the value, more than the bounds it decides)
    with mpmath.workdps(dps):
        total = mpmath.mpf(0)
        for piece in pieces:
            piece = _clip(piece, front_of_point)
            if len(piece) >= 3:
                total += polygon_form_factor_mp(point, normal, piece, dps)
    return total


def _hull(points, keep):
    """The convex hull (monotone chain, exact) of points sorted by their ``keep``
    coordinates, as a list of those points in counter-clockwise order of ``keep``."""
    flat = lambda v: (v[keep[0]], v[keep[1]])

    def chain(seq):
        out = []
        for v in seq:
            while len(out) >= 2 and _left_of(flat(out[-2]), flat(out[-1]))(flat(v)) <= 0:
                out.pop()
            out.append(v)
        return out[:-1]
    return chain(points) + chain(points[::-1])


def seen_whole(scene, point, target):
    """Whether no other polygon hides any part of polygon ``target`` from ``point``
    (exact, in rationals); False where that is not decided here.

    Every other polygon is clipped to the cone from the point over the convex hull of the
    target's image and to the near side of the target's far
    thickness; a piece left with an image of positive area (exactly planar, not edge-on
    from the point) may hide part of the target, and so may any piece of a polygon that
    is not exactly planar or lies within the engines' depth-tie band of the target
    (conservative: False)."""
    P, T, frame = _point_and_target(scene, point, target)
    if frame is None:
        return False
    m, height, slab = frame
    depth = lambda v: _dot(m, _sub(v, P)) / height
    if any(depth(v) <= 0 for v in T):
        return False
    axis = max(range(3), key=lambda i: abs(m[i]))
    keep = [i for i in range(3) if i != axis]
    # the cone over the convex hull of the target's image (its vertices projected onto
    # the plane m . x = m . T[0])
    image = sorted({tuple(p + (x - p) / depth(v) for p, x in zip(P, v)) for v in T},
                   key=lambda v: (v[keep[0]], v[keep[1]]))
    H = _hull(image, keep)
    far = 1 + slab / abs(height)
    halves = [lambda v: depth(v), lambda v: far - depth(v)] + _cone(P, H)
    # the polygons a float filter shows nowhere near the target's plane nor the pyramid
    skip = _seen_whole_skips(scene, P, T, m, height, slab, _cone_planes(P, H))
    for j, polygon in enumerate(scene.polygons):
        if j == target or skip[j]:
            continue
        V = [_rational(v) for v in polygon]
        if _near_coplanar(V, T):
            return False
        # the piece in the closed pyramid from the point to the target's far thickness
        for half in halves:
            if len(V) < 3:
                break
            V = _clip(V, half)
        if len(V) < 3:
            continue
        if _plane([_rational(v) for v in polygon]) is None:
            return False
        normal = _newell(V)
        if normal is None or _dot(normal, _sub(V[0], P)) == 0:
            continue                     # no area, or edge-on from the point: no image
        return False
    return True


def unoccluded_form_factor(scene, point, normal, target, two_sided=False, dps=60):
    """The form factor from ``point`` to the whole of polygon ``target`` (its part in
    front of the point's plane), as an mpmath number, where :func:`seen_whole` holds;
    else None. The contour form over the target's boundary clipped to the point's front
    half-space (valid for a non-convex target: the clip's bridging edges cancel)."""
    if not seen_whole(scene, point, target):
        return None
    P = _rational(point)
    T = [_rational(v) for v in scene.polygons[target]]
    m = _newell(T)
    if _dot(m, _rational(scene.normals[target])) < 0:
        m = tuple(-c for c in m)
    if _dot(m, _sub(P, T[0])) < 0 and not two_sided:
        return mpmath.mpf(0)              # the point is behind the target
    n = _rational(normal)
    piece = _clip(T, lambda v: _dot(n, _sub(v, P)))
    if len(piece) < 3:
        return mpmath.mpf(0)
    return polygon_form_factor_mp(point, normal, piece, dps)
