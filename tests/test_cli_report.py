"""The command line's remainder (ff and matrix --remainder) and the report written
beside every matrix (STEM.report.json)."""

import json

import numpy as np

import exactff as ef
from exactff.cli import main


def front_halves(scene, y0):
    """The open Cornell box closed by its front wall (z = 0; ``cornell_box(closed=True)``'s
    last polygon) cut at the height y0, and the indices of the part below and above
    (None for an empty part, where y0 is at the wall's bottom or top)."""
    front = ef.scenes.cornell_box(closed=True).polygons[-1]
    (x0, b), (x1, _), (x2, top), (x3, _) = front[0, :2], front[1, :2], front[2, :2], front[3, :2]
    assert x0 == x3 == b == 0 and front[1, 1] == 0 and front[3, 1] == top
    xr = x1 + (x2 - x1) * y0 / top                  # the right edge at y0
    below = [[0, 0, 0], [x1, 0, 0], [xr, y0, 0], [0, y0, 0]] if y0 > 0 else None
    above = [[0, y0, 0], [xr, y0, 0], [x2, top, 0], [0, top, 0]] if y0 < top else None
    parts = [P for P in (below, above) if P is not None]
    k = len(scene)
    return (ef.Scene.from_polygons(list(scene.polygons) + parts),
            k if below is not None else None, k + len(parts) - 1 if above is not None else None)


def test_ff_remainder_prints_sky_and_ground(capsys):
    """The Cornell box is open at the front: from the floor, part of it is sky (nothing below:
    no ground); the printed values are the API's, and they close the row to 1."""
    scene = ef.scenes.cornell_box()
    p, n = scene.centroids[1], scene.normals[1]      # the floor: the open front is sky
    args = ["ff", "cornell_box", "--point", *map(repr, p.tolist()),
            "--normal", *map(repr, n.tolist()), "--remainder", "--up", "0", "1", "0"]
    assert main(args) == 0
    out = capsys.readouterr().out
    F, sky, ground = ef.form_factors(scene, p, n, remainder=True, up=(0, 1, 0))
    assert f"sky                      {sky:.15f}" in out
    assert f"ground                   {ground:.15f}" in out
    assert sky > 0.01 and "sum with sky and ground  1.000000000000000" in out
    # the sky: the row's value of the front wall in the closed box (the floor's point is
    # at the wall's bottom: all of it above); the row: the open box's, unchanged
    G = ef.form_factors(ef.scenes.cornell_box(closed=True), p, n)
    assert abs(sky - G[-1]) <= 1e-12 and ground == 0.0
    assert np.abs(F - G[:-1]).max() <= 1e-13


def test_matrix_remainder_and_report(tmp_path, capsys):
    out = tmp_path / "m.npy"
    assert main(["matrix", "cornell_box", "-o", str(out), "--no-progress", "--remainder",
                 "--up", "0", "1", "0", "--rows", "4:10"]) == 0
    text = capsys.readouterr().out
    R = np.load(tmp_path / "m.remainder.npy")
    M = np.load(out)
    assert R.shape == (6, 2) and M.shape == (6, 20)
    # sky and ground: the rows' values of the missing front wall's parts above and below
    # each point's height, in the box closed by them (rows 4 to 9: ceiling quads, and
    # walls at mid height, where the cut is)
    scene = ef.scenes.cornell_box()
    for k, i in enumerate(range(4, 10)):
        p, n = scene.centroids[i], scene.normals[i]
        closed, below, above = front_halves(scene, p[1])
        F = ef.form_factors(closed, p, n)
        sky, ground = (0.0 if j is None else F[j] for j in (above, below))
        assert abs(R[k, 0] - sky) <= 1e-12 and abs(R[k, 1] - ground) <= 1e-12
    doc = json.loads((tmp_path / "m.report.json").read_text())
    assert doc["ok"] and doc["judged"] == "remainder" and doc["rows"] == list(range(4, 10))
    assert "m.remainder.npy" in text and "every row, pair and value within its bound" in text


def test_matrix_report_names_rows_of_an_open_scene_only_with_remainder(tmp_path, capsys):
    """Without the remainder the open Cornell box's rows need not sum to 1."""
    assert main(["matrix", "cornell_box", "-o", str(tmp_path / "m"), "--no-progress"]) == 0
    text = capsys.readouterr().out
    doc = json.loads((tmp_path / "m.report.json").read_text())
    assert doc["judged"] is None and doc["ok"] and "need not be 1" in text
    # a closed box: judged, and within bounds
    assert main(["matrix", "box:2", "-o", str(tmp_path / "b"), "--no-progress"]) == 0
    doc = json.loads((tmp_path / "b.report.json").read_text())
    assert doc["judged"] == "closed scene" and doc["ok"] and doc["reciprocity"] > 0


def test_remainder_usage_errors(tmp_path, capsys):
    assert main(["ff", "box:1", "--point", "0.5", "0.5", "0.5", "--normal", "0", "0", "1",
                 "--up", "0", "0", "1"]) == 2
    assert main(["matrix", "box:1", "-o", str(tmp_path / "a"), "--area", "--remainder"]) == 2
    err = capsys.readouterr().err
    assert "--up is the up direction of --remainder" in err and "not with --area" in err
