"""exactff.audit: another tool's matrix against the exact one. Planted defects are found
where they were planted; exact matrices (from another engine, another tolerance) audit
clean within their bounds."""

import json

import numpy as np
import pytest
import scipy.sparse as sp

import exactff as ef
from exactff.audits import CONFIGURATIONS, pair_configurations



def _howell_c11(a, b, c):
    """Howell C-11: parallel, directly opposed a x b rectangles c apart (mpmath, 40
    digits)."""
    import mpmath as mp

    with mp.workdps(40):
        X, Y = mp.mpf(a) / c, mp.mpf(b) / c
        sx, sy = mp.sqrt(1 + X * X), mp.sqrt(1 + Y * Y)
        return float(2 / (mp.pi * X * Y) * (
            mp.log(mp.sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)))
            + X * sy * mp.atan(X / sy) + Y * sx * mp.atan(Y / sx)
            - X * mp.atan(X) - Y * mp.atan(Y)))


def _howell_c14(w, h, l):
    """Howell C-14: rectangles w x l and h x l at 90 degrees sharing the edge l (mpmath,
    40 digits), from the w one."""
    import mpmath as mp

    with mp.workdps(40):
        W, H = mp.mpf(w) / l, mp.mpf(h) / l
        r = mp.sqrt(W * W + H * H)
        q = 1 + W * W + H * H
        log = mp.log((1 + W * W) * (1 + H * H) / q
                     * (W * W * q / ((1 + W * W) * r * r)) ** (W * W)
                     * (H * H * q / ((1 + H * H) * r * r)) ** (H * H))
        return float((W * mp.atan(1 / W) + H * mp.atan(1 / H) - r * mp.atan(1 / r)
                      + log / 4) / (mp.pi * W))


ADJACENT = _howell_c14(1, 1, 1)
FACING = _howell_c11(1, 1, 1)


def _sq(z, up):
    return [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]][::1 if up else -1]


PLATE = [[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]]


@pytest.fixture(scope="module")
def sandwich():
    """Unit squares two apart facing each other, a two-sided plate halfway between: the
    squares' pair is partly occluded."""
    scene = ef.Scene.from_polygons([_sq(0, True), _sq(2, False), PLATE, PLATE[::-1]])
    return scene, ef.area_form_factors(scene, tolerance=1e-10)


@pytest.fixture(scope="module")
def open_box():
    """box:2 without its ceiling: rows that do not sum to 1."""
    b = ef.scenes.subdivided_box(2)
    scene = ef.Scene.from_polygons(b.polygons[:4] + b.polygons[8:])
    return scene, ef.area_form_factors(scene, tolerance=1e-10)


def _shared_vertex_pairs(scene):
    """Pairs with two vertices in common (exact coordinates): the box's edge neighbours,
    found without the audit's collinear-overlap test."""
    sets = [{tuple(v) for v in p.tolist()} for p in scene.polygons]
    n = len(scene)
    M = np.zeros((n, n), bool)
    for i in range(n):
        for j in range(n):
            M[i, j] = i != j and len(sets[i] & sets[j]) >= 2
    return M


def test_audit_exact_values_vs_closed_form():
    box = ef.scenes.subdivided_box(1)
    rep = ef.audit(box, np.zeros((6, 6)), kind="area", tolerance=1e-9)
    # faces 0 (z = 0) and 1 (z = 1) face each other; 0 and 2 share an edge
    assert rep.exact[0, 1] == pytest.approx(FACING, abs=1e-10)
    assert rep.exact[0, 2] == pytest.approx(ADJACENT, abs=1e-10)
    assert np.all(rep.bound <= 1e-9)
    # every value is an error of the zero matrix, row sums off by 1 (closed box)
    assert rep.outside[~np.eye(6, dtype=bool)].all()
    assert rep.rows_off == list(range(6))
    np.testing.assert_allclose(rep.error, -rep.exact, rtol=0, atol=0)


def test_audit_exact_matrix_is_clean(sandwich):
    scene, F = sandwich
    rep = ef.audit(scene, F, kind="area", tolerance=1e-6)
    # computed at 1e-10, audited at 1e-6: every difference within the audit's bounds
    assert rep.clean, str(rep)
    assert np.all(np.abs(rep.error) <= rep.slack)
    assert rep.rows_off == [] and rep.pairs_off == [] and not rep.outside.any()
    assert rep.exact[0, 1] == pytest.approx(0.0314026942480, abs=1e-6)   # area doctest's


