"""The compiled core's tiles (issue 48): the grid of planes through the point that the
shadow tree starts from is cut at once only into coarse blocks (fewer than
``SVBSP_TILES_EAGER`` planes along each axis), and a block is cut further only where a
visible piece arriving in it lies clearly on one side of its middle plane, or is seen
from nearly in its own plane (``Core::grow_tile``, ``stats["tiles_cut"]``). The planes
chosen never change what is visible, only how pieces are cut: values are checked
against the Python engine, the constructions of ``exact_visibility`` and the rows
without tiles, and the blocks against the grid's cells (one small piece in each cuts
every block down to its cells, no more and no less)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hst

import exactff as ef
from exactff import _tolerances as tol
from exactff.visibility import compiled, compiled_core

from common import examples, rect_xy
from exact_visibility import unoccluded_form_factor
from test_compiled import COMPILED, assert_engines_agree


def _grid(n, z, lo=-2.0, hi=2.0, skip=()):
    edges = np.linspace(lo, hi, n + 1)
    return [rect_xy(x0, x1, y0, y1, z) for i, (x0, x1) in enumerate(zip(edges[:-1], edges[1:]))
            for j, (y0, y1) in enumerate(zip(edges[:-1], edges[1:])) if (i, j) not in skip]


def test_a_large_polygon_over_the_point_stays_one_piece():
    # a square over the point fills most of the hemisphere: its image lies across the
    # middle planes of the grid's blocks, so no block is cut for it and it is one
    # visible piece (a grid cut at once, 7 planes along each axis, cut it into 64); a
    # square behind it is hidden
    scene = ef.Scene.from_polygons([rect_xy(-3, 3, -3, 3, 1.0), rect_xy(-1, 1, -1, 1, 2.0)])
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    assert compiled._shadow_tiles(len(scene)) < tol.SVBSP_TILES_EAGER   # all cut where needed
    st = {}
    F, E = COMPILED.point_form_factors(scene, p, n, error=True, stats=st)
    assert st["visible_pieces"] == 1 and st["tiles_cut"] == 0, st
    assert abs(F[0] - float(unoccluded_form_factor(scene, p, n, 0))) <= E[0] and F[1] == 0


def test_small_pieces_cut_the_blocks_they_lie_in():
    # a near square over the point (its shadow takes the whole grid) and, around and
    # behind it, a floor of small tiles seen past its edges: the small pieces land in
    # the square's free leaves, which are the grid's block, and cut it there. Values
    # against the Python engine (and rationals where the two bounds part)
    near = [rect_xy(-0.5, 0.5, -0.5, 0.5, 1.0)]
    scene = ef.Scene.from_polygons(near + _grid(24, 2.0, -6.0, 6.0))
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    st = assert_engines_agree(scene, p, n)
    stats = {}
    F = COMPILED.point_form_factors(scene, p, n, stats=stats)
    assert stats["tiles_cut"] > 0, stats
    # the tiles the square hides (images within its own) are 0, those past it are seen
    c = scene.centroids[1:]
    hidden = (np.abs(c[:, 0] - 0.01) < 0.4) & (np.abs(c[:, 1] - 0.02) < 0.4)
    assert np.all(F[1:][hidden] == 0) and np.all(F[1:][~hidden & (np.abs(c[:, 0]) > 2)] > 0)


@settings(deadline=None)
@given(tiles=hst.integers(0, 63), z=hst.floats(1.5, 4.0),
       gaps=hst.sets(hst.tuples(hst.integers(0, 7), hst.integers(0, 7)), max_size=12))
def test_the_grid_changes_no_value_beyond_the_bounds(tiles, z, gaps):
    # a screen of 8 x 8 squares with gaps over a floor of 16 x 16: every value with any
    # number of tiles (below SVBSP_TILES_EAGER all cut where pieces need it, above it
    # cut at once into blocks first) within the two bounds of the row without tiles
    scene = ef.Scene.from_polygons(_grid(8, 1.0, skip=gaps) + _grid(16, z, -3.0, 3.0))
    p, n = np.array([0.013, -0.021, 0.0]), np.array([0, 0, 1.0])
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(compiled, "_shadow_tiles", lambda n: 0)
        F0, E0 = COMPILED.point_form_factors(scene, p, n, error=True)
        mp.setattr(compiled, "_shadow_tiles", lambda n: tiles)
        F, E = COMPILED.point_form_factors(scene, p, n, error=True)
    assert np.all(np.abs(F - F0) <= E + E0)


def test_the_core_refuses_more_tiles_than_a_block_holds():
    scene = ef.scenes.cornell_box()
    tree, core = compiled_core(scene)
    side = np.ones(len(scene), dtype=np.int8)
    with pytest.raises(ValueError, match="tiles"):
        core.row(np.zeros(3), np.array([0, 0, 1.0]), np.zeros(len(tree), np.int8), side,
                 False, True, 8, 64, 0.0, 0.0)


def _frame(n):
    # the core's frame about n (Core::tile_normals)
    n = np.asarray(n, float) / np.linalg.norm(n)
    e = np.zeros(3)
    e[int(np.argmin(np.abs(n)))] = 1
    u = np.cross(e, n)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u), n


def _cell_squares(n, tiles, scale=0.25):
    # a small square facing the point in every cell of the grid about n (planes
    # cos t w - sin t n, t evenly spaced in angle), well inside its cell
    u, v, n = _frame(n)
    t = -np.pi / 2 + np.pi * np.arange(tiles + 2) / (tiles + 1)   # the planes and both ends
    squares = []
    for i in range(tiles + 1):
        for j in range(tiles + 1):
            a, b = (t[i] + t[i + 1]) / 2, (t[j] + t[j + 1]) / 2
            d = np.cross(np.cos(a) * u - np.sin(a) * n, np.cos(b) * v - np.sin(b) * n)
            d /= np.linalg.norm(d) * np.sign(d @ n)
            # its angular room: the angle to the nearest of the cell's four planes
            room = min(abs(np.arcsin((np.cos(s) * w - np.sin(s) * n) @ d))
                       for w, ends in ((u, t[i:i + 2]), (v, t[j:j + 2])) for s in ends
                       if abs(s) < np.pi / 2)
            r = scale * np.tan(room)
            e1 = np.cross(d, u if abs(d @ u) < 0.9 else v)
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(d, e1)   # (e1, e2, d) right-handed: the square faces -d
            squares.append([d + r * (x * e1 + y * e2)
                            for x, y in ((-1, -1), (-1, 1), (1, 1), (1, -1))])
    return squares


def _blocks(k):
    # the coarse blocks Core::cut_tiles leaves along an axis of k planes
    return 1 if k < tol.SVBSP_TILES_EAGER else _blocks(k // 2) + _blocks(k - k // 2 - 1)


@pytest.mark.parametrize("tiles", [1, 4, 7, 9, 10, 13, 21, 40, 63])
def test_one_small_piece_a_cell_cuts_the_grid_into_its_cells(tiles):
    # (tiles + 1)^2 small squares, one well inside each cell: each block is cut until
    # each of its cells is a leaf of its own, and no further (the tree's nodes: one
    # less than its leaves). A block whose halves were not the planes on each side of
    # its middle one (tile_plane) or whose code lost a bit (tile_leaf) leaves some
    # cells together or cuts more
    p, n = np.array([0.01, 0.02, 0.0]), np.array([0, 0, 1.0])
    scene = ef.Scene.from_polygons([p + np.array(q) for q in _cell_squares(n, tiles)])
    st = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(compiled, "_shadow_tiles", lambda m: tiles)
        F = compiled.compiled_form_factors(scene, p, n, two_sided=True, stats=st,
                                             shortcuts=False)   # (no unoccluded path)
    assert np.all(F > 0), st
    assert st["tiles_cut"] == (tiles + 1) ** 2 - _blocks(tiles) ** 2, st


@pytest.mark.parametrize("tiles", [4, 7, 13, 63])
def test_the_sphere_cuts_the_grid_below_the_horizon_into_its_cells(tiles):
    # the same below the horizon in a sphere row (the grid about -n, Core::run): the
    # blocks below are cut along their own planes
    p = np.array([0.01, 0.02, 0.0])
    up = _cell_squares([0, 0, 1.0], tiles)
    down = _cell_squares([0, 0, -1.0], tiles)
    scene = ef.Scene.from_polygons([p + np.array(q) for q in up + down])
    st = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(compiled, "_shadow_tiles", lambda m: tiles)
        W, _ = compiled.compiled_solid_angles(scene, p, stats=st)
    assert np.all(W > 0), st
    assert st["tiles_cut"] == 2 * ((tiles + 1) ** 2 - _blocks(tiles) ** 2), st


def _screens_and_floors(gaps, z):
    # above the point and below it: a screen of 8 x 8 squares with gaps (their own for
    # each side) in front of a floor of 16 x 16
    return ef.Scene.from_polygons(
        [q for s in (1, -1) for q in
         _grid(8, s * 1.0, -2.0, 2.0, {(i, j) for i, j, up in gaps if up == (s > 0)})
         + _grid(16, s * z, -3.0, 3.0)])


SCREENS = dict(tiles=hst.integers(0, 63), z=hst.floats(1.5, 4.0),
               gaps=hst.sets(hst.tuples(hst.integers(0, 7), hst.integers(0, 7), hst.booleans()),
                             max_size=24))


@settings(deadline=None, max_examples=examples(40))
@given(**SCREENS)
def test_the_sphere_grid_changes_no_value_beyond_the_bounds(tiles, z, gaps):
    # sphere rows (both grids, above and below the horizon): every value with any number
    # of tiles within the two bounds of the row without tiles
    scene = _screens_and_floors(gaps, z)
    p = np.array([0.013, -0.021, 0.0])
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(compiled, "_shadow_tiles", lambda m: 0)
        W0, E0 = compiled.compiled_solid_angles(scene, p)
        mp.setattr(compiled, "_shadow_tiles", lambda m: tiles)
        W, E = compiled.compiled_solid_angles(scene, p)
    assert np.all(np.abs(W - W0) <= E + E0)


@settings(deadline=None, max_examples=examples(40))
@given(**SCREENS)
def test_two_sided_rows_with_any_grid_within_the_bounds(tiles, z, gaps):
    # a two-sided row, tilted (the screens' backs below receive too): within the bounds
    # of the row without tiles
    scene = _screens_and_floors(gaps, z)
    p, n = np.array([0.013, -0.021, 0.0]), np.array([0.3, 0.2, 1.0])
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(compiled, "_shadow_tiles", lambda m: 0)
        F0, E0 = COMPILED.point_form_factors(scene, p, n, two_sided=True, error=True)
        mp.setattr(compiled, "_shadow_tiles", lambda m: tiles)
        F, E = COMPILED.point_form_factors(scene, p, n, two_sided=True, error=True)
    assert np.all(np.abs(F - F0) <= E + E0)
