"""Issue 33: bounds that hold on every path (no silent zero, NaN or clamp).

Each test here failed before its fix; the references are independent of the kernels
(closed forms evaluated with mpmath, or an independent construction of the scene).
"""

import mpmath as mp
import numpy as np
import pytest

import exactff as ef


def _corner_mp(a, b, c):
    """Howell's plane element to a parallel a x b rectangle at distance c, the normal
    through a corner, in mpmath at the working precision."""
    A, B = a / c, b / c
    return (A / mp.sqrt(1 + A * A) * mp.atan(B / mp.sqrt(1 + A * A))
            + B / mp.sqrt(1 + B * B) * mp.atan(A / mp.sqrt(1 + B * B))) / (2 * mp.pi)


# ---------------------------------------------------------------------------------------
# item 1: a plane inside the rounding band is not seen edge-on
# ---------------------------------------------------------------------------------------
BAND_CASES = [(1e8, 1e-7), (1e12, 1e-3)]


def _band_scene(c, h, hidden):
    """A unit square at z = c facing down, a point below its centre at float(c - h)
    (inside the plane's rounding band: 16 ulps of c), normal +z; ``hidden`` adds a
    second square above the first, wholly hidden by it (so that the row goes through
    the clipper). Returns the scene, the point, and the exact heights' references."""
    sq = np.array([[c, c, c], [c, c + 1, c], [c + 1, c + 1, c], [c + 1, c, c]])
    polys = [sq] + ([sq + [0.0, 0.0, 1.0]] if hidden else [])
    p = np.array([c + 0.5, c + 0.5, c - h])
    with mp.workdps(50):
        # the float input is exact: the height is c - p_z, computed without rounding
        height = mp.mpf(c) - mp.mpf(float(p[2]))
        ref = [float(4 * _corner_mp(mp.mpf(0.5), mp.mpf(0.5), height))]
    if hidden:
        ref.append(0.0)
    return ef.Scene.from_polygons(polys), p, np.array(ref)


@pytest.mark.parametrize("c,h", BAND_CASES)
@pytest.mark.parametrize("hidden", [False, True], ids=["alone", "occluding"])
@pytest.mark.parametrize("shortcuts", [True, False], ids=["shortcuts", "no_shortcuts"])
def test_point_in_plane_band_gets_its_value_with_a_bound_that_holds(c, h, hidden, shortcuts):
    scene, p, ref = _band_scene(c, h, hidden)
    # the point is inside the band that used to count the square as seen edge-on
    assert abs(p[2] - c) <= 16 * 2.0 ** -53 * 2 * (c + 1)
    F, E = ef.form_factors(scene, p, [0, 0, 1], error=True, shortcuts=shortcuts)
    assert ref[0] > 0.99999
    assert np.all(np.abs(F - ref) <= E + 1e-300), (F, E, ref)
    # the bound meets the default tolerance (1e-12 relative), and so does the value
    assert E[0] <= 1e-12 * F[0]
    assert abs(F[0] - ref[0]) <= 1e-12 * ref[0]
    # the unoccluded value agrees with the engine
    u = ef.point_polygon_form_factor(p, [0, 0, 1], scene.polygons[0])
    assert abs(u - ref[0]) <= 1e-12 * ref[0]


@pytest.mark.parametrize("c,h", BAND_CASES)
def test_point_in_plane_band_eq3_integrator(c, h):
    scene, p, ref = _band_scene(c, h, False)
    F, E = ef.form_factors(scene, p, [0, 0, 1], error=True,
                           method=ef.Exact(integrator="eq3"))
    assert abs(F[0] - ref[0]) <= E[0] + 1e-300
    assert abs(F[0] - ref[0]) <= 1e-12 * ref[0]


@pytest.mark.parametrize("c,d", [(1e8, 1e-7), (1e12, 1e-3)])
def test_far_wall_whose_plane_passes_near_the_point_is_a_sliver_not_edge_on(c, d):
    # the wall's plane y = c passes 1e-7 (7 ulps of 1e8) from p: its image is a thin
    # sliver along a great circle, F ~ 1e-9, once counted as seen edge-on (0, bound 0)
    from exactff.testing.mp_reference import boundary_form_factor

    wall = np.array([[c + 2, c, c + 1], [c + 2, c, c + 2], [c + 3, c, c + 2], [c + 3, c, c + 1]])
    behind = wall + [0.0, -1.0, 0.0]            # makes the scene non-convex: the clipper
    p = np.array([c + 0.5, c + d, c])
    ref = float(boundary_form_factor(p, [0, 0, 1], wall, dps=40))
    assert ref > 1e-10
    for polys in ([wall], [wall, behind]):
        F, E = ef.form_factors(ef.Scene.from_polygons(polys), p, [0, 0, 1], error=True)
        assert abs(F[0] - ref) <= E[0] + 1e-300 and abs(F[0] - ref) <= 1e-12 * ref


