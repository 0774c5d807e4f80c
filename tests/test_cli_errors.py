"""Bad scene files on the command line: one line naming the file (and the line for OBJ),
exit code 2, no traceback (issue 11, item 8); ``python -m exactff`` works."""

import subprocess
import sys

import pytest

from exactff.cli import main

BAD_JSON = {
    "empty_object.json": "{}",
    "list.json": "[]",
    "no_surfaces.json": '{"schema": "exactff-scene/1"}',
    "surfaces_not_list.json": '{"schema": "exactff-scene/1", "surfaces": 3}',
    "no_vertices.json": '{"schema": "exactff-scene/1", "surfaces": [{"name": "a"}]}',
    "not_json.json": "this is not JSON",
    "nan.json": '{"schema": "exactff-scene/1", "surfaces": [{"vertices": '
                '[[0, 0, 0], [1, 0, 0], [NaN, 1, 0]]}]}',
}
BAD_OBJ = {
    "bad_index.obj": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n", ":4:"),
    "text.obj": ("v 0 0 0\nv 1 0 0\nhello world\nv one 1 0\n", ":4:"),
    "nan.obj": ("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", ":3:"),
    "no_faces.obj": ("v 0 0 0\n", "no faces"),
}


@pytest.mark.parametrize("name", sorted(BAD_JSON))
@pytest.mark.parametrize("command", ["info", "matrix"])
def test_bad_json_gives_one_line_and_exit_2(tmp_path, capsys, name, command):
    path = tmp_path / name
    path.write_text(BAD_JSON[name])
    argv = [command, str(path)] + (["--output", str(tmp_path / "out.npy")] if command == "matrix" else [])
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "Traceback" not in err[0]


@pytest.mark.parametrize("name", sorted(BAD_OBJ))
def test_bad_obj_gives_one_line_naming_file_and_line(tmp_path, capsys, name):
    text, where = BAD_OBJ[name]
    path = tmp_path / name
    path.write_text(text)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and where in err[0]


def test_binary_file_is_an_error(tmp_path, capsys):
    path = tmp_path / "x.obj"
    path.write_bytes(b"\xff\xfe\x00bad")
    assert main(["info", str(path)]) == 2
    assert str(path) in capsys.readouterr().err


def test_python_dash_m_runs_the_command():
    out = subprocess.run([sys.executable, "-m", "exactff", "info", "cornell_box"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "polygons" in out.stdout


# ---------------------------------------------------------------------------------------
# exit codes (issue 33): 2 for usage errors, 1 for failures of the computation
# ---------------------------------------------------------------------------------------
ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


def _run(*argv, prelude=""):
    """``python -m exactff ARGV`` from the checkout, after ``prelude`` (Python run in the
    same process first, e.g. to inject a failure)."""
    code = prelude + "\nimport runpy\nimport sys\nsys.argv = ['exactff'] + sys.argv[1:]\n" \
                     "runpy.run_module('exactff', run_name='__main__')\n"
    return subprocess.run([sys.executable, "-c", code, *argv], capture_output=True,
                          text=True, timeout=120, cwd=ROOT)


@pytest.mark.parametrize("spec, names", [
    ("box:abc", ["box:abc", "K", "'abc'"]), ("box:", ["box:", "K"]),
    ("box:0", ["box:0", "box:K", "positive"]),
    ("office:x", ["office:x", "N", "'x'"]), ("office:0", ["office:0", "office:N"]),
    ("cloister:1.5", ["cloister:1.5", "N", "'1.5'"]),
    ("building:axb", ["building:axb", "NX", "'a'"]), ("building:2xb", ["building:2xb", "NY"]),
    ("building:2x", ["building:2x", "NY"]), ("building:1x2x3", ["building:1x2x3", "NXxNY"]),
    ("building:2x0", ["building:2x0", "NXxNY", "ny"])])
def test_bad_built_in_scene_names_the_argument(capsys, spec, names):
    # before: "invalid literal for int() with base 10: 'abc'", naming nothing
    assert main(["info", spec]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"exactff: error: scene {spec!r}")
    for name in names:
        assert name in err[0], (name, err[0])


def test_good_built_in_sizes_still_open(capsys):
    for spec, count in (("box:2", 24), ("building:2", None), ("building:2x1", None)):
        assert main(["info", spec]) == 0
        out = capsys.readouterr().out
        if count:
            assert f"polygons         {count}" in out
    assert main(["info", "building:2"]) == 0
    one = capsys.readouterr().out
    assert main(["info", "building:2x1"]) == 0
    assert capsys.readouterr().out.replace("building:2x1", "building:2") == one


@pytest.mark.parametrize("argv, argparse_error", [
    (["info", "box:abc"], False), (["info", "no-such-scene.obj"], False),
    (["matrix", "box:1", "--rows", "7"], False), (["matrix", "box:1", "--jobs", "0"], False),
    (["compare", "box:1", "--methods", "nope", "--out", "x"], False),
    (["matrix", "box:1", "--frobnicate"], True), (["matrix"], True), ([], True)])
def test_usage_errors_exit_2_with_one_line(argv, argparse_error):
    import re

    r = _run(*argv)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr and r.stdout == ""
    err = r.stderr.strip().splitlines()
    assert re.match(r"exactff( matrix)?: error: \S", err[-1]), err
    # exactff's own errors are one line; argparse's add its usage before it
    assert len(err) == 1 or (argparse_error and err[0].startswith("usage: exactff"))


INJECT = """
import exactff as ef

def _fails(self, *args, **kwargs):
    raise ef.NumericalError("polygon 3: the form factor 0.25 misses the tolerance 1e-12\\n"
                            "(error estimate 2e-09) even in 1000-digit arithmetic")

ef.Exact.point_form_factors = _fails
"""


def test_numerical_error_exits_1_with_one_line(tmp_path):
    # a NumericalError raised inside the computation reaches the command line as one
    # line on stderr (no traceback), exit status 1: a failure, not a usage error
    r = _run("matrix", "box:1", "-o", str(tmp_path / "m.npy"), "--no-progress",
             prelude=INJECT)
    assert r.returncode == 1, (r.returncode, r.stderr)
    err = r.stderr.strip().splitlines()
    assert err == ["exactff: numerical error: polygon 3: the form factor 0.25 misses the "
                   "tolerance 1e-12 (error estimate 2e-09) even in 1000-digit arithmetic"]
    # without the failure the same command succeeds
    r = _run("matrix", "box:1", "-o", str(tmp_path / "m.npy"), "--no-progress")
    assert r.returncode == 0, r.stderr


def test_numerical_error_in_process(monkeypatch, capsys, tmp_path):
    import exactff as ef

    def fails(self, *args, **kwargs):
        raise ef.NumericalError("polygon 0: mpmath did not converge")

    monkeypatch.setattr(ef.Exact, "point_form_factors", fails)
    assert main(["matrix", "box:1", "-o", str(tmp_path / "m.npy"), "--no-progress"]) == 1
    assert capsys.readouterr().err == "exactff: numerical error: polygon 0: mpmath did not converge\n"
    # from worker processes too (the pool sends the exception back to the parent); the
    # workers are forked, so they inherit the failure
    import multiprocessing

    if multiprocessing.get_start_method() == "fork":
        assert main(["matrix", "box:1", "-o", str(tmp_path / "j.npy"), "--no-progress",
                     "--jobs", "2"]) == 1
        assert capsys.readouterr().err.startswith("exactff: numerical error: polygon 0:")
