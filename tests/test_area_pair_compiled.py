"""An occluded pair's compiled path (exactff/_core/pair.cpp, module exactff.area._pair)
against the numpy and GEOS reference it replaces: the visibility events of every
occluded pair of View3D's files, the same segments to the bit and the same events culled;
and the events of a blocker between two squares against the lines derived by hand; the
curved events (curved.cpp) of every occluded pair of gunter1 and the 106-surface box
against curved.py's numpy; the adaptive levels (levels.cpp) and the hidden parts' set-up
(hidden_setup.cpp) against their numpy reference, call by call."""

import os

import numpy as np
import pytest
import shapely

import exactff as ef
from exactff import NumericalError
from exactff import _tolerances as tol
from exactff.area import adaptive, compiled_pair
from exactff.area import row as row_module
from exactff.area._pair import event_lines as compiled_event_lines
from exactff.area.curved import curved_event_lines
from exactff.area.events import event_lines
from exactff.area.row import AreaStats, area_row
from exactff.area.rules import budget_refined
from exactff.geometry import plane_frame, receiver_frame

from common import rotation

DATA = os.path.join(os.path.dirname(__file__), "data", "view3d")
GUNTER2 = os.path.join(DATA, "gunter2.vs3")


def _every_occluded_pair(monkeypatch, scene, rows, shortcuts, visit):
    """``visit(S, Qc, nP, dP, R, c, radius, atol, solid)`` on every occluded pair of the
    rows at 1e-6 (those that walls hide whole too: exactff.area.walls off), with the
    arguments the pair's integral forms for its events (the integral itself skipped:
    the pair's unoccluded value stands in): the list of what it returned."""
    monkeypatch.setattr(row_module, "hidden_by_walls", lambda *a: False)
    seen = []

    def visit_only(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, st, solid=None,
                   inner=None):
        R, c = receiver_frame(nP), Pc.mean(axis=0)
        dP = float(nP @ Pc[0])
        radius = (1.0 + tol.AREA_HIDDEN_PAD) * float(np.linalg.norm(Pc - c, axis=1).max())
        seen.append(visit(S, Qc, nP, dP, R, c, radius, atol, solid))
        return whole[0], whole[1], 0

    monkeypatch.setattr(adaptive, "_hidden_integral", visit_only)
    for r in rows:
        area_row(scene, r, 1e-6, shortcuts=shortcuts)
    return seen


def _events_of_every_pair(monkeypatch, scene, rows, shortcuts=True):
    """For every occluded pair of the rows, the events both ways: a list of (numpy,
    compiled, their counters (culled_events, solid_events) each)."""

    def both(S, Qc, nP, dP, R, c, radius, atol, solid):
        a, b = AreaStats(), AreaStats()
        ref = event_lines(S, nP, dP, R, c, radius, Qc, shortcuts, a, solid, compiled=False)
        got = event_lines(S, nP, dP, R, c, radius, Qc, shortcuts, b, solid)
        return ref, got, (a.culled_events, a.solid_events), (b.culled_events, b.solid_events)

    return _every_occluded_pair(monkeypatch, scene, rows, shortcuts, both)


@pytest.mark.parametrize("name, rows, shortcuts", [
    ("test4.vs3", None, True), ("facet.vs3", None, True), ("l_room_f3.vs3", None, True),
    ("l_room_f3a.vs3", None, True), ("gunter1.vs3", None, True),
    ("gunter1.vs3", [0, 5, 17], False), ("gunter2.vs3", [0, 150, 397], True)])
def test_compiled_events_are_the_reference_to_the_bit(monkeypatch, name, rows, shortcuts):
    path = GUNTER2 if name == "gunter2.vs3" else os.path.join(DATA, name)
    if not os.path.exists(path):
        pytest.skip(f"{path} not here")
    scene = ef.read_vs3(path)
    seen = _events_of_every_pair(monkeypatch, scene, range(len(scene)) if rows is None else rows,
                                 shortcuts)
    assert len(seen) > 5
    for ref, got, counts_ref, counts_got in seen:
        assert got.shape == ref.shape and np.array_equal(got, ref)
        assert counts_got == counts_ref
    # the shortcuts culled events somewhere (the comparison covers the culling test)
    if shortcuts and name in ("l_room_f3a.vs3", "gunter1.vs3"):
        assert sum(c[0] for _, _, c, _ in seen) > 0


def _curves_of_every_pair(monkeypatch, scene, rows, shortcuts=True):
    """For every occluded pair of the rows, the curved events both ways: a list of
    (numpy, compiled, their counters (curved_events, curved_skipped) each, the disk's
    radius)."""

    def both(S, Qc, nP, dP, R, c, radius, atol, solid):
        a, b = AreaStats(), AreaStats()
        sol = solid if shortcuts else None
        ref = curved_event_lines(S, Qc, nP, dP, R, c, radius, atol, sol, a, compiled=False)
        got = curved_event_lines(S, Qc, nP, dP, R, c, radius, atol, sol, b)
        return (ref, got, (a.curved_events, a.curved_skipped),
                (b.curved_events, b.curved_skipped), radius)

    return _every_occluded_pair(monkeypatch, scene, rows, shortcuts, both)


@pytest.mark.parametrize("name, rows, shortcuts, max_triples, skips", [
    ("gunter1.vs3", None, True, None, False), ("gunter1.vs3", [0, 5, 17], False, None, False),
    ("box", None, True, 50, True), ("box", None, True, None, False),
    ("gunter2.vs3", [38, 150], True, None, True)])
def test_compiled_curves_are_the_reference(monkeypatch, name, rows, shortcuts, max_triples,
                                           skips):
    """The chords of the curved events compiled (_core/curved.cpp) against curved.py's
    numpy, on every occluded pair of the rows at 1e-6: the same number of chords, the
    same counters, each end within 1e-12 of the disk's radius of the reference's (the
    same steps in the same order: they agree to the bit here, the tolerance leaves room
    for a compiler's rounding). Pairs beyond AREA_CURVED_MAX_TRIPLES (gunter2's row 38
    has some, and the box's with the limit lowered to 50; none of gunter1's since only
    mutually skew edges make curves) are skipped alike (no chords) and counted."""
    if max_triples is not None:
        monkeypatch.setattr(tol, "AREA_CURVED_MAX_TRIPLES", max_triples)
    path = GUNTER2 if name == "gunter2.vs3" else os.path.join(DATA, name)
    if name != "box" and not os.path.exists(path):
        pytest.skip(f"{path} not here")
    scene = ef.scenes.unit_squares_room() if name == "box" else ef.read_vs3(path)
    seen = _curves_of_every_pair(monkeypatch, scene, range(len(scene)) if rows is None else rows,
                                 shortcuts)
    assert len(seen) > 20
    for ref, got, counts_ref, counts_got, radius in seen:
        assert got.shape == ref.shape and counts_got == counts_ref
        assert np.all(np.abs(got - ref) <= 1e-12 * radius)
    # the comparison covers curves traced and pairs skipped
    traced = sum(c[0] for _, _, c, _, _ in seen)
    skipped = sum(c[1] for _, _, c, _, _ in seen)
    assert traced > 40 and sum(len(r) for r, *_ in seen) > 400
    assert (skipped > 0) == skips


