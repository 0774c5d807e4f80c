"""The command line and the flat public API."""

import subprocess
import sys

import exactff as ef
from exactff.cli import main


def test_exports_are_the_documented_list():
    documented = {"Scene", "SceneError", "load_scene", "point_polygon_form_factor",
                  "point_polygon_form_factors", "scenes"}
    assert documented <= set(ef.__all__)
    for name in ef.__all__:
        assert hasattr(ef, name), name
    # each name of the flat API is its home module's own object (one home per name)
    import importlib

    for name in ef.__all__:
        obj = getattr(ef, name)
        home = getattr(obj, "__module__", None)
        if home and home.startswith("exactff") and not isinstance(obj, type(ef)):
            home = "exactff.errors" if home == "exactff" else home
            assert getattr(importlib.import_module(home), name) is obj, name
    for mod in (ef.scene, ef.geometry, ef.kernel, ef.io):
        assert mod.__doc__ and mod.__all__


def test_cli_help_runs_as_a_console_script():
    out = subprocess.run([sys.executable, "-m", "exactff.cli", "--help"],
                         capture_output=True, text=True, check=True).stdout
    assert "info" in out


def test_cli_info_cornell_box(capsys):
    assert main(["info", "cornell_box"]) == 0
    out = capsys.readouterr().out
    assert "polygons         20" in out and "open" in out
    assert main(["info", "box:2"]) == 0
    assert "polygons         24" in capsys.readouterr().out


def test_cli_ff_prints_row(capsys):
    assert main(["ff", "box:1", "--point", "0.5", "0.5", "0.5", "--normal", "0", "0", "1"]) == 0
    out = capsys.readouterr().out
    assert "sum" in out and "1.000000000000000" in out


def test_cli_reports_errors(capsys, tmp_path):
    assert main(["info", str(tmp_path / "missing.obj")]) == 2
    assert "error" in capsys.readouterr().err


def test_cli_matrix_writes_resumes_and_overwrites(tmp_path, capsys):
    import numpy as np

    import exactff as ef

    out = tmp_path / "m.npy"
    csv = tmp_path / "m.csv"
    assert main(["matrix", "cornell_box_closed", "-o", str(out), "--csv", str(csv),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "21 x 21" in text and "min 1.000000000000000" in text
    M = np.load(out)
    ref = ef.form_factor_matrix(ef.scenes.cornell_box(closed=True))
    assert np.array_equal(M, ref)
    assert np.allclose(np.loadtxt(csv, delimiter=","), ref, rtol=0, atol=0)
    assert main(["matrix", "cornell_box_closed", "-o", str(out), "--no-progress"]) == 0
    assert "resuming" in capsys.readouterr().out
    # another scene into the same file: refused, unless --overwrite
    assert main(["matrix", "box:1", "-o", str(out), "--no-progress"]) == 2
    assert "not written by this computation" in capsys.readouterr().err
    assert main(["matrix", "box:1", "-o", str(out), "--no-progress", "--overwrite",
                 "--rows", "0:3"]) == 0
    assert np.load(out).shape == (3, 6)
