"""Spherical point factors (``ef.sphere_form_factors``): unoccluded single polygons against
Van Oosterom and Strackee in mpmath, occluded layers against 2-D boolean constructions
measured in mpmath, enclosures, symmetry, splitting, Monte Carlo, the bounds, bad input."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import exactff as ef
from exactff.kernel import polygon_solid_angles, solid_angle_sums
from exactff.methods.exact import hemisphere_solid_angles
from exactff.testing import assert_form_factors_close
from exactff.testing.mp_reference import solid_angle
from exactff.testing.strategies import convex_polygons, enclosures, planar_polygons, points

from common import examples, random_rotation, rect_xy
from test_visibility import FURNITURE, OCC_ATOL, inside_any_box, layered_reference, layered_scenes

FOUR_PI = 4 * math.pi
# the unoccluded accuracy target (DESIGN 6): 1e-13 + 1e-12 S
UNOCC_ATOL, UNOCC_RTOL = 1e-13, 1e-12
# the reference's own rounding to double (half an ulp: at most 2**-53 relative)
REF_ROUNDING = 2.0 ** -53
EXACT_PYTHON_NO_SHORTCUTS = ef.Exact(shortcuts=False)
PYTHON_ENGINE = ef.Exact(engine="python")


def mp_sphere(p, P):
    """The reference: 40-digit Van Oosterom-Strackee fan over 4 pi."""
    return float(solid_angle(p, P, dps=40) / (4 * np.pi))


# ---------------------------------------------------------------------------------------
# unoccluded single polygons
# ---------------------------------------------------------------------------------------
@settings(max_examples=examples(30))
@given(P=planar_polygons(), p=points(2.0))
def test_sphere_single_polygon_vs_mpmath(P, p):
    scene = ef.Scene.from_polygons([P])
    n = scene.normals[0]
    d = float(n @ (p - scene.centroids[0]))
    # a point off the polygon's plane by more than rounding (in the plane: edge-on, 0)
    assume(abs(d) > 1e-6)
    ref = mp_sphere(p, P)
    S, E = ef.sphere_form_factors(scene, p, error=True)
    # in front: the unoccluded path; behind: both hemispheres through the clipper
    atol = UNOCC_ATOL if d > 0 else OCC_ATOL
    assert_form_factors_close(S, [ref], rtol=UNOCC_RTOL, atol=atol)
    assert abs(S[0] - ref) <= E[0] + REF_ROUNDING * ref, (S[0], ref, E[0])   # the bound holds
    # one-sided: only the front receives
    S1 = ef.sphere_form_factors(scene, p, two_sided=False)
    assert_form_factors_close(S1, [ref if d > 0 else 0.0], rtol=UNOCC_RTOL, atol=atol)


@settings(max_examples=examples(20))
@given(P=convex_polygons(), p=points(2.0))
def test_sphere_single_polygon_through_the_clipper_vs_mpmath(P, p):
    scene = ef.Scene.from_polygons([P])
    assume(abs(float(scene.normals[0] @ (p - scene.centroids[0]))) > 1e-6)
    ref = mp_sphere(p, P)
    S, E = ef.sphere_form_factors(scene, p, error=True, method=EXACT_PYTHON_NO_SHORTCUTS)
    assert_form_factors_close(S, [ref], rtol=0, atol=OCC_ATOL)
    assert abs(S[0] - ref) <= E[0] + REF_ROUNDING * ref, (S[0], ref, E[0])


@pytest.mark.parametrize("height", [1e-5, 1.41706337e-06, 1e-7, 1e-9])
def test_sphere_point_just_behind_a_large_polygon_bound_holds(height):
    # found by hypothesis: a point 1.4e-6 behind a triangle of circumradius 1 came out
    # 4.3e-12 off with a bound of 2.1e-14 (the chart clip's crossings, interpolated
    # between vertices 1 away, had directions off by 1e-10 in the top chart's corners)
    P = np.array([[1.0, 0.0, height], [-0.5, 0.866025404, height], [-0.5, -0.866025404, height]])
    p = np.zeros(3)
    ref = mp_sphere(p, P)
    S, E = ef.sphere_form_factors(ef.Scene.from_polygons([P]), p, error=True)
    assert abs(S[0] - ref) <= E[0], (S[0], ref, E[0])
    assert abs(S[0] - ref) <= UNOCC_ATOL + UNOCC_RTOL * ref


def test_clip_crossing_keeps_its_direction_far_from_the_vertices():
    # an edge at height 1e-6 over the origin, 1 away, met by the plane z = x: the crossing
    # is (1e-6, y, 1e-6) exactly in direction (u = x / z = 1 in the top chart)
    from exactff.halfspace import clip_halfspace

    h = 1e-6
    V = np.array([[[1.0, -0.3, h], [-0.5, 0.8, h], [-0.5, -0.8, h]]])
    W, k = clip_halfspace(V, np.array([3]), np.array([-1.0, 0.0, 1.0]))
    X = W[0, :k[0]]
    on_plane = X[np.abs(X[:, 0] - X[:, 2]) < 1e-3 * h]
    assert len(on_plane) == 2
    assert np.all(np.abs(on_plane[:, 0] / on_plane[:, 2] - 1.0) <= 4 * np.finfo(float).eps)


def test_solid_angle_kernel_vs_mpmath_small_and_far():
    # stiff: a 1e-6 square 1e3 away (the offset form keeps its digits)
    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float) * 1e-6 + [3.0, -2.0, 1e3]
    p = np.array([0.1, 0.2, -0.3])
    w, e = polygon_solid_angles(p, [sq], error=True)
    ref = float(solid_angle(p, sq, dps=60))
    assert abs(w[0] - ref) <= 1e-12 * ref and abs(w[0] - ref) <= e[0]


def test_solid_angle_kernel_of_a_hole_and_a_non_convex_ring():
    # an L-shaped ring (non-convex) at height 1 against its three unit squares' sum
    L = np.array([[0, 0, 1], [2, 0, 1], [2, 1, 1], [1, 1, 1], [1, 2, 1], [0, 2, 1]], float)
    squares = [np.array([[x, y, 1], [x + 1, y, 1], [x + 1, y + 1, 1], [x, y + 1, 1]], float)
               for x, y in ((0, 0), (1, 0), (0, 1))]
    p = np.array([0.3, -0.4, 0.0])
    ref = sum(float(solid_angle(p, q)) for q in squares)
    assert abs(polygon_solid_angles(p, [L])[0] - ref) < 1e-14
    # the kernel on a ring with a vertex count of 3 and the reference vertex's zero offset
    A0 = np.array([[0.0, 0.0, 1.0]])
    E = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    S, _ = solid_angle_sums(A0, E, np.array([1, 2, 0]), np.zeros(3, int), 1)
    assert abs(S[0] - float(solid_angle([0, 0, 0], A0[0] + E))) < 1e-15


# ---------------------------------------------------------------------------------------
# occluded: horizontal layers above and below the point, by 2-D boolean operations
# ---------------------------------------------------------------------------------------
def _layers_both_sides(above, below, R=None):
    """``above`` as drawn (facing down, over the origin) and ``below`` mirrored through
    z = 0 (facing up, under it), rotated by R; and their independent references (the
    mirror's is that of the layers before mirroring)."""
    p = np.zeros(3)

    def measure(ring):
        return float(solid_angle(p, ring, dps=40)) / FOUR_PI

    ref = np.concatenate([layered_reference(p, None, above, measure),
                          layered_reference(p, None, below, measure)])
    mirrored = [P[::-1] * [1.0, 1.0, -1.0] for P in below]
    polys = [P @ R.T if R is not None else P for P in above + mirrored]
    return ef.Scene.from_polygons(polys), ref


@settings(max_examples=examples(15))
@given(above=layered_scenes(), below=layered_scenes(), seed=st.integers(0, 2 ** 32 - 1))
def test_sphere_layers_vs_2d_boolean_construction(above, below, seed):
    R = random_rotation(np.random.default_rng(seed))
    scene, ref = _layers_both_sides(above, below, R)
    S, E = ef.sphere_form_factors(scene, np.zeros(3), error=True)
    assert_form_factors_close(S, ref, rtol=0, atol=OCC_ATOL)
    assert np.all(np.abs(S - ref) <= E + 1e-15)


def test_sphere_layers_example_is_occluded():
    above = [rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0), rect_xy(-1, 1, -1, 1, 2.0),
             rect_xy(0.2, 1.2, -0.3, 0.6, 1.5)]
    below = [rect_xy(-0.3, 0.9, -0.2, 0.4, 0.5), rect_xy(-2, 1, -1, 1.5, 1.2)]
    scene, ref = _layers_both_sides(above, below)
    S = ef.sphere_form_factors(scene, np.zeros(3))
    unocc = polygon_solid_angles(np.zeros(3), scene.polygons) / FOUR_PI
    assert np.all(S[[1, 2, 4]] < unocc[[1, 2, 4]] - 0.005)      # genuinely occluded
    assert_form_factors_close(S, ref, rtol=0, atol=OCC_ATOL)


