"""Exact unoccluded point-to-polygon form factors: the sector (Lambert) form and Eq. 3.

Every function here works in the local frame of the receiving point ``p``: origin at
``p``, z along the unit normal ``n``. A polygon is first clipped to the upper half-space
(horizon clipping); each remaining edge ``a -> b`` projects onto the hemisphere as a
great-circle arc, whose orthographic image on the base disk is an ellipse arc. The form
factor is the area of the image of the polygon divided by pi.

Two exact evaluations of that area are provided:

* the **sector form** (Lambert's contour formula, DESIGN 2.1)
  ``F = (1 / 2 pi) sum_k theta_k (m_k . n)`` with ``m_k = (a x b) / |a x b|`` and
  ``theta_k = atan2(|a x b|, a . b)``; it needs no special cases and is the hot path;
* the paper's **Eq. 3, corrected**, integrated span by span between the x-extremes of
  each arc (monotone-span splitting), in :func:`eq3_form_factor`.

The sector sums are evaluated in offset form with a rounding-error estimate per
polygon; where the estimate misses the requested ``tolerance``, the value is evaluated
again from the float input in long double and, if need be, with mpmath
(``docs/explanation/robustness.md``). See ``docs/explanation/conventions.md`` for the
orientation conventions.
"""

import math

import numpy as np

from . import _tolerances as tol
from .scene import NumericalError
from .geometry import receiver_frame, rotate, to_local

__all__ = [
    "mp_form_factor",
    "point_polygon_form_factor",
    "point_polygon_form_factors",
    "sector_form_factor",
    "eq3_form_factor",
    "eq3_ring_area",
    "eq3_edge_integral",
    "arc_x_extremes",
]

TWO_PI = 2.0 * math.pi


# ---------------------------------------------------------------------------------------
# argument checks shared by every entry point
# ---------------------------------------------------------------------------------------
def as_point(point, name="point"):
    """Return ``point`` as a finite float array of shape (..., 3), or raise ValueError."""
    p = np.asarray(point, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"{name} must have shape (..., 3), got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} must be finite, got {point!r}")
    return p


def as_normal(normal, name="normal"):
    """Return ``normal`` scaled to unit length, shape (..., 3), or raise ValueError.

    Any finite non-zero vector is accepted and normalised.
    """
    n = as_point(normal, name)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    if np.any(length == 0) or not np.all(np.isfinite(length)):
        raise ValueError(f"{name} must be a non-zero finite vector, got {normal!r}")
    return n / length


def as_receiver(point, normal):
    """One receiver, checked once for every entry point: ``point`` and ``normal`` as float
    arrays of shape (3,), finite, the normal non-zero (returned as given, not scaled:
    the methods normalise it). Raises ValueError naming the argument.

    Examples
    --------
    >>> as_receiver([0, 0, 0], [0, 0, 2])[1].tolist()
    [0.0, 0.0, 2.0]
    >>> as_receiver([0, float("nan"), 0], [0, 0, 1])
    Traceback (most recent call last):
    ...
    ValueError: point must be finite, got [0, nan, 0]
    """
    P, N, shape = as_receivers(point, normal)
    if shape != ():
        raise ValueError(f"point and normal must have shape (3,), got {np.shape(point)} and "
                         f"{np.shape(normal)}")
    return P[0], N[0]


def as_receivers(point, normal, names=("point", "normal")):
    """Receivers broadcast together: ``(P, N, shape)`` with ``P``, ``N`` of shape (M, 3)
    (normals as given, not scaled) and ``shape`` the broadcast shape without the last
    axis. Raises ValueError naming the argument.

    Examples
    --------
    >>> P, N, shape = as_receivers([[0, 0, 0], [1, 0, 0]], [0, 0, 1])
    >>> P.shape, N.shape, shape
    ((2, 3), (2, 3), (2,))
    """
    p = as_point(point, names[0])
    as_normal(normal, names[1])
    n = np.asarray(normal, dtype=float)
    try:
        p, n = np.broadcast_arrays(p, n)
    except ValueError:
        raise ValueError(f"{names[0]} of shape {p.shape} and {names[1]} of shape {n.shape} "
                         f"do not broadcast") from None
    return p.reshape(-1, 3), n.reshape(-1, 3), p.shape[:-1]


def as_scene(scene):
    """``scene`` if it is an :class:`exactff.Scene`, else a TypeError saying what to do."""
    from .scene import Scene

    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an exactff.Scene (build one with "
                        f"Scene.from_polygons or load_scene), got {type(scene).__name__}")
    return scene


# ---------------------------------------------------------------------------------------
# sector (Lambert) form, vectorised over edges
# ---------------------------------------------------------------------------------------
#: constants of the rounding-error estimate (DESIGN 2.2): per edge term, the relative
#: error of its angle and sum (C1 ulps), and of its plane's direction (C2 ulps per unit
#: of the cross product's condition number)
_C1, _C2 = 10.0, 10.0


