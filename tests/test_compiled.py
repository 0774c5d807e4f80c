"""The compiled visibility core against the Python engine (the oracle, issue 28): the same
values within the two bounds on every family of scenes the suite has, closed rows that
sum to 1, the fallback where a bound misses the tolerance, and the convex pieces."""

import math
from fractions import Fraction

import mpmath
import numpy as np
import pytest
import shapely
from hypothesis import assume, given
from hypothesis import strategies as hst

import exactff as ef
from exactff import _tolerances as tol
from exactff.kernel import flat_polygons
from exactff.predicates import engine_sides
from exactff.visibility import compiled_core, compiled_form_factors, convex_pieces
from exactff.visibility.bsp import node_sides
from exactff.testing.strategies import enclosures, flush_faces, occluded_scenes

from common import rect_xy
from exact_visibility import polygon_form_factor_mp, unoccluded_form_factor, visible_form_factor
from test_visibility import FURNITURE

# DESIGN 6: an occluded value within 1e-11 of the exact one (absolute)
OCC_ATOL = 1e-11
# Where the engines' bounds did not cover their gap on office rows, the exact visible part
# (tests/exact_visibility.py) decides. office(600) from (7.5, 1.8, 6): floor tile 174
# shows a sliver of 2.4e-32 m^2 past polygon 461, F = 2.0412e-34; the compiled core gives
# 2.0451e-34 +- 1.3e-34, the Python engine gave 0 +- 0 (and missed its bound on polygons
# 175, 284 and 452 of that row, 2.6-29x) until its refinement took each edge's nearest
# plane among the images in front and charged the others (issue 48): it holds its bound
# there now.

COMPILED = ef.Exact(tolerance=None, engine="compiled")
PYTHON = ef.Exact(engine="python")


def assert_engines_agree(scene, p, n, two_sided=False, closed=False, within_bounds=True,
                         compiled=COMPILED, every_value=False):
    """Both engines' values within the accuracy target and (``within_bounds``) within the
    sum of their bounds; a closed row sums to 1.

    Where the bounds do not cover the gap, an independent value decides: the visible part
    constructed in rationals and integrated in mpmath (``exact_visibility``), where the
    polygons are convex and exactly planar; else, for a polygon nothing hides (checked in
    rationals: ``exact_visibility.seen_whole``), the unoccluded value at 60 digits. Both
    bounds must be within the accuracy target ``OCC_ATOL``. The compiled value must hold against a value so
    constructed; the Python engine's misses beyond its own bound are a defect of the
    oracle, counted in the returned stats as ``oracle_misses``. With ``every_value``, every
    value the construction decides is checked so, not only where the bounds part."""
    st = {}
    F, E = compiled.point_form_factors(scene, p, n, two_sided=two_sided, error=True, stats=st)
    G, H = PYTHON.point_form_factors(scene, p, n, two_sided=two_sided, error=True)
    assert np.all(F >= 0) and np.all(np.isfinite(E)) and np.all(E >= 0)
    # each side's bound within the accuracy target (DESIGN 6): a bound of 0.5 would let an
    # engine that ignores occlusion pass the comparison below (issue 50, item 1)
    assert np.all(E <= OCC_ATOL), (int(np.argmax(E)), float(np.max(E)))
    assert np.all(H <= OCC_ATOL), (int(np.argmax(H)), float(np.max(H)))
    gap = np.abs(F - G)
    # the accuracy target, or bounds that say it is not reached: ``compiled`` runs with
    # tolerance=None (no escalation; its honest bound is the contract), and the default
    # one falls back where a bound is above the tolerance (test_values_within_their_...)
    assert np.all(gap <= np.maximum(OCC_ATOL, E + H))
    st["oracle_misses"], st["decided"], undecided = 0, 0, []
    parted = gap > E + H
    for j in range(len(scene)) if every_value else np.flatnonzero(parted):
        U = visible_form_factor(scene, p, n, j, two_sided=two_sided)
        if U is not None:
            assert abs(F[j] - U) <= E[j], (int(j), F[j], float(U), E[j])
            st["oracle_misses"] += int(abs(G[j] - U) > H[j])
            st["decided"] += 1
            continue
        if not parted[j]:
            continue
        # a polygon nothing hides from p (checked in rationals: seen_whole): its whole
        # value by the contour form at 60 digits, kept as an mpf (a double's rounding of
        # it is half an ulp: more than the bounds it decides)
        U = unoccluded_form_factor(scene, p, n, j, two_sided=two_sided)
        if U is not None and abs(F[j] - U) <= E[j] and abs(G[j] - U) > H[j]:
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
    # convex rooms take the unoccluded kernel in both engines: at the same tolerance;
    # where the bounds do not cover the gap the exact construction decides (600 drawn
    # enclosures all within the bounds, after the kernel's offsets' rounding was charged)
    assert_engines_agree(scene, p, n, closed=True, compiled=ef.Exact(engine="compiled"))


@given(case=occluded_scenes())
def test_occluded_scenes(case):
    scene, p, n = case
    # the accuracy target, and every value the exact construction decides: the compiled
    # value must hold against it (DECIDED below came from here). Undecided cases remain:
    # rotated polygons that are not exactly planar and reach into each other's range,
    # images that are not convex, and points within rounding of a plane (edge-on by the
    # engines' convention)
    assert_engines_agree(scene, p, n, within_bounds=False, every_value=True)
    assert_engines_agree(scene, p, n, two_sided=True, within_bounds=False, every_value=True)


NAMED = {
    "cornell closed": (lambda: ef.scenes.cornell_box(closed=True), True),
    "cornell open": (lambda: ef.scenes.cornell_box(), False),
    "cornell whole ceiling": (lambda: ef.scenes.cornell_box(ceiling="whole", closed=True), True),
    "building": (lambda: ef.scenes.building(2, 2), True),
    "room with sphere": (lambda: ef.scenes.room_with_sphere(1), True),
    "furnished box": (lambda: ef.scenes.furnished_box(2, FURNITURE[2]), True),
    "vaulted hall": (lambda: ef.scenes.vaulted_hall(2, 16, 8), True),
}


@pytest.mark.parametrize("name", ["cornell closed", "cornell open", "cornell whole ceiling",
                                  "building", "furnished box", "room with sphere",
                                  "vaulted hall"])
def test_named_scenes(name):
    make, closed = NAMED[name]
    scene = make()
    for i in rows_of(scene, 8):
        assert_engines_agree(scene, scene.centroids[i], scene.normals[i], closed=closed)


def test_office_rows():
    scene = ef.scenes.office(600)
    culled = misses = 0
    for i in rows_of(scene, 5):
        st = assert_engines_agree(scene, scene.centroids[i], scene.normals[i], closed=True)
        culled += st["subtrees_culled"]
        misses += st["oracle_misses"]
    assert culled > 0   # the hierarchy left work out somewhere
    assert misses == 0  # the oracle within its own bound wherever the reference decided


