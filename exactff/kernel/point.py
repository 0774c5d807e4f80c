"""Unoccluded form factors from points: one polygon, many polygons, a scene's row.

Every function works in the local frame of the receiving point ``p`` (origin at ``p``,
z along the unit normal ``n``); a polygon is first clipped to the upper half-space
(horizon clipping) and then integrated by the sector form (:mod:`exactff.kernel.sector`)
with a rounding-error estimate per polygon, climbing the escalation ladder
(:mod:`exactff.kernel.ladder`) where the estimate misses the requested tolerance. See
``docs/explanation/conventions.md`` for the orientation conventions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import _tolerances as tol
from ..checks import as_normal, as_point, check_sides, check_tolerance
from ..errors import check_finite, misses_tolerance, tolerance_missed
from ..geometry import area_vector, receiver_frame
from ..halfspace import clip_above_horizon
from ..predicates import exact_side, plane_sides, polygon_side
from ..scene import Scene, validate_polygon
from .flat import flat_polygons
from .ladder import extended_values, mp_form_factor
from ._sector import engine_sides as _engine_sides
from ._sector import row_sums
from .sector import sector_values

__all__ = ["unoccluded_row", "unoccluded_rows", "engine_sides_rows", "point_polygon_form_factors", "sector_form_factor",
           "point_polygon_form_factor", "local_clipped"]


def unoccluded_row(flat, p, n, *, two_sided=False, tolerance=None,
                   return_error=False, in_band="exact", strict=None, sides=None):
    """Unoccluded form factors from ``p`` (normal ``n``) to every polygon of ``flat``.

    The hot path: culls polygons seen edge-on, facing away (unless ``two_sided``) or wholly below
    the horizon, then evaluates the sector form over all remaining edges in one compiled
    pass (``exactff/_core/sector_sums.h``, the arithmetic of
    :func:`~exactff.kernel.sector.clipped_sector_sums` with rounded offsets), in offset
    form, with a rounding-error estimate per polygon. With a ``tolerance``, every
    value whose estimate exceeds ``tolerance * F`` is re-evaluated (long double, then
    mpmath) from the
    original float input (:func:`mp_form_factor`). Returns (N,) values, and their error estimates if
    ``return_error``.

    ``in_band`` says what happens to polygons whose plane passes within rounding of
    ``p``: ``"exact"`` decides the side exactly and evaluates them with mpmath (their
    double value is unreliable); ``"edge_on"`` counts them as seen edge-on (0).
    ``sides``: the pair ``(side, band)`` already decided by the caller (as
    :func:`exactff.predicates.plane_sides` returns it; the visibility engine's
    :func:`exactff.predicates.engine_sides`), instead of ``in_band``; band polygons
    with a non-zero side are evaluated with mpmath.

    ``strict`` (default: not ``return_error``): raise :class:`NumericalError` when a
    value misses the tolerance even in the last tier, instead of returning it with its
    estimate.
    """
    if strict is None:
        strict = not return_error
    p = np.asarray(p, dtype=float)
    if sides is not None:
        side, band = (np.array(a) for a in sides)
    else:
        side, band = plane_sides(flat, p, exact=(in_band == "exact"))
        if in_band == "edge_on":
            band[:] = False
    F, err = unoccluded_rows(flat, p[None], np.asarray(n, dtype=float)[None], side[None],
                             band[None], two_sided=two_sided, tolerance=tolerance,
                             strict=strict)
    return (F[0], err[0]) if return_error else F[0]


def unoccluded_rows(flat, P, N, side, band, *, two_sided=False, tolerance=None, strict=True):
    """Unoccluded form factors from many points at once, and their error estimates: the
    rows of :func:`unoccluded_row`, value for value, with the compiled sums of all the
    rows in one call per tier (what a convex enclosure's matrix does row after row).

    Parameters
    ----------
    flat : FlatPolygons
    P, N : ndarray of shape (R, 3)
        The points and their normals (normalised here).
    side : ndarray of shape (R, len(flat.normals)), int
        The side of each point for each polygon (+1 front, -1 back, 0 edge-on), as
        :func:`exactff.predicates.plane_sides` or
        :func:`exactff.predicates.engine_sides` decide it.
    band : ndarray of shape (R, len(flat.normals)), bool
        Where the polygon's plane passes within rounding of the point (a non-zero side
        there was decided exactly, and only mpmath can give the value).
    two_sided : bool, default False
        Whether a polygon's back receives too (default: only its front).
    tolerance : float or None
        As for :func:`unoccluded_row`.
    strict : bool, default True
        Raise :class:`NumericalError` where a value misses the tolerance even in the
        last tier (else return it with its estimate).

    Returns
    -------
    (ndarray of shape (R, len(flat.normals)), ndarray of the same shape)

    Examples
    --------
    From the centres of the floor and of a wall of a closed box, each row sums to 1:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> flat = flat_polygons(box)
    >>> P, N = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5]]), np.eye(3)[[2, 0]]
    >>> side, band = engine_sides_rows(flat, P)
    >>> F, E = unoccluded_rows(flat, P, N, side, band, tolerance=1e-12)
    >>> bool(np.abs(F.sum(axis=1) - 1).max() < 1e-14), bool(E.max() < 1e-14)
    (True, True)
    """
    F = np.zeros(side.shape)
    err = np.zeros(side.shape)
    # the pairs by their positions in the (R, N) arrays (flat indices: one gather or
    # scatter each, not a pair of index arrays)
    Ff, ef_, side_f, band_f = F.reshape(-1), err.reshape(-1), side.reshape(-1), band.reshape(-1)
    at = np.flatnonzero(side_f != 0) if two_sided else np.flatnonzero(side_f > 0)
    if not len(at):
        return F, err
    rows, ids = np.divmod(at, side.shape[1])
    # the sector sums of every live pair in one compiled pass (exactff/_core/sector_sums.h:
    # clipped_sector_sums with rounded offsets, the same arithmetic); polygons wholly
    # below a row's horizon have nothing to integrate
    frames = receiver_frame(N)
    S, mags, errs, above = row_sums(flat.V, flat.offsets, ids, rows, P, frames, tol.EPS,
                                    tol.OFFSET_ROUNDING_ULPS, tol.C2 * tol.EPS)
    if not above.all():
        at, rows, ids, S, mags, errs = (a[above] for a in (at, rows, ids, S, mags, errs))
    if not len(ids):
        return F, err
    in_band = band_f[at]
    d0 = -side_f[at].astype(float)
    Fv, Ev = sector_values(S, mags, errs, d0, two_sided, unchecked=in_band)
    # p within rounding of the polygon's plane (its side decided exactly): the double
    # value can be anything; only the high-precision tier can give it
    Ev[in_band] = np.inf
    missing = np.zeros(0, dtype=np.int64)   # pairs (positions in at) left to mpmath
    if tolerance is not None:
        missing = np.flatnonzero(Ev > tolerance * Fv)
        ext = missing[~in_band[missing]]
        if len(ext) and tol.LONGDOUBLE_EPS < tol.EPS / 100:
            # second tier: the same sums in extended precision (x87 80-bit long double
            # where the platform has it), from the original float input
            Fl, el = extended_values(flat, ids[ext], rows[ext], P, N, d0[ext], two_sided)
            good = el <= tolerance * Fl
            Fv[ext[good]], Ev[ext[good]] = Fl[good], el[good]
            missing = np.setdiff1d(missing, ext[good], assume_unique=True)
    Ff[at], ef_[at] = Fv, Ev
    if tolerance is not None:
        fr, fi = rows[missing], ids[missing]
        # last tier (docs/explanation/robustness.md): mpmath at the digits the value needs
        for r, i in zip(fr.tolist(), fi.tolist()):
            Q = flat.V[flat.offsets[i]:flat.offsets[i + 1]]
            F[r, i], err[r, i] = mp_form_factor(P[r], N[r], Q, two_sided=two_sided,
                                                tolerance=tolerance, error=True,
                                                side=int(side[r, i]))
        # the last tier's values are checked too: one that still misses the tolerance
        # (mpmath stopped at its precision limit) is returned with its estimate when the
        # caller asks for estimates, and raises otherwise
        missed = np.flatnonzero(misses_tolerance(F[fr, fi], err[fr, fi], tolerance))
        if len(missed) and strict:
            r, i = int(fr[missed[0]]), int(fi[missed[0]])
            where = f"polygon {i}" if len(P) == 1 else f"row {r}, polygon {i}"
            raise tolerance_missed(where, F[r, i], err[r, i], tolerance,
                                   f"even in {tol.MP_MAX_DPS}-digit arithmetic")
    # (a NaN is not "missed" above: it is refused here, on every tier's way out)
    check_finite(F, err)
    return F, err


def engine_sides_rows(flat, P):
    """The sides of many points for every polygon, each row what
    :func:`exactff.predicates.engine_sides` gives for its point alone (the same
    arithmetic, compiled: ``exactff/_core/sides.h``; the exact tests in the band, where
    the point is not in the plane to a rounding, here as there): what a matrix's rows of
    a convex enclosure need at once.

    Parameters
    ----------
    flat : FlatPolygons
    P : ndarray of shape (R, 3)

    Returns
    -------
    (ndarray of int8, ndarray of bool), each of shape (R, len(flat.normals))

    Examples
    --------
    The centres of a closed box's floor and ceiling: in front of every face but the
    one they lie on (seen edge-on, in the band):

    >>> import exactff as ef
    >>> flat = flat_polygons(ef.scenes.subdivided_box(1))
    >>> side, band = engine_sides_rows(flat, np.array([[0.5, 0.5, 0.0], [0.5, 0.5, 1.0]]))
    >>> side.tolist(), band.sum(axis=1).tolist()
    ([[0, 1, 1, 1, 1, 1], [1, 0, 1, 1, 1, 1]], [1, 1])
    """
    P = np.ascontiguousarray(P, dtype=float).reshape(-1, 3)
    side, band, undecided = _engine_sides(flat.normals, flat.centroids, flat.vmax, P, tol.EPS,
                                          tol.ON_PLANE_ULPS, tol.PLANE_SIDE_ULPS)
    for r, i in zip(*(a.tolist() for a in np.nonzero(undecided))):
        side[r, i] = exact_side(flat.V[flat.offsets[i]:flat.offsets[i + 1]], P[r])
    return side, band


def point_polygon_form_factors(point: ArrayLike, normal: ArrayLike, polygons, *,
                               two_sided: bool = False, one_sided: bool | None = None,
                               tolerance: float | None = tol.DEFAULT_RTOL,
                               error: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Unoccluded form factors from one point to many polygons (vectorised).

    Parameters
    ----------
    point : array_like of shape (3,)
        Receiving point ``p``.
    normal : array_like of shape (3,)
        Receiver normal ``n`` (normalised if not unit).
    polygons : Scene or sequence of array_like of shape (K_i, 3)
        The polygons; a sequence is validated as by :meth:`exactff.Scene.from_polygons`.
    two_sided : bool, default False
        If True, a polygon receives on either side; else only when its front faces
        ``p``. (``one_sided=`` is its deprecated old name.)
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

    Raises
    ------
    NumericalError
        As :func:`point_polygon_form_factor`: a value missed the tolerance (unless
        ``error=True``), fell below 0 beyond its estimate, or came out NaN or infinite.

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
    two_sided = check_sides(two_sided, one_sided)
    p = as_point(point)
    as_normal(normal)
    n = np.asarray(normal, dtype=float)
    if p.shape != (3,) or n.shape != (3,):
        raise ValueError("point and normal must have shape (3,)")
    check_tolerance(tolerance)
    scene = polygons if isinstance(polygons, Scene) else Scene.from_polygons(polygons)
    F, err = unoccluded_row(flat_polygons(scene), p, n, two_sided=two_sided,
                            tolerance=tolerance, return_error=True, strict=not error)
    return (F, err) if error else F


def local_clipped(point, normal, polygon, two_sided):
    """Validated polygon in the local frame of ``p``, clipped to z >= 0, and the sign
    that turns its signed image area into a form factor (0: nothing received).

    Examples
    --------
    >>> ring, sign = local_clipped([0, 0, 0], [0, 0, 1], [[0, 0, 1], [0, 1, 1], [1, 0, 1]], False)
    >>> len(ring), sign
    (3, 1.0)
    """
    p = as_point(point)
    n = as_normal(normal)
    if p.shape != (3,) or n.shape != (3,):
        raise ValueError("point and normal must have shape (3,)")
    P = validate_polygon(polygon, 0)
    R = receiver_frame(n)
    Q = (P - p) @ R.T
    # the side of p, from the validated polygon's own (world) plane
    N = area_vector(P)
    side = polygon_side(P, p, N / np.linalg.norm(N))
    if side == 0 or (not two_sided and side < 0):
        return [], 0.0
    return clip_above_horizon(Q), (1.0 if side > 0 else -1.0)


def sector_form_factor(point: ArrayLike, normal: ArrayLike, polygon: ArrayLike, *,
                       two_sided: bool = False, one_sided: bool | None = None, tolerance: float | None = tol.DEFAULT_RTOL,
                       error: bool = False) -> float | tuple[float, float]:
    """Unoccluded form factor by the sector (Lambert) form, one polygon.

    ``F = (1 / 2 pi) sum_k atan2(|a_k x b_k|, a_k . b_k) (a_k x b_k)_z / |a_k x b_k|``
    over the edges of the horizon-clipped polygon (``docs/explanation/ppbh-method.md``,
    "The sector form"), in offset form, with a rounding-error estimate and automatic
    escalation to mpmath (``docs/explanation/robustness.md``).

    Parameters
    ----------
    point : array_like of shape (3,)
    normal : array_like of shape (3,)
    polygon : array_like of shape (K, 3)
    two_sided : bool, default False
        As for :func:`exactff.point_polygon_form_factor` (``one_sided=``: deprecated).
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
    two_sided = check_sides(two_sided, one_sided)
    F, err = point_polygon_form_factors(point, normal, [polygon], two_sided=two_sided,
                                        tolerance=tolerance, error=True)
    return (float(F[0]), float(err[0])) if error else float(F[0])


def point_polygon_form_factor(point: ArrayLike, normal: ArrayLike, polygon: ArrayLike, *,
                              two_sided: bool = False, one_sided: bool | None = None,
                              tolerance: float | None = tol.DEFAULT_RTOL,
                              error: bool = False) -> float | tuple[float, float]:
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
    two_sided : bool, default False
        If False (the default), the polygon receives only when its front faces ``p``;
        if True, either side does. (``one_sided=`` is its deprecated old name.)
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
    NumericalError
        The value missed ``tolerance`` even in the last precision tier (unless
        ``error=True``), fell below 0 beyond its estimate, or came out NaN or infinite.

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
    two_sided = check_sides(two_sided, one_sided)
    return sector_form_factor(point, normal, polygon, two_sided=two_sided,
                              tolerance=tolerance, error=error)
