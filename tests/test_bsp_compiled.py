"""The BSP tree built in compiled code (``build_bsp(engine="compiled")``, the compiled
core's tree): the Python build's tree where neither draws at random, and a valid
partition (planes holding their fragments, subtrees on their sides, areas kept) where
they do."""

import numpy as np
import pytest
from hypothesis import given

import exactff as ef
from exactff import _tolerances as tol
from exactff.geometry import area_vector
from exactff.predicates import coplanar_band_sides
from exactff.testing import assert_form_factors_close
from exactff.testing.strategies import enclosures
from exactff.visibility import build_bsp

EVERY_CANDIDATE = 10 ** 9


def _same_tree(a, b):
    assert (len(a), len(a.fragments), a.splits) == (len(b), len(b.fragments), b.splits)
    for name in ("front", "back", "source", "whole"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.node_fragments == b.node_fragments
    assert a.node_fragments_behind == b.node_fragments_behind
    np.testing.assert_array_equal(a.normals, b.normals)
    # split vertices and axis planes' medians: the same formulas, up to rounding
    scale = max(np.abs(P).max() for P in a.fragments)
    assert np.abs(a.offsets - b.offsets).max() <= 1e-14 * scale
    for P, Q in zip(a.fragments, b.fragments):
        assert P.shape == Q.shape
        assert np.abs(P - Q).max() <= 1e-14 * scale


def _check_partition(scene, tree):
    """Every node's plane holds its fragments and its subtrees lie on their sides (within
    the near-coplanar band), and the fragments of each polygon tile it."""
    def subtree(k):
        out, stack = [], [k]
        while stack:
            j = stack.pop()
            if j < 0:
                continue
            out += tree.node_fragments[j]
            stack += [int(tree.front[j]), int(tree.back[j])]
        return out

    for k in range(len(tree)):
        n, d = tree.normals[k][None], tree.offsets[k:k + 1]
        for frags, allowed in ((subtree(int(tree.front[k])), (0, 1)),
                               (subtree(int(tree.back[k])), (-1, 0))):
            if frags:
                sign, _ = coplanar_band_sides(np.concatenate([tree.fragments[f] for f in frags]),
                                              n, d)
                assert set(sign.ravel().tolist()) <= set(allowed), k
        # the node's own fragments: in its plane, or pieces of the polygon that gave it
        for f in tree.node_fragments[k]:
            sign, _ = coplanar_band_sides(tree.fragments[f], n, d)
            own = np.allclose(np.abs(scene.normals[tree.source[f]] @ n[0]), 1, atol=1e-12)
            assert own or not sign.any(), (k, f)
    assert sorted(f for here in tree.node_fragments for f in here) == list(range(len(tree.fragments)))
    area = np.zeros(len(scene))
    np.add.at(area, tree.source, [np.linalg.norm(area_vector(P)) for P in tree.fragments])
    assert_form_factors_close(area, scene.areas, rtol=1e-11, atol=0)


@pytest.mark.parametrize("name", ["box", "cornell", "building", "office600", "sphere"])
def test_compiled_build_is_the_python_build_without_random_draws(name, monkeypatch):
    scene = {"box": lambda: ef.scenes.subdivided_box(3),
             "cornell": lambda: ef.scenes.cornell_box(closed=True),
             "building": lambda: ef.scenes.building(2, 2),
             "office600": lambda: ef.scenes.office(600),
             "sphere": lambda: ef.scenes.room_with_sphere(2, 3)}[name]()
    if name == "sphere":
        # nodes of more than 32 fragments also try the axis plane
        monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 32)
    assert len(scene) <= tol.BSP_SCORE_SAMPLE
    a = build_bsp(scene, candidates=EVERY_CANDIDATE)
    b = build_bsp(scene, candidates=EVERY_CANDIDATE, engine="compiled")
    _same_tree(a, b)
    if name in ("office600", "sphere"):
        assert b.splits > 0
    if name == "sphere":
        # and some node takes it: a plane that is no polygon's
        planes = set(zip(map(tuple, scene.normals.tolist()), scene.plane_offsets.tolist()))
        assert any((tuple(n), d) not in planes for n, d in zip(b.normals.tolist(), b.offsets.tolist()))