def test_compiled_curves_check_their_arrays():
    from exactff.area._pair import curved_event_lines as compiled_curves
    from exactff.area.curved import _CURVED_TOLERANCES

    Q = np.array([[0, 0, 2], [0, 1, 2], [1, 1, 2], [1, 0, 2]], float)
    ok = dict(W=np.vstack([Q, Q + 1, Q - 1]), start=np.array([0, 4, 8, 12]),
              solid=np.zeros(0, np.int64), Qc=Q, nP=[0, 0, 1.0], dP=0.0, frame=np.eye(3),
              c=[0, 0, 0.0], radius=1.0, atol=1e-6,
              tol={k: getattr(tol, k) for k in _CURVED_TOLERANCES})
    assert compiled_curves(**ok)[0].shape[1:] == (2, 2)
    with pytest.raises(ValueError, match="wrong shapes"):
        compiled_curves(**{**ok, "Qc": Q[:, :2]})
    with pytest.raises(ValueError, match="wrong shapes"):
        compiled_curves(**{**ok, "solid": np.zeros(2, np.int64)})
    with pytest.raises(IndexError, match="start"):
        compiled_curves(**{**ok, "start": np.array([0, 4, 8, 13])})


def test_events_of_a_blocker_between_two_squares():
    # a unit square Q at height 2 over the emitter's plane z = 0 and a square blocker K
    # [.4, .6]^2 at height 1: the image through a vertex v of K of Q's edge at e is 2 v - e
    # on z = 0, the image through a vertex of Q of K's edge 2 e - v; the lines are
    # x = -0.2, 0.2, 0.8, 1.2 and the same in y (both planes are parallel to z = 0: no
    # line of their own)
    Q = np.array([[0, 0, 2], [0, 1, 2], [1, 1, 2], [1, 0, 2]], float)
    K = np.array([[.4, .4, 1], [.6, .4, 1], [.6, .6, 1], [.4, .6, 1]], float)
    nP, c = np.array([0, 0, 1.0]), np.array([.5, .5, 0])
    R = receiver_frame(nP)
    lines = event_lines([Q, K], nP, 0.0, R, c, 2.0, Q)
    ends = c + lines @ R[:2]                                      # (m, 2, 3), z = 0
    on = {("x", round(float(x), 12)) for s in ends if abs(s[0, 0] - s[1, 0]) < 1e-15
          for x in [s[0, 0]]}
    on |= {("y", round(float(y), 12)) for s in ends if abs(s[0, 1] - s[1, 1]) < 1e-15
           for y in [s[0, 1]]}
    expect = {(a, v) for a in "xy" for v in (-0.2, 0.2, 0.8, 1.2)}
    assert on == expect
    # every segment on one of those lines and within the disk
    assert all(abs(s[0, 0] - s[1, 0]) < 1e-15 or abs(s[0, 1] - s[1, 1]) < 1e-15 for s in ends)
    assert np.all(np.linalg.norm(lines, axis=2) <= 2.0 * (1 + 1e-15))
    assert np.array_equal(lines, event_lines([Q, K], nP, 0.0, R, c, 2.0, Q, compiled=False))


@pytest.mark.parametrize("draw", range(5))
def test_a_vertex_on_an_edge_line_makes_no_event_turned(draw):
    # a blocker's vertex (0, 0, 1) above the emitter's corner and another blocker's edge
    # from that corner up to (0, 0, 2): on one line, whose plane with the vertex is m =
    # 0 as built (no event); turned and moved by up to 1000, m is rounding's, a plane
    # through the line at random, and its event line passed near the corner but not
    # through it (gunter1 turned: 1.4e-4 off, cutting the corner from its cell; 4 of these
    # 5 draws before). Compiled and numpy alike: no line meets P within 1e-2 of its
    # corner but misses the corner by more than 1e-9
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    Q = np.array([[2, -1, 3], [2, 2, 3], [-1, 2, 3], [-1, -1, 3]], float)     # facing P
    A = np.array([[0, 0, 1], [0.5, -0.5, 1], [0.5, -1, 1.5]], float)
    B = np.array([[0, 0, 0], [0, 0, 2], [-0.5, -0.5, 2], [-0.5, -0.5, 0]], float)
    rng = np.random.default_rng(5)
    for _ in range(draw + 1):
        axis, angle, move = rng.normal(size=3), rng.uniform(0, 2 * np.pi), rng.uniform(-1e3, 1e3, 3)
    turn = rotation(axis, angle)
    S = [X @ turn.T + move for X in (Q, A, B)]
    Pt = P @ turn.T + move
    nP = turn[:, 2]
    R, c = receiver_frame(nP), Pt.mean(axis=0)
    lines = event_lines(S, nP, float(nP @ Pt[0]), R, c, 1.0, S[0])
    assert np.array_equal(lines, event_lines(S, nP, float(nP @ Pt[0]), R, c, 1.0, S[0],
                                             compiled=False))
    # each segment's distance from the corner (segments of no length: none)
    corner = (Pt[0] - c) @ R[:2].T
    lines = lines[np.any(lines[:, 1] != lines[:, 0], axis=1)]
    d = lines[:, 1] - lines[:, 0]
    off = np.abs(d[:, 0] * (corner[1] - lines[:, 0, 1])
                 - d[:, 1] * (corner[0] - lines[:, 0, 0])) / np.linalg.norm(d, axis=1)
    meets = shapely.intersects(shapely.linestrings(lines), shapely.Polygon((Pt - c) @ R[:2].T))
    assert meets.sum() >= 10 and not np.any(meets & (off > 1e-9) & (off < 1e-2)), off[meets]


