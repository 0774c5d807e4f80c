"""check_matrix: the invariants of any matrix (exactff.reports.check_matrix).

The defects are put in by construction (a value moved, a NaN, a negative), so the
expected report is known independently of the code under test.
"""

import json

import numpy as np
import pytest
import scipy.sparse as sp

import exactff as ef

from common import rect_xy


@pytest.fixture(scope="module")
def box():
    return ef.scenes.subdivided_box(2)


@pytest.fixture(scope="module")
def exact(box):
    return ef.form_factor_matrix(box)


def test_exact_closed_box_passes(box, exact):
    r = ef.check_matrix(exact, box)
    assert r.ok and r.judged == "closed scene" and r.rows_missing == []
    assert np.abs(r.deficits).max() <= 1e-12
    assert r.negatives == r.nans == r.above_one == 0
    assert "within its bound" in str(r)


def test_defects_put_in_are_named(box, exact):
    F = np.array(exact)
    F[3, 5] += 0.01                  # row 3 sums to 1.01
    F[7, 2] = np.nan                 # a NaN in row 7
    F[9, 1] = -1e-3                  # a negative in row 9 (its sum off too)
    F[11, 0] = 1.5                   # above 1 in row 11
    r = ef.check_matrix(F, box)
    assert r.rows_missing == [3, 7, 9, 11]
    assert (r.nans, r.negatives, r.above_one) == (1, 1, 1)
    assert abs(r.deficits[3] + 0.01) <= 1e-12
    text = str(r)
    assert "MISSED           4 rows: 3, 7, 9, 11" in text


def test_reciprocity_by_construction():
    """Two parallel rectangles of areas 1 and 2: A_0 F_01 = 0.4, A_1 F_10 = 0.5."""
    a = rect_xy(0, 1, 0, 1, 0.0, facing_down=False)
    b = rect_xy(0, 2, 0, 1, 1.0)
    scene = ef.Scene.from_polygons([a, b])
    F = np.array([[0.0, 0.4], [0.25, 0.0]])
    r = ef.check_matrix(F, scene, area=True)
    assert abs(r.reciprocity - 0.1) <= 1e-15 and r.reciprocity_pair in ((0, 1), (1, 0))
    assert r.pairs_missing == [(0, 1)] and r.judged is None   # open: sums not judged
    assert "pairs (reciprocity): (0, 1)" in str(r)
    # point rows are not reciprocal: the defect is reported, not judged
    r = ef.check_matrix(F, scene)
    assert r.pairs_missing == [] and r.ok and "not judged" in str(r)
    # within the estimates: A_0 E_01 + A_1 E_10 = 0.06 + 0.04 >= 0.1
    E = np.array([[0.0, 0.06], [0.02, 0.0]])
    assert ef.check_matrix(F, scene, E, area=True).pairs_missing == []
    assert ef.check_matrix(F, scene, E * 0.9, area=True).pairs_missing == [(0, 1)]


def test_area_matrix_with_bounds():
    box = ef.scenes.subdivided_box(1)
    F, E = ef.area_form_factors(box, tolerance=1e-9, error=True)
    r = ef.check_matrix(F, box, E, area=True)
    assert r.ok, str(r)
    assert r.max_error == E.max() and r.reciprocity <= 1e-12
    G = F.copy()
    G[1, 2] += 1e-6                  # breaks reciprocity of (1, 2) and row 1's sum
    r = ef.check_matrix(G, box, E, area=True)
    assert r.pairs_missing == [(1, 2)] and r.rows_missing == [1]


def test_rows_are_named_by_their_polygon(box, exact):
    F = np.array(exact[[3, 8, 20]])
    F[1, 0] += 0.1                      # the row of polygon 8
    r = ef.check_matrix(F, box, rows=[3, 8, 20])
    assert r.rows_missing == [8] and "(row 8)" in str(r) and r.reciprocity is None


def test_sparse_and_memmap_give_the_same_report(box, exact, tmp_path):
    F = np.array(exact)
    F[4, 4] = 0.3
    dense = ef.check_matrix(F, box).to_dict()
    assert ef.check_matrix(sp.csr_array(F), box).to_dict() == dict(dense, sparse=True)
    np.save(tmp_path / "m.npy", F)
    mm = np.load(tmp_path / "m.npy", mmap_mode="r")
    assert ef.check_matrix(mm, box).to_dict() == dense
    json.dumps(dense)                # plain values


def test_remainder_makes_open_rows_sum_to_one(box):
    open_box = ef.Scene.from_polygons(box.polygons[:4] + box.polygons[8:])
    M, R = ef.form_factor_matrix(open_box, remainder=True)
    assert ef.check_matrix(M, open_box).judged is None          # open: not judged
    r = ef.check_matrix(M, open_box, remainder=R)
    assert r.judged == "remainder" and r.ok
    # the remainder itself: the closed box's values of the missing top face (z = 1, above
    # every row's point: all sky)
    kept = list(range(4)) + list(range(8, len(box)))
    full = ef.form_factors(box, box.centroids[kept], box.normals[kept])
    assert np.abs(R[:, 0] - full[:, 4:8].sum(axis=1)).max() <= 1e-12
    assert np.all(R[:, 1] == 0)
    bad = R.copy()
    bad[2, 0] += 1e-6
    assert ef.check_matrix(M, open_box, remainder=bad).rows_missing == [2]


def test_obstructed_not_above_unobstructed():
    """A plate between two squares hides part of the top one from the bottom's centre."""
    a = rect_xy(0, 1, 0, 1, 0.0, facing_down=False)
    top = rect_xy(0, 1, 0, 1, 2.0)
    plate = rect_xy(0.25, 0.75, 0.25, 0.75, 1.0)
    scene = ef.Scene.from_polygons([a, top, plate])
    M = ef.form_factor_matrix(scene)
    r = ef.check_matrix(M, scene, unobstructed="points")
    assert r.excess_missing == [] and r.obstructed_excess <= 1e-15
    U = np.array([ef.point_polygon_form_factors(scene.centroids[i], scene.normals[i], scene)
                  for i in range(3)])
    assert U[0, 1] - M[0, 1] > 0.01              # the plate hides something
    G = np.array(M)
    G[0, 1] = U[0, 1] + 1e-6
    r = ef.check_matrix(G, scene, unobstructed=U)
    assert r.excess_missing == [(0, 1)] and abs(r.obstructed_excess - 1e-6) <= 1e-15
    assert "above their unobstructed value: (0, 1)" in str(r)


def test_bad_input(box, exact):
    with pytest.raises(ValueError, match="columns"):
        ef.check_matrix(np.zeros((2, 3)), box)
    with pytest.raises(ValueError, match="E must"):
        ef.check_matrix(exact, box, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="remainder"):
        ef.check_matrix(exact, box, remainder=np.zeros(3))
    with pytest.raises(ValueError, match="unobstructed"):
        ef.check_matrix(exact, box, unobstructed="area")
    with pytest.raises(ValueError, match="rows"):
        ef.check_matrix(exact, box, rows=[0, 1])
