"""Real scene files (issue 16): non-planar faces, errors that name the face, STL / PLY /
OFF / VTK through meshio, pyvista meshes, View3D ``.vs3``."""

from types import SimpleNamespace

import meshio
import numpy as np
import pytest

import exactff as ef
from exactff.cli import main
from exactff.io import load_scene
from exactff.scene import split_nonplanar
from exactff.reports import describe

from common import parallel_rect_corner

# The original Cornell box in OBJ format, as published by Guedis Cardenas and Morgan
# McGuire, Williams College, 2011 (public domain; http://graphics.cs.williams.edu/data,
# after http://www.graphics.cornell.edu/online/box/data.html), with its back wall
# commented out as in the distributed file. Its left wall is not planar (a vertex 0.005
# off), and each box's "Bottom Face" line repeats one of its side faces (the face
# statements point 8 or 12 vertices back instead of 4): 17 faces.
CORNELL_BOX_ORIGINAL = """\
# The original Cornell Box in OBJ format.
# Note that the real box is not a perfect cube, so
# the faces are imperfect in this data set.
#
# Created by Guedis Cardenas and Morgan McGuire at Williams College, 2011
# Released into the Public Domain.
#
# http://graphics.cs.williams.edu/data
# http://www.graphics.cornell.edu/online/box/data.html
#

mtllib CornellBox-Original.mtl

## Object floor
v  -1.01  0.00   0.99
v   1.00  0.00   0.99
v   1.00  0.00  -1.04
v  -0.99  0.00  -1.04

g floor
usemtl floor
f -4 -3 -2 -1

## Object ceiling
v  -1.02  1.99   0.99
v  -1.02  1.99  -1.04
v   1.00  1.99  -1.04
v   1.00  1.99   0.99

g ceiling
usemtl ceiling
f -4 -3 -2 -1

# ## Object backwall
# v  -0.99  0.00  -1.04
# v   1.00  0.00  -1.04
# v   1.00  1.99  -1.04
# v  -1.02  1.99  -1.04

# g backWall
# usemtl backWall
# f -4 -3 -2 -1

## Object rightwall
v\t1.00  0.00  -1.04
v\t1.00  0.00   0.99
v\t1.00  1.99   0.99
v\t1.00  1.99  -1.04

g rightWall
usemtl rightWall
f -4 -3 -2 -1

## Object leftWall
v  -1.01  0.00   0.99
v  -0.99  0.00  -1.04
v  -1.02  1.99  -1.04
v  -1.02  1.99   0.99

g leftWall
usemtl leftWall
f -4 -3 -2 -1

## Object shortBox
usemtl shortBox

# Top Face
v\t0.53  0.60   0.75
v\t0.70  0.60   0.17
v\t0.13  0.60   0.00
v  -0.05  0.60   0.57
f -4 -3 -2 -1

# Left Face
v  -0.05  0.00   0.57
v  -0.05  0.60   0.57
v   0.13  0.60   0.00
v   0.13  0.00   0.00
f -4 -3 -2 -1

# Front Face
v\t0.53  0.00   0.75
v\t0.53  0.60   0.75
v  -0.05  0.60   0.57
v  -0.05  0.00   0.57
f -4 -3 -2 -1

# Right Face
v\t0.70  0.00   0.17
v\t0.70  0.60   0.17
v\t0.53  0.60   0.75
v\t0.53  0.00   0.75
f -4 -3 -2 -1

# Back Face
v\t0.13  0.00   0.00
v\t0.13  0.60   0.00
v\t0.70  0.60   0.17
v\t0.70  0.00   0.17
f -4 -3 -2 -1

# Bottom Face
v\t0.53  0.00   0.75
v\t0.70  0.00   0.17
v\t0.13  0.00   0.00
v  -0.05  0.00   0.57
f -12 -11 -10 -9

g shortBox
usemtl shortBox

## Object tallBox
usemtl tallBox

# Top Face
v\t-0.53  1.20   0.09
v\t 0.04  1.20  -0.09
v\t-0.14  1.20  -0.67
v\t-0.71  1.20  -0.49
f -4 -3 -2 -1

# Left Face
v\t-0.53  0.00   0.09
v\t-0.53  1.20   0.09
v\t-0.71  1.20  -0.49
v\t-0.71  0.00  -0.49
f -4 -3 -2 -1

# Back Face
v\t-0.71  0.00  -0.49
v\t-0.71  1.20  -0.49
v\t-0.14  1.20  -0.67
v\t-0.14  0.00  -0.67
f -4 -3 -2 -1

# Right Face
v\t-0.14  0.00  -0.67
v\t-0.14  1.20  -0.67
v\t 0.04  1.20  -0.09
v\t 0.04  0.00  -0.09
f -4 -3 -2 -1

# Front Face
v\t 0.04  0.00  -0.09
v\t 0.04  1.20  -0.09
v\t-0.53  1.20   0.09
v\t-0.53  0.00   0.09
f -4 -3 -2 -1

# Bottom Face
v\t-0.53  0.00   0.09
v\t 0.04  0.00  -0.09
v\t-0.14  0.00  -0.67
v\t-0.71  0.00  -0.49
f -8 -7 -6 -5

g tallBox
usemtl tallBox

## Object light
v\t-0.24  1.98   0.16
v\t-0.24  1.98  -0.22
v\t 0.23  1.98  -0.22
v\t 0.23  1.98   0.16

g light
usemtl light
f -4 -3 -2 -1
"""