def test_compiled_events_check_their_arrays():
    Q = np.array([[0, 0, 2], [0, 1, 2], [1, 1, 2], [1, 0, 2]], float)
    nQ, q0, RQ, Q2 = plane_frame(Q)
    ok = dict(W=Q, start=np.array([0, 4]), solid=np.zeros(0, np.int64), nP=[0, 0, 1.0],
              dP=0.0, frame=np.eye(3), c=[0, 0, 0.0], radius=1.0, nQ=nQ, q0=q0, RQ=RQ[:2],
              Q2=Q2, shortcuts=True, ray_parallel=tol.AREA_RAY_PARALLEL,
              event_parallel=tol.AREA_EVENT_PARALLEL, line_ulps=tol.AREA_EVENT_LINE_ULPS,
              eps=tol.EPS)
    assert compiled_event_lines(**ok)[0].shape[1:] == (2, 2)
    with pytest.raises(ValueError, match="wrong shapes"):
        compiled_event_lines(**{**ok, "nP": [0, 1.0]})
    with pytest.raises(ValueError, match="wrong shapes"):
        compiled_event_lines(**{**ok, "solid": np.zeros(3, np.int64)})
    with pytest.raises(IndexError, match="start"):
        compiled_event_lines(**{**ok, "start": np.array([0, 5])})


def test_hidden_parts_kept_in_doubles_within_the_estimates(monkeypatch):
    # a point whose images the doubles' rounding can move by more than
    # AREA_IMAGE_PRECISE_RTOL is computed again in long double only where that moves more
    # of its value than AREA_IMAGE_PRECISE_SHARE of the budget: the hidden parts of
    # gunter1's row 17 at 1e-6 (every call, all their points) both ways, within the two
    # estimates of each other, and the doubles' estimates within the budget's share more
    from exactff.area import hidden

    calls, values = [], hidden.hidden_values

    def record(X, nP, Qc, blockers, st=None, atol=0.0, setup=None, *a, **k):
        calls.append((X, nP, Qc, blockers, atol, setup))
        return values(X, nP, Qc, blockers, st, atol, setup, *a, **k)

    # the levels by numpy, which call hidden_values (the compiled ones do its
    # work inside: test_compiled_levels_against_numpy)
    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", False)
    monkeypatch.setattr(adaptive, "hidden_values", record)
    ef.area_form_factors(ef.read_vs3(os.path.join(DATA, "gunter1.vs3")), rows=[17],
                         tolerance=1e-6)
    monkeypatch.undo()
    assert len(calls) > 5
    changed = 0
    for X, nP, Qc, blockers, atol, setup in calls:
        H, EH = values(X, nP, Qc, blockers, None, atol, setup)
        with monkeypatch.context() as m:
            m.setattr(tol, "AREA_IMAGE_PRECISE_SHARE", -1.0)       # always again
            H1, EH1 = values(X, nP, Qc, blockers, None, atol, setup)
        assert np.all(np.abs(H - H1) <= EH + EH1)
        assert np.all(EH <= EH1 + tol.AREA_IMAGE_PRECISE_SHARE * atol * (1 + 1e-9))
        changed += int(np.count_nonzero(H != H1))
    assert changed > 1000          # the doubles stood for many points


def _cut_calls(monkeypatch, scene, rows):
    """The first cut of every occluded pair of the rows (lengthened, no grid): its
    arguments, the compiled cells (triangles, count, ok) and GEOS's (triangles, count)."""
    import shapely

    from exactff.area import events
    from exactff.area._pair import cut_cells as compiled_cut_cells

    calls, cut = [], events.cut_cells

    def record(Pc, nP, lines, R, c, grid=None, lengthen=True):
        if grid is None and lengthen:
            calls.append((Pc, nP, np.asarray(lines, float).reshape(-1, 2, 2), R, c))
        return cut(Pc, nP, lines, R, c, grid, lengthen)

    monkeypatch.setattr(adaptive, "cut_cells", record)
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", False)   # the steps one by one
    for r in rows:
        area_row(scene, r, 1e-6)
    monkeypatch.undo()
    faces, cdt = [], shapely.constrained_delaunay_triangles

    def count(geoms, *a, **k):
        faces.append(shapely.area(geoms))
        return cdt(geoms, *a, **k)

    out = []
    for Pc, nP, lines, R, c in calls:
        P2 = (Pc - c) @ R[:2].T
        A = 0.5 * float(np.sum(P2[:, 0] * np.roll(P2[:, 1], -1) - np.roll(P2[:, 0], -1) * P2[:, 1]))
        size = float(np.ptp(P2, axis=0).max())
        got = compiled_cut_cells(P2=np.ascontiguousarray(P2 if A > 0 else P2[::-1]),
                                 segments=lines, step=tol.AREA_CUT_EXTEND_RTOL * np.sqrt(abs(A)),
                                 merge=tol.AREA_HULL_RTOL * size,
                                 sliver=tol.AREA_SLIVER_CELL * abs(A))
        with monkeypatch.context() as m:
            m.setattr(shapely, "constrained_delaunay_triangles", count)
            T = cut(Pc, nP, lines, R, c, compiled=False)
        out.append((P2, abs(A), got, ((T - c) @ R[:2].T)[:, :, :2], faces[-1]))
    return out


def _tri_area(T):
    return 0.5 * np.abs((T[:, 1, 0] - T[:, 0, 0]) * (T[:, 2, 1] - T[:, 0, 1])
                        - (T[:, 1, 1] - T[:, 0, 1]) * (T[:, 2, 0] - T[:, 0, 0]))


@pytest.mark.parametrize("name, rows", [
    ("test4.vs3", None), ("facet.vs3", None), ("l_room_f3a.vs3", None),
    ("gunter1.vs3", None), ("gunter2.vs3", [150, 397]), ("window", None)])
