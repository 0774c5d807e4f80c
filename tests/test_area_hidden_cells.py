"""The hidden regions' blockers settled once for a cell's points (``_core/hidden.cpp``,
Hints): a blocker whose part in the pyramid lies in the cone over the first blocker
projected (the hint) is left out, decided for a whole cell where the cell's box of points
settles it, else point by point; either way the same exact decision."""

import numpy as np
import pytest

import exactff as ef


def _plate(x1, z):
    """A plate at height z over x <= x1, wider than the receiver's view in y, facing up."""
    return np.array([[-1, -1, z], [x1, -1, z], [x1, 2, z], [-1, 2, z]], float)


# The unit receiver Q at z = 2 facing down, seen from points (px, 0.5, 0) of the floor
# (normal +z) over two plates: A at z = 1 to x = 0.5, B at z = 1.5 to x = 0.55. A's edge
# shades Q beyond x = 1 - px, B's beyond x = 0.7333 - px / 3: B's image lies in A's for
# px < 0.4 (B inside A's cone where it meets the pyramid: left out) and reaches past it
# for px > 0.4 (a strip of B's own, 0.067 wide at px = 0.5).
_Q = np.array([[0, 0, 2], [0, 1, 2], [1, 1, 2], [1, 0, 2]], float)
_BLOCKERS = [_plate(0.5, 1.0), _plate(0.55, 1.5)]
_NP = np.array([0.0, 0.0, 1.0])


def _points(lo, hi, k=12):
    x = np.linspace(lo, hi, k)
    return np.column_stack([x, 0.5 + 0.01 * np.sin(7 * x), np.zeros(k)])


@pytest.mark.parametrize("span", [(0.2, 0.35), (0.3, 0.5), (0.45, 0.6)])
def test_a_cell_settles_the_blockers_as_its_points_do(monkeypatch, span):
    # a cell of points where B is inside A's cone at every point, at some and not
    # others (the box does not settle it: each point is decided alone), and at none:
    # the hidden parts with the points taken as one cell are those point by point, to
    # the bit, and both are the engine's (F(x -> Q) less the occluded value) within the
    # estimates; a cell settled from its first point alone (its box not taken) would
    # leave B's strip out past px = 0.4 on the second span
    from exactff.area import hidden as area
    from exactff.area.points import point_values

    X = _points(*span)
    H, EH = area.hidden_values(X, _NP, _Q, _BLOCKERS)
    build = area.hidden_pieces

    def one_cell(*args, **kwargs):
        return build(*args, **kwargs, cells=np.zeros(len(args[0]), dtype=np.int64))

    monkeypatch.setattr(area, "hidden_pieces", one_cell)
    G, EG = area.hidden_values(X, _NP, _Q, _BLOCKERS)
    monkeypatch.undo()
    assert np.array_equal(G, H) and np.array_equal(EG, EH)
    F, E = ef.form_factors(ef.Scene.from_polygons([_Q] + _BLOCKERS), X, _NP, error=True)
    U, EU = (v[0] for v in point_values(X, _NP, [_Q]))
    assert np.all(np.abs(G - (U - F[:, 0])) <= EG + EU + E[:, 0] + 1e-16)
    assert np.all(EG <= 1e-12)
    # (B's strip, where it adds to A's image, is not nothing)
    if span[1] > 0.45:
        only_a = area.hidden_values(X, _NP, _Q, _BLOCKERS[:1])[0]
        assert (G - only_a).max() > 1e-3


def test_cells_are_one_per_point():
    from exactff.area import hidden as area

    setup = area.hidden_setup(_Q, _BLOCKERS)
    nQ, q0, RQ, _, corners, parts, part_counts, V, counts, NK, group, *_, extent, _ = setup
    X = _points(0.2, 0.4)
    with pytest.raises(ValueError, match="one cell per point"):
        area.hidden_pieces(X, corners, q0, nQ, RQ[:2], V, counts, NK, group, 0.0, 0.0, 4.0,
                           4.0, 64, 1e-9, extent, parts, part_counts, np.eye(3), 1.0, 1.0,
                           2.0 ** -52, False, precise_atol=0.0, cells=np.zeros(3, np.int64))


