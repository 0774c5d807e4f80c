"""The exact visibility engine: occluded rows against independent constructions and
invariants (enclosure, monotonicity, rigid motions, splitting), and shortcut neutrality."""

import math
import tempfile

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import exactff as ef
from exactff.methods import Exact
from exactff.testing import assert_form_factors_close
from exactff.testing.mp_reference import boundary_form_factor
from exactff.testing.strategies import flush_faces, unit_vectors

from common import examples, rect_xy, rotation, upward_unit_vectors

# occluded accuracy target of the issue: 1e-11 absolute; row sums 1 +- 1e-11
OCC_ATOL = 1e-11


# ---------------------------------------------------------------------------------------
# independent construction: horizontal layers facing down over a point
# ---------------------------------------------------------------------------------------
def layered_reference(p, n, polygons, measure=None):
    """Occluded form factors of horizontal polygons facing down, above p, by other means:
    project every polygon centrally onto the plane z = p_z + 1 (a similarity for
    horizontal polygons), resolve visibility nearest first with 2-D boolean operations,
    and integrate each visible region in that plane by mpmath quadrature of its
    boundary (``exactff.testing.mp_reference``, 30 digits; exterior minus holes), not
    by the kernel the engine uses. ``measure(ring)``, given, replaces the integration
    of a lifted ring (``n`` is then unused)."""
    if measure is None:
        def measure(ring):
            return float(boundary_form_factor(p, n, ring, two_sided=True, dps=30))
    h = [P[0, 2] - p[2] for P in polygons]
    images = [shapely.Polygon((P[:, :2] - p[:2]) / hk) for P, hk in zip(polygons, h)]
    F = np.zeros(len(polygons))
    covered = shapely.Polygon()
    for k in np.argsort(h, kind="stable"):
        vis = images[k].difference(covered)
        covered = covered.union(images[k])
        for part in shapely.get_parts(vis):
            if part.geom_type != "Polygon" or part.area == 0:
                continue
            rings = [np.asarray(part.exterior.coords)[:-1]] + [np.asarray(r.coords)[:-1]
                                                                for r in part.interiors]
            for r, ring in enumerate(rings):
                lifted = np.column_stack([ring + p[:2], np.full(len(ring), p[2] + 1.0)])
                val = measure(lifted)
                F[k] += val if r == 0 else -val
    return F


@st.composite
def layered_scenes(draw):
    m = draw(st.integers(2, 6))
    polys = []
    used = set()
    # coordinates on a 1e-6 grid: the 2-D reference divides them by the heights, and
    # values near the underflow threshold (1e-308) would lose their digits there
    coord = st.floats(-1.5, 1.0).map(lambda v: round(v, 6))
    for _ in range(m):
        x0 = draw(coord)
        y0 = draw(coord)
        w = draw(st.floats(0.1, 1.5))
        d = draw(st.floats(0.1, 1.5))
        # heights on a 1e-3 grid, distinct: layers within rounding of each other are a
        # tie that the engine resolves by input order (documented), not by height
        z = draw(st.integers(300, 3000).filter(lambda k: k not in used)) / 1000
        used.add(round(z * 1000))
        polys.append(rect_xy(x0, x0 + w, y0, y0 + d, z))
    return polys


@settings(max_examples=examples(40))
@given(polys=layered_scenes(), n=upward_unit_vectors(0.05))
def test_layered_scene_vs_2d_boolean_construction(polys, n):
    # the layers must be in the upper hemisphere at least partly: normals with z > 0.05
    p = np.zeros(3)
    F = ef.form_factors(ef.Scene.from_polygons(polys), p, n)
    ref = layered_reference(p, n, polys)
    assert_form_factors_close(F, ref, rtol=0, atol=OCC_ATOL)


def test_layered_scene_example_is_partially_occluded():
    polys = [rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0), rect_xy(-1, 1, -1, 1, 2.0),
             rect_xy(0.2, 1.2, -0.3, 0.6, 1.5)]
    p, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    F = ef.form_factors(ef.Scene.from_polygons(polys), p, n)
    ref = layered_reference(p, n, polys)
    unocc = ef.point_polygon_form_factors(p, n, polys)
    assert np.all(F[1:] < unocc[1:] - 0.01)      # genuinely occluded
    assert_form_factors_close(F, ref, rtol=0, atol=OCC_ATOL)