LEFT_WALL = np.array([[-1.01, 0.00, 0.99], [-0.99, 0.00, -1.04],
                      [-1.02, 1.99, -1.04], [-1.02, 1.99, 0.99]])


@pytest.fixture
def cornell_obj(tmp_path):
    path = tmp_path / "CornellBox-Original.obj"
    path.write_text(CORNELL_BOX_ORIGINAL)
    return path


def test_cornell_obj_refused_naming_the_wall_and_the_line(cornell_obj):
    with pytest.raises(ef.SceneError) as info:
        load_scene(cornell_obj)
    msg = str(info.value)
    lines = CORNELL_BOX_ORIGINAL.splitlines()
    face_line = lines.index("g leftWall") + 3          # its "f" statement, 1-based
    assert lines[face_line - 1].startswith("f ")
    assert "leftWall" in msg and f"{cornell_obj}:{face_line}:" in msg and "not planar" in msg
    assert "--split-nonplanar" in msg and info.value.index == 3


def _same_cycle(P, Q):
    """Whether two polygons have the same vertices in the same cyclic order."""
    P, Q = np.asarray(P, dtype=float), np.asarray(Q, dtype=float)
    return len(P) == len(Q) and any(np.array_equal(np.roll(P, k, axis=0), Q)
                                    for k in range(len(P)))


