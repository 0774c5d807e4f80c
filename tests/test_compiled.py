"""The compiled visibility core against the Python engine (the oracle, issue 28): the same
values within the two bounds on every family of scenes the suite has, closed rows that
sum to 1, the fallback where a bound misses the tolerance, and the convex pieces."""

import numpy as np
import pytest
import shapely
from hypothesis import given

import exactff as ef
from exactff.kernel import mp_form_factor
from exactff.visibility import compiled_core, compiled_form_factors, convex_pieces
from exactff.testing.strategies import enclosures, occluded_scenes

from common import rect_xy
from test_visibility import FURNITURE

# DESIGN 6: an occluded value within 1e-11 of the exact one (absolute)
OCC_ATOL = 1e-11
# open (issue 28): on office rows the engines disagree on some occluded
# values beyond both bounds (office(600) row 183, polygon 345: 4.2e-18 apart, bounds
# 3.6e-19 and 2.2e-19); where such a polygon is wholly visible, mpmath shows the Python
# engine wrong (polygon 530: its value 3.0e-17 off, bound 8.9e-19; the compiled one
# exact to its bound); which one is short on occluded values is not decided yet
UNDECIDED = pytest.mark.xfail(strict=True, reason="engines apart beyond both bounds")

COMPILED = ef.Exact(tolerance=None, engine="compiled")
PYTHON = ef.Exact(engine="python")


def assert_engines_agree(scene, p, n, two_sided=False, closed=False, within_bounds=True,
                         compiled=COMPILED):
    """Both engines' values within the accuracy target and (``within_bounds``) within the
    sum of their bounds; a closed row sums to 1.

    Where the bounds do not cover the gap, mpmath decides for a polygon both engines
    see whole (the unoccluded value at 40 digits): the compiled value must hold there,
    and the Python engine's then misses it by more than its own bound (a defect of the
    oracle, counted in the returned stats as ``oracle_misses``)."""
    st = {}
    F, E = compiled.point_form_factors(scene, p, n, two_sided=two_sided, error=True, stats=st)
    G, H = PYTHON.point_form_factors(scene, p, n, two_sided=two_sided, error=True)
    assert np.all(F >= 0) and np.all(np.isfinite(E)) and np.all(E >= 0)
    gap = np.abs(F - G)
    assert np.all(gap <= OCC_ATOL)
    st["oracle_misses"], undecided = 0, []
    for j in np.flatnonzero(gap > E + H):
        U = float(mp_form_factor(p, n, scene.polygons[j], two_sided=two_sided,
                                 tolerance=1e-30))
        if abs(F[j] - U) <= E[j] and abs(G[j] - U) > H[j]:
            st["oracle_misses"] += 1
        else:
            undecided.append((int(j), F[j], G[j], E[j], H[j]))
    if within_bounds:
        assert undecided == [], undecided
    if closed:
        assert abs(F.sum() - 1.0) <= 1e-12
    return st


def rows_of(scene, k, seed=0):
    rng = np.random.default_rng(seed)
    return rng.choice(len(scene), size=min(k, len(scene)), replace=False)


@given(case=enclosures())
def test_enclosures(case):
    scene, p, n = case
    # convex rooms take the unoccluded kernel in both engines: at the same tolerance
    # (without escalation the kernel's estimate is itself a few times short on some
    # polygons near the horizon: a separate finding, noted on issue 33)
    # the accuracy target and closed sums; within the bounds is the office's open
    # question (hypothesis finds enclosures with boxes where the engines are 3e-17
    # apart against bounds of 8e-18)
    assert_engines_agree(scene, p, n, closed=True, within_bounds=False,
                         compiled=ef.Exact(engine="compiled"))


@given(case=occluded_scenes())
def test_occluded_scenes(case):
    scene, p, n = case
    # the accuracy target, and mpmath where the engines disagree on a wholly visible
    # polygon; hypothesis also finds undecided occluded values (2e-18 apart against
    # bounds 3e-19: the office's open question, pinned there)
    assert_engines_agree(scene, p, n, within_bounds=False)
    assert_engines_agree(scene, p, n, two_sided=True, within_bounds=False)


NAMED = {
    "cornell closed": (lambda: ef.scenes.cornell_box(closed=True), True),
    "cornell open": (lambda: ef.scenes.cornell_box(), False),
    "cornell whole ceiling": (lambda: ef.scenes.cornell_box(ceiling="whole", closed=True), True),
    "building": (lambda: ef.scenes.building(2, 2), True),
    "room with sphere": (lambda: ef.scenes.room_with_sphere(1), True),
    "furnished box": (lambda: ef.scenes.furnished_box(2, FURNITURE[2]), True),
}


@pytest.mark.parametrize("name", ["cornell closed", "cornell open", "cornell whole ceiling",
                                  "building", "furnished box", "room with sphere"])
def test_named_scenes(name):
    make, closed = NAMED[name]
    scene = make()
    for i in rows_of(scene, 8):
        assert_engines_agree(scene, scene.centroids[i], scene.normals[i], closed=closed)


@pytest.mark.parametrize("within_bounds", [False, pytest.param(True, marks=UNDECIDED)])
def test_office_rows(within_bounds):
    scene = ef.scenes.office(600)
    culled = 0
    for i in rows_of(scene, 5):
        st = assert_engines_agree(scene, scene.centroids[i], scene.normals[i], closed=True,
                                  within_bounds=within_bounds)
        culled += st["subtrees_culled"]
    assert culled > 0   # the hierarchy left work out somewhere


