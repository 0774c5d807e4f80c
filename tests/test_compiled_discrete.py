"""The compiled z-buffer of the discrete methods against its numpy oracle (issue 55):
the hemicube, the cubic tetrahedron and the single plane (planar faces,
``exactff.methods._raster.rasterise_face``), the polar plane (``rasterise_polar``) and
discrete PPBH (the disk's ellipse arcs, ``rasterise_disk``).

The compiled backend (``exactff.methods._zbuffer``) scan-converts and depth-tests as
the numpy rasteriser does, cell for cell: the same scanlines, the same crossings from
an edge's lower end point, the same even-odd spans, the same depths and the same
chunked depth-tie rule (coplanar by the BSP tree's rule, then ``tie_priority``). So
the polygon shown in every cell is identical, not merely close: every test here asks
for ``array_equal``, on the scene families of the native tests (tests/test_native_discrete.py),
the zero-thickness walls and same-facing overlaps of tests/test_ties.py and the faces flush
to within rounding of tests/test_near_coplanar_band.py.
"""

import numpy as np
import pytest
from hypothesis import given, settings

import exactff as ef
import exactff.methods._raster as raster
from exactff import _tolerances as tol
from exactff.checks import as_receiver
from exactff.testing import strategies

from common import discrete_methods, examples, small_discrete_methods

#: the methods with a compiled rasteriser, and their resolutions (those of the native
#: tests)
COMPILED = discrete_methods()
SMALL = list(small_discrete_methods().values())


def assert_backends_identical(make, scene, point, normal):
    """Every cell shows the same polygon with both backends; returns the cells."""
    p, n = as_receiver(point, normal)
    compiled = make().native_hits(scene, p, n)
    oracle = make(backend="numpy").native_hits(scene, p, n)
    diff = np.flatnonzero(compiled != oracle)
    assert len(diff) == 0, (len(diff), diff[:5], compiled[diff[:5]], oracle[diff[:5]])
    return compiled


def _rows(scene, k, seed=0):
    rng = np.random.default_rng(seed)
    for i in rng.choice(len(scene), k, replace=False):
        yield scene.centroids[i] + 1e-3 * scene.normals[i], scene.normals[i]


SCENES = {"cornell": ef.scenes.cornell_box, "office": ef.scenes.office,
          "box": lambda: ef.scenes.subdivided_box(3),
          "building": lambda: ef.scenes.building(2, 2),
          "walls_low": lambda: ef.scenes.building(2, 1, walls_first="low"),
          "walls_high": lambda: ef.scenes.building(2, 1, walls_first="high"),
          "light_on_ceiling": lambda: ef.scenes.cornell_box(ceiling="whole", closed=True)}


@pytest.mark.parametrize("method", sorted(COMPILED))
@pytest.mark.parametrize("scene_name", sorted(SCENES))
def test_compiled_cells_identical_to_numpy(method, scene_name):
    scene = SCENES[scene_name]()
    for p, n in _rows(scene, 3):
        assert_backends_identical(COMPILED[method], scene, p, n)


@pytest.mark.parametrize("method", ["hemicube-64", "tetra-52", "plane-refined", "polar-20x48",
                                    "ppbh-64"])
@pytest.mark.parametrize("scene_name", ["walls_low", "walls_high", "light_on_ceiling"])
def test_compiled_cells_identical_to_numpy_on_ties_from_the_floor(method, scene_name):
    # the rows of test_ties.py: from the floors, through zero-thickness walls (back to
    # back, coplanar) and a light on a whole ceiling (same facing, coplanar)
    scene = SCENES[scene_name]()
    floors = [i for i, g in enumerate(scene.groups) if g == "floor"] or [
        scene.names.index("floor")]
    for i in floors:
        hit = assert_backends_identical(COMPILED[method], scene, scene.centroids[i],
                                        scene.normals[i])
        if method.startswith(("hemicube", "ppbh")):
            assert np.all(hit >= 0)     # closed: every cell shows a polygon


@pytest.mark.parametrize("method", ["hemicube-64", "tetra-52", "plane-refined", "polar-20x48",
                                    "ppbh-64"])