# Scenes hypothesis found (occluded_scenes) where the compiled core's bound missed the
# exact value (tests/exact_visibility.py) before the BSP build's rounded crossings were
# charged (Builder::crossing, Core::input_error and input_tilt), and one where the Python
# engine is wrong. Each: polygons, point, normal.
DECIDED = {
    # polygon 2 pierces polygon 0: its visible part ends at the split, whose crossing was
    # rounded by an ulp (6.5e-19 off, bound 1.6e-19, two-sided)
    "a split bounds the visible part": (
        [[[2.25, 1.0, 2.25], [-1.1249999999999996, -0.948557158514987, 2.25],
          [-1.1250000000000009, 2.948557158514986, 2.25]],
         [[0.375, 1.0, 0.75], [-0.30338137289060524, 0.7795805303903225, 0.75],
          [0.11588137289060521, 1.3566461936106826, 0.75]],
         [[0.5, 1.0, 1.6339745962155612], [-0.2499999999999999, 1.8660254037844388,
                                           2.933012701892219],
          [-0.2500000000000002, 0.13397459621556163, 2.9330127018922196]]],
        [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
    # polygon 3 is split by polygon 2's plane, and its split edge bounds the shadow it
    # casts on polygon 2 (7.6e-19 off, bound 2.8e-19, two-sided, with the crossings
    # charged but not yet the tilt of the shadow planes through them)
    "a split bounds a shadow": (
        [[[1.7886780300098506, 1.228293256202952, -0.5403023058681398],
          [1.1203052382129253, 1.6574504905071719, 0.9988864023252176],
          [0.3328305669860627, 2.163082162137255, -0.4585840964570775]],
         [[0.8943390150049253, 0.614146628101476, -0.2701511529340699],
          [0.5601526191064626, 0.8287252452535859, 0.4994432011626088],
          [0.16641528349303136, 1.0815410810686275, -0.22929204822853874]],
         [[1.214358014063841, 3.1016182978015863, -1.2684893393762895],
          [1.572021077170966, 3.6294526648438463, -0.5628148312314936],
          [1.660084257401898, 3.063870986626743, -0.42919692687258604]],
         [[3.307204907085631, 2.0358510200019557, -1.0806046117362795],
          [0.39550998103805624, 3.9054288318705614, -0.9171681929141562],
          [1.9704593234917793, 2.8941654886103962, 1.9977728046504353]]],
        [0.0, 0.0, 0.0], [0.5403023058681398, 0.8414709848078965, 0.0]),
    # the occluder is the far pentagon scaled by 1/3 towards the point, both rounded:
    # a sliver of 2.15e-18 shows (the Python engine: 0 +- 0)
    "a scaled copy nearly hides the far polygon": (
        [[[3.348076211353316, 0.0, 0.20096189432334233],
          [2.829838957134527, -1.4265847744427302, 1.0985751490052742],
          [1.9913134655721056, -0.8816778784387098, 2.5509439038330552],
          [1.9913134655721054, 0.8816778784387096, 2.5509439038330557],
          [2.8298389571345264, 1.4265847744427305, 1.0985751490052744]],
         [[1.1160254037844388, 0.0, 0.06698729810778076],
          [0.9432796523781756, -0.47552825814757677, 0.3661917163350914],
          [0.6637711551907018, -0.2938926261462366, 0.8503146346110184],
          [0.6637711551907018, 0.2938926261462365, 0.8503146346110186],
          [0.9432796523781755, 0.4755282581475768, 0.36619171633509146]]],
        [0.0, 0.0, 0.0], [0.8660254037844387, 0.0, 0.5000000000000001]),
    # polygons 2 and 3 are one triangle in z = 2.5, mirrored in y (so each vertex rounds
    # its own way) and facing opposite ways: the one facing away is behind (the rule for
    # depth ties) but for a sliver of 9.6e-17 (the Python engine: 0 +- 0)
    "a mirrored coincident triangle": (
        [[[1.0, 0.0, 2.0], [-0.4999999999999998, -0.8660254037844387, 2.0],
          [-0.5000000000000004, 0.8660254037844384, 2.0]],
         [[0.5, 0.0, 1.0], [-0.2499999999999999, -0.43301270189221935, 1.0],
          [-0.2500000000000002, 0.4330127018922192, 1.0]],
         [[2.0, 0.0, 2.5], [-0.9999999999999996, -1.7320508075688774, 2.5],
          [-1.0000000000000009, 1.7320508075688767, 2.5]],
         [[2.0, 0.0, 2.5], [-0.9999999999999996, 1.7320508075688774, 2.5],
          [-1.0000000000000009, -1.7320508075688767, 2.5]]],
        [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    # polygons 2 and 3 cross at an angle of 1e-8: the crossing slides along polygon 3's
    # edge by 1e-9 (bound 9e-9), and polygon 2's value is 2.3e-10 off with a bound of
    # 2.6e-9; the default tolerance falls back to the Python engine, exact here
    "a grazing split": (
        [[[1.0, 0.0, 2.0], [-0.4999999999999998, -0.8660254037844387, 2.0],
          [-0.5000000000000004, 0.8660254037844384, 2.0]],
         [[0.5, 0.0, 1.0], [-0.2499999999999999, -0.43301270189221935, 1.0],
          [-0.2500000000000002, 0.4330127018922192, 1.0]],
         [[2.0, 0.0, 2.500000014901161], [0.5000000000000002, -0.8660254037844387,
                                          2.4999999925494194],
          [0.49999999999999967, 0.8660254037844384, 2.4999999925494194]],
         [[2.0, 0.0, 2.5], [0.5000000000000002, 0.8660254037844387, 2.5],
          [0.49999999999999956, -0.8660254037844384, 2.5]]],
        [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
}


@pytest.mark.parametrize("two_sided", [False, True])
@pytest.mark.parametrize("name", sorted(DECIDED))
def test_values_within_their_bounds_of_the_exact_visible_part(name, two_sided):
    polygons, p, n = DECIDED[name]
    scene = ef.Scene([np.array(P) for P in polygons])
    F, E = COMPILED.point_form_factors(scene, p, n, two_sided=two_sided, error=True)
    for j in range(len(scene)):
        U = visible_form_factor(scene, p, n, j, two_sided=two_sided)
        assert U is not None
        assert abs(F[j] - U) <= E[j], (j, F[j], float(U), E[j])
    # at the default tolerance, the accuracy target (by a fallback where needed)
    D = ef.Exact().point_form_factors(scene, p, n, two_sided=two_sided)
    for j in range(len(scene)):
        assert abs(D[j] - visible_form_factor(scene, p, n, j, two_sided=two_sided)) <= OCC_ATOL
    # and the engines' comparison holds where it decides with that construction. Not on
    # the grazing split: its compiled bound (1.7e-9 one-sided, 1.9e-9 two-sided, on
    # polygons 2 and 3) is above OCC_ATOL, at tolerance=None and at the default tolerance
    # too, whose fallback adds the compiled tree's crossing bound to the Python engine's
    # (issue 48); its values are checked against the exact construction above
    if name != "a grazing split":
        assert_engines_agree(scene, p, n, two_sided=two_sided)


def test_a_triangle_with_a_hole_within_its_bound():
    # a small triangle at z = 1 casts a hole wholly inside a triangle at z = 2, no BSP
    # split. Once pinned as a strict xfail: the reference's sum was rounded to a double
    # (mpmath's default precision), off by 7.2e-18 against a bound of 1.2e-17 for the
    # compiled value; at the working precision the compiled value is the nearest double
    # (its long double pieces' sum is off by 3e-21)
    polygons = [[[1.0, 0.0, 2.0], [-0.4999999999999998, -0.8660254037844387, 2.0],
                 [-0.5000000000000004, 0.8660254037844384, 2.0]],
                [[0.125, 0.0, 1.0], [-0.06249999999999997, -0.10825317547305484, 1.0],
                 [-0.06250000000000006, 0.1082531754730548, 1.0]]]
    scene = ef.Scene([np.array(P) for P in polygons])
    p, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    F, E = COMPILED.point_form_factors(scene, p, n, error=True)
    U = visible_form_factor(scene, p, n, 0)
    assert abs(F[0] - U) <= E[0]


def test_split_vertices_carry_their_rounding():
    # the compiled build's crossings are within their bound of the exact crossing (in
    # rationals: the edge's with the splitter's plane, exact for these axis planes and
    # for polygon 0's plane z = 2.25), and the input's own vertices have none
    from fractions import Fraction
    polygons, _, _ = DECIDED["a split bounds the visible part"]
    scene = ef.Scene([np.array(P) for P in polygons])
    tree, _ = compiled_core(scene)
    inputs = {tuple(v) for P in polygons for v in P}
    crossings = 0
    for P, errors in zip(tree.fragments, tree.vertex_errors):
        for v, e in zip(P.tolist(), errors):
            if tuple(v) in inputs:
                assert e == 0
                continue
            crossings += 1
            # on polygon 2's edge through its first vertex, at z = 2.25 exactly
            A, B = ([Fraction(c) for c in polygons[2][0]],
                    [Fraction(c) for c in polygons[2][1 if v[1] > 1 else 2]])
            t = (Fraction(2.25) - A[2]) / (B[2] - A[2])
            exact = [a + t * (b - a) for a, b in zip(A, B)]
            off = math.sqrt(sum(float(Fraction(x) - y) ** 2 for x, y in zip(v, exact)))
            assert 0 < e <= 1e-14 and off <= e   # an honest bound, and a tight one
    assert crossings == 4


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


def test_a_missed_tolerance_falls_back_to_the_python_engine_per_polygon():
    scene = ef.scenes.cornell_box(closed=True)
    p, n = scene.centroids[1], scene.normals[1]
    st = {}
    # 1e-30 is out of reach: the Python engine returns its bounds (error=True) rather
    # than raise (tests/test_tolerance.py); only the values that missed are its
    F, E = compiled_form_factors(scene, p, n, tolerance=1e-30, stats=st, error=True)
    assert st["path"] == "compiled, python for some polygons"
    missed = st["compiled_missed"]
    assert missed > 0 and st["python_polygons"] == missed
    Fc, Ec = compiled_form_factors(scene, p, n, error=True)
    Fp, Ep = ef.Exact(engine="python", tolerance=1e-30).point_form_factors(scene, p, n,
                                                                          error=True)
    taken = F != Fc
    assert 0 < taken.sum() <= missed
    np.testing.assert_array_equal(F[taken], Fp[taken])
    # its bounds, and the compiled tree's measure of the BSP crossings' rounding, which
    # the Python engine's bound leaves out
    assert np.all(E[taken] >= Ep[taken])
    assert st["max_crossing_bound"] > 0   # the closed box's BSP splits some polygons
    with pytest.raises(ef.NumericalError, match="misses the tolerance 1e-30"):
        compiled_form_factors(scene, p, n, tolerance=1e-30)
    st = {}
    compiled_form_factors(scene, p, n, tolerance=1e-12, stats=st)
    assert st["path"] == "compiled"


def test_a_missed_tolerance_on_a_large_scene_raises_at_once(monkeypatch):
    # above COMPILED_FALLBACK_MAX_POLYGONS the Python engine never takes the whole
    # scene, only the missed values' shafts, and those only where they hold at most
    # that many polygons in all (the compiled core's shafts, SHAFT_COMPILED_MAX_POLYGONS,
    # alike): here (1e-30, every value missed) they hold more, and the row raises at
    # once naming the polygon, or is returned with its bounds
    import exactff.visibility.compiled as compiled
    from exactff import _tolerances

    scene = ef.scenes.cornell_box(closed=True)
    p, n = scene.centroids[1], scene.normals[1]
    monkeypatch.setattr(_tolerances, "COMPILED_FALLBACK_MAX_POLYGONS", len(scene) - 1)
    monkeypatch.setattr(_tolerances, "SHAFT_COMPILED_MAX_POLYGONS", len(scene) - 1)

    def no_python(*args, **kwargs):
        raise AssertionError("the Python engine was called")

    monkeypatch.setattr(compiled, "visible_form_factors", no_python)
    with pytest.raises(ef.NumericalError, match=r"polygon \d+: .* in the compiled core"):
        compiled_form_factors(scene, p, n, tolerance=1e-30)
    st = {}
    F, E = compiled_form_factors(scene, p, n, tolerance=1e-30, stats=st, error=True)
    Fc, Ec = compiled_form_factors(scene, p, n, error=True)
    assert np.all(np.abs(F - Fc) <= E + Ec) and np.all(np.isfinite(E))
    assert st["compiled_missed"] > 0 and "python_polygons" not in st
    assert st["shaft_polygons"] == 0 and "shaft_sizes" not in st


@pytest.mark.parametrize("core_settles", [True, False])
def test_a_value_the_core_leaves_unsettled_is_settled_on_its_shaft(monkeypatch, core_settles):
    # a large scene's value whose compiled bound misses (here: its rounded crossings'
    # part set above the accuracy target of occluded values) is recomputed on its shaft,
    # the polygons reaching into the hull of the point and it: by the compiled core on
    # the shaft's own tree, or where that misses too (planted in every tree), by the
    # Python engine. The closed Cornell box from inside, the floor seen past the two
    # blocks. The value must agree with the whole scene's Python engine and with the
    # core's own within the bounds, from a sub-scene smaller than the scene (a shaft
    # without the blocks, or with every polygon dropped, gives the unoccluded wall:
    # planted, caught below)
    import exactff.visibility.compiled as compiled
    from exactff import _tolerances

    scene = ef.scenes.cornell_box(closed=True)
    p, n = scene.centroids[20], scene.normals[20]    # the front wall's centre, facing in
    wall = 6                                         # the back wall, past the blocks
    Fc, Ec = compiled_form_factors(scene, p, n, error=True)
    monkeypatch.setattr(_tolerances, "COMPILED_FALLBACK_MAX_POLYGONS", len(scene) - 1)
    built = compiled.compiled_core

    class Unsettled:
        def __init__(self, core, at):
            self.core, self.at = core, at

        def row(self, **kwargs):
            F, E, band, crossing, counters = self.core.row(**kwargs)
            crossing = crossing.copy()
            crossing[self.at] = 1.0
            return F, E, band, crossing, counters

    def planted(s, *a):
        # the wall's value unsettled in the scene's tree (and in every shaft's)
        tree, core = built(s, *a)
        at = np.flatnonzero(np.all(np.isclose(s.centroids, scene.centroids[wall]), axis=1))
        if s is not scene and (core_settles or len(at) == 0):
            return tree, core
        return tree, Unsettled(core, int(at[0]))

    monkeypatch.setattr(compiled, "compiled_core", planted)
    st = {}
    F, E = compiled_form_factors(scene, p, n, tolerance=1e-12, stats=st, error=True)
    assert st["path"] == "compiled, shaft for some polygons" and st["shaft_polygons"] == 1
    assert st["shaft_compiled"] == int(core_settles)
    assert 1 < st["shaft_sizes"][0] < len(scene)
    Fp, Ep = ef.Exact(engine="python").point_form_factors(scene, p, n, error=True)
    assert abs(F[wall] - Fp[wall]) <= E[wall] + Ep[wall]
    assert abs(F[wall] - Fc[wall]) <= E[wall] + Ec[wall]
    assert E[wall] <= 1e-12 * max(F[wall], 0.01)
    # the blocks hide part of the wall: without them it would be larger
    assert F[wall] < ef.point_polygon_form_factor(p, n, scene.polygons[wall]) - 1e-3


def _floor_face_wall(Y, face_ulps, L, face_x=(2, 3), face_down=True):
    """A floor A (y = Y, facing +y), a face B ``face_ulps`` ulps of Y off the floor's
    plane (coplanar with it by the band: one BSP node), facing down (or up), over
    ``face_x`` times L in x, and a wall W standing on the floor at x = L (y from Y to
    Y + 1), facing the origin."""
    t = face_ulps * np.spacing(Y)
    A = np.array([[-1, Y, -1], [-1, Y, 1], [1, Y, 1], [1, Y, -1.0]])
    x0, x1 = face_x[0] * L, face_x[1] * L
    B = np.array([[x0, Y + t, -1], [x1, Y + t, -1], [x1, Y + t, 1], [x0, Y + t, 1.0]])
    if not face_down:
        B = B[::-1]
    W = np.array([[L, Y, -2], [L, Y, 2], [L, Y + 1, 2], [L, Y + 1, -2.0]])   # faces -x
    return ef.Scene.from_polygons([A, B, W]), t


@pytest.mark.parametrize("Y", [10.37, 1000.0])
@pytest.mark.parametrize("L", [1e-3, 1e-11])
@pytest.mark.parametrize("between", [False, True])
def test_wall_standing_on_the_floor_in_front_of_a_flush_face_is_bounded(Y, L, between):
    # a face B 32 ulps above the floor, facing down onto a point on the floor, comes
    # before the floor's front subtree (node_sides); the wall W standing on the floor
    # between the point and B is in that subtree, and hides all of B (every line of
    # sight from the point to B crosses W's inside: checked below in rationals), but
    # the slab between the floor and B is too thin for the tree to say so: B showed
    # through W, 0.029 of the hemisphere with the wall 1e-11 away, 1.4e-11 at 1 mm,
    # with bounds of 1e-18 (found by review). What visiting B first may misplace is
    # charged (node_first_charges): B's value 0 and W's (nothing in front of it: its
    # unoccluded closed form) hold within the bounds
    scene, t = _floor_face_wall(Y, 32, L)
    p = np.array([0.0, Y + t / 2 if between else Y, 0.0])
    assert not between or Y < p[1] < Y + t
    P = [Fraction(c) for c in p]
    for v in scene.polygons[1]:
        v = [Fraction(c) for c in v]
        s = (Fraction(L) - P[0]) / (v[0] - P[0])          # where the sight line meets x = L
        y, z = P[1] + s * (v[1] - P[1]), P[2] + s * (v[2] - P[2])
        assert Fraction(Y) < y < Fraction(Y) + 1 and -2 < z < 2
    n = np.array([1.0, 0.0, 0.0])
    U = float(polygon_form_factor_mp(p, n, [tuple(map(Fraction, v)) for v in scene.polygons[2]]))
    for engine in (ef.Exact(engine="compiled"), ef.Exact(engine="python"), COMPILED):
        F, E = engine.point_form_factors(scene, p, n, error=True)
        assert F[1] <= E[1] and abs(F[2] - U) <= E[2], (F, E, U)


def test_faces_behind_the_point_keep_the_usual_order():
    # the floor A and a face B 32 ulps below it (one node), the point 8 ulps above the
    # floor: no fragment of the node lies between the point and the wall W standing on
    # the floor (the point is in front of both planes), so the usual order holds
    # exactly and W's strip below the point's level is seen whole. Sent first for
    # lying within the node's thickness (found by review), the floor hid that strip:
    # 2.8e-12 sr at 1 cm, beyond bounds of 6e-14
    Y, L = 10.37, 0.01
    scene, t = _floor_face_wall(Y, -32, L, face_x=(10, 11), face_down=False)
    p = np.array([0.0, Y + 8 * np.spacing(Y), 0.0])
    n = np.array([1.0, -1.0, 0.0])
    # W's part in the point's hemisphere, below y = p_y + L (the strip under the
    # point's level included: the floor is below it)
    top = Fraction(p[1]) + Fraction(L)
    part = [(Fraction(L), Fraction(Y), Fraction(z)) for z in (-2, 2)]
    part += [(Fraction(L), top, Fraction(z)) for z in (2, -2)]
    U = float(polygon_form_factor_mp(p, n, part))
    for engine in (ef.Exact(engine="compiled"), ef.Exact(engine="python"), COMPILED):
        F, E = engine.point_form_factors(scene, p, n, error=True)
        assert abs(F[2] - U) <= E[2] and F[1] <= E[1], (F, E, U)
    tree, _ = compiled_core(scene)
    side, _ = engine_sides(flat_polygons(scene), p)
    assert side.tolist() == [1, 1, 1] and set(node_sides(tree, p, side).tolist()) <= {1, -1}


@pytest.mark.parametrize("Y", [10.37, 1000.0])
@pytest.mark.parametrize("L", [1e-3, 1.0])
def test_flush_face_beside_the_point_keeps_the_usual_order_and_its_charge(Y, L):
    # a face B 32 ulps above the floor A, facing down, from 0.2 L to 0.5 L off the point
    # on the floor (it does not cover the point), and a wall W standing on the floor at
    # L behind it: B hides W's foot, the strip 2t to 5t high (every line of sight
    # through B meets W there: t L / x for x in [0.2 L, 0.5 L]). B lies farther than
    # twice the slab's width from the point, so the usual order stays (node_sides: the
    # node first there lost 1.1e-3 of the hemisphere on SampleHouse4 row 18196), W is
    # drawn first, and what that may misplace, rays within sin a <= w / d, is charged
    # to B and W (node_first_charges with the sides). Both values, against their exact
    # values in mpmath (B seen whole; W less the strip), hold within the bounds; without
    # the charge B's 0 has a bound of 1e-18 against 1e-10
    scene, t = _floor_face_wall(Y, 32, L, face_x=(0.2, 0.5))
    p, n = np.array([0.0, Y, 0.0]), np.array([1.0, 0.0, 0.0])
    fr = lambda P: [tuple(map(Fraction, v)) for v in P]
    T = Fraction(t)
    strip = [(Fraction(L), Fraction(Y) + k * T, Fraction(z)) for k, z in
             ((2, -2), (2, 2), (5, 2), (5, -2))]
    UB = float(polygon_form_factor_mp(p, n, fr(scene.polygons[1])))
    UW = float(polygon_form_factor_mp(p, n, fr(scene.polygons[2])) -
               polygon_form_factor_mp(p, n, strip))
    assert UB > 0
    tree, _ = compiled_core(scene)
    side, _ = engine_sides(flat_polygons(scene), p)
    code = node_sides(tree, p, side)
    assert set(code.tolist()) <= {1, -1}
    for engine in (ef.Exact(engine="compiled"), ef.Exact(engine="python"), COMPILED):
        F, E = engine.point_form_factors(scene, p, n, error=True)
        assert abs(F[1] - UB) <= E[1] and abs(F[2] - UW) <= E[2], (F, E, UB, UW)


@given(hst.lists(hst.floats(-3, 3).map(lambda v: round(v, 6)), min_size=3, max_size=6),
       hst.floats(-3, 3), hst.floats(-3, 3), hst.floats(-2, 2))
def test_point_polygon_distance_of_a_polygon_without_area(xs, x, y, h):
    # a BSP sliver whose vertices rounded onto a line has no normal: its distance is
    # its edges' (a NaN was ignored by the node-first charge's minimum, which could
    # then take a farther fragment's), against shapely's distance to the segment
    from exactff.geometry import point_polygon_distance
    P = np.array([[v, 0.5 * v, 0.0] for v in xs])
    d = point_polygon_distance([x, y, h], P)
    line = shapely.LineString(P[:, :2]) if np.ptp(xs) > 0 else shapely.Point(P[0, :2])
    true = math.hypot(shapely.distance(shapely.Point(x, y), line), h)
    assert np.isfinite(d) and d <= true and d >= true - 1e-9


@given(hst.lists(hst.tuples(hst.floats(-3, 3), hst.floats(-3, 3)), min_size=3, max_size=8),
       hst.floats(-3, 3), hst.floats(-3, 3), hst.floats(-2, 2))
def test_point_polygon_distance_against_shapely(ring, x, y, h):
    # the node-first charge's distance (exactff.geometry.point_polygon_distance) is a
    # lower bound on the true distance, and close to it: a polygon in z = 0 (its convex
    # hull, to be simple), a point at height h, against shapely's planar distance
    from exactff.geometry import point_polygon_distance
    hull = shapely.MultiPoint(ring).convex_hull
    assume(hull.geom_type == "Polygon" and hull.area > 1e-6)
    P = np.array([(a, b, 0.0) for a, b in np.asarray(hull.exterior.coords)[:-1]])
    true = math.hypot(h, shapely.Point(x, y).distance(hull))
    got = point_polygon_distance([x, y, h], P)
    assert true - 1e-9 <= got <= true * (1 + 1e-12) + 1e-15


def test_shaft_of_a_polygon_within_rounding_of_the_point_plane():
    # a floor tile j in the point's own plane (to rounding: 2 ulps above it) spans no
    # solid hull with the point; its lines of sight graze the floor. The shaft starts
    # them from the point +- the margin along j's normal instead (it returned None,
    # and the row raised): a wall standing across the floor between the point and the
    # tile may hide part of it and is kept; one behind the point, and one beside the
    # tile's lines of sight, are not
    from exactff.geometry import hull_blockers
    from exactff.visibility.compiled import _shaft

    y0 = 3.0
    up = y0 + 2 * np.spacing(y0)
    floor = lambda x0, x1, y, z0, z1: np.array([[x0, y, z0], [x0, y, z1], [x1, y, z1],
                                                [x1, y, z0]])
    across = lambda x, z0, z1: np.array([[x, y0 - 1, z0], [x, y0 + 1, z0], [x, y0 + 1, z1],
                                         [x, y0 - 1, z1]])
    scene = ef.Scene.from_polygons([floor(-1, 1, y0, -1, 1), floor(3, 4, up, -1, 1),
                                    across(2, -2, 2), across(-2, -2, 2), across(3.5, 5, 6)])
    p, j = np.array([0.0, y0, 0.0]), 1
    Q = scene.polygons[j]
    assert hull_blockers(np.array([scene.polygons[2]]), [0], p[None], Q, 0.0,
                         none_if_flat=True) is None       # (no solid hull from p alone)
    keep = _shaft(scene, p, j)
    assert keep is not None and {1, 2} <= set(keep.tolist()) and not {3, 4} & set(keep.tolist())


def test_a_bound_that_says_nothing_is_capped_by_the_unoccluded_value(monkeypatch):
    # a bound above its value (the band's slivers reached 1e7 on a value of 3e-6 in
    # SampleHouse4) is capped by what the value could be off by at all: the exact value
    # lies between 0 and the polygon's unoccluded value. Planted here: the back wall's
    # band part set to 1e7 (the blocks hide part of it), a small light's to 0.5
    import exactff.visibility.compiled as compiled

    scene = ef.scenes.cornell_box(closed=True)
    p, n = scene.centroids[20], scene.normals[20]
    tree, core = compiled.compiled_core(scene)
    Fc, Ec = compiled_form_factors(scene, p, n, error=True)
    wall = 6
    light = int(np.argmin(np.where(Fc > 0, Fc, np.inf)))
    assert Fc[light] < 0.5

    class Blown:
        def row(self, **kwargs):
            F, E, band, crossing, counters = core.row(**kwargs)
            band = band.copy()
            band[wall], band[light] = 1e7, 0.5
            return F, E, band, crossing, counters

    monkeypatch.setattr(compiled, "compiled_core", lambda s, *a: (tree, Blown()))
    F, E = compiled_form_factors(scene, p, n, error=True)
    U = ef.point_polygon_form_factors(p, n, [scene.polygons[wall], scene.polygons[light]])
    assert F[wall] == Fc[wall] and Fc[wall] < U[0] - 1e-3
    assert E[wall] == pytest.approx(max(F[wall], U[0] - F[wall]), rel=1e-12)
    assert E[light] == pytest.approx(max(F[light], U[1] - F[light]), abs=1e-15)
    Fp, Ep = ef.Exact(engine="python").point_form_factors(scene, p, n, error=True)
    assert np.all(np.abs(F - Fp) <= E + Ep)
    np.testing.assert_array_equal(np.delete(E, [wall, light]), np.delete(Ec, [wall, light]))


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
        core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(3, np.int8), side, False, True, 8, 0,
                 0.0, 0.0)
    with pytest.raises(ValueError, match="source_side"):
        core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(len(tree), np.int8),
                 side[:2], False, True, 8, 0, 0.0, 0.0)
    for rtol, floor in ((1e-12, -1e-2), (1e-12, np.inf), (-1e-12, 1e-2), (np.nan, 1e-2)):
        with pytest.raises(ValueError, match="rtol and floor"):
            core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(len(tree), np.int8),
                     side, False, True, 8, 0, rtol, floor)


def test_engine_argument():
    assert ef.Exact().engine == "compiled"
    assert ef.Exact(engine="python").engine == "python"
    assert ef.Exact(integrator="eq3").engine == "compiled"
    assert ef.Exact(integrator="eq3", engine="python").engine == "python"
    with pytest.raises(ValueError, match="engine"):
        ef.Exact(engine="gpu")


@given(case=flush_faces())
def test_flush_faces(case):
    # issue 48: faces flush to 1e-16..1e-9 of their size, crossing each other's plane at
    # grazing angles, far from the origin (walls on slabs, rafters under roofs in IFC
    # exports). The BSP's crossings there slid along their edges by the splitter's
    # rounding over the sine of the angle (a bound of 4e-4 on these scenes, 1.4e15 on a
    # house); from the splitter's own plane in quadruple precision each is within an ulp
    # (7e-15 over 300 drawn scenes). Every value the exact construction decides holds
    # against it within the compiled bound. The construction follows the rule of
    # docs/explanation/conventions.md (coplanar pairs are depth ties, any other pair is
    # ordered by its exact geometry): over 150 drawn scenes it decided 437 of 450 values
    # (the rest: one face within the other's band but not the other way round, where the
    # BSP tree's choice of splitter decides, or a vertex at a band's edge). Before the
    # builds followed the rule (they took a vertex in the band as on the plane whatever
    # the pair), 39 of 591 decided values were off, by up to 2 %.
    # The Python engine (the oracle) follows the same rule; its bound leaves its own
    # crossings' rounding out (docs/explanation/robustness.md), so it is held to the
    # accuracy target: over 400 drawn scenes it decided 1,193 values, the compiled
    # core held all within its bound and the Python engine all within 2.7e-16.
    scene, p, n = case
    F, E = COMPILED.point_form_factors(scene, p, n, error=True)
    G, H = PYTHON.point_form_factors(scene, p, n, error=True)
    assert np.all(F >= 0) and np.all(E <= OCC_ATOL), E
    for j in range(len(scene)):
        U = visible_form_factor(scene, p, n, j)
        if U is not None:
            assert abs(F[j] - U) <= E[j], (j, F[j], float(U), E[j])
            assert abs(G[j] - U) <= H[j] + OCC_ATOL, (j, G[j], float(U), H[j])


# A flush pair hypothesis found where the Python engine's double crossings missed: a
# triangle 1.7e-9 of its size off a rotated triangle's plane, crossing it. The
# construction gives 0.0631155693781842 for the base; the compiled core 0.06311556937818426
# (bound 5.5e-17); the Python engine gave 0.06311557582738951 (6.4e-9 off, bound 6.8e-15)
# until its build took each crossing exactly (bsp._ExactPoints), as the compiled one does.
FLUSH_PYTHON_MISS = (
    [[[1.3660254037844388, 0.0, -0.3660254037844386],
      [0.6160254037844388, -0.8660254037844387, 0.9330127018922193],
      [0.6160254037844385, 0.8660254037844384, 0.9330127018922199]],
     [[1.3660254022844387, 0.0, -0.366025404650464],
      [0.6160254022844388, 0.8660254037844387, 0.9330127010261938],
      [0.6160254052844384, -0.8660254037844384, 0.9330127027582452]],
     [[0.6830127018922194, 1.0, -0.1830127018922193],
      [0.3080127018922194, 0.5669872981077806, 0.46650635094610965],
      [0.30801270189221924, 1.4330127018922192, 0.4665063509461099]]],
    [0.0, 0.0, 0.0], [0.8660254037844387, 0.0, 0.5000000000000001])


def test_flush_pair_both_engines_hold():
    polys, p, n = FLUSH_PYTHON_MISS
    scene = ef.Scene.from_polygons([np.array(P) for P in polys])
    p, n = np.array(p), np.array(n)
    F, E = COMPILED.point_form_factors(scene, p, n, error=True)
    G, H = PYTHON.point_form_factors(scene, p, n, error=True)
    for j in range(len(scene)):
        U = visible_form_factor(scene, p, n, j)
        assert U is not None and abs(F[j] - U) <= E[j] <= 1e-16
        assert abs(G[j] - U) <= H[j]

def _facing_flush_scene(y0, ulps, order, between=False):
    """A wall face r in the plane y = y0 facing +y, a face j facing it from ``ulps``
    units of rounding of y0 away (coplanar with r by the band's rule, so the BSP tree
    puts both in one node, but beyond the edge-on convention: j is in front of a point
    on r and covers its whole hemisphere), and a face b 1 behind j, facing -y; in the
    input ``order`` (a permutation of "rjb"). Returns the scene, the indices of r, j
    and b, and the point: on r (its y exactly y0), or ``between`` r and j (in front of
    r, below j: within the node's thickness whichever plane the node has)."""
    delta = ulps * 2.0 ** -53 * abs(y0)
    yj = y0 + delta
    assert yj - y0 > 4 * 2.0 ** -53 * abs(y0)          # beyond the edge-on convention
    faces = {"r": np.array([[-2, y0, -2], [-2, y0, 2], [2, y0, 2], [2, y0, -2.0]]),
             "j": np.array([[-3, yj, -3], [3, yj, -3], [3, yj, 3], [-3, yj, 3.0]]),
             "b": np.array([[-1, y0 + 1, -1], [1, y0 + 1, -1], [1, y0 + 1, 1],
                            [-1, y0 + 1, 1.0]])}
    scene = ef.Scene.from_polygons([faces[c] for c in order])
    p = np.array([0.3, y0 + delta / 2 if between else y0, -0.2])
    assert y0 < p[1] < yj or not between
    return scene, [order.index(c) for c in "rjb"], p


@pytest.mark.parametrize("y0", [-10.37, 3.0, 250.0])
@pytest.mark.parametrize("order", ["rjb", "jrb", "brj"])
@pytest.mark.parametrize(("ulps", "between"), [(8, False), (12, False), (32, False), (64, False),
                                               (110, False), (32, True), (110, True)])
def test_face_flush_in_front_of_the_point_hides_what_is_behind_it(y0, ulps, order, between):
    # issue 48 (Duplex_A's rows 16886, 13100, 723: a wall face and a slab face facing
    # it 1.95e-14 away, coplanar by the band, in one BSP node): a point on the node's
    # plane, or within the node's thickness, visited the near subtree before the node's
    # own fragments, so the face behind (b) showed through the flush face j: 0.667 of
    # the hemisphere on the house's row, within a bound of 5.8e-3, and the Python
    # engine gave the same within 1e-13. j is in front of the point by the exact side
    # (docs/explanation/conventions.md), nothing is in front of it: its value is its
    # unoccluded closed form (mpmath), and b's is 0. At 8 and 12 ulps the Python engine
    # also needed its charts' clip in rational arithmetic (charts.exact_chart_clip): the
    # float clip of j to the top chart's frustum had corners 10 % off, and b showed
    # through by 0.003 (bound 2e-15)
    scene, (r, j, b), p = _facing_flush_scene(y0, ulps, order, between)
    n = np.array([0.0, 1.0, 0.0])
    tree, _ = compiled_core(scene)
    assert any({r, j} <= {int(tree.source[f]) for f in here} for here in tree.node_fragments)
    U = float(polygon_form_factor_mp(p, n, [tuple(map(Fraction, v)) for v in scene.polygons[j]]))
    for engine in (ef.Exact(engine="compiled"), ef.Exact(engine="python"), COMPILED,
                   ef.Exact(engine="compiled", shortcuts=False),
                   ef.Exact(engine="python", shortcuts=False)):
        F, E = engine.point_form_factors(scene, p, n, error=True)
        assert F[r] == 0 and abs(F[j] - U) <= E[j] and F[b] <= E[b] <= OCC_ATOL, (F, E)


def test_fragments_in_cells_proven_covered_are_hidden_and_only_they():
    # a wall with a window over a floor of small tiles: the tiles behind the wall are
    # skipped once the cells of the cube map about the point they lie in are proven
    # covered (Core::cell_covered), without being cut along the wall's shadows; the
    # tiles seen through the window must still be found (a proof that marked a cell
    # with a free leaf in it, or a footprint that missed a cell, would skip them)
    wall = [rect_xy(-2, 2, 0.2, 2, 1.0), rect_xy(-2, 2, -2, -0.2, 1.0),
            rect_xy(-2, -0.3, -0.2, 0.2, 1.0), rect_xy(0.3, 2, -0.2, 0.2, 1.0)]
    # two layers of tiles, the second behind the first in the cells the first proves
    edges = np.linspace(-2, 2, 41)
    tiles = [rect_xy(x0, x1, y0, y1, z) for z in (2.0, 3.0)
             for x0, x1 in zip(edges[:-1], edges[1:]) for y0, y1 in zip(edges[:-1], edges[1:])]
    scene = ef.Scene.from_polygons(wall + tiles)
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    st = assert_engines_agree(scene, p, n)
    assert st["fragments_covered"] > 100, st
    F = COMPILED.point_form_factors(scene, p, n)
    # through the window (|x| < 0.3, |y| < 0.2 at z = 1: |x| < 0.6, |y| < 0.4 at z = 2,
    # about the point) the first layer's tiles show, every other tile is hidden
    c = scene.centroids[len(wall):]
    front = c[:, 2] == 2.0
    through = front & (np.abs(c[:, 0] - 0.01) < 0.55) & (np.abs(c[:, 1] - 0.02) < 0.35)
    assert np.all(F[len(wall):][through] > 0)
    far = (np.abs(c[:, 0]) > 0.8) | (np.abs(c[:, 1]) > 0.6) | ~front
    assert np.all(F[len(wall):][far] == 0)


def test_fragments_behind_the_tangent_plane_and_back_faces():
    # a point on a floor (z = 0, facing up): tiles below it (skipped whole, clearly behind
    # the tangent plane: Core::behind_horizon), tiles just below it within rounding of
    # the plane, a ceiling seen from behind (it receives nothing, but hides: its pieces'
    # values are computed only where their shadows are left out, Core::piece_worth), a
    # tile behind that ceiling (hidden) and a tile beside it (seen); values bit for bit
    # those of the row without the shortcuts (which skips nothing), bounds at most theirs
    edges = np.linspace(-2, 2, 9)
    below = [rect_xy(x0, x1, y0, y1, z, facing_down=False) for z in (-1.0, -2.0)
             for x0, x1 in zip(edges[:-1], edges[1:]) for y0, y1 in zip(edges[:-1], edges[1:])]
    grazing = [rect_xy(3.0, 4.0, -1.0, 1.0, -1e-17, facing_down=False),
               rect_xy(-4.0, -3.0, -1.0, 1.0, -1e-300, facing_down=False)]
    ceiling = rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0, facing_down=False)   # its back seen
    hidden = rect_xy(-0.2, 0.2, -0.2, 0.2, 2.0)
    seen = rect_xy(1.0, 1.5, -0.2, 0.2, 1.0)
    scene = ef.Scene.from_polygons(below + grazing + [ceiling, hidden, seen])
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    st = assert_engines_agree(scene, p, n)
    assert st["fragments_behind"] >= len(below) // 2, st
    F, E = COMPILED.point_form_factors(scene, p, n, error=True)
    F0, E0 = ef.Exact(tolerance=None, engine="compiled", shortcuts=False).point_form_factors(
        scene, p, n, error=True)
    assert np.array_equal(F, F0) and np.all(E <= E0)
    c, h, v = len(below) + 2, len(below) + 3, len(below) + 4
    assert np.all(F[:len(below)] == 0) and F[c] == 0 and F[h] == 0 and F[v] > 0
    assert F[v] == pytest.approx(unoccluded_form_factor(scene, p, n, v), rel=1e-12)


def test_vertices_just_above_the_tangent_plane_are_not_behind_it():
    # a triangle's tip just above the tangent plane through the point, its other corners
    # well below (the plane tilted: its dot products round in double, unlike an axis's).
    # The tip is above the widest width Core::behind_horizon's long double test allows
    # (W: the band, the root's tilt bound of 2 roundoffs and a vertex's error of 4, in
    # long double's roundoffs) by more than 3 W, far beyond that test's rounding, but
    # below 2^-55 |v| (a quarter of a double roundoff); and its dot product in double (the
    # core's unit normal rounded to double, the double difference) is below -2 W |v|: a
    # double filter with no margin for its own roundoff would call every vertex behind
    # and skip the triangle (with the margin planted to 0, each of these is skipped:
    # 0 +- 0 against about 1e-52). The triangle is not behind (no fragment skipped so),
    # and its sliver above the plane has its value within its bound (the value from
    # rationals and 60 digits). A square across the point from the triangle, turned away
    # from it (it hides and receives nothing), makes the scene non-convex: the row goes
    # through the core
    u = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    p = np.array([0.1, 0.2, 0.3])
    e1 = np.cross(u, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    W = Fraction(tol.SVBSP_BAND) + 6 * Fraction(tol.LONGDOUBLE_EPS)
    low, high = 4 * W, Fraction(2.0 ** -55)
    with mpmath.workdps(40):
        unit = [float(mpmath.mpf(c) / mpmath.sqrt(sum(mpmath.mpf(d) ** 2 for d in u)))
                for c in u]
    U2 = sum(Fraction(c) ** 2 for c in u)

    def tip_case(C):
        v = [Fraction(c) - Fraction(q) for c, q in zip(C, p)]
        h, v2 = sum(Fraction(a) * b for a, b in zip(u, v)), sum(c * c for c in v)
        # exactly: low |u| |v| < h < high |u| |v|
        if not (h > 0 and low ** 2 * U2 * v2 < h * h < high ** 2 * U2 * v2):
            return False
        vd = C - p
        dd = (unit[0] * vd[0] + unit[1] * vd[1]) + unit[2] * vd[2]
        return dd < -2 * float(W) * math.sqrt((vd[0] * vd[0] + vd[1] * vd[1]) + vd[2] * vd[2])

    # such tips on a grid about the point's plane (whether a tip's double dot product
    # errs that way depends on its direction: some grid rows have none), six of them
    tips = [C for C in (p + a * e1 + b * e2 for b in np.linspace(-0.2, 0.2, 9)
                        for a in np.linspace(0.8, 1.2, 401)) if tip_case(C)]
    assert len(tips) >= 6
    tips = tips[::len(tips) // 6][:6]
    square = np.array([p - e1 + s * e2 + t * u for s, t in
                       ((-0.3, 0.1), (-0.3, 0.4), (0.3, 0.4), (0.3, 0.1))])
    if np.cross(square[1] - square[0], square[2] - square[0]) @ e1 > 0:
        square = square[::-1].copy()                    # facing away from the point
    for C in tips:
        A, B = C + 0.2 * e1 + 0.3 * e2 - 0.2 * u, C + 0.2 * e1 - 0.3 * e2 - 0.2 * u
        triangle = np.array([A, B, C])
        if np.cross(B - A, C - A) @ (p - A) < 0:
            triangle = triangle[::-1].copy()            # facing the point
        scene = ef.Scene.from_polygons([triangle, square])
        st = {}
        F, E = COMPILED.point_form_factors(scene, p, u, error=True, stats=st)
        U = unoccluded_form_factor(scene, p, u, 0)
        assert U is not None and U > 0
        assert abs(F[0] - U) <= E[0], (C.tolist(), F[0], float(U), E[0])
        assert F[1] == 0
        assert st["path"] == "compiled" and st["fragments_behind"] == 0, st


def test_sides_a_mesh_shares_are_one_node():
    # a wall of triangles (two a square, a window of four squares left out) over a floor
    # of tiles: the second triangle at each shared edge finds that edge's plane on the
    # path to its leaf, with its cell on its side, and adds no node for it
    # (Core::drop_repeated_sides). The shadow must stay the wall's: tiles show through
    # the window and nowhere else (a side dropped where the plane on the path is another
    # edge's, or the cell is on the far side, would open or close the shadow there). With
    # every second triangle turned over (a back face: it hides, receives nothing), the
    # shared edges run the same way in both triangles (the other orientation of the two
    # planes' normals): as many sides must be left out, the shadow the same
    edges = np.linspace(-2, 2, 9)
    floor = np.linspace(-3, 3, 25)
    tiles = [rect_xy(x0, x1, y0, y1, 2.0) for x0, x1 in zip(floor[:-1], floor[1:])
             for y0, y1 in zip(floor[:-1], floor[1:])]
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    # behind the window, the tiles' sum is the unoccluded square the window's image cuts
    # from the floor (z = 2: x = 2 w - 0.01, y = 2 w - 0.02 for |w| < 0.5 at z = 1)
    square = ef.Scene.from_polygons([rect_xy(-1.01, 0.99, -1.02, 0.98, 2.0)])
    seen = unoccluded_form_factor(square, p, n, 0)
    repeated = []
    for turned in (False, True):
        wall, front = [], []
        for i, (x0, x1) in enumerate(zip(edges[:-1], edges[1:])):
            for j, (y0, y1) in enumerate(zip(edges[:-1], edges[1:])):
                if i in (3, 4) and j in (3, 4):
                    continue  # the window, |x| < 0.5 and |y| < 0.5
                a, b, c, d = [x0, y0, 1.0], [x0, y1, 1.0], [x1, y1, 1.0], [x1, y0, 1.0]
                second = np.array([a, c, d])
                wall += [np.array([a, b, c]), second[::-1].copy() if turned else second]
                front += [True, not turned]
        scene = ef.Scene.from_polygons(wall + tiles)
        st = assert_engines_agree(scene, p, n)
        repeated.append(st["repeated_sides"])
        F = COMPILED.point_form_factors(scene, p, n)
        # the wall's front faces whole, its back faces nothing; behind it, tiles within
        # the window's image (|x|, |y| < 1 about the point at z = 2) show, the others
        # are hidden
        front = np.array(front)
        assert np.all(F[:len(wall)][front] > 0) and np.all(F[:len(wall)][~front] == 0)
        c = scene.centroids[len(wall):]
        inside = (np.abs(c[:, 0] - 0.01) < 0.85) & (np.abs(c[:, 1] - 0.02) < 0.85)
        outside = (np.abs(c[:, 0]) > 1.2) | (np.abs(c[:, 1]) > 1.2)
        assert np.all(F[len(wall):][inside] > 0)
        assert np.all(F[len(wall):][outside] == 0)
        assert F[len(wall):].sum() == pytest.approx(seen, rel=1e-12)
    assert repeated[0] > 50 and abs(repeated[1] - repeated[0]) <= 0.05 * repeated[0], repeated
    # without the shortcuts every side is a node (the core's cull flag): none left out,
    # the same values within both bounds
    st = {}
    F0, E0 = ef.Exact(shortcuts=False).point_form_factors(scene, p, n, error=True, stats=st)
    F1, E1 = COMPILED.point_form_factors(scene, p, n, error=True)
    assert st["repeated_sides"] == 0 and st["shadow_planes"] > 0
    assert np.all(np.abs(F0 - F1) <= E0 + E1)


def test_a_cell_partly_free_is_not_proven_covered():
    # a square near the point hides a small tile T behind it, near its image's edge: T's
    # cells of the cube map (gnomonic u = x / z in [0.47, 0.495], cells of width 1 / 32
    # from -1 + 0.0123456789) include one, [0.4811, 0.5123], that the square covers only
    # below u = 0.5. Tiles behind in that cell, seen past the square's edge, must show:
    # T2 wholly in it, T3 across it and the covered cell before it
    square = rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0)
    T = rect_xy(0.94, 0.99, 0.2, 0.24, 2.0)
    T2 = rect_xy(1.506, 1.53, 0.33, 0.39, 3.0)
    T3 = rect_xy(1.41, 1.59, 0.24, 0.3, 3.0)
    scene = ef.Scene.from_polygons([square, T, T2, T3])
    p, n = np.zeros(3), np.array([0, 0, 1.0])
    st = assert_engines_agree(scene, p, n)
    assert st["cover_cells"] > 0, st
    F = COMPILED.point_form_factors(scene, p, n)
    assert F[1] == 0 and F[2] > 0 and F[3] > 0
    # T2 whole, T3 from u = 0.5 on (x = 1.5 at z = 3): unoccluded closed forms
    assert F[2] == pytest.approx(unoccluded_form_factor(scene, p, n, 2), rel=1e-12)
    part = ef.Scene.from_polygons([rect_xy(1.5, 1.59, 0.24, 0.3, 3.0)])
    assert F[3] == pytest.approx(unoccluded_form_factor(part, p, n, 0), rel=1e-12)
