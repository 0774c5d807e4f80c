"""Native z-buffers of the discrete methods against the shared sampling core (issue 17).

The shared core (``nearest_polygons``: cell directions sorted into the engine's charts,
a crossing-number test per cell) is the oracle; each native rasteriser must show the
same polygon in every cell, except cells whose direction lies on an edge of one of the two
polygons shown (within rounding): a cell on the silhouette of the nearer one, which
the half-open rule of each rasteriser may put on either side.
"""

import numpy as np
import pytest
from hypothesis import given, settings

import exactff as ef
from exactff.geometry import receiver_frame
from exactff.integrate import as_receiver
from exactff.methods._sampling import nearest_polygons
from exactff.testing import strategies

from common import examples

NATIVE = [
    (ef.Hemicube, 16), (ef.Hemicube, 64), (ef.Hemicube, 130),
    (ef.DiscretePPBH, 17), (ef.DiscretePPBH, 64), (ef.DiscretePPBH, 101),
]

#: a cell on a polygon's edge: its direction within this angle of the edge's plane
ON_EDGE = 1e-12


def _edge_distance(scene, j, p, R, d):
    P = (scene.polygons[j] - p) @ R.T
    m = np.cross(P, np.roll(P, -1, axis=0))
    m /= np.linalg.norm(m, axis=1)[:, None]
    return float(np.min(np.abs(m @ d)))


def assert_native_matches_oracle(method, scene, point, normal):
    p, n = as_receiver(point, normal)
    D = method.layout().directions
    native = method.native_hits(scene, p, n)
    oracle = nearest_polygons(scene, p, n, D)
    R = receiver_frame(n)
    for c in np.flatnonzero(native != oracle):
        # the cell's direction lies on an edge of one of the two (a silhouette)
        near = [_edge_distance(scene, j, p, R, D[c]) for j in (native[c], oracle[c]) if j >= 0]
        assert min(near) <= ON_EDGE, (c, native[c], oracle[c], near)
    return native, oracle


def _rows(scene, k, seed=0):
    rng = np.random.default_rng(seed)
    for i in rng.choice(len(scene), k, replace=False):
        yield scene.centroids[i] + 1e-3 * scene.normals[i], scene.normals[i]


@pytest.mark.parametrize("cls,res", NATIVE, ids=lambda x: getattr(x, "__name__", str(x)))
@pytest.mark.parametrize("scene_name", ["cornell", "office", "box", "building"])
def test_native_cells_equal_the_oracle(cls, res, scene_name):
    scene = {"cornell": ef.scenes.cornell_box, "office": ef.scenes.office,
             "box": lambda: ef.scenes.subdivided_box(3),
             "building": lambda: ef.scenes.building(2, 2)}[scene_name]()
    for p, n in _rows(scene, 3):
        native, oracle = assert_native_matches_oracle(cls(resolution=res), scene, p, n)
        if scene_name != "cornell":       # closed scenes: every cell shows a polygon
            assert np.all(native >= 0)
        # and almost every cell agrees exactly
        assert np.mean(native != oracle) <= 0.02


@given(strategies.enclosures())
@settings(max_examples=examples(25), deadline=None)
def test_native_cells_equal_the_oracle_in_random_rooms(case):
    scene, p, n = case
    for cls, res in ((ef.Hemicube, 32), (ef.DiscretePPBH, 45)):
        native, _ = assert_native_matches_oracle(cls(resolution=res), scene, p, n)
        assert np.all(native >= 0)


@given(strategies.occluded_scenes())
@settings(max_examples=examples(25), deadline=None)
def test_native_cells_equal_the_oracle_in_occluded_scenes(case):
    scene, p, n = case
    for cls, res in ((ef.Hemicube, 32), (ef.DiscretePPBH, 45)):
        assert_native_matches_oracle(cls(resolution=res), scene, p, n)


@pytest.mark.parametrize("cls", [ef.Hemicube, ef.DiscretePPBH])
def test_native_rows_equal_the_oracle_rows(cls):
    # through the public interface: native (default) and native=False rows agree up to
    # the weight of the cells on edges, and sum to the layout's weight in a closed room
    scene = ef.scenes.office()
    for p, n in _rows(scene, 2, seed=3):
        m1, m0 = cls(resolution=64), cls(resolution=64, native=False)
        F1, F0 = m1.point_form_factors(scene, p, n), m0.point_form_factors(scene, p, n)
        w = m1.layout().weights
        assert np.abs(F1 - F0).sum() <= 2 * 0.02 * w.sum()
        assert abs(F1.sum() - w.sum()) <= 1e-12


def test_native_flag_in_repr_and_default():
    assert ef.Hemicube(resolution=8).native and ef.DiscretePPBH(resolution=8).native
    assert "native=False" in repr(ef.Hemicube(resolution=8, native=False))
    assert "native" not in repr(ef.DiscretePPBH(resolution=8))