def test_compiled_cells_are_geos_cells(monkeypatch, name, rows):
    # the arrangement compiled against GEOS's noded union, polygonized: the same cells
    # (each line cuts where it meets others or P's boundary, a dangle cuts nothing), up
    # to slivers of less than 1e-12 of P's area (GEOS keeps a few just above the sliver
    # limit, 1e-14, where the compiled noding merges crossings closer than 1e-12 of P's
    # size) and a few cells the compiled noding cuts further, and the same area to
    # rounding, every triangle in P
    # (the window: a room with a window on its wall and a box, the tie rule's scene,
    # where a cut missed by near-parallel lines left a row 1.4e-9 from 1 beyond its
    # estimates of 6.0e-10)
    if name == "window":
        from test_area import _room_with_a_window

        scene = _room_with_a_window(True, True)[0]
    else:
        path = GUNTER2 if name == "gunter2.vs3" else os.path.join(DATA, name)
        if not os.path.exists(path):
            pytest.skip(f"{path} not here")
        scene = ef.read_vs3(path)
    # (the pairs that walls hide whole cut all the same:
    # exactff.area.walls takes most of gunter2's rows 150 and 397)
    monkeypatch.setattr(row_module, "hidden_by_walls", lambda *a: False)
    out = _cut_calls(monkeypatch, scene, range(len(scene)) if rows is None else rows)
    assert len(out) > 5
    split = 0
    declined = 0
    for P2, A, (tris, cells, _, ok), T, faces in out:
        if not ok:                     # left to GEOS (counted)
            declined += 1
            continue
        big, big_geos = list(cells[cells > 1e-12 * A]), list(faces[faces > 1e-12 * A])
        for a in list(big_geos):                  # the cells both have, matched
            k = np.flatnonzero(np.abs(np.array(big) - a) <= 1e-12 * A) if big else []
            if len(k):
                big.pop(int(k[0]))
                big_geos.remove(a)
        # the rest: GEOS cells the compiled noding cut further, along a line that ends
        # on another within 1e-12 of P's size (a dangle to GEOS, ends a few ulps short)
        assert len(big) >= len(big_geos) and abs(sum(big) - sum(big_geos)) <= 1e-12 * A
        split += bool(big_geos)
        assert abs(_tri_area(tris).sum() - _tri_area(T).sum()) <= 1e-12 * A
        assert abs(_tri_area(tris).sum() - A) <= 1e-12 * A
        # counter-clockwise, inside P (every vertex on P's side of each edge, to rounding)
        d = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
        assert np.all(d[0][:, 0] * d[1][:, 1] - d[0][:, 1] * d[1][:, 0] > 0)
        E = np.roll(P2, -1, axis=0) - P2
        V = tris.reshape(-1, 2)
        side = (E[None, :, 0] * (V[:, None, 1] - P2[None, :, 1])
                - E[None, :, 1] * (V[:, None, 0] - P2[None, :, 0]))
        assert side.min() >= -1e-12 * A
    # (gunter1: 2 of 252 calls, the same 2 without any curved event; 7 when curves were
    # traced for edges whose lines meet: straight chords copying a vertex-edge event,
    # ending 1e-6 short of P's boundary, along which GEOS dropped a real cut)
    assert split <= max(2, len(out) // 50), split
    assert declined <= len(out) // 10, declined


def test_compiled_cells_of_a_square():
    # a unit square cut by its diagonals (four cells of 1/4), by one line ending inside it
    # (a dangle: no cut), by a line ending within the lengthening of the boundary (a cut),
    # and by two lines crossing inside with their ends free (no cut: dangles on both)
    from exactff.area._pair import cut_cells as compiled_cut_cells

    P = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)

    def cells(*segments):
        tris, areas, _, ok = compiled_cut_cells(P2=P, segments=np.array(segments, float).reshape(-1, 2, 2),
                                             step=1e-9, merge=1e-12, sliver=1e-14)
        assert ok and abs(areas.sum() - 1) < 1e-15
        return len(areas), np.sort(np.round(_tri_area(tris), 12))

    n, a = cells([[-1, -1], [2, 2]], [[-1, 2], [2, -1]])
    assert n == 4 and np.allclose(a, 0.25) and len(a) == 4
    assert cells([[-1, 0.5], [0.5, 0.5]])[0] == 1
    n, a = cells([[1e-10, 0.5], [1 - 1e-10, 0.5]])
    assert n == 2 and np.allclose(a, 0.25)
    assert cells([[0.2, 0.5], [0.8, 0.5]], [[0.5, 0.2], [0.5, 0.8]])[0] == 1
    # not convex: left to GEOS
    L = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    assert not compiled_cut_cells(P2=L, segments=np.zeros((0, 2, 2)), step=1e-9, merge=1e-12,
                                  sliver=1e-14)[3]


def _strip_lines(rng, copies, pieces):
    """A 100 x 1 strip and its event lines: 60 lengthwise and 1,000 across, each line
    given as ``copies`` (lengthwise) or ``pieces`` (across) overlapping parts of it whose
    union spans the strip, shuffled."""
    P = np.array([[0, 0], [100, 0], [100, 1], [0, 1]], float)
    segs = []
    for y in (np.arange(60) + 0.5) / 60:
        lo = rng.uniform(-1, 99, copies)
        lo[:2] = -1, 50
        segs += [[[a, y], [a + 51, y]] for a in lo]
    for x in (np.arange(1000) + 0.5) / 10:
        cuts = np.sort(rng.uniform(0, 1, pieces - 1))
        ends = np.concatenate([[-0.5], cuts, [1.5]])
        segs += [[[x, a - 0.01], [x, b + 0.01]] for a, b in zip(ends[:-1], ends[1:])]
    segs = np.array(segs, float)
    return P, segs[rng.permutation(len(segs))]


def test_compiled_cells_join_collinear_lines():
    # thousands of events on few lines (View3D's gunter2, row 38: 14,177 lines in one
    # emitter lay on 1,586; noding each copy against the others took 8 GB and raised):
    # the copies are joined before the noding, so the arrangement is that of the lines
    # (60 x 1,000 crossings), not of the copies (24,000 x 5,000), the same cells as the
    # lines given once each, in bounded memory (the peak resident size of the process
    # grows by less than 200 MB: noding the copies took 820 MB more)
    import resource

    from exactff.area._pair import cut_cells as compiled_cut_cells

    rng = np.random.default_rng(49)
    P, segs = _strip_lines(rng, copies=400, pieces=5)
    assert len(segs) == 29000
    once = np.concatenate([[[[-1, y], [101, y]] for y in (np.arange(60) + 0.5) / 60],
                           [[[x, -0.5], [x, 1.5]] for x in (np.arange(1000) + 0.5) / 10]])

    def cut(segments):
        return compiled_cut_cells(P2=P, segments=segments, step=1e-9 * 10,
                                  merge=1e-12 * 100, sliver=1e-14 * 100)

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss           # KiB
    tris, areas, lines, ok = cut(segs)
    grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - peak
    assert ok and lines == 4 + 60 + 1000 and grown < 200_000, (ok, lines, grown)
    ref_tris, ref_areas, ref_lines, ref_ok = cut(once)
    assert ref_ok and ref_lines == lines and len(areas) == len(ref_areas) == 61 * 1001
    assert np.allclose(np.sort(areas), np.sort(ref_areas), rtol=0, atol=1e-12 * 100)
    assert abs(areas.sum() - 100) <= 1e-12 * 100


