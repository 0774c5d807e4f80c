"""Reading scenes: Wavefront OBJ (faces kept as polygons) and exactff-scene/1 JSON."""

import json
import math
import os

from .scene import Scene

__all__ = ["load_scene", "read_obj", "read_scene_json", "scene_from_json"]


def load_scene(path, **options):
    """Read a scene file, choosing the reader by extension.

    Parameters
    ----------
    path : str or os.PathLike
        ``.obj`` (Wavefront OBJ) or ``.json`` (``exactff-scene/1``).
    **options
        Passed to :meth:`exactff.Scene.from_polygons` (e.g. ``planarity_rtol``).

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
    ext = os.path.splitext(path)[1].lower()
    if ext == ".obj":
        return read_obj(path, **options)
    if ext == ".json":
        return read_scene_json(path, **options)
    raise ValueError(f"path: unknown scene format {ext!r} in {path!r}; expected .obj or .json")


def read_obj(path, **options):
    """Read a Wavefront OBJ file; each face stays one polygon.

    Vertex references may be positive (1-based) or negative (relative to the vertices
    read so far), with or without ``/texture/normal`` parts. ``o`` and ``g`` set the
    group of the faces that follow, ``usemtl`` their material. Other statements
    (``vt``, ``vn``, ``s``, ``mtllib``, lines and points) are ignored.
    """
    verts, faces, groups, materials = [], [], [], []
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
            elif key in ("o", "g"):
                group = " ".join(rest) or None
            elif key == "usemtl":
                material = " ".join(rest) or None
    if not faces:
        raise ValueError(f"{path}: no faces")
    return Scene.from_polygons(faces, groups=groups, materials=materials, **options)


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
    return Scene.from_polygons(
        [s["vertices"] for s in surfaces],
        names=[s.get("name") for s in surfaces],
        groups=[s.get("group") for s in surfaces],
        materials=[s.get("material") for s in surfaces],
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
