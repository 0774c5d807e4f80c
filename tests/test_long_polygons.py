"""One long polygon in a scene: stored ragged (buckets of vertex counts), exact, and
equal to the same polygon cut into a fan of pieces."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import exactff as ef
from exactff.geometry import polygon_diameter
from exactff.rings import padded_buckets
from exactff.testing import assert_form_factors_close

from common import examples


def disc(k, centre=(0.5, 0.45, 0.5), radius=0.3, tilt=0.2):
    """A regular k-gon in a slightly tilted plane through ``centre``, facing up."""
    t = 2 * np.pi * np.arange(k) / k
    P = np.column_stack([radius * np.cos(t), radius * np.sin(t), tilt * radius * np.cos(t)])
    return P + np.asarray(centre)


def fan(P, centre):
    return [np.array([centre, P[i], P[(i + 1) % len(P)]]) for i in range(len(P))]


@pytest.fixture(scope="module")
def scenes():
    room = ef.scenes.furnished_box(2, [((0.1, 0.1, 0.0), (0.3, 0.35, 0.6))])
    P = disc(1500)
    c = np.array([0.5, 0.45, 0.5])
    long_ = ef.Scene.from_polygons(list(room.polygons) + [P])
    cut = ef.Scene.from_polygons(list(room.polygons) + fan(P, c))
    return room, long_, cut


@pytest.mark.parametrize("method", ["exact", "hemicube"])
def test_long_polygon_equals_its_fan(scenes, method):
    room, long_, cut = scenes
    n = len(room)
    seen = 0
    for i in (0, 9, 14, 20):   # floor, walls and ceiling rows
        p, nrm = room.centroids[i], room.normals[i]
        F = ef.form_factors(long_, p, nrm, method=method)
        G = ef.form_factors(cut, p, nrm, method=method)
        assert_form_factors_close(F[:n], G[:n], rtol=0, atol=1e-14 if method == "exact" else 1e-12)
        assert abs(F[n] - G[n:].sum()) <= (1e-14 if method == "exact" else 1e-12)
        seen += F[n] > 1e-3
    assert seen >= 2   # the disc is really seen (its value is a real comparison)


def test_disc_receives_and_occludes(scenes):
    room, long_, _ = scenes
    n = len(room)
    i = 20   # a ceiling quad: the disc faces up, away from it, and hides the floor
    F0 = ef.form_factors(room, room.centroids[i], room.normals[i])
    F = ef.form_factors(long_, room.centroids[i], room.normals[i])
    assert F[n] == 0.0                                  # seen from its back
    assert np.all(F[:n] <= F0 + 1e-15) and np.any(F[:n] < F0 - 1e-3)
    k = 9    # a wall quad above the disc's plane sees its front
    assert ef.form_factors(long_, room.centroids[k], room.normals[k])[n] > 0


def test_buckets_bound_the_padding():
    polys = [np.zeros((3, 3)), np.ones((5000, 3)), np.ones((4, 3)), np.ones((9, 3))]
    buckets = padded_buckets(polys)
    assert sorted(np.concatenate([ids for ids, _, _ in buckets]).tolist()) == [0, 1, 2, 3]
    for ids, V, counts in buckets:
        assert V.shape[1] == counts.max() and V.shape[1] < 2 * max(counts.min(), 2)


def test_diameter_of_long_polygons_against_all_pairs():
    rng = np.random.default_rng(0)
    for _ in range(5):
        k = int(rng.integers(129, 700))
        t = np.sort(rng.uniform(0, 2 * np.pi, k))
        r = rng.uniform(0.5, 1.5, k)    # star-shaped, not convex
        P = np.column_stack([r * np.cos(t), r * np.sin(t), np.zeros(k)])
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        P = P @ R.T + rng.normal(size=3)
        D = P[:, None, :] - P[None, :, :]
        assert abs(polygon_diameter(P) - np.sqrt((D * D).sum(-1)).max()) <= 1e-12


def test_refinement_of_a_long_polygon_does_not_depend_on_its_candidate_search(monkeypatch):
    """The refinement finds a long fragment's (and a long scene polygon's) candidate
    edges by proximity, not among all of them (issue 33): the same labels, so the same
    values and estimates as trying every edge."""
    from exactff import _tolerances as tol

    room = ef.scenes.furnished_box(2, [((0.1, 0.1, 0.0), (0.3, 0.35, 0.6))])
    long_ = ef.Scene.from_polygons(list(room.polygons) + [disc(200)])
    # a tolerance below what the clipper's vertices give: every visible piece is refined,
    # the disc's too (the Python engine's refinement; its estimates now also hold what an
    # edge's other plausible labels and the BSP's rounded crossings may move, so they do
    # not all reach 1e-15: the refinement is told by its counters)
    method = ef.Exact(tolerance=1e-15, engine="python")
    for i in (4, 9, 14, 21):   # walls and ceiling rows that see the disc
        p, nrm = long_.centroids[i], long_.normals[i]
        st = {}
        F, E = method.point_form_factors(long_, p, nrm, error=True, stats=st)
        assert F[-1] > 0 and st["refined_rings"] > 0, st
        with monkeypatch.context() as m:
            m.setattr(tol, "LONG_POLYGON", len(long_.polygons[-1]) + 1)
            F0, E0 = method.point_form_factors(long_, p, nrm, error=True)
        np.testing.assert_array_equal(F, F0)
        np.testing.assert_array_equal(E, E0)


def test_long_polygon_shadow_is_a_tree_of_chords(scenes):
    # the disc's shadow as a chain of its 1,500 edges' planes cost every piece behind it a
    # visit per edge (the office with a 5,000-vertex table: 10x the rows without it); as a
    # balanced tree of chords (Core::long_shadow) about log2(edges / leaf) + leaf
    room, long_, _ = scenes
    k = len(long_.polygons[-1])
    for i in (9, 20):   # a wall and the ceiling: the floor and the box behind the disc
        base, st = {}, {}
        ef.Exact().point_form_factors(room, room.centroids[i], room.normals[i], stats=base)
        ef.Exact().point_form_factors(long_, room.centroids[i], room.normals[i], stats=st)
        assert st["hidden_pieces"] > base["hidden_pieces"]   # the disc hides things
        assert st["node_visits"] <= 4 * base["node_visits"] + 2 * k, (st, base)


def test_long_polygon_sphere_row_equals_its_fan(scenes):
    # the compiled sphere mode: the disc's shadow (a tree of chords) on both sides of the
    # core's horizon, against the fan's 1,500 triangles (each a short chain)
    room, long_, cut = scenes
    n = len(room)
    for p in ([0.5, 0.45, 0.8], [0.7, 0.2, 0.3]):
        S, E = ef.sphere_form_factors(long_, p, error=True)
        T, H = ef.sphere_form_factors(cut, p, error=True)
        assert_form_factors_close(S[:n], T[:n], rtol=0, atol=1e-14)
        assert abs(S[n] - T[n:].sum()) <= 1e-14
        assert S[n] > 1e-2 and abs(S.sum() - 1) <= 1e-13


@settings(max_examples=examples(10), deadline=None)
@given(k=st.integers(40, 300), seed=st.integers(0, 2 ** 32 - 1))
def test_irregular_long_polygon_equals_its_fan(k, seed):
    # an irregular convex k-gon (random angles on a tilted ellipse: chords that do not
    # meet in one point, parts of unequal size) over the furnished room's floor, from
    # points above, below and beside it: the tree of chords against the fan's chains
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    t = t[np.diff(np.append(t, t[0] + 2 * np.pi)) > 1e-3]   # distinct vertices
    a, b = rng.uniform(0.15, 0.4), rng.uniform(0.1, 0.3)
    c = np.array([0.5, 0.45, rng.uniform(0.3, 0.7)])
    P = np.column_stack([a * np.cos(t), b * np.sin(t), 0.3 * a * np.cos(t)]) + c
    room = ef.scenes.furnished_box(2, [((0.1, 0.1, 0.0), (0.3, 0.35, 0.2))])
    long_ = ef.Scene.from_polygons(list(room.polygons) + [P])
    cut = ef.Scene.from_polygons(list(room.polygons) + fan(P, c))
    n = len(room)
    for i in (9, 20):
        p, nrm = room.centroids[i], room.normals[i]
        F = ef.form_factors(long_, p, nrm)
        G = ef.form_factors(cut, p, nrm)
        assert_form_factors_close(F[:n], G[:n], rtol=0, atol=1e-14)
        assert abs(F[n] - G[n:].sum()) <= 1e-14
    p = np.array([rng.uniform(0.35, 0.65), rng.uniform(0.35, 0.55), 0.95])
    S, T = ef.sphere_form_factors(long_, p), ef.sphere_form_factors(cut, p)
    assert_form_factors_close(S[:n], T[:n], rtol=0, atol=1e-14)
    assert abs(S[n] - T[n:].sum()) <= 1e-14


@pytest.mark.parametrize("lift", [1e-6, 1e-5])
def test_long_polygon_not_convex_to_a_roundoff_keeps_its_kernel(lift):
    # a long piece's image is taken as convex without its m^2 vertex tests only where an
    # O(m) certificate proves it (shadow_tree.cpp, convex_image). A 200-gon disc whose
    # every other vertex is raised by 1e-8 (planar within the validation tolerance), seen
    # from a wall point just above its plane, has a zigzag image: its shadow must be its
    # kernel, charged to the bounds (a missing charge left the room's values 4.6e-8
    # beyond them). Reference: the same disc as a fan of triangles (pieces of three
    # vertices, never certified).
    room = ef.scenes.furnished_box(2, [((0.1, 0.1, 0.0), (0.3, 0.35, 0.2))])
    n, k, delta = len(room), 200, 1e-8
    t = 2 * np.pi * np.arange(k) / k
    P = np.column_stack([0.5 + 0.3 * np.cos(t), 0.45 + 0.3 * np.sin(t),
                         0.5 + delta * (np.arange(k) % 2)])
    long_ = ef.Scene.from_polygons(list(room.polygons) + [P])
    cut = ef.Scene.from_polygons(list(room.polygons) + fan(P, [0.5, 0.45, 0.5 + delta / 2]))
    p, nrm = np.array([1e-3, 0.45, 0.5 + lift]), np.array([1.0, 0.0, 0.0])
    st = {}
    F, E = ef.Exact().point_form_factors(long_, p, nrm, stats=st, error=True)
    G, H = ef.Exact().point_form_factors(cut, p, nrm, error=True)
    assert st["kernel_shadows"] >= 1
    assert np.all(np.abs(F[:n] - G[:n]) <= E[:n] + H[:n])
    assert abs(F[n] - G[n:].sum()) <= E[n] + H[n:].sum() + 1e-15
    assert np.abs(F[:n] - G[:n]).max() > 1e-10   # the rows do differ: the bounds are tested