@pytest.mark.parametrize("order", ["front_first", "back_first"])
def test_back_to_back_twins_near_a_far_point_follow_the_exact_side(order):
    # a zero-thickness wall (two coincident rectangles facing either way) at y = 1e8,
    # the point 10 ulps in front of one: that one receives (F ~ 1 - 7e-14) and hides its
    # twin, in either input order (the BSP's tie order agrees with the exact side)
    from exactff.testing.mp_reference import boundary_form_factor

    c = 1e8
    front = np.array([[c, c, c], [c, c, c + 1], [c + 1, c, c + 1], [c + 1, c, c]])  # faces +y
    back = front[::-1].copy()
    polys = [front, back] if order == "front_first" else [back, front]
    scene = ef.Scene.from_polygons(polys + [front + [0.0, 3.0, 0.0]])
    p = np.array([c + 0.5, c + 10 * np.spacing(c), c + 0.5])
    i = 0 if order == "front_first" else 1
    ref = float(boundary_form_factor(p, [0, -1, 0], front, dps=40))
    F, E = ef.form_factors(scene, p, [0, -1, 0], error=True)
    assert ref > 0.99999
    assert abs(F[i] - ref) <= E[i] and abs(F[i] - ref) <= 1e-12 * ref
    assert F[1 - i] == 0.0


# ---------------------------------------------------------------------------------------
# item 2: a repeated vertex (a zero-length edge) gave NaN in area form factors
# ---------------------------------------------------------------------------------------
#: Howell's catalogue, C-11: parallel unit squares one apart, directly opposed
HOWELL_C11 = 0.19982489569838746

UNIT_UP = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
UNIT_DOWN_AT_1 = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]
REPEATED = {
    "repeated_consecutive": [[0, 0, 0], [1, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    "closing_vertex": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]],
    "three_in_a_row": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 0], [1, 1, 0], [0, 1, 0]],
}


@pytest.mark.parametrize("name", sorted(REPEATED))
def test_repeated_vertices_give_the_values_of_the_clean_ring(name):
    scene = ef.Scene.from_polygons([REPEATED[name], UNIT_DOWN_AT_1])
    clean = ef.Scene.from_polygons([UNIT_UP, UNIT_DOWN_AT_1])   # built without repeats
    # the scene keeps the clean ring (same polygon index, its vertices only)
    assert len(scene) == 2
    np.testing.assert_array_equal(scene.polygons[0], np.array(UNIT_UP, dtype=float))
    F, E = ef.area_form_factors(scene, error=True)
    F0, E0 = ef.area_form_factors(clean, error=True)
    assert np.all(np.isfinite(F)) and np.all(np.isfinite(E))
    np.testing.assert_array_equal(F, F0)
    for i, j in ((0, 1), (1, 0)):
        assert abs(F[i, j] - HOWELL_C11) <= max(E[i, j], 1e-12)
        assert abs(F[i, j] - HOWELL_C11) <= 1e-12
    # the unoccluded pair, from the raw input, either way round
    for f in (ef.polygon_form_factor(REPEATED[name], UNIT_DOWN_AT_1),
              ef.polygon_form_factor(UNIT_DOWN_AT_1, REPEATED[name])):
        assert abs(f - HOWELL_C11) <= 1e-12


def _nan_pair(P, Q, shortcuts=True, atol=0.0):
    return float("nan"), 0.0


def _nan_pairs(P, Qs, **options):
    return np.full(len(Qs), np.nan), np.zeros(len(Qs))


def _nan_pieces(pieces, m, **kwargs):
    return np.full(m, np.nan), np.zeros(m)


def _nan_mp(*args, **kwargs):
    return float("nan"), float("nan")


def _band_square():
    c = 1e8
    sq = np.array([[c, c, c], [c, c + 1, c], [c + 1, c + 1, c], [c + 1, c, c]])
    return sq, np.array([c + 0.5, c + 0.5, c - 1e-7]), np.array([0.0, 0.0, 1.0])


def _nan_core(scene):
    # the compiled core with a row that makes a NaN
    import exactff.visibility.bsp as bsp

    class NaNCore:
        def row(self, point, normal, node_side, source_side, **options):
            F = np.full(len(source_side), np.nan)
            return F, np.zeros_like(F), np.zeros_like(F), np.zeros_like(F), {}

    return bsp.scene_bsp(scene)[0], NaNCore()


