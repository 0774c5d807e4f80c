"""The procedural office: the spec's validation (planarity, orientation, closure, rows)."""

import numpy as np
import pytest

import exactff as ef


@pytest.fixture(scope="module")
def office():
    return ef.scenes.office(1000)


def test_office_size_and_groups(office):
    assert abs(len(office) - 1000) <= 10
    assert set(office.groups) == {"floor", "ceiling", "wall", "door", "window", "light",
                                  "desk", "partition", "shelf"}
    light = np.array(office.groups) == "light"
    assert office.areas[light].sum() == pytest.approx(1.2 * 0.6, rel=1e-12)
    assert np.allclose(office.normals[light], [0, -1, 0], rtol=0, atol=1e-15)
    door = np.array(office.groups) == "door"
    assert office.areas[door].sum() == pytest.approx(0.9 * 2.1, rel=1e-12)


def test_office_orientation(office):
    # the centroid moved a little along the normal is inside the room, outside every solid
    h = 1e-6
    x = office.centroids + h * office.normals
    assert np.all((x > 0) & (x < [8.0, 2.8, 6.0]))
    for lo, hi, _ in ef.scenes.office_solids():
        inside = np.all((x > lo) & (x < hi), axis=1)
        assert not inside.any()


def test_office_closure_and_planarity(office):
    d = ef.describe(office)
    assert d["closure_residual"] <= 1e-12
    assert d["max_planarity_deviation"] == 0.0


def test_office_rows_sum_to_one(office):
    rows = np.random.default_rng(0).choice(len(office), 20, replace=False)
    M = ef.form_factor_matrix(office, rows=rows)
    assert np.all(M >= 0)
    assert np.abs(M.sum(axis=1) - 1).max() <= 1e-11


def test_office_bad_n():
    with pytest.raises(ValueError, match="n must be"):
        ef.scenes.office(10)


@pytest.fixture(scope="module")
def cloister():
    return ef.scenes.cloister(4000)


def test_cloister_size_groups_and_light(cloister):
    assert abs(len(cloister) - 4000) <= 400
    assert cloister.groups.count("light") == 1
    light = cloister.groups.index("light")
    assert cloister.areas[light] == pytest.approx(400.0, rel=1e-15)
    assert np.allclose(cloister.normals[light], [0, -1, 0], rtol=0, atol=1e-15)
    assert {"garth", "walk_floor", "walk_ceiling", "outer_wall", "arcade", "pier"} <= \
        set(cloister.groups)


def test_cloister_closure_and_planarity(cloister):
    d = ef.describe(cloister)
    assert d["closure_residual"] <= 1e-12
    assert d["max_planarity_deviation"] <= 1e-12


def test_cloister_rows_sum_to_one_and_walks_see_the_sky_through_arches(cloister):
    rows = np.random.default_rng(3).choice(len(cloister), 12, replace=False)
    M = ef.form_factor_matrix(cloister, rows=rows)
    assert np.all(M >= 0)
    assert np.abs(M.sum(axis=1) - 1).max() <= 1e-11
    light = cloister.groups.index("light")
    walk = [i for i, g in enumerate(cloister.groups) if g == "walk_floor"]
    i = walk[len(walk) // 2]
    F = ef.form_factors(cloister, cloister.centroids[i], cloister.normals[i])
    U = ef.point_polygon_form_factors(cloister.centroids[i], cloister.normals[i], cloister)
    assert 0 < F[light] < U[light]      # partly hidden by the arcade


def test_vaulted_hall_is_closed_and_faces_in():
    # (the columns stand open-ended on the floor, which closes them: rows sum to 1, below,
    # though the signed areas of the surfaces do not cancel)
    hall = ef.scenes.vaulted_hall(3, 24, 12)
    # a point just off each surface along its normal is inside the hall (under the vault,
    # within the walls) and outside every column
    x = hall.centroids + 1e-6 * hall.normals
    R, height = 4.0, 5.0
    assert np.all((x[:, 0] > 0) & (x[:, 0] < 12) & (np.abs(x[:, 1]) < R) & (x[:, 2] > 0))
    assert np.all(x[:, 1] ** 2 + np.maximum(x[:, 2] - height, 0) ** 2 < R ** 2)
    for xc in (0.6, 4.0, 8.0, 11.4):
        for yc in (-3.4, 3.4):
            inside = ((x[:, 0] - xc) ** 2 + (x[:, 1] - yc) ** 2 < 0.2 ** 2) & (x[:, 2] < height)
            assert not inside.any()
    rows = np.random.default_rng(0).choice(len(hall), 6, replace=False)
    M = ef.form_factor_matrix(hall, rows=rows)
    assert np.all(M >= 0) and np.abs(M.sum(axis=1) - 1).max() <= 1e-12


@pytest.mark.parametrize("kw", [{"bays": 0}, {"segments": 1}, {"column_sides": 2},
                                {"span": 1.0}, {"bay": -1.0}, {"height": float("nan")}])
def test_vaulted_hall_bad_arguments(kw):
    with pytest.raises(ValueError, match=next(iter(kw))):
        ef.scenes.vaulted_hall(**kw)