def _hidden_outputs(X, Q, blockers, cells=None):
    """hidden_pieces' per-point outputs (lost, reach, length, box, moved, dropped, hidden,
    rounding) with the area code's constants, the blockers as given (checked unchanged by
    the set-up) and, with ``cells``, one cell per value."""
    from exactff import _tolerances as tol
    from exactff.area import hidden as area
    from exactff.geometry import receiver_frame

    setup = area.hidden_setup(Q, blockers)
    nQ, q0, RQ, _, corners, parts, part_counts, V, counts, NK, group, lo, hi, extent, _ = setup
    for k, K in enumerate(blockers):
        assert np.array_equal(V[k, :len(K)], K)
    size = float((np.maximum(hi, X.max(axis=0)) - np.minimum(lo, X.min(axis=0))).max())
    out = area.hidden_pieces(
        X, corners, q0, nQ, RQ[:2], V, counts, NK, group, tol.AREA_BACK_FACE_RTOL * size,
        tol.AREA_EDGE_ON_RTOL * size, tol.AREA_IMAGE_ULPS, tol.AREA_SLIVER_ULPS,
        tol.AREA_MAX_PIECES, tol.AREA_IMAGE_PRECISE_RTOL, extent, parts, part_counts,
        receiver_frame(_NP), tol.C1, tol.C2, tol.EPS, False, precise_atol=0.0,
        **({} if cells is None else {"cells": cells}))
    return [np.asarray(v) for v in out[3:11]]


def test_a_vertex_outside_by_less_than_rounding_is_outside():
    # the hint A (a triangle at z = 1 whose edge a -> b runs along y ~ x, its ends 12.6
    # from the points' region) and a triangle C under it whose vertex c lies on the
    # hint's side of that edge in the doubles' evaluation of the cell's side
    # (b - a) x (c - a) but strictly outside it exactly (the three in z = 1: the side is
    # that 2-D orientation at every point of the emitter's plane z = 0). Only the rounding
    # margin of the cell's test (and of each point's before its exact predicate) keeps C
    # from being left out. C outside A's cone is projected: the outputs are those with C
    # tried first (the hint then, nothing to settle), one call per point; left out they
    # would be those without C (C's vertices near the points move more than A's: the
    # estimate's terms differ)
    from fractions import Fraction

    a = (-12.60505625382985, -12.604379803586038, 1.0)
    b = (12.637996580788332, 12.6381473688075, 1.0)
    c = (0.5, 0.5004035500890797, 1.0)
    A = np.array([a, b, (-14.0, 14.0, 1.0)])
    C = np.array([c, (0.45, 0.6, 1.0), (0.297, 0.305, 0.01)])

    def side(x, exact):
        f = Fraction if exact else float
        e = [f(b[i]) - f(a[i]) for i in range(2)]
        d = [f(x[i]) - f(a[i]) for i in range(2)]
        return e[0] * d[1] - e[1] * d[0]

    inside = np.sign(side(A[2], True))
    assert np.sign(side(c, False)) == inside and np.sign(side(c, True)) == -inside
    k = np.arange(12)
    X = np.column_stack([0.3 + 0.002 * np.sin(k), 0.3 + 0.002 * np.cos(k), np.zeros(12)])
    cell = _hidden_outputs(X, _Q, [A, C], cells=np.zeros(12, np.int64))
    points = _hidden_outputs(X, _Q, [A, C])
    first = [np.concatenate(v) for v in zip(*(_hidden_outputs(X[i:i + 1], _Q, [C, A])
                                                for i in range(12)))]
    without = [np.concatenate(v) for v in zip(*(_hidden_outputs(X[i:i + 1], _Q, [A])
                                                  for i in range(12)))]
    for got in (cell, points):
        assert all(np.array_equal(g, f) for g, f in zip(got, first))
    # (C's own terms are in them: moved, the slivers dropped and their box)
    assert not all(np.array_equal(w, f) for w, f in zip(without, first))
