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
    verts, faces, groups, materials, lines = [], [], [], [], []
    group = material = None
    isfinite = math.isfinite
    with open(path, encoding="utf-8") as fh:
        for lineno, raw in enumerate(fh, start=1):
            if "#" in raw:
                raw = raw.split("#", 1)[0]
            words = raw.split()
            if not words:
                continue
            key = words[0]
            if key == "v":
                if len(words) not in (4, 5, 7, 8):
                    raise ValueError(f"{path}:{lineno}: a vertex needs 3 coordinates: "
                                     f"{raw.strip()!r}")
                try:
                    xyz = (float(words[1]), float(words[2]), float(words[3]))
                except ValueError:
                    raise ValueError(f"{path}:{lineno}: bad vertex coordinate: "
                                     f"{raw.strip()!r}") from None
                if not (isfinite(xyz[0]) and isfinite(xyz[1]) and isfinite(xyz[2])):
                    raise ValueError(f"{path}:{lineno}: NaN or infinite vertex coordinate: "
                                     f"{raw.strip()!r}")
                verts.append(xyz)
            elif key == "f":
                if len(words) < 4:
                    raise ValueError(f"{path}:{lineno}: a face needs at least 3 vertices: "
                                     f"{raw.strip()!r}")
                face = []
                nv = len(verts)
                for ref in words[1:]:
                    try:
                        i = int(ref if "/" not in ref else ref.split("/", 1)[0])
                    except ValueError:
                        raise ValueError(f"{path}:{lineno}: bad vertex reference {ref!r}") from None
                    j = i - 1 if i > 0 else nv + i
                    if i == 0 or not 0 <= j < nv:
                        raise ValueError(f"{path}:{lineno}: vertex reference {i} out of range "
                                         f"(1..{nv} or -{nv}..-1)")
                    face.append(verts[j])
                faces.append(face)
                groups.append(group)
                materials.append(material)
                lines.append(lineno)
            elif key in ("o", "g"):
                group = " ".join(words[1:]) or None
            elif key == "usemtl":
                material = " ".join(words[1:]) or None
    if not faces:
        raise ValueError(f"{path}: no faces")
    return build_scene(faces, groups=groups, materials=materials,
                       sources=_Lines(path, lines), **options)


class _Lines:
    """``"path:line"`` of every face, made when an error asks for one."""

    def __init__(self, path, lines):
        self.path, self.lines = path, lines

    def __len__(self):
        return len(self.lines)

    def __getitem__(self, i):
        return f"{self.path}:{self.lines[i]}"
