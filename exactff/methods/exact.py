"""The exact method: continuous PPBH with BSP ordering and the area-sorting clipper."""

import math

import numpy as np

from .._tolerances import DEFAULT_RTOL, EPS, VALUE_FLOOR
from ..checks import as_point, as_receiver, as_receivers
from ..errors import NumericalError, check_finite
from ..kernel import flat_polygons, mp_solid_angle, offset_error, solid_angle_sums
from ..predicates import engine_sides
from ..scene import as_scene
from ..visibility import (compiled_form_factor_rows, compiled_form_factors,
                          compiled_solid_angles, is_convex_enclosure, visible_form_factors,
                          visible_solid_angles)
from ._base import FormFactorMethod

__all__ = ["Exact", "INTEGRATORS", "ENGINES", "hemisphere_solid_angles",
           "unoccluded_solid_angles", "SPHERE_AXES"]

#: The two hemispheres the sphere is measured in: any frame does; normal +z and -z.
SPHERE_AXES = (np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]))

_FOUR_PI = 4.0 * math.pi

#: How visible pieces can be integrated (both exact; ``docs/explanation/ppbh-method.md``).
INTEGRATORS = ("sector", "eq3")

#: Which visibility engine computes a row: the compiled core (shadow-volume BSP tree,
#: output-sensitive) or the Python engine (gnomonic charts and GEOS), kept as the oracle.
ENGINES = ("compiled", "python")