def test_gunter2_pair_of_many_events_cut_into_cells():
    # the pair of View3D's gunter2 that raised (row 38, the strip under a saw-tooth
    # roof, to the wall 3 behind 151 blockers): 32,000 event segments, cut by the
    # compiled arrangement into cells that tile the emitter, the lines joined to fewer
    # than 1,600
    from exactff.area._pair import cut_cells as compiled_cut_cells
    from exactff.area.culling import padded_polygons, pair_blockers
    from exactff.area.events import cut_cells

    if not os.path.exists(GUNTER2):
        pytest.skip(f"{GUNTER2} not here")
    scene = ef.read_vs3(GUNTER2)
    polys = [np.asarray(p, float) for p in scene.polygons]
    Pc, Qc = polys[38], polys[3]
    scale = float(np.ptp(scene.vertices, axis=0).max())
    B = pair_blockers(padded_polygons(polys), 38, 3, Pc, Qc, scale)
    assert len(B) > 140
    nP = scene.normals[38]
    R, c = receiver_frame(nP), Pc.mean(axis=0)
    radius = (1.0 + tol.AREA_HIDDEN_PAD) * float(np.linalg.norm(Pc - c, axis=1).max())
    lines = event_lines([Qc] + [polys[k] for k in B], nP, float(nP @ Pc[0]), R, c, radius, Qc)
    assert len(lines) > 20000
    P2 = (Pc - c) @ R[:2].T
    A = 0.5 * float(np.sum(P2[:, 0] * np.roll(P2[:, 1], -1) - np.roll(P2[:, 0], -1) * P2[:, 1]))
    _, areas, joined, ok = compiled_cut_cells(
        P2=np.ascontiguousarray(P2 if A > 0 else P2[::-1]), segments=lines,
        step=tol.AREA_CUT_EXTEND_RTOL * np.sqrt(abs(A)),
        merge=tol.AREA_HULL_RTOL * float(np.ptp(P2, axis=0).max()),
        sliver=tol.AREA_SLIVER_CELL * abs(A))
    assert ok and joined < 1600 and len(areas) > 10000, (ok, joined, len(areas))
    assert abs(areas.sum() - abs(A)) <= 1e-12 * abs(A)
    T = cut_cells(Pc, nP, lines, R, c)
    assert abs(_tri_area((T - c) @ R[:2].T).sum() - abs(A)) <= 1e-12 * abs(A)


def _level_calls(monkeypatch, scene, rows, tolerance):
    """Every call of the adaptive levels that the rows make (by numpy), with copies of
    its arguments: (args, acc) for :func:`exactff.area.adaptive._levels`."""
    calls, levels = [], adaptive._adaptive_levels

    def record(*args):
        acc = args[-1]
        calls.append((tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args[:-1]),
                      {k: list(v) for k, v in acc.items()}))
        return levels(*args)

    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", False)
    monkeypatch.setattr(adaptive, "_adaptive_levels", record)
    ef.area_form_factors(scene, rows=rows, tolerance=tolerance)
    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", True)
    monkeypatch.setattr(adaptive, "_adaptive_levels", levels)
    return calls


@pytest.mark.parametrize("name, rows, tolerance, small", [("test4.vs3", None, 1e-9, None),
                                                          ("facet.vs3", None, 1e-9, None),
                                                          ("gunter1.vs3", [8, 17], 1e-6, None),
                                                          ("gunter1.vs3", [8, 17], 1e-6, 1.0)])
def test_compiled_levels_against_numpy(monkeypatch, name, rows, tolerance, small):
    # every call of the adaptive levels (_core/levels.cpp) that the rows make, compiled
    # and by numpy (adaptive._adaptive_levels, the reference) from the same triangles:
    # the same triangles accepted in the same order, at the same level, rung and corner,
    # the same slivers and points, and the rules' sums equal to rounding (the nodes' sums
    # are taken in another order), far within the nodes' estimates. At 1e-6 the small
    # triangles take the symmetric pairs of degrees 2 and 4, then 4 and 8 (rules.rule_pair;
    # ``small`` 1: the share of every triangle, so that the distance alone decides, and
    # small triangles are met on both rungs: counted below)
    if small is not None:
        monkeypatch.setattr(tol, "AREA_SMALL_TRIANGLE_SHARE", small)
    calls = _level_calls(monkeypatch, ef.read_vs3(os.path.join(DATA, name)), rows, tolerance)
    assert len(calls) > 10
    reference, pair, met = adaptive._adaptive_levels, adaptive.rule_pair, {}

    def counted(T, rung, corner, atol, small=False):
        met[rung, small] = met.get((rung, small), 0) + len(T)
        return pair(T, rung, corner, atol, small)

    monkeypatch.setattr(adaptive, "rule_pair", counted)
    for args, acc in calls:
        got, ref = ({k: list(v) for k, v in acc.items()} for _ in range(2))
        monkeypatch.setattr(adaptive, "COMPILED_LEVELS", True)
        monkeypatch.setattr(adaptive, "_adaptive_levels", None)      # no fallback taken
        r_got = adaptive._levels(*args, got)
        monkeypatch.setattr(adaptive, "_adaptive_levels", reference)
        r_ref = adaptive._adaptive_levels(*args, ref)
        assert not len(r_got[0]) and not len(r_ref[0])
        assert r_got[4] == pytest.approx(r_ref[4], rel=1e-12, abs=1e-300)   # slivers
        assert r_got[5] == r_ref[5]                                        # points
        got, ref = ({k: np.concatenate(v) if v else np.zeros(0) for k, v in a.items()}
                    for a in (got, ref))
        for k in ("T", "depth", "rung", "corner", "checked"):
            assert np.array_equal(got[k], ref[k]), k
        scale = np.abs(ref["rnd"]) + np.abs(ref["rndU"]) + 1e-300
        for k in ("hi", "lo", "diff", "hiU", "loU"):
            assert np.all(np.abs(got[k] - ref[k]) <= 1e-12 * np.abs(ref[k]) + 1e-3 * scale), k
        for k in ("rnd", "rndU"):
            assert np.allclose(got[k], ref[k], rtol=1e-12, atol=0), k
    if small:
        assert met.get((0, True)) and met.get((1, True)) and met.get((0, False)), met


def test_compiled_levels_matrix_against_numpy(monkeypatch):
    # test4's full matrix at 1e-9 both ways: the same points, values within 1e-13 of each
    # other (and so within the estimates), estimates alike
    scene = ef.read_vs3(os.path.join(DATA, "test4.vs3"))
    out = []
    for compiled in (True, False):
        monkeypatch.setattr(adaptive, "COMPILED_LEVELS", compiled)
        st = {}
        out.append(ef.area_form_factors(scene, tolerance=1e-9, error=True, stats=st) + (st,))
    (F, E, st), (G, EG, sg) = out
    assert st == sg and st["point_values"] > 10_000
    assert np.all(np.abs(F - G) <= 1e-13) and np.allclose(E, EG, rtol=1e-9, atol=1e-16)