# ---------------------------------------------------------------------------------------
# enclosures, symmetry, splitting, occluders
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("k", [1, 3])
@pytest.mark.parametrize("method", [ef.Exact(), EXACT_PYTHON_NO_SHORTCUTS, PYTHON_ENGINE])
def test_sphere_cube_centre_sees_a_sixth_per_face(k, method):
    box = ef.scenes.subdivided_box(k)
    S = ef.sphere_form_factors(box, [0.5, 0.5, 0.5], method=method)
    faces = S.reshape(6, k * k).sum(axis=1)
    # symmetry: each face subtends 4 pi / 6 exactly
    assert_form_factors_close(faces, np.full(6, 1 / 6), rtol=UNOCC_RTOL, atol=UNOCC_ATOL)


def test_sphere_closed_cornell_box_rows_sum_to_one():
    scene = ef.scenes.cornell_box(closed=True)
    pts = np.array([[278, 273, 279.6], [100, 400, 100], [450, 30, 500], [278, 548.7, 279.6]])
    pts[3, 1] -= 1.0          # just under the light
    S, E = ef.sphere_form_factors(scene, pts, error=True)
    assert S.shape == (4, len(scene)) and np.all(S >= 0)
    off = np.abs(S.sum(axis=1) - 1)
    assert np.all(off <= OCC_ATOL) and np.all(off <= E.sum(axis=1) + 1e-15)


