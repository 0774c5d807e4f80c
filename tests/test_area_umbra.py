"""The umbras of occluded area pairs (exactff.area.umbra, issue 49): regions of the
emitter from which one blocker hides the whole receiver, proven with a margin, their
event lines cut away and their cells integrated in closed form; and the cap on a pair's
distinct event lines."""

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

import exactff as ef
from exactff import _tolerances as tol
from exactff.area import AreaStats, area_row
from exactff.area import row as row_module
from exactff.area.events import distinct_lines
from exactff.area.points import unoccluded_bound
from exactff.area.joint_umbra import blocker_frames, hidden_pieces, hiding_rows
from exactff.area.umbra import in_umbra, merged_blockers, outside_umbras, sees_through, umbras
from exactff.geometry import receiver_frame


def _hits(x, q, K):
    """Whether the segment x -> q meets the convex polygon K, by brute force: its
    crossing with K's plane (strictly between) inside K, decided by shapely in K's
    frame (the independent check of :func:`sees_through`)."""
    a = np.cross(K[1] - K[0], K[2] - K[0])
    n = a / np.linalg.norm(a)
    sx, sq = (x - K[0]) @ n, (q - K[0]) @ n
    if not sx * sq < 0:
        return False
    y = x + sx / (sx - sq) * (q - x)
    R = receiver_frame(n)
    return shapely.Polygon(K @ R[:2].T).covers(shapely.Point(y @ R[:2].T))


def _random_case(rng):
    """A receiver square at height 4, a convex blocker (a random quad, convex) at height
    1 to 3, points at height 0."""
    Q = np.array([[0, 0, 4], [1, 0, 4], [1, 1, 4], [0, 1, 4]], float) * [1, 1, 1]
    Q[:, :2] += rng.uniform(-1, 1, 2)
    h = rng.uniform(1, 3)
    c = rng.uniform(-1, 1, 2)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 4))
    r = rng.uniform(0.5, 2.5)
    K = np.column_stack([c[0] + r * np.cos(angles), c[1] + r * np.sin(angles), np.full(4, h)])
    K[:, 2] += 0.2 * (K[:, 0] - c[0]) * rng.uniform(-1, 1)      # tilted, still planar
    return Q, K


def test_sees_through_never_claims_a_segment_that_misses():
    """Every point that passes sees every sampled point of the receiver (its vertices,
    edges and inside) through K, by brute force; and the test is not vacuous (points
    pass). Planted: the opposite-sides condition dropped from sees_through (a crossing
    of K's plane beyond q counted): points that see q past K's plane pass, caught."""
    rng = np.random.default_rng(49)
    passed = 0
    for _ in range(60):
        Q, K = _random_case(rng)
        X = np.column_stack([rng.uniform(-3, 3, (40, 2)), np.zeros(40)])
        X[:, 2] = rng.choice([0.0, 3.9, 4.5], 40)              # some beyond K or Q
        # and some just above or below the receiver (K's plane crossed behind x or q)
        near = Q.mean(axis=0) + rng.uniform(-0.3, 0.3, (20, 3)) * [1, 1, 0]
        near[:, 2] = rng.choice([3.95, 6.0], 20)
        X = np.concatenate([X, near])
        ok = sees_through(X, Q, K)
        g = rng.random((30, 2))
        samples = np.concatenate([Q, Q[0] + g[:, :1] * (Q[1] - Q[0]) + g[:, 1:] * (Q[3] - Q[0])])
        for x in X[ok]:
            assert all(_hits(x, q, K) for q in samples)
        passed += int(ok.sum())
    assert passed > 40
    # a point above the receiver, over a blocker under both: the line through them
    # crosses K's plane beyond q, which is no crossing of the segment
    Q = np.array([[0, 0, 4], [1, 0, 4], [1, 1, 4], [0, 1, 4]], float)
    K = np.array([[-5, -5, 1], [6, -5, 1], [6, 6, 1], [-5, 6, 1]], float)
    assert sees_through(np.array([[.5, .5, 0.0], [.5, .5, 6.0], [.5, .5, 3.9]]), Q,
                        K).tolist() == [True, False, False]