def test_exactly_covered_polygon_gets_zero():
    far = rect_xy(-1, 1, -1, 1, 2.0)
    near = rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0)   # its image is exactly far's image
    F = ef.form_factors(ef.Scene.from_polygons([far, near]), [0, 0, 0], [0, 0, 1])
    assert F[0] == 0.0 or F[0] < 1e-15
    assert_form_factors_close(F[1], ef.point_polygon_form_factor([0, 0, 0], [0, 0, 1], near))


# ---------------------------------------------------------------------------------------
# enclosures: rows from free space sum to 1
# ---------------------------------------------------------------------------------------
def inside_any_box(x, boxes):
    """Not in free space: inside an obstacle, or outside the unit room."""
    outside_room = np.any(x <= 0) or np.any(x >= 1)
    return outside_room or any(np.all(x > np.asarray(lo)) and np.all(x < np.asarray(hi))
                               for lo, hi in boxes)


# corners chosen off the face centroids of the room and of each other's faces, so that
# no receiving point lies exactly on an obstacle's surface (it would see into it)
FURNITURE = [
    [((0.21, 0.17, 0.31), (0.47, 0.53, 0.62))],                                   # floating
    [((0.11, 0.13, 0.0), (0.43, 0.39, 0.37)), ((0.29, 0.23, 0.19), (0.71, 0.83, 0.53))],
    [((0.61, 0.12, 0.09), (0.89, 0.31, 0.87)), ((0.07, 0.59, 0.04), (0.79, 0.73, 0.21)),
     ((0.33, 0.36, 0.37), (0.63, 0.67, 0.66))],
]


@pytest.mark.parametrize("boxes", FURNITURE)
@pytest.mark.parametrize("k", [1, 3])
def test_furnished_box_rows_sum_to_one(boxes, k):
    scene = ef.scenes.furnished_box(k, boxes, box_k=2 if k == 3 else 1)
    rows = [i for i in range(len(scene))
            if not inside_any_box(scene.centroids[i] + 1e-9 * scene.normals[i], boxes)]
    M = ef.form_factor_matrix(scene, rows=rows)
    assert np.all(M >= 0) and np.all(np.isfinite(M))
    assert_form_factors_close(M.sum(axis=1), np.ones(len(rows)), rtol=0, atol=OCC_ATOL)
    # the obstacles do occlude: some room-to-room value is below its unoccluded value
    flat = ef.point_polygon_form_factors(scene.centroids[0], scene.normals[0], scene)
    assert np.any(M[0] < flat - 1e-3)


@pytest.mark.parametrize("seed", range(3))
def test_random_points_in_furnished_box_sum_to_one(seed):
    rng = np.random.default_rng(seed)
    boxes = FURNITURE[2]
    scene = ef.scenes.furnished_box(2, boxes)
    pts = []
    while len(pts) < 5:
        x = rng.uniform(0.02, 0.98, 3)
        if not inside_any_box(x, boxes):
            pts.append(x)
    nrm = rng.normal(size=(5, 3))
    F = ef.form_factors(scene, np.array(pts), nrm)
    assert F.shape == (5, len(scene))
    assert_form_factors_close(F.sum(axis=1), np.ones(5), rtol=0, atol=OCC_ATOL)


def test_closed_cornell_box_rows_sum_to_one():
    scene = ef.scenes.cornell_box(closed=True)
    M = ef.form_factor_matrix(scene)
    assert_form_factors_close(M.sum(axis=1), np.ones(len(scene)), rtol=0, atol=OCC_ATOL)
    assert np.all(M >= 0)
    # the blocks hide part of the floor from the light
    light = scene.names.index("light")
    floor = scene.names.index("floor")
    unocc = ef.point_polygon_form_factors(scene.centroids[light], scene.normals[light], scene)
    assert M[light, floor] < unocc[floor] - 0.01


