"""Exact visibility: occluded form factors from a point to every polygon of a scene.

The engine (``docs/explanation/visibility.md``): a BSP tree orders the fragments front
to back from the point; the area-sorting clipper keeps the covered region in five
gnomonic charts and cuts each new fragment's image against it; every visible piece is
integrated exactly with the sector form. The compiled core
(:mod:`exactff.visibility.compiled`) keeps the covered region as a shadow-volume BSP
tree instead, and is the default. Shortcuts leave out what a row does not need; each is
reported in ``stats`` and tested to be neutral.
"""

from .compiled import (compiled_core, compiled_form_factor_rows, compiled_form_factors,
                       compiled_solid_angles, convex_pieces, convex_rings)
from .bsp import BSPTree, build_bsp, coplanar_overlaps, front_to_back, scene_bsp
from .coplanar import plane_overlaps
from .engine import (is_convex_enclosure, visible_form_factors, visible_graph,
                     visible_solid_angles)

__all__ = ["visible_form_factors", "visible_solid_angles", "visible_graph", "is_convex_enclosure", "scene_bsp", "build_bsp",
           "front_to_back", "coplanar_overlaps", "plane_overlaps", "BSPTree",
           "compiled_form_factors", "compiled_form_factor_rows", "compiled_core",
           "compiled_solid_angles", "convex_pieces", "convex_rings"]