def test_umbras_are_hidden_everywhere_near_them():
    """Every point within AREA_UMBRA_SHRINK of P's size of a returned region (sampled,
    its corners moved out by that much included) sees the receiver wholly hidden, by
    brute force; and regions are found. Blockers are tilted steeply half the time, so that
    their plane crosses P's. Planted: the K-plane half-plane left out of the central
    images and the corners not proven: points on the wrong side of a tilted blocker
    returned, caught; the half-plane left out alone: the proof drops those regions (fewer
    found, none wrong)."""
    rng = np.random.default_rng(7)
    found = 0
    for trial in range(40):
        Q, K = _random_case(rng)
        if trial % 2:
            # steep, through P's plane: points of P in the pyramid between q and K
            K[:, 2] = -1.0 + 3.5 * (K[:, 0] - K[:, 0].min()) / np.ptp(K[:, 0])
        P = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], float)
        R, c = receiver_frame(np.array([0, 0, 1.0])), P.mean(axis=0)
        regions = umbras(P, Q, [K], R, c)
        for region, H in regions:
            found += 1
            eps = tol.AREA_UMBRA_SHRINK * 4.0
            centre = region.mean(axis=0)
            out = region + eps * (region - centre) / np.linalg.norm(region - centre, axis=1)[:, None]
            w = rng.dirichlet(np.ones(len(region)), 40)
            U2 = np.concatenate([out, w @ region])
            assert in_umbra(U2, [(region, H)], eps)[0].all()
            g = rng.random((20, 2))
            samples = np.concatenate([Q, Q[0] + g[:, :1] * (Q[1] - Q[0]) + g[:, 1:] * (Q[3] - Q[0])])
            for u in U2:
                x = c + u @ R[:2]
                assert all(_hits(x, q, K) for q in samples)
    assert found >= 10


def test_merged_blockers_join_coplanar_pieces_only_where_convex():
    """Two squares sharing an edge become one rectangle; an L of three does not become a
    hexagon (its union is not convex: only two of them join); squares in parallel
    planes or sharing only a corner stay apart. Planted: the convexity check dropped (the
    L joined into one non-convex polygon, which sees_through would treat as its hull),
    caught."""
    A = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    (M,) = merged_blockers([A, A + [1, 0, 0]])
    assert shapely.Polygon(M[:, :2]).equals(shapely.box(0, 0, 2, 1)) and len(M) == 4
    L = merged_blockers([A, A + [1, 0, 0], A + [0, 1, 0]])
    assert len(L) == 2 and all(len(K) == 4 for K in L)
    assert sum(shapely.Polygon(K[:, :2]).area for K in L) == pytest.approx(3.0)
    assert len(merged_blockers([A, A + [1, 0, 1e-6]])) == 2
    assert len(merged_blockers([A, A + [1, 1, 0]])) == 2
    # a quad on A's right edge reaching below and above it: the union has a reflex corner
    B = np.array([[1, 0, 0], [2, -1, 0], [2, 2, 0], [1, 1, 0]], float)
    assert len(merged_blockers([A, B])) == 2


@given(st.lists(st.integers(1, 3), min_size=1, max_size=4),
       st.lists(st.integers(1, 3), min_size=1, max_size=4), st.randoms(use_true_random=False),
       st.sampled_from([0.0, 0.5, 1e3]))
