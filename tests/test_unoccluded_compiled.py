"""Unoccluded rows by the compiled sector sums (exactff/_core/sector_sums.h, issue 52): the closed
cube's rows against Howell's closed forms and their row sums, rows that cross the
horizon against mpmath, and the compiled sums against the numpy reference
(kernel/sector.py's clipped_sector_sums) they reproduce, in both tiers."""

import math

import numpy as np
import pytest

import exactff as ef
from exactff import _tolerances as tol
from exactff.geometry import receiver_frame, rotate
from exactff.kernel import clipped_sector_sums, flat_polygons
from exactff.kernel._sector import row_sums, row_sums_extended
from exactff.methods import Exact
from exactff.rings import repack
from exactff.testing.mp_reference import boundary_form_factor

from common import parallel_rect_corner, perpendicular_rect


def rect_from_corner(x0, x1, y0, y1, corner_form):
    """A rectangle's value from a point over the corner (0, 0) of its plane's axes, by
    superposition of the four rectangles with a corner there (signed extents)."""
    total = 0.0
    for x, sx in ((x1, 1), (x0, -1)):
        for y, sy in ((y1, 1), (y0, -1)):
            if x != 0 and y != 0:
                total += sx * sy * math.copysign(1, x) * math.copysign(1, y) * \
                    corner_form(abs(x), abs(y))
    return total


@pytest.fixture(scope="module")
def cube():
    return ef.scenes.subdivided_box(4)   # the unit cube, 4 x 4 quads a face


@pytest.mark.parametrize("row", [0, 5, 10])   # floor quads: centre, inner, edge
def test_closed_cube_row_vs_closed_forms(cube, row):
    p, n = cube.centroids[row], cube.normals[row]
    assert np.allclose(n, [0, 0, 1])
    st = {}
    F, E = Exact().point_form_factors(cube, p, n, stats=st, error=True)
    assert st["path"] == "unoccluded"
    checked = 0
    for j, Q in enumerate(cube.polygons):
        Q = np.asarray(Q)
        lo, hi = Q.min(axis=0) - p, Q.max(axis=0) - p
        if np.allclose(cube.normals[j], [0, 0, -1]):      # ceiling: parallel at height 1
            c = hi[2]
            ref = rect_from_corner(lo[0], hi[0], lo[1], hi[1],
                                   lambda a, b: parallel_rect_corner(a, b, c))
        elif abs(cube.normals[j][2]) == 0:                  # walls: perpendicular
            a = int(np.argmax(np.abs(cube.normals[j])))     # the wall's axis
            o = 1 - a                                       # the other horizontal one
            d = abs(lo[a])
            # width along o (signed, from the foot of p's perpendicular), height above
            # the floor's plane, through p
            ref = rect_from_corner(lo[o], hi[o], lo[2], hi[2],
                                   lambda b, h: perpendicular_rect(b, h, d))
        else:                                               # the floor: edge-on
            assert F[j] == 0.0
            continue
        assert abs(F[j] - ref) <= E[j] + 4 * tol.EPS * abs(ref), (j, F[j], ref, E[j])
        checked += 1
    assert checked == 80   # the 16 ceiling and 64 wall quads


def test_closed_cube_rows_sum_to_one():
    box = ef.scenes.subdivided_box(16)
    for i in np.random.default_rng(0).choice(len(box), 8, replace=False):
        st = {}
        F, E = Exact().point_form_factors(box, box.centroids[i], box.normals[i], stats=st,
                                          error=True)
        assert st["path"] == "unoccluded"
        # the row of a closed enclosure sums to 1 (its summation's rounding added)
        assert abs(F.sum() - 1) <= E.sum() + len(F) * tol.EPS
        assert E.max() <= 1e-12 * np.maximum(F, tol.VALUE_FLOOR).min()