def _nan_calls():
    import exactff.area.closed_form as closed_form
    import exactff.area.row as row
    import exactff.kernel.eq3 as eq3
    import exactff.kernel.point as point
    import exactff.visibility.compiled as compiled
    import exactff.visibility.engine as engine

    sq, p, n = _band_square()
    pair = ef.Scene.from_polygons([UNIT_UP, UNIT_DOWN_AT_1])
    alone = ef.Scene.from_polygons([sq])
    return {
        "polygon_form_factor": (closed_form, "unoccluded_pair", _nan_pair,
                                lambda: ef.polygon_form_factor(UNIT_UP, UNIT_DOWN_AT_1)),
        "area_form_factors": (row, "unoccluded_pairs", _nan_pairs,
                              lambda: ef.area_form_factors(pair, error=True)),
        # the last precision tier (a polygon in the rounding band always reaches it)
        "point_polygon_form_factor": (point, "mp_form_factor", _nan_mp,
                                      lambda: ef.point_polygon_form_factor(p, n, sq, error=True)),
        "point_polygon_form_factors": (point, "mp_form_factor", _nan_mp,
                                       lambda: ef.point_polygon_form_factors(p, n, [sq],
                                                                             error=True)),
        "form_factors_unoccluded_path": (point, "mp_form_factor", _nan_mp,
                                         lambda: ef.form_factors(alone, p, n, error=True)),
        "form_factors_clipper": (engine, "pieces_form_factors", _nan_pieces,
                                 lambda: ef.form_factors(alone, p, n, shortcuts=False,
                                                         engine="python")),
        "form_factors_compiled": (compiled, "compiled_core", _nan_core,
                                  lambda: ef.form_factors(alone, p, n, shortcuts=False)),
        "eq3_form_factor": (eq3, "eq3_ring_sums",
                            lambda *a, **k: (np.array([np.nan]), np.ones(1), np.zeros(1)),
                            lambda: ef.eq3_form_factor([0, 0, 0], [0, 0, 1],
                                                       UNIT_DOWN_AT_1)),
    }


@pytest.mark.parametrize("name", ["polygon_form_factor", "area_form_factors",
                                  "point_polygon_form_factor", "point_polygon_form_factors",
                                  "form_factors_unoccluded_path", "form_factors_clipper",
                                  "form_factors_compiled", "eq3_form_factor"])
def test_nan_from_a_kernel_is_refused_by_every_public_result(monkeypatch, name):
    # the finiteness check on the way out of each path: a NaN made inside a kernel (here
    # injected) raises NumericalError saying so, never comes back as a value
    module, attr, fake, call = _nan_calls()[name]
    monkeypatch.setattr(module, attr, fake)
    with pytest.raises(ef.NumericalError, match="not finite"):
        out = call()
        pytest.fail(f"{name} returned {out!r}")


# ---------------------------------------------------------------------------------------
# item 4: a value below 0 beyond its own bound raises; within it, 0 with a bound that
# covers the clamp
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("k", [0.5, 1.0, 2.0, 500.0])
def test_unoccluded_value_below_zero_is_clamped_only_within_its_bound(k):
    from exactff.kernel.sector import sector_values

    # one front-facing polygon (d0 < 0: F = -S / 2 pi), its estimate e / 2 pi
    e = 1e-14
    S = np.array([k * e])
    F_raw, err_raw = -k * e / (2 * np.pi), e / (2 * np.pi)
    if k <= 1.0:
        F, err = sector_values(S, np.zeros(1), np.array([e]), np.array([-1.0]), False)
        assert F[0] == 0.0
        # 0 <= exact <= F_raw + err: the bound still covers the clamped value
        assert err[0] >= F_raw + err_raw >= 0.0
    else:
        with pytest.raises(ef.NumericalError, match="below 0 beyond"):
            sector_values(S, np.zeros(1), np.array([e]), np.array([-1.0]), False)


@pytest.mark.parametrize("k", [0.5, 2.0, 500.0])
def test_occluded_value_below_zero_is_clamped_only_within_its_bound(monkeypatch, k):
    import exactff.visibility.engine as engine

    E0 = 1e-14

    def pieces(pieces, m, **kwargs):        # fragment values: the first polygon's only
        F, E = np.zeros(m), np.zeros(m)
        F[0], E[0] = -k * E0, E0
        return F, E

    sq, p, n = _band_square()
    scene = ef.Scene.from_polygons([sq])
    monkeypatch.setattr(engine, "pieces_form_factors", pieces)
    if k <= 1.0:
        F, E = ef.form_factors(scene, p, n, error=True, shortcuts=False, engine="python")
        assert F[0] == 0.0 and E[0] >= k * E0
    else:
        with pytest.raises(ef.NumericalError, match="below 0 beyond"):
            ef.form_factors(scene, p, n, error=True, shortcuts=False, engine="python")