def _clipped_sector_sums(A0, E, nxt, owner, m, eps=tol.EPS):
    """Sector sums of horizon-clipped polygons, with their rounding-error estimates.

    The polygons are given in *offset form* (DESIGN 2.2): ``A0`` (m, 3) is a reference
    vertex of each polygon relative to the point, in the local frame, and ``E`` (V, 3)
    are the vertices' offsets from it. The edge plane ``m = a x b`` is evaluated as
    ``A0 x (e_b - e_a) + e_a x e_b``, which stays accurate for polygons small next to
    their distance (the plain cross product loses ``log10(distance / size)`` digits).

    Returns ``(S, mags, errs)``: per polygon the sum of the sector terms, the sum of
    their absolute values, and the estimated error of the plane directions. Works in the
    dtype of ``A0`` and ``E`` (float64, or longdouble for the second tier), with unit
    roundoff ``eps``; ``owner`` must be sorted (each polygon's vertices contiguous).
    """
    dt = A0.dtype
    n_e = len(owner)
    Ax, Ay, Az = (A0[owner, k] for k in range(3))
    Eax, Eay, Eaz = (E[:, k].copy() for k in range(3))
    Ebx, Eby, Ebz = Eax[nxt], Eay[nxt], Eaz[nxt]
    za = Az + Eaz
    zb = Az + Ebz
    above_a, above_b = za > 0, zb > 0
    ci = np.flatnonzero(above_a != above_b)
    # horizon crossing of the edge, as an offset (its height is exactly 0)
    t = za[ci] / (za[ci] - zb[ci])
    EX = np.column_stack([Ea[ci] + t * (Eb[ci] - Ea[ci])
                          for Ea, Eb in ((Eax, Ebx), (Eay, Eby), (Eaz, Ebz))])
    enter = ~above_a[ci]
    ce, cx = ci[enter], ci[~enter]
    for k, (Ea, Eb) in enumerate(((Eax, Ebx), (Eay, Eby), (Eaz, Ebz))):
        Ea[ce] = EX[enter, k]
        Eb[cx] = EX[~enter, k]
    keep = above_a | above_b
    if not keep.all():
        kk = np.flatnonzero(keep)
        Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz = (
            v[kk] for v in (Ax, Ay, Az, Eax, Eay, Eaz, Ebx, Eby, Ebz))
    else:
        kk = slice(None)
    # the edge's plane in offset form: m = A x (Eb - Ea) + Ea x Eb
    Dx, Dy, Dz = Ebx - Eax, Eby - Eay, Ebz - Eaz
    p1, p2, p3, p4 = Ax * Dy, Ay * Dx, Eax * Eby, Eay * Ebx
    Mz = (p1 - p2) + (p3 - p4)
    Mx = (Ay * Dz - Az * Dy) + (Eay * Ebz - Eaz * Eby)
    My = (Az * Dx - Ax * Dz) + (Eaz * Ebx - Eax * Ebz)
    s = np.sqrt(Mx * Mx + My * My + Mz * Mz)
    ax, ay, az = Ax + Eax, Ay + Eay, Az + Eaz
    bx, by, bz = Ax + Ebx, Ay + Eby, Az + Ebz
    theta = np.arctan2(s, ax * bx + ay * by + az * bz)
    ok = s > 0
    terms = np.zeros(n_e, dtype=dt)
    terms[kk] = np.divide(theta * Mz, s, out=np.zeros_like(s), where=ok)
    # rounding error of each term theta m_z / |m| (first order): for small theta the term
    # is about m_z / (a . b), so the error of m_z dominates, bounded componentwise by the
    # magnitudes of its summands (Z); the error of |m| enters at relative order theta^2,
    # bounded by |a| |b| (at least the cross product's condition)
    Z = np.abs(p1) + np.abs(p2) + np.abs(p3) + np.abs(p4)
    Nm = np.sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(ok, _C2 * eps * (Z + theta * theta * Nm) / s,
                       np.where(Nm > 0, np.inf, 0.0))
    err = np.zeros(n_e, dtype=dt)
    err[kk] = theta * np.minimum(2.0, rel)
    # horizon arcs: each runs from an exit point to the next entry point along the line
    # where the polygon's plane meets z = 0; its term is the signed angle between them,
    # phi(entry) - phi(exit). phi is measured from the polygon's first crossing point:
    # the crossing points lie on one line not through the origin, so their angles from
    # any one of them stay within (-pi, pi), and short horizon arcs give small angles
    # (no cancellation between large ones)
    oc = owner[ci]
    X = A0[oc] + EX
    first_of = np.full(m, -1)
    first_of[oc[::-1]] = np.arange(len(ci))[::-1]
    f = X[first_of[oc], :2]
    phi = np.arctan2(f[:, 0] * X[:, 1] - f[:, 1] * X[:, 0], f[:, 0] * X[:, 0] + f[:, 1] * X[:, 1])
    terms[ci] += np.where(enter, phi, -phi)
    # per-polygon sums over contiguous blocks (reduceat keeps the dtype; bincount
    # would round longdouble to double)
    starts = np.searchsorted(owner, np.arange(m))
    sums = np.add.reduceat(terms, starts)
    mags = np.add.reduceat(np.abs(terms), starts)
    errs = np.add.reduceat(err, starts)
    return sums, mags, errs


def _finish(S, mags, errs, d0, one_sided, eps=tol.EPS, unchecked=None):
    """Form factors and their error estimates from signed sector sums ``S``
    (front-facing polygons have S < 0). ``unchecked`` marks values known to be
    unreliable, exempt from the sign check."""
    F = np.sign(d0) * S / TWO_PI
    err = (_C1 * eps * mags + errs) / TWO_PI
    if one_sided:
        F[d0 >= 0] = 0.0
        err[d0 >= 0] = 0.0
    # rounding can leave a value below 0 by at most its error estimate
    ok = F >= -tol.ROUNDING_OVERSHOOT * (err + 1e-300)
    if unchecked is not None:
        ok |= unchecked
    if not np.all(ok):
        i = int(np.flatnonzero(~ok)[0])
        raise NumericalError(f"polygon {i}: form factor {F[i]!r} below 0 beyond its rounding "
                             f"error estimate {err[i]:.3g}")
    return np.maximum(F, 0.0), err