def test_coplanar_overlap_earlier_polygon_is_in_front():
    # the light lies on top of the whole ceiling (coplanar overlap): the polygon earlier
    # in input order (the light) is in front, so the ceiling's visible part is the cut
    # ceiling's, and the light's value does not change
    whole = ef.scenes.cornell_box(ceiling="whole", closed=True)
    cut = ef.scenes.cornell_box(closed=True)
    p, n = whole.centroids[whole.names.index("floor")], whole.normals[whole.names.index("floor")]
    Fw = ef.form_factors(whole, p, n)
    Fc = ef.form_factors(cut, p, n)
    li_w, li_c = whole.names.index("light"), cut.names.index("light")
    assert_form_factors_close(Fw[li_w], Fc[li_c], rtol=0, atol=OCC_ATOL)
    pieces = [i for i, nm in enumerate(cut.names) if nm.startswith("ceiling_")]
    assert_form_factors_close(Fw[whole.names.index("ceiling")], Fc[pieces].sum(), rtol=0,
                              atol=OCC_ATOL)


# ---------------------------------------------------------------------------------------
# invariants
# ---------------------------------------------------------------------------------------
@settings(max_examples=examples(15))
@given(occluder=st.tuples(st.floats(0.05, 0.6), st.floats(0.05, 0.6), st.floats(0.05, 0.35),
                          st.floats(0.05, 0.35), st.floats(0.1, 0.85)), flip=st.booleans())
def test_adding_an_occluder_never_raises_a_value(occluder, flip):
    base = ef.scenes.furnished_box(2, [((0.6, 0.55, 0.0), (0.9, 0.9, 0.4))])
    x0, y0, w, d, z = occluder
    extra = rect_xy(x0, x0 + w, y0, y0 + d, z, facing_down=flip)
    more = ef.Scene.from_polygons(list(base.polygons) + [extra])
    for i in (0, 5, 10, len(base) - 1):
        p, n = base.centroids[i], base.normals[i]
        F0 = ef.form_factors(base, p, n)
        F1 = ef.form_factors(more, p, n)[: len(base)]
        assert np.all(F1 <= F0 + OCC_ATOL)


@settings(max_examples=examples(10))
@given(axis=unit_vectors(), angle=st.floats(0, 2 * math.pi),
       shift=st.tuples(*[st.floats(-50, 50)] * 3))
def test_occluded_rows_invariant_under_rigid_motion(axis, angle, shift):
    boxes = FURNITURE[1]
    scene = ef.scenes.furnished_box(2, boxes)
    Rm = rotation(axis, angle)
    moved = ef.Scene.from_polygons([P @ Rm.T + shift for P in scene.polygons])
    for i in (0, 9, 20):
        F0 = ef.form_factors(scene, scene.centroids[i], scene.normals[i])
        F1 = ef.form_factors(moved, scene.centroids[i] @ Rm.T + shift, Rm @ scene.normals[i])
        # moved coordinates are rounded at |shift| ~ 50: ulp 7e-15 on unit-size geometry
        assert_form_factors_close(F1, F0, rtol=0, atol=1e-11)


def test_a_scene_turned_by_a_subnormal_angle_keeps_its_rows():
    # the furnished box turned by 2.2e-313 about z (found by the clean-clone CI's draw of
    # the test above): coordinates that were 0 become subnormal, the point lies a
    # subnormal distance off its floor; the compiled core's band slivers reached 1e307
    # and its row from the floor summed to 0.607 with them unchecked. A value whose
    # slivers exceed its own scale is now recomputed (the Python engine here); planted:
    # the slivers left unchecked again fails
    boxes = FURNITURE[1]
    scene = ef.scenes.furnished_box(2, boxes)
    Rm = rotation([0.0, 0.0, 1.0], 2.2250738585e-313)
    moved = ef.Scene.from_polygons([P @ Rm.T for P in scene.polygons])
    for i in (0, 9, 20):
        F0 = ef.form_factors(scene, scene.centroids[i], scene.normals[i])
        F1 = ef.form_factors(moved, scene.centroids[i] @ Rm.T, Rm @ scene.normals[i])
        assert_form_factors_close(F1, F0, rtol=0, atol=1e-11)