@pytest.mark.parametrize("name, rows", [("gunter1.vs3", range(0, 25, 3)), ("test4.vs3", None),
                                        ("facet.vs3", None), ("cornell", [0, 1, 10, 16]),
                                        ("furnished", [0, 5, 29]), ("inward", [0, 1])])
def test_compiled_hidden_setup_against_numpy(monkeypatch, name, rows):
    # every hidden parts' set-up that the rows make (at 1e-6), compiled
    # (_core/hidden_setup.cpp) and by numpy (hidden_setup(compiled=False), the reference):
    # None alike; else the same blockers kept, vertex counts and solids, the vertices
    # (clipped to Qc's plane: numpy's matrix products may fuse a multiply-add) within a
    # few units of rounding of the scene's size, the normals and the box alike
    from exactff.area import hidden

    # (furnished: a room of 24 squares facing in with a cube inside; inward: a closed box
    # facing in between two squares facing each other, a convex solid whose members'
    # normals the set-up turns outward)
    floor = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    scene = (ef.scenes.cornell_box(closed=True) if name == "cornell" else
             ef.scenes.furnished_box(2, [((.3, .3, .2), (.6, .7, .5))]) if name == "furnished"
             else ef.Scene.from_polygons([floor, [[x, y, 3] for x, y, _ in floor[::-1]]]
                                         + ef.scenes.box_polygons((.3, .3, 1), (.7, .6, 2)))
             if name == "inward" else ef.read_vs3(os.path.join(DATA, name)))
    calls, setup = [], hidden.hidden_setup

    def record(*a, **k):
        calls.append((a, k))
        return setup(*a, **k)

    monkeypatch.setattr(adaptive, "hidden_setup", record)
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", False)   # the steps one by one
    ef.area_form_factors(scene, rows=rows, tolerance=1e-6)
    monkeypatch.undo()
    assert len(calls) > 5
    size = float(np.ptp(scene.vertices, axis=0).max())
    near = 8 * tol.EPS * float(np.abs(scene.vertices).max())
    solids = 0
    for a, k in calls:
        A, B = setup(*a, **k), setup(*a, **k, compiled=False)
        assert (A is None) == (B is None)
        if A is None:
            continue
        assert A.parts.shape[0] == 0 == B.parts.shape[0] and np.array_equal(A.corners, B.corners)
        assert np.array_equal(A.counts, B.counts) and np.array_equal(A.group, B.group)
        assert A.V.shape == B.V.shape and np.abs(A.V - B.V).max() <= near
        assert all(np.abs(x - y).max() <= near for x, y in zip(A.Kc, B.Kc))
        assert len(A.Kc) == len(B.Kc)
        for f in ("nQ", "q0", "RQ", "NK"):
            assert np.allclose(getattr(A, f), getattr(B, f), rtol=0, atol=1e-14), f
        assert np.abs(A.lo - B.lo).max() <= near and np.abs(A.hi - B.hi).max() <= near
        assert A.extent == pytest.approx(B.extent, rel=1e-14, abs=near / size)
        solids += int((A.group >= 0).sum())
    if name in ("cornell", "furnished", "inward"):
        assert solids > 0                  # the blocks' faces as members of their solids