@pytest.mark.parametrize("scene_name", ["office", "building", "light_on_ceiling"])
def test_compiled_cells_identical_to_numpy_in_small_chunks(method, scene_name, monkeypatch):
    # chunks of a few scanlines and a few hundred candidates: the depth buffer merges
    # chunk after chunk, the tie rule across chunks included (both backends use the
    # module's chunk sizes)
    monkeypatch.setattr(raster, "PAIR_CHUNK", 40)
    monkeypatch.setattr(raster, "DEPTH_CHUNK", 300)
    scene = SCENES[scene_name]()
    for p, n in _rows(scene, 2, seed=1):
        assert_backends_identical(COMPILED[method], scene, p, n)


def aligned_box():
    """A closed box [-1, 1]^2 x [0, 1], each face in 16 x 16 tiles: from the origin the
    tiles' edges project exactly onto the scanlines and cell centres of a hemicube of
    resolution 8 (odd multiples of 1/8), where the shared-edge rule decides."""
    box = ef.scenes.subdivided_box(16, size=(2.0, 2.0, 1.0))
    return ef.Scene.from_polygons([P - [1.0, 1.0, 0.0] for P in box.polygons])


@pytest.mark.parametrize("resolution", [8, 16])
@pytest.mark.parametrize("point", [(0.0, 0.0, 0.0), (0.125, -0.25, 0.0)])
def test_compiled_cells_identical_to_numpy_on_edges_through_cell_centres(resolution, point):
    scene = aligned_box()
    make = lambda **k: ef.Hemicube(resolution=resolution, **k)
    hit = assert_backends_identical(make, scene, point, [0.0, 0.0, 1.0])
    assert np.all(hit >= 0)
    if resolution == 8:
        # the premise: every top-face cell centre lies on a corner of the ceiling's
        # tiles (x / z and y / z odd multiples of 1/8), on the tiles' shared edges
        from exactff.methods.hemicube import _grid

        c = 8.0 * (_grid(8, -1.0, 1.0)[0][:, None] - np.array(point[:2]))
        assert np.array_equal(c, np.round(c))


@given(strategies.enclosures())
@settings(max_examples=examples(25), deadline=None)
def test_compiled_cells_identical_to_numpy_in_random_rooms(case):
    scene, p, n = case
    for make in SMALL:
        assert_backends_identical(make, scene, p, n)


@given(strategies.occluded_scenes())
@settings(max_examples=examples(25), deadline=None)
def test_compiled_cells_identical_to_numpy_in_occluded_scenes(case):
    scene, p, n = case
    for make in SMALL:
        assert_backends_identical(make, scene, p, n)


@given(strategies.flush_faces())
@settings(max_examples=examples(40), deadline=None)
def test_compiled_cells_identical_to_numpy_on_flush_faces(case):
    # faces flush to within rounding: coplanar by the band or ordered by the geometry,
    # crossing at grazing angles; the tie rule decides many cells
    scene, p, n = case
    for make in SMALL:
        assert_backends_identical(make, scene, p, n)


@given(strategies.flush_faces())
@settings(max_examples=examples(40), deadline=None)
def test_compiled_cells_identical_to_numpy_on_flush_faces_in_small_chunks(case):
    # the tie rule across chunks: a face flush with one drawn in an earlier chunk
    scene, p, n = case
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(raster, "PAIR_CHUNK", 5)
        mp.setattr(raster, "DEPTH_CHUNK", 50)
        for make in SMALL:
            assert_backends_identical(make, scene, p, n)


def clip_pairs():
    """(numpy clipper, compiled clipper) pairs, each ``clip(V, counts) -> (live, UV,
    cl)``: the five charts (chart_clip, margin 0), the cubic tetrahedron's faces and
    the single and polar planes (FaceClip)."""
    from exactff.methods import _zbuffer
    from exactff.methods._raster import face_clipper, plane_clipper
    from exactff.methods.cubic_tetrahedron import cubic_tetrahedron_frame
    from exactff.visibility.charts import CHARTS, chart_clip, chart_planes

    pairs = [(lambda V, c, ch=ch: chart_clip(V, c, ch),
              lambda V, c, ch=ch: _zbuffer.chart_clip(V, c, np.array(chart_planes(ch)), *ch,
                                                      tol.CLIP_MEET_ULPS, tol.CHART_EDGE_ULPS))
             for ch in CHARTS]
    a1, a2, a3 = cubic_tetrahedron_frame()
    tetra = [[-1.0, 0.0, 1.0], [0.0, -1.0, 1.0], [1.0, 1.0, 1.0]]
    for clip in (face_clipper([a2, a3, a1], tetra), face_clipper([a3, a1, a2], tetra),
                 plane_clipper(4.0), plane_clipper(10.0)):
        pairs.append((clip, lambda V, c, f=clip: _zbuffer.face_clip(V, c, f.R, f.planes, f.scale,
                                                                    tol.CLIP_MEET_ULPS)))
    return pairs


