"""Area-to-area form factors (the paper's Eq. 1), one concept a module: unoccluded pairs
in closed form (:mod:`~exactff.area.closed_form`, with :mod:`~exactff.area.edge_integrals`,
:mod:`~exactff.area.far_field` and the tanh-sinh :mod:`~exactff.area.contour_rule`);
pairs with occlusion as the closed form less the integral of the hidden part
(:mod:`~exactff.area.culling`, :mod:`~exactff.area.events`, :mod:`~exactff.area.curved`,
:mod:`~exactff.area.hidden`,
:mod:`~exactff.area.adaptive`, on the triangle :mod:`~exactff.area.rules`); a row of them
(:mod:`~exactff.area.row`). The matrix, with occlusion and error estimates, is
:func:`exactff.area_form_factors`.
"""

from .closed_form import polygon_form_factor
from .row import AreaStats, area_row

__all__ = ["polygon_form_factor", "area_row", "AreaStats"]
