"""Reading scenes: Wavefront OBJ (faces kept as polygons), exactff-scene/1 JSON, View3D
``.vs3``, and the mesh formats of meshio (STL, PLY, OFF, VTK, ...)."""

import json
import math
import os

import numpy as np

from . import _tolerances as tol
from .scene import Scene, SceneError, validate_polygon

__all__ = ["load_scene", "read_obj", "read_scene_json", "scene_from_json", "read_vs3",
           "read_mesh", "split_nonplanar", "NONPLANAR"]

#: what to do with a face that is not planar within the tolerance
NONPLANAR = ("error", "split")

#: extensions read by meshio (an optional dependency: ``pip install exactff[formats]``)
MESHIO_EXTENSIONS = (".stl", ".ply", ".off", ".vtk", ".vtu", ".vtp", ".msh", ".mesh",
                     ".med", ".xdmf", ".inp", ".dat", ".tri")


def _fan_score(P, apex):
    """Triangles of the fan of polygon P from vertex ``apex``, and how flat it is: the
    least cosine between a triangle's normal and the polygon's mean normal (-inf when a
    triangle is degenerate or turned over)."""
    k = len(P)
    order = [(apex + j) % k for j in range(k)]
    tris = [P[[order[0], order[j], order[j + 1]]] for j in range(1, k - 1)]
    N = np.array([np.cross(t[1] - t[0], t[2] - t[0]) for t in tris])
    L = np.linalg.norm(N, axis=1)
    mean = N.sum(axis=0)
    if np.any(L <= tol.DEGENERATE_AREA_RTOL * np.max(L)) or not np.linalg.norm(mean) > 0:
        return tris, -np.inf
    cos = (N @ mean) / (L * np.linalg.norm(mean))
    return tris, float(cos.min())


def split_nonplanar(polygon):
    """Planar triangles covering a polygon that is not planar: the fan from the vertex
    that gives the flattest pieces (the triangles' normals closest to the polygon's
    mean normal), orientation kept.

    Parameters
    ----------
    polygon : array_like of shape (K, 3)

    Returns
    -------
    list of ndarray of shape (3, 3)

    Examples
    --------
    A quad with one corner lifted splits along the diagonal that leaves the flattest
    halves:

    >>> q = [[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0]]
    >>> [t.tolist() for t in split_nonplanar(q)]
    [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.1]], [[0.0, 0.0, 0.0], [1.0, 1.0, 0.1], [0.0, 1.0, 0.0]]]
    """
    P = np.asarray(polygon, dtype=float)
    best, best_score = None, -np.inf
    for apex in range(len(P)):
        tris, score = _fan_score(P, apex)
        if score > best_score + tol.SPLIT_FLATNESS_TIE:
            best, best_score = tris, score
    if best is None:
        raise ValueError("no fan of the polygon gives valid triangles")
    return best


def _hint(reason):
    if reason.startswith("not planar"):
        return ("; to load it anyway, split such faces into planar triangles "
                "(--split-nonplanar, or nonplanar='split') or allow more "
                "(--planarity-rtol, or planarity_rtol=)")
    return "; fix the face in the file (or leave it out)"


