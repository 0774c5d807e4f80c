"""Every public entry point checks its receiver, scene and rows once and names the bad
argument (issue 11, items 5 and 6): no silent row of zeros, no unrelated IndexError."""

import numpy as np
import pytest

import exactff as ef
from exactff.methods import METHODS

BAD = [([np.nan, 0.5, 0.5], [0, 0, 1], "point"), ([np.inf, 0.5, 0.5], [0, 0, 1], "point"),
       ([0.5, 0.5, 0.5], [0, 0, 0], "normal"), ([0.5, 0.5, 0.5], [0, np.nan, 1], "normal"),
       ([0.5, 0.5], [0, 0, 1], "point")]


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("point, normal, name", BAD)
def test_methods_reject_bad_receivers(method, point, normal, name):
    scene = ef.scenes.subdivided_box(1)
    m = METHODS[method]()
    with pytest.raises(ValueError, match=name):
        m.point_form_factors(scene, np.array(point, dtype=float), np.array(normal, dtype=float))
    with pytest.raises(ValueError, match=name):
        ef.form_factors(scene, point, normal, method=m)


def test_monte_carlo_with_error_rejects_bad_receivers():
    with pytest.raises(ValueError, match="normal"):
        ef.MonteCarlo().form_factors_with_error(ef.scenes.subdivided_box(1), [0.5] * 3, [0, 0, 0])


@pytest.mark.parametrize("method", sorted(METHODS))
def test_a_list_is_not_a_scene(method):
    polys = list(ef.scenes.subdivided_box(1).polygons)
    with pytest.raises(TypeError, match="Scene.from_polygons"):
        METHODS[method]().point_form_factors(polys, np.full(3, 0.5), np.array([0, 0, 1.0]))
    with pytest.raises(TypeError, match="exactff.Scene"):
        ef.form_factors(polys, [0.5] * 3, [0, 0, 1])
    with pytest.raises(TypeError, match="exactff.Scene"):
        ef.form_factor_matrix(polys)


@pytest.mark.parametrize("rows", [[0.7, 1.9], [True, False], ["0"]])
def test_matrix_rows_must_be_integers(rows):
    with pytest.raises(ValueError, match="rows"):
        ef.form_factor_matrix(ef.scenes.subdivided_box(1), rows=rows)


def test_cli_rows_out_of_range_is_an_error(capsys):
    from exactff.cli import parse_rows

    assert parse_rows("2:4", 6).tolist() == [2, 3]
    for text in ("0:100", "5,6", "-1:3", "4:2"):
        with pytest.raises(ValueError, match="--rows"):
            parse_rows(text, 6)


def test_resume_refuses_a_method_with_other_options(tmp_path):
    # the resume check compared repr(method), which leaves out SinglePlane's refine
    scene = ef.scenes.subdivided_box(1)
    out = tmp_path / "m.npy"
    ef.form_factor_matrix(scene, method=ef.SinglePlane(8, refine=1), out=out)
    with pytest.raises(ValueError, match="not written by this computation"):
        ef.form_factor_matrix(scene, method=ef.SinglePlane(8, refine=3), out=out)
    # the same method and options resume (here: everything is done already)
    M = ef.form_factor_matrix(scene, method=ef.SinglePlane(8, refine=1), out=out)
    assert M.shape == (6, 6)


def test_mpmath_that_does_not_converge_raises(monkeypatch):
    # issue 11, item 7: mp_form_factor used to give up silently at its precision limit
    import exactff.kernel as integ
    from exactff import _tolerances as tol

    sq = np.array([[0, 0, 1], [0, 1e-9, 1], [1e-9, 1e-9, 1], [1e-9, 0, 1.0]])
    monkeypatch.setattr(tol, "MP_MAX_DPS", 10)        # a limit this case cannot meet
    with pytest.raises(ef.NumericalError, match="did not converge"):
        integ.mp_form_factor([0, 0, 0], [0, 0, 1], sq, tolerance=1e-30, dps=10)
    value, err = integ.mp_form_factor([0, 0, 0], [0, 0, 1], sq, tolerance=1e-30, dps=10,
                                      error=True)
    assert value > 0 and err > 0


