"""Other tools' view-factor matrices read back onto a scene: View3D, OpenFOAM,
EnergyPlus, Elmer and plain arrays, each mapped to the scene's polygon order or refused
with the reason."""

import os

import numpy as np

from .. import _tolerances as tol
from ..scene import as_scene
from .energyplus import read_energyplus_view_factors
from .solvers import read_elmer_view_factors, read_openfoam_view_factors
from .vs3 import read_view3d_factors

__all__ = ["read_view_factors", "align_view_factors", "VIEW_FACTOR_FORMATS",
           "guess_view_factor_format"]

#: The formats :func:`read_view_factors` reads, with what it expects of each.
VIEW_FACTOR_FORMATS = {
    "view3d": "View3D's output file, text or binary (the areas must match the scene's)",
    "openfoam": "a case directory (or its constant/F), with constant/globalFaceFaces",
    "energyplus": "an IDF holding ZoneProperty:UserViewFactors:BySurfaceName (names "
                  "matched to the scene's, any case)",
    "elmer": "Elmer's ViewFactors.dat",
    "npy": "a NumPy .npy array of shape (N, N)",
    "npz": "scipy.sparse.save_npz, or numpy.savez with 'F' (and 'names')",
    "csv": "N rows of N numbers; a first row of names (and a first column of names, as "
           "pandas writes) matched to the scene's",
}


def guess_view_factor_format(path):
    """The format of a view-factor file, from its name and first bytes.

    Examples
    --------
    >>> guess_view_factor_format("case/constant/F"), guess_view_factor_format("m.csv")
    ('openfoam', 'csv')
    """
    path = os.fspath(path)
    base = os.path.basename(path.rstrip("/"))
    ext = os.path.splitext(base)[1].lower()
    if os.path.isdir(path) or base == "F":
        return "openfoam"
    if ext in (".npy", ".npz", ".csv"):
        return ext[1:]
    if ext == ".idf":
        return "energyplus"
    if base.lower().startswith("viewfactors.dat"):
        return "elmer"
    try:
        with open(path, "rb") as fh:
            head = fh.read(32).split(b"\n")[0].split()
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror or exc}") from None
    if len(head) >= 6 and all(w.isdigit() for w in head[2:6]):
        return "view3d"
    raise ValueError(f"{path}: cannot tell its format; give format= one of "
                     f"{', '.join(VIEW_FACTOR_FORMATS)}")


def align_view_factors(F, scene, *, names=None, areas=None, patches=None, source="F"):
    """A matrix in another tool's surface order mapped onto a scene's polygons.

    Parameters
    ----------
    F : ndarray or scipy.sparse matrix of shape (N, N)
    scene : Scene
    names : sequence of N str, optional
        The tool's surface names: matched to ``scene.names`` (ignoring case), and the
        matrix permuted to the scene's order.
    areas : array_like of shape (N,), optional
        The tool's surface areas: each must match its polygon's within
        ``AUDIT_AREA_RTOL`` (what tells surfaces given in another order).
    patches : sequence of N str, optional
        Each surface's patch (OpenFOAM): where the scene has groups, each must be its
        polygon's group.
    source : str
        What to name in the errors (the file).

    Returns
    -------
    ndarray or scipy.sparse.csr_array of shape (len(scene), len(scene))

    Raises
    ------
    ValueError
        The counts differ, a name is missing on either side or repeats, an area or a
        patch differs (the message names the surface and the polygon).

    Examples
    --------
    >>> import exactff as ef
    >>> tri = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    >>> s = ef.Scene.from_polygons([tri, tri], names=["a", "b"])
    >>> align_view_factors([[0, 1], [2, 0]], s, names=["B", "A"]).tolist()
    [[0, 2], [1, 0]]
    """
    import scipy.sparse as sp

    scene = as_scene(scene)
    n = len(scene)
    if not sp.issparse(F):
        F = np.asarray(F)
    if F.ndim != 2 or F.shape[0] != F.shape[1]:
        raise ValueError(f"{source}: expected a square matrix, got shape {F.shape}")
    if F.shape[0] != n:
        hint = ""
        if "view3d" in scene.metadata:
            from ..combine import combined_surfaces

            if len(combined_surfaces(scene)) == F.shape[0]:
                hint = ("; it has the surfaces View3D reports for the scene (combined "
                        "surfaces, subsurfaces), which an audit does not compare yet")
        raise ValueError(f"{source}: {F.shape[0]} surfaces, but the scene has {n} polygons "
                         f"(one row and column per polygon, in the scene's order){hint}")
    if areas is not None:
        A = np.asarray(areas, dtype=float)
        rel = np.abs(A - scene.areas) / scene.areas
        bad = np.flatnonzero(~(rel <= tol.AUDIT_AREA_RTOL))
        if len(bad):
            k = int(bad[0])
            raise ValueError(f"{source}: surface {k + 1} has area {A[k]:.9g} but polygon {k} "
                             f"of the scene {scene.areas[k]:.9g} ({len(bad)} surfaces "
                             f"differ): another scene, or its surfaces in another order")
    if patches is not None and any(g is not None for g in scene.groups):
        for k, (p, g) in enumerate(zip(patches, scene.groups)):
            if p != g:
                raise ValueError(f"{source}: face {k} is on patch {p!r} but polygon {k} of "
                                 f"the scene is in group {g!r}: another scene, or its faces "
                                 f"in another order")
    if names is None:
        return F
    names = [str(x) for x in names]
    if any(x is None for x in scene.names):
        raise ValueError(f"{source}: the file names its surfaces but the scene's polygons "
                         f"have no names to match them with (read the scene from a file "
                         f"that names them, e.g. the IDF)")
    index = {}
    for k, name in enumerate(scene.names):
        if name.lower() in index:
            raise ValueError(f"{source}: the scene's name {name!r} repeats (polygons "
                             f"{index[name.lower()]} and {k}): names cannot be matched")
        index[name.lower()] = k
    seen = set()
    for name in names:
        if name.lower() in seen:
            raise ValueError(f"{source}: surface {name!r} appears twice")
        seen.add(name.lower())
    absent = [x for x in names if x.lower() not in index]
    unlisted = [x for x in scene.names if x.lower() not in seen]
    if absent or unlisted:
        raise ValueError(f"{source}: surface names do not match the scene's: not in the "
                         f"scene {absent[:5]}, not in the file {unlisted[:5]}")
    perm = np.array([index[x.lower()] for x in names])     # file surface k -> polygon
    order = np.argsort(perm)                                # polygon -> file surface
    if sp.issparse(F):
        return sp.csr_array(sp.csr_array(F)[order][:, order])
    return F[np.ix_(order, order)]


