"""The discrete comparators: delta form factors against the exact kernel, closure,
convergence to the exact method, Monte Carlo statistics, the shared z-buffer, errors."""

import importlib.util
import math
import os

import numpy as np
import pytest

import exactff as ef
from exactff.methods import METHODS
from exactff.methods._sampling import nearest_polygons
from exactff.methods.cubic_tetrahedron import cubic_tetrahedron_frame

from common import coaxial_disc, parallel_rect_corner

ORIGIN, UP = np.zeros(3), np.array([0.0, 0.0, 1.0])
DISCRETE = [m for m in METHODS if m != "exact"]


def exact_region(P):
    """Exact form factor of a region given by a polygon, from the origin with normal z,
    either side receiving (the kernel under test elsewhere, against mpmath)."""
    return ef.point_polygon_form_factor(ORIGIN, UP, np.asarray(P, float), two_sided=True)


def cells_in(layout, mask_fn):
    D = layout.directions
    return layout.weights[mask_fn(D)].sum()


# ---------------------------------------------------------------------------------------
# delta form factors: each region's cells against the region's exact form factor
# ---------------------------------------------------------------------------------------
def test_hemicube_faces_vs_exact():
    top = [[-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]
    side = [[1, -1, 0], [1, 1, 0], [1, 1, 1], [1, -1, 1]]
    errs = []
    for r in (16, 32, 64):
        L = ef.Hemicube(r).layout()
        on_top = lambda D: D[:, 2] >= np.maximum(np.abs(D[:, 0]), np.abs(D[:, 1]))
        on_px = lambda D: (D[:, 0] > np.abs(D[:, 1])) & (D[:, 0] > D[:, 2])
        e_top = abs(cells_in(L, on_top) - exact_region(top))
        e_side = abs(cells_in(L, on_px) - exact_region(side))
        errs.append((e_top, e_side))
    # the midpoint rule: error falls about 4 x per doubling of the resolution
    for (a, b), (c, d) in zip(errs, errs[1:]):
        assert 3.0 < a / c < 5.0 and 3.0 < b / d < 5.0
    assert errs[-1][0] < 2e-4 and errs[-1][1] < 2e-4


def test_cubic_tetrahedron_face_vs_exact():
    A = cubic_tetrahedron_frame()
    # face x' = 1 of the tetrahedron: the triangle v, w <= 1 above 1 + v + w = 0
    face = np.array([[1, 1, 1], [1, -2, 1], [1, 1, -2]], float) @ A
    ref = exact_region(face)
    assert ref == pytest.approx(1 / 3, abs=1e-14)  # three congruent faces tile the hemisphere
    prev = None
    for r in (16, 64, 256):
        L = ef.CubicTetrahedron(r).layout()
        cube = L.directions @ A.T
        s = L.weights[(cube[:, 0] > cube[:, 1]) & (cube[:, 0] > cube[:, 2])].sum()
        err = abs(s - ref)
        if prev is not None:
            assert err < prev / 2.5  # cells cut by the base dominate: about 1 / r
        prev = err
    assert prev < 2e-3


def test_ppbh_cells_are_the_grid_cells_with_centre_in_the_disk():
    for r in (10, 64, 301):
        L = ef.DiscretePPBH(r).layout()
        # the cells, counted independently: centres of an r x r grid over [-1, 1]^2
        # strictly inside the unit disk; each carries the same share
        c = -1.0 + (np.arange(r) + 0.5) * 2.0 / r
        X, Y = np.meshgrid(c, c, indexing="ij")
        inside = X * X + Y * Y < 1.0
        assert len(L) == int(inside.sum())
        got = np.round(L.directions[:, :2], 9)
        want = np.round(np.column_stack([X[inside], Y[inside]]), 9)
        assert np.array_equal(got[np.lexsort(got.T)], want[np.lexsort(want.T)])
        assert np.allclose(L.weights, 1.0 / inside.sum(), rtol=1e-15)
    # a region: the cells of x > 0 carry half
    L = ef.DiscretePPBH(300).layout()
    assert cells_in(L, lambda D: D[:, 0] > 0) == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("E", [1.0, 4.0, 10.0])
def test_single_plane_equal_ff_cells_sum_to_the_covered_square(E):
    L = ef.SinglePlane(40, extent=E).layout()
    ref = 4 * parallel_rect_corner(E, E, 1.0)
    assert L.covered == pytest.approx(ref, abs=1e-14)
    assert L.weights.sum() == pytest.approx(ref, abs=1e-13)
    assert L.missed == pytest.approx(1 - ref, abs=1e-14)
    # comparable delta form factors: far more even than the uniform plane's
    U = ef.SinglePlane(40, extent=E, cells="uniform").layout()
    ratio = L.weights.max() / L.weights.min()
    assert ratio < 25 and ratio < (U.weights.max() / U.weights.min()) / 2


def test_single_plane_uniform_variants_vs_exact():
    E = 3.0
    ref = 4 * parallel_rect_corner(E, E, 1.0)
    e1 = abs(ef.SinglePlane(60, extent=E, cells="uniform").layout().weights.sum() - ref)
    e2 = abs(ef.SinglePlane(120, extent=E, cells="uniform").layout().weights.sum() - ref)
    assert 3.0 < e1 / e2 < 5.0
    refined = ef.SinglePlane(60, extent=E, cells="uniform_refined", refine=4).layout()
    assert len(refined) == 60 * 60 + 20 * 20 * 15        # centre cells 16 x finer (refine 4)
    # the finer centre: the hemicube top face [-1, 1]^2 is integrated 16 x better
    top = 4 * parallel_rect_corner(1.0, 1.0, 1.0)
    in_top = lambda D: (np.abs(D[:, 0] / D[:, 2]) < 1) & (np.abs(D[:, 1] / D[:, 2]) < 1)
    coarse = ef.SinglePlane(60, extent=E, cells="uniform").layout()
    e_coarse = abs(cells_in(coarse, in_top) - top)
    e_fine = abs(cells_in(refined, in_top) - top)
    assert 12 < e_coarse / e_fine < 20


def test_polar_plane_cells_are_equal_and_sum_to_the_disc():
    for E in (2.0, 10.0):
        L = ef.PolarPlane(20, 60, extent=E).layout()
        assert L.weights.sum() == pytest.approx(coaxial_disc(E, 1.0), abs=1e-13)
        # the cells inside radius r_k carry exactly F(r_k): rings of equal form factor
        k = 7
        Fk = k / 20 * coaxial_disc(E, 1.0)
        rk = math.sqrt(Fk / (1 - Fk))
        D = L.directions
        rho = np.hypot(D[:, 0], D[:, 1]) / D[:, 2]
        assert L.weights[rho < rk].sum() == pytest.approx(coaxial_disc(rk, 1.0), abs=1e-13)


def load_delta_ff_tool():
    path = os.path.join(os.path.dirname(__file__), "..", "tools", "derive_delta_ff.py")
    spec = importlib.util.spec_from_file_location("derive_delta_ff", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_delta_ff_derivation_script():
    assert load_delta_ff_tool().main() == 0


def test_hemicube_cells_carry_the_derived_delta_ff():
    # the package's cells against the delta form factor derived with sympy from
    # cos(theta_p) cos(theta_c) / (pi r^2), evaluated at each cell's centre on its face
    # (the cells' directions, scaled onto the face) times the cell's area
    tool = load_delta_ff_tool()
    sp = tool.sp
    x, y, z = sp.symbols("x y z", real=True)
    top = sp.lambdify((x, y), tool.delta_ff((x, y, 1), (0, 0, 1), (0, 0, 1)), "numpy")
    side = sp.lambdify((y, z), tool.delta_ff((1, y, z), (0, 0, 1), (1, 0, 0)), "numpy")
    r = 16
    L = ef.Hemicube(r).layout()
    D = L.directions
    on_top = D[:, 2] >= np.abs(D[:, :2]).max(axis=1) - 1e-12
    dA = (2.0 / r) ** 2
    T = D[on_top] / D[on_top, 2:]
    assert on_top.sum() == r * r
    np.testing.assert_allclose(L.weights[on_top], top(T[:, 0], T[:, 1]) * dA, rtol=1e-13)
    S = D[~on_top]
    k = np.argmax(np.abs(S[:, :2]), axis=1)                # the side face's axis
    a = np.abs(S[np.arange(len(S)), k])
    Q = S / a[:, None]                                      # a point on face |x| = 1 or |y| = 1
    along = Q[np.arange(len(S)), 1 - k]
    np.testing.assert_allclose(L.weights[~on_top], side(along, Q[:, 2]) * dA, rtol=1e-13)


# ---------------------------------------------------------------------------------------
# the shared z-buffer against brute-force ray casting
# ---------------------------------------------------------------------------------------
def brute_force_nearest(scene, p, n, D):
    R = ef.receiver_frame(n)
    W = D @ R  # world directions
    best = np.full(len(D), np.inf)
    hit = np.full(len(D), -1)
    ulps = ef._tolerances.PLANE_SIDE_ULPS * ef._tolerances.EPS
    for j, P in enumerate(scene.polygons):
        nj, c = scene.normals[j], scene.centroids[j]
        num, den = (c - p) @ nj, W @ nj
        # decided explicitly, not by a rounded 0: p in the plane to rounding sees the
        # polygon edge-on, a ray parallel to it to rounding misses it
        if abs(num) <= ulps * (np.abs(p).max() + np.abs(P).max()):
            continue
        ok = np.abs(den) > ulps
        t = np.divide(num, den, out=np.full(len(W), np.inf), where=ok)
        X = p + np.where(ok, t, 0.0)[:, None] * W
        # inside test in the polygon's plane (crossing number in 2-D)
        e1 = P[1] - P[0]
        e1 = e1 / np.linalg.norm(e1)
        e2 = np.cross(nj, e1)
        q = np.column_stack([(X - P[0]) @ e1, (X - P[0]) @ e2])
        Q = np.column_stack([(P - P[0]) @ e1, (P - P[0]) @ e2])
        inside = np.zeros(len(D), bool)
        for k in range(len(Q)):
            a, b = Q[k], Q[(k + 1) % len(Q)]
            st = (a[1] > q[:, 1]) != (b[1] > q[:, 1])     # then b[1] != a[1]
            ux = a[0] + np.divide((q[:, 1] - a[1]) * (b[0] - a[0]), b[1] - a[1],
                                  out=np.zeros(len(q)), where=st)
            inside ^= st & (q[:, 0] < ux)
        ok &= inside & (t > 0) & (t < best)
        best[ok], hit[ok] = t[ok], j
    return hit


@pytest.mark.parametrize("seed", range(3))
def test_nearest_polygons_vs_brute_force(seed):
    rng = np.random.default_rng(seed)
    scene = ef.scenes.furnished_box(2, [((0.2, 0.3, 0.1), (0.55, 0.6, 0.45)),
                                        ((0.6, 0.1, 0.0), (0.9, 0.45, 0.7))])
    p = np.array([0.13, 0.82, 0.07]) + rng.uniform(-0.05, 0.05, 3)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    D = rng.normal(size=(4000, 3))
    D[:, 2] = np.abs(D[:, 2]) + 1e-3
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    got = nearest_polygons(scene, p, n, D)
    ref = brute_force_nearest(scene, p, n, D)
    # random directions almost never graze an edge: every cell agrees
    assert np.mean(got == ref) == 1.0


# ---------------------------------------------------------------------------------------
# rows: closure, convergence, Monte Carlo
# ---------------------------------------------------------------------------------------
def free_rows(scene, boxes):
    from test_visibility import inside_any_box
    return [i for i in range(len(scene))
            if not inside_any_box(scene.centroids[i] + 1e-9 * scene.normals[i], boxes)]


# corners off the 45-degree diagonals of the receiving points: a cell ray that grazes a
# box edge exactly may stop on a back face (a tie of measure zero)
BOXES = [((0.21, 0.17, 0.0), (0.47, 0.53, 0.62)), ((0.61, 0.13, 0.09), (0.89, 0.31, 0.86))]


@pytest.mark.parametrize("name", DISCRETE)
def test_rows_in_a_closed_room_sum_to_the_covered_fraction(name):
    scene = ef.scenes.furnished_box(2, BOXES)
    m = ef.methods.resolve(name, samples=20000)
    L = m.layout()
    for i in free_rows(scene, BOXES)[::5]:
        F = m.point_form_factors(scene, scene.centroids[i], scene.normals[i])
        # every cell hits a front face: the row carries all the cells' delta FFs
        assert F.sum() == pytest.approx(L.weights.sum(), abs=1e-12)
        assert np.all(F >= 0)


@pytest.mark.parametrize("name", DISCRETE)
def test_discrete_methods_converge_to_exact(name):
    scene = ef.scenes.cornell_box(closed=True)
    rows = range(len(scene))
    exact = ef.form_factor_matrix(scene, rows=rows)
    # the plane methods miss a band above the horizon; with a huge extent the band's
    # form factor (1e-6) stays below the sampling error
    options = {"single_plane": {"extent": 1e3}, "polar_plane": {"extent": 1e3}}.get(name, {})
    errs = []
    for samples in (4096, 65536):
        m = ef.methods.resolve(name, samples=samples, **options)
        M = ef.form_factor_matrix(scene, rows=rows, method=m)
        errs.append(np.abs(M - exact).mean())
    rate = math.log(errs[0] / errs[1]) / math.log(16)
    print(f"{name}: mean abs error {errs[0]:.2e} -> {errs[1]:.2e}, rate {rate:.2f}")
    # loosely: 16 x the samples at least halves the mean error (rates 0.25 .. 1 expected)
    assert errs[1] < errs[0] / 2
    assert errs[1] < 2e-3


def test_monte_carlo_within_four_and_a_half_standard_errors():
    scene = ef.scenes.cornell_box(closed=True)
    mc = ef.MonteCarlo(samples=40000, seed=3)
    z = []
    for i in range(len(scene)):
        p, n = scene.centroids[i], scene.normals[i]
        F, se = mc.form_factors_with_error(scene, p, n)
        ex = ef.form_factors(scene, p, n)
        ok = se > 0
        z.extend(np.abs(F[ok] - ex[ok]) / se[ok])
        # a polygon no sample hit (no standard error): 0, and small enough that missing
        # it is plausible, P(no hit) = (1 - F)^N >= exp(-14) = 8e-7 for N F <= 14
        assert np.all(F[~ok] == 0) and np.all(ex[~ok] * mc.samples <= 14), ex[~ok]
    z = np.array(z)
    assert np.all(z < 4.5)
    assert np.mean(z < 2) > 0.9  # about 95 % within 2 standard errors


def test_monte_carlo_seed_reproduces():
    scene = ef.scenes.cornell_box()
    p, n = scene.centroids[1], scene.normals[1]
    a = ef.MonteCarlo(5000, seed=7).point_form_factors(scene, p, n)
    b = ef.MonteCarlo(5000, seed=7).point_form_factors(scene, p, n)
    c = ef.MonteCarlo(5000, seed=8).point_form_factors(scene, p, n)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_methods_by_name_and_instance_agree():
    scene = ef.scenes.cornell_box()
    p, n = scene.centroids[1], scene.normals[1]
    a = ef.form_factors(scene, p, n, method="hemicube", resolution=32)
    b = ef.form_factors(scene, p, n, method=ef.Hemicube(resolution=32))
    assert np.array_equal(a, b)


# ---------------------------------------------------------------------------------------
# bad options
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("make,word", [
    (lambda: ef.Hemicube(resolution=0), "resolution"),
    (lambda: ef.Hemicube(resolution=-4), "resolution"),
    (lambda: ef.Hemicube(resolution=7), "even"),
    (lambda: ef.DiscretePPBH(samples=0), "samples"),
    (lambda: ef.CubicTetrahedron(resolution=2.5), "resolution"),
    (lambda: ef.SinglePlane(16, extent=-1), "extent"),
    (lambda: ef.SinglePlane(16, cells="x"), "cells"),
    (lambda: ef.PolarPlane(0, 4), "rings"),
    (lambda: ef.MonteCarlo(samples=-1), "samples"),
    (lambda: ef.MonteCarlo(seed=1.5), "seed"),
])
def test_bad_options_raise_value_error(make, word):
    with pytest.raises(ValueError, match=word):
        make()


def test_unknown_method_lists_the_choices():
    with pytest.raises(ValueError) as info:
        ef.form_factors(ef.scenes.cornell_box(), [1, 1, 1], [0, 1, 0], method="radiosity")
    for name in METHODS:
        assert name in str(info.value)


def test_compare_records_against_an_independent_loop():
    scene = ef.scenes.cornell_box(closed=True)
    rows = [0, 1, 7]
    recs = ef.compare(scene, ["ppbh", ef.Hemicube(resolution=16)], samples=[1000, 4000],
                      rows=rows)
    assert [r["method"] for r in recs] == ["ppbh", "ppbh", "hemicube"]
    exact = np.array([ef.form_factors(scene, scene.centroids[i], scene.normals[i])
                      for i in rows])
    for r, m in zip(recs, [ef.DiscretePPBH(samples=1000), ef.DiscretePPBH(samples=4000),
                           ef.Hemicube(resolution=16)]):
        M = np.array([m.point_form_factors(scene, scene.centroids[i], scene.normals[i])
                      for i in rows])
        assert r["samples"] == m.samples and r["rows"] == 3
        assert r["mean_abs_error"] == pytest.approx(np.abs(M - exact).mean(), rel=1e-12)
        assert r["max_abs_error"] == pytest.approx(np.abs(M - exact).max(), rel=1e-12)
        assert r["time_per_row"] > 0
    assert "| ppbh | " in ef.to_markdown(recs)
    with pytest.raises(ValueError, match="reference"):
        ef.compare(scene, ["ppbh"], rows=rows, reference=np.zeros((2, 2)))


def test_cubic_tetrahedron_cells_carry_the_derived_delta_ff():
    # the package's cells against the sympy-derived delta FF of the face x' = 1 of the
    # cube (receiver normal (1, 1, 1)/sqrt 3), at each cell's centre times its area
    from exactff.methods.cubic_tetrahedron import cubic_tetrahedron_frame

    tool = load_delta_ff_tool()
    sp = tool.sp
    v, w = sp.symbols("v w", real=True)
    dff = sp.lambdify((v, w), tool.delta_ff((1, v, w), [1 / sp.sqrt(3)] * 3, (1, 0, 0)), "numpy")
    r = 24
    L = ef.CubicTetrahedron(r).layout()
    C = L.directions @ np.linalg.inv(cubic_tetrahedron_frame())   # cube coordinates
    face = np.argmax(C, axis=1)
    C = C / C[np.arange(len(C)), face][:, None]
    # the faces are (1, v, w), (w, 1, v), (v, w, 1)
    vv = C[np.arange(len(C)), (face + 1) % 3]
    ww = C[np.arange(len(C)), (face + 2) % 3]
    np.testing.assert_allclose(L.weights, dff(vv, ww) * (3.0 / r) ** 2, rtol=1e-12)
    assert np.bincount(face, minlength=3).tolist() == [len(C) // 3] * 3
