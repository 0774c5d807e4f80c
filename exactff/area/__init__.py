"""Area-to-area form factors (the paper's Eq. 1): unoccluded pairs by the contour
integral (:mod:`~exactff.area.contour`), pairs with occlusion by the contour integral
less the hidden part (:mod:`~exactff.area.occluded`). The matrix of them, with
occlusion and error estimates, is :func:`exactff.area_form_factors`.
"""

from .contour import polygon_form_factor
from .occluded import area_row

__all__ = ["polygon_form_factor", "area_row"]
