"""Wavefront OBJ: faces kept as polygons, with their names, groups and materials."""

import math

from ..scene import build_scene

__all__ = ["read_obj"]


def read_obj(path, **options):
    """Read a Wavefront OBJ file; each face stays one polygon.

    Vertex references may be positive (1-based) or negative (relative to the vertices
    read so far), with or without ``/texture/normal`` parts. ``o`` and ``g`` set the
    group of the faces that follow, ``usemtl`` their material. Other statements
    (``vt``, ``vn``, ``s``, ``mtllib``, lines and points) are ignored. ``options``
    go to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
    ``planarity_rtol``).
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