def test_merged_blockers_tile_the_wall_they_came_from(widths, heights, rnd, z):
    # a wall in the plane z tiled by a grid of rectangles (some cut into two triangles),
    # given in a random order, each tile's vertices turned to start anywhere: the
    # merged blockers are strictly convex, do not overlap and cover the wall (their
    # areas sum to its area, and their union is it), and where two tiles share an edge
    # at least one pair is joined. Planted: the shared-edge prefilter taking A's edges
    # the same way round (no pair ever joined) fails
    from exactff.area.umbra import blocker_frame
    xs, ys = np.cumsum([0] + widths, dtype=float), np.cumsum([0] + heights, dtype=float)
    tiles = []
    for x0, x1 in zip(xs, xs[1:]):
        for y0, y1 in zip(ys, ys[1:]):
            R = np.array([[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]])
            tiles += [R[[0, 1, 2]], R[[0, 2, 3]]] if rnd.random() < 0.3 else [R]
    tiles = [np.roll(K, rnd.randrange(len(K)), axis=0) for K in tiles]
    rnd.shuffle(tiles)
    merged = merged_blockers(tiles)
    assert all(blocker_frame(K) is not None for K in merged)
    wall = shapely.box(0, 0, xs[-1], ys[-1])
    shapes = [shapely.Polygon(K[:, :2]) for K in merged]
    assert sum(S.area for S in shapes) == pytest.approx(wall.area, rel=1e-12)
    assert shapely.union_all(shapes).symmetric_difference(wall).area <= 1e-9 * wall.area
    if len(tiles) > 1:
        assert len(merged) < len(tiles)


def test_outside_umbras_keeps_the_parts_outside():
    """A segment across a square region keeps its two ends, one inside loses all of
    itself, one beside it all of itself: the lengths kept are those of shapely's
    difference."""
    region = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    H = np.array([[1, 0, 0], [-1, 0, 1], [0, 1, 0], [0, -1, 1]], float)
    lines = np.array([[[-1, .5], [2, .5]], [[.2, .2], [.8, .7]], [[-1, -1], [3, -2]],
                      [[.5, -1], [.5, .5]]], float)
    kept = outside_umbras(lines, [(region, H)])
    box = shapely.box(0, 0, 1, 1)
    expected = sum(shapely.difference(shapely.LineString(s), box).length for s in lines)
    assert sum(np.linalg.norm(s[1] - s[0]) for s in kept) == pytest.approx(expected)
    assert len(kept) == 4


def _walled_floor(plates=2):
    """A floor strip P (x 0..10) looking at a far wall Q (x 0..3) across a wall that hides
    Q from the part of P with x below about 7, and small plates in the way of the rest
    (events there)."""
    P = [[0, 0, 0], [10, 0, 0], [10, 1, 0], [0, 1, 0]]
    Q = [[0, 20, .5], [3, 20, .5], [3, 20, 3], [0, 20, 3]]                 # faces -y
    wall = [[-5, 10, 0], [5, 10, 0], [5, 10, 3.5], [-5, 10, 3.5]]
    polys = [P, Q, wall]
    for k in range(plates):
        x, z = 5.5 + 0.7 * k, 0.6 + 0.9 * k
        polys.append([[x, 14, z], [x + 0.5, 14, z], [x + 0.5, 14, z + 0.4], [x, 14, z + 0.4]])
    return ef.Scene.from_polygons(polys)


def _engine_over_floor(scene, strips=20, order=6):
    """F(P -> Q) of the walled floor by the point engine integrated over P: a Gauss-
    Legendre rule of ``order`` points a side on each of ``strips`` strips across x."""
    x, w = np.polynomial.legendre.leggauss(order)
    h = 10.0 / strips
    X = np.array([[a + 0.5 * h * (xi + 1), 0.5 * (yj + 1), 0.0]
                  for a in np.arange(strips) * h for xi in x for yj in x])
    W = np.array([0.5 * h * wi * 0.5 * wj for _ in range(strips) for wi in w for wj in w])
    exact = ef.Exact()
    F = np.array([exact.point_form_factors(scene, p, np.array([0, 0, 1.0]))[1] for p in X])
    return float(W @ F) / 10.0


