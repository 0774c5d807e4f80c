"""View3D, complete (issue 32 item 1): the F 3 and F 3a input formats with every control
value and surface kind, combined surfaces, subsurfaces, masks and null surfaces
(``area_form_factors(..., combine=True)``), ``.vs3`` written from a scene, and View3D's
output file written from a matrix.

The references: View3D's manual (the cube's 0.199824896 and 0.200043776 and its output
file; the L-shaped room in both formats), and polygons that make the same surfaces
directly (an L-shaped polygon for three combined rectangles, a U-shaped wall for a wall
with a door in it), computed without any combination.
"""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import exactff as ef

DATA = Path(__file__).parent / "data" / "view3d"
TOL = 1e-6


def quad(x0, x1, y0, y1, z=0.0, up=True):
    q = [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]
    return q if up else q[::-1]


def write(tmp_path, text, name="t.vs3"):
    path = tmp_path / name
    path.write_text(text)
    return path


def vs3_text(polys, kinds=None, extra="", control="encl=0"):
    """An F 3 file: ``polys`` with ``(kind, base, cmb, name)`` records."""
    lines = [f"T test", f"C {control}", "F 3"]
    k = 0
    for P in polys:
        for v in P:
            k += 1
            lines.append(f"V {k} " + " ".join(repr(float(c)) for c in v))
    k = 0
    for n, P in enumerate(polys, start=1):
        ids = list(range(k + 1, k + 1 + len(P)))
        k += len(P)
        ids = ids + [0] if len(ids) == 3 else ids
        kind, base, cmb, name = (kinds or {}).get(n, ("S", 0, 0, f"s{n}"))
        if kind == "O":
            lines.append(f"O {n} " + " ".join(map(str, ids)))
        else:
            lines.append(f"{kind} {n} " + " ".join(map(str, ids)) + f" {base} {cmb} 0.9 {name}")
    return "\n".join(lines) + "\n" + extra + "End of data\n"


# --- the manual's examples ---------------------------------------------------------------

def test_cube_as_in_the_manual(tmp_path):
    scene = ef.read_vs3(DATA / "cube.vs3")
    F = ef.area_form_factors(scene, tolerance=1e-6, combine=True)
    assert F.shape == (6, 6)
    opposite = np.array([F[i, (i + 3) % 6] for i in range(6)])
    adjacent = np.array([F[i, j] for i in range(6) for j in range(6)
                         if j != i and j != (i + 3) % 6])
    assert np.abs(opposite - 0.199824896).max() < 1e-9
    assert np.abs(adjacent - 0.200043776).max() < 1e-9
    # the output file of the manual, byte for byte, in View3D's own formats
    out = tmp_path / "cube.out"
    ef.write_view3d_factors(out, F, scene, fmt="view3d", program="View3D", version="3.3.1")
    assert out.read_text() == (DATA / "cube.out").read_text()