def test_splitting_polygons_keeps_occluded_totals():
    boxes = FURNITURE[1]
    coarse = ef.scenes.furnished_box(1, boxes, box_k=1)
    fine = ef.scenes.furnished_box(2, boxes, box_k=2)
    # the k = 2 scene splits every face of the k = 1 scene into 4 quads, in face order
    for pt, nv in [((0.5, 0.5, 0.95), (0, 0, -1)), ((0.05, 0.9, 0.5), (1, -0.3, 0)),
                   ((0.8, 0.5, 0.6), (-0.5, 0.2, -0.4))]:
        Fc = ef.form_factors(coarse, pt, nv)
        Ff = ef.form_factors(fine, pt, nv)
        assert_form_factors_close(Ff.reshape(-1, 4).sum(axis=1), Fc, rtol=0, atol=OCC_ATOL)


def strips(flip_first, flip_second):
    a = rect_xy(0.1, 0.4, 0.1, 0.9, 1.0)
    b = rect_xy(0.6, 0.9, 0.1, 0.9, 1.0)
    receiver = rect_xy(0.0, 1.0, 0.0, 1.0, 2.0)
    return ef.Scene.from_polygons([receiver, a[::-1] if flip_first else a,
                                   b[::-1] if flip_second else b])


def test_back_facing_occluder_still_occludes():
    g = np.linspace(0.05, 0.95, 5)
    pts = np.array([[x, y, 0.0] for x in g for y in g])
    ref = ef.form_factors(strips(False, False), pts, [0, 0, 1])
    for flips in [(True, False), (False, True), (True, True)]:
        F = ef.form_factors(strips(*flips), pts, [0, 0, 1])
        assert_form_factors_close(F[:, 0], ref[:, 0], rtol=0, atol=OCC_ATOL)
    # and the strips really hide part of the receiver
    unocc = np.array([ef.point_polygon_form_factor(p, [0, 0, 1], rect_xy(0, 1, 0, 1, 2.0))
                      for p in pts])
    assert np.all(ref[:, 0] < unocc)


def test_two_sided_receiving():
    scene = strips(True, False)
    p = [0.25, 0.5, 0.0]
    one = ef.form_factors(scene, p, [0, 0, 1])
    two = ef.form_factors(scene, p, [0, 0, 1], two_sided=True)
    assert one[1] == 0.0
    # nothing is in front of the strip: its back receives its unoccluded value
    assert_form_factors_close(two[1], ef.point_polygon_form_factor(
        p, [0, 0, 1], scene.polygons[1], two_sided=True), rtol=0, atol=OCC_ATOL)
    assert_form_factors_close(two[[0, 2]], one[[0, 2]], rtol=0, atol=OCC_ATOL)


# ---------------------------------------------------------------------------------------
# shortcuts never change a result
# ---------------------------------------------------------------------------------------
#: the Python engine's counts of work its shortcuts leave out
PYTHON_SHORTCUT_COUNTERS = ("covered_rejections", "bbox_rejections", "culled_below_horizon",
                            "charts_full")


