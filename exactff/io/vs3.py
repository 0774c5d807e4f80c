"""View3D ``.vs3`` input files: the surfaces (F 3 and F 3a) as polygons."""

import math

from ..scene import build_scene

__all__ = ["read_vs3"]


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
    ``options`` go to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
    ``planarity_rtol``).
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