def test_negative_values_beyond_rounding_raise_a_named_error():
    # invariants were checked with assert, which python -O removes
    import exactff.kernel as integ

    S = np.array([-1.0, 1e-3])          # the second would be a form factor of -1.6e-4
    with pytest.raises(ef.NumericalError, match="polygon 1"):
        integ.sector_values(S, np.ones(2), np.zeros(2), np.array([-1.0, -1.0]), False)



def test_last_tier_values_are_checked_against_the_tolerance(monkeypatch):
    # a 1e-9 square needs mpmath; with its precision capped below what the tolerance
    # needs, the value is returned with its (large) estimate on request, else raises
    from exactff import _tolerances as tol

    sq = np.array([[0, 0, 1], [0, 1e-9, 1], [1e-9, 1e-9, 1], [1e-9, 0, 1.0]])
    monkeypatch.setattr(tol, "MP_MAX_DPS", 10)
    F, E = ef.point_polygon_form_factors([0, 0, 0], [0, 0, 1], [sq], tolerance=1e-40,
                                         error=True)
    assert F[0] > 0 and E[0] > 1e-40 * F[0]
    with pytest.raises(ef.NumericalError, match="misses the tolerance"):
        ef.point_polygon_form_factors([0, 0, 0], [0, 0, 1], [sq], tolerance=1e-40)


@pytest.mark.parametrize("point, normal", [
    ([0.5, 0.5, 0.5], [0, 0, 2]), ([np.nan, 0.5, 0.5], [0, 0, 1]), ([0.5, -np.inf, 0], [0, 0, 1]),
    ([0, 0, 0], [0, 0, 0]), ([0, 0, 0], [np.inf, 0, 0]), ([0, 0, 0], [0, np.nan, 1]),
    ([0, 0, 0], [1e-200, 0, 0]), ([0, 0, 0], [0, 1e200, 0]), ([1, 2, 3], [1e-160, 1e-160, 0]),
    ([1e300, -1e300, 0], [3, 4, 0])])
def test_one_receiver_is_checked_as_the_broadcast_receivers(point, normal):
    # as_receiver takes one point and one normal of shape (3,) in Python floats (a
    # row's call); as_receivers, numpy's whole-array checks, is the reference: the same
    # arrays, or the same ValueError, for finite, infinite and NaN coordinates and for
    # normals whose squared length underflows to 0 (refused) or overflows (refused)
    from exactff.checks import as_receiver, as_receivers
    point, normal = np.array(point, dtype=float), np.array(normal, dtype=float)
    try:
        with np.errstate(over="ignore"):       # (numpy's norm squares 1e200)
            P, N, shape = as_receivers(point, normal)
        expected = (P[0].tolist(), N[0].tolist())
    except ValueError as e:
        expected = str(e)
    try:
        p, n = as_receiver(point, normal)
        assert p.shape == n.shape == (3,) and p.dtype == n.dtype == np.float64
        got = (p.tolist(), n.tolist())
    except ValueError as e:
        got = str(e)
    assert got == expected


@pytest.mark.parametrize("point, normal", [([1, 2], "abc"), ([1, 2, np.nan], "abc"),
                                           ([1, 2, 3], [0, 0]), ((0.5, 0.5, 0.5), (0, 0, 1))])
def test_one_receiver_checks_the_point_first(point, normal):
    # the point is checked before the normal is read, as as_receivers does: a bad point
    # is named even where the normal is not a vector at all
    from exactff.checks import as_receiver, as_receivers

    def outcome(f):
        try:
            return [a.tolist() for a in f(point, normal)[:2]]
        except ValueError as e:
            return str(e)
    assert outcome(as_receiver) == outcome(lambda a, b: [x[0] for x in as_receivers(a, b)[:2]])
