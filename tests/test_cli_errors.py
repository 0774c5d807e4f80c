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