class _Polygons:
    """Flat (ragged) polygon arrays of a scene, shared by the vectorised kernels."""

    __slots__ = ("V", "nxt", "owner", "normals", "centroids", "counts", "offsets", "vmax",
                 "first", "E")

    def __init__(self, scene):
        self.V = scene.vertices
        self.offsets = scene.offsets
        self.counts = np.diff(scene.offsets)
        self.owner = np.repeat(np.arange(len(scene)), self.counts)
        nxt = np.arange(len(self.V)) + 1
        nxt[scene.offsets[1:] - 1] = scene.offsets[:-1]
        self.nxt = nxt
        self.normals = scene.normals
        self.centroids = scene.centroids
        # largest coordinate magnitude of each polygon: the scale of its rounding
        self.vmax = np.maximum.reduceat(np.abs(self.V).max(axis=1), scene.offsets[:-1])
        # offset form: each polygon's first vertex, and every vertex relative to it
        self.first = self.V[scene.offsets[:-1]]
        self.E = self.V - self.first[self.owner]

    @classmethod
    def of(cls, scene):
        cache = scene._cache
        if "flat" not in cache:
            cache["flat"] = cls(scene)
        return cache["flat"]


def plane_distances(flat, p):
    """Signed distances of ``p`` from each polygon's plane (> 0: in front), and the
    tolerance below which their float value cannot decide the side."""
    rel = flat.centroids - p
    d = -np.einsum("ij,ij->i", flat.normals, rel)
    scale = np.abs(p).max() + flat.vmax
    return d, tol.PLANE_SIDE_ULPS * tol.EPS * scale


def exact_side(P, p):
    """Exact sign of ``A . (p - c)`` with ``A`` the Newell area vector and ``c`` the
    vertex mean of polygon ``P``, in rational arithmetic (the float input is exact):
    +1 when ``p`` is in front of the polygon's plane, -1 behind, 0 in it."""
    from fractions import Fraction

    Q = [[Fraction(float(c)) for c in v] for v in P]
    q0 = Q[0]
    A = [Fraction(0)] * 3
    for a, b in zip(Q[1:-1], Q[2:]):
        u = [a[i] - q0[i] for i in range(3)]
        w = [b[i] - q0[i] for i in range(3)]
        A[0] += u[1] * w[2] - u[2] * w[1]
        A[1] += u[2] * w[0] - u[0] * w[2]
        A[2] += u[0] * w[1] - u[1] * w[0]
    k = len(Q)
    val = sum(A[i] * (Fraction(float(p[i])) - sum(v[i] for v in Q) / k) for i in range(3))
    return (val > 0) - (val < 0)


def plane_sides(flat, p, exact=True):
    """Side of ``p`` for every polygon (+1 front, -1 back, 0 in the plane), and the mask
    of polygons whose plane passes within rounding of ``p`` (the band).

    Beyond the band the float value decides. Inside it, ``exact=True`` decides in
    rational arithmetic (the double-precision form factor is then unreliable), and
    ``exact=False`` gives 0: seen edge-on, as the visibility engine counts them."""
    d, dtol = plane_distances(flat, p)
    side = np.sign(d).astype(np.int8)
    band = np.abs(d) <= dtol
    side[band] = 0
    if exact and band.any():
        # exactly coplanar and axis-aligned (all vertices share p's coordinate on some
        # axis): side 0 without rational arithmetic, the common case in rooms
        same = np.zeros(len(band), dtype=bool)
        for k in range(3):
            same |= np.logical_and.reduceat(flat.V[:, k] == p[k], flat.offsets[:-1])
        for i in np.flatnonzero(band & ~same):
            side[i] = exact_side(flat.V[flat.offsets[i]:flat.offsets[i + 1]], p)
    return side, band


_LONGDOUBLE_EPS = float(np.finfo(np.longdouble).eps) / 2


def _extended_values(flat, ids, p, n_raw, d0, one_sided):
    """Form factors and error estimates of polygons ``ids`` in long double arithmetic."""
    ld = np.longdouble
    counts = flat.counts[ids]
    owner = np.repeat(np.arange(len(ids)), counts)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    vidx = flat.offsets[ids][owner] + np.arange(len(owner)) - starts[owner]
    nxt = np.arange(len(vidx)) + 1
    nxt[starts + counts - 1] = starts
    R = receiver_frame(n_raw, dtype=ld)
    V = flat.V[vidx].astype(ld)
    first = V[starts]
    A0 = rotate(first - p.astype(ld), R)
    E = rotate(V - first[owner], R)
    S, mags, errs = _clipped_sector_sums(A0, E, nxt, owner, len(ids), eps=_LONGDOUBLE_EPS)
    F, err = _finish(S, mags, errs, d0, one_sided, eps=_LONGDOUBLE_EPS)
    return F.astype(float), err.astype(float)