@pytest.mark.parametrize("engine", ["compiled", "python"])
@pytest.mark.parametrize("scene_name", ["box", "cornell", "furnished"])
def test_shortcuts_are_neutral(scene_name, engine):
    scene = {"box": lambda: ef.scenes.subdivided_box(3),
             "cornell": lambda: ef.scenes.cornell_box(closed=True),
             "furnished": lambda: ef.scenes.furnished_box(2, FURNITURE[2])}[scene_name]()
    rng = np.random.default_rng(1)
    used = set()
    for i in rng.choice(len(scene), size=min(8, len(scene)), replace=False):
        p, n = scene.centroids[i], scene.normals[i]
        st_on, st_off = {}, {}
        on = Exact(engine=engine).point_form_factors(scene, p, n, stats=st_on)
        off = Exact(shortcuts=False, engine=engine).point_form_factors(scene, p, n,
                                                                       stats=st_off)
        assert_form_factors_close(on, off, rtol=0, atol=1e-13)
        if engine == "python":
            # with shortcuts off, none of the work they leave out is left out
            assert st_off["path"] == "clipper"
            assert all(st_off[k] == 0 for k in PYTHON_SHORTCUT_COUNTERS), st_off
        else:
            assert st_off["path"] == "compiled" and st_off["subtrees_culled"] == 0
            if st_on.get("subtrees_culled"):
                # culled subtrees' fragments were never filtered
                assert st_on["fragments"] < st_off["fragments"]
        used |= {k for k, v in st_on.items() if k != "path" and v} | {st_on["path"]}
    if scene_name == "box":
        assert "unoccluded" in used              # convex room: the clipper is skipped
    elif engine == "python":
        # work really left out (not flags): fragments hidden or kept whole without an
        # overlay, and fragments below the horizon culled (each 0 with shortcuts off,
        # above; culled_edge_on is no shortcut: edge-on fragments have no image either way)
        assert set(PYTHON_SHORTCUT_COUNTERS) <= used
    else:
        assert "subtrees_culled" in used


def test_convex_scene_detection():
    from exactff.visibility import is_convex_enclosure
    assert is_convex_enclosure(ef.scenes.subdivided_box(2))
    assert not is_convex_enclosure(ef.scenes.cornell_box(closed=True))
    assert not is_convex_enclosure(ef.scenes.furnished_box(1, FURNITURE[0]))


def test_point_outside_convex_room_uses_clipper():
    box = ef.scenes.subdivided_box(2)
    st = {}
    F = Exact(engine="python").point_form_factors(box, np.array([0.5, 0.5, -1.0]),
                                                  np.array([0, 0, 1.0]), stats=st)
    assert st["path"] == "clipper"
    assert np.all(F == 0)   # from outside only back faces are seen
    F = Exact(engine="compiled").point_form_factors(box, np.array([0.5, 0.5, -1.0]),
                                                    np.array([0, 0, 1.0]), stats=st)
    assert st["path"] == "compiled"
    assert np.all(F == 0)   # from outside only back faces are seen


def test_horizon_culling_is_neutral():
    # polygons wholly below the horizon change nothing
    above = [rect_xy(-1, 1, -1, 1, 1.0), rect_xy(0, 2, 0, 1, 0.5)]
    below = [rect_xy(-1, 1, -1, 1, -1.0, facing_down=False), rect_xy(-3, 3, -3, 3, -0.2)]
    F1 = ef.form_factors(ef.Scene.from_polygons(above), [0, 0, 0], [0, 0, 1])
    st = {}
    F2 = Exact(engine="python").point_form_factors(ef.Scene.from_polygons(above + below),
                                                   np.zeros(3), np.array([0, 0, 1.0]),
                                                   stats=st)
    assert st["culled_below_horizon"] == 2
    assert_form_factors_close(F2[:2], F1, rtol=0, atol=1e-14)
    assert np.all(F2[2:] == 0)


# ---------------------------------------------------------------------------------------
# API behaviour
# ---------------------------------------------------------------------------------------
def test_form_factors_broadcast_vs_loop():
    scene = ef.scenes.furnished_box(1, FURNITURE[0])
    pts = np.array([[0.1, 0.2, 0.05], [0.9, 0.8, 0.7], [0.5, 0.95, 0.5]])
    F = ef.form_factors(scene, pts[:, None, :], [[0, 0, 1], [0, 1, 0]])
    assert F.shape == (3, 2, len(scene))
    for a in range(3):
        for b, nv in enumerate([[0, 0, 1], [0, 1, 0]]):
            assert np.array_equal(F[a, b], ef.form_factors(scene, pts[a], nv))


def test_bad_arguments():
    scene = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match="method must be one of"):
        ef.form_factors(scene, [0.5] * 3, [0, 0, 1], method="nope")
    with pytest.raises(ValueError, match="normal"):
        ef.form_factors(scene, [0.5] * 3, [0, 0, 0])
    with pytest.raises(ValueError, match="point"):
        ef.form_factors(scene, [0.5, np.nan, 0.5], [0, 0, 1])
    with pytest.raises(ValueError, match="broadcast"):
        ef.form_factors(scene, np.zeros((2, 3)), np.ones((3, 3)))
    with pytest.raises(ValueError, match="rows"):
        ef.form_factor_matrix(scene, rows=[0, 6])