def test_cornell_obj_split_equals_the_same_triangles_by_hand(cornell_obj):
    scene = load_scene(cornell_obj, nonplanar="split")
    assert len(scene) == 18 and describe(scene)["split_faces"] == 1
    assert scene.groups[3] == scene.groups[4] == "leftWall"
    assert scene.materials[4] == "leftWall"
    # the same scene built by hand from the OBJ text: the left wall as the two
    # triangles of either diagonal (both are valid splits; the reader's choice is the
    # flatter one), every other face as written (the boxes' bottom faces repeat the
    # vertices of their right and front faces: "f -12 -11 -10 -9", "f -8 -7 -6 -5")
    tris = [scene.polygons[3], scene.polygons[4]]
    for t in tris:
        assert all(any(np.array_equal(v, w) for w in LEFT_WALL) for v in t)
    splits = [[LEFT_WALL[[0, 1, 2]], LEFT_WALL[[0, 2, 3]]],
              [LEFT_WALL[[0, 1, 3]], LEFT_WALL[[1, 2, 3]]]]
    left = next(pair for pair in splits
                if all(any(_same_cycle(t, u) for u in pair) for t in tris))
    short_right = [[0.70, 0.00, 0.17], [0.70, 0.60, 0.17], [0.53, 0.60, 0.75],
                   [0.53, 0.00, 0.75]]
    tall_front = [[0.04, 0.00, -0.09], [0.04, 1.20, -0.09], [-0.53, 1.20, 0.09],
                  [-0.53, 0.00, 0.09]]
    by_hand_faces = [
        [[-1.01, 0.00, 0.99], [1.00, 0.00, 0.99], [1.00, 0.00, -1.04], [-0.99, 0.00, -1.04]],
        [[-1.02, 1.99, 0.99], [-1.02, 1.99, -1.04], [1.00, 1.99, -1.04], [1.00, 1.99, 0.99]],
        [[1.00, 0.00, -1.04], [1.00, 0.00, 0.99], [1.00, 1.99, 0.99], [1.00, 1.99, -1.04]],
        left[0], left[1],
        [[0.53, 0.60, 0.75], [0.70, 0.60, 0.17], [0.13, 0.60, 0.00], [-0.05, 0.60, 0.57]],
        [[-0.05, 0.00, 0.57], [-0.05, 0.60, 0.57], [0.13, 0.60, 0.00], [0.13, 0.00, 0.00]],
        [[0.53, 0.00, 0.75], [0.53, 0.60, 0.75], [-0.05, 0.60, 0.57], [-0.05, 0.00, 0.57]],
        short_right,
        [[0.13, 0.00, 0.00], [0.13, 0.60, 0.00], [0.70, 0.60, 0.17], [0.70, 0.00, 0.17]],
        short_right,
        [[-0.53, 1.20, 0.09], [0.04, 1.20, -0.09], [-0.14, 1.20, -0.67], [-0.71, 1.20, -0.49]],
        [[-0.53, 0.00, 0.09], [-0.53, 1.20, 0.09], [-0.71, 1.20, -0.49], [-0.71, 0.00, -0.49]],
        [[-0.71, 0.00, -0.49], [-0.71, 1.20, -0.49], [-0.14, 1.20, -0.67], [-0.14, 0.00, -0.67]],
        [[-0.14, 0.00, -0.67], [-0.14, 1.20, -0.67], [0.04, 1.20, -0.09], [0.04, 0.00, -0.09]],
        tall_front,
        tall_front,
        [[-0.24, 1.98, 0.16], [-0.24, 1.98, -0.22], [0.23, 1.98, -0.22], [0.23, 1.98, 0.16]],
    ]
    assert len(by_hand_faces) == 18
    for j, (P, Q) in enumerate(zip(scene.polygons, by_hand_faces)):
        assert _same_cycle(P, Q), j
    assert np.isclose(sum(np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) / 2 for t in tris),
                      sum(np.linalg.norm(np.cross(t[1] - t[0], t[2] - t[0])) / 2
                          for t in split_nonplanar(LEFT_WALL)), rtol=1e-14, atol=0)
    by_hand = ef.Scene.from_polygons(by_hand_faces)
    floor = 0
    p, n = scene.centroids[floor], scene.normals[floor]
    np.testing.assert_array_equal(ef.form_factors(scene, p, n), ef.form_factors(by_hand, p, n))
    # and the box is open (no back wall): the floor's row sums to less than 1
    assert ef.form_factors(scene, p, n).sum() < 0.95


def test_split_nonplanar_gives_planar_triangles_of_the_same_outline():
    tris = split_nonplanar(LEFT_WALL)
    assert len(tris) == 2
    # the fan covers the quad: every quad vertex is used, the shared diagonal twice
    used = np.concatenate(tris)
    assert {tuple(v) for v in used} == {tuple(v) for v in LEFT_WALL}
    # same orientation as the quad's mean normal
    N = np.cross(LEFT_WALL[2] - LEFT_WALL[0], LEFT_WALL[3] - LEFT_WALL[1])
    for t in tris:
        assert np.cross(t[1] - t[0], t[2] - t[0]) @ N > 0


def test_cli_split_nonplanar_and_planarity_rtol(cornell_obj, capsys):
    assert main(["info", str(cornell_obj)]) == 2
    err = capsys.readouterr().err
    assert "leftWall" in err and "--split-nonplanar" in err and err.count("\n") == 1
    assert main(["info", str(cornell_obj), "--split-nonplanar"]) == 0
    out = capsys.readouterr().out
    assert "polygons         18" in out and "1 non-planar faces split" in out
    assert main(["info", str(cornell_obj), "--planarity-rtol", "0.01"]) == 0
    assert "polygons         17" in capsys.readouterr().out
    assert main(["info", str(cornell_obj), "--planarity-rtol", "-1"]) == 2
    assert "--planarity-rtol" in capsys.readouterr().err


def test_cli_matrix_from_the_cornell_obj(cornell_obj, tmp_path, capsys):
    out = tmp_path / "m.npy"
    assert main(["matrix", str(cornell_obj), "--split-nonplanar", "-o", str(out),
                 "--no-progress", "--rows", "0,1"]) == 0
    M = np.load(out)
    # --rows 0,1 writes those two rows only (form_factor_matrix's rows=), each of the 18
    # polygons a column; row k is the row from polygon k's centroid: polygon 0's
    # row, not the others' (the bit-for-bit equality only says which rows were written)
    assert M.shape == (2, 18)
    scene = load_scene(cornell_obj, nonplanar="split")
    rows = ef.form_factors(scene, scene.centroids, scene.normals)
    for k in (0, 1):
        assert [i for i in range(18) if np.array_equal(M[k], rows[i])] == [k]
    assert M[0, 0] == M[1, 1] == 0 and np.all(M >= 0)
    assert np.all(M.sum(axis=1) < 1)                   # the box is open


