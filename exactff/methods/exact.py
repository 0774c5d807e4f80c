"""The exact method: continuous PPBH with BSP ordering and the area-sorting clipper."""

import numpy as np

from .._tolerances import DEFAULT_RTOL
from ..checks import as_receiver
from ..scene import as_scene
from ..visibility import compiled_form_factors, visible_form_factors
from ._base import FormFactorMethod

__all__ = ["Exact", "INTEGRATORS", "ENGINES"]

#: How visible pieces can be integrated (both exact; DESIGN 2).
INTEGRATORS = ("sector", "eq3")

#: Which visibility engine computes a row: the compiled core (shadow-volume BSP tree,
#: output-sensitive) or the Python engine (gnomonic charts and GEOS), kept as the oracle.
ENGINES = ("compiled", "python")


class Exact(FormFactorMethod):
    """Exact occluded form factors (continuous PPBH; DESIGN 2 and 3).

    Parameters
    ----------
    tolerance : float or None, default 1e-12
        Requested relative accuracy: values whose error estimate exceeds it are
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
    shortcuts : bool, default True
        Leave out what a row does not need: the convex-scene shortcut, the tiled
        clipper (fragments hidden by full tiles or decided by exact predicates instead
        of overlays) and the early stop once a chart is covered. Results do not depend
        on it (tested to 1e-15); False is for checking that.
    integrator : {"sector", "eq3"}, default "sector"
        How visible pieces are integrated: Lambert's sector form (vectorised over all
        pieces, with error estimates and escalation) or the paper's Eq. 3, corrected,
        with monotone-span splitting (one ring at a time in Python, no escalation).
        Both are exact; the sector form is the default because it is faster (see
        ``docs/benchmarks.md``) and escalates where double precision falls short.
        Eq. 3 is integrated by the Python engine only. With ``"eq3"`` nothing is
        refined or escalated, but the values are still checked against
        ``tolerance``: one whose bound misses it raises
        :class:`exactff.NumericalError` (suggesting ``integrator="sector"``) unless
        ``error=True`` was asked, as it does on most occluded rows at the default
        tolerance; ``tolerance=None`` turns the check off (to compare the
        integrators).
    engine : {"compiled", "python"} or None, default None
        ``"compiled"``: the compiled core (:mod:`exactff.visibility.compiled`), whose
        cost follows what a row sees; a row any of whose values misses the tolerance is
        recomputed by the Python engine. ``"python"``: the Python engine
        (:func:`exactff.visibility.visible_form_factors`), unchanged, the oracle the
        compiled core is tested against. None: compiled, or Python with
        ``integrator="eq3"`` (the compiled core integrates with the sector form).

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> round(float(ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=Exact()).sum()), 12)
    1.0
    """

    name = "exact"

    def __init__(self, *, tolerance=DEFAULT_RTOL, shortcuts=True, integrator="sector",
                 engine=None):
        if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        if engine is None:
            engine = "python" if integrator == "eq3" else "compiled"
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
        if engine == "compiled" and integrator != "sector":
            raise ValueError(f"engine='compiled' integrates with the sector form; "
                             f"integrator={integrator!r} needs engine='python'")
        self.tolerance = tolerance
        self.shortcuts = bool(shortcuts)
        self.integrator = integrator
        self.engine = engine

    def point_form_factors(self, scene, point, normal, *, two_sided=False, stats=None,
                           error=False):
        """One row; with ``error=True`` also the error bound of every value (see
        :func:`exactff.visibility.visible_form_factors`)."""
        as_scene(scene)
        point, normal = as_receiver(point, normal)
        if self.engine == "compiled":
            return compiled_form_factors(scene, point, normal, two_sided=two_sided,
                                         stats=stats, shortcuts=self.shortcuts,
                                         tolerance=self.tolerance, error=error)
        return visible_form_factors(scene, point, normal, two_sided=two_sided, stats=stats,
                                    shortcuts=self.shortcuts, tolerance=self.tolerance,
                                    integrator=self.integrator, error=error)

    def __repr__(self):
        extra = "" if self.integrator == "sector" else f", integrator={self.integrator!r}"
        if self.engine != ("python" if self.integrator == "eq3" else "compiled"):
            extra += f", engine={self.engine!r}"
        return f"Exact(tolerance={self.tolerance}, shortcuts={self.shortcuts}{extra})"