def test_compiled_hidden_setup_declines_what_it_does_not_build():
    # a receiver not strictly convex (a vertex on an edge's line), or a blocker not
    # convex (an L), is declined (status 2) and built by numpy; nothing in front: None
    from exactff.area import hidden
    from exactff.area._pair import hidden_setup as compiled

    names = ("EPS", "CONVEX_TURN_ULPS", "CLIP_MEET_ULPS", "AREA_STRICT_TURN", "AREA_HULL_RTOL")
    t = {k: getattr(tol, k) for k in names} | {"NORMAL_FLOOR": 1e-292}
    Q = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]], float)        # facing down
    Qline = np.array([[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0.5, 1], [1, 0, 1]], float)
    K = np.array([[.2, .2, .5], [.8, .2, .5], [.8, .8, .5], [.2, .8, .5]])
    L = np.array([[.2, .2, .5], [.8, .2, .5], [.8, .4, .5], [.4, .4, .5], [.4, .8, .5],
                  [.2, .8, .5]])
    none = (np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    for R, B, status in ((Q, K, 0), (Qline, K, 2), (Q, L, 2), (Q, K + [0, 0, 1], 1)):
        r = compiled(R, B, np.array([0, len(B)]), *none, t)
        assert r[0] == status
        want = hidden.hidden_setup(R, [B], compiled=False)
        got = hidden.hidden_setup(R, [B])
        assert (got is None) == (want is None) == (status == 1)
        if want is not None:
            assert len(got.Kc) == len(want.Kc) and np.array_equal(got.V, want.V)



def test_compiled_levels_give_pairs_with_lost_points_to_numpy(monkeypatch):
    # a point with more pieces than AREA_MAX_PIECES is lost (here every point with any:
    # 0 allowed): the compiled levels decline the pair and numpy's levels send its
    # points to the bound 0 <= hidden <= U or the engine; the row both ways alike, the
    # same points, engine calls and bounded points, and near the reference value
    from test_area import OCCLUDED_REFERENCES, _square

    plate, ref = OCCLUDED_REFERENCES[0]
    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
    out, declined, levels = [], [], adaptive._compiled_adaptive_levels

    def record(*a, **k):
        r = levels(*a, **k)
        declined.append(not r[0])
        return r

    monkeypatch.setattr(adaptive, "_compiled_adaptive_levels", record)
    monkeypatch.setattr(tol, "AREA_MAX_PIECES", 0)
    for compiled in (True, False):
        monkeypatch.setattr(adaptive, "COMPILED_LEVELS", compiled)
        st = {}
        out.append(ef.area_form_factors(scene, rows=[0], tolerance=1e-6, error=True, stats=st)
                   + (st,))
    (F, E, st), (G, EG, sg) = out
    assert declined and all(declined)
    assert st == sg and st["engine_fallback_points"] + st["bounded_points"] > 0
    assert np.array_equal(F, G) and np.array_equal(E, EG)
    assert abs(F[0, 1] - ref) <= E[0, 1] + 1e-13


def test_compiled_corner_first_against_numpy(monkeypatch):
    # every call of the cells' corner test that test4, l_room_f3a and gunter1 make at
    # 1e-6, compiled and by numpy (_corner_first(compiled=False), the reference): the
    # same triangles, turned alike, the same corners; some cut in four (two corners)
    calls, corner_first = [], adaptive._corner_first

    def record(*a, **k):
        calls.append((a, k))
        return corner_first(*a, **k)

    monkeypatch.setattr(adaptive, "_corner_first", record)
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", False)   # the steps one by one
    for name in ("test4.vs3", "l_room_f3a.vs3", "gunter1.vs3"):
        ef.area_form_factors(ef.read_vs3(os.path.join(DATA, name)), tolerance=1e-6)
    monkeypatch.undo()
    corners = cut = 0
    for a, k in calls:
        (T, c), (T0, c0) = corner_first(*a, **k), corner_first(*a, **k, compiled=False)
        assert np.array_equal(T, T0) and np.array_equal(c, c0)
        corners += int(c.sum())
        cut += len(T) > len(a[0])
    assert corners > 1000 and cut > 0


def test_levels_raise_where_a_rules_difference_is_not_finite(monkeypatch):
    # a rules' difference NaN (here every one: the emitter's area NaN divides the rules'
    # sums) has no place in the largest-first order of the error budget: the compiled
    # levels (whose sort would be undefined behaviour on it) decline the pair, and
    # numpy's budget_refined raises, as it does when called directly
    from test_area import OCCLUDED_REFERENCES, _square

    with pytest.raises(NumericalError, match="triangle 1 is nan: not finite"):
        budget_refined(np.array([0.1, np.nan, 0.2]), np.ones(3), np.zeros(3, int),
                       np.zeros(3, int), 0.0, 1.0, 3.0)
    with pytest.raises(NumericalError, match="triangle 0 is inf: not finite"):
        budget_refined(np.array([np.inf]), np.ones(1), np.zeros(1, int), np.zeros(1, int),
                       0.0, 1.0, 1.0)
    plate, _ = OCCLUDED_REFERENCES[0]
    scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
    calls = _level_calls(monkeypatch, scene, [0], 1e-6)
    assert calls
    args, acc = calls[0]
    args = list(args)
    args[10] = np.nan                                                   # area_P
    declined, levels = [], adaptive._compiled_adaptive_levels

    def record(*a, **k):
        r = levels(*a, **k)
        declined.append(not r[0])
        return r

    monkeypatch.setattr(adaptive, "_compiled_adaptive_levels", record)
    monkeypatch.setattr(adaptive, "COMPILED_LEVELS", True)
    with pytest.raises(NumericalError, match="not finite"):
        adaptive._levels(*args, {k: list(v) for k, v in acc.items()})
    assert declined == [True]


def _pair_statuses(monkeypatch):
    """The compiled pair's statuses, as they come (0: taken; else declined)."""
    statuses, pair = [], adaptive._hidden_integral_in_one_call

    def record(*a, **k):
        r = pair(*a, **k)
        statuses.append(r[0])
        return r

    monkeypatch.setattr(adaptive, "_hidden_integral_in_one_call", record)
    return statuses


@pytest.mark.parametrize("name, rows, tolerance, shortcuts", [
    ("gunter1.vs3", None, 1e-6, True), ("gunter1.vs3", [8, 17], 1e-9, True),
    ("test4.vs3", None, 1e-9, True), ("test4.vs3", None, 1e-6, False),
    ("facet.vs3", None, 1e-9, True), ("box", range(0, 106, 9), 1e-6, True)])
def test_compiled_pair_is_the_reference_to_the_bit(monkeypatch, name, rows, tolerance,
                                                   shortcuts):
    # the whole pair in one call (_core/occluded_pair.cpp) and its steps one by one
    # (_hidden_integral, the reference): every value and estimate the same to the bit
    # (numpy's pairwise sums and the BLAS's fused products kept), the same counts, and
    # every occluded pair taken by the one call (gunter1 at 1e-6 leaves 6 triangles
    # unevaluated, points.unevaluated)
    scene = (ef.scenes.unit_squares_room() if name == "box"
             else ef.read_vs3(os.path.join(DATA, name)))
    st = _compiled_against_reference(monkeypatch, scene, rows, tolerance, shortcuts)
    assert (st["unevaluated_triangles"] > 0) == (name == "gunter1.vs3" and tolerance == 1e-6)


def _compiled_against_reference(monkeypatch, scene, rows, tolerance, shortcuts):
    """The rows by the one call and by the reference's steps: the same values,
    estimates and counts, to the bit, every pair taken by the one call; the counts."""
    statuses = _pair_statuses(monkeypatch)
    out = []
    for compiled in (True, False):
        monkeypatch.setattr(adaptive, "COMPILED_PAIR", compiled)
        st = {}
        out.append(ef.area_form_factors(scene, rows=rows, tolerance=tolerance, error=True,
                                        shortcuts=shortcuts, stats=st) + (st,))
    (F, E, st), (G, EG, sg) = out
    assert st == sg and st["occluded_pairs"] > 5
    assert len(statuses) == st["occluded_pairs"] and not any(statuses)
    assert np.array_equal(F, G) and np.array_equal(E, EG)
    return st


@pytest.mark.parametrize("name", ["gunter1.vs3", "box"])
def test_compiled_pair_leaves_out_the_reference_triangles(monkeypatch, name):
    # the triangles left unevaluated (points.unevaluated, the compiled drop_unevaluated)
    # wherever their share of the tolerance allows, however few (AREA_UNEVALUATED_LEAST
    # 0: 103 of gunter1's at 1e-6, 33 of the box's rows): the one call as the
    # reference's steps, to the bit
    monkeypatch.setattr(tol, "AREA_UNEVALUATED_LEAST", 0.0)
    scene, rows = ((ef.scenes.unit_squares_room(), range(0, 106, 9)) if name == "box"
                   else (ef.read_vs3(os.path.join(DATA, name)), None))
    st = _compiled_against_reference(monkeypatch, scene, rows, 1e-6, True)
    assert st["unevaluated_triangles"] >= 30, st["unevaluated_triangles"]


def test_compiled_pair_declines_what_the_reference_takes(monkeypatch):
    # an umbra to look for (AREA_UMBRA_MIN_LINES 0: every pair with an event) and too
    # many distinct lines (AREA_MAX_EVENT_LINES 1: the reference raises, naming the pair):
    # the one call declines (status 1, 2), the reference's steps give the values
    scene = ef.read_vs3(os.path.join(DATA, "test4.vs3"))
    statuses = _pair_statuses(monkeypatch)
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 0)
    out = []
    for compiled in (True, False):
        monkeypatch.setattr(adaptive, "COMPILED_PAIR", compiled)
        out.append(ef.area_form_factors(scene, tolerance=1e-6, error=True))
    assert statuses and set(statuses) == {1}
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
    statuses.clear()
    monkeypatch.setattr(tol, "AREA_UMBRA_MIN_LINES", 1000)
    monkeypatch.setattr(tol, "AREA_MAX_EVENT_LINES", 1)
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", True)
    with pytest.raises(NumericalError, match="distinct lines"):
        ef.area_form_factors(scene, tolerance=1e-6)
    assert statuses == [2]