def _box_triangles():
    """A closed unit box, every quad face split into two triangles, fronts inward."""
    tris = []
    for P in ef.scenes.subdivided_box(1).polygons:
        tris += [P[[0, 1, 2]], P[[0, 2, 3]]]
    return tris


@pytest.mark.parametrize("binary", [False, True])
def test_stl_box_rows_sum_to_one(tmp_path, binary):
    tris = _box_triangles()
    points = np.concatenate(tris)
    cells = [("triangle", np.arange(len(points)).reshape(-1, 3))]
    path = tmp_path / "box.stl"
    meshio.write_points_cells(path, points, cells, binary=binary)
    scene = load_scene(path)
    assert len(scene) == 12
    for i in (0, 5, 11):
        F = ef.form_factors(scene, scene.centroids[i] + 1e-9 * scene.normals[i], scene.normals[i])
        assert abs(F.sum() - 1) <= 1e-11
    # STL keeps the facet order: the same polygons as written (to float32 for binary)
    assert np.allclose(scene.polygons[0], tris[0], rtol=0, atol=1e-7)


@pytest.mark.parametrize("ext", [".ply", ".off", ".vtk"])
def test_mesh_formats_keep_quads(tmp_path, ext):
    # quads stay quads where the format has them (meshio writes OFF as triangles only)
    box = ef.scenes.subdivided_box(2)
    if ext == ".off":
        faces = [t for P in box.polygons for t in (P[[0, 1, 2]], P[[0, 2, 3]])]
        kind, k = "triangle", 3
    else:
        faces, kind, k = list(box.polygons), "quad", 4
    points = np.concatenate(faces)
    cells = [(kind, np.arange(len(points)).reshape(-1, k))]
    path = tmp_path / f"box{ext}"
    meshio.write_points_cells(path, points, cells)
    scene = load_scene(path)
    assert len(scene) == len(faces)
    np.testing.assert_allclose(np.concatenate(scene.polygons), points, rtol=0, atol=1e-7)
    F = ef.form_factors(scene, [0.5, 0.5, 1e-9], [0, 0, 1])
    assert abs(F.sum() - 1) <= 1e-11