class Exact(FormFactorMethod):
    """Exact occluded form factors (continuous PPBH: ``docs/explanation/ppbh-method.md``
    and ``docs/explanation/visibility.md``).

    Parameters
    ----------
    tolerance : float or None, default 1e-12
        Requested **relative** accuracy (unlike :func:`exactff.area_form_factors`'
        ``tolerance``, which is absolute; ``docs/explanation/conventions.md``): values
        whose error estimate exceeds it are
        re-evaluated; unoccluded ones in long double or mpmath, visible pieces refined
        (their vertices recomputed from the input, where the clipper's double-precision
        coordinates fall short) and integrated in long double or mpmath (see
        ``docs/explanation/robustness.md``). A value whose bound still exceeds
        ``tolerance`` times the larger of the value and ``VALUE_FLOOR`` (1e-2 of the
        hemisphere: a value near 0 cannot carry relative digits;
        :func:`exactff.errors.misses_tolerance`) after all that raises
        :class:`exactff.NumericalError` naming the polygon (on every path, either
        engine and either integrator), unless the row is asked for with
        ``error=True``, which returns it with its bound. None: no refinement,
        escalation or check.
    floor : float, default VALUE_FLOOR
        Where the compiled engine's quadruple-precision tier stops: a polygon whose
        long double bound is within half ``tolerance`` times ``floor`` keeps it, one
        whose value is above ``floor`` is held to ``tolerance`` times its value. The
        default, ``VALUE_FLOOR``, spends no quadruple precision below the contract's
        floor (what a value under it is asked: the bound of a grazing value of 1e-9 is
        about 1e-18, absolute); 0 holds every value's bound to ``tolerance`` times the
        value as far as that tier reaches (:func:`exactff.testing.ground_truth`), at
        the cost of that tier on slivers and grazing values. Between 0 and
        ``VALUE_FLOOR``; the check (above) is the same whatever the floor. The Python
        engine refines relative to each value whatever the floor.
    shortcuts : bool, default True
        Leave out what a row does not need: the convex-scene shortcut, the tiled
        clipper (fragments hidden by full tiles or decided by exact predicates instead
        of overlays) and the early stop once a chart is covered. Results do not depend
        on it (tested to 1e-15); False is for checking that.
    integrator : {"sector", "eq3"}, default "sector"
        How visible pieces are integrated: Lambert's sector form, or the paper's Eq. 3
        (corrected, with monotone-span splitting) in its stable form, the large
        ``C asin`` terms subtracted analytically (``tools/derive_eq3.py``,
        ``docs/explanation/ppbh-method.md``). Both are exact, run in either engine and
        take the same refinement and precision tiers; they agree within the sum of
        their bounds. The sector form is the default: over a closed contour Eq. 3's
        stable form is its sum plus terms that telescope to zero, whose rounding makes
        Eq. 3's bound the larger (``docs/benchmarks.md``).
    engine : {"compiled", "python"} or None, default None
        ``"compiled"``: the compiled core (:mod:`exactff.visibility.compiled`), whose
        cost follows what a row sees; a row any of whose values misses the tolerance is
        recomputed by the Python engine. ``"python"``: the Python engine
        (:func:`exactff.visibility.visible_form_factors`), unchanged, the oracle the
        compiled core is tested against. None: compiled, with either integrator.

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> round(float(ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=Exact()).sum()), 12)
    1.0
    """

    name = "exact"

    def __init__(self, *, tolerance=DEFAULT_RTOL, shortcuts=True, integrator="sector",
                 engine=None, floor=VALUE_FLOOR):
        if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")
        number = isinstance(floor, (int, float, np.floating, np.integer))
        if isinstance(floor, bool) or not number or not 0 <= floor <= VALUE_FLOOR:
            raise ValueError(f"floor must be a number between 0 and VALUE_FLOOR "
                             f"({VALUE_FLOOR:g}), got {floor!r}")
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        if engine is None:
            engine = "compiled"
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
        self.tolerance = tolerance
        self.shortcuts = bool(shortcuts)
        self.integrator = integrator
        self.engine = engine
        self.floor = float(floor)

    def point_form_factors(self, scene, point, normal, *, two_sided=False, stats=None,
                           error=False):
        """One row; with ``error=True`` also the error bound of every value (see
        :func:`exactff.visibility.visible_form_factors`)."""
        as_scene(scene)
        point, normal = as_receiver(point, normal)
        if self.engine == "compiled":
            return compiled_form_factors(scene, point, normal, two_sided=two_sided,
                                         stats=stats, shortcuts=self.shortcuts,
                                         tolerance=self.tolerance, error=error,
                                         integrator=self.integrator, floor=self.floor)
        return visible_form_factors(scene, point, normal, two_sided=two_sided, stats=stats,
                                    shortcuts=self.shortcuts, tolerance=self.tolerance,
                                    integrator=self.integrator, error=error)

    def point_rows(self, scene, points, normals, *, two_sided=False):
        """Many rows, value for value those of :meth:`point_form_factors`: with the
        compiled engine, the rows a convex enclosure leaves unoccluded are computed
        together (:func:`exactff.visibility.compiled_form_factor_rows`), what a matrix's
        rows of a closed room do; otherwise one by one. Where :meth:`point_form_factors`
        is not this class's own (a subclass's override, or a replacement), every row is
        its call, one by one.

        Parameters
        ----------
        scene : Scene
        points, normals : array_like of shape (R, 3)

        Returns
        -------
        ndarray of shape (R, len(scene))

        Examples
        --------
        >>> import exactff as ef
        >>> box = ef.scenes.subdivided_box(2)
        >>> F = Exact().point_rows(box, box.centroids[:3], box.normals[:3])
        >>> F.shape, bool(np.abs(F.sum(axis=1) - 1).max() < 1e-14)
        ((3, 24), True)
        """
        as_scene(scene)
        P, N, _ = as_receivers(points, normals)
        if self.engine == "compiled" and type(self).point_form_factors is _OWN_ROW:
            return compiled_form_factor_rows(scene, P, N, two_sided=two_sided,
                                             shortcuts=self.shortcuts,
                                             tolerance=self.tolerance, floor=self.floor)
        out = np.zeros((len(P), len(scene)))
        for r in range(len(P)):
            out[r] = self.point_form_factors(scene, P[r], N[r], two_sided=two_sided)
        return out

    def point_sphere_factors(self, scene, point, *, two_sided=True, stats=None,
                             error=False):
        """One row of spherical factors: the visible solid angle of every polygon from
        ``point``, over 4 pi (see :func:`exactff.sphere_form_factors`).

        Unoccluded (a convex enclosure seen from inside, with shortcuts): whole
        polygons (:func:`unoccluded_solid_angles`). Otherwise, with the compiled engine,
        the whole sphere in one row of the compiled core
        (:func:`exactff.visibility.compiled_solid_angles`); with the Python engine, two
        hemispheres about ``SPHERE_AXES`` by :func:`hemisphere_solid_angles`."""
        as_scene(scene)
        p = as_point(point)
        if p.shape != (3,):
            raise ValueError(f"point must have shape (3,), got {p.shape}")
        st = stats if stats is not None else {}
        flat = flat_polygons(scene)
        side, band = engine_sides(flat, p)
        if self.shortcuts and is_convex_enclosure(scene) and np.all(side >= 0):
            st["path"] = "unoccluded"
            W, E = unoccluded_solid_angles(scene, p, side, two_sided=two_sided,
                                           tolerance=self.tolerance)
        elif self.engine == "compiled":
            W, E = compiled_solid_angles(scene, p, two_sided=two_sided, stats=st,
                                         shortcuts=self.shortcuts)
        else:
            st["path"] = "hemispheres"
            W, E = np.zeros(len(scene)), np.zeros(len(scene))
            for axis in SPHERE_AXES:
                w, e = hemisphere_solid_angles(scene, p, axis, two_sided=two_sided,
                                               engine=self.engine, shortcuts=self.shortcuts)
                W += w
                E += e
        # over 4 pi: the division and the constant's rounding (2 u S) move S beyond W's
        # bound, by as much as that bound itself when W came from mpmath (E = u W)
        S = W / _FOUR_PI
        E = E / _FOUR_PI * (1 + 4 * EPS) + 3 * EPS * S
        check_finite(S, E)
        return (S, E) if error else S

    def __repr__(self):
        extra = "" if self.integrator == "sector" else f", integrator={self.integrator!r}"
        if self.engine != "compiled":
            extra += f", engine={self.engine!r}"
        if self.floor != VALUE_FLOOR:
            extra += f", floor={self.floor!r}"
        return f"Exact(tolerance={self.tolerance}, shortcuts={self.shortcuts}{extra})"