def build_scene(faces, *, names=None, groups=None, materials=None, sources=None,
                nonplanar="error", planarity_rtol=tol.PLANARITY_RTOL):
    """A scene from faces read from a file, with errors that name the face.

    Parameters
    ----------
    faces : list of array_like of shape (K_i, 3)
    names, groups, materials : list of str or None, optional
    sources : list of str, optional
        Where each face comes from (``"path:line"``), for the error messages.
    nonplanar : {"error", "split"}, default "error"
        ``"split"`` cuts every face that is not planar within ``planarity_rtol`` into
        planar triangles (:func:`split_nonplanar`); the pieces keep the face's name,
        group and material. The scene records how many faces were split
        (``describe(scene)["split_faces"]``).
    planarity_rtol : float

    Raises
    ------
    SceneError
        A face is ill-formed: the message gives where it comes from, its index, its
        name or group, the reason and how to proceed.
    """
    if nonplanar not in NONPLANAR:
        raise ValueError(f"nonplanar must be one of {NONPLANAR}, got {nonplanar!r}")
    n = len(faces)
    names = list(names) if names is not None else [None] * n
    groups = list(groups) if groups is not None else [None] * n
    materials = list(materials) if materials is not None else [None] * n
    sources = list(sources) if sources is not None else [None] * n
    split = 0
    if nonplanar == "split":
        out = ([], [], [], [], [])
        for i, F in enumerate(faces):
            pieces = [F]
            try:
                validate_polygon(F, i, planarity_rtol=planarity_rtol)
            except SceneError as exc:
                if exc.reason.startswith("not planar"):
                    pieces = split_nonplanar(F)
                    split += 1
            for Q in pieces:
                for lst, val in zip(out, (Q, names[i], groups[i], materials[i], sources[i])):
                    lst.append(val)
        faces, names, groups, materials, sources = out
    try:
        scene = Scene.from_polygons(faces, names=names, groups=groups, materials=materials,
                                    planarity_rtol=planarity_rtol)
    except SceneError as exc:
        i = exc.index
        label = (f" ({names[i]!r})" if names[i] else
                 f" (group {groups[i]!r})" if groups[i] else "")
        where = f"{sources[i]}: " if sources[i] else ""
        exc.args = (f"{where}polygon {i}{label}: {exc.reason}{_hint(exc.reason)}",)
        raise
    scene._cache["split_faces"] = split
    return scene


def load_scene(path, *, nonplanar="error", planarity_rtol=tol.PLANARITY_RTOL):
    """Read a scene file, choosing the reader by extension.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj`` (Wavefront OBJ: faces kept as polygons, groups and materials kept),
        ``.json`` (``exactff-scene/1``), ``.vs3`` (View3D input: the geometry), or a
        mesh format of meshio (``.stl``, ``.ply``, ``.off``, ``.vtk``, ``.vtu``, ...;
        ``pip install exactff[formats]``).
    nonplanar : {"error", "split"}, default "error"
        What to do with a face that is not planar within ``planarity_rtol``: raise
        (naming the face and the line), or cut it into planar triangles.
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
        A polygon is ill-formed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "q.obj").write_text("v 0 0 0\\nv 1 0 0\\nv 1 1 0\\nv 0 1 0\\nf 1 2 3 4\\n")
    >>> len(load_scene(d / "q.obj"))
    1
    """
    path = os.fspath(path)
    options = dict(nonplanar=nonplanar, planarity_rtol=planarity_rtol)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return read_obj(path, **options)
    if ext == ".json":
        return read_scene_json(path, **options)
    if ext == ".vs3":
        return read_vs3(path, **options)
    if ext in MESHIO_EXTENSIONS:
        return read_mesh(path, **options)
    raise ValueError(f"path: unknown scene format {ext!r} in {path!r}; expected .obj, .json, "
                     f".vs3 or a mesh format ({', '.join(MESHIO_EXTENSIONS)})")