def test_l_room_f3_and_f3a_agree_and_combine_to_8_surfaces():
    a, b = ef.read_vs3(DATA / "l_room_f3.vs3"), ef.read_vs3(DATA / "l_room_f3a.vs3")
    va, vb = a.metadata["view3d"], b.metadata["view3d"]
    assert (va["format"], vb["format"]) == ("3", "3a")
    assert va["control"]["encl"] == 1 and va["control"]["emit"] == 1
    assert va["control"]["maxU"] == 8 and vb["control"]["eps"] == 1e-5
    assert any("maxU=8" in n and "ignored" in n for n in va["notes"])
    assert [s["cmb"] for s in va["surfaces"]] == [0] * 8 + [7, 7, 8, 8]
    assert [s["shape"] for s in vb["surfaces"]] == list("RRRRRRQQQQQQ")
    # the same polygons: vertex by vertex within the rounding of the placement's sines
    for P, Q in zip(a.polygons, b.polygons):
        d = np.abs(P[:, None, :] - Q[None, :, :]).max(axis=2)
        assert d.min(axis=1).max() < 1e-14 and len(P) == len(Q)
    Fa, Ea = ef.area_form_factors(a, tolerance=TOL, combine=True, error=True)
    Fb = ef.area_form_factors(b, tolerance=TOL, combine=True)
    assert Fa.shape == Fb.shape == (8, 8)
    assert np.abs(Fa - Fb).max() < 4 * TOL
    assert np.abs(Fa.sum(axis=1) - 1).max() < 8 * TOL and Ea.max() <= TOL
    c = ef.combined_surfaces(a)
    assert c.names == tuple(f"srf-{k}" for k in range(1, 9))
    np.testing.assert_allclose(c.areas, [9, 3, 6, 6, 3, 9, 5, 5], rtol=1e-15)
    # reciprocity of the combined surfaces
    AF = c.areas[:, None] * Fa
    assert np.abs(AF - AF.T).max() < 10 * TOL
    # the ceiling and floor as one L-shaped polygon each: no combination at all
    P = [np.asarray(p) for p in a.polygons]
    ceiling = [[0, 0, 3], [0, 3, 3], [1, 3, 3], [1, 1, 3], [3, 1, 3], [3, 0, 3]]
    floor = [[0, 0, 0], [3, 0, 0], [3, 1, 0], [1, 1, 0], [1, 3, 0], [0, 3, 0]]
    direct = ef.Scene.from_polygons(P[:6] + [ceiling, floor])
    np.testing.assert_allclose(direct.areas[6:], [5, 5])
    D, DE = ef.area_form_factors(direct, tolerance=TOL, error=True)
    assert np.all(np.abs(Fa - D) <= Ea + DE + 1e-13)


def test_obstructions_have_no_row_or_column(tmp_path):
    lo, hi, mid = quad(0, 1, 0, 1), quad(0, 1, 0, 1, 1, up=False), quad(0, .5, 0, .5, .5)
    scene = ef.read_vs3(write(tmp_path, vs3_text([lo, hi, mid], {3: ("O", 0, 0, "")})))
    assert scene.groups == (None, None, "obstruction")
    F = ef.area_form_factors(scene, tolerance=TOL, combine=True)
    raw = ef.area_form_factors(scene, tolerance=TOL)
    assert F.shape == (2, 2)
    np.testing.assert_allclose(F, raw[:2, :2], rtol=0, atol=1e-15)


# --- subsurfaces, masks, null surfaces ----------------------------------------------------

def _room_with_wall(wall, extra):
    """A closed 4 x 3 x 3 room whose y = 0 wall is ``wall``, plus ``extra`` polygons."""
    floor = quad(0, 4, 0, 3, 0)
    ceiling = quad(0, 4, 0, 3, 3, up=False)
    back = [[0, 3, 0], [0, 3, 3], [4, 3, 3], [4, 3, 0]][::-1]
    left = [[0, 0, 0], [0, 0, 3], [0, 3, 3], [0, 3, 0]][::-1]
    right = [[4, 0, 0], [4, 3, 0], [4, 3, 3], [4, 0, 3]][::-1]
    return [floor, ceiling, back, left, right, wall] + extra


# the y = 0 wall, facing +y (into the room), a door in it, and the wall around the door
WALL = [[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3]][::-1]
DOOR = [[1, 0, 0], [2, 0, 0], [2, 0, 2], [1, 0, 2]][::-1]
WALL_WITHOUT_DOOR = [[0, 0, 0], [1, 0, 0], [1, 0, 2], [2, 0, 2], [2, 0, 0], [4, 0, 0],
                     [4, 0, 3], [0, 0, 3]][::-1]


def test_subsurface_is_separated_from_its_base(tmp_path):
    polys = _room_with_wall(WALL, [DOOR])
    scene = ef.read_vs3(write(tmp_path, vs3_text(polys, {7: ("S", 6, 0, "door")},
                                                 control="encl=1")))
    F, E = ef.area_form_factors(scene, tolerance=TOL, combine=True, error=True)
    direct = ef.Scene.from_polygons(_room_with_wall(WALL_WITHOUT_DOOR, [DOOR]))
    D, DE = ef.area_form_factors(direct, tolerance=TOL, error=True)
    assert F.shape == D.shape == (7, 7)
    assert np.all(np.abs(F - D) <= E + DE + 1e-13)
    np.testing.assert_allclose(ef.combined_surfaces(scene).areas[5:], [10, 2], rtol=1e-14)
    assert np.abs(F.sum(axis=1) - 1).max() < 10 * TOL