def test_audit_point_rows_of_the_python_engine_are_clean():
    # the compiled engine's exact rows audited against the Python/GEOS engine's
    scene = ef.scenes.cornell_box()
    n = len(scene)
    M, E = ef.form_factors(scene, scene.centroids, scene.normals, error=True,
                           method=ef.Exact(engine="python"))
    # the engines may differ by a few roundoffs: within the two bounds
    rep = ef.audit(scene, M, kind="point", other_bound=E)
    assert rep.clean, str(rep)
    assert 0 < np.abs(rep.error).max() <= 1e-15 and rep.exact.shape == (n, n)
    assert rep.breakdown()["partly_occluded"]["pairs"] > 0


def test_audit_finds_a_constant_on_edge_neighbours():
    box = ef.scenes.subdivided_box(2)
    F = ef.area_form_factors(box, tolerance=1e-10)
    edge = _shared_vertex_pairs(box)
    conf, _ = pair_configurations(box)
    assert np.array_equal(conf["edge_sharing"], edge)
    assert not conf["partly_occluded"].any()          # no exact values given
    # OpenFOAM's viewFactorsGen defect: +0.00965 on every edge neighbour
    rep = ef.audit(box, F + 0.00965 * edge, kind="area", tolerance=1e-9)
    assert not rep.clean
    assert np.array_equal(rep.outside, edge)
    b = rep.breakdown()
    assert b["edge_sharing"]["mean_error"] == pytest.approx(0.00965, abs=1e-12)
    assert b["edge_sharing"]["outside"] == b["edge_sharing"]["pairs"] == int(edge.sum())
    assert b["other"]["outside"] == 0 and b["other"]["max_abs_error"] < 1e-12
    assert b["edge_sharing"]["share"] == pytest.approx(1.0, abs=1e-9)
    assert b["partly_occluded"]["pairs"] == 0         # a convex enclosure
    i, j, other, exact, error = rep.worst(1)[0]
    assert edge[i, j] and error == pytest.approx(0.00965, abs=1e-12)


def test_audit_finds_a_pair_given_binary_visibility(sandwich):
    scene, F = sandwich
    G = F.copy()
    # a ray caster with one ray per pair calls the pair wholly visible (its unoccluded
    # value, in closed form) or wholly hidden
    unoccluded = ef.polygon_form_factor(scene.polygons[0], scene.polygons[1])
    assert unoccluded > F[0, 1] + 0.02
    G[0, 1] = unoccluded
    rep = ef.audit(scene, G, kind="area", tolerance=1e-7)
    # the squares' pair is the one partly occluded (the plate's faces see the squares
    # whole); nothing grazes; the plate's two faces share their edges
    occluded = rep.configurations["partly_occluded"]
    assert list(zip(*np.nonzero(occluded))) == [(0, 1), (1, 0)]
    assert not rep.configurations["grazing"].any()
    assert list(zip(*np.nonzero(rep.configurations["edge_sharing"]))) == [(2, 3), (3, 2)]
    assert rep.worst(1)[0][:2] == (0, 1)
    assert rep.worst(1)[0][4] == pytest.approx(unoccluded - F[0, 1], abs=1e-7)
    assert list(zip(*np.nonzero(rep.outside))) == [(0, 1)]
    assert rep.pairs_off == [(0, 1)] and rep.rows_off == [0]
    assert rep.breakdown()["partly_occluded"]["outside"] == 1
    G[0, 1] = 0.0                                        # the other verdict: hidden
    assert ef.audit(scene, G, kind="area", tolerance=1e-7).worst(1)[0][:2] == (0, 1)


def test_audit_finds_a_normalised_row(open_box):
    scene, F = open_box
    G = F.copy()
    G[5] /= G[5].sum()          # an open box's row made to sum to 1
    rep = ef.audit(scene, G, kind="area", tolerance=1e-8)
    assert rep.rows_off == [5]
    rows, _ = np.nonzero(rep.outside)
    assert set(rows.tolist()) == {5}
    o, e, _ = rep.row_sums
    assert o[5] == pytest.approx(1.0, abs=1e-14) and e[5] == pytest.approx(F[5].sum(), abs=1e-8)
    assert ef.audit(scene, F, kind="area", tolerance=1e-8).clean