def _read_csv(path):
    """A CSV matrix, with optional names in its first row (and first column)."""
    import csv

    with open(path, newline="", encoding="utf-8") as fh:
        table = [row for row in csv.reader(fh) if row]
    if not table:
        raise ValueError(f"{path}: empty")

    def numbers(row):
        try:
            return [float(x) for x in row]
        except ValueError:
            return None

    names = None
    if numbers(table[0]) is None:
        names, table = [x.strip() for x in table[0]], table[1:]
    # a first column of labels (pandas writes the index): one more column than rows
    labelled = len(table) and all(len(r) == len(table) + 1 for r in table)
    body = [numbers(r[1:] if labelled else r) for r in table]
    if any(r is None for r in body):
        raise ValueError(f"{path}: a value is not a number")
    if len({len(r) for r in body}) > 1:
        raise ValueError(f"{path}: rows of different lengths")
    if names is not None and labelled and len(names) == len(body) + 1:
        names = names[1:]
    if names is not None and names == [str(k) for k in range(len(names))]:
        names = None                  # the labels of a scene without names: its indices
    return np.array(body, dtype=float).reshape(len(body), -1), names


def _read_npz(path):
    import scipy.sparse as sp

    with np.load(path, allow_pickle=False) as z:
        keys = set(z.files)
        if {"data", "indices", "indptr", "shape"} <= keys or {"row", "col", "data"} <= keys:
            pass
        elif "F" in keys:
            names = [str(x) for x in z["names"]] if "names" in keys else None
            return np.array(z["F"], dtype=float), names
        else:
            raise ValueError(f"{path}: an .npz of scipy.sparse.save_npz, or with an array "
                             f"'F', expected; it holds {sorted(keys)}")
    return sp.csr_array(sp.load_npz(path)), None


def read_view_factors(path, scene=None, *, format=None, zone=None, region=None):
    """Read another tool's view-factor matrix, in the scene's polygon order.

    Parameters
    ----------
    path : str or os.PathLike
        The file (an OpenFOAM case directory for ``"openfoam"``).
    scene : Scene, optional
        The scene the matrix is for: the file's surfaces are matched to its polygons
        (by name where the file names them, by area for View3D, by patch for OpenFOAM,
        by count always) and a mismatch is refused (:func:`align_view_factors`).
        Without it, the matrix in the file's order.
    format : str, optional
        One of :data:`VIEW_FACTOR_FORMATS` (default: guessed from the name and the
        first bytes, :func:`guess_view_factor_format`).
    zone : str, optional
        EnergyPlus: the zone whose view factors to read.
    region : str, optional
        OpenFOAM: the mesh region.

    Returns
    -------
    ndarray or scipy.sparse.csr_array of shape (N, N)
        ``F[i, j]`` = F(i -> j). The sparse formats (OpenFOAM, Elmer, EnergyPlus,
        sparse ``.npz``) give a CSR array whose entries not stored are those the tool
        left out (:func:`exactff.audit` reports their exact mass).

    Raises
    ------
    ValueError
        An unknown format, a malformed file, or a matrix that does not match the scene
        (the message names the file and what differs).

    Examples
    --------
    >>> import tempfile, pathlib, exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "box.vf"
    >>> F = ef.area_form_factors(box)
    >>> ef.write_view3d_factors(p, F, box)
    >>> bool((read_view_factors(p, box) == F).all())
    True
    >>> read_view_factors(p, ef.scenes.subdivided_box(2))
    Traceback (most recent call last):
    ...
    ValueError: ...box.vf: 6 surfaces, but the scene has 24 polygons (one row and column per polygon, in the scene's order)
    """
    path = os.fspath(path)
    fmt = guess_view_factor_format(path) if format is None else format
    if fmt not in VIEW_FACTOR_FORMATS:
        raise ValueError(f"format must be one of {', '.join(VIEW_FACTOR_FORMATS)}, got "
                         f"{format!r}")
    if fmt != "openfoam" and not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    names = areas = patches = None
    if fmt == "view3d":
        d = read_view3d_factors(path)
        if d["emit"]:
            raise ValueError(f"{path}: written with emit=1 (Hottel's script-F exchange "
                             f"factors, not form factors); run View3D with emit=0")
        F, areas = d["F"], d["areas"]
    elif fmt == "openfoam":
        F, patches = read_openfoam_view_factors(path, region=region)
    elif fmt == "energyplus":
        names, F = read_energyplus_view_factors(path, zone=zone)
    elif fmt == "elmer":
        F = read_elmer_view_factors(path)
    elif fmt == "npy":
        F = np.load(path, allow_pickle=False)
    elif fmt == "npz":
        F, names = _read_npz(path)
    else:
        F, names = _read_csv(path)
    if scene is None:
        return F
    return align_view_factors(F, scene, names=names, areas=areas, patches=patches,
                              source=path)