def read_obj(path, **options):
    """Read a Wavefront OBJ file; each face stays one polygon.

    Vertex references may be positive (1-based) or negative (relative to the vertices
    read so far), with or without ``/texture/normal`` parts. ``o`` and ``g`` set the
    group of the faces that follow, ``usemtl`` their material. Other statements
    (``vt``, ``vn``, ``s``, ``mtllib``, lines and points) are ignored.
    """
    verts, faces, groups, materials, sources = [], [], [], [], []
    group = material = None
    with open(path, encoding="utf-8") as fh:
        for lineno, raw in enumerate(fh, start=1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            key, *rest = line.split()
            where = f"{path}:{lineno}"
            if key == "v":
                if len(rest) not in (3, 4, 6, 7):
                    raise ValueError(f"{where}: a vertex needs 3 coordinates: {raw.strip()!r}")
                try:
                    xyz = tuple(float(c) for c in rest[:3])
                except ValueError:
                    raise ValueError(f"{where}: bad vertex coordinate: {raw.strip()!r}") from None
                if not all(math.isfinite(c) for c in xyz):
                    raise ValueError(f"{where}: NaN or infinite vertex coordinate: {raw.strip()!r}")
                verts.append(xyz)
            elif key == "f":
                if len(rest) < 3:
                    raise ValueError(f"{where}: a face needs at least 3 vertices: {raw.strip()!r}")
                face = []
                for ref in rest:
                    try:
                        i = int(ref.split("/", 1)[0])
                    except ValueError:
                        raise ValueError(f"{where}: bad vertex reference {ref!r}") from None
                    j = i - 1 if i > 0 else len(verts) + i
                    if i == 0 or not 0 <= j < len(verts):
                        raise ValueError(f"{where}: vertex reference {i} out of range "
                                         f"(1..{len(verts)} or -{len(verts)}..-1)")
                    face.append(verts[j])
                faces.append(face)
                groups.append(group)
                materials.append(material)
                sources.append(where)
            elif key in ("o", "g"):
                group = " ".join(rest) or None
            elif key == "usemtl":
                material = " ".join(rest) or None
    if not faces:
        raise ValueError(f"{path}: no faces")
    return build_scene(faces, groups=groups, materials=materials, sources=sources, **options)


def scene_from_json(data, **options):
    """Build a scene from a parsed ``exactff-scene/1`` document (its ``surfaces``).

    Raises
    ------
    ValueError
        The document is not an ``exactff-scene/1`` object with a non-empty list of
        surfaces, each an object with ``vertices`` (the message says what is missing).
    SceneError
        A surface's polygon is ill-formed.
    """
    if not isinstance(data, dict):
        raise ValueError(f"expected a JSON object (exactff-scene/1), got a {type(data).__name__}")
    if data.get("schema") != "exactff-scene/1":
        raise ValueError(f"schema: expected 'exactff-scene/1', got {data.get('schema')!r}")
    surfaces = data.get("surfaces")
    if not isinstance(surfaces, list) or not surfaces:
        raise ValueError("surfaces: expected a non-empty list of surfaces")
    for i, s in enumerate(surfaces):
        if not isinstance(s, dict) or "vertices" not in s:
            raise ValueError(f"surfaces[{i}]: expected an object with 'vertices'")
    return build_scene(
        [s["vertices"] for s in surfaces],
        names=[s.get("name") for s in surfaces],
        groups=[s.get("group") for s in surfaces],
        materials=[s.get("material") for s in surfaces],
        sources=[f"surfaces[{i}]" for i in range(len(surfaces))],
        **options,
    )


def read_scene_json(path, **options):
    """Read an ``exactff-scene/1`` JSON file (see ``shared/scenes/README.md``)."""
    with open(path, encoding="utf-8") as fh:
        try:
            data = json.load(fh)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}:{exc.lineno}: invalid JSON: {exc.msg}") from None
    try:
        return scene_from_json(data, **options)
    except ValueError as exc:
        if type(exc) is ValueError:   # the document's structure (SceneError passes as is)
            raise ValueError(f"{path}: {exc}") from None
        raise