#: :meth:`Exact.point_form_factors` as defined here (what :meth:`Exact.point_rows` may
#: share work for)
_OWN_ROW = Exact.point_form_factors


def hemisphere_solid_angles(scene, point, normal, *, two_sided=True, engine="compiled",
                            shortcuts=True, stats=None):
    """Visible solid angles from ``point`` within the hemisphere around ``normal``, with
    occlusion, and their error bounds: half of a spherical row, the place where an
    engine supplies the measure.

    Parameters
    ----------
    scene : Scene
    point : ndarray of shape (3,)
    normal : ndarray of shape (3,)
        The hemisphere's axis (unit).
    two_sided : bool, default True
        Both faces of a polygon receive (every polygon occludes either way).
    engine : {"compiled", "python"}, default "compiled"
        Checked, and served by the Python engine
        (:func:`exactff.visibility.visible_solid_angles`) either way: the compiled
        core measures the whole sphere in one row instead
        (:func:`exactff.visibility.compiled_solid_angles`), which
        :meth:`Exact.point_sphere_factors` uses.
    shortcuts : bool, default True
    stats : dict, optional

    Returns
    -------
    (ndarray of shape (len(scene),), ndarray of shape (len(scene),))
        Solid angles in steradians (their sum at most 2 pi) and error bounds.

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> W, E = hemisphere_solid_angles(box, np.array([0.5, 0.5, 0.5]), SPHERE_AXES[1])
    >>> round(float(W[0] / (2 * np.pi)), 12)       # the floor: a third of the lower half
    0.333333333333
    """
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    return visible_solid_angles(scene, point, normal, two_sided=two_sided, stats=stats,
                                shortcuts=shortcuts)


def unoccluded_solid_angles(scene, point, side, *, two_sided=True, tolerance=DEFAULT_RTOL):
    """Solid angles of every polygon of a scene from ``point`` with nothing in between,
    and their error bounds: the fan over all edges at once
    (:func:`exactff.kernel.solid_angle_sums`, offset form), the offsets' rounding
    (:func:`exactff.kernel.offset_error`), and mpmath
    (:func:`exactff.kernel.mp_solid_angle`) for the values whose bound exceeds
    ``tolerance`` times the value (None: none).

    ``side`` is the point's side of every polygon (:func:`exactff.predicates.engine_sides`):
    0 (seen edge-on) gives 0; a back side (-1) receives only with ``two_sided``.

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> W, E = unoccluded_solid_angles(box, np.full(3, 0.5), np.ones(6))
    >>> np.round(W / (4 * np.pi), 12).tolist()
    [0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667, 0.166666666667]
    """
    flat = flat_polygons(scene)
    p = np.asarray(point, dtype=float)
    m = len(scene)
    A0 = flat.first - p
    W, E = solid_angle_sums(A0, flat.E, flat.nxt, flat.owner, m)
    W = np.abs(W)
    E = E + offset_error(A0, flat.E, flat.nxt, flat.owner, m)
    live = (side > 0) | (two_sided & (side < 0))
    W[~live] = 0.0
    E[~live] = 0.0
    if tolerance is not None:
        for i in np.flatnonzero(live & ~(E <= tolerance * W)):
            P = flat.V[flat.offsets[i]:flat.offsets[i + 1]]
            W[i], E[i] = mp_solid_angle(p, P, tolerance=tolerance)
    if not np.all(W <= 2 * np.pi + E):
        i = int(np.flatnonzero(~(W <= 2 * np.pi + E))[0])
        raise NumericalError(f"polygon {i}: solid angle {W[i]!r} above 2 pi beyond its "
                             f"bound {E[i]:.3g}")
    return W, E
