"""exactff: exact form factors for scenes of planar polygons (continuous PPBH).

The flat API gathers the public functions of the layers below
(``docs/explanation/layout.md``); see ``docs/reference``.
"""

from . import catalog, scenes
from .errors import NumericalError, SceneError
from .formfactors import area_form_factors, form_factor_matrix, form_factors
from .geometry import (area_vector, polygon_area, polygon_centroid, polygon_diameter,
                       receiver_frame, rotate, to_local, unit_normal)
from .combine import combined_surfaces
from .io import (load_scene, read_idf, read_mesh, read_obj, read_rad, read_scene_json,
                 read_view3d_factors, read_vs3, scene_from_json, script_f, to_dataframe,
                 write_elmer_view_factors, write_energyplus_view_factors,
                 write_openfoam_view_factors, write_view3d_factors, write_vs3,
                 read_view_factors, read_energyplus_view_factors, read_elmer_view_factors,
                 read_openfoam_view_factors)
from .kernel import (arc_x_extremes, eq3_edge_integral, eq3_form_factor, eq3_ring_area,
                     mp_form_factor, point_polygon_form_factor, point_polygon_form_factors,
                     sector_form_factor)
from .area import polygon_form_factor
from .methods import (METHODS, CubicTetrahedron, DiscretePPBH, Exact, FormFactorMethod,
                      Hemicube, MonteCarlo, PolarPlane, SinglePlane)
from .reports import MatrixReport, check_matrix, compare, describe, to_markdown
from .audits import AuditReport, audit
from .rings import padded, padded_buckets
from .scene import (DEGENERATE, NONPLANAR, Scene, split_nonplanar, validate_polygon,
                    validate_polygons)
from .sphere import sphere_form_factors
from .storage import load_matrix
from .version import __version__

__all__ = ["catalog", "scenes", "__version__",
           "SceneError", "NumericalError",
           "Scene", "validate_polygon", "validate_polygons", "split_nonplanar", "NONPLANAR", "DEGENERATE",
           "load_scene", "read_obj", "read_scene_json", "scene_from_json", "read_vs3",
           "read_idf", "read_rad", "read_mesh", "describe", "write_vs3",
           "write_view3d_factors", "read_view3d_factors", "script_f", "combined_surfaces",
           "write_energyplus_view_factors", "write_elmer_view_factors",
           "write_openfoam_view_factors", "to_dataframe", "read_view_factors",
           "read_energyplus_view_factors", "read_elmer_view_factors",
           "read_openfoam_view_factors",
           "area_vector", "polygon_area", "polygon_centroid", "polygon_diameter", "unit_normal",
           "receiver_frame", "rotate", "to_local", "padded", "padded_buckets",
           "point_polygon_form_factor", "point_polygon_form_factors", "sector_form_factor",
           "mp_form_factor", "eq3_form_factor", "eq3_ring_area", "eq3_edge_integral",
           "arc_x_extremes", "polygon_form_factor",
           "form_factors", "form_factor_matrix", "area_form_factors", "load_matrix",
           "sphere_form_factors",
           "METHODS", "FormFactorMethod", "Exact", "DiscretePPBH", "Hemicube",
           "CubicTetrahedron", "SinglePlane", "PolarPlane", "MonteCarlo",
           "compare", "to_markdown", "check_matrix", "MatrixReport", "audit", "AuditReport"]