def test_cloister_rows_of_every_group():
    scene = ef.scenes.cloister(3000)
    groups = np.array(scene.groups)
    rng = np.random.default_rng(0)
    for g in sorted(set(scene.groups)):
        i = rng.choice(np.flatnonzero(groups == g))
        assert_engines_agree(scene, scene.centroids[i], scene.normals[i])


def test_long_polygon_occludes_and_receives():
    # a 2,000-gon disc over a floor, and a square above it: the disc is convexified
    # for the core (it is convex: kept whole) and an L-shape next to it is triangulated
    t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
    disc = np.column_stack([0.4 * np.cos(t), 0.4 * np.sin(t), np.full_like(t, 0.9)])[::-1]
    L = np.array([[0.5, -1, 1.2], [1, -1, 1.2], [1, 1, 1.2], [0.7, 1, 1.2], [0.7, -0.5, 1.2],
                  [0.5, -0.5, 1.2]])[::-1]
    scene = ef.Scene.from_polygons([disc, L, rect_xy(-1, 1, -1, 1, 2.0)])
    for p in ([0.0, 0, 0], [0.3, 0.2, 0], [0.8, -0.7, 0.5]):
        assert_engines_agree(scene, np.array(p), np.array([0, 0, 1.0]))


def test_compiled_core_matches_python_on_an_exact_construction():
    # a square at height 1 half hidden by a nearer square: the visible part is the
    # rectangle x in [0, 1], y in [0, 1] at z = 1 (a closed form, Howell C-11 corner)
    far = rect_xy(-1, 1, 0, 1, 1.0)
    near = rect_xy(-1, 0, 0, 1, 0.5)  # hides x < 0 of the far square exactly
    scene = ef.Scene.from_polygons([far, near])
    F = COMPILED.point_form_factors(scene, np.zeros(3), np.array([0, 0, 1.0]))
    visible = ef.point_polygon_form_factor([0, 0, 0], [0, 0, 1], rect_xy(0, 1, 0, 1, 1.0))
    assert abs(F[0] - visible) <= 1e-15


def test_a_missed_tolerance_falls_back_to_the_python_engine():
    scene = ef.scenes.cornell_box(closed=True)
    p, n = scene.centroids[1], scene.normals[1]
    st = {}
    # 1e-30 is out of reach: the Python engine returns its bounds (error=True) rather
    # than raise (tests/test_tolerance.py)
    F, E = compiled_form_factors(scene, p, n, tolerance=1e-30, stats=st, error=True)
    assert st["path"] == "compiled, then python" and st["compiled_missed"] > 0
    Fp, Ep = ef.Exact(engine="python", tolerance=1e-30).point_form_factors(scene, p, n,
                                                                          error=True)
    np.testing.assert_array_equal(F, Fp)
    np.testing.assert_array_equal(E, Ep)
    with pytest.raises(ef.NumericalError, match="misses the tolerance 1e-30"):
        compiled_form_factors(scene, p, n, tolerance=1e-30)
    st = {}
    compiled_form_factors(scene, p, n, tolerance=1e-12, stats=st)
    assert st["path"] == "compiled"


def test_rows_in_threads_give_the_same_values():
    from concurrent.futures import ThreadPoolExecutor
    scene = ef.scenes.office(300)
    rows = rows_of(scene, 6)
    one = [COMPILED.point_form_factors(scene, scene.centroids[i], scene.normals[i]) for i in rows]
    with ThreadPoolExecutor(2) as pool:
        two = list(pool.map(lambda i: COMPILED.point_form_factors(
            scene, scene.centroids[i], scene.normals[i]), rows))
    for a, b in zip(one, two):
        np.testing.assert_array_equal(a, b)


def test_convex_pieces_cover_the_polygon_with_its_own_vertices():
    L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0.0]])
    pieces = convex_pieces(L, np.array([0, 0, 1.0]))
    assert len(pieces) == 4
    area = sum(shapely.Polygon(q[:, :2]).area for q in pieces)
    assert area == pytest.approx(3.0, abs=1e-15)
    for q in pieces:
        assert all(any(np.array_equal(v, w) for w in L) for v in q)
        assert np.cross(q[1] - q[0], q[2] - q[0])[2] > 0   # the polygon's winding


def test_core_refuses_inconsistent_arrays():
    scene = ef.scenes.cornell_box()
    tree, core = compiled_core(scene)
    side = np.ones(len(scene), dtype=np.int8)
    with pytest.raises(ValueError, match="node_side"):
        core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(3, np.int8), side, False, True, 8, 0, 0.0)
    with pytest.raises(ValueError, match="source_side"):
        core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(len(tree), np.int8),
                 side[:2], False, True, 8, 0, 0.0)


def test_engine_argument():
    assert ef.Exact().engine == "compiled"
    assert ef.Exact(engine="python").engine == "python"
    assert ef.Exact(integrator="eq3").engine == "python"
    with pytest.raises(ValueError, match="engine"):
        ef.Exact(engine="gpu")
    with pytest.raises(ValueError, match="eq3"):
        ef.Exact(engine="compiled", integrator="eq3")