def test_audit_reports_an_entry_left_out(open_box):
    scene, F = open_box
    S = sp.csr_array(F)
    S.eliminate_zeros()
    # nothing left out but exact zeros: clean, no mass missing
    rep = ef.audit(scene, S, kind="area", tolerance=1e-8)
    assert rep.clean and rep.missing_mass.sum() == 0
    # leave out the largest entry of row 3
    j = int(np.argmax(F[3]))
    D = S.toarray()
    mask = D != 0
    mask[3, j] = False
    rows, cols = np.nonzero(mask)
    T = sp.csr_array((D[rows, cols], (rows, cols)), shape=D.shape)
    rep = ef.audit(scene, T, kind="area", tolerance=1e-8)
    assert list(zip(*np.nonzero(rep.missing))) == [(3, j)]
    assert rep.missing_mass[3] == pytest.approx(F[3, j], abs=1e-8)
    assert rep.missing_mass.sum() == pytest.approx(F[3, j], abs=1e-8)
    assert rep.rows_off == [3] and rep.pairs_off == [(min(3, j), max(3, j))]
    d = rep.to_dict()
    assert d["missing"]["entries"] == 1 and d["missing"]["largest"][0][:2] == [3, j]


def test_audit_point_rows_from_given_points():
    box = ef.scenes.subdivided_box(2)
    P = np.array(box.centroids)
    P[0] = [0.5, 0.5, 0.0]           # the floor's centre, a corner of floor quad 0
    F = ef.form_factor_matrix(box)
    rep = ef.audit(box, F, kind="point", points=P)
    # from the floor's centre the ceiling's four quads take 4 F(corner of a 0.5 x 0.5
    # rectangle at height 1) (form_factors' doctest)
    assert rep.exact[0, 4:8].sum() == pytest.approx(0.2394564705, abs=1e-10)
    assert rep.rows_off == []        # both row 0s sum to 1: a closed box
    assert set(np.nonzero(rep.outside)[0].tolist()) == {0}
    assert ef.audit(box, F, kind="point").clean


def test_audit_worst_and_dict():
    box = ef.scenes.subdivided_box(1)
    F = ef.area_form_factors(box)
    G = F.copy()
    G[0, 1] += 0.03
    G[2, 3] -= 0.05
    G[4, 0] += 0.01
    rep = ef.audit(box, G)
    w = rep.worst(3)
    assert [(i, j) for i, j, *_ in w] == [(2, 3), (0, 1), (4, 0)]
    for i, j, other, exact, error in w:
        assert other == G[i, j] and exact == rep.exact[i, j] and error == other - exact
        assert all(isinstance(v, float) for v in (other, exact, error))
    d = rep.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text)["worst"][0]["i"] == 2
    assert set(d["breakdown"]) == set(CONFIGURATIONS) | {"other"}
    assert "other" not in d and "other" in rep.to_dict(matrices=True)
    assert "verdict" in str(rep)


def test_audit_refuses_bad_input():
    box = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match=r"F_other: expected shape \(6, 6\)"):
        ef.audit(box, np.zeros((5, 5)))
    with pytest.raises(ValueError, match="F_other: NaN"):
        ef.audit(box, np.full((6, 6), np.nan))
    with pytest.raises(ValueError, match="kind must be one of"):
        ef.audit(box, np.zeros((6, 6)), kind="areas")
    with pytest.raises(ValueError, match="points="):
        ef.audit(box, np.zeros((6, 6)), points=box.centroids)
    with pytest.raises(ValueError, match="points must have shape"):
        ef.audit(box, np.zeros((6, 6)), kind="point", points=np.zeros((5, 3)))
    with pytest.raises(ValueError, match="tolerance"):
        ef.audit(box, np.zeros((6, 6)), tolerance=-1.0)


def test_cli_audit_writes_json_csv_and_figures(tmp_path, capsys):
    from exactff.cli import main

    box = ef.scenes.subdivided_box(2)
    F = ef.area_form_factors(box, tolerance=1e-10)
    F[3, 9] += 0.02
    np.save(tmp_path / "m.npy", F)
    out = tmp_path / "out"
    assert main(["audit", "box:2", str(tmp_path / "m.npy"), "--area", "--out", str(out),
                 "--no-progress", "--worst", "3"]) == 0
    text = capsys.readouterr().out
    assert "3 -> 9" in text and "differs" in text
    doc = json.loads((out / "audit.json").read_text())
    assert doc["kind"] == "area" and doc["clean"] is False and doc["polygons"] == 24
    assert doc["worst"][0]["i"] == 3 and doc["worst"][0]["j"] == 9
    assert doc["worst"][0]["error"] == pytest.approx(0.02, abs=1e-9)
    assert doc["entries_outside"] == 1 and doc["rows_off"] == [3]
    lines = (out / "worst.csv").read_text().splitlines()
    assert lines[0].startswith("i,j,from,to") and len(lines) == 4
    assert lines[1].startswith("3,9,")
    for name in ("error_vs_distance.png", "relative_errors.png", "row_errors.png"):
        assert (out / name).stat().st_size > 0
    # a second run resumes the exact values from OUT
    assert main(["audit", "box:2", str(tmp_path / "m.npy"), "--out", str(out),
                 "--no-progress"]) == 0