def test_matrix_executor_progress_and_resume(tmp_path):
    from concurrent.futures import ThreadPoolExecutor

    scene = ef.scenes.furnished_box(1, FURNITURE[0])
    ref = ef.form_factor_matrix(scene)
    with ThreadPoolExecutor(2) as ex:
        M = ef.form_factor_matrix(scene, executor=ex, chunk_rows=2)
    assert np.array_equal(M, ref)
    path = tmp_path / "m.npy"
    # an interrupted run: only some rows written, the done-mask says which
    part = ef.form_factor_matrix(scene, rows=range(len(scene)), out=path)
    assert np.array_equal(np.load(path), ref)
    assert not (tmp_path / "m.done.npy").exists()
    mm = np.lib.format.open_memmap(path, mode="r+")
    mm[3:] = -1.0
    mm.flush()
    del mm, part
    done = np.zeros(len(scene), bool)
    done[:3] = True
    np.save(tmp_path / "m.done.npy", done)
    M2 = ef.form_factor_matrix(scene, out=path, progress=True)
    assert np.array_equal(np.asarray(M2), ref)
    # a different computation does not silently reuse the file
    other = ef.scenes.furnished_box(1, [((0.1, 0.2, 0.3), (0.4, 0.5, 0.6))])
    assert len(other) == len(scene)
    with pytest.raises(ValueError, match="not written by this computation"):
        ef.form_factor_matrix(other, out=path)
    with pytest.raises(ValueError, match="not written by this computation"):
        ef.form_factor_matrix(scene, out=path, two_sided=True)


# ---------------------------------------------------------------------------------------
# issue 48: the Python engine (the oracle) within its own bound of the rational reference
# ---------------------------------------------------------------------------------------
#: A flush pair far from the origin (flush_faces, drawn): the flush face (polygon 1)
#: crosses the base's plane and the BSP splits it there, its crossings rounded to doubles
#: of magnitude 4e3 (an ulp 4.5e-13). Python engine 0.1553197024312614 with a bound of
#: 1.1e-14 before the crossings' rounding was charged; the reference 0.15531970243124346.
FLUSH_FAR = (
    [[[2289.2658289027486, 3768.3837874794144, -816.2810495820108],
      [2288.9929019422702, 3770.4951449876635, -815.4951057581036],
      [2290.197242160082, 3768.6736471073336, -816.2956188211137]],
     [[2290.5898519775324, 3769.590740855709, -816.0188458843438],
      [2288.723026038973, 3768.0555846358243, -816.3292479020378],
      [2288.2953108449137, 3769.5510848333925, -815.7429260935832]],
     [[2289.6351933812275, 3770.589897293482, -816.4340030776805],
      [2289.456352152465, 3770.3333719517304, -816.5026962478908],
      [2289.2499463618888, 3770.315866103441, -816.4828366719505],
      [2289.150800100656, 3770.3636751762174, -816.4532888782317],
      [2289.0472657916994, 3770.5387059676577, -816.377907417983],
      [2289.239781274529, 3770.8456484782155, -816.2929989073652],
      [2289.3928846739923, 3770.863904694789, -816.3058539161918],
      [2289.565135354931, 3770.7764868214676, -816.3587392452825]]],
    [2289.2498223587936, 3770.0203977879974, -817.4068608419406],
    [0.17038908145598294, -0.7083772468132975, 0.6849592959569197])


def _python_within_its_bound(scene, p, n, targets=None):
    """Every value of the Python engine (default tolerance, error=True) that the rational
    construction decides within the engine's own bound of it, and every bound within
    the accuracy target; returns how many were decided."""
    from exact_visibility import visible_form_factor

    G, H = Exact(engine="python").point_form_factors(scene, p, n, error=True)
    assert np.all(H <= 1e-11), float(H.max())
    decided = 0
    for j in range(len(scene)) if targets is None else targets:
        U = visible_form_factor(scene, p, n, j)
        if U is None:
            continue
        assert abs(G[j] - U) <= H[j], (j, G[j], float(U), H[j])
        decided += 1
    return decided