def read_vs3(path, **options):
    """Read the geometry of a View3D input file (``.vs3``, format 3).

    View3D (G. N. Walton, NISTIR 6925, 2002; github.com/jasondegraw/View3D) describes a
    scene by lines whose first word is a keyword: ``V n x y z`` (vertex ``n``),
    ``S n v1 v2 v3 v4 base cmb emit name`` (radiating surface: ``v4 = 0`` for a
    triangle; vertices counter-clockwise seen from the front, as in exactff),
    ``O n v1 v2 v3 v4`` (obstruction-only surface), ``T`` title, ``C`` control, ``F``
    format, ``!`` and ``/`` comments, ``E`` or ``*`` end of data.

    Kept: surfaces in file order (numbered from 1 in View3D, from 0 here), their names
    (``S``), group ``"obstruction"`` for ``O`` surfaces (they occlude like every
    polygon; View3D reports no form factors to or from them, exactff computes them:
    ignore those rows and columns). Refused with a clear error: subsurfaces
    (``base > 0``), mask and null surfaces (``M``, ``N``), the 2-D and ``3a`` formats.
    """
    verts, faces, names, groups, sources = {}, [], [], [], []
    with open(path, encoding="utf-8") as fh:
        for lineno, raw in enumerate(fh, start=1):
            words = raw.split()
            if not words:
                continue
            where = f"{path}:{lineno}"
            key = words[0][0].upper()
            try:
                if key in "!/TCX":
                    continue
                if key in "E*":
                    break
                if key == "F":
                    if len(words) < 2 or words[1] != "3":
                        raise ValueError(f"only the 3-D vertex/surface format (F 3) is read, "
                                         f"got {raw.strip()!r}")
                elif key == "V":
                    n, xyz = int(words[1]), [float(c) for c in words[2:5]]
                    if len(xyz) != 3 or not all(math.isfinite(c) for c in xyz):
                        raise ValueError(f"a vertex needs 3 finite coordinates: {raw.strip()!r}")
                    if n != len(verts) + 1:
                        raise ValueError(f"vertex {n} out of sequence (expected {len(verts) + 1})")
                    verts[n] = xyz
                elif key in "SO":
                    n = int(words[1])
                    if n != len(faces) + 1:
                        raise ValueError(f"surface {n} out of sequence (expected {len(faces) + 1})")
                    ids = [int(v) for v in words[2:6]]
                    if len(ids) != 4:
                        raise ValueError(f"a surface needs 4 vertex numbers (0 for the 4th "
                                         f"of a triangle): {raw.strip()!r}")
                    if ids[3] == 0:
                        ids = ids[:3]
                    for v in ids:
                        if v not in verts:
                            raise ValueError(f"surface {n}: vertex {v} is not defined above")
                    name = None
                    if key == "S":
                        if len(words) >= 7 and int(words[6]) != 0:
                            raise ValueError(f"surface {n}: subsurfaces (base surface "
                                             f"{words[6]}) are not supported")
                        name = words[9] if len(words) >= 10 else None
                    faces.append([verts[v] for v in ids])
                    names.append(name)
                    groups.append("obstruction" if key == "O" else None)
                    sources.append(where)
                elif key in "MN":
                    raise ValueError("mask and null surfaces (M, N) are not supported")
                else:
                    raise ValueError(f"unknown keyword {words[0]!r}")
            except (ValueError, IndexError) as exc:
                msg = str(exc) if isinstance(exc, ValueError) else f"too few fields: {raw.strip()!r}"
                if msg.startswith("invalid literal"):
                    msg = f"bad number in {raw.strip()!r}"
                raise ValueError(f"{where}: {msg}") from None
    if not faces:
        raise ValueError(f"{path}: no surfaces")
    return build_scene(faces, names=names, groups=groups, sources=sources, **options)


def read_mesh(path, **options):
    """Read a surface mesh with meshio (STL, PLY, OFF, VTK, ...): every triangle, quad
    or polygon cell becomes a polygon, in file order (``pip install exactff[formats]``).

    Kept: the faces (polygons stay polygons where the format has them; STL has
    triangles only) and their vertex order (counter-clockwise seen from the front:
    STL's facet order; a closed solid written with outward normals is seen from
    outside). Not kept: names, groups and materials (meshio does not expose them
    uniformly). Volume cells are refused; lines and points are ignored.
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
