"""Other tools' files (issue 32): EnergyPlus IDF surfaces in and view factors out,
Radiance polygons in, Elmer's ViewFactors.dat and OpenFOAM's F / globalFaceFaces out,
pandas tables.

Readers are tested on small files written by hand in each tool's conventions; writers
are read back by parsers written here, independently of the code under test, and must
give back the matrix to the digits written."""

import math
import pathlib
import re
import warnings

import numpy as np
import pytest
import scipy.sparse

import exactff as ef

DATA = pathlib.Path(__file__).resolve().parent / "data"

# View3D's manual (NISTIR 6925), its cube.vs3 example: unit cube, opposite faces and
# adjacent faces, printed to 9 digits (the issue quotes them)
CUBE_OPPOSITE = 0.199824896
CUBE_ADJACENT = 0.200043776
# View3D prints 9 significant digits; exactff is asked for 1e-11 below
VIEW3D_DIGITS = 5e-10

# ---------------------------------------------------------------------------------
# EnergyPlus
# ---------------------------------------------------------------------------------
# A 1 m cube zone as EnergyPlus wants it: vertices counter-clockwise seen from OUTSIDE,
# starting at the upper left corner (GlobalGeometryRules), EnergyPlus 9.4 (no Space
# Name field), world coordinates. A window on the south wall is not read.
CUBE_IDF = """\
! a unit cube, by hand
Version, 9.4;
GlobalGeometryRules,
  UpperLeftCorner,         !- Starting Vertex Position
  CounterClockWise,        !- Vertex Entry Direction
  World;                   !- Coordinate System
Zone, Room;
BuildingSurface:Detailed,
  Floor,                   !- Name
  Floor,                   !- Surface Type
  Slab,                    !- Construction Name
  Room,                    !- Zone Name
  Ground, ,                !- Outside Boundary Condition (Object)
  NoSun, NoWind, ,         !- Sun Exposure, Wind Exposure, View Factor to Ground
  4,                       !- Number of Vertices
  1, 1, 0,  1, 0, 0,  0, 0, 0,  0, 1, 0;
BuildingSurface:Detailed, Ceiling, Roof, Deck, Room, Outdoors, , SunExposed,
  WindExposed, , 4,
  0, 1, 1,  0, 0, 1,  1, 0, 1,  1, 1, 1;
BuildingSurface:Detailed, South, Wall, Ext, Room, Outdoors, , SunExposed, WindExposed,
  autocalculate, autocalculate,
  0, 0, 1,  0, 0, 0,  1, 0, 0,  1, 0, 1;
BuildingSurface:Detailed, East, Wall, Ext, Room, Outdoors, , SunExposed, WindExposed, , ,
  1, 0, 1,  1, 0, 0,  1, 1, 0,  1, 1, 1;
BuildingSurface:Detailed, North, Wall, Ext, Room, Outdoors, , SunExposed, WindExposed, , 4,
  1, 1, 1,  1, 1, 0,  0, 1, 0,  0, 1, 1;
BuildingSurface:Detailed, West, Wall, Ext, Room, Outdoors, , SunExposed, WindExposed, , 4,
  0, 1, 1,  0, 1, 0,  0, 0, 0,  0, 0, 1;
FenestrationSurface:Detailed, Win, Window, Glass, , South, , autocalculate, , 1, 4,
  0.2, 0, 0.8,  0.2, 0, 0.2,  0.8, 0, 0.2,  0.8, 0, 0.8;
"""

# the inward normals of the cube's faces, in file order
CUBE_INWARD = [[0, 0, 1], [0, 0, -1], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [1, 0, 0]]


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def _read_cube(tmp_path, **kw):
    p = _write(tmp_path, "cube.idf", CUBE_IDF)
    with pytest.warns(UserWarning, match="1 FenestrationSurface:Detailed"):
        return ef.read_idf(p, **kw)