def test_umbras_keep_values_within_their_estimates(monkeypatch):
    """The walled floor's row 0 with the umbras forced (AREA_UMBRA_MIN_LINES 0) against
    the same row without them (the hidden part integrated by the rules everywhere, an
    independent path for the umbra's cells): every value within the two estimates, cells
    taken by the closed form, fewer points; and the value against the point engine
    integrated over P by Gauss rules on strips (a third way; the rule's own error, at
    the events' kinks, dominates that difference). Planted: the umbra's unoccluded part
    not subtracted from the pair's whole value: caught (the values differ by it)."""
    scene = _walled_floor()
    # the umbras of one blocker alone (those of several: the two plates' tests below)
    monkeypatch.setattr(tol, "AREA_UMBRA_SPLIT_DEPTH", -1)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 2 ** 62)
    s0 = AreaStats()
    f0, e0 = area_row(scene, 0, 1e-8, stats=s0)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 0)
    s1 = AreaStats()
    f1, e1 = area_row(scene, 0, 1e-8, stats=s1)
    assert s1.umbra_pairs >= 1 and s1.umbra_cells > 0 and s0.umbra_cells == 0
    assert s1.point_values < s0.point_values
    assert (np.abs(f1 - f0) <= e0 + e1).all(), (f1 - f0, e0 + e1)
    assert f1[1] > 5e-5                  # the far wall: seen past the wall's end
    assert abs(_engine_over_floor(scene) - f1[1]) <= 2e-3 * f1[1]


def test_too_many_event_lines_raise_naming_the_pair(monkeypatch):
    """A pair whose events lie on more distinct lines than AREA_MAX_EVENT_LINES raises
    NumericalError naming the pair, the count and what to do, before any cell is made;
    collinear segments count as one line. Planted: the cap's raise left out, caught."""
    scene = _walled_floor()
    monkeypatch.setattr(tol, "AREA_MAX_EVENT_LINES", 1)
    with pytest.raises(ef.NumericalError, match=r"area form factor \(0, \d\): .* on \d+ distinct "
                       r"lines.*AREA_MAX_EVENT_LINES = 1.*split the emitter"):
        area_row(scene, 0, 1e-6)
    # collinear copies count once
    S = np.array([[[0, 0], [1, 0]], [[1, 0], [2, 0]], [[0.5, 0], [3, 0]], [[0, 0], [0, 1]]], float)
    assert distinct_lines(S, 3.0) == 2
    assert distinct_lines(S, 3.0, np.array([[.2, -.5], [4, -.5], [4, .5], [.2, .5]])) == 1


@pytest.mark.slow
def test_gunter2_row_38_with_umbras_sums_to_one():
    """View3D's gunter2, row 38 (a roof slat; its pairs (38, 23) and (38, 3) had 472,008
    and 18,175 cells, a wall or the ridge's far slope hiding the receiver from most of
    the slat): with the umbras, cells are taken in closed form and the row, an
    enclosure's, sums to 1 within its estimates (about a minute)."""
    from pathlib import Path
    scene = ef.read_vs3(Path(__file__).parent / "data" / "view3d" / "gunter2.vs3")
    st = AreaStats()
    f, e = area_row(scene, 38, 1e-6, stats=st)
    assert st.umbra_pairs >= 2 and st.umbra_cells + st.umbra_pieces > 0
    assert abs(f.sum() - 1.0) <= e.sum(), (f.sum() - 1.0, e.sum())
    assert (f >= 0).all()


def _two_plates(gap):
    """A strip P (x -6..6, y 0..1) at height 0 (facing up), a unit square Q at height
    10 facing it, and two plates near Q: K1 at height 9 over x <= 0.5, K2 at height 9.2
    over x >= 0.5 + gap. A segment from P to Q moves at most 0.14 in x between the
    plates' heights, so with gap <= -0.14 the two together hide Q from all of P, and
    neither alone does; with gap > 0, Q is seen through the gap from the middle of P
    (not from its left end, whose lines through the gap pass by Q)."""
    P = [[-6, 0, 0], [6, 0, 0], [6, 1, 0], [-6, 1, 0]]
    Q = [[0, 0, 10], [0, 1, 10], [1, 1, 10], [1, 0, 10]]
    K1 = [[-3, -3, 9], [0.5, -3, 9], [0.5, 4, 9], [-3, 4, 9]]
    K2 = [[0.5 + gap, -3, 9.2], [4, -3, 9.2], [4, 4, 9.2], [0.5 + gap, 4, 9.2]]
    return ef.Scene.from_polygons([P, Q, K1, K2])


