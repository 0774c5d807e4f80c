"""Mesh formats read by meshio (STL, PLY, OFF, VTK, ...): every cell one polygon."""

import numpy as np

from ..scene import build_scene

__all__ = ["MESHIO_EXTENSIONS", "read_mesh"]


#: extensions read by meshio (an optional dependency: ``pip install exactff[formats]``)
MESHIO_EXTENSIONS = (".stl", ".ply", ".off", ".vtk", ".vtu", ".vtp", ".msh", ".mesh",
                     ".med", ".xdmf", ".inp", ".dat", ".tri")


def read_mesh(path, **options):
    """Read a surface mesh with meshio (STL, PLY, OFF, VTK, ...): every triangle, quad
    or polygon cell becomes a polygon, in file order (``pip install exactff[formats]``).

    Kept: the faces (polygons stay polygons where the format has them; STL has
    triangles only) and their vertex order (counter-clockwise seen from the front:
    STL's facet order; a closed solid written with outward normals is seen from
    outside). Not kept: names, groups and materials (meshio does not expose them
    uniformly). Volume cells are refused; lines and points are ignored. ``options`` go
    to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
    ``planarity_rtol``).
    """
    try:
        import meshio
    except ImportError:
        raise ValueError(f"{path}: reading this format needs meshio "
                         f"(pip install exactff[formats])") from None
    import contextlib
    import io as _io
    import warnings

    chatter = _io.StringIO()
    try:
        # meshio prints and calls sys.exit on a file it cannot read, and warns on some
        # it can: keep all of that out of the user's program
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mesh = meshio.read(path)
    except (Exception, SystemExit) as exc:
        detail = (str(exc).splitlines() or [""])[0] if not isinstance(exc, SystemExit) else ""
        detail = detail or " ".join(chatter.getvalue().split()) or "malformed"
        raise ValueError(f"{path}: cannot read the mesh ({detail})") from None
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError(f"{path}: expected 2-D or 3-D points")
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    faces, sources = [], []
    for b, block in enumerate(mesh.cells):
        kind = block.type
        if kind in ("triangle", "quad") or kind.startswith("polygon"):
            for c, cell in enumerate(np.asarray(block.data)):
                faces.append(points[cell])
                sources.append(f"{path}: cell block {b} ({kind}) cell {c}")
        elif kind in ("vertex", "line", "line3"):
            continue
        else:
            raise ValueError(f"{path}: cell block {b} has {kind!r} cells; exactff needs a "
                             f"surface (triangles, quads, polygons)")
    if not faces:
        raise ValueError(f"{path}: no faces (triangles, quads or polygons)")
    return build_scene(faces, sources=sources, **options)