def test_idf_surfaces_names_zones_constructions(tmp_path):
    scene = _read_cube(tmp_path)
    assert scene.names == ("Floor", "Ceiling", "South", "East", "North", "West")
    assert scene.groups == ("Room",) * 6
    assert scene.materials == ("Slab", "Deck", "Ext", "Ext", "Ext", "Ext")
    assert ef.describe(scene)["skipped_primitives"] == {"FenestrationSurface:Detailed": 1}
    # facing="inside": EnergyPlus's order reversed, its first vertex kept
    assert scene.polygons[0].tolist() == [[1, 1, 0], [0, 1, 0], [0, 0, 0], [1, 0, 0]]
    assert np.array_equal(scene.normals, np.array(CUBE_INWARD, dtype=float))


def test_idf_outside_keeps_energyplus_order(tmp_path):
    scene = _read_cube(tmp_path, facing="outside")
    assert scene.polygons[0].tolist() == [[1, 1, 0], [1, 0, 0], [0, 0, 0], [0, 1, 0]]
    assert np.array_equal(scene.normals, -np.array(CUBE_INWARD, dtype=float))


def test_idf_cube_view_factors_vs_view3d(tmp_path):
    """The file's cube, read and integrated: View3D's figures for the same cube."""
    scene = _read_cube(tmp_path)
    F = ef.area_form_factors(scene, tolerance=1e-11)
    assert abs(F[0, 1] - CUBE_OPPOSITE) < VIEW3D_DIGITS
    assert abs(F[0, 2] - CUBE_ADJACENT) < VIEW3D_DIGITS
    assert abs(F.sum(axis=1) - 1).max() < 1e-10   # a closed zone


def test_idf_energyplus_example_file():
    """EnergyPlus's 1ZoneUncontrolled: every surface faces into the zone, the zone is
    closed, and floor to roof is Howell's C-11 for 15.24 m squares 4.572 m apart."""
    from test_area import howell_parallel

    scene = ef.read_idf(DATA / "1ZoneUncontrolled.idf")
    assert scene.names[4:] == ("Zn001:Flr001", "Zn001:Roof001")
    centre = np.array([7.62, 7.62, 2.286])
    inward = np.einsum("ij,ij->i", scene.normals, centre - scene.centroids)
    assert (inward > 0).all()
    F = ef.area_form_factors(scene, tolerance=1e-11)
    assert abs(F.sum(axis=1) - 1).max() < 1e-10
    # C-11 to 40 digits; the area form factors are asked for 1e-11
    assert abs(F[4, 5] - howell_parallel(15.24, 15.24, 4.572)) < 1e-10


def test_idf_load_scene_dispatches(tmp_path):
    p = _write(tmp_path, "cube.idf", CUBE_IDF)
    with pytest.warns(UserWarning):
        assert ef.load_scene(p).names[5] == "West"


# EnergyPlus 9.6 and later: a Space Name field after the zone's. Clockwise from
# outside, coordinates relative to the zone (origin (10, 20, 3), relative north 90).
RELATIVE_IDF = """\
Version,23.2;
GlobalGeometryRules,LowerLeftCorner,Clockwise,Relative;
Zone,Attic,90,10,20,3;
Zone,Plain,,,,;
BuildingSurface:Detailed,Attic Floor,Floor,Slab,Attic,,Adiabatic,,NoSun,NoWind,,3,
  0,0,0, 1,0,0, 0,2,0;
BuildingSurface:Detailed,Plain Floor,Floor,Slab,Plain,Space 1,Adiabatic,,NoSun,NoWind,,3,
  0.1,0,0, 0.7,0,0, 0,0.3,0;
"""


def test_idf_relative_clockwise_space_field(tmp_path):
    p = _write(tmp_path, "rel.idf", RELATIVE_IDF)
    scene = ef.read_idf(p)
    # clockwise from outside, facing inside: the file's own order; zone coordinates
    # turned by -90 degrees about z ((x, y) -> (y, -x)), then moved to the origin
    expected = [[10, 20, 3], [10, 19, 3], [12, 20, 3]]
    assert np.allclose(scene.polygons[0], expected, rtol=0, atol=1e-14)
    # zone origin and north blank (0): the file's coordinates exactly
    assert scene.polygons[1].tolist() == [[0.1, 0, 0], [0.7, 0, 0], [0, 0.3, 0]]
    assert scene.groups == ("Attic", "Plain")
    assert scene.normals[1].tolist() == [0.0, 0.0, 1.0]    # clockwise from below: up