@pytest.mark.parametrize("boxes", FURNITURE)
def test_sphere_furnished_box_sums_to_one(boxes):
    scene = ef.scenes.furnished_box(2, boxes)
    rng = np.random.default_rng(7)
    pts = []
    while len(pts) < 3:
        x = rng.uniform(0.02, 0.98, 3)
        if not inside_any_box(x, boxes):
            pts.append(x)
    S, E = ef.sphere_form_factors(scene, np.array(pts), error=True)
    assert_form_factors_close(S.sum(axis=1), np.ones(3), rtol=0, atol=OCC_ATOL)
    # the obstacles hide something: some value is below its unoccluded one
    unocc = polygon_solid_angles(pts[0], scene.polygons) / FOUR_PI
    assert np.any(S[0] < unocc - 1e-3)


@settings(max_examples=examples(10))
@given(case=enclosures(max_boxes=2, max_k=2))
def test_sphere_enclosures_sum_to_one(case):
    scene, point, _ = case
    S, E = ef.sphere_form_factors(scene, point, error=True)
    assert np.all(S >= 0) and np.all(np.isfinite(S))
    assert abs(S.sum() - 1) <= max(OCC_ATOL, E.sum()) + 1e-15, (S.sum(), E.sum())


def test_sphere_office_sensor_sums_to_one():
    scene = ef.scenes.office(600)
    S, E = ef.sphere_form_factors(scene, [[2.5, 1.1, 2.6], [4.2, 0.4, 3.6]], error=True)
    assert_form_factors_close(S.sum(axis=1), np.ones(2), rtol=0, atol=OCC_ATOL)
    floor = np.array(scene.groups) == "floor"
    # the desks hide part of the floor: less than the unoccluded floor
    unocc = polygon_solid_angles([2.5, 1.1, 2.6], scene.polygons) / FOUR_PI
    assert S[0, floor].sum() < unocc[floor].sum() - 0.01


def test_sphere_splitting_a_polygon_keeps_its_total():
    occluder = rect_xy(-0.3, 0.4, -0.2, 0.5, 0.6)
    whole = rect_xy(-1, 1, -1, 1, 1.5)
    halves = [rect_xy(-1, 0.13, -1, 1, 1.5), rect_xy(0.13, 1, -1, 1, 1.5)]
    below = [rect_xy(-1, 1, -1, 1, -0.7, facing_down=False)]
    p = np.array([0.05, -0.02, 0.0])
    S1 = ef.sphere_form_factors(ef.Scene.from_polygons([occluder, whole] + below), p)
    S2 = ef.sphere_form_factors(ef.Scene.from_polygons([occluder] + halves + below), p)
    assert abs(S1[1] - (S2[1] + S2[2])) <= OCC_ATOL
    assert abs(S1[0] - S2[0]) <= OCC_ATOL and abs(S1[2] - S2[3]) <= OCC_ATOL


