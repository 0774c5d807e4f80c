"""Issue 33, item 3: the tolerance is enforced on every path. A value whose bound still
misses ``tolerance`` after everything its path can do raises NumericalError naming the
polygon (and the row), its bound and the tolerance; with ``error=True`` it comes back
with that bound instead. Each test here failed before its fix.
"""

import numpy as np
import pytest

import exactff as ef
from exactff.visibility import visible_form_factors

from test_refinement import sliver_scene

UNIT_UP = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
UNIT_DOWN_AT_1 = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]


def test_one_acceptance_criterion():
    from exactff.errors import misses_tolerance

    # the unoccluded path's last tier, the clipper and Eq. 3 use it relative, area
    # form factors with an absolute floor: E > max(atol, rtol |F|)
    F = np.array([0.5, 0.5, 0.0, 0.0])
    E = np.array([5e-13, 6e-13, 0.0, 1e-20])
    assert misses_tolerance(F, E, 1e-12).tolist() == [False, True, False, True]
    assert misses_tolerance(F, E, None, atol=1e-15).tolist() == [True, True, False, False]
    assert not misses_tolerance(0.1, 1e-9, 1e-12, atol=1e-9)


# ---------------------------------------------------------------------------------------
# (a) the clipper path checks its values against the tolerance after refinement
# ---------------------------------------------------------------------------------------
def _occluded_pair():
    # a unit square at height 1 facing down, hiding a second one above it: a convex
    # enclosure it is not, so the row goes through the clipper
    sq = np.array(UNIT_DOWN_AT_1, dtype=float) - [0.5, 0.5, 0.0]
    return ef.Scene.from_polygons([sq, sq + [0.0, 0.0, 1.0]]), np.zeros(3), np.array([0, 0, 1.0])


def test_clipper_value_whose_bound_misses_the_tolerance_raises(monkeypatch):
    import exactff.visibility.engine as engine

    def pieces(pieces, m, **kwargs):          # polygon 0 with a bound 1e-9: misses 1e-12
        F, E = np.zeros(m), np.zeros(m)
        F[0], E[0] = 0.2394564705, 1e-9
        return F, E

    scene, p, n = _occluded_pair()
    monkeypatch.setattr(engine, "pieces_form_factors", pieces)
    with pytest.raises(ef.NumericalError, match=r"polygon 0: .* misses the tolerance 1e-12 "
                                                r"\(error estimate 1e-09\) after refining"):
        ef.form_factors(scene, p, n)
    # asked for bounds: the value and its honest bound
    F, E = ef.form_factors(scene, p, n, error=True)
    assert F[0] == 0.2394564705 and E[0] == 1e-9
    # no tolerance asked: no check
    assert ef.form_factors(scene, p, n, tolerance=None)[0] == 0.2394564705


def test_unrefinable_sliver_raises_instead_of_returning_the_clippers_bound(monkeypatch):
    # the sliver family (test_refinement) with the refinement made to fail (no ring can
    # be traced to the input): the clipper's value keeps its bound, far above 1e-12 F
    from exactff.visibility.refine import Refiner

    polys, p, n = sliver_scene(1e-9, 0, 0.0)
    scene = ef.Scene.from_polygons(polys)
    real = Refiner.refine_ld

    def unrefinable(self, ci, chart, coords, nxt, ring_of, n_rings, frag):
        val, est, ok, lab = real(self, ci, chart, coords, nxt, ring_of, n_rings, frag)
        return val, np.full(n_rings, np.inf), np.zeros(n_rings, dtype=bool), None

    monkeypatch.setattr(Refiner, "refine_ld", unrefinable)
    st = {}
    F, E = visible_form_factors(scene, p, n, tolerance=1e-12, error=True, stats=st)
    assert st["unrefined_rings"] > 0 and E[0] > 1e-12 * F[0]       # the honest bound
    with pytest.raises(ef.NumericalError, match=r"polygon 0: .*could not be refined"):
        visible_form_factors(scene, p, n, tolerance=1e-12)


# ---------------------------------------------------------------------------------------
# (b) integrator="eq3": not refined, but checked
# ---------------------------------------------------------------------------------------
#: a 1e-6 square off the axis at distance ~1 (F ~ 2.5e-13): Eq. 3 keeps ~3 digits
TINY = np.array([[0.3, 0.2, 1], [0.3, 0.2 + 1e-6, 1], [0.3 + 1e-6, 0.2 + 1e-6, 1],
                 [0.3 + 1e-6, 0.2, 1.0]])


