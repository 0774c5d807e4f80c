"""The exact method: continuous PPBH with BSP ordering and the area-sorting clipper."""

from ..visibility import visible_form_factors
from ._base import FormFactorMethod

__all__ = ["Exact"]


class Exact(FormFactorMethod):
    """Exact occluded form factors (continuous PPBH; DESIGN 2 and 3).

    Parameters
    ----------
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

    def __init__(self, *, shortcuts=True):
        self.shortcuts = bool(shortcuts)

    def point_form_factors(self, scene, point, normal, *, two_sided=False, stats=None):
        return visible_form_factors(scene, point, normal, two_sided=two_sided, stats=stats,
                                    shortcuts=self.shortcuts)

    def __repr__(self):
        return f"Exact(shortcuts={self.shortcuts})"
