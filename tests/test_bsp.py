"""BSP set-up for tessellated curved objects: array-based node work, shallow trees from
axis planes where the facets' own planes would make a chain, and the same exact rows."""

import numpy as np
import pytest

import exactff as ef
from exactff import _tolerances as tol
from exactff.testing import assert_form_factors_close
from exactff.visibility import build_bsp


def depth(tree):
    best, stack = 0, [(0, 1)]
    while stack:
        k, d = stack.pop()
        best = max(best, d)
        stack += [(c, d + 1) for c in (tree.front[k], tree.back[k]) if c >= 0]
    return best


def test_convex_tessellation_gives_a_shallow_tree():
    scene = ef.scenes.room_with_sphere(3, 4)     # 1,280 triangles, 96 quads
    tree = build_bsp(scene)
    # the facets' own planes alone make a chain about as deep as the sphere has facets;
    # nodes of up to BSP_AXIS_CANDIDATE_MIN fragments may still chain
    assert depth(tree) < tol.BSP_AXIS_CANDIDATE_MIN + 100 < 1280
    assert sorted(set(tree.source.tolist())) == list(range(len(scene)))


def test_rows_do_not_depend_on_the_tree(monkeypatch):
    scene = ef.scenes.room_with_sphere(2, 3)     # 320 triangles
    rows = [0, 7, 20, 33, 50]
    monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 32)
    shallow = ef.form_factor_matrix(scene, rows=rows)
    d_shallow = depth(build_bsp(scene))
    monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 10**9)
    chain_scene = ef.Scene.from_polygons(scene.polygons)
    chain = ef.form_factor_matrix(chain_scene, rows=rows)
    assert depth(build_bsp(chain_scene)) > 300 > 100 > d_shallow
    assert_form_factors_close(shallow, chain, rtol=0, atol=1e-13)


@pytest.mark.parametrize("level", [1, 3])
def test_room_with_sphere_rows_sum_to_one(level):
    scene = ef.scenes.room_with_sphere(level, 4)
    groups = np.array(scene.groups)
    rows = np.flatnonzero(groups == "room")[::7].tolist() + np.flatnonzero(groups == "sphere")[::37].tolist()
    M = ef.form_factor_matrix(scene, rows=rows)
    assert_form_factors_close(M.sum(axis=1), np.ones(len(rows)), rtol=0, atol=1e-11)
    # the sphere hides part of the room from the room's points
    i = rows[0]
    U = ef.point_polygon_form_factors(scene.centroids[i], scene.normals[i], scene)
    assert np.any(M[0] < U - 1e-4)


def test_split_fragments_keep_their_area():
    scene = ef.scenes.room_with_sphere(3, 2)
    tree = build_bsp(scene)
    assert tree.splits > 0
    area = np.zeros(len(scene))
    np.add.at(area, tree.source, [np.linalg.norm(ef.geometry.area_vector(P)) for P in tree.fragments])
    assert_form_factors_close(area, scene.areas, rtol=1e-12, atol=0)