def test_idf_relative_outside_reverses_clockwise(tmp_path):
    scene = ef.read_idf(_write(tmp_path, "rel.idf", RELATIVE_IDF), facing="outside")
    assert scene.polygons[1].tolist() == [[0.1, 0, 0], [0, 0.3, 0], [0.7, 0, 0]]
    assert scene.normals[1].tolist() == [0.0, 0.0, -1.0]


@pytest.mark.parametrize("system", ["World", "absolute", ""])
def test_idf_world_absolute_and_default_relative(tmp_path, system):
    """World and Absolute read the vertices as they are; a blank Coordinate System is
    EnergyPlus's default, Relative (here with a zone at the origin: the same)."""
    text = (f"GlobalGeometryRules,UpperLeftCorner,Counterclockwise,{system};\n"
            "Zone, Z, 0, 0, 0, 0;  Version, 9.4;   ! two objects on a line\n"
            "BuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,\n"
            "  3   ! the count, its comma on the next line\n"
            "  , 0.5,0,0, 1,0,0, 0,1,0;\n")
    scene = ef.read_idf(_write(tmp_path, "w.idf", text), facing="outside")
    assert scene.polygons[0].tolist() == [[0.5, 0, 0], [1, 0, 0], [0, 1, 0]]


def test_idf_layout_without_version(tmp_path):
    """No Version object: the layout is the one that leaves whole x, y, z triples."""
    old = ("GlobalGeometryRules,UpperLeftCorner,Counterclockwise,World;\n"
           "BuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,3, 0,0,0, 1,0,0, 0,1,0;\n"
           "BuildingSurface:Detailed,B,Wall,C,Z,S,Outdoors,,,,,3, 0,0,5, 1,0,5, 0,1,5;\n"
           "Wall:Detailed,W,C,Z,Outdoors,,,,,3, 0,0,7, 0,1,7, 1,0,7;\n")
    scene = ef.read_idf(_write(tmp_path, "nov.idf", old), facing="outside")
    assert [P[0, 2] for P in scene.polygons] == [0, 5, 7]
    assert scene.names == ("A", "B", "W") and scene.materials == ("C", "C", "C")