@settings(max_examples=examples(15))
@given(P=convex_polygons(), Q=convex_polygons(), p=points(2.0))
def test_sphere_adding_an_occluder_never_raises_a_value(P, Q, p):
    alone = ef.Scene.from_polygons([P])
    both = ef.Scene.from_polygons([P, Q])
    for sc in (alone, both):
        assume(np.all(np.abs(np.einsum("ij,ij->i", sc.normals, p - sc.centroids)) > 1e-6))
    S1, E1 = ef.sphere_form_factors(alone, p, error=True)
    S2, E2 = ef.sphere_form_factors(both, p, error=True)
    assert S2[0] <= S1[0] + E1[0] + E2[0]
    assert S2.sum() <= 1 + E2.sum()


def test_sphere_shortcuts_are_neutral():
    scene = ef.scenes.subdivided_box(2)
    for p in ([0.5, 0.5, 0.5], [0.1, 0.7, 0.3], [0.999, 0.01, 0.5]):
        a, ea = ef.sphere_form_factors(scene, p, error=True)
        b, eb = ef.sphere_form_factors(scene, p, error=True, method=EXACT_PYTHON_NO_SHORTCUTS)
        assert np.all(np.abs(a - b) <= ea + eb)
        assert_form_factors_close(b, a, rtol=0, atol=1e-14)


def test_sphere_hemispheres_add_up():
    # (both engine names are served by the Python engine, as hemisphere_solid_angles
    # documents; the compiled core's whole-sphere rows are compared with it below)
    scene = ef.scenes.cornell_box(closed=True)
    p = np.array([200.0, 300.0, 250.0])
    halves = [hemisphere_solid_angles(scene, p, n) for n in ([0, 0, 1.0], [0, 0, -1.0])]
    total = halves[0][0] + halves[1][0]
    assert abs(total.sum() - FOUR_PI) <= 1e-11
    # any frame: the hemispheres about x give the same sphere
    other = sum(hemisphere_solid_angles(scene, p, n)[0] for n in ([1.0, 0, 0], [-1.0, 0, 0]))
    assert_form_factors_close(other / FOUR_PI, total / FOUR_PI, rtol=0, atol=OCC_ATOL)


def test_sphere_rows_broadcast_vs_loop():
    scene = ef.scenes.furnished_box(1, FURNITURE[0])
    pts = np.array([[[0.1, 0.1, 0.1], [0.8, 0.9, 0.2]], [[0.5, 0.05, 0.9], [0.9, 0.5, 0.5]]])
    S = ef.sphere_form_factors(scene, pts)
    assert S.shape == (2, 2, len(scene))
    for idx in np.ndindex(2, 2):
        assert np.array_equal(S[idx], ef.sphere_form_factors(scene, pts[idx]))


# ---------------------------------------------------------------------------------------
# Monte Carlo over the sphere
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1])
def test_sphere_monte_carlo_within_five_standard_errors(seed):
    scene = ef.scenes.cornell_box(closed=True)
    p = [150.0, 200.0, 300.0]
    S = ef.sphere_form_factors(scene, p)
    M, se = ef.sphere_form_factors(scene, p, method="monte_carlo", samples=100_000,
                                   seed=seed, error=True)
    assert abs(M.sum() - 1) < 1e-12           # every ray hits something in a closed box
    assert np.all(np.abs(M - S) <= 5 * np.maximum(se, np.sqrt(S * (1 - S) / 100_000)) + 1e-12)
    # reproducible: the same seed and point give the same row
    assert np.array_equal(M, ef.sphere_form_factors(scene, p, method=ef.MonteCarlo(
        100_000, seed=seed)))


def test_sphere_monte_carlo_one_sided_open_scene():
    # a single square seen from behind: two-sided it is seen, one-sided it is not
    scene = ef.Scene.from_polygons([rect_xy(-1, 1, -1, 1, 1.0, facing_down=False)])
    p = np.zeros(3)
    ref = mp_sphere(p, scene.polygons[0])
    M, se = ef.sphere_form_factors(scene, p, method="monte_carlo", samples=50_000, error=True)
    assert abs(M[0] - ref) <= 5 * se[0]
    assert ef.sphere_form_factors(scene, p, method="monte_carlo", two_sided=False)[0] == 0.0