def test_hiding_rows_never_claim_a_segment_that_misses():
    """Where a blocker's rows (hiding_rows, for a square's corners) hold at a point y of
    the receiver's plane, every segment from the square (its corners and random points)
    to y meets the blocker, by brute force; and the rows are not vacuous. Planted: the
    rows built from the square's centre alone (not its corners): segments from its
    corners that miss the blocker pass, caught."""
    rng = np.random.default_rng(67)
    held = 0
    for _ in range(40):
        Q, K = _random_case(rng)
        q0 = Q.mean(axis=0)
        RQ = receiver_frame(np.array([0, 0, 1.0]))[:2]
        c, s = rng.uniform(-1, 1, 2), rng.uniform(0.2, 1.5)
        C = np.array([[c[0], c[1], 0], [c[0] + s, c[1], 0], [c[0] + s, c[1] + s, 0],
                      [c[0], c[1] + s, 0]])
        rows = hiding_rows(C, blocker_frames([K]), q0, RQ, 10.0, tol.AREA_UMBRA_MARGIN,
                           tol.AREA_UMBRA_ROW_MARGIN)
        U = rng.uniform(-3, 3, (300, 2))
        ok = ((U @ rows[:, :, :2].transpose(0, 2, 1) + rows[:, None, :, 2]) >= 0).all(
            axis=2).any(axis=0) if len(rows) else np.zeros(len(U), dtype=bool)
        g = rng.random((10, 2))
        X = np.concatenate([C, C[0] + g[:, :1] * (C[1] - C[0]) + g[:, 1:] * (C[3] - C[0])])
        for y in q0 + U[ok] @ RQ:
            assert all(_hits(x, y, K) for x in X)
        held += int(ok.sum())
    assert held > 200


def test_two_blockers_together_hide_the_receiver(monkeypatch):
    """Two plates that together, not alone, hide Q from all of P (_two_plates): the
    umbras of several blockers take all of P (no piece left, the value 0 to the strips'
    bound along P's boundary), neither plate alone takes it, and the row's value is 0
    within its estimate (the exact value: no segment from P to Q misses both). Planted:
    the receiver covered where one blocker's rows hold at one vertex of a triangle (not
    all three): caught below, where a gap lets Q be seen."""
    scene = _two_plates(-0.2)
    P, Q, K1, K2 = (np.asarray(p, float) for p in scene.polygons)
    nP = np.array([0, 0, 1.0])
    args = (receiver_frame(nP), P.mean(axis=0), nP, 1e-9, 12.0)
    left, value, err, count, taken = hidden_pieces(P, Q, [K1, K2], *args)
    # the strips along P's boundary, AREA_UMBRA_SHRINK of its size wide, bounded
    assert left == [] and taken == pytest.approx(12.0)
    assert 0 <= value == err <= 30 * 12 * tol.AREA_UMBRA_SHRINK * unoccluded_bound(P, Q)
    for K in (K1, K2):
        alone = hidden_pieces(P, Q, [K], *args)
        assert alone is None or alone[0]
    # the two plates' planes, one behind the other, prove it too (exactff.area.walls,
    # tried first whatever the blockers): exactly 0
    monkeypatch.setattr(tol, "AREA_WALL_MIN_BLOCKERS", 0)
    st = AreaStats()
    f, e = area_row(scene, 0, 1e-9, stats=st)
    assert st.wall_hidden_pairs == 1 and f[1] == e[1] == 0.0
    monkeypatch.setattr(row_module, "hidden_by_walls", lambda *a: False)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 0)
    monkeypatch.setattr(tol, "AREA_UMBRA_SPLIT_MIN_BLOCKERS", 0)
    st = AreaStats()
    f, e = area_row(scene, 0, 1e-9, stats=st)
    assert st.umbra_pieces > 0 and st.point_values == 0
    assert abs(f[1]) <= e[1] <= tol.AREA_UMBRA_CLOSED_SHARE * 1e-9