@pytest.mark.parametrize("text, match", [
    ("Version,9.4;\nBuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,3,0,0,0,1,0,0,0,1,0;\n",
     r"x\.idf: no GlobalGeometryRules object"),
    ("GlobalGeometryRules,UpperLeftCorner,Sideways,World;\n",
     r"x\.idf:1: GlobalGeometryRules: Vertex Entry Direction"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,World;\nVersion,9.4;\n"
     "BuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,3,\n 0,0,0,\n 1,zero,0,\n 0,1,0;\n",
     r"x\.idf:5: BuildingSurface:Detailed 'A': vertex 2 y-coordinate: expected a finite "
     r"number, got 'zero'"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,World;\nVersion,9.4;\n"
     "BuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,4,0,0,0,1,0,0,0,1,0;\n",
     r"x\.idf:3: BuildingSurface:Detailed 'A': Number of Vertices is 4 but 3 vertices"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,World;\nVersion,9.4;\n"
     "BuildingSurface:Detailed,A,Wall,C,Z,Outdoors,,,,,3,0,0,0,1,0,0,0,1;\n",
     r"x\.idf:3: BuildingSurface:Detailed 'A': expected 9 fields, the vertex count"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,Relative;\nVersion,9.4;\n"
     "BuildingSurface:Detailed,A,Wall,C,Nowhere,Outdoors,,,,,3,0,0,0,1,0,0,0,1,0;\n",
     r"x\.idf:3: BuildingSurface:Detailed 'A': zone 'Nowhere' is not defined"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,World;\nZone,\n  Room\n",
     r"x\.idf:2: Zone: not ended by ';'"),
    ("GlobalGeometryRules,UpperLeftCorner,Clockwise,World;\nZone,\n  Room\n  Two;\n",
     r"x\.idf:4: two values in one field: 'Room' and 'Two'"),
    ("Version, nine;\nGlobalGeometryRules,UpperLeftCorner,Clockwise,World;\n",
     r"x\.idf:1: Version: expected a version such as '9\.6'"),
])
def test_idf_errors_name_file_line_object(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        ef.read_idf(_write(tmp_path, "x.idf", text))


def test_idf_ill_formed_polygon_names_line_and_surface(tmp_path):
    text = ("GlobalGeometryRules,UpperLeftCorner,Counterclockwise,World;\nVersion,9.4;\n\n"
            "BuildingSurface:Detailed,Flat,Wall,C,Z,Outdoors,,,,,3,0,0,0,1,0,0,2,0,0;\n")
    with pytest.raises(ef.SceneError, match=r"x\.idf:4: BuildingSurface:Detailed: polygon 0 "
                                            r"\('Flat'\): zero area"):
        ef.read_idf(_write(tmp_path, "x.idf", text))


def _parse_user_view_factors(text):
    """An independent reader of ZoneProperty:UserViewFactors:BySurfaceName: comments
    dropped, fields split at commas, the object ended by its semicolon."""
    body = "\n".join(line.split("!", 1)[0] for line in text.splitlines())
    objects = [o for o in body.split(";") if o.strip()]
    out = []
    for obj in objects:
        fields = [f.strip() for f in obj.split(",")]
        assert fields[0].lower() == "zoneproperty:userviewfactors:bysurfacename"
        triples = fields[2:]
        assert len(triples) % 3 == 0
        out.append((fields[1], [(triples[k], triples[k + 1], float(triples[k + 2]))
                                for k in range(0, len(triples), 3)]))
    return out


def test_energyplus_view_factors_round_trip(tmp_path):
    scene = _read_cube(tmp_path)
    F = ef.area_form_factors(scene, tolerance=1e-11)
    F[0, 2] = math.nextafter(F[0, 2], 1)    # a value only 17 digits tell apart
    p = tmp_path / "vf.idf"
    ef.write_energyplus_view_factors(p, F, names=scene, zone="Room")
    [(zone, triples)] = _parse_user_view_factors(p.read_text())
    assert zone == "Room" and len(triples) == 36
    names = list(scene.names)
    got = np.full((6, 6), np.nan)
    for a, b, v in triples:
        got[names.index(a), names.index(b)] = v
    assert np.array_equal(got, F)       # every pair, bit for bit
    assert [(a, b) for a, b, _ in triples[:3]] == [("Floor", "Floor"), ("Floor", "Ceiling"),
                                                   ("Floor", "South")]


def test_energyplus_view_factors_to_the_digits_written_and_append(tmp_path):
    F = np.array([[0.0, 1 / 3, 2 / 3], [0.5, 0.0, 0.5], [2 / 3, 1 / 3, 0.0]])
    p = tmp_path / "model.idf"
    p.write_text("Version, 9.4;\n")
    ef.write_energyplus_view_factors(p, F, names=["a", "b", "c"], zone="Z", fmt="%.6e",
                                     append=True)
    text = p.read_text()
    assert text.startswith("Version, 9.4;\n")
    [(_, triples)] = _parse_user_view_factors(text.split(";", 1)[1])
    assert [v for _, _, v in triples] == [float("%.6e" % x) for x in F.ravel()]


@pytest.mark.parametrize("kwargs, match", [
    (dict(names=["a", "A"]), r"names\[1\]: 'A' repeats names\[0\]"),
    (dict(names=["a", "b,c"]), r"names\[1\]: 'b,c' cannot be an EnergyPlus name"),
    (dict(names=["a"]), r"F: expected shape \(1, 1\)"),
    (dict(zone=" Room"), r"zone: ' Room' cannot be an EnergyPlus name"),
    (dict(fmt="%d %d"), r"fmt: expected a printf format for one float"),
])
def test_energyplus_view_factors_bad_arguments(tmp_path, kwargs, match):
    args = dict(names=["a", "b"], zone="Room") | kwargs
    with pytest.raises(ValueError, match=match):
        ef.write_energyplus_view_factors(tmp_path / "vf.idf", [[0, 1], [1, 0]], **args)
    with pytest.raises(ValueError, match=r"F: NaN or infinite value at row 0, column 1"):
        ef.write_energyplus_view_factors(tmp_path / "vf.idf", [[0, np.nan], [1, 0]],
                                         names=["a", "b"], zone="Room")


# ---------------------------------------------------------------------------------
# Radiance
# ---------------------------------------------------------------------------------
# A small scene in Radiance's conventions: materials before use, polygons counter-
# clockwise seen from their front, arguments over several lines, comments, a quoted
# string argument, and surfaces that are not polygons.
ROOM_RAD = """\
# room.rad: a floor, a wall and some furniture
void plastic grey
0
0
5 0.5 0.5 0.5 0 0

void brightfunc sky 2 skybright "sky file.cal" 0 0
grey alias wallmat grey

grey polygon floor
0
0
12
    0 0 0
    4 0 0
    4 3 0
    0 3 0

wallmat polygon north_wall 0 0 12 0 3 0  4 3 0  4 3 2.5  0 3 2.5   # a comment
grey sphere lamp 0 0 4 2 1.5 2.2 0.1
grey ring disk 0 0 8 1 1 0.01 0 0 1 0 0.3
grey cone shade 0 0 8 2 1.5 2 2 1.5 2.2 0.2 0.1
"""


def test_rad_polygons_names_modifiers_and_skipped(tmp_path):
    p = _write(tmp_path, "room.rad", ROOM_RAD)
    with pytest.warns(UserWarning, match=r"1 sphere, 1 ring, 1 cone"):
        scene = ef.load_scene(p)
    assert scene.names == ("floor", "north_wall")
    assert scene.materials == ("grey", "wallmat")
    assert scene.polygons[0].tolist() == [[0, 0, 0], [4, 0, 0], [4, 3, 0], [0, 3, 0]]
    assert scene.polygons[1].tolist() == [[0, 3, 0], [4, 3, 0], [4, 3, 2.5], [0, 3, 2.5]]
    # the right-hand normals: the floor faces up, the wall faces -y (into the room)
    assert scene.normals.tolist() == [[0, 0, 1], [0, -1, 0]]
    assert ef.describe(scene)["skipped_primitives"] == {"sphere": 1, "ring": 1, "cone": 1}


def test_info_says_what_was_not_read(tmp_path, capsys):
    from exactff.cli import main

    p = _write(tmp_path, "room.rad", ROOM_RAD)
    with pytest.warns(UserWarning):
        assert main(["info", str(p)]) == 0
    assert "not read         1 sphere, 1 ring, 1 cone (not polygons)" in capsys.readouterr().out


def test_rad_without_other_surfaces_warns_nothing(tmp_path):
    p = _write(tmp_path, "one.rad", "void polygon t 0 0 9 0 0 0 1 0 0 0 1 0\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = ef.read_rad(p)
    assert ef.describe(scene)["skipped_primitives"] == {} and scene.materials == ("void",)


@pytest.mark.parametrize("text, match", [
    ("void plastic m 0 0 5 1 1 1 0 0\nm polygon floor 0 0 8 0 0 0 1 0 0 0 1\n",
     r"x\.rad:2: polygon 'floor': a polygon needs 3 reals \(x y z\) for each of at least 3 "
     r"vertices, got 8"),
    ("void polygon floor\n0\nzero\n9 0 0 0 1 0 0 0 1 0\n",
     r"x\.rad:3: polygon 'floor': expected the number of integer arguments, got 'zero'"),
    ("void polygon floor 0 0 9 0 0 0\n1 0 0\n0 1.o 0\n",
     r"x\.rad:3: polygon 'floor': a coordinate: expected a finite number, got '1\.o'"),
    ("void polygon floor 0 0 9 0 0 0 1 0 0\n",
     r"x\.rad:1: polygon 'floor': the file ends inside its 9 real arguments \(read 6\)"),
    ("void polygon floor 1 s 0 9 0 0 0 1 0 0 0 1 0\n",
     r"x\.rad:1: polygon 'floor': a polygon has no string or integer arguments"),
    ("!genbox grey box 1 1 1\n", r"x\.rad:1: inline command '!genbox': exactff runs no "
                                 r"commands"),
    ("void polygon\n", r"x\.rad:1: a primitive needs a modifier, a type and an identifier"),
])
def test_rad_errors_name_file_line_primitive(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        ef.read_rad(_write(tmp_path, "x.rad", text))


def test_rad_ill_formed_polygon_names_line_and_identifier(tmp_path):
    text = "# c\nvoid polygon ok 0 0 9 0 0 0 1 0 0 0 1 0\nvoid polygon flat 0 0 9 0 0 0 1 0 0 2 0 0\n"
    with pytest.raises(ef.SceneError, match=r"x\.rad:3: polygon: polygon 1 \('flat'\): zero area"):
        ef.read_rad(_write(tmp_path, "x.rad", text))


# ---------------------------------------------------------------------------------
# Elmer and OpenFOAM
# ---------------------------------------------------------------------------------
def _box_matrix():
    """An exact matrix of a closed room (rows sum to 1), with a few tiny entries and a
    value that only 17 digits tell apart."""
    scene = ef.scenes.subdivided_box(1)
    F = ef.area_form_factors(scene, tolerance=1e-11)
    F[0, 1] = math.nextafter(F[0, 1], 1)
    return F


def _read_elmer(path, n):
    """An independent reader of ViewFactors.dat: per row a count, then 'i j F' lines."""
    with open(path) as fh:
        words = fh.read().split()
    F, at = np.zeros((n, n)), 0
    for i in range(1, n + 1):
        k = int(words[at])
        at += 1
        for _ in range(k):
            row, col, value = int(words[at]), int(words[at + 1]), float(words[at + 2])
            assert row == i and 1 <= col <= n and F[i - 1, col - 1] == 0
            F[i - 1, col - 1] = value
            at += 3
    assert at == len(words)
    return F


def test_elmer_round_trip(tmp_path):
    F = _box_matrix()
    p = tmp_path / "ViewFactors.dat"
    ef.write_elmer_view_factors(p, F)
    back = _read_elmer(p, len(F))
    assert np.array_equal(back, np.where(F > 0, F, 0.0))
    assert np.array_equal(back, F)          # a box face sees itself with exactly 0


def test_elmer_min_factor_and_sparse_input(tmp_path):
    F = np.array([[0.0, 0.7, 0.3 - 1e-9, 1e-9], [0.25, 0.0, 0.5, 0.25],
                  [1e-12, 0.5, 0.0, 0.5 - 1e-12], [0.2, 0.2, 0.6, 0.0]])
    p = tmp_path / "ViewFactors.dat"
    ef.write_elmer_view_factors(p, scipy.sparse.csr_matrix(F), min_factor=1e-6)
    back = _read_elmer(p, 4)
    assert np.array_equal(back, np.where(F > 1e-6, F, 0.0))
    with open(p) as fh:
        assert fh.readline() == "2\n"    # row 1 keeps 0.7 and 0.3 - 1e-9
    with pytest.raises(ValueError, match=r"min_factor: expected a finite number >= 0"):
        ef.write_elmer_view_factors(p, F, min_factor=-1)


def _read_foam(path):
    """An independent reader of an OpenFOAM ASCII list of lists: its FoamFile header as
    a dict, then the rows (each 'k(v v ...)')."""
    with open(path) as fh:
        text = fh.read()
    header = dict(re.findall(r"^\s+(\w+)\s+\"?([^\";]+)\"?;", text.split("}", 1)[0], re.M))
    body = re.sub(r"//[^\n]*", "", text.split("}", 1)[1])
    m = re.match(r"\s*(\d+)\s*\((.*)\)\s*$", body, re.S)
    n, rows = int(m.group(1)), re.findall(r"(\d+)\(([^()]*)\)", m.group(2))
    assert len(rows) == n
    out = []
    for k, values in rows:
        values = values.split()
        assert len(values) == int(k)
        out.append(values)
    return header, out


def test_openfoam_round_trip(tmp_path):
    F = _box_matrix()
    f_path, g_path = ef.write_openfoam_view_factors(tmp_path, F, patches=[
        "floor"] * 2 + ["walls"] * (len(F) - 2), min_factor=0.0)
    assert f_path == str(tmp_path / "constant" / "F")
    hf, Frows = _read_foam(f_path)
    hg, Grows = _read_foam(g_path)
    assert (hf["class"], hf["object"], hf["location"]) == ("scalarListList", "F", "constant")
    assert (hg["class"], hg["object"]) == ("labelListList", "globalFaceFaces")
    back = np.zeros_like(F)
    for i, (js, vs) in enumerate(zip(Grows, Frows)):
        assert len(js) == len(vs)
        for j, v in zip(js, vs):
            back[i, int(j)] = float(v)
    assert np.array_equal(back, F)
    with open(f_path) as fh:
        text = fh.read()
    assert f"// patch floor: faces 0 to 1\n// patch walls: faces 2 to {len(F) - 1}\n" in text


def test_openfoam_region_min_factor_and_patches(tmp_path):
    F = np.array([[0.0, 0.9, 0.1], [0.5, 0.0, 0.5], [1e-8, 1 - 1e-8, 0.0]])
    f_path, g_path = ef.write_openfoam_view_factors(tmp_path, F, region="air",
                                                    min_factor=1e-6, fmt="%.3g")
    assert f_path == str(tmp_path / "constant" / "air" / "F")
    hf, Frows = _read_foam(f_path)
    _, Grows = _read_foam(g_path)
    assert hf["location"] == "constant/air"
    assert Grows == [["1", "2"], ["0", "2"], ["1"]]
    assert [[float(v) for v in r] for r in Frows] == [[0.9, 0.1], [0.5, 0.5], [1.0]]
    with pytest.raises(ValueError, match=r"patches\[2\]: 'a' again after 'b'"):
        ef.write_openfoam_view_factors(tmp_path, F, patches=["a", "b", "a"])
    with pytest.raises(ValueError, match=r"patches: expected one patch name per face \(3\)"):
        ef.write_openfoam_view_factors(tmp_path, F, patches=["a"])


# ---------------------------------------------------------------------------------
# pandas
# ---------------------------------------------------------------------------------
def test_to_dataframe_labels_and_values(tmp_path):
    scene = _read_cube(tmp_path)
    F = ef.area_form_factors(scene, tolerance=1e-11)
    df = ef.to_dataframe(F, scene)
    assert list(df.index) == list(scene.names) == list(df.columns)
    assert df.index.name == "from" and df.columns.name == "to"
    assert np.array_equal(df.to_numpy(), F)
    assert abs(df.loc["Floor", "Ceiling"] - CUBE_OPPOSITE) < VIEW3D_DIGITS
    rows = ef.area_form_factors(scene, rows=[4, 1], tolerance=1e-11)
    part = ef.to_dataframe(rows, scene, rows=[4, 1])
    assert list(part.index) == ["North", "Ceiling"]
    assert np.array_equal(part.to_numpy(), rows)


def test_to_dataframe_without_names_and_sparse():
    scene = ef.Scene.from_polygons(ef.scenes.subdivided_box(1).polygons)   # no labels
    F = ef.area_form_factors(scene, tolerance=1e-11)
    assert list(ef.to_dataframe(F).index) == list(range(len(F)))
    assert list(ef.to_dataframe(F, scene).columns) == list(range(len(F)))
    S = scipy.sparse.csr_matrix(F)
    sdf = ef.to_dataframe(S)
    assert np.array_equal(sdf.sparse.to_dense().to_numpy(), F)


def test_to_dataframe_bad_arguments():
    scene = ef.scenes.subdivided_box(1)
    n = len(scene)
    with pytest.raises(ValueError, match=rf"F: {n - 1} columns, but the scene has {n}"):
        ef.to_dataframe(np.zeros((n - 1, n - 1)), scene)
    with pytest.raises(ValueError, match=r"give rows="):
        ef.to_dataframe(np.zeros((2, n)), scene)
    with pytest.raises(ValueError, match=rf"rows: index {n} out of range"):
        ef.to_dataframe(np.zeros((1, n)), scene, rows=[n])
