"""Readers of other tools' view-factor matrices: each reads back what its writer wrote,
onto the scene's polygon order, and refuses a matrix whose surfaces do not match."""

import os

import numpy as np
import pytest
import scipy.sparse as sp

import exactff as ef
from exactff.io.view_factors import guess_view_factor_format


@pytest.fixture(scope="module")
def room():
    """box:1 with names and groups (a room of six walls) and a matrix with distinct,
    non-symmetric values (so that a permuted read differs)."""
    box = ef.scenes.subdivided_box(1)
    names = ["Floor", "Ceiling", "WallA", "WallB", "WallC", "WallD"]
    scene = ef.Scene.from_polygons(box.polygons, names=names,
                                   groups=["floor", "ceiling"] + ["walls"] * 4)
    F = ef.area_form_factors(scene) + np.arange(36).reshape(6, 6) * 1e-3
    np.fill_diagonal(F, 0.0)
    return scene, F


def test_view3d_text_and_binary_round_trip(room, tmp_path):
    scene, F = room
    ef.write_view3d_factors(tmp_path / "t.vf", F, scene)
    assert guess_view_factor_format(tmp_path / "t.vf") == "view3d"
    assert np.array_equal(ef.read_view_factors(tmp_path / "t.vf", scene), F)
    ef.write_view3d_factors(tmp_path / "b.vf", F, scene, binary=True)
    got = ef.read_view_factors(tmp_path / "b.vf", scene)
    # float32 in the file: within its rounding
    np.testing.assert_allclose(got, F, rtol=2 ** -24, atol=0)
    assert not np.array_equal(got, F)
    ef.write_view3d_factors(tmp_path / "v.vf", F, scene, fmt="view3d")   # %.6f
    np.testing.assert_allclose(ef.read_view_factors(tmp_path / "v.vf", scene), F,
                               rtol=0, atol=5e-7)


def test_view3d_refuses_another_order_or_size(room, tmp_path):
    scene, F = room
    # surfaces in another order: the areas say so (the Cornell box's differ)
    cornell = ef.scenes.cornell_box()
    n = len(cornell)
    ef.write_view3d_factors(tmp_path / "o.vf", np.zeros((n, n)), cornell)
    assert ef.read_view_factors(tmp_path / "o.vf", cornell).shape == (n, n)
    swapped = ef.Scene.from_polygons([cornell.polygons[k] for k in [1, 0] + list(range(2, n))])
    with pytest.raises(ValueError, match="surface 1 has area .* but polygon 0 of the scene "
                                         ".* in another order"):
        ef.read_view_factors(tmp_path / "o.vf", swapped)
    ef.write_view3d_factors(tmp_path / "r.vf", F, scene)
    with pytest.raises(ValueError, match="6 surfaces, but the scene has 24 polygons"):
        ef.read_view_factors(tmp_path / "r.vf", ef.scenes.subdivided_box(2))
    ef.write_view3d_factors(tmp_path / "e.vf", F, scene, emit=True,
                            emissivities=np.full(6, 0.9))
    with pytest.raises(ValueError, match="emit=1"):
        ef.read_view_factors(tmp_path / "e.vf", scene)


def test_openfoam_round_trip(room, tmp_path):
    scene, F = room
    ef.write_openfoam_view_factors(tmp_path, F, patches=scene)
    assert guess_view_factor_format(tmp_path) == "openfoam"
    G, patches = ef.read_openfoam_view_factors(tmp_path)
    assert patches == list(scene.groups)
    got = ef.read_view_factors(tmp_path, scene)
    assert sp.issparse(got) and np.array_equal(got.toarray(), F)
    # the F file's path does too; zeros left out (the diagonal)
    got = ef.read_view_factors(tmp_path / "constant" / "F", scene)
    assert got.nnz == 30
    ef.write_openfoam_view_factors(tmp_path / "r", F, region="air", min_factor=0.05)
    got = ef.read_openfoam_view_factors(tmp_path / "r", region="air")[0]
    assert np.array_equal(got.toarray(), np.where(F > 0.05, F, 0.0))


def test_openfoam_refuses_other_patches_or_files(room, tmp_path):
    scene, F = room
    patches = ["walls"] * 4 + ["floor", "ceiling"]
    ef.write_openfoam_view_factors(tmp_path, F, patches=patches)
    with pytest.raises(ValueError, match="face 0 is on patch 'walls' but polygon 0 of the "
                                         "scene is in group 'floor'"):
        ef.read_view_factors(tmp_path, scene)
    with pytest.raises(ValueError, match="6 surfaces, but the scene has 24"):
        ef.read_view_factors(tmp_path, ef.scenes.subdivided_box(2))
    os.remove(tmp_path / "constant" / "globalFaceFaces")
    with pytest.raises(ValueError, match="globalFaceFaces: not found"):
        ef.read_view_factors(tmp_path, scene)
    (tmp_path / "constant" / "globalFaceFaces").write_text("2\n(\n1(1)\n1(0)\n)\n")
    with pytest.raises(ValueError, match="the lists differ in shape"):
        ef.read_view_factors(tmp_path, scene)