def test_two_blockers_with_a_gap_keep_the_value(monkeypatch):
    """Two plates with a gap through which Q is seen from part of P (_two_plates(0.02)):
    with the umbras of several blockers forced (AREA_UMBRA_MIN_LINES 0) the value is
    within the two estimates of the value without any umbra, and agrees with the point
    engine integrated over P (Gauss-Legendre, 6 points a side on 24 x 2 squares; its
    own error, at the visibility's kinks, bounds that comparison). Planted: the pieces
    proven from their centre alone (hiding_rows given the mean of the corners): pieces
    from whose corners Q is seen through the gap taken as hidden, the value too small,
    caught."""
    scene = _two_plates(0.02)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 0)
    monkeypatch.setattr(tol, "AREA_UMBRA_SPLIT_MIN_BLOCKERS", 0)
    # every square left (where Q is seen) integrated as a pair of its own
    monkeypatch.setattr(tol, "AREA_UMBRA_MAX_LEFT", 10 ** 6)
    st = AreaStats()
    f1, e1 = area_row(scene, 0, 1e-9, stats=st)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 2 ** 62)
    f0, e0 = area_row(scene, 0, 1e-9)
    assert st.umbra_pieces > 0
    assert abs(f1[1] - f0[1]) <= e0[1] + e1[1], (f1[1], f0[1], e0[1] + e1[1])
    # the point engine on 24 x 2 squares of P, 6 x 6 Gauss-Legendre points each
    x, w = np.polynomial.legendre.leggauss(6)
    gx = -6 + (np.arange(24)[:, None] + 0.5 * (x[None, :] + 1)).ravel() / 2
    gy = (np.arange(2)[:, None] + 0.5 * (x[None, :] + 1)).ravel() / 2
    W = np.outer(np.tile(w, 24), np.tile(w, 2)).ravel() / 16
    exact = ef.Exact()
    F = [exact.point_form_factors(scene, np.array([a, b, 0.0]), np.array([0, 0, 1.0]))[1]
         for a in gx for b in gy]
    assert f1[1] > 1e-6
    assert abs(float(W @ np.array(F)) / 12 - f1[1]) <= 1e-3 * f1[1], (float(W @ np.array(F)) / 12, f1[1])


@pytest.mark.parametrize("compiled", [True, False])
def test_umbras_of_several_blockers_are_off_without_shortcuts(monkeypatch, compiled):
    """The umbras of several blockers are a shortcut: with ``shortcuts=False`` the two
    plates that together hide Q (_two_plates) take no piece, and the row is within the
    two estimates of the row with them (0: no segment from P to Q misses both plates);
    on the compiled pair and on its numpy reference (``COMPILED_PAIR`` off). Planted:
    the reference's split tried whatever ``shortcuts`` (its guard removed): pieces
    taken without shortcuts, caught."""
    from exactff.area import adaptive
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", compiled)
    monkeypatch.setattr(row_module, "hidden_by_walls", lambda *a: False)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 0)
    monkeypatch.setattr(tol, "AREA_UMBRA_SPLIT_MIN_BLOCKERS", 0)
    scene = _two_plates(-0.2)
    on, off = AreaStats(), AreaStats()
    f1, e1 = area_row(scene, 0, 1e-9, stats=on)
    f0, e0 = area_row(scene, 0, 1e-9, shortcuts=False, stats=off)
    assert on.umbra_pieces > 0 and off.umbra_pieces == 0 and off.umbra_pairs == 0
    assert off.point_values > 0
    assert np.all(np.abs(f1 - f0) <= e0 + e1), (f1, f0, e0 + e1)
    assert abs(f0[1]) <= e0[1]
