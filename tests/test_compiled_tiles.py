"""The compiled core's tiles (issue 48): the grid of planes through the point that the
shadow tree starts from is cut at once only into coarse blocks (fewer than
``SVBSP_TILES_EAGER`` planes along each axis), and a block is cut further only where a
visible piece arriving in it lies clearly on one side of its middle plane
(``Core::grow_tile``, ``stats["tiles_cut"]``). The planes chosen never change what is
visible, only how pieces are cut: values are checked against the Python engine and
the constructions of ``exact_visibility``, and the grid's finer planes against
pieces left whole."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as hst

import exactff as ef
from exactff import _tolerances as tol
from exactff.visibility import compiled
from exactff.visibility import compiled_core

from common import rect_xy
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
