"""The exact method: continuous PPBH with BSP ordering and the area-sorting clipper."""

import numpy as np

from .._tolerances import DEFAULT_RTOL
from ..visibility import visible_form_factors
from ._base import FormFactorMethod

__all__ = ["Exact"]


class Exact(FormFactorMethod):
    """Exact occluded form factors (continuous PPBH; DESIGN 2 and 3).

    Parameters
    ----------
    tolerance : float or None, default 1e-12
        Requested relative accuracy: values (and visible pieces) whose rounding-error
        estimate exceeds it are re-evaluated in long double or mpmath. Visible pieces
        start from double-precision clip coordinates, which bounds thin slivers to about
        1e-16 absolute (see ``docs/explanation/robustness.md``).
    shortcuts : bool, default True
        Use the convex-scene shortcut and stop filling charts once they are covered.
        Results do not depend on it (tested); False is for checking that.

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> round(float(ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=Exact()).sum()), 12)
    1.0
    """

    name = "exact"

    def __init__(self, *, tolerance=DEFAULT_RTOL, shortcuts=True):
        if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")
        self.tolerance = tolerance
        self.shortcuts = bool(shortcuts)

    def point_form_factors(self, scene, point, normal, *, two_sided=False, stats=None):
        return visible_form_factors(scene, point, normal, two_sided=two_sided, stats=stats,
                                    shortcuts=self.shortcuts, tolerance=self.tolerance)

    def __repr__(self):
        return f"Exact(tolerance={self.tolerance}, shortcuts={self.shortcuts})"