def receivers(scene, count, seed, lift):
    """Points just in front of random polygons, with random normals (most rows cross
    the horizon of many polygons)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        i = int(rng.integers(len(scene)))
        n = rng.normal(size=3)
        yield scene.centroids[i] + lift * scene.normals[i], n / np.linalg.norm(n)


def test_rows_crossing_the_horizon_vs_mpmath():
    office = ef.scenes.office()
    flat = flat_polygons(office)
    for p, n in receivers(office, 2, seed=3, lift=0.05):
        F, E = ef.point_polygon_form_factors(p, n, office, error=True)
        # the polygons the horizon cuts, and a few it leaves whole
        ids = np.arange(len(office))
        S, _, _, above = row_sums(flat.V, flat.offsets, ids, np.zeros_like(ids), p[None],
                                  receiver_frame(n)[None], tol.EPS, 8.0, tol.C2 * tol.EPS)
        z = rotate(office.vertices - p, receiver_frame(n))[:, 2]
        low = np.minimum.reduceat(z, office.offsets[:-1]) < 0
        cut = np.flatnonzero(above & low & (F > 0))
        whole = np.flatnonzero(~low & (F > 0))
        assert len(cut) >= 3
        for j in list(cut[:6]) + list(whole[:3]):
            ref = float(boundary_form_factor(p, n, office.polygons[j], dps=40))
            assert abs(F[j] - ref) <= E[j] + 1e-15 * abs(ref), (j, F[j], ref, E[j])


def numpy_sums(flat, ids, p, n, dtype):
    """kernel/sector.py's clipped_sector_sums with rounded offsets, from the float input
    in ``dtype`` (what the tiers computed before the compiled pass)."""
    vidx, owner, starts, nxt = repack(flat.offsets[ids], flat.counts[ids])
    R = receiver_frame(n, dtype=dtype)
    V = flat.V[vidx].astype(dtype)
    first = V[starts]
    eps = tol.EPS if dtype == float else tol.LONGDOUBLE_EPS
    return clipped_sector_sums(rotate(first - p.astype(dtype), R),
                               rotate(V - first[owner], R), nxt, owner, len(ids), eps=eps,
                               rounded_offsets=True)


@pytest.mark.parametrize("tier", ["double", "long double"])
def test_compiled_sums_reproduce_the_numpy_sums(tier):
    dtype, fn, eps = ((float, row_sums, tol.EPS) if tier == "double" else
                      (np.longdouble, row_sums_extended, tol.LONGDOUBLE_EPS))
    scene = ef.scenes.office()
    flat = flat_polygons(scene)
    for p, n in receivers(scene, 4, seed=1, lift=0.01):
        ids = np.arange(len(scene))
        S0, M0, E0 = numpy_sums(flat, ids, p, n, dtype)
        S1, M1, E1, _ = fn(flat.V, flat.offsets, ids, np.zeros_like(ids), p[None],
                           receiver_frame(n, dtype=dtype)[None], eps,
                           tol.OFFSET_ROUNDING_ULPS, tol.C2 * eps)
        assert S1.dtype == dtype
        # the same arithmetic up to the order of libm's and numpy's last bits: within the
        # sums' own rounding model (C1 eps times the magnitudes)
        assert np.all(np.abs(S1 - S0) <= tol.C1 * eps * M0)
        assert np.all(np.abs(M1 - M0) <= tol.C1 * eps * M0)
        # the bounds to a few digits: they are estimates, of the same first-order terms
        assert np.all(np.abs(E1 - E0) <= 1e-6 * E0 + tol.C1 * eps * M0)


def test_ids_out_of_range_are_refused():
    flat = flat_polygons(ef.scenes.subdivided_box(1))
    with pytest.raises(IndexError):
        row_sums(flat.V, flat.offsets, np.array([6]), np.array([0]), np.zeros((1, 3)),
                 np.eye(3)[None], tol.EPS, 8.0, tol.C2 * tol.EPS)
    with pytest.raises(IndexError):     # a row beyond the points
        row_sums(flat.V, flat.offsets, np.array([0]), np.array([1]), np.zeros((1, 3)),
                 np.eye(3)[None], tol.EPS, 8.0, tol.C2 * tol.EPS)


@pytest.mark.parametrize("scene", ["cube", "cornell"])
def test_rows_together_are_the_rows_one_by_one(scene):
    # a closed cube's rows go together (unoccluded_rows), the open Cornell box's one by
    # one (occluded); either way the matrix is the rows of point_form_factors, bit for bit
    s = ef.scenes.subdivided_box(3) if scene == "cube" else ef.scenes.cornell_box()
    M = ef.form_factor_matrix(s)
    single = np.array([Exact().point_form_factors(s, c, n)
                       for c, n in zip(s.centroids, s.normals)])
    assert np.array_equal(M, single)
    rows = Exact().point_rows(s, s.centroids[::2], s.normals[::2], two_sided=True)
    assert np.array_equal(rows, [Exact().point_form_factors(s, c, n, two_sided=True)
                                 for c, n in zip(s.centroids[::2], s.normals[::2])])
    if scene == "cube":
        assert np.abs(M.sum(axis=1) - 1).max() <= 1e-14   # a closed enclosure's rows


def test_point_rows_refuse_bad_receivers():
    box = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match="normal"):
        Exact().point_rows(box, box.centroids, np.zeros((6, 3)))
    with pytest.raises(ValueError, match="point"):
        Exact().point_rows(box, np.full((6, 3), np.nan), box.normals)


def test_sides_of_many_points_are_each_points_own():
    # a matrix's rows of a convex enclosure take the sides of all their points at once
    # (engine_sides_rows, compiled: exactff/_core/sides.h): each row must be what
    # engine_sides (numpy) gives for its point alone, and every side it decides (non-zero)
    # the exact one (rational arithmetic). A rotated box: its centroids lie off their
    # planes by rounding; points pushed 2e-15 along the normals (or against them) lie in
    # the band (3.5e-15 here) and off the plane (7e-16), where the exact tests decide;
    # 1e-13, beyond the band
    from exactff.kernel import engine_sides_rows
    from exactff.predicates import engine_sides, exact_side
    box = ef.scenes.subdivided_box(3)
    R = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))[0]
    scene = ef.Scene.from_polygons([np.asarray(P) @ R.T for P in box.polygons])
    flat = flat_polygons(scene)
    sign = (-1.0) ** np.arange(len(scene))[:, None]     # in front, behind, in front...
    P = np.concatenate([scene.centroids, scene.centroids + 2e-15 * sign * scene.normals,
                        scene.centroids[:5] + 1e-13 * scene.normals[:5]])
    side, band = engine_sides_rows(flat, P)
    assert side.shape == band.shape == (len(P), len(scene)) and side.dtype == np.int8
    for r, p in enumerate(P):
        one_side, one_band = engine_sides(flat, p)
        assert np.array_equal(side[r], one_side) and np.array_equal(band[r], one_band), r
    rows, ids = np.nonzero(side != 0)
    for r, i in zip(rows, ids):
        assert side[r, i] == exact_side(scene.polygons[i], P[r]), (r, i)
    assert band.sum() > len(P) and np.any(band & (side != 0))   # the band was tested
    # every centroid row sees its own polygon edge-on
    assert np.all(side[np.arange(len(scene)), np.arange(len(scene))] == 0)
    # and on the office, from its centroids and points off them, the same as one by one
    office = ef.scenes.office()
    flat = flat_polygons(office)
    Q = office.centroids[::150].copy()
    Q[::2] += 2e-15 * office.normals[::150][::2]
    Q[1::2] += np.random.default_rng(2).normal(size=Q[1::2].shape) * 0.1
    side, band = engine_sides_rows(flat, Q)
    for r, p in enumerate(Q):
        one_side, one_band = engine_sides(flat, p)
        assert np.array_equal(side[r], one_side) and np.array_equal(band[r], one_band), r