# ---------------------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------------------
def test_sphere_bad_arguments():
    box = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match="points"):
        ef.sphere_form_factors(box, [0.5, np.nan, 0.5])
    with pytest.raises(ValueError, match="points"):
        ef.sphere_form_factors(box, [0.5, 0.5])
    with pytest.raises(ValueError, match="method"):
        ef.sphere_form_factors(box, [0.5, 0.5, 0.5], method="hemicube")
    with pytest.raises(ValueError, match="tolerance"):
        ef.sphere_form_factors(box, [0.5, 0.5, 0.5], tolerance=-1.0)
    with pytest.raises(ValueError, match="tolerance"):
        ef.sphere_form_factors(box, [0.5, 0.5, 0.5], method="monte_carlo", tolerance=1e-9)
    with pytest.raises(ValueError, match="two_sided"):
        ef.sphere_form_factors(box, [0.5, 0.5, 0.5], two_sided="yes")
    with pytest.raises(ValueError, match="engine"):
        hemisphere_solid_angles(box, np.full(3, 0.5), np.array([0, 0, 1.0]), engine="gpu")


def test_sphere_point_on_a_wall_sees_the_rest_as_a_half_sphere():
    # on the floor of a closed box (in its plane): the floor is edge-on (0), the other
    # faces fill the upper half of the sphere
    box = ef.scenes.subdivided_box(1)
    S = ef.sphere_form_factors(box, [0.5, 0.5, 0.0])
    floor = int(np.argmin(np.abs(box.centroids[:, 2])))
    assert S[floor] == 0.0
    assert_form_factors_close(S.sum(), 0.5, rtol=0, atol=OCC_ATOL)


# ---------------------------------------------------------------------------------------
# the command line: exactff matrix --sphere
# ---------------------------------------------------------------------------------------
def test_cli_matrix_sphere_from_points_and_centroids(tmp_path, capsys):
    from exactff.cli import main

    pts = np.array([[0.5, 0.5, 0.5], [0.2, 0.7, 0.4]])
    (tmp_path / "pts.txt").write_text("# x y z\n0.5 0.5 0.5\n0.2, 0.7, 0.4\n")
    np.save(tmp_path / "pts.npy", pts)
    box = ef.scenes.subdivided_box(2)
    for src in ("pts.txt", "pts.npy"):
        out = tmp_path / f"S_{src[-3:]}.npy"
        assert main(["matrix", "box:2", "--sphere", "--points", str(tmp_path / src), "-o",
                     str(out), "--no-progress"]) == 0
        S = np.load(out)
        assert np.array_equal(S, ef.sphere_form_factors(box, pts))
        assert np.load(tmp_path / f"S_{src[-3:]}.error.npy").shape == S.shape
    assert "from 2 points" in capsys.readouterr().out
    # from the centroids: each polygon edge-on from its own, the half in front seen
    out = tmp_path / "C.npy"
    assert main(["matrix", "box:2", "--sphere", "--rows", "0,5", "-o", str(out),
                 "--no-progress"]) == 0
    C = np.load(out)
    assert C.shape == (2, 24) and C[0, 0] == 0 and C[1, 5] == 0
    assert_form_factors_close(C.sum(axis=1), [0.5, 0.5], rtol=0, atol=1e-13)
    # front only: from outside the box, nothing faces the point (the faces face in)
    out = tmp_path / "F.npy"
    (tmp_path / "far.txt").write_text("3 3 3\n")
    assert main(["matrix", "box:2", "--sphere", "--front-only", "--points",
                 str(tmp_path / "far.txt"), "-o", str(out), "--no-progress"]) == 0
    assert np.load(out).sum() == 0.0


def test_cli_matrix_sphere_bad_arguments(tmp_path, capsys):
    from exactff.cli import main

    (tmp_path / "bad.txt").write_text("1 2\n")
    (tmp_path / "ok.txt").write_text("0.5 0.5 0.5\n")
    cases = [(["--sphere", "--points", str(tmp_path / "bad.txt")], "--points"),
             (["--sphere", "--points", str(tmp_path / "missing.txt")], "--points"),
             (["--points", str(tmp_path / "ok.txt")], "--sphere"),
             (["--sphere", "--jobs", "2"], "--sphere"),
             (["--sphere", "--points", str(tmp_path / "ok.txt"), "--rows", "0:2"], "--rows")]
    for extra, word in cases:
        assert main(["matrix", "box:1", "-o", str(tmp_path / "x.npy"), "--no-progress"]
                    + extra) == 2
        assert word in capsys.readouterr().err