@pytest.mark.parametrize("text,needle", [
    ("solid x\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n", "box.stl"),
    ("not a mesh at all\n", "box.stl"),
])
def test_malformed_mesh_refused_in_one_line(tmp_path, text, needle, capsys):
    path = tmp_path / "box.stl"
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        load_scene(path)
    assert needle in str(info.value)
    assert main(["info", str(path)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_unknown_extension_lists_the_formats(tmp_path):
    path = tmp_path / "x.abc"
    path.write_text("")
    with pytest.raises(ValueError, match=r"\.vs3"):
        load_scene(path)


def test_from_pyvista_polydata_layout():
    box = ef.scenes.subdivided_box(2)
    points = np.concatenate(box.polygons)
    faces = np.concatenate([[4, *range(k, k + 4)] for k in range(0, len(points), 4)])
    scene = ef.Scene.from_pyvista(SimpleNamespace(points=points, faces=faces))
    assert len(scene) == len(box)
    p, n = [0.3, 0.6, 0.0], [0, 0, 1]
    np.testing.assert_array_equal(ef.form_factors(scene, p, n), ef.form_factors(box, p, n))
    with pytest.raises(ValueError, match="faces"):
        ef.Scene.from_pyvista(SimpleNamespace(points=points, faces=[4, 0, 1]))


def test_to_pyvista_round_trip():
    import pyvista as pv          # in the test extra: a missing install fails, not skips
    box = ef.scenes.subdivided_box(2)
    mesh = box.to_pyvista()
    assert isinstance(mesh, pv.PolyData) and mesh.n_cells == len(box)
    # VTK's own normals (float32), areas and cell centres agree with the scene's
    np.testing.assert_allclose(mesh.cell_normals, box.normals, rtol=0, atol=1e-7)
    np.testing.assert_allclose(mesh.compute_cell_sizes().cell_data["Area"], box.areas,
                               rtol=1e-14, atol=0)
    np.testing.assert_allclose(mesh.cell_centers().points, box.centroids, rtol=0, atol=1e-15)
    back = ef.Scene.from_pyvista(mesh)
    np.testing.assert_array_equal(np.concatenate(back.polygons), np.concatenate(box.polygons))


# View3D's example "Two squares with a square obstruction in between" (examples/
# square-obstruction.vs3 of github.com/jasondegraw/View3D), with its middle square as an
# obstruction-only surface (O) and a comment, a title and a control line.
VS3 = """\
T Two squares with a square obstruction in between
C encl=0 list=3
F 3
!  #   x    y    z      coordinates of vertices
V  1   0.   0.   0.
V  2   1.   0.   0.
V  3   1.   1.   0.
V  4   0.   1.   0.
V  5   0.   0.   1.
V  6   1.   0.   1.
V  7   1.   1.   1.
V  8   0.   1.   1.
V  9   0.   0.   .5
V 10   .5   0.   .5
V 11   .5   .5   .5
V 12   0.   .5   .5
!  #   v1  v2  v3  v4 base cmb  emit  name      surface data
S  1    1   2   3   4   0   0   0.50  zeq0.0
S  2    7   6   5   8   0   0   0.50  zeq1.0
O  3    9  10  11  12
End of data
"""


def test_vs3_reads_surfaces_and_obstructions(tmp_path):
    path = tmp_path / "sq.vs3"
    path.write_text(VS3)
    scene = load_scene(path)
    assert len(scene) == 3
    assert scene.names[:2] == ("zeq0.0", "zeq1.0") and scene.groups[2] == "obstruction"
    # the lower square faces up, the upper one down: the obstruction (a quarter of the
    # square, in the corner) hides the corner of the upper square from the lower one
    assert np.allclose(scene.normals[:2], [[0, 0, 1], [0, 0, -1]], rtol=0, atol=1e-15)
    F_open = ef.form_factors(ef.Scene.from_polygons(scene.polygons[:2]), [0.1, 0.1, 0], [0, 0, 1])
    F = ef.form_factors(scene, [0.1, 0.1, 0], [0, 0, 1])
    # Howell superposition: from (0.1, 0.1, 0) the obstruction [0, .5]^2 at z = .5 casts
    # [-0.1, 0.9]^2 at z = 1, so [0, 0.9]^2 of the upper square is hidden; the visible
    # part is the square minus that rectangle (corner rectangles, odd in each side)
    def rect(x1, x2, y1, y2, p=(0.1, 0.1), c=1.0):
        f = lambda a, b: parallel_rect_corner(a, b, c)
        return (f(x2 - p[0], y2 - p[1]) - f(x1 - p[0], y2 - p[1])
                - f(x2 - p[0], y1 - p[1]) + f(x1 - p[0], y1 - p[1]))
    assert abs(F_open[1] - rect(0, 1, 0, 1)) <= 1e-13
    # DESIGN 6: an occluded value within 1e-11 absolute
    assert abs(F[1] - (rect(0, 1, 0, 1) - rect(0, 0.9, 0, 0.9))) <= 1e-11


@pytest.mark.parametrize("line,needle", [
    ("S  3    9  10  11  12   5   0   0.50  sub", "base surface 5 does not exist"),
    ("M  3    9  10  11  12   0   0   0.50  m", "needs a base"),
    ("S  3    9  10  11  99   0   0   0.50  x", "vertex 99 is not defined"),
    ("S  4    9  10  11  12   0   0   0.50  x", "out of sequence"),
    ("V 13   0. 0.", "vertex 13: coordinate: 'End' (line 21) is not a number"),
    ("Q what", "unknown keyword"),
])
def test_vs3_errors_name_the_line(tmp_path, line, needle):
    path = tmp_path / "bad.vs3"
    text = VS3.replace("O  3    9  10  11  12\n", line + "\n")
    path.write_text(text)
    with pytest.raises(ValueError) as info:
        load_scene(path)
    assert needle in str(info.value) and f"{path}:" in str(info.value)


def test_json_errors_name_the_surface(tmp_path):
    import json

    path = tmp_path / "s.json"
    path.write_text(json.dumps({"schema": "exactff-scene/1", "surfaces": [
        {"vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "name": "ok"},
        {"vertices": [[0, 0, 0], [1, 0, 0], [2, 0, 0]], "name": "flat"}]}))
    with pytest.raises(ef.SceneError, match=r"surfaces\[1\]: polygon 1 \('flat'\): zero area"):
        load_scene(path)