def test_window_in_a_wall_equals_four_combined_rectangles(tmp_path):
    window = [[1, 0, 1], [2, 0, 1], [2, 0, 2], [1, 0, 2]][::-1]
    sub = ef.read_vs3(write(tmp_path, vs3_text(_room_with_wall(WALL, [window]),
                                               {7: ("S", 6, 0, "window")}), "sub.vs3"))
    parts = [p[::-1] for p in ([[0, 0, 0], [1, 0, 0], [1, 0, 3], [0, 0, 3]],
                               [[1, 0, 0], [2, 0, 0], [2, 0, 1], [1, 0, 1]],
                               [[1, 0, 2], [2, 0, 2], [2, 0, 3], [1, 0, 3]],
                               [[2, 0, 0], [4, 0, 0], [4, 0, 3], [2, 0, 3]])]
    polys = _room_with_wall(parts[0], [window] + parts[1:])
    kinds = {7: ("S", 0, 0, "window"), 8: ("S", 0, 6, "a"), 9: ("S", 0, 6, "b"),
             10: ("S", 0, 6, "c")}
    cmb = ef.read_vs3(write(tmp_path, vs3_text(polys, kinds), "cmb.vs3"))
    F, E = ef.area_form_factors(sub, tolerance=TOL, combine=True, error=True)
    G, GE = ef.area_form_factors(cmb, tolerance=TOL, combine=True, error=True)
    assert F.shape == G.shape == (7, 7)
    assert np.all(np.abs(F - G) <= E + GE + 1e-13)


def test_mask_and_null_surface(tmp_path):
    mask = DOOR[::-1]                       # faces against its base, lies on it
    room = _room_with_wall(WALL, [mask])
    direct = ef.Scene.from_polygons(_room_with_wall(WALL_WITHOUT_DOOR, []))
    D, DE = ef.area_form_factors(direct, tolerance=TOL, error=True)
    # a null surface: its part of the wall is gone (neither emits nor receives)
    nul = ef.read_vs3(write(tmp_path, vs3_text(room, {7: ("N", 6, 0, "hole")}), "n.vs3"))
    assert nul.groups[6] == "null"
    F, E = ef.area_form_factors(nul, tolerance=TOL, combine=True, error=True)
    assert F.shape == (6, 6) and np.all(np.abs(F - D) <= E + DE + 1e-13)
    assert ef.combined_surfaces(nul).areas[5] == pytest.approx(10, rel=1e-14)
    # a mask: the wall keeps its area and sees the mask, the mask sees only the wall
    msk = ef.read_vs3(write(tmp_path, vs3_text(room, {7: ("M", 6, 0, "cover")}), "m.vs3"))
    F, E = ef.area_form_factors(msk, tolerance=TOL, combine=True, error=True)
    c = ef.combined_surfaces(msk)
    assert F.shape == (7, 7) and c.names[6] == "cover"
    np.testing.assert_allclose(c.areas[5:], [12, 2], rtol=1e-14)
    np.testing.assert_allclose(F[6], [0, 0, 0, 0, 0, 1, 0], rtol=0, atol=1e-15)
    assert F[5, 6] == pytest.approx(2 / 12, rel=1e-14)
    np.testing.assert_array_equal(F[:5, 6], 0)
    # the wall's row: its unmasked part, over its whole area
    assert np.all(np.abs(F[5, :5] - D[5, :5] * 10 / 12) <= E[5, :5] + DE[5, :5] + 1e-13)
    assert np.all(np.abs(F[:5, :6] - D[:5, :6]) <= E[:5, :6] + DE[:5, :6] + 1e-13)
    # the wall's and the mask's rows sum to 1; what the others send to the mask's back
    # is lost, as in View3D (the room with a hole in the wall, D)
    assert np.abs(F[5:].sum(axis=1) - 1).max() < 10 * TOL