def test_cli_audit_without_matplotlib(tmp_path, capsys, monkeypatch):
    import sys

    from exactff.cli import main

    box = ef.scenes.subdivided_box(1)
    np.save(tmp_path / "m.npy", ef.form_factor_matrix(box))
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert main(["audit", "box:1", str(tmp_path / "m.npy"), "--centroids", "--out",
                 str(tmp_path / "o"), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "figures: not drawn" in text and "clean" in text
    assert sorted(p.name for p in (tmp_path / "o").glob("*.png")) == []
    assert json.loads((tmp_path / "o" / "audit.json").read_text())["clean"] is True


def test_cli_audit_refuses_a_matrix_of_another_scene(tmp_path, capsys):
    from exactff.cli import main

    np.save(tmp_path / "m.npy", np.zeros((5, 5)))
    assert main(["audit", "box:1", str(tmp_path / "m.npy"), "--out", str(tmp_path / "o")]) == 2
    assert "5 surfaces, but the scene has 6 polygons" in capsys.readouterr().err


def test_audit_relative_error_and_workers():
    box = ef.scenes.subdivided_box(2)
    F = ef.area_form_factors(box)
    G = F.copy()
    G[0, 1] = 0.5                     # coplanar neighbours: exact 0
    G[0, 8] *= 1.25
    rep = ef.audit(box, G, jobs=2)    # the exact values in two worker processes
    serial = ef.audit(box, G)
    assert np.array_equal(rep.exact, serial.exact) and np.array_equal(rep.bound, serial.bound)
    rel = rep.relative_error
    assert rel[0, 1] == np.inf and rel[0, 2] == 0.0      # 0.5 / 0, and 0 / 0
    assert rel[0, 8] == pytest.approx(0.25, abs=1e-12)
    assert rep.to_dict()["worst"][0]["relative_error"] == "inf"


def test_cli_audit_point_rows_from_a_points_file(tmp_path, capsys):
    from exactff.cli import main

    box = ef.scenes.subdivided_box(1)
    P = np.array(box.centroids) + 0.1 * np.array([[1, 1, 0], [1, 1, 0], [0, 1, 1],
                                                  [0, 1, 1], [1, 0, 1], [1, 0, 1]])
    np.savetxt(tmp_path / "p.txt", P)
    F = ef.form_factors(box, P, box.normals)
    np.save(tmp_path / "m.npy", F)
    assert main(["audit", "box:1", str(tmp_path / "m.npy"), "--points", str(tmp_path / "p.txt"),
                 "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    doc = json.loads((tmp_path / "o" / "audit.json").read_text())
    assert doc["kind"] == "point" and doc["clean"] is True
    # the same matrix against the centroids' rows: every row differs
    assert main(["audit", "box:1", str(tmp_path / "m.npy"), "--centroids",
                 "--out", str(tmp_path / "c"), "--no-progress"]) == 0
    doc = json.loads((tmp_path / "c" / "audit.json").read_text())
    assert doc["clean"] is False and doc["rows"]["max_abs_error"][0] > 1e-3
    capsys.readouterr()


def test_pair_configurations_of_boxes_and_far_squares():
    box = ef.scenes.subdivided_box(1)
    conf, sep = pair_configurations(box)
    # faces 0 and 1 are opposite: centroids 1 apart, circumradius sqrt(2) / 2
    assert sep[0, 1] == pytest.approx(np.sqrt(2), rel=1e-15)
    assert conf["near"][0, 1] and not conf["grazing"][0, 1] and not conf["edge_sharing"][0, 1]
    # faces 0 and 2 meet at an edge: each reaches the other's plane
    assert conf["edge_sharing"][0, 2] and conf["grazing"][0, 2]
    far = ef.Scene.from_polygons([_sq(0, True), _sq(10, False)])
    conf, sep = pair_configurations(far)
    assert sep[0, 1] == pytest.approx(10 / (np.sqrt(2) / 2), rel=1e-15)
    assert not any(conf[c].any() for c in CONFIGURATIONS)
    # a square tilted so that a corner dips 1 % of its size below the other's plane
    tilted = ef.Scene.from_polygons([_sq(0, True), [[3, 0, -0.01], [3, 1, -0.01], [3, 1, 1],
                                                    [3, 0, 1]][::-1]])
    conf, _ = pair_configurations(tilted)
    assert conf["grazing"][0, 1] and conf["grazing"][1, 0] and not conf["near"][0, 1]
