"""Spherical point factors: the visible solid angle of every polygon from a point, over
4 pi, with occlusion (what mean radiant temperature and radiant asymmetry use)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .checks import as_point, check_tolerance
from .methods import FormFactorMethod, resolve
from .scene import Scene, as_scene

__all__ = ["sphere_form_factors", "SPHERE_METHODS"]

#: The methods with a sphere mode (``point_sphere_factors``).
SPHERE_METHODS = ("exact", "monte_carlo")


def sphere_form_factors(scene: Scene, points: ArrayLike, *,
                        method: str | FormFactorMethod = "exact", two_sided: bool = True,
                        error: bool = False, tolerance: float | None = None,
                        **options) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Spherical factors from points: the visible solid angle of each polygon, over 4 pi.

    ``S[..., j] = Omega_j / (4 pi)``, with ``Omega_j`` the solid angle of the part of
    polygon ``j`` seen from the point, every other polygon occluding. Inside a closed
    scene a row sums to 1. This is the factor of a small sphere (a globe
    thermometer, a sensor, a person taken as a point) where the plane factor of
    :func:`form_factors` is that of a small flat receiver.

    Parameters
    ----------
    scene : Scene
    points : array_like of shape (3,) or (P, 3)
        Viewpoints (any leading shape: ``(..., 3)``).
    method : str or FormFactorMethod, default "exact"
        ``"exact"``, or ``"monte_carlo"`` (uniform directions over the sphere, seeded
        per point, each ray carrying ``1 / samples``), or a configured instance of
        either.
    two_sided : bool, default True
        Both faces of a polygon receive (on a sphere every polygon is seen from some
        side). False: only polygons whose front faces the point receive. Every polygon
        occludes, whichever way it faces.
    error : bool, default False
        Also return ``E`` per value: for the exact method a bound on
        ``|S - exact|`` (the rounding of the solid-angle fans plus the error of the
        visible pieces' vertices, given the clipper's topology); for Monte Carlo the
        standard error ``sqrt(S (1 - S) / samples)``.
    tolerance : float, optional
        The exact method's relative accuracy (default: :class:`Exact`'s, 1e-12):
        unoccluded values whose bound exceeds it are evaluated again in mpmath.
        Occluded values are not refined; their bounds say what the engine's vertices
        allow (the compiled core's long double, about 1e-17 a value on the office; the
        Python engine's clipper, about 1e-14 of the chart's unit per vertex).
    **options
        Passed to the method's constructor when ``method`` is a name
        (``samples=``, ``seed=`` for Monte Carlo; ``engine=``, ``shortcuts=`` for
        the exact method).

    Returns
    -------
    ndarray of shape (..., len(scene)), or a pair of them with ``error=True``
        ``(N,)`` for one point of shape (3,), ``(P, N)`` for P points.

    Raises
    ------
    ValueError
        Bad points, method, tolerance, or a method without a sphere mode.

    Notes
    -----
    The exact method measures the whole sphere in one row of the compiled core
    (:func:`exactff.visibility.compiled_solid_angles`: the BSP order and the shadow tree
    of :func:`form_factors`, free on both sides of its root plane), or, with
    ``engine="python"``, as two hemispheres (about +z and -z) through the Python
    engine's clipper (five gnomonic charts per hemisphere); either way each visible
    piece is measured by its solid angle, Van Oosterom and Strackee's triangle formula
    over a fan (:mod:`exactff.kernel.solid_angle`). In a convex room seen from inside
    nothing is hidden, and whole polygons are measured.
    A polygon whose plane holds the point (seen edge-on) gets 0. Conventions:
    ``docs/explanation/conventions.md``; mean radiant temperature from these factors:
    ``docs/how-to/mean-radiant-temperature.md``.

    References
    ----------
    A. van Oosterom and J. Strackee, "The solid angle of a plane triangle", IEEE Trans.
    Biomed. Eng. BME-30 (2), 125-126, 1983, doi:10.1109/TBME.1983.325207.

    Examples
    --------
    From the centre of a closed unit box every face takes a sixth of the sphere:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> S = ef.sphere_form_factors(box, [0.5, 0.5, 0.5])
    >>> np.round(S, 12).tolist(), round(float(S.sum()), 12)
    ([0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667], 1.0)

    Off centre, with a bound per value, and two points at once:

    >>> S, E = ef.sphere_form_factors(box, [[0.5, 0.5, 0.25], [0.2, 0.3, 0.4]], error=True)
    >>> S.shape, np.round(S.sum(axis=1), 12).tolist(), bool(E.max() < 1e-13)
    ((2, 6), [1.0, 1.0], True)
    """
    scene = as_scene(scene)
    if not isinstance(two_sided, (bool, np.bool_)):
        raise ValueError(f"two_sided must be True or False, got {two_sided!r}")
    check_tolerance(tolerance)
    m = _sphere_method(method, tolerance, options)
    P = as_point(points, "points")
    shape = P.shape[:-1]
    P = P.reshape(-1, 3)
    out = np.empty((len(P), len(scene)))
    err = np.empty_like(out)
    for i in range(len(P)):
        out[i], err[i] = m.point_sphere_factors(scene, P[i], two_sided=bool(two_sided),
                                                error=True)
    out = out.reshape(shape + (len(scene),))
    return (out, err.reshape(out.shape)) if error else out


def _sphere_method(method, tolerance, options):
    """The configured method of a spherical row, or ValueError naming the argument."""
    if tolerance is not None:
        if not (isinstance(method, str) and method == "exact"):
            raise ValueError(f"tolerance= configures method='exact' by name; got "
                             f"method={method!r} (configure an instance instead)")
        options = dict(options, tolerance=tolerance)
    m = resolve(method, **options)
    if m.name not in SPHERE_METHODS:
        raise ValueError(f"method must be one of {SPHERE_METHODS} (the methods with a "
                         f"sphere mode) or an instance of one, got {method!r}")
    return m