def test_python_engine_charges_its_rounded_crossings():
    polys, p, n = FLUSH_FAR
    scene = ef.Scene.from_polygons([np.array(P) for P in polys])
    assert _python_within_its_bound(scene, np.array(p), np.array(n)) == 3


def test_python_sphere_rows_charge_the_rounded_crossings():
    # the Python engine's spherical rows had no term for the BSP's rounded crossings
    # (its form factors have had one, engine._crossing_charges): the closed Cornell
    # box's floor is split at x = 326.076 (fragments 13 and 21). Taking a split vertex of
    # fragment 13 (326.076, 0, 0) as uncertain by r = 1 (in a box of 550), the row's bound must cover the
    # row computed with that vertex moved by r
    from exactff.visibility.bsp import scene_bsp

    scene = ef.scenes.cornell_box(closed=True)
    tree, buckets = scene_bsp(scene)   # (this scene's own: cached on it)
    f, k, r = 13, 1, 1.0
    assert tree.source[f] == 20 and tree.vertex_errors[f][k] > 0
    tree.vertex_errors[f][k] = r
    p = np.array([278.0, 274.0, 280.0])
    method = ef.Exact(engine="python")
    S0, E0 = method.point_sphere_factors(scene, p, error=True)
    # the same vertex moved by r away from the split line (-x: a gap opens between the halves; across it, fragment 21 would hide the overlap), in the tree and its bucket
    tree.fragments[f][k, 0] -= r
    for ids, Vb, cb in buckets:
        if f in ids:
            Vb[list(ids).index(f), k, 0] -= r
    S1, E1 = method.point_sphere_factors(scene, p, error=True)
    moved_by = np.abs(S1 - S0)
    assert moved_by[20] > 1e-5                      # the move is seen
    assert np.all(moved_by <= E0 + E1), (moved_by[20], E0[20])


@settings(max_examples=examples(30))
@given(case=flush_faces())
def test_python_engine_within_its_bound_on_flush_faces(case):
    # faces flush to 1e-16..1e-9 of their size, crossing at grazing angles, far from the
    # origin: over 300 drawn scenes (897 decided values) the Python engine missed its
    # bound 4 times (by up to 5.0e-14) before its BSP crossings' rounding was charged
    scene, p, n = case
    _python_within_its_bound(scene, p, n)


def test_python_engine_labels_edges_by_the_nearest_plane_in_front():
    # SampleHouse4 row 21905 (the centroid of polygon 21905), the polygons within 0.3 m
    # of the lines to four targets' centroids: a curtain wall's plates seen past the
    # mullions flush with their edges to 2e-14. The refinement took a plate's own edge
    # (residual 1.5e-14 from the clipper's edge) without looking at the mullion's in
    # front (4e-17): plate 359 came out 0 +- 0 against 2.1e-15, plate 481 9.2e-16 beyond
    # its bound (on the whole row: 343, 359, 481 and 15515, by 1.25e-15 at most)
    from common import load_real_file

    scene = load_real_file("ifc-SampleHouse4.obj", tempfile.mkdtemp(prefix="exactff-sh4-"))
    row, targets = 21905, [343, 359, 481, 15515]
    p, n = scene.centroids[row], scene.normals[row]
    keep = set(targets)
    C = scene.centroids
    for t in targets:
        d = C[t] - p
        length = np.linalg.norm(d)
        d = d / length
        s = np.clip((C - p) @ d, 0, length)
        keep |= set(np.flatnonzero(np.linalg.norm(C - p - s[:, None] * d, axis=1)
                                   < 0.3).tolist())
    keep = sorted(keep)
    sub = ef.Scene.from_polygons([scene.polygons[i] for i in keep])
    assert len(sub) == 232
    assert _python_within_its_bound(sub, p, n, [keep.index(t) for t in targets]) == 4