def unoccluded_row(flat, p, n, *, one_sided=True, tolerance=None,
                   return_error=False, in_band="exact", strict=None):
    """Unoccluded form factors from ``p`` (normal ``n``) to every polygon of ``flat``.

    The hot path: culls polygons seen edge-on, facing away (one-sided) or wholly below
    the horizon, then evaluates the sector form over all remaining edges at once, in
    offset form, with a rounding-error estimate per polygon. With a ``tolerance``, every
    value whose estimate exceeds ``tolerance * F`` is re-evaluated with mpmath from the
    original float input (:func:`mp_form_factor`). Returns (N,) values, and their error estimates if
    ``return_error``.

    ``in_band`` says what happens to polygons whose plane passes within rounding of
    ``p``: ``"exact"`` decides the side exactly and evaluates them with mpmath (their
    double value is unreliable); ``"edge_on"`` counts them as seen edge-on (0), as the
    visibility engine does.

    ``strict`` (default: not ``return_error``): raise :class:`NumericalError` when a
    value misses the tolerance even in the last tier, instead of returning it with its
    estimate.
    """
    if strict is None:
        strict = not return_error
    N = len(flat.normals)
    p = np.asarray(p, dtype=float)
    n_raw = np.asarray(n, dtype=float)
    side, band = plane_sides(flat, p, exact=(in_band == "exact"))
    if in_band == "edge_on":
        band[:] = False
    live = (side > 0) if one_sided else (side != 0)
    F = np.zeros(N)
    err = np.zeros(N)
    if not live.any():
        return (F, err) if return_error else F
    R = receiver_frame(n_raw)
    vmask = live[flat.owner]
    idx = np.flatnonzero(vmask)
    newpos = np.cumsum(vmask) - 1
    owner_all = flat.owner[idx]
    A0_all = to_local(flat.first, p, R)
    E = rotate(flat.E[idx], R)
    # wholly below the horizon: nothing to integrate
    zmax = np.full(N, -np.inf)
    np.maximum.at(zmax, owner_all, A0_all[owner_all, 2] + E[:, 2])
    live &= zmax > 0
    if not live.any():
        return (F, err) if return_error else F
    keep_v = live[owner_all]
    if not keep_v.all():
        sel = np.flatnonzero(keep_v)
        newpos2 = np.cumsum(keep_v) - 1
        nxt = newpos2[newpos[flat.nxt[idx[sel]]]]
        E = E[sel]
        owner_all = owner_all[sel]
    else:
        nxt = newpos[flat.nxt[idx]]
    ids = np.flatnonzero(live)
    local_id = np.full(N, -1)
    local_id[ids] = np.arange(len(ids))
    owner = local_id[owner_all]
    S, mags, errs = _clipped_sector_sums(A0_all[ids], E, nxt, owner, len(ids))
    F[ids], err[ids] = _finish(S, mags, errs, -side[ids].astype(float), one_sided,
                               unchecked=band[ids])
    # p within rounding of the polygon's plane (its side decided exactly): the double
    # value can be anything; only the high-precision tier can give it
    err[ids[band[ids]]] = np.inf
    if tolerance is not None:
        flagged = ids[err[ids] > tolerance * F[ids]]
        extended = flagged[~band[flagged]]
        if len(extended) and _LONGDOUBLE_EPS < tol.EPS / 100:
            # second tier: the same vectorised sums in extended precision (x87 80-bit
            # long double where the platform has it), from the original float input
            Fl, el = _extended_values(flat, extended, p, n_raw,
                                      -side[extended].astype(float), one_sided)
            good = el <= tolerance * Fl
            F[extended[good]], err[extended[good]] = Fl[good], el[good]
            flagged = np.setdiff1d(flagged, extended[good])
        # last tier (DESIGN 2.2): mpmath at the digits the value needs
        for i in flagged:
            P = flat.V[flat.offsets[i]:flat.offsets[i + 1]]
            F[i], err[i] = mp_form_factor(p, n_raw, P, one_sided=one_sided,
                                          tolerance=tolerance, error=True,
                                          side=int(side[i]))
        # the last tier's values are checked too: one that still misses the tolerance
        # (mpmath stopped at its precision limit) is returned with its estimate when the
        # caller asks for estimates, and raises otherwise
        missed = flagged[~(err[flagged] <= tolerance * F[flagged] + tol.MP_VALUE_FLOOR)]
        if len(missed) and strict:
            i = int(missed[0])
            raise NumericalError(f"polygon {i}: the form factor {F[i]:.17g} misses the "
                                 f"tolerance {tolerance:g} (error estimate {err[i]:.3g}) "
                                 f"even in {tol.MP_MAX_DPS}-digit arithmetic; ask error=True "
                                 f"for the value with its estimate")
    return (F, err) if return_error else F