# ---------------------------------------------------------------------------------------
# the compiled core's sphere mode against the Python engine's two hemispheres (its oracle)
# ---------------------------------------------------------------------------------------
def _both_engines(scene, p, two_sided=True):
    """The compiled whole-sphere row and the Python engine's, each with its bounds."""
    st = {}
    a, ea = ef.Exact().point_sphere_factors(scene, p, two_sided=two_sided, stats=st,
                                            error=True)
    b, eb = PYTHON_ENGINE.point_sphere_factors(scene, p, two_sided=two_sided, error=True)
    return st, a, ea, b, eb


def _assert_engines_agree(st, a, ea, b, eb):
    assert st["path"] == "compiled sphere", st["path"]
    assert np.all(a >= 0) and np.all(np.isfinite(ea))
    # both bounds within the accuracy target of occluded values (a loose bound would let
    # anything pass below), and the values within the target or the sum of the bounds
    # (the Python engine's leaves its clipper's topology out: where a sliver's side is
    # decided within rounding, as test_compiled's comparison has it; the independent
    # references are the mpmath and boolean constructions above)
    assert np.all(ea <= OCC_ATOL) and np.all(eb <= OCC_ATOL), (ea.max(), eb.max())
    gap = np.abs(a - b)
    bad = np.flatnonzero(~(gap <= np.maximum(OCC_ATOL, ea + eb)))
    assert len(bad) == 0, (bad[:5], a[bad[:5]], b[bad[:5]], ea[bad[:5]], eb[bad[:5]])


@pytest.mark.parametrize("p", [[2.5, 1.1, 2.6], [4.2, 0.4, 3.6], [1.3, 2.2, 0.7]])
def test_compiled_sphere_office_vs_python_engine(p):
    scene = ef.scenes.office(600)
    st, a, ea, b, eb = _both_engines(scene, np.array(p))
    _assert_engines_agree(st, a, ea, b, eb)
    # occluded (the desks hide part of the floor), and a whole sphere: a row sums to 1
    assert st["hidden_pieces"] > 0
    assert abs(a.sum() - 1) <= max(ea.sum(), 1e-15)
    # one-sided: only the polygons facing the point receive, by both engines
    _assert_engines_agree(*_both_engines(scene, np.array(p), two_sided=False))


@settings(max_examples=examples(10), deadline=None)
@given(above=layered_scenes(), below=layered_scenes(), seed=st.integers(0, 2 ** 32 - 1))
def test_compiled_sphere_layers_vs_python_engine(above, below, seed):
    # rotated layers on both sides of the point: pieces across the core's horizon plane
    R = random_rotation(np.random.default_rng(seed))
    scene, _ = _layers_both_sides(above, below, R)
    _assert_engines_agree(*_both_engines(scene, np.zeros(3)))


@pytest.mark.parametrize("boxes", FURNITURE)
def test_compiled_sphere_furnished_box_vs_python_engine(boxes):
    scene = ef.scenes.furnished_box(2, boxes)
    rng = np.random.default_rng(11)
    done = 0
    while done < 2:
        x = rng.uniform(0.02, 0.98, 3)
        if inside_any_box(x, boxes):
            continue
        st, a, ea, b, eb = _both_engines(scene, x)
        _assert_engines_agree(st, a, ea, b, eb)
        assert abs(a.sum() - 1) <= max(ea.sum(), 1e-15)
        done += 1


def test_compiled_sphere_polygon_behind_a_polygon_vs_mpmath():
    # a square hidden in part by a smaller one in front, below the core's horizon (and,
    # rotated, across it): the visible part is the big square minus the small one's image,
    # whose solid angle is the difference of the two (the small one wholly inside)
    small = rect_xy(-0.2, 0.3, -0.25, 0.15, -1.0, facing_down=False)
    big = rect_xy(-1.0, 1.0, -1.0, 1.0, -2.0, facing_down=False)
    for R in (np.eye(3), random_rotation(np.random.default_rng(5))):
        polys = [small @ R.T, big @ R.T]
        scene = ef.Scene.from_polygons(polys)
        p = np.zeros(3)
        # the small square's image lies inside the big one's: its shadow on the plane
        # z = -2 is the square scaled by 2, within [-1, 1]^2
        ref_small = mp_sphere(p, polys[0])
        ref_big = mp_sphere(p, polys[1]) - mp_sphere(p, (small * 2.0) @ R.T)
        S, E = ef.sphere_form_factors(scene, p, error=True)
        assert abs(S[0] - ref_small) <= E[0] and abs(S[1] - ref_big) <= E[1], (S, E)
        assert_form_factors_close(S, [ref_small, ref_big], rtol=0, atol=OCC_ATOL)