def test_compiled_pair_of_many_sided_polygons_is_the_reference_to_the_bit(monkeypatch):
    # a 13-gon emitter and an 11-gon receiver (sums over more than 8 vertices: numpy's
    # pairwise sums and its reductions along the vertices) with a plate and a tilted
    # square between them, at 1e-6 and 1e-9: the one call and the steps alike, to the bit
    def ngon(k, r, z, up, tilt=0.0):
        t = 2 * np.pi * np.arange(k) / k + 0.1
        P = np.stack([r * np.cos(t) + 0.05, r * np.sin(t) - 0.03, z + tilt * np.cos(t)], axis=1)
        return P if up else P[::-1]

    scene = ef.Scene.from_polygons([ngon(13, 1.0, 0.0, True), ngon(11, 0.9, 2.0, False),
                                    ngon(4, 0.35, 1.0, True), ngon(4, 0.3, 1.4, False, 0.1)])
    statuses = _pair_statuses(monkeypatch)
    for tolerance in (1e-6, 1e-9):
        out = []
        for compiled in (True, False):
            monkeypatch.setattr(adaptive, "COMPILED_PAIR", compiled)
            out.append(ef.area_form_factors(scene, tolerance=tolerance, error=True))
        assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
    assert statuses and not any(statuses)


def test_pair_constants_never_read_half_stored(monkeypatch):
    # rows in threads (executor=ThreadPoolExecutor) ask for the pair's constants while
    # one of them builds them for changed tolerances: a thread switched to during that
    # build (here the build asks for them itself, as that thread would) gets constants
    # of the tolerances now set, never the old ones (nor, at first use, none: KeyError)
    old = compiled_pair.pair_constants()
    build, inner = compiled_pair._compiled_pair_constants, []

    def build_asking_again(*a):
        if not inner:
            inner.append(None)
            inner[0] = compiled_pair.pair_constants()
        return build(*a)

    monkeypatch.setattr(compiled_pair, "_compiled_pair_constants", build_asking_again)
    monkeypatch.setattr(tol, "AREA_HULL_RTOL", 2 * tol.AREA_HULL_RTOL)
    new = compiled_pair.pair_constants()
    assert inner and inner[0] is not old and new is not old
    assert compiled_pair.pair_constants() is new        # built once per change


def test_compiled_pair_declines_where_the_rules_miss_the_closed_form(monkeypatch):
    # the rules' integral of the unoccluded point values against the pair's closed form
    # (missed_U): given a closed form 1e-3 off (far beyond the rules' differences), the
    # one call declines (status 7) and the reference's steps check the triangles one by
    # one; given the pair's own, the one call takes every pair of test4
    calls, pair = [], adaptive._hidden_integral_in_one_call

    def record(*a):
        calls.append(a)
        return pair(*a)

    monkeypatch.setattr(adaptive, "_hidden_integral_in_one_call", record)
    ef.area_form_factors(ef.read_vs3(os.path.join(DATA, "test4.vs3")), tolerance=1e-6)
    monkeypatch.undo()
    assert len(calls) > 5
    for S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner in calls:
        off = (whole[0] + 1e-3, whole[1])
        assert compiled_pair.hidden_integral_in_one_call(
            S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner)[0] == 0
        assert compiled_pair.hidden_integral_in_one_call(
            S, Pc, Qc, nP, atol, area_P, off, shortcuts, solid, inner)[0] == 7
    S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner = calls[0]
    st = AreaStats()
    monkeypatch.setattr(adaptive, "COMPILED_PAIR", False)
    adaptive.occluded_pair(S, Pc, Qc, nP, atol, area_P, (whole[0] + 1e-3, whole[1]),
                           shortcuts, st, solid=solid, inner=inner)
    assert st.checked_triangles > 0


def _box_pair_with_solids():
    """A recorded occluded pair of the 106-surface box's row 0 whose blockers carry
    solids (the two cubes): ``(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid,
    inner)``."""
    calls, pair = [], adaptive._hidden_integral_in_one_call

    def record(*a):
        calls.append(a)
        return pair(*a)

    adaptive._hidden_integral_in_one_call = record
    try:
        ef.area_form_factors(ef.scenes.unit_squares_room(), rows=[0], tolerance=1e-6)
    finally:
        adaptive._hidden_integral_in_one_call = pair
    return next(a for a in calls if a[8] is not None and np.any(a[8] >= 0))


def test_compiled_pair_declines_a_blocker_in_the_receivers_plane_with_solids():
    # a triangle inside Qc and in its plane, added to a pair with solids: the one call
    # declines it (status 4: the reference's solids decide its events), and the
    # reference's value is the pair's without it within the two estimates (a blocker in
    # the receiver's plane hides nothing of it)
    S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner = _box_pair_with_solids()
    c = Qc.mean(axis=0)
    flat = c + 0.3 * (Qc[:3] - c)
    S2, solid2 = list(S) + [flat], np.append(solid, -1)
    inner2 = np.vstack([inner, np.full((1, 3), np.nan)])
    call = compiled_pair.hidden_integral_in_one_call
    assert call(S2, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid2, inner2)[0] == 4
    r = call(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner)
    assert r[0] == 0 and r[1] > 1e-3
    v, e, _ = adaptive._hidden_integral(S2, Pc, Qc, nP, atol, area_P, whole, shortcuts, None,
                                        solid2, inner2)
    assert abs(v - r[1]) <= e + r[2]


def test_compiled_pair_declines_where_a_points_image_is_not_to_be_trusted(monkeypatch):
    # with AREA_IMAGE_RTOL below 0, every image counts as moved beyond it: where what
    # that moves exceeds the pair's atol, the points go to the engine in the reference
    # (hidden.hidden_values), and the one call declines the pair (status 6) instead of
    # using those points' values
    S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner = _box_pair_with_solids()
    call = compiled_pair.hidden_integral_in_one_call
    assert call(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner)[0] == 0
    monkeypatch.setattr(tol, "AREA_IMAGE_RTOL", -1.0)
    assert call(S, Pc, Qc, nP, atol, area_P, whole, shortcuts, solid, inner)[0] == 6