def point_polygon_form_factors(point, normal, polygons, *, one_sided=True,
                               tolerance=tol.DEFAULT_RTOL, error=False):
    """Unoccluded form factors from one point to many polygons (vectorised).

    Parameters
    ----------
    point : array_like of shape (3,)
        Receiving point ``p``.
    normal : array_like of shape (3,)
        Receiver normal ``n`` (normalised if not unit).
    polygons : Scene or sequence of array_like of shape (K_i, 3)
        The polygons; a sequence is validated as by :meth:`exactff.Scene.from_polygons`.
    one_sided : bool, default True
        If True, a polygon receives only when its front faces ``p``.
    tolerance : float or None, default 1e-12
        Requested relative accuracy. Values whose rounding-error estimate exceeds
        ``tolerance * F`` are re-evaluated with mpmath from the float input (see
        ``docs/explanation/robustness.md``). None: plain double precision.
    error : bool, default False
        Also return the error estimates.

    Returns
    -------
    ndarray of shape (M,)
        ``F(p -> polygon_j)`` with horizon clipping and no occlusion; with
        ``error=True``, a pair ``(F, err)``.

    See Also
    --------
    point_polygon_form_factor : the same for one polygon, as a float.

    Examples
    --------
    Two unit squares facing down at height 1, one centred over ``p``:

    >>> sq = np.array([[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]])
    >>> point_polygon_form_factors([0, 0, 0], [0, 0, 1], [sq, sq + [1, 0, 0]]).round(6)
    array([0.239456, 0.084354])
    """
    from .scene import Scene

    p = as_point(point)
    as_normal(normal)
    n = np.asarray(normal, dtype=float)
    if p.shape != (3,) or n.shape != (3,):
        raise ValueError("point and normal must have shape (3,)")
    _check_tolerance(tolerance)
    scene = polygons if isinstance(polygons, Scene) else Scene.from_polygons(polygons)
    F, err = unoccluded_row(_Polygons.of(scene), p, n, one_sided=one_sided,
                            tolerance=tolerance, return_error=True, strict=not error)
    return (F, err) if error else F


def _check_tolerance(tolerance):
    if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")


# ---------------------------------------------------------------------------------------
# high precision: the sector form in mpmath, from the original float input
# ---------------------------------------------------------------------------------------
def _mp_sector(point, normal, polygon, one_sided, dps, side_hint=None):
    import mpmath as mp

    with mp.workdps(dps):
        nv = [mp.mpf(float(c)) for c in normal]
        ln = mp.sqrt(sum(c * c for c in nv))
        nz = [c / ln for c in nv]
        k = min(range(3), key=lambda i: abs(nz[i]))
        e = [mp.mpf(0)] * 3
        e[k] = mp.mpf(1)
        dot = nz[k]
        t1 = [e[i] - dot * nz[i] for i in range(3)]
        l1 = mp.sqrt(sum(c * c for c in t1))
        t1 = [c / l1 for c in t1]
        t2 = [nz[1] * t1[2] - nz[2] * t1[1], nz[2] * t1[0] - nz[0] * t1[2],
              nz[0] * t1[1] - nz[1] * t1[0]]
        pv = [mp.mpf(float(c)) for c in point]
        Q = []
        for v in polygon:
            r = [mp.mpf(float(v[i])) - pv[i] for i in range(3)]
            Q.append([sum(r[i] * ax[i] for i in range(3)) for ax in (t1, t2, nz)])
        # side of p: Newell normal . (centroid - p), exact up to the working precision
        K = len(Q)
        Nw = [mp.mpf(0)] * 3
        for i in range(K):
            a, b = Q[i], Q[(i + 1) % K]
            Nw[0] += (a[1] - b[1]) * (a[2] + b[2])
            Nw[1] += (a[2] - b[2]) * (a[0] + b[0])
            Nw[2] += (a[0] - b[0]) * (a[1] + b[1])
        side = sum(Nw[i] * sum(q[i] for q in Q) for i in range(3))
        if side_hint is not None:
            # the exact side (rational arithmetic): the working precision may not resolve
            # a point extremely close to the plane (side < 0 means p in front)
            side = -side_hint
        if side == 0 or (one_sided and side > 0):
            return mp.mpf(0)
        C = []
        for i in range(K):
            a, b = Q[i], Q[(i + 1) % K]
            if a[2] > 0:
                C.append(a)
            if (a[2] > 0) != (b[2] > 0):
                t = a[2] / (a[2] - b[2])
                C.append([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), mp.mpf(0)])
        total = mp.mpf(0)
        for i in range(len(C)):
            a, b = C[i], C[(i + 1) % len(C)]
            m = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            sm = mp.sqrt(sum(c * c for c in m))
            if sm != 0:
                total += mp.atan2(sm, sum(a[j] * b[j] for j in range(3))) * m[2] / sm
        # the image of the boundary ring, whichever way it winds: for a point within
        # rounding of a polygon that is planar only to rounding, the ring's winding can
        # disagree with the side decided from the polygon's Newell plane (value 0 for
        # 0.5 before); every other path integrates the ring as given too
        return abs(total) / (2 * mp.pi)


def mp_form_factor(point, normal, polygon, *, one_sided=True, tolerance=tol.DEFAULT_RTOL,
                   dps=None, error=False, side=None):
    """Unoccluded form factor with mpmath, from the float input taken as exact.

    The sector form evaluated at ``dps`` decimal digits and again 20 digits higher; the
    precision grows until the two agree to ``tolerance`` (relative), up to 400 digits;
    beyond, :class:`exactff.NumericalError` (with ``error=True``: the value and the
    difference as its error estimate). This is what automatic escalation calls.

    Parameters
    ----------
    point, normal : array_like of shape (3,)
    polygon : array_like of shape (K, 3)
    one_sided : bool, default True
    tolerance : float, default 1e-12
    dps : int, optional
        Starting precision (default 30 digits).
    error : bool, default False
        Also return the error estimate (the difference of the two evaluations).
    side : {-1, 0, 1}, optional
        The side of the point, if already decided exactly (+1: in front).

    Returns
    -------
    float, or (float, float) with ``error=True``

    Examples
    --------
    A 1e-9 square at distance 1, where double precision keeps only a few digits:

    >>> sq = np.array([[0, 0, 1], [0, 1e-9, 1], [1e-9, 1e-9, 1], [1e-9, 0, 1]])
    >>> mp_form_factor([0, 0, 0], [0, 0, 1], sq)  # F = A / pi to first order
    3.183098861837907e-19
    """
    P = np.asarray(polygon, dtype=float)
    prec = 30 if dps is None else int(dps)
    while True:
        lo = _mp_sector(point, normal, P, one_sided, prec, side)
        hi = _mp_sector(point, normal, P, one_sided, prec + 20, side)
        diff = abs(hi - lo)
        if (diff <= (tolerance if tolerance else 1e-15) * abs(hi) * 1e-3 or hi == lo
                or float(diff) < tol.MP_VALUE_FLOOR):
            break
        if prec >= tol.MP_MAX_DPS:
            if not error:
                raise NumericalError(
                    f"mpmath did not converge at {tol.MP_MAX_DPS} digits: two evaluations "
                    f"differ by {float(diff):.3g} (value {float(hi):.3g}); ask error=True "
                    f"to get the value with this estimate")
            break
        prec += 40
    value = max(float(hi), 0.0)
    return (value, float(diff) + abs(value) * tol.EPS) if error else value


