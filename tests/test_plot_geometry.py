"""The geometry drawings: the visible graph on the disk, the arcs' x-extremes (the ends
of Eq. 3's monotone spans), and the plot helpers that draw them."""

import matplotlib
import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

import exactff as ef
from exactff.kernel import arc_x_extremes
from exactff.visibility import visible_graph

matplotlib.use("Agg")


def _areas(graph, n):
    A = np.zeros(n)
    for j, piece in graph:
        A[j] += piece.area
    return A


@pytest.mark.parametrize("point, normal", [([278, 0.5, 279.6], [0, 1, 0]),
                                           ([100, 548.0, 450], [0, -1, 0]),
                                           ([0.5, 300, 200], [1, 0, 0])])
def test_visible_graph_tiles_the_disk_of_a_closed_room(point, normal):
    scene = ef.scenes.cornell_box(closed=True)
    graph = visible_graph(scene, point, normal, max_segment=0.01)
    import shapely
    union = shapely.union_all([g for _, g in graph])
    total = sum(g.area for _, g in graph)
    # pieces do not overlap and fill the disk, up to the chords' error: a shared edge is
    # cut into chords independently on its two sides (chord error here about 5e-5)
    assert abs(union.area - total) < 5e-6
    assert 0 < np.pi - total < 2e-4
    assert union.buffer(-1e-3).within(shapely.Point(0, 0).buffer(1.0, 256))


def test_visible_graph_areas_converge_to_the_exact_row():
    scene = ef.scenes.cornell_box(closed=True)
    p, n = np.array([278, 0.5, 279.6]), np.array([0, 1, 0])
    F = ef.form_factors(scene, p, n)
    errors = [np.abs(_areas(visible_graph(scene, p, n, max_segment=h), len(scene)) / np.pi
                     - F).max() for h in (0.08, 0.04, 0.02)]
    # chords inside arcs: the error shrinks as max_segment**2
    assert errors[0] > errors[1] > errors[2] > 0
    assert errors[0] / errors[2] > 10
    assert errors[2] < 5e-5


def test_visible_graph_of_one_polygon_against_the_kernel():
    # one polygon, nothing in front: the piece's area is the sector form's value
    rect = [[0, 0, 1], [0, 2, 1], [1, 2, 1], [1, 0, 1]]
    scene = ef.Scene.from_polygons([rect])
    A = _areas(visible_graph(scene, [0, 0, 0], [0, 0, 1], max_segment=0.002), 1)
    assert abs(A[0] / np.pi - 0.167375009914384) < 2e-6      # Howell's catalogue


def test_visible_graph_rejects_bad_arguments():
    scene = ef.scenes.cornell_box()
    with pytest.raises(ValueError, match="point"):
        visible_graph(scene, [np.nan, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="max_segment"):
        visible_graph(scene, [278, 1, 279], [0, 1, 0], max_segment=0)


def _sampled_turns(a, b, n=200001):
    """Interior extremes of x along the arc a -> b, found by dense sampling."""
    ua, ub = np.asarray(a, float) / np.linalg.norm(a), np.asarray(b, float) / np.linalg.norm(b)
    om = np.arctan2(np.linalg.norm(np.cross(ua, ub)), ua @ ub)
    s = np.linspace(0, 1, n)[:, None]
    d = (np.sin((1 - s) * om) * ua + np.sin(s * om) * ub) / np.sin(om)
    x = d[:, 0]
    k = np.flatnonzero((x[1:-1] - x[:-2]) * (x[2:] - x[1:-1]) < 0) + 1
    return d[k]


@settings(deadline=None)       # the profile's count (thorough: 1000)
@given(st.lists(st.floats(-1, 1), min_size=6, max_size=6))
def test_arc_x_extremes_against_sampling(c):
    a = np.array([c[0], c[1], abs(c[2]) + 0.05])
    b = np.array([c[3], c[4], abs(c[5]) + 0.05])
    m = np.cross(a, b)
    # an arc of (almost) zero length, or (almost) in the plane x = 0: no turn to sample
    assume(np.linalg.norm(m) >= 1e-3 * np.linalg.norm(a) * np.linalg.norm(b))
    assume(np.hypot(m[1], m[2]) >= 1e-3)
    w, w_perp, ta, theta, ts = arc_x_extremes(a, b)
    found = np.array([np.cos(t) * w + np.sin(t) * w_perp for t in ts]).reshape(-1, 3)
    sampled = _sampled_turns(a, b)
    # a turn within a sample's width of an end point may be missed by one or the other
    assert abs(len(found) - len(sampled)) <= 0 or min(ts[0] - ta, ta + theta - ts[-1]) < 1e-4
    if len(found) == len(sampled):
        assert np.allclose(found, sampled, rtol=0, atol=1e-4)
    # the start of the parametrisation is a
    assert np.allclose(np.cos(ta) * w + np.sin(ta) * w_perp, a / np.linalg.norm(a), rtol=0,
                       atol=1e-12)


def test_hemisphere_projection_draws_the_image_and_its_span_ends():
    from exactff import plot

    xy = np.array([[0.3, -0.5], [1.6, -0.2], [1.0, 0.9], [-0.9, 0.7]])
    polygon = np.c_[xy, 0.6 - 0.3 * xy[:, 0]][::-1]
    F = ef.point_polygon_form_factor([0, 0, 0], [0, 0, 1], polygon)
    ax = plot.hemisphere_projection([0, 0, 0], [0, 0, 1], polygon)
    assert ax.get_title() == f"projection onto the base: F = {F:.6g}"
    # the filled image has the polygon's image area: pi F (to the arcs' sampling)
    image = ax.patches[0].get_path().vertices
    x, y = image[:, 0], image[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert abs(area / np.pi - F) < 1e-3
    labels = [line.get_label() for line in ax.lines]
    assert "x-extremes" in labels and "vertices" in labels
    ax3 = plot.hemisphere_projection([0, 0, 0], [0, 0, 1], polygon, view="3d")
    assert ax3.name == "3d"
    with pytest.raises(ValueError, match="view"):
        plot.hemisphere_projection([0, 0, 0], [0, 0, 1], polygon, view="side")


def test_plot_visible_graph_draws_every_piece():
    import shapely
    from exactff import plot

    scene = ef.scenes.cornell_box(closed=True)
    p, n = [278, 0.5, 279.6], [0, 1, 0]
    parts = sum(len(shapely.get_parts(g)) for _, g in visible_graph(scene, p, n))
    ax = plot.visible_graph(scene, p, n, labels=True)
    assert len(ax.patches) == parts
    assert {t.get_text() for t in ax.texts} <= set(scene.names)
    assert "floor" not in {t.get_text() for t in ax.texts}     # the point is on the floor
