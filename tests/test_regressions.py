"""Cases that once failed, pinned with literal floats."""

import numpy as np
import pytest

import exactff as ef
from exactff.visibility import bsp

from common import rect_xy


def test_subnormal_normal_component_in_the_engine():
    # a receiver normal with a subnormal component (5e-324) put subnormal coordinates into
    # the charts, and GEOS returned a wrong overlay (2.6e-5 off); they are flushed to 0
    polys = [rect_xy(0, 1, 0, 1, 1.0), rect_xy(0, 1, -0.5, 0.5, 1.001)]
    n = np.array([0.8660254037844386, 5e-324, 0.5])
    F = ef.form_factors(ef.Scene.from_polygons(polys), np.zeros(3), n)
    ref = ef.form_factors(ef.Scene.from_polygons(polys), np.zeros(3),
                          np.array([0.8660254037844386, 0.0, 0.5]))
    assert np.abs(F - ref).max() < 1e-15


@pytest.mark.parametrize("candidates,seed", [(8, 0), (3, 1), (3, 2), (8, 2), (8, 3)])
def test_cornell_front_wall_row_for_every_bsp_tree(candidates, seed):
    # these trees once ordered two block faces so that GEOS saw edges that should
    # coincide differ by a few ulps, and the overlay lost 1.2e-3 of the row; shared
    # edges are now bit-identical
    scene = ef.scenes.cornell_box(closed=True)
    tree = bsp.build_bsp(scene, candidates=candidates, seed=seed)
    scene._cache["bsp"] = (tree, *ef.geometry.padded(tree.fragments))
    i = scene.names.index("front_wall")
    F = ef.form_factors(scene, scene.centroids[i], scene.normals[i])
    assert abs(F.sum() - 1.0) < 1e-13


def test_point_within_rounding_of_a_far_plane_is_decided_exactly():
    # p 1e-7 below a unit polygon, all coordinates near 1e8 (ulp 1.5e-8): the float side
    # test is inside its rounding band; the exact side says "in front", and the value
    # (about 0.5) comes from the high-precision tier instead of a silent 0
    shift = 1e8
    P = np.array([[-0.5, -0.5, 1e-7], [-0.5, 0.5, 1e-7], [0.5, 0.5, 1e-7], [0.5, -0.5, 1e-7]])
    P = P + shift
    p = np.full(3, shift)
    F = ef.point_polygon_form_factor(p, [0, 0, 1], P, one_sided=False)
    from exactff.testing.mp_reference import boundary_form_factor
    ref = float(boundary_form_factor(p, [0, 0, 1], P, one_sided=False, dps=40))
    assert ref > 0.9 and abs(F - ref) <= 1e-10 * ref


def test_cloister_row_where_geos_returned_a_wrong_difference():
    # GEOS returned a difference that did not remove a fully covered image (no exception,
    # valid output); the union that followed had nested shells. The area-conservation
    # check of the clipper now recomputes such steps with snap-rounding.
    scene = ef.scenes.cloister(4000)
    i = 3894
    F = ef.form_factors(scene, scene.centroids[i], scene.normals[i])
    assert abs(F.sum() - 1) < 1e-13


def test_zbuffer_cell_on_a_shared_edge_is_inside_one_polygon():
    # found by the rigid-motion test of zero-thickness walls: moved by 1e-13, four
    # hemicube cells of a floor row lay on the vertical corner edge of two walls to
    # rounding, and the crossing test (which evaluated the shared edge from opposite
    # end points in the two polygons) put them in neither: the row lost 1.6e-3
    base = ef.scenes.building(2, 1)
    scene = ef.Scene.from_polygons([P + [0.0, 1e-13, 0.0] for P in base.polygons])
    i = base.names.index("room0_0_floor")
    m = ef.Hemicube(resolution=32)
    H = ef.form_factors(scene, scene.centroids[i], scene.normals[i], method=m)
    assert abs(H.sum() - m.layout().weights.sum()) <= 1e-12