def test_compiled_build_with_draws_is_a_partition():
    scene = ef.scenes.office()                  # 4,424 polygons: sampled scores at the root
    assert len(scene) > tol.BSP_SCORE_SAMPLE
    tree = build_bsp(scene, engine="compiled")
    assert tree.splits > 0
    _check_partition(scene, tree)
    # deterministic for a seed, and the seed draws
    again = build_bsp(scene, engine="compiled")
    _same_tree(tree, again)
    other = build_bsp(scene, engine="compiled", seed=1)
    assert (len(other), other.splits) != (len(tree), tree.splits)
    _check_partition(scene, other)


def test_compiled_build_of_a_sphere_with_axis_planes_is_a_partition(monkeypatch):
    scene = ef.scenes.room_with_sphere(3, 4)     # 1,280 triangles, 96 quads
    monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 64)
    tree = build_bsp(scene, engine="compiled")
    # the facets' own planes alone chain about as deep as the sphere has facets
    assert tree.depth() < 200
    _check_partition(scene, tree)


@given(case=enclosures())
def test_compiled_build_of_enclosures_is_a_partition(case):
    scene, _, _ = case
    _check_partition(scene, build_bsp(scene, engine="compiled"))
    _same_tree(build_bsp(scene, candidates=EVERY_CANDIDATE),
               build_bsp(scene, candidates=EVERY_CANDIDATE, engine="compiled"))


def test_compiled_build_with_a_subnormal_coordinate_is_a_partition():
    # found by CI: an enclosure (a box 0.1 wide whose floor lies at z = 2.2e-309, a
    # subnormal) holding a cube given twice. The compiled build's expansions are exact
    # only while no product underflows; it put a fragment on the wrong side of a node.
    # Such a scene is now built by the Python build (BSP_COMPILED_MIN_MAGNITUDE)
    z = 2.225073858507203e-309
    box = [[[0, 0, z], [.1, 0, z], [.1, .1, z], [0, .1, z]],
           [[0, 0, .1], [0, .1, .1], [.1, .1, .1], [.1, 0, .1]],
           [[0, 0, z], [0, 0, .1], [.1, 0, .1], [.1, 0, z]],
           [[0, .1, z], [.1, .1, z], [.1, .1, .1], [0, .1, .1]],
           [[0, 0, z], [0, .1, z], [0, .1, .1], [0, 0, .1]],
           [[.1, 0, z], [.1, 0, .1], [.1, .1, .1], [.1, .1, z]]]
    cube = [[[.05, .1, .05], [.1, .1, .05], [.1, .05, .05], [.05, .05, .05]],
            [[.1, .05, .1], [.1, .1, .1], [.05, .1, .1], [.05, .05, .1]],
            [[.1, .05, .05], [.1, .05, .1], [.05, .05, .1], [.05, .05, .05]],
            [[.05, .1, .1], [.1, .1, .1], [.1, .1, .05], [.05, .1, .05]],
            [[.05, .05, .1], [.05, .1, .1], [.05, .1, .05], [.05, .05, .05]],
            [[.1, .1, .05], [.1, .1, .1], [.1, .05, .1], [.1, .05, .05]]]
    scene = ef.Scene.from_polygons([np.array(P, float) for P in box + cube + cube])
    _check_partition(scene, build_bsp(scene, engine="compiled"))
    _same_tree(build_bsp(scene, candidates=EVERY_CANDIDATE),
               build_bsp(scene, candidates=EVERY_CANDIDATE, engine="compiled"))


def test_build_bsp_names_bad_options():
    scene = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match="engine"):
        build_bsp(scene, engine="fortran")
    with pytest.raises(ValueError, match="candidates"):
        build_bsp(scene, candidates=0, engine="compiled")
    with pytest.raises(ValueError, match="seed"):
        build_bsp(scene, seed=-1, engine="compiled")