# ---------------------------------------------------------------------------------------
# scalar paths: horizon clipping and the two exact edge integrals
# ---------------------------------------------------------------------------------------
def _local_clipped(point, normal, polygon, one_sided):
    """Validated polygon in the local frame of ``p``, clipped to z >= 0, and the sign
    that turns its signed image area into a form factor (0: nothing received)."""
    from .scene import validate_polygon
    from .geometry import area_vector

    p = as_point(point)
    n = as_normal(normal)
    if p.shape != (3,) or n.shape != (3,):
        raise ValueError("point and normal must have shape (3,)")
    P = validate_polygon(polygon, 0)
    R = receiver_frame(n)
    Q = (P - p) @ R.T
    # the side of p, from the validated polygon's own (world) plane
    N = area_vector(P)
    N /= np.linalg.norm(N)
    d = float(N @ (P.mean(axis=0) - p))  # < 0: p is in front of the polygon
    dtol = tol.PLANE_SIDE_ULPS * tol.EPS * (np.abs(p).max() + np.abs(P).max())
    if abs(d) <= dtol:
        d = -float(exact_side(P, p))  # decided exactly
    if d == 0 or (one_sided and d > 0):
        return [], 0.0
    # Sutherland-Hodgman against z >= 0; crossings get z = 0 exactly
    out = []
    k = len(Q)
    for i in range(k):
        a, b = Q[i], Q[(i + 1) % k]
        if a[2] > 0:
            out.append(tuple(a))
        if (a[2] > 0) != (b[2] > 0):
            t = a[2] / (a[2] - b[2])
            X = a + t * (b - a)
            out.append((X[0], X[1], 0.0))
    return out, (1.0 if d < 0 else -1.0)


def sector_form_factor(point, normal, polygon, *, one_sided=True,
                       tolerance=tol.DEFAULT_RTOL, error=False):
    """Unoccluded form factor by the sector (Lambert) form, one polygon.

    ``F = (1 / 2 pi) sum_k atan2(|a_k x b_k|, a_k . b_k) (a_k x b_k)_z / |a_k x b_k|``
    over the edges of the horizon-clipped polygon (DESIGN 2.1), in offset form, with a
    rounding-error estimate and automatic escalation to mpmath (DESIGN 2.2).

    Parameters
    ----------
    point : array_like of shape (3,)
    normal : array_like of shape (3,)
    polygon : array_like of shape (K, 3)
    one_sided : bool, default True
    tolerance : float or None, default 1e-12
        Requested relative accuracy (None: plain double precision, no escalation).
    error : bool, default False
        Return ``(value, error_estimate)``.

    Returns
    -------
    float

    Examples
    --------
    >>> sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]
    >>> round(sector_form_factor([0, 0, 0], [0, 0, 1], sq), 12)
    0.239456470461
    """
    F, err = point_polygon_form_factors(point, normal, [polygon], one_sided=one_sided,
                                        tolerance=tolerance, error=True)
    return (float(F[0]), float(err[0])) if error else float(F[0])


def point_polygon_form_factor(point, normal, polygon, *, one_sided=True,
                              tolerance=tol.DEFAULT_RTOL, error=False):
    """Unoccluded form factor from a differential area to one planar polygon.

    ``F(p -> j) = (1 / pi) * integral over j of cos(theta_p) cos(theta_j) / r^2 dA``,
    with the part of the polygon below the tangent plane of ``p`` clipped away.

    Parameters
    ----------
    point : array_like of shape (3,)
        Receiving point ``p``.
    normal : array_like of shape (3,)
        Receiver normal ``n``; normalised if not unit.
    polygon : array_like of shape (K, 3)
        Planar simple polygon, counter-clockwise seen from its front.
    one_sided : bool, default True
        If True (the default), the polygon receives only when its front faces ``p``;
        if False, either side does.
    tolerance : float or None, default 1e-12
        Requested relative accuracy. When the rounding-error estimate of the double
        precision value exceeds ``tolerance * F``, the value is re-evaluated with
        mpmath from the float input. None: plain double precision.
    error : bool, default False
        Return ``(value, error_estimate)`` (in the spirit of mpmath's ``error=True``).

    Returns
    -------
    float
        In [0, 1]. Exactly 0 for a polygon behind ``p``, in its tangent plane, seen
        edge-on, or (one-sided) facing away.

    Raises
    ------
    SceneError
        The polygon is ill-formed (the error names polygon 0).
    ValueError
        ``point`` or ``normal`` is not finite, or the normal is zero.

    Notes
    -----
    Evaluated with the sector form (:func:`sector_form_factor`); :func:`eq3_form_factor`
    gives the same value by the paper's Eq. 3. Conventions:
    ``docs/explanation/conventions.md``.

    Examples
    --------
    Point under the corner of a parallel 1 x 2 rectangle at height 1 (Howell's
    "plane element to parallel rectangle, normal through a corner"):

    >>> rect = [[0, 0, 1], [0, 2, 1], [1, 2, 1], [1, 0, 1]]
    >>> round(point_polygon_form_factor([0, 0, 0], [0, 0, 1], rect), 10)
    0.1673750099
    """
    return sector_form_factor(point, normal, polygon, one_sided=one_sided,
                              tolerance=tolerance, error=error)