@pytest.mark.parametrize("shortcuts", [True, False], ids=["unoccluded_path", "clipper"])
def test_eq3_value_that_misses_the_tolerance_raises_and_suggests_sector(shortcuts):
    scene = ef.Scene.from_polygons([TINY])
    p, n = np.zeros(3), np.array([0, 0, 1.0])
    eq3 = ef.Exact(integrator="eq3", shortcuts=shortcuts)
    F, E = eq3.point_form_factors(scene, p, n, error=True)
    assert E[0] > 1e-12 * F[0]           # its rounding bound: ~5e-4 relative
    with pytest.raises(ef.NumericalError, match=r"polygon 0: .*integrator='eq3'.*"
                                                r"integrator='sector'"):
        eq3.point_form_factors(scene, p, n)
    # the sector integrator escalates and meets it
    ref = ef.mp_form_factor(p, n, TINY)
    Fs, Es = ef.Exact(shortcuts=shortcuts).point_form_factors(scene, p, n, error=True)
    assert abs(Fs[0] - ref) <= 1e-12 * ref and Es[0] <= 1e-12 * Fs[0]


# ---------------------------------------------------------------------------------------
# (c) the mpmath tier of the refinement stops at its limit: raises
# ---------------------------------------------------------------------------------------
def test_refinement_mpmath_that_does_not_converge_raises(monkeypatch):
    import exactff.visibility.refine as refine

    real = refine.mp_converge
    calls = []

    def stopped(evaluate, tolerance, dps=30):        # as at MP_MAX_DPS: not agreed
        hi, diff, _ = real(evaluate, tolerance, dps)
        calls.append(1)
        return hi, diff, False

    polys, p, n = sliver_scene(1e-12, 0, 0.0)
    scene = ef.Scene.from_polygons(polys)
    st = {}
    visible_form_factors(scene, p, n, tolerance=1e-12, stats=st)
    assert st["refined_rings_mp"] > 0        # the scene reaches the mpmath tier
    monkeypatch.setattr(refine, "mp_converge", stopped)
    with pytest.raises(ef.NumericalError, match=r"polygon 0 \(a ring of one of its visible "
                                                r"pieces\).*mpmath did not converge"):
        visible_form_factors(scene, p, n, tolerance=1e-12)
    assert calls
    st = {}
    F, E = visible_form_factors(scene, p, n, tolerance=1e-12, error=True, stats=st)
    assert st["refine_mp_unconverged"] > 0 and np.all(np.isfinite(E)) and F[0] > 0


# ---------------------------------------------------------------------------------------
# (d) area form factors
# ---------------------------------------------------------------------------------------
def test_area_value_whose_estimate_misses_the_tolerance_raises(monkeypatch):
    import exactff.area.occluded as occluded

    pair = ef.Scene.from_polygons([UNIT_UP, UNIT_DOWN_AT_1])
    F0 = ef.area_form_factors(pair, tolerance=1e-9)          # meets it: no error
    monkeypatch.setattr(occluded, "unoccluded_pair",
                        lambda P, Q, far=True: (0.19982489569838746, 1e-6))
    with pytest.raises(ef.NumericalError, match=r"row 0, polygon 1: .*misses the tolerance "
                                                r"1e-09 absolute \(error estimate 1e-06\)"):
        ef.area_form_factors(pair, tolerance=1e-9)
    with pytest.raises(ef.NumericalError, match=r"max\(1e-15, 1e-09 \* F\)"):
        ef.area_form_factors(pair, tolerance=1e-15, rtol=1e-9)
    F, E = ef.area_form_factors(pair, tolerance=1e-9, error=True)
    assert np.all(E[[0, 1], [1, 0]] == 1e-6)
    assert abs(F[0, 1] - F0[0, 1]) <= 1e-12
    # within a looser absolute tolerance it passes
    ef.area_form_factors(pair, tolerance=1e-5)


def test_occluded_area_value_that_the_rules_cannot_resolve_raises(monkeypatch):
    # an occluded pair with the adaptive cutting switched off (AREA_MAX_DEPTH = 0) and
    # a tolerance the uncut rules cannot meet: a genuine miss, said so
    from exactff import _tolerances as tol

    plate = [[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]]
    down_at_2 = (np.array(UNIT_DOWN_AT_1) + [0, 0, 1]).tolist()
    scene = ef.Scene.from_polygons([UNIT_UP, down_at_2, plate])
    monkeypatch.setattr(tol, "AREA_MAX_DEPTH", 0)
    F, E = ef.area_form_factors(scene, rows=[0], tolerance=1e-14, error=True)
    assert E[0, 1] > 1e-14
    with pytest.raises(ef.NumericalError, match=r"row 0, polygon 1: "):
        ef.area_form_factors(scene, rows=[0], tolerance=1e-14)
