"""The exact kernel: unoccluded form factors from points, by the sector (Lambert) form
and by the paper's Eq. 3 (corrected), with rounding-error estimates and the escalation
ladder (float, long double, mpmath).

* :mod:`~exactff.kernel.sector`: the sector sums, vectorised, and their error model;
* :mod:`~exactff.kernel.flat`: a scene's polygons as flat arrays;
* :mod:`~exactff.kernel.ladder`: long double and mpmath re-evaluation;
* :mod:`~exactff.kernel.point`: one point to one polygon, many polygons, a scene's row;
* :mod:`~exactff.kernel.eq3`: Eq. 3 with monotone-span splitting, as printed (corrected)
  and in its stable form;
* :mod:`~exactff.kernel.solid_angle`: solid angles (Van Oosterom and Strackee), the
  measure of the spherical factors.
"""

from .eq3 import (arc_x_extremes, eq3_edge_integral, eq3_form_factor, eq3_ring_area,
                  eq3_ring_sums, mp_eq3_sum)
from .flat import FlatPolygons, flat_polygons
from .ladder import mp_form_factor
from .point import (engine_sides_rows, point_polygon_form_factor, point_polygon_form_factors,
                    sector_form_factor, unoccluded_row, unoccluded_rows)
from .sector import TWO_PI, TWO_PI_LONG, clipped_sector_sums, sector_values
from .solid_angle import mp_solid_angle, offset_error, polygon_solid_angles, solid_angle_sums

__all__ = ["mp_form_factor", "point_polygon_form_factor", "point_polygon_form_factors",
           "sector_form_factor", "eq3_form_factor", "eq3_ring_area", "eq3_edge_integral",
           "eq3_ring_sums", "mp_eq3_sum", "arc_x_extremes", "unoccluded_row", "unoccluded_rows",
           "engine_sides_rows",
           "clipped_sector_sums", "sector_values",
           "FlatPolygons", "flat_polygons", "TWO_PI", "TWO_PI_LONG", "solid_angle_sums",
           "polygon_solid_angles", "offset_error", "mp_solid_angle"]
