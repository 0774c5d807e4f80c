"""Reading scenes: Wavefront OBJ (faces kept as polygons), exactff-scene/1 JSON, View3D
``.vs3``, EnergyPlus ``.idf``, Radiance ``.rad``, and the mesh formats of meshio (STL,
PLY, OFF, VTK, ...), one module each; :func:`load_scene` chooses the reader by
extension. Writing View3D's input and output files (:mod:`exactff.io.vs3`), and
matrices for other tools: EnergyPlus, Elmer, OpenFOAM, pandas; and their matrices
read back onto a scene (:func:`read_view_factors`)."""

from __future__ import annotations

import os

from .. import _tolerances as tol
from .dataframe import to_dataframe
from .energyplus import (read_energyplus_view_factors, read_idf,
                         write_energyplus_view_factors)
from .mesh import MESHIO_EXTENSIONS, read_mesh
from .obj import read_obj
from .radiance import read_rad
from .scene_json import read_scene_json, scene_from_json
from .solvers import (read_elmer_view_factors, read_openfoam_view_factors,
                      write_elmer_view_factors, write_openfoam_view_factors)
from .view_factors import read_view_factors
from .vs3 import (read_view3d_factors, read_vs3, script_f, write_view3d_factors,
                  write_vs3)
from ..scene import Scene

__all__ = ["load_scene", "read_obj", "read_scene_json", "scene_from_json", "read_vs3",
           "read_idf", "read_rad", "read_mesh", "MESHIO_EXTENSIONS", "write_vs3",
           "write_view3d_factors", "read_view3d_factors", "script_f",
           "write_energyplus_view_factors", "write_elmer_view_factors",
           "write_openfoam_view_factors", "to_dataframe", "read_view_factors",
           "read_energyplus_view_factors", "read_elmer_view_factors",
           "read_openfoam_view_factors"]


def load_scene(path: str | os.PathLike, *, nonplanar: str = "error",
               degenerate: str = "raise",
               planarity_rtol: float = tol.PLANARITY_RTOL) -> Scene:
    """Read a scene file, choosing the reader by extension.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj`` (Wavefront OBJ: faces kept as polygons, groups and materials kept),
        ``.json`` (``exactff-scene/1``), ``.vs3`` (View3D input: the geometry),
        ``.idf`` (EnergyPlus: the building surfaces, facing into their zones;
        :func:`read_idf`), ``.rad`` (Radiance: the polygons; :func:`read_rad`), or a
        mesh format of meshio (``.stl``, ``.ply``, ``.off``, ``.vtk``, ``.vtu``, ...;
        ``pip install exactff[formats]``).
    nonplanar : {"error", "split"}, default "error"
        What to do with a face that is not planar within ``planarity_rtol``: raise
        (naming the face and the line), or cut it into planar triangles.
    degenerate : {"raise", "drop"}, default "raise"
        What to do with a degenerate face (fewer than 3 distinct vertices, or zero
        area: collinear vertices): raise, counting every such face and naming the first
        few, or leave it out (the remaining polygons keep the file's order; how many
        were left out: ``describe(scene)["dropped_faces"]``). NaN or infinite
        coordinates are broken input, not degenerate, and raise either way.
    planarity_rtol : float, optional
        Allowed distance of a vertex from its face's plane, relative to the face's
        diameter (default 1e-6).

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        Unknown extension, or a malformed file (the message gives the line number).
    SceneError
        Polygons are ill-formed (the message counts them and names the first few).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "q.obj").write_text("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nf 1 2 3 4\\n")
    >>> len(load_scene(d / "q.obj"))
    1
    >>> _ = (d / "t.obj").write_text("v 0 0 0\\nv 1 0 0\\nv 2 0 0\\nv 0 1 0\\n"
    ...                              "f 1 2 4\\nf 1 2 3\\nf 1 1 4\\nf 2 3 4\\n")
    >>> s = load_scene(d / "t.obj", degenerate="drop")
    >>> len(s), s.dropped_faces
    (2, 2)
    """
    path = os.fspath(path)
    options = dict(nonplanar=nonplanar, degenerate=degenerate, planarity_rtol=planarity_rtol)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return read_obj(path, **options)
    if ext == ".json":
        return read_scene_json(path, **options)
    if ext == ".vs3":
        return read_vs3(path, **options)
    if ext == ".idf":
        return read_idf(path, **options)
    if ext == ".rad":
        return read_rad(path, **options)
    if ext in MESHIO_EXTENSIONS:
        return read_mesh(path, **options)
    raise ValueError(f"path: unknown scene format {ext!r} in {path!r}; expected .obj, .json, "
                     f".vs3, .idf, .rad or a mesh format ({', '.join(MESHIO_EXTENSIONS)})")
