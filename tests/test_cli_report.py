"""The command line's remainder (ff and matrix --remainder) and the report written
beside every matrix (STEM.report.json)."""

import json

import numpy as np

import exactff as ef
from exactff.cli import main


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


def test_matrix_remainder_and_report(tmp_path, capsys):
    out = tmp_path / "m.npy"
    assert main(["matrix", "cornell_box", "-o", str(out), "--no-progress", "--remainder",
                 "--up", "0", "1", "0", "--rows", "0:6"]) == 0
    text = capsys.readouterr().out
    R = np.load(tmp_path / "m.remainder.npy")
    M = np.load(out)
    assert R.shape == (6, 2) and np.abs(M.sum(axis=1) + R.sum(axis=1) - 1).max() <= 1e-13
    doc = json.loads((tmp_path / "m.report.json").read_text())
    assert doc["ok"] and doc["judged"] == "remainder" and doc["rows"] == list(range(6))
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