def assert_clips_identical(scene, p, n):
    """Each compiled clipper gives its numpy clipper's live polygons, counts and
    coordinates, bit for bit, for every bucket of the row."""
    from exactff.methods._sampling import ZBufferRow

    p, n = as_receiver(p, n)
    for numpy_clip, compiled_clip in clip_pairs():
        for _, V, counts in ZBufferRow(scene, p, n).local:
            live, UV, cl = numpy_clip(V, counts)
            live_c, UV_c, cl_c = compiled_clip(V, counts)
            assert np.array_equal(live_c, live) and np.array_equal(cl_c, cl)
            assert UV_c.shape == UV.shape
            assert np.array_equal(UV_c, UV, equal_nan=True)


@pytest.mark.parametrize("scene_name", ["office", "building", "cornell"])
def test_compiled_clips_identical_to_numpy(scene_name):
    scene = SCENES[scene_name]()
    for p, n in _rows(scene, 4, seed=2):
        assert_clips_identical(scene, p, n)
        # from the polygon's centroid itself: the point on its plane
        i = int(np.argmin(np.linalg.norm(scene.centroids - p, axis=1)))
        assert_clips_identical(scene, scene.centroids[i], scene.normals[i])


@given(strategies.occluded_scenes() | strategies.enclosures() | strategies.flush_faces())
@settings(max_examples=examples(40), deadline=None)
def test_compiled_clips_identical_to_numpy_in_random_scenes(case):
    assert_clips_identical(*case)


@pytest.mark.parametrize("method", ["hemicube-64", "tetra-52", "plane-refined", "polar-20x48",
                                    "ppbh-64"])
def test_compiled_rows_equal_numpy_rows(method):
    # through the public interface: the rows are equal to the last bit
    scene = ef.scenes.office()
    for p, n in _rows(scene, 2, seed=3):
        F1 = ef.form_factors(scene, p, n, method=COMPILED[method]())
        F0 = ef.form_factors(scene, p, n, method=COMPILED[method](backend="numpy"))
        assert np.array_equal(F1, F0)


def test_face_clip_rejects_planes_it_cannot_test_exactly():
    # a plane with other entries would make h . W depend on the order of the products
    from exactff.methods._raster import face_clipper

    with pytest.raises(ValueError, match="entries must be 0, 1 or -1"):
        face_clipper(np.eye(3), [[0.5, 0.0, 1.0]])


@pytest.mark.parametrize("method", sorted(COMPILED))
def test_backend_option_checked_and_in_repr(method):
    assert COMPILED[method]().backend == "compiled"
    assert "backend" not in repr(COMPILED[method]())
    assert "backend='numpy'" in repr(COMPILED[method](backend="numpy"))
    with pytest.raises(ValueError, match="backend"):
        COMPILED[method](backend="cuda")


def test_zbuffer_rejects_a_buffer_it_cannot_write():
    # a depth buffer of another dtype would be converted, and the results lost
    from exactff.methods._sampling import ZBufferRow

    scene = ef.scenes.cornell_box()
    m = ef.Hemicube(resolution=8)
    L = m.layout()
    z = ZBufferRow(scene, scene.centroids[0], scene.normals[0])
    zb = raster.compiled_zbuffer(z, L)
    UV = np.zeros((1, 3, 2))
    args = (UV, np.array([3]), np.array([0]), np.arange(8.0), np.arange(8.0),
            np.zeros((8, 8), dtype=np.int64))
    with pytest.raises(ValueError, match="best_t and best"):
        zb.face(*args, np.full(len(L), np.inf), np.full(len(L), -1, dtype=np.int32), 10, 10)
    with pytest.raises(ValueError, match="src out of range"):
        zb.face(UV, np.array([3]), np.array([10 ** 6]), *args[3:], np.full(len(L), np.inf),
                np.full(len(L), -1, dtype=np.int64), 10, 10)


