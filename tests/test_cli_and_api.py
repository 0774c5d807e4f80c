"""The command line and the flat public API."""

import subprocess
import sys

import exactff as ef
from exactff.cli import main


# DESIGN.md section 5 (first and second rounds): the names that checks outside the
# project call, written out here rather than taken from the package
DESIGN_NAMES = {"Scene", "SceneError", "NumericalError", "load_scene", "scenes", "form_factors",
                "point_polygon_form_factor", "point_polygon_form_factors",
                "form_factor_matrix", "compare", "Exact", "DiscretePPBH", "Hemicube",
                "CubicTetrahedron", "SinglePlane", "PolarPlane", "MonteCarlo", "METHODS",
                "load_matrix", "polygon_form_factor", "area_form_factors", "describe",
                "read_vs3", "__version__"}


def _documented_flat_names():
    """The names in the reference's autosummary of the flat namespace
    (docs/reference/index.md, kept by hand)."""
    import pathlib

    text = (pathlib.Path(__file__).resolve().parents[1] / "docs" / "reference"
            / "index.md").read_text()
    block = text.split(".. currentmodule:: exactff\n", 1)[1].split("```", 1)[0]
    return {line.strip() for line in block.splitlines()
            if line.startswith("   ") and not line.strip().startswith(":")}


def test_exports_are_the_documented_list():
    assert DESIGN_NAMES <= set(ef.__all__), DESIGN_NAMES - set(ef.__all__)
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
    # every export has its page in the reference and every page an export (the
    # submodules and the version are documented in sections of their own)
    documented = _documented_flat_names()
    assert len(documented) > 40
    exported = set(ef.__all__) - {"catalog", "scenes", "__version__"}
    assert exported - documented == set(), "exported but not in docs/reference/index.md"
    assert documented - exported == set(), "in docs/reference/index.md but not exported"
    assert len(ef.__all__) == len(set(ef.__all__))
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


def test_cli_output_without_a_suffix_gets_the_formats_suffix(tmp_path, capsys):
    import numpy as np
    import scipy.sparse as sp

    scene = ef.scenes.subdivided_box(1)
    ref = ef.form_factor_matrix(scene)
    # the unit box seen from a face's centre: the opposite face by Howell's catalogue
    # (parallel_rect_corner of the four quarters), each adjacent face (1 - that) / 4
    from common import parallel_rect_corner

    opposite = 4 * parallel_rect_corner(0.5, 0.5, 1.0)
    for sparse, written in ((False, "m.npy"), (True, "m.npz")):
        d = tmp_path / written[2:]
        d.mkdir()
        argv = ["matrix", "box:1", "-o", str(d / "m"), "--no-progress"]
        assert main(argv + (["--sparse"] if sparse else [])) == 0
        assert f"-> {d / written}" in capsys.readouterr().out
        assert sorted(p.name for p in d.iterdir()) == sorted(["m.meta.json", "m.report.json", written])
        M = ef.load_matrix(d / written)
        M = M.toarray() if sp.issparse(M) else np.asarray(M)
        assert np.array_equal(M, ref)
        assert abs(M[0, 1] - opposite) <= 1e-13 + 1e-12 * opposite
        side = (1 - opposite) / 4
        assert np.all(np.abs(M[0, 2:] - side) <= 1e-13 + 1e-12 * side)


def test_version_from_python_dash_m_and_the_console_script(capsys):
    import pathlib
    import re

    import pytest

    root = pathlib.Path(__file__).resolve().parents[1]
    # the version is written once, in exactff/version.py (pyproject.toml reads it there)
    version = re.search(r'__version__ = "([^"]+)"', (root / "exactff" / "version.py").read_text())
    want = f"exactff {version.group(1)}\n"
    pyproject = (root / "pyproject.toml").read_text()
    script = re.search(r'^exactff = "([^"]+)"', pyproject, re.M).group(1)
    r = subprocess.run([sys.executable, "-m", "exactff", "--version"], capture_output=True,
                       text=True, timeout=120, cwd=root)
    assert r.returncode == 0 and r.stdout == want and r.stderr == ""
    # the console script `exactff` is the entry point pyproject.toml names
    module, _, func = script.partition(":")
    entry = getattr(__import__(module, fromlist=[func]), func)
    with pytest.raises(SystemExit) as exit_:
        entry(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out == want