@pytest.mark.parametrize("kinds,poly,needle", [
    ({7: ("S", 6, 0, "x")}, [[1, 0.1, 1], [2, 0.1, 1], [2, 0.1, 2], [1, 0.1, 2]],
     "not in the plane of its base"),
    ({7: ("S", 6, 0, "x")}, [[1, 0, 1], [2, 0, 1], [2, 0, 2], [1, 0, 2]],
     "should face the same way"),
    ({7: ("M", 6, 0, "x")}, [[1, 0, 1], [1, 0, 2], [2, 0, 2], [2, 0, 1]], "face against"),
    ({7: ("S", 6, 0, "x")}, [[3, 0, 1], [3, 0, 2], [5, 0, 2], [5, 0, 1]],
     "not within its base"),
])
def test_subsurface_errors_name_the_line(tmp_path, kinds, poly, needle):
    path = write(tmp_path, vs3_text(_room_with_wall(WALL, [poly]), kinds))
    with pytest.raises(ValueError, match=re.escape(needle)) as info:
        ef.read_vs3(path)
    line = 3 + 4 * 7 + 7                    # title, control, format, vertices, surface 7
    assert f"{path}:{line}: surface 7" in str(info.value)


# --- control values ----------------------------------------------------------------------

def test_row_control_selects_the_row_and_encl_checks_the_sums(tmp_path):
    room = _room_with_wall(WALL, [])
    scene = ef.read_vs3(write(tmp_path, vs3_text(room, control="encl=1 row=3")))
    F = ef.area_form_factors(scene, tolerance=TOL, combine=True)
    full = ef.area_form_factors(scene, rows=range(6), tolerance=TOL, combine=True)
    assert F.shape == (1, 6)
    np.testing.assert_array_equal(F[0], full[2])
    # encl=1 on a room with a missing wall: the rows do not sum to 1
    open_room = ef.read_vs3(write(tmp_path, vs3_text(room[:5], control="encl=1"), "o.vs3"))
    with pytest.warns(UserWarning, match="encl=1"):
        ef.area_form_factors(open_room, tolerance=1e-6, combine=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ef.area_form_factors(scene, rows=[0], tolerance=1e-6, combine=True)


def test_control_line_is_read_as_view3d_reads_it(tmp_path):
    text = vs3_text([quad(0, 1, 0, 1)], control="eps=1e-6, MAXU=10 minO = 1 emit=1 foo=3 out=1")
    v3 = ef.read_vs3(write(tmp_path, text)).metadata["view3d"]
    c = v3["control"]
    assert (c["eps"], c["maxU"], c["minO"], c["emit"], c["out"], c["maxO"]) == \
        (1e-6, 10, 1, 1, 1, 8)
    notes = " ".join(v3["notes"])
    assert "'foo'" in notes and "maxU=10" in notes and "minO=1" in notes and "eps" in notes


# --- errors ------------------------------------------------------------------------------

@pytest.mark.parametrize("line,needle", [
    ("F 2", "F 3 and F 3a"),
    ("S 2 1 2 3 4 0 0", "emissivity: 'End' (line 9) is not a number"),   # as View3D
    ("S 2 1 2 3 9 0 0 0.9 x", "vertex 9 is not defined"),
    ("S 2 1 2 3 4 3 0 0.9 x", "base surface 3 does not exist"),
    ("S 2 1 2 3 4 0 2 0.9 x", "combine a surface with one before it"),
    ("M 2 1 2 3 4 0 0 0.9 x", "needs a base"),
    ("S 2 1 2 3 4 0 0 abc x", "'abc' is not a number"),
    ("C encl=yes", "not an integer"),
    ("Q 2", "unknown keyword"),
])
def test_errors_name_the_file_and_line(tmp_path, line, needle):
    text = "T t\nF 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 1 1 0\nV 4 0 1 0\nS 1 1 2 3 4 0 0 0.9 a\n"
    path = write(tmp_path, text + line + "\nEnd\n")
    with pytest.raises(ValueError, match=re.escape(needle)) as info:
        ef.read_vs3(path)
    assert str(info.value).startswith(f"{path}:")


def test_chained_combination_and_obstruction_order_are_refused(tmp_path):
    P = [quad(0, 1, 0, 1), quad(1, 2, 0, 1), quad(2, 3, 0, 1)]
    chain = vs3_text(P, {2: ("S", 0, 1, "b"), 3: ("S", 0, 2, "c")})
    with pytest.raises(ValueError, match="chain"):
        ef.read_vs3(write(tmp_path, chain, "a.vs3"))
    early = vs3_text(P, {1: ("O", 0, 0, "")})
    with pytest.raises(ValueError, match="obstruction surface 1 out of sequence"):
        ef.read_vs3(write(tmp_path, early, "b.vs3"))


# --- writing .vs3 ------------------------------------------------------------------------

def _same_polygons(a, b):
    return len(a) == len(b) and all(P.shape == Q.shape and P.tobytes() == Q.tobytes()
                                    for P, Q in zip(a.polygons, b.polygons))


@pytest.mark.parametrize("source", ["cube.vs3", "l_room_f3.vs3", "l_room_f3a.vs3"])
def test_write_vs3_round_trips_view3d_files(tmp_path, source):
    scene = ef.read_vs3(DATA / source)
    ef.write_vs3(scene, tmp_path / "w.vs3")
    back = ef.read_vs3(tmp_path / "w.vs3")
    assert _same_polygons(scene, back) and back.names == scene.names
    a, b = scene.metadata["view3d"], back.metadata["view3d"]
    assert b["control"] == a["control"] and b["title"] == a["title"]
    keys = ("number", "kind", "base", "cmb", "emit", "name")
    assert [{k: s[k] for k in keys} for s in a["surfaces"]] == \
        [{k: s[k] for k in keys} for s in b["surfaces"]]


def test_write_vs3_round_trips_subsurfaces_masks_and_odd_coordinates(tmp_path):
    wall = np.array(WALL, dtype=float) + [0.1, -1e-300, 1 / 3]
    door = np.array(DOOR, dtype=float) + [0.1, -1e-300, 1 / 3]
    polys = [quad(-0.0, 0.1, 1e-17, 7.3), wall, door, door[::-1], quad(5, 6, 5, 6, 1)]
    kinds = {3: ("S", 2, 0, "door"), 4: ("M", 3, 0, "m"), 5: ("O", 0, 0, "")}
    scene = ef.read_vs3(write(tmp_path, vs3_text(polys, kinds)))
    ef.write_vs3(scene, tmp_path / "w.vs3")
    back = ef.read_vs3(tmp_path / "w.vs3")
    assert _same_polygons(scene, back)
    assert [(s["kind"], s["base"]) for s in back.metadata["view3d"]["surfaces"]] == \
        [("S", 0), ("S", 0), ("S", 2), ("M", 3), ("O", 0)]


def test_write_vs3_of_any_scene(tmp_path):
    box = ef.scenes.subdivided_box(2)
    ef.write_vs3(box, tmp_path / "box.vs3")
    back = ef.read_vs3(tmp_path / "box.vs3")
    assert _same_polygons(box, back)
    # a hexagon and a non-convex quadrilateral: refused, or written as convex pieces
    hexagon = [[np.cos(t), np.sin(t), 0] for t in np.linspace(0, 2 * np.pi, 7)[:-1]]
    dart = [[0, 0, 1], [0, 2, 1], [0.5, 0.5, 1], [2, 0, 1]]
    scene = ef.Scene.from_polygons([hexagon, dart], names=["hex agon", None])
    with pytest.raises(ValueError, match="polygon 0 .hex agon.: View3D takes triangles"):
        ef.write_vs3(scene, tmp_path / "x.vs3")
    ef.write_vs3(scene, tmp_path / "x.vs3", split=True)
    pieces = ef.read_vs3(tmp_path / "x.vs3")
    assert len(pieces) > 2 and pieces.names[0] == "hex_agon"
    F, E = ef.area_form_factors(pieces, tolerance=TOL, combine=True, error=True)
    D, DE = ef.area_form_factors(scene, tolerance=TOL, error=True)
    assert F.shape == (2, 2) and np.all(np.abs(F - D) <= E + DE + 1e-13)


# --- View3D's output file ----------------------------------------------------------------

def _parse_view3d_output(text):
    """An independent reader of View3D's text output (as its ReadF0s reads it): the
    header's words, then whitespace-separated numbers."""
    head, rest = text.split("\n", 1)
    program, version, fmt, encl, emit, n = head.split()
    n = int(n)
    v = [float(w) for w in rest.split()]
    return (program, int(fmt), int(encl), int(emit), np.array(v[:n]),
            np.array(v[n:n + n * n]).reshape(n, n), np.array(v[n + n * n:]))


def test_view3d_output_full_precision_round_trip(tmp_path):
    scene = ef.read_vs3(DATA / "l_room_f3.vs3")
    F = ef.area_form_factors(scene, tolerance=1e-6, combine=True)
    path = tmp_path / "room.vf"
    ef.write_view3d_factors(path, F, scene, emit=False)
    text = path.read_text()
    assert len(text.split("\n")[0]) == 30
    program, fmt, encl, emit, A, G, eps = _parse_view3d_output(text)
    assert (program, fmt, encl, emit) == ("exactff", 0, 1, 0)
    np.testing.assert_array_equal(G, F)
    np.testing.assert_array_equal(A, ef.combined_surfaces(scene).areas)
    np.testing.assert_array_equal(eps, [0.9] * 8)
    got = ef.read_view3d_factors(path)
    np.testing.assert_array_equal(got["F"], F)
    # the file's emit=1: script-F, as View3D writes it; rows sum to the emissivities
    ef.write_view3d_factors(path, F, scene)
    program, fmt, encl, emit, A, S, eps = _parse_view3d_output(path.read_text())
    assert emit == 1
    np.testing.assert_array_equal(S, ef.script_f(F, A, eps))
    assert np.abs(S.sum(axis=1) - 0.9).max() < 1e-5
    # binary (out=1): float32 values after a 32-byte header
    ef.write_view3d_factors(path, F, scene, binary=True, emit=False)
    raw = path.read_bytes()
    assert raw[30:32] == b"\r\n" and len(raw) == 32 + 4 * (8 * 8 + 16)
    got = ef.read_view3d_factors(path)
    assert got["format"] == 1
    np.testing.assert_array_equal(got["F"], F.astype(np.float32))
    with pytest.raises(ValueError, match="8 surfaces"):
        ef.write_view3d_factors(path, F[:7, :7], scene)


def test_script_f():
    rng = np.random.default_rng(3)
    box = ef.scenes.subdivided_box(1)
    F = ef.area_form_factors(box, tolerance=1e-12)
    A, eps = box.areas, rng.uniform(0.1, 1.0, 6)
    S = ef.script_f(F, A, eps)
    np.testing.assert_allclose(S.sum(axis=1), eps, rtol=1e-12)
    np.testing.assert_allclose(A[:, None] * S, (A[:, None] * S).T, rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(ef.script_f(F, A, np.ones(6)), F, rtol=0, atol=1e-15)
    # View3D's algorithm (Hottel and Sarofim; viewpp.c IntFac), independently: the
    # radiosities of unit emissive power at one surface, the others at zero
    rho = 1 - eps
    for i in range(6):
        E = np.zeros(6)
        E[i] = eps[i]
        J = np.linalg.solve(np.eye(6) - rho[:, None] * F, E)
        absorbed = eps * (F @ J)                      # per area: eps_j H_j
        np.testing.assert_allclose(A * absorbed / A[i], S[i], rtol=1e-12, atol=1e-15)


def test_command_line(tmp_path, capsys):
    from exactff.cli import main

    path = str(DATA / "cube.vs3")
    assert main(["info", path]) == 0
    assert "View3D           format F 3; 6 surfaces" in capsys.readouterr().out
    out = str(tmp_path / "cube.npy")
    assert main(["matrix", path, "--area", "--combine", "--tolerance", "1e-6", "-o", out,
                 "--no-progress"]) == 0
    assert "6 x 6 area-to-area, the surfaces View3D reports" in capsys.readouterr().out
    F = np.load(out)
    assert abs(F[0, 3] - 0.199824896) < 1e-9
    assert main(["matrix", path, "--combine"]) == 2
    assert "--combine" in capsys.readouterr().err
