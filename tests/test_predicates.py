"""The exact side of a point for many planes (sides_of_point) against the sign of the
plane's value in rational arithmetic, computed here from the floats directly."""

from fractions import Fraction

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from exactff.predicates import sides_of_point

from common import examples


def rational_sides(N, D, p):
    """The sign of ``N[k] . p - D[k]`` for each plane k, from the floats as rationals."""
    out = []
    for n, d in zip(N, D):
        v = sum(Fraction(float(a)) * Fraction(float(b)) for a, b in zip(n, p)) - Fraction(float(d))
        out.append((v > 0) - (v < 0))
    return out


def test_repeated_planes_through_the_point_are_each_decided_exactly():
    # a point in a floor (y = 0.1 + 0.2, not 0.3): the floor's plane repeated at many
    # nodes, as coplanar fragments give, some with -0.0 components, beside planes an ulp
    # off in either direction, a tilted one through the point to rounding, and planes
    # far from it (decided by floats, between the others)
    p = np.array([0.7, 0.1 + 0.2, 1.3])
    up = np.array([0.0, 1.0, 0.0])
    N = [up, -up, np.array([-0.0, 1.0, -0.0]), up, up, up]
    D = [0.3, -0.3, 0.3, 0.1 + 0.2, np.nextafter(0.1 + 0.2, 1), np.nextafter(0.1 + 0.2, 0)]
    tilt = np.array([0.6, 0.8, 0.0])
    N += [tilt] * 3
    D += [float(tilt @ p)] * 3
    N += [up, tilt]
    D += [5.0, -2.0]
    N, D = np.array(N * 40), np.array(D * 40)
    got = sides_of_point(N, D, p)
    assert got.tolist() == rational_sides(N, D, p)
    # every kind of answer occurs: the check is not one-sided
    assert {-1, 0, 1} <= set(got.tolist())


coords = st.floats(-4, 4, allow_nan=False).map(lambda x: round(x, 2))
BASE = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, 0.8, 0], [0, 0.28, 0.96],
                 [1 / 3, 2 / 3, 2 / 3]])


@settings(max_examples=examples(60))
@given(p=st.tuples(coords, coords, coords),
       planes=st.lists(st.tuples(st.integers(0, len(BASE) - 1), st.integers(-3, 3)),
                       min_size=1, max_size=30))
def test_sides_of_point_are_the_rational_signs(p, planes):
    # planes through p (offset 0: their float offsets are within rounding of it) or
    # through p shifted by a few hundredths along any of the normals
    p = np.array(p)
    N = BASE[[k for k, _ in planes]]
    D = np.array([float(n @ (p + 0.01 * shift * n)) for n, (_, shift) in zip(N, planes)])
    assert sides_of_point(N, D, p).tolist() == rational_sides(N, D, p)


def test_coplanar_pairs_repeated_and_long_polygons():
    # squares at z = 15 and just below it: 1e-13 is within the near-coplanar band there
    # (2.1e-13), 3.5e-13 beyond it; and a 5,000-gon at z = 15 (a table top), asked about
    # in many repeated pairs, as a z-buffer's cells ask (issue 52: each distinct pair is
    # tested once)
    from exactff.predicates import coplanar_pairs

    sq = lambda z: [[0, 0, z], [0, 1, z], [1, 1, z], [1, 0, z]]
    t = 2 * np.pi * np.arange(5000) / 5000
    disc = np.column_stack([np.cos(t), np.sin(t), np.full(5000, 15.0)])[::-1]
    V = np.vstack([sq(15.0), sq(15.0 - 1e-13), sq(15.0 - 3.5e-13), disc])
    offsets = np.array([0, 4, 8, 12, 5012])
    N = np.array([[0, 0, -1.0]] * 4)
    D = -V[offsets[:-1], 2]
    a = np.array([0, 0, 3, 1, 3, 0, 2, 3, 3, 0] * 30)
    b = np.array([1, 2, 0, 3, 2, 1, 3, 0, 1, 2] * 30)
    expected = [True, False, True, True, False, True, False, True, True, False] * 30
    assert coplanar_pairs(V, offsets, N, D, a, b).tolist() == expected


def _far_room(shift):
    """A box of 2 x 2 quads per face, moved by ``shift`` and turned about a slanted
    axis (no coordinate plane holds a face)."""
    import exactff as ef
    box = ef.scenes.subdivided_box(2)
    a = np.array([1.0, 2.0, 2.0]) / 3.0
    c, s = np.cos(0.7), np.sin(0.7)
    R = c * np.eye(3) + s * np.cross(np.eye(3), a) + (1 - c) * np.outer(a, a)
    return ef.Scene.from_polygons([np.asarray(P) @ R.T + shift for P in box.polygons])


def test_tree_planes_sides_follow_the_tree_and_the_point():
    # the BSP tree's kept plane magnitudes (BSPTree.plane_magnitudes, asked every row)
    # are each tree's own, asked in turn with another tree's: |n| and |d| of its own
    # planes, and the sides of points on the nodes' planes (the centroids) of a box
    # near the origin, then of one 1e4 away, then of the first again, against the
    # rational signs
    from exactff.predicates import point_plane_offsets
    from exactff.visibility import build_bsp
    trees = []
    for shift in (0.0, 1e4, 0.0):
        scene = _far_room(np.array([shift, -shift, 0.5 * shift]))
        tree = build_bsp(scene)
        trees.append(tree)
        for t in trees[::-1]:
            absN, absD = t.plane_magnitudes()
            assert np.array_equal(absN, np.abs(t.normals))
            assert np.array_equal(absD, np.abs(t.offsets))
        for p in scene.centroids[::3]:
            got = sides_of_point(tree.normals, tree.offsets, p, offsets=point_plane_offsets(
                tree.normals, tree.offsets, p, tree.plane_magnitudes()))
            assert got.tolist() == rational_sides(tree.normals, tree.offsets, p)


def test_plane_distances_follow_the_scene_and_the_point():
    # the signed distances from FlatPolygons' by-coordinate copies, scene after scene
    # and point after point, against -n . (c - p) in rational arithmetic from the same
    # floats: within the rounding of its three products and two sums (and of c - p)
    from exactff.kernel import flat_polygons
    from exactff.predicates import gamma, plane_distances
    rng = np.random.default_rng(4)
    for shift in (0.0, 1e4, 3.0):
        scene = _far_room(np.array([shift, -shift, 0.5 * shift]))
        flat = flat_polygons(scene)
        for p in [scene.centroids[1], scene.centroids[7] + rng.normal(size=3)]:
            d, _ = plane_distances(flat, p)
            for k, (n, c) in enumerate(zip(scene.normals, scene.centroids)):
                exact = -sum(Fraction(float(a)) * (Fraction(float(b)) - Fraction(float(q)))
                             for a, b, q in zip(n, c, p))
                room = gamma(4) * float(np.abs(n) @ (np.abs(c) + np.abs(p)))
                assert abs(Fraction(float(d[k])) - exact) <= Fraction(room), (shift, k)