@pytest.mark.parametrize("fold", ["within_rows", "across_rows"])
@pytest.mark.parametrize("scene_name", ["walls_low", "box"])
def test_compiled_cells_identical_to_numpy_on_tables_sharing_cells(fold, scene_name):
    # a table that gives one layout cell to two grid cells (within a scanline, or in two
    # scanlines): the compiled scan cannot resolve such a chunk scanline by scanline
    # and resolves it candidate by candidate, as the numpy code does (scanline by
    # scanline, the shared cells of the walls' and the box's tiles differ)
    from exactff.methods._sampling import ZBufferRow

    scene = SCENES[scene_name]()
    m = ef.Hemicube(resolution=32)
    L = m.layout()
    chart, uc, vc, table = m._faces()[0]
    r = len(uc)
    if fold == "within_rows":
        table = table[:, np.minimum(np.arange(r), r - 1 - np.arange(r))]
    else:
        table = table[np.arange(r) // 2 * 2]
    table = np.ascontiguousarray(table)
    assert len(np.unique(table)) < table.size       # the premise: cells shared
    rows = list(_rows(scene, 3, seed=2))
    if scene_name == "walls_low":
        rows += [(scene.centroids[i], scene.normals[i])
                 for i, g in enumerate(scene.groups) if g == "floor"]
    for p, n in rows:
        p, n = as_receiver(p, n)
        z = ZBufferRow(scene, p, n)
        out = []
        for zb in (raster.compiled_zbuffer(z, L), None):
            best_t = np.full(len(L), np.inf)
            best = np.full(len(L), -1, dtype=np.int64)
            raster.rasterise_face(z, chart, uc, vc, table, L.directions, best_t, best,
                                  zbuffer=zb)
            out.append(best)
        assert np.array_equal(out[0], out[1])
        assert (out[1] >= 0).sum() > r * r // 4        # the face shows polygons


def test_row_sums_reject_cells_beyond_the_live_polygons():
    # a cell showing live polygon L (of L) would read past ids: an error, not a row
    from exactff.methods._zbuffer import row_sums

    ids = np.array([2, 0, 1])
    receives = np.ones(3, dtype=bool)
    F, hit = row_sums(np.array([0, -1, 2, 2]), ids, receives, np.full(4, 0.25), 3)
    assert F.tolist() == [0.0, 0.5, 0.25] and hit == 3        # np.bincount's sums
    with pytest.raises(ValueError, match="best out of range"):
        row_sums(np.array([0, -1, 3, 2]), ids, receives, np.full(4, 0.25), 3)


def test_compiled_scan_rejects_tables_beyond_the_buffer():
    from exactff.methods._sampling import ZBufferRow

    scene = ef.scenes.cornell_box()
    m = ef.Hemicube(resolution=8)
    L = m.layout()
    chart, uc, vc, table = m._faces()[0]
    z = ZBufferRow(scene, scene.centroids[0], scene.normals[0])
    with pytest.raises(ValueError, match="table's cells out of range"):
        raster.rasterise_face(z, chart, uc, vc, table + len(L), L.directions,
                              np.full(len(L), np.inf), np.full(len(L), -1, dtype=np.int64),
                              zbuffer=raster.compiled_zbuffer(z, L))


@pytest.mark.parametrize("scene_name", ["office", "cornell", "walls_low"])
def test_compiled_row_setup_is_the_numpy_one(scene_name):
    # ZBufferRow's live polygons (compiled live_local) against the numpy expressions
    # they replaced: to_local of every padded vertex, alive (not edge-on) with a vertex
    # above the horizon; the same polygons and the same local vertices, bit for bit
    from exactff.geometry import receiver_frame, to_local
    from exactff.kernel import flat_polygons
    from exactff.methods._sampling import ZBufferRow, _polygon_buckets
    from exactff.predicates import plane_sides

    scene = SCENES[scene_name]()
    rng = np.random.default_rng(13)
    for p, n in list(_rows(scene, 3, seed=3)) + [(scene.centroids[0], rng.normal(size=3))]:
        p, n = as_receiver(p, n / np.linalg.norm(n))
        z = ZBufferRow(scene, p, n)
        side, _ = plane_sides(flat_polygons(scene), p, exact=False)
        R = receiver_frame(n)
        want_V, want_ids = [], []
        for b_ids, Vb, cb in _polygon_buckets(scene):
            V = to_local(Vb, p, R)
            slot = np.arange(V.shape[1])[None, :] < cb[:, None]
            live = (side[b_ids] != 0) & (np.where(slot, V[:, :, 2], -np.inf).max(axis=1) > 0)
            if live.any():
                want_V.append(V[live])
                want_ids.append(b_ids[live])
        assert 0 < len(z.ids) < len(scene) or scene_name != "office"
        assert np.array_equal(z.ids, np.concatenate(want_ids))
        assert len(z.local) == len(want_V)
        for (g, V, counts), W in zip(z.local, want_V):
            assert np.array_equal(V, W)


# ---- Monte Carlo: the shared core's rays through the compiled z-buffer ----

def test_compiled_ray_directions_are_the_numpy_expressions():
    # cosine_directions against the numpy expressions it replaced (the disk's points
    # lifted, normalised as CellLayout normalises): bit for bit where numpy's cos and
    # sin are libm's (as here), within an ulp of each coordinate anyway
    import math

    from exactff.methods._sampling import CellLayout
    from exactff.methods._zbuffer import cosine_directions

    rng = np.random.default_rng(11)
    q1, q2 = rng.random(50000), rng.random(50000)
    q1[:3] = [0.0, 1.0 - 2.0 ** -53, 0.25]        # the centre, the rim, a quarter
    r, a = np.sqrt(q1), 2.0 * np.pi * q2
    x, y = r * np.cos(a), r * np.sin(a)
    D = np.column_stack([x, y, np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))])
    D[D[:, 2] == 0, 2] = 1e-300
    L = CellLayout(D, np.ones(len(D)), 1.0)
    got, norms = cosine_directions(q1, q2)
    assert np.all(np.abs(got - L.directions) <= np.spacing(np.abs(L.directions)))
    assert np.all(got[:, 2] > 0)
    libm = all(np.cos(t) == math.cos(t) and np.sin(t) == math.sin(t) for t in a[:2000])
    if libm:
        assert np.array_equal(got, L.directions)
    assert np.array_equal(norms, np.linalg.norm(got, axis=1))