# ---------------------------------------------------------------------------------------
# Eq. 3 (corrected) with monotone-span splitting
# ---------------------------------------------------------------------------------------
def eq3_edge_integral(a, b):
    """Integral of ``y dx`` along the image of the great-circle arc ``a -> b``.

    The image of the arc on the base disk lies on the ellipse of Eq. 2,
    ``y(x) = (-A B x +- C sqrt(eta^2 - kappa^2 x^2)) / eta^2`` with ``(A, B, C) = a x b``,
    ``eta^2 = B^2 + C^2`` and ``kappa^2 = A^2 + B^2 + C^2``. The arc is split at its
    x-extremes (``x = +- eta / kappa``) into monotone spans, each integrated on its own
    branch ``s = +-1`` with the corrected Eq. 3,

    ``Area_s(x) = (1 / 2 kappa) [ s C asin(kappa x / eta)
    + s (kappa C x / eta^2) sqrt(eta^2 - kappa^2 x^2) - (kappa A B / eta^2) x^2 ]``.

    ``asin(kappa x / eta)`` and ``sqrt(eta^2 - kappa^2 x^2)`` are evaluated from the
    point's coordinates in the arc's own plane (``kappa x / eta = cos t`` and
    ``sqrt(...) = eta |sin t|``), which keeps them accurate next to the x-extremes.

    Parameters
    ----------
    a, b : array_like of shape (3,)
        End points in the local frame, ``z >= 0``; only their directions matter.

    Returns
    -------
    float
        The signed integral; minus the sum over a closed contour is the signed
        (counter-clockwise positive) area of its image.

    Examples
    --------
    The image of the quarter horizon from x to y is the quarter circle, and the
    integral of ``y dx`` along it (x from 1 to 0) is ``-pi / 4``:

    >>> round(eq3_edge_integral([1, 0, 0], [0, 1, 0]), 12)
    -0.785398163397
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    m = np.cross(a, b)
    kappa = float(np.linalg.norm(m))
    if kappa == 0.0:
        # a and b parallel: a point (or an edge through p, excluded upstream)
        return 0.0
    A, B, C = m / kappa  # normalised so that kappa = 1 below
    eta = math.hypot(B, C)
    if eta == 0.0:
        # B = C = 0: the plane x = 0, a vertical segment on the disk, dx = 0
        return 0.0
    if C == 0.0:
        # C = 0: the plane holds the zenith; the image is the segment y = -A x / B
        xa = a[0] / np.linalg.norm(a)
        xb = b[0] / np.linalg.norm(b)
        return float(-A / B * (xb * xb - xa * xa) / 2.0)
    w, w_perp, ta, theta, extremes = arc_x_extremes(a, b)
    ua = a / np.linalg.norm(a)
    ub = b / np.linalg.norm(b)
    # span ends as (t, x, cos t, |sin t|): the arc's end points, and its x-extremes
    # t = k pi (x = +- eta, cos t = +- 1, sin t = 0) where the arc passes them
    ends = [(ta, float(ua[0]), float(ua @ w), abs(float(ua @ w_perp)))]
    for t in extremes:
        c = 1.0 if round(t / math.pi) % 2 == 0 else -1.0
        ends.append((t, eta * c, c, 0.0))
    ends.append((ta + theta, float(ub[0]), float(ub @ w), abs(float(ub @ w_perp))))

    def area(s, x, cos_t, abs_sin_t):
        # corrected Eq. 3 with kappa = 1: asin(x / eta) = atan2(cos t, |sin t|),
        # sqrt(eta^2 - x^2) = eta |sin t|
        return 0.5 * (s * C * math.atan2(cos_t, abs_sin_t)
                      + s * (C * x / eta) * abs_sin_t
                      - (A * B / eta ** 2) * x * x)

    total = []
    for (t0, *P0), (t1, *P1) in zip(ends[:-1], ends[1:]):
        # branch of this span, from its midpoint: s C sqrt(...) = eta^2 y + A B x
        tm = 0.5 * (t0 + t1)
        um = math.cos(tm) * w + math.sin(tm) * w_perp
        s = 1.0 if C * (eta ** 2 * um[1] + A * B * um[0]) >= 0 else -1.0
        total.append(area(s, *P1) - area(s, *P0))
    return math.fsum(total)


def arc_x_extremes(a, b):
    """Where the image of the great-circle arc ``a -> b`` on the base disk turns in x:
    the ends of its monotone spans (Eq. 3 is integrated span by span).

    The arc is parametrised in its own plane as ``cos t w + sin t w_perp``, with ``w``
    the direction of largest x on the great circle (x = eta) and ``w_perp = m x w``
    (``m`` the unit normal of the arc's plane, ``a x b`` normalised); x is extreme at
    ``t = k pi``.

    Parameters
    ----------
    a, b : array_like of shape (3,)
        End points in the local frame; only their directions matter. The arc's plane
        must not hold the z axis's perpendicular x direction only (``eta > 0``) and
        ``a``, ``b`` must not be parallel.

    Returns
    -------
    (ndarray of shape (3,), ndarray of shape (3,), float, float, list of float)
        ``w``, ``w_perp``, the parameter of ``a``, the arc's length (in (0, pi)) and the
        parameters ``k pi`` strictly inside the arc, increasing.

    Examples
    --------
    The horizon from +y past -x turns in x once, at -x (t = pi); from +y to x it is
    monotone:

    >>> w, w_perp, ta, theta, ts = arc_x_extremes([0, 1, 0], [-1, -0.1, 0])
    >>> w.tolist(), [round(t / np.pi, 6) for t in ts]
    ([1.0, 0.0, 0.0], [1.0])
    >>> arc_x_extremes([0, 1, 0], [1, 0, 0])[4]
    []
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    m = np.cross(a, b)
    kappa = float(np.linalg.norm(m))
    mhat = m / kappa
    eta = math.hypot(mhat[1], mhat[2])
    # orthonormal basis of the arc's plane: w at the x-maximum (x = eta), w_perp = m x w
    w = (np.array([1.0, 0.0, 0.0]) - mhat[0] * mhat) / eta
    w_perp = np.cross(mhat, w)
    ua = a / np.linalg.norm(a)
    ta = math.atan2(float(ua @ w_perp), float(ua @ w))
    theta = math.atan2(kappa, float(a @ b))  # arc length, in (0, pi)
    extremes = [k * math.pi for k in range(-1, 4) if ta < k * math.pi < ta + theta]
    return w, w_perp, ta, theta, extremes


def eq3_form_factor(point, normal, polygon, *, one_sided=True, error=False):
    """Unoccluded form factor by the paper's Eq. 3 (corrected), with span splitting.

    The frame is first rotated about ``n`` (which changes no area) so that no edge
    plane is close to ``x = 0``, where ``eta -> 0`` makes Eq. 3 ill-conditioned.

    Parameters and return value as :func:`point_polygon_form_factor`; ``error=True``
    also returns a rounding-error estimate (``C1 u`` times the sum of the absolute edge
    integrals, over pi).

    Examples
    --------
    >>> sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]
    >>> round(eq3_form_factor([0, 0, 0], [0, 0, 1], sq), 12)
    0.239456470461
    """
    C, sign = _local_clipped(point, normal, polygon, one_sided)
    if not sign or len(C) < 2:
        return (0.0, 0.0) if error else 0.0
    area, mag = eq3_ring_area(np.array(C))
    # a polygon whose front faces p has a clockwise image (seen from above the disk)
    F = -sign * area / math.pi
    if not F >= -tol.ROUNDING_OVERSHOOT * tol.EPS:
        raise NumericalError(f"Eq. 3 gave the form factor {F!r}, below 0 beyond rounding")
    return (max(F, 0.0), _C1 * tol.EPS * mag / math.pi) if error else max(F, 0.0)


def eq3_ring_area(ring):
    """Signed area (counter-clockwise positive) of the image on the base disk of a closed
    chain of great-circle arcs, by Eq. 3 (corrected) with monotone-span splitting.

    The frame is rotated about z (which changes no area) so that no arc's plane is
    close to ``x = 0``, where ``eta -> 0`` makes Eq. 3 ill-conditioned.

    Parameters
    ----------
    ring : ndarray of shape (K, 3)
        Vertices in the local frame of the point (z along its normal), ``z >= 0``;
        consecutive vertices (and the last and first) are joined by great-circle arcs.
        Only directions matter: a polygon clipped to the upper half-space, or
        directions lifted from a gnomonic chart.

    Returns
    -------
    (float, float)
        The signed area and the sum of the absolute edge integrals (the scale of its
        rounding error).

    Examples
    --------
    The quarter of the upper hemisphere over the first quadrant projects onto a
    quarter of the unit disk:

    >>> a, m = eq3_ring_area(np.array([[0, 0, 1.0], [1, 0, 0], [0, 1, 0]]))
    >>> round(a / (math.pi / 4), 12)
    1.0
    """
    Q = np.array(ring, dtype=float)
    M = np.cross(Q, np.roll(Q, -1, axis=0))
    Ml = np.linalg.norm(M, axis=1)
    M = M[Ml > 0] / Ml[Ml > 0, None]
    if len(M) == 0:
        return 0.0, 0.0
    # rotation about z maximising the smallest eta = sqrt(1 - m_x^2) over the edges
    k = 2 * len(Q) + 2
    phis = np.arange(k) * math.pi / k
    mx = np.cos(phis)[:, None] * M[None, :, 0] + np.sin(phis)[:, None] * M[None, :, 1]
    phi = phis[int(np.argmin(np.abs(mx).max(axis=1)))]
    c, s = math.cos(phi), math.sin(phi)
    Rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    z = Q[:, 2].copy()
    Q = Q @ Rz.T
    Q[:, 2] = z
    parts = [eq3_edge_integral(Q[i], Q[(i + 1) % len(Q)]) for i in range(len(Q))]
    # image area (counter-clockwise positive) = - sum of y dx
    return -math.fsum(parts), math.fsum(abs(x) for x in parts)