@pytest.mark.parametrize("area,mag,ok", [
    (1e-15, 1e-20, False),     # 1e-15 below 0, estimate 3.5e-36: beyond (was clamped)
    (1e-12, 1e6, True),        # 1e-12 below 0, estimate 3.5e-10: within (was refused)
])
def test_eq3_value_below_zero_is_judged_against_its_own_estimate(monkeypatch, area, mag, ok):
    import exactff.kernel.eq3 as integ

    sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]   # faces p: F = -area / pi
    # twice the image's area, and the absolute terms (twice the magnitude)
    monkeypatch.setattr(integ, "eq3_ring_sums", lambda *a, **k: (
        np.array([2 * area * np.pi]), np.array([2 * mag]), np.zeros(1)))
    if ok:
        F, E = ef.eq3_form_factor([0, 0, 0], [0, 0, 1], sq, error=True)
        assert F == 0.0 and E >= area
    else:
        with pytest.raises(ef.NumericalError, match="below 0"):
            ef.eq3_form_factor([0, 0, 0], [0, 0, 1], sq, error=True)


# ---------------------------------------------------------------------------------------
# interface: one name for the sidedness option
# ---------------------------------------------------------------------------------------
def test_two_sided_is_the_option_and_one_sided_is_deprecated():
    # a unit square facing away from p (front towards +z, p below): 0 one-sided; seen
    # from behind, Howell's point below the centre of a parallel square at distance 1
    # (the mpmath reference of exactff.testing too)
    from exactff.testing.mp_reference import boundary_form_factor

    sq = np.array([[-.5, -.5, 1], [.5, -.5, 1], [.5, .5, 1], [-.5, .5, 1]], dtype=float)
    p, n = np.zeros(3), np.array([0, 0, 1.0])
    ref = 0.2394564705
    for f in (ef.point_polygon_form_factor, ef.sector_form_factor, ef.eq3_form_factor,
              ef.mp_form_factor,
              lambda p, n, P, **k: float(ef.point_polygon_form_factors(p, n, [P], **k)[0]),
              lambda p, n, P, **k: float(boundary_form_factor(p, n, P, dps=20, **k))):
        assert f(p, n, sq) == 0.0
        assert abs(f(p, n, sq, two_sided=True) - ref) < 1e-10
        with pytest.warns(DeprecationWarning, match="two_sided"):
            assert abs(f(p, n, sq, one_sided=False) - ref) < 1e-10
        with pytest.warns(DeprecationWarning, match="two_sided"):
            assert f(p, n, sq, one_sided=True) == 0.0
        with pytest.raises(ValueError, match="contradicts"), \
                pytest.warns(DeprecationWarning):
            f(p, n, sq, two_sided=True, one_sided=True)
    with pytest.raises(ValueError, match="two_sided"):
        ef.point_polygon_form_factor(p, n, sq, two_sided="yes")


# ---------------------------------------------------------------------------------------
# the offset form's rounding of the point's offset is in the estimate
# ---------------------------------------------------------------------------------------
NEAR_EDGE = (np.array([[1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0]]),
             np.array([0.9996199694573367, 0.0007600610853263808, 0.0]))


@pytest.mark.parametrize("tolerance", [None, 1e-12])
def test_point_kernel_estimate_covers_a_point_near_an_edge_in_its_horizon(tolerance):
    # the square x = 1 seen from 3.8e-4 before it, its edge z = 0 in the point's
    # horizon plane: 0.426100134642847 (40 digits). The double sums gave
    # 0.4261001346428431 with an estimate of 1.4e-15: the rounding of Q0 - p moves the
    # vertex 7.6e-4 from the point by 5e-17, which the estimate left out
    from exactff.testing.mp_reference import boundary_form_factor

    Q, x = NEAR_EDGE
    n = np.array([0.0, 0.0, 1.0])
    F, E = ef.point_polygon_form_factor(x, n, Q, error=True, tolerance=tolerance)
    assert abs(F - float(boundary_form_factor(x, n, Q, dps=40))) <= E
    if tolerance is not None:
        assert E <= tolerance * F        # the long double tier meets it