def test_compiled_direction_norms_are_numpys():
    # the depth-tie slack's norms: np.linalg.norm's sum, (x x + y y) + z z, on
    # directions of any length
    from exactff.methods._zbuffer import direction_norms

    rng = np.random.default_rng(12)
    D = rng.standard_normal((100000, 3)) * 10.0 ** rng.uniform(-3, 3, (100000, 3))
    assert np.array_equal(direction_norms(D), np.linalg.norm(D, axis=1))


@pytest.mark.parametrize("samples", [1, 50, 4000, 65536])
def test_compiled_ray_charts_are_the_numpy_grid(samples):
    # ray_charts against _chart_of and _cell_grid: the same charts, buckets, order (a
    # stable sort) and renumbering, so that chart_rays sees the candidates of the
    # numpy code in its order
    from exactff.methods._sampling import (_CHART_AXIS, _CHART_SIGN_W, _cell_grid,
                                           _chart_of)
    from exactff.methods._zbuffer import ray_charts
    from exactff.visibility.charts import CHARTS

    D, _ = ef.MonteCarlo(samples, seed=7).directions_for(np.zeros(3))
    if samples == 4000:
        D = ef.Hemicube(resolution=36).layout().directions     # on the charts' edges
    Dp, norms, slot, charts = ray_charts(D, _CHART_AXIS, _CHART_SIGN_W, tol.CHART_MARGIN)
    chart, u, v = _chart_of(D)
    perm = []
    for ci, ids, cu, cv, nb, v_lo, order, starts in charts:
        cells = np.flatnonzero(chart == ci)
        g = _cell_grid(u[cells], v[cells], CHARTS[ci][3])
        assert (nb, v_lo) == g[:2] and np.array_equal(starts, g[3])
        assert np.array_equal(cu, u[cells][g[2]]) and np.array_equal(cv, v[cells][g[2]])
        assert np.array_equal(ids, len(np.concatenate(perm or [[]])) + np.arange(len(cells)))
        assert np.array_equal(order, np.arange(len(cells)))
        perm.append(cells[g[2]])
    perm = np.concatenate(perm)
    assert [c[0] for c in charts] == [ci for ci in range(5) if (chart == ci).any()]
    assert np.array_equal(slot[perm], np.arange(len(D)))
    assert np.array_equal(Dp, D[perm])
    assert np.array_equal(norms, np.linalg.norm(Dp, axis=1))