def test_energyplus_round_trip_in_another_order(room, tmp_path):
    scene, F = room
    # the file lists the surfaces in another order and another case: mapped by name
    order = [3, 0, 5, 1, 4, 2]
    names = [scene.names[k].upper() for k in order]
    ef.write_energyplus_view_factors(tmp_path / "vf.idf", F[np.ix_(order, order)],
                                     names=names, zone="Room")
    got = ef.read_view_factors(tmp_path / "vf.idf", scene)
    assert np.array_equal(got.toarray(), F)
    ef.write_energyplus_view_factors(tmp_path / "vf.idf", F[:5, :5], names=names[:5],
                                     zone="Room2", append=True)
    with pytest.raises(ValueError, match="2 ZoneProperty:UserViewFactors:BySurfaceName"):
        ef.read_view_factors(tmp_path / "vf.idf", scene)
    with pytest.raises(ValueError, match="5 surfaces, but the scene has 6"):
        ef.read_view_factors(tmp_path / "vf.idf", scene, zone="room2")


def test_energyplus_refuses_other_names(room, tmp_path):
    scene, F = room
    names = list(scene.names)
    names[2] = "Window"
    ef.write_energyplus_view_factors(tmp_path / "vf.idf", F, names=names, zone="Room")
    with pytest.raises(ValueError, match=r"not in the scene \['Window'\], not in the file "
                                         r"\['WallA'\]"):
        ef.read_view_factors(tmp_path / "vf.idf", scene)
    with pytest.raises(ValueError, match="have no names"):
        ef.read_view_factors(tmp_path / "vf.idf", ef.scenes.subdivided_box(1))


def test_elmer_round_trip(room, tmp_path):
    scene, F = room
    ef.write_elmer_view_factors(tmp_path / "ViewFactors.dat", F)
    assert guess_view_factor_format(tmp_path / "ViewFactors.dat") == "elmer"
    got = ef.read_view_factors(tmp_path / "ViewFactors.dat", scene)
    assert np.array_equal(got.toarray(), F) and got.nnz == 30
    with pytest.raises(ValueError, match="6 surfaces, but the scene has 24"):
        ef.read_view_factors(tmp_path / "ViewFactors.dat", ef.scenes.subdivided_box(2))
    (tmp_path / "bad.dat").write_text("2\n1 2 0.5\n")
    with pytest.raises(ValueError, match="ends inside row 1"):
        ef.read_view_factors(tmp_path / "bad.dat", format="elmer")
    (tmp_path / "bad.dat").write_text("1\n2 1 0.5\n1\n2 1 0.5\n")
    with pytest.raises(ValueError, match="row 2 where row 1 was expected"):
        ef.read_view_factors(tmp_path / "bad.dat", format="elmer")


def test_plain_arrays_round_trip(room, tmp_path):
    scene, F = room
    np.save(tmp_path / "m.npy", F)
    assert np.array_equal(ef.read_view_factors(tmp_path / "m.npy", scene), F)
    sp.save_npz(tmp_path / "s.npz", sp.csr_array(F))
    assert np.array_equal(ef.read_view_factors(tmp_path / "s.npz", scene).toarray(), F)
    order = [5, 4, 3, 2, 1, 0]
    np.savez(tmp_path / "n.npz", F=F[np.ix_(order, order)],
             names=np.array([scene.names[k] for k in order]))
    assert np.array_equal(ef.read_view_factors(tmp_path / "n.npz", scene), F)
    np.savetxt(tmp_path / "m.csv", F, delimiter=",", fmt="%.17g")
    assert np.array_equal(ef.read_view_factors(tmp_path / "m.csv", scene), F)
    pd = pytest.importorskip("pandas")
    ef.to_dataframe(F, scene).to_csv(tmp_path / "df.csv", float_format="%.17g")
    assert np.array_equal(ef.read_view_factors(tmp_path / "df.csv", scene), F)
    assert pd is not None
    with pytest.raises(ValueError, match="6 surfaces, but the scene has 24"):
        ef.read_view_factors(tmp_path / "m.csv", ef.scenes.subdivided_box(2))
    with pytest.raises(ValueError, match="format must be one of"):
        ef.read_view_factors(tmp_path / "m.csv", format="hemicube")
    (tmp_path / "x.txt").write_text("hello\n")
    with pytest.raises(ValueError, match="cannot tell its format"):
        ef.read_view_factors(tmp_path / "x.txt", scene)


def test_audit_of_files_written_by_the_writers(room, tmp_path):
    # an exact matrix through each writer and reader audits clean
    scene, _ = room
    F = ef.area_form_factors(scene)
    ef.write_energyplus_view_factors(tmp_path / "vf.idf", F, names=scene, zone="Room")
    ef.write_openfoam_view_factors(tmp_path, F, patches=scene)
    ef.write_elmer_view_factors(tmp_path / "ViewFactors.dat", F)
    ef.write_view3d_factors(tmp_path / "t.vf", F, scene)
    for path in ("vf.idf", ".", "ViewFactors.dat", "t.vf"):
        rep = ef.audit(scene, ef.read_view_factors(tmp_path / path, scene))
        assert rep.clean, (path, str(rep))