def assert_rays_identical(scene, point, normal, seed=0, samples=4000):
    """The compiled shared core against its numpy code: bit for bit with the charts'
    exact frustums (margin 0, what the compiled one clips to), and the same hits as
    the numpy code's widened frustums (CHART_MARGIN: only a ray within rounding of a
    chart's edge and of a polygon's edge there could differ)."""
    from exactff.methods._sampling import nearest_polygons

    p, n = as_receiver(point, normal)
    D, _ = ef.MonteCarlo(samples, seed=seed).directions_for(p)
    compiled = nearest_polygons(scene, p, n, D, backend="compiled")
    exact_frustum = nearest_polygons(scene, p, n, D, margin=0.0)
    widened = nearest_polygons(scene, p, n, D)
    assert np.array_equal(compiled, exact_frustum)
    assert np.array_equal(compiled, widened)
    return compiled


@pytest.mark.parametrize("scene_name", sorted(SCENES))
def test_compiled_rays_identical_to_numpy(scene_name):
    scene = SCENES[scene_name]()
    for p, n in _rows(scene, 3, seed=4):
        assert_rays_identical(scene, p, n)


@pytest.mark.parametrize("scene_name", ["walls_low", "walls_high", "light_on_ceiling"])
def test_compiled_rays_identical_to_numpy_on_ties_from_the_floor(scene_name):
    scene = SCENES[scene_name]()
    floors = [i for i, g in enumerate(scene.groups) if g == "floor"] or [
        scene.names.index("floor")]
    for i in floors:
        hit = assert_rays_identical(scene, scene.centroids[i], scene.normals[i])
        assert np.all(hit >= 0)


@pytest.mark.parametrize("scene_name", ["office", "building", "light_on_ceiling"])
def test_compiled_rays_identical_to_numpy_in_small_chunks(scene_name, monkeypatch):
    import exactff.methods._sampling as sampling

    monkeypatch.setattr(sampling, "PAIR_CHUNK", 300)
    scene = SCENES[scene_name]()
    for p, n in _rows(scene, 2, seed=5):
        assert_rays_identical(scene, p, n)


def test_compiled_rays_identical_to_numpy_through_cell_layouts():
    # grid layouts (cells on shared edges and chart edges), not random rays
    from exactff.methods._sampling import _chart_of, nearest_polygons

    scene = aligned_box()
    for m in (ef.Hemicube(resolution=16), ef.DiscretePPBH(resolution=40),
              ef.CubicTetrahedron(resolution=20)):
        D = m.layout().directions
        for point in [(0.0, 0.0, 0.0), (0.125, -0.25, 0.0)]:
            p, n = as_receiver(point, [0.0, 0.0, 1.0])
            compiled = nearest_polygons(scene, p, n, D, backend="compiled")
            assert np.array_equal(compiled, nearest_polygons(scene, p, n, D, margin=0.0))
            # closed: every cell shows a polygon, but cells exactly on a chart's edge
            # (discrete PPBH's diagonal |x| = |y|: u = 1), which an image clipped to
            # the exact frustum has on its boundary; the numpy code widens the
            # frustums for them (random rays are not there)
            _, u, v = _chart_of(D)
            on_edge = (np.abs(u) == 1.0) | (np.abs(v) == 1.0) | (v == 0.0)
            assert np.all(compiled[~on_edge] >= 0)
            if isinstance(m, ef.Hemicube):
                assert not on_edge.any()


def test_compiled_rays_leave_long_polygons_to_numpy():
    # a 300-gon (wider than LONG_POLYGON): the numpy code tests it with shapely, and
    # the compiled backend hands that bucket back to it, in order
    room = ef.scenes.furnished_box(2, [((0.1, 0.1, 0.0), (0.3, 0.35, 0.6))])
    t = 2 * np.pi * np.arange(300) / 300
    disc = np.column_stack([0.3 * np.cos(t), 0.3 * np.sin(t), 0.06 * np.cos(t)]) + [0.5, 0.45, 0.5]
    scene = ef.Scene.from_polygons(list(room.polygons) + [disc])
    seen = 0
    for i in (0, 9, 14):
        hit = assert_rays_identical(scene, room.centroids[i], room.normals[i])
        seen += np.sum(hit == len(room))
    assert seen > 100    # the disc is hit


@given(strategies.enclosures() | strategies.occluded_scenes() | strategies.flush_faces())
@settings(max_examples=examples(40), deadline=None)
def test_compiled_rays_identical_to_numpy_in_random_scenes(case):
    assert_rays_identical(*case, samples=1500)


def test_monte_carlo_rows_equal_numpy_rows():
    scene = ef.scenes.office()
    for p, n in _rows(scene, 2, seed=6):
        F1 = ef.form_factors(scene, p, n, method=ef.MonteCarlo(20000, seed=3))
        F0 = ef.form_factors(scene, p, n, method=ef.MonteCarlo(20000, seed=3, backend="numpy"))
        assert np.array_equal(F1, F0)
    S1 = ef.sphere_form_factors(scene, scene.centroids[:3], method=ef.MonteCarlo(8000))
    S0 = ef.sphere_form_factors(scene, scene.centroids[:3],
                                method=ef.MonteCarlo(8000, backend="numpy"))
    assert np.array_equal(S1, S0)


def test_monte_carlo_backend_option_checked_and_in_repr():
    assert "backend" not in repr(ef.MonteCarlo(10))
    assert "backend='numpy'" in repr(ef.MonteCarlo(10, backend="numpy"))
    with pytest.raises(ValueError, match="backend"):
        ef.MonteCarlo(10, backend="cuda")
    from exactff.methods._sampling import nearest_polygons

    scene = ef.scenes.cornell_box()
    with pytest.raises(ValueError, match="margin"):
        nearest_polygons(scene, scene.centroids[0], scene.normals[0], np.array([[0, 0, 1.0]]),
                         backend="compiled", margin=1e-6)


@pytest.mark.parametrize("offset", [1e-11, -1e-11, 3e-10])
def test_compiled_disk_casts_polygons_through_the_point_as_numpy_does(offset):
    # the point on the floor, a hair off a wall's plane at its foot: the wall's bottom
    # edge passes within RASTER_NEAR_ORIGIN of the point, and both backends cast its
    # rays one by one before the disk's scan
    from exactff.methods._raster import _passes_near_origin
    from exactff.methods._sampling import ZBufferRow

    scene = ef.scenes.subdivided_box(2)
    p, n = as_receiver([offset, 0.3, 0.0], [0.0, 0.0, 1.0])
    z = ZBufferRow(scene, p, n)
    assert any(_passes_near_origin(V, c).any() for _, V, c in z.local)   # the premise
    for r in (17, 45):
        assert_backends_identical(lambda **k: ef.DiscretePPBH(resolution=r, **k), scene, p, n)


def test_compiled_rows_on_two_threads_equal_rows_one_by_one():
    # the compiled z-buffers run without the GIL, each thread with its own scratch:
    # rows computed on two threads at once are the rows computed one by one
    from concurrent.futures import ThreadPoolExecutor

    scene = ef.scenes.office()
    rows = list(_rows(scene, 6, seed=7))
    for m in (ef.DiscretePPBH(resolution=64), ef.PolarPlane(rings=20, sectors=48),
              ef.CubicTetrahedron(resolution=30), ef.MonteCarlo(4000)):
        one = [m.point_form_factors(scene, p, n) for p, n in rows]
        with ThreadPoolExecutor(2) as pool:
            two = list(pool.map(lambda pn: m.point_form_factors(scene, *pn), rows))
        assert all(np.array_equal(a, b) for a, b in zip(one, two))
