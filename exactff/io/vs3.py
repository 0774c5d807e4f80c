"""View3D files: the input (``.vs3``, formats F 3 and F 3a) read into a Scene and
written from one, and the view-factor output file written from a matrix and read back.

View3D (G. N. Walton, NIST; NISTIR 6925, 2002; the View3D 3.3 user manual) reads a
scene as lines whose first word is a keyword (``T`` title, ``C`` control values, ``F``
format, ``V`` vertex, ``S``/``M``/``N``/``O`` surfaces, ``!`` and ``/`` comments, ``E``
or ``*`` end of data) and writes its factors as a header line, the areas, the N x N
factors and the emissivities. What is read and written, and how it maps to exactff:
``docs/how-to/view3d.md``.
"""

from __future__ import annotations

import math
import os
import re

import numpy as np

from .. import _tolerances as tol
from ..combine import combined_surfaces
from ..scene import Scene, as_scene, build_scene

__all__ = ["read_vs3", "write_vs3", "write_view3d_factors", "read_view3d_factors",
           "script_f", "CONTROL_DEFAULTS"]

#: View3D's control values and their defaults (``C name=value ...``; names are
#: case-insensitive): ``eps`` convergence, ``maxU``/``maxO``/``minO`` recursion limits,
#: ``row``/``col`` one row (or one value) only, ``encl`` the surfaces form an
#: enclosure, ``emit`` script-F factors (reflections included), ``out`` output file
#: format (0 text, 1 binary), ``list`` log detail, ``prjD`` projection direction,
#: ``maxV`` polygon vertex buffer
CONTROL_DEFAULTS = {"eps": 1e-4, "maxU": 12, "maxO": 8, "minO": 0, "row": 0, "col": 0,
                    "encl": 0, "emit": 0, "out": 0, "list": 0, "prjD": 0, "maxV": 12}
_FLOAT_CONTROLS = ("eps",)
#: controls that change nothing exactff computes, and why
_IGNORED = {
    "maxU": "View3D's recursion limit for unobstructed factors",
    "maxO": "View3D's recursion limit for obstructed factors",
    "minO": "View3D's minimum recursions for obstructed factors",
    "prjD": "View3D's projection direction",
    "maxV": "View3D's vertex buffer size",
    "list": "View3D's log detail",
}
_KINDS = {"S": "surface", "M": "mask", "N": "null surface", "O": "obstruction"}
_GROUPS = {"S": None, "M": "mask", "N": "null", "O": "obstruction"}
_SEPARATORS = re.compile(r"[ ,\t\r\0]+")


class _Words:
    """The file as View3D's reader sees it: words separated by blanks, commas and tabs;
    ``!`` at the start of a word begins a comment to the end of the line; a word
    starting with ``*`` ends the data. Each record starts with the first word of a line
    and may continue onto the following lines."""

    def __init__(self, path):
        self.path = path
        with open(path, encoding="utf-8") as fh:
            self.lines = fh.read().split("\n")
        self.words = []                     # (word, line number)
        self.first = []                     # positions of each line's first word
        for lineno, raw in enumerate(self.lines, start=1):
            start = len(self.words)
            for w in _SEPARATORS.split(raw):
                if not w:
                    continue
                if w.startswith("!"):
                    break
                if w.startswith("*"):
                    self.lines = self.lines[:lineno]
                    if len(self.words) > start:
                        self.first.append(start)
                    return
                self.words.append((w, lineno))
            if len(self.words) > start:
                self.first.append(start)

    def records(self):
        """``(keyword word, line, position of the next word)`` of each line's first word,
        skipping lines a record already consumed (``self.at`` past their first word)."""
        self.at = 0
        for pos in self.first:
            if pos < self.at:
                continue
            self.at = pos + 1
            yield self.words[pos][0], self.words[pos][1], pos

    def rest_of_line(self, lineno):
        """The text of line ``lineno`` after its first word (a title, control values)."""
        raw = self.lines[lineno - 1].lstrip(" \t,")
        return re.split(r"[ ,\t]", raw, maxsplit=1)[1] if re.search(r"[ ,\t]", raw) else ""

    def next(self, what, record_line):
        """The next word of the record (it may be on a following line)."""
        if self.at >= len(self.words):
            raise _Error(record_line, f"{what} expected, the file ends")
        w, line = self.words[self.at]
        self.at += 1
        return w, line

    def next_line(self, what, record_line):
        """The first word of the line after the last word read (F 3a geometry)."""
        line = self.words[self.at - 1][1]
        while self.at < len(self.words) and self.words[self.at][1] == line:
            self.at += 1
        return self.next(what, record_line)


class _Error(Exception):
    def __init__(self, line, message):
        super().__init__(message)
        self.line, self.message = line, message


def _number(words, what, line, kind=float):
    w, wline = words.next(what, line)
    where = "" if wline == line else f" (line {wline})"
    try:
        value = int(w) if kind is int else float(w)
    except ValueError:
        raise _Error(line, f"{what}: {w!r}{where} is not a"
                           f"{'n integer' if kind is int else ' number'}") from None
    if kind is float and not math.isfinite(value):
        raise _Error(line, f"{what}: {w!r}{where} is not a finite number")
    return value


def _parse_control(text, line, control, given, notes):
    words = [w for w in re.split(r"[= ,\t\r]+", text) if w]
    names = {k.lower(): k for k in CONTROL_DEFAULTS}
    for k in range(0, len(words), 2):
        key = names.get(words[k].lower())
        if key is None:
            notes.append(f"line {line}: unknown control word {words[k]!r} ignored "
                         f"(as View3D does)")
            continue
        if k + 1 >= len(words):
            raise _Error(line, f"control value {words[k]!r}: no value")
        try:
            value = (float if key in _FLOAT_CONTROLS else int)(words[k + 1])
        except ValueError:
            raise _Error(line, f"control value {words[k]}={words[k + 1]!r} is not "
                               f"{'a number' if key in _FLOAT_CONTROLS else 'an integer'}"
                         ) from None
        if key in ("encl", "emit", "prjD"):
            value = int(value != 0)
        if key in ("row", "col"):
            value = max(value, 0)
        if key == "out" and value not in (0, 1):
            raise _Error(line, f"control value out={value}: expected 0 (text) or 1 (binary)")
        control[key] = value
        given.append(key)


def _surface_fields(words, kind, n, line, nrad):
    """``base cmb emit name`` of an S, M or N surface, checked as View3D does."""
    base = _number(words, f"surface {n}: base surface number", line, int)
    cmb = _number(words, f"surface {n}: combination surface number", line, int)
    emit = _number(words, f"surface {n}: emissivity", line)
    name, _ = words.next(f"surface {n}: name", line)
    if base < 0:
        raise _Error(line, f"surface {n}: improper base surface number {base}")
    if kind in "MN" and not 0 < base < n:
        raise _Error(line, f"surface {n}: a mask or null surface needs a base surface "
                           f"numbered before it, got {base}")
    if kind == "S" and 0 < base <= nrad and base >= n:
        raise _Error(line, f"surface {n}: a subsurface must come after its base {base}")
    if cmb < 0 or cmb > nrad:
        raise _Error(line, f"surface {n}: improper combination surface number {cmb}")
    if cmb and kind in "MN":
        raise _Error(line, f"surface {n}: a mask or null surface cannot be combined")
    if cmb and cmb >= n:
        raise _Error(line, f"surface {n}: combine a surface with one before it, got {cmb}")
    return base, cmb, emit, name


def _placed(origin, azimuth, tilt, uv):
    """View3D's F 3a placement (getdat.c): the plane through ``origin`` with
    ``azimuth`` (degrees clockwise from north, +y) and ``tilt`` (0 facing up, 90
    vertical, 180 facing down); local (u, v) to x, y, z exactly as View3D computes them,
    coordinates below ``VIEW3D_ZERO_COORDINATE`` in magnitude set to 0 as it does."""
    ca, sa = -math.cos(azimuth * math.pi / 180.0), math.sin(azimuth * math.pi / 180.0)
    ct, st = math.cos(tilt * math.pi / 180.0), math.sin(tilt * math.pi / 180.0)
    x0, y0, z0 = origin
    out = []
    for u, v in uv:
        xyz = (x0 + u * ca - (v * ct - 0.0 * st) * sa,
               y0 + u * sa + (v * ct - 0.0 * st) * ca,
               z0 + v * st + 0.0 * ct)
        out.append([0.0 if abs(c) < tol.VIEW3D_ZERO_COORDINATE else c for c in xyz])
    return out


def read_vs3(path, **options) -> Scene:
    """Read a View3D input file (``.vs3``): formats F 3 (vertices and surfaces) and F 3a
    (surfaces by shape and placement).

    The polygons are View3D's surfaces in file order (numbered from 1 there, from 0
    here), vertices counter-clockwise seen from the front as in exactff. Every surface
    kind is read: ``S`` (named; a subsurface when its ``base`` is not 0), ``M`` masks and
    ``N`` null surfaces (groups ``"mask"`` and ``"null"``), ``O`` obstructions (group
    ``"obstruction"``; no name). What View3D does with them beyond the geometry is kept
    in ``scene.metadata["view3d"]``:

    - ``format`` (``"3"`` or ``"3a"``), ``title``, ``control`` (every control value,
      View3D's defaults for those not given; :data:`CONTROL_DEFAULTS`) and ``given``
      (the names given);
    - ``surfaces``: one dict per View3D surface: ``number``, ``kind`` (S, M, N, O),
      ``base``, ``cmb`` (View3D numbers, 0 for none), ``emit`` (clamped to 0.001-0.999
      as View3D does), ``name``, ``line``, and for F 3a the ``shape`` (R, Q, T);
    - ``polygon_surface``: the View3D number of each polygon (a face split by
      ``nonplanar="split"`` gives several);
    - ``notes``: what is accepted and ignored (``maxU``, ``maxO``, ``minO``, ``list``,
      ``prjD``, ``maxV``, ``eps``, ``X`` lines, unknown control words, clamped
      emissivities).

    :func:`exactff.area_form_factors` with ``combine=True`` gives the matrix View3D
    prints from them (combined surfaces merged, subsurfaces separated, masks, null
    surfaces and obstructions as View3D treats them; :mod:`exactff.combine`).

    Parameters
    ----------
    path : str or os.PathLike
    **options
        Passed to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
        ``planarity_rtol``).

    Returns
    -------
    Scene

    Raises
    ------
    ValueError
        A malformed file, named by its path and line, and the surface or vertex: an
        unknown keyword, a bad number, a surface or vertex out of sequence or
        undefined, a bad base or combination number (View3D's rules: a subsurface after
        its base, a mask or null surface after its base, combined with an earlier
        surface, no chains of combinations, obstructions after every other surface), a
        subsurface, mask or null surface not in its base's plane, facing the wrong way
        or not within it, ``row``/``col`` out of range.
    SceneError
        A polygon is ill-formed (named with its line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "wall.vs3"
    >>> _ = p.write_text("T a wall with a window\\nC encl=0\\nF 3a\\n"
    ...                  "S 1 R 0 0 0.9 wall\\n 4 0 0 0 90 4 3\\n"
    ...                  "S 2 R 1 0 0.8 window\\n 2 0 1 0 90 1 1\\n")
    >>> s = read_vs3(p)
    >>> s.names, [float(a) for a in s.areas]
    (('wall', 'window'), [12.0, 1.0])
    >>> s.metadata["view3d"]["surfaces"][1]["base"]
    1
    """
    path = os.fspath(path)
    words = _Words(path)
    title, fmt, control, given, notes = None, None, dict(CONTROL_DEFAULTS), [], []
    verts, surfaces, faces = {}, [], []
    nrad = 0                        # View3D counts the radiating surfaces first
    for pos in words.first:
        key = words.words[pos][0][0].upper()
        if key == "E":
            break
        nrad += key in "SMN"
    current = None
    try:
        for word, line, pos in words.records():
            current = line
            key = word[0].upper()
            if key in "!/":
                continue
            if key == "E":
                break
            if key == "T":
                title = words.rest_of_line(line).strip() or None
                _skip_line(words, line)
            elif key == "C":
                _parse_control(words.rest_of_line(line), line, control, given, notes)
                _skip_line(words, line)
            elif key == "X":
                notes.append(f"line {line}: coordinate transformation lines (X) are ignored, "
                             f"as View3D ignores them")
                _skip_line(words, line)
            elif key == "F":
                w, _ = words.next("the format", line)
                if w not in ("3",) and w.lower() != "3a":
                    raise _Error(line, f"format {w!r}: View3D's 3-D formats are F 3 and F 3a "
                                       f"(2 is its 2-D program's)")
                fmt = w.lower()
            elif key == "V":
                n = _number(words, "vertex number", line, int)
                if n != len(verts) + 1:
                    raise _Error(line, f"vertex {n} out of sequence (expected {len(verts) + 1})")
                verts[n] = ([_number(words, f"vertex {n}: coordinate", line) for _ in range(3)],
                            line)
            elif key in "SMNO":
                n = _number(words, "surface number", line, int)
                if n != len(surfaces) + 1:
                    raise _Error(line, f"surface {n} out of sequence (expected "
                                       f"{len(surfaces) + 1})")
                if key == "O" and n <= nrad:
                    raise _Error(line, f"obstruction surface {n} out of sequence: View3D "
                                       f"numbers obstructions after every S, M and N surface")
                s = {"number": n, "kind": key, "base": 0, "cmb": 0, "emit": None,
                     "name": None, "line": line}
                if fmt == "3a":
                    w, _ = words.next(f"surface {n}: shape (R, Q or T)", line)
                    shape = w[0].upper()
                    if shape not in "RQT" or len(w) > 1:
                        raise _Error(line, f"surface {n}: shape {w!r}: expected R, Q or T")
                    s["shape"] = shape
                if fmt != "3a":
                    ids = [_number(words, f"surface {n}: vertex number", line, int)
                           for _ in range(4)]
                    if min(ids[:3]) < 1 or ids[3] < 0:
                        raise _Error(line, f"surface {n}: improper vertex numbers {ids}")
                    faces.append(ids[:3] if ids[3] == 0 else ids)
                if key != "O":
                    s["base"], s["cmb"], s["emit"], s["name"] = _surface_fields(
                        words, key, n, line, nrad)
                if fmt == "3a":
                    faces.append(_read_3a_geometry(words, n, line, s["shape"]))
                surfaces.append(s)
                _skip_line(words, words.words[words.at - 1][1])
            else:
                raise _Error(line, f"unknown keyword {word!r}")
        current = None
        if fmt is None and surfaces:
            fmt = "3"
        if not surfaces:
            raise _Error(None, "no surfaces")
        _check_numbers(surfaces, control)
    except _Error as exc:
        where = f"{path}:{exc.line}" if exc.line else path
        raise ValueError(f"{where}: {exc.message}") from None
    # vertices may be defined anywhere in the file (View3D counts them first)
    polys = []
    for s, face in zip(surfaces, faces):
        if fmt == "3a":
            polys.append(face)
            continue
        for v in face:
            if v not in verts:
                raise ValueError(f"{path}:{s['line']}: surface {s['number']}: vertex {v} is "
                                 f"not defined in the file")
        polys.append([verts[v][0] for v in face])
    for s in surfaces:
        lo, hi = tol.VIEW3D_EMISSIVITY_RANGE
        if s["emit"] is not None and not lo <= s["emit"] <= hi:
            e = min(max(s["emit"], lo), hi)
            notes.append(f"line {s['line']}: surface {s['number']}: emissivity {s['emit']:g} "
                         f"replaced by {e:g}, as View3D does")
            s["emit"] = e
    ignored = [k for k in given if k in _IGNORED]
    if ignored:
        notes.append("; ".join(f"{k}={control[k]} ({_IGNORED[k]})" for k in dict.fromkeys(ignored))
                     + ": accepted and ignored (exactff's accuracy is the tolerance asked for)")
    if "eps" in given:
        notes.append(f"eps={control['eps']:g} is View3D's convergence criterion: exactff takes "
                     f"tolerance= instead (an absolute bound per value)")
    if control["col"]:
        notes.append(f"col={control['col']}: View3D computes that one value; exactff computes "
                     f"the whole row {control['row']}")
    kept = []
    scene = build_scene(polys, names=[s["name"] for s in surfaces],
                        groups=[_GROUPS[s["kind"]] for s in surfaces],
                        sources=[f"{path}:{s['line']}: surface {s['number']}" for s in surfaces],
                        face_index=kept, **options)
    dropped = set(range(len(surfaces))) - set(kept)
    for i in sorted(dropped):
        s = surfaces[i]
        related = any(t["base"] == s["number"] or t["cmb"] == s["number"] for t in surfaces)
        if s["kind"] != "O" and (s["base"] or related):
            raise ValueError(f"{path}:{s['line']}: surface {s['number']} is degenerate and was "
                             f"left out, but it is a subsurface, base or combined surface")
    meta = {"format": fmt, "title": title, "control": control, "given": list(dict.fromkeys(given)),
            "surfaces": surfaces, "polygon_surface": [surfaces[i]["number"] for i in kept],
            "notes": notes, "source": path}
    scene = scene.with_metadata({"view3d": meta})
    try:
        combined_surfaces(scene)          # View3D's tests of subsurfaces and masks
    except ValueError as exc:
        m = re.match(r"surface (\d+)", str(exc))
        line = surfaces[int(m.group(1)) - 1]["line"] if m else None
        raise ValueError(f"{path}:{line}: {exc}" if line else f"{path}: {exc}") from None
    return scene


def _skip_line(words, line):
    """Past the rest of line ``line``: the next record starts on a later line."""
    while words.at < len(words.words) and words.words[words.at][1] <= line:
        words.at += 1


def _read_3a_geometry(words, n, line, shape):
    """An F 3a surface's placement and shape, from the line after its surface line."""
    w, wline = words.next_line(f"surface {n}: origin x", line)
    words.at -= 1
    origin = [_number(words, f"surface {n}: origin", wline) for _ in range(3)]
    azimuth = _number(words, f"surface {n}: azimuth", wline)
    tilt = _number(words, f"surface {n}: tilt", wline)
    if shape == "R":
        width = _number(words, f"surface {n}: width", wline)
        height = _number(words, f"surface {n}: height", wline)
        uv = [(0.0, height), (0.0, 0.0), (width, 0.0), (width, height)]
    else:
        uv = [(_number(words, f"surface {n}: vertex x", wline),
               _number(words, f"surface {n}: vertex y", wline))
              for _ in range(3 if shape == "T" else 4)]
    return _placed(origin, azimuth, tilt, uv)


def _check_numbers(surfaces, control):
    """The references between surfaces, checked once every surface is known."""
    nall = len(surfaces)
    nrad = sum(1 for s in surfaces if s["kind"] != "O")
    for s in surfaces:
        if s["base"] > nall:
            raise _Error(s["line"], f"surface {s['number']}: base surface {s['base']} does not "
                                    f"exist")
        if s["base"] and surfaces[s["base"] - 1]["kind"] in "MN":
            raise _Error(s["line"], f"surface {s['number']}: its base {s['base']} is a mask or "
                                    f"null surface")
        if s["kind"] in "MN" and s["base"] and surfaces[s["base"] - 1]["kind"] == "O":
            raise _Error(s["line"], f"surface {s['number']}: a mask or null surface needs a "
                                    f"radiating base, not obstruction {s['base']}")
        c = s["cmb"]
        if c:
            t = surfaces[c - 1]
            if t["kind"] != "S":
                raise _Error(s["line"], f"surface {s['number']}: combined with {c}, which is "
                                        f"not an S surface")
            if t["cmb"]:
                raise _Error(s["line"], f"surface {s['number']}: may not chain combined "
                                        f"surfaces ({c} is itself combined with {t['cmb']}); "
                                        f"combine every one with the lowest numbered")
    if control["row"] > nrad or control["col"] > nrad:
        raise _Error(None, f"control row={control['row']} col={control['col']}: the file has "
                           f"{nrad} radiating surfaces")
    if control["col"] and not control["row"]:
        raise _Error(None, "control col is set without row (View3D: set row before column)")


# ---------------------------------------------------------------------------------------
# writing .vs3
# ---------------------------------------------------------------------------------------
def _convex_quad(P, normal):
    if len(P) != 4:
        return len(P) == 3
    turns = [np.cross(P[(k + 1) % 4] - P[k], P[(k + 2) % 4] - P[(k + 1) % 4]) @ normal
             for k in range(4)]
    return all(t > 0 for t in turns)


def _ear_pieces(P, normal):
    """Convex pieces of a simple polygon with more than 4 vertices, or a non-convex
    quadrilateral: a fan of quadrilaterals for a convex polygon, ear-clipped triangles
    otherwise (in order, facing as P)."""
    k = len(P)
    turn = lambda a, b, c: np.cross(b - a, c - b) @ normal
    if all(turn(P[i - 1], P[i], P[(i + 1) % k]) > 0 for i in range(k)):
        out, i = [], 1
        while i < k - 1:
            j = min(i + 2, k - 1)
            out.append(P[[0, *range(i, j + 1)]])
            i = j
        return out
    idx, out = list(range(k)), []
    while len(idx) > 3:
        for m in range(len(idx)):
            a, b, c = idx[m - 1], idx[m], idx[(m + 1) % len(idx)]
            if turn(P[a], P[b], P[c]) <= 0:
                continue
            T = P[[a, b, c]]
            inside = False
            for q in idx:
                if q in (a, b, c):
                    continue
                if all(np.cross(T[(e + 1) % 3] - T[e], P[q] - T[e]) @ normal >= 0
                       for e in range(3)):
                    inside = True
                    break
            if not inside:
                out.append(T)
                idx.pop(m)
                break
        else:
            raise ValueError("no ear found (the polygon is not simple)")
    out.append(P[idx])
    return out


def _name(name, number):
    if not name:
        return f"srf-{number}"
    return re.sub(r"[\s,!*]+", "_", str(name))


def write_vs3(scene: Scene, path, *, title=None, control=None, emissivity=0.9,
              split=False):
    """Write a scene as a View3D input file (format F 3), which :func:`read_vs3` reads
    back to the same polygons, bit for bit (coordinates in Python's shortest round-trip
    form).

    A scene read from a ``.vs3`` file (F 3 or F 3a) is written with everything
    ``scene.metadata["view3d"]`` holds: its title, control values, surface kinds,
    subsurfaces, combined surfaces, emissivities and names. Any other scene is written
    as radiating surfaces (``S``), named by the scene's names (blanks replaced by
    ``_``; ``srf-N`` where there is none), polygons of group ``"obstruction"`` as ``O``
    surfaces (View3D wants them last).

    Parameters
    ----------
    scene : Scene
    path : str or os.PathLike
    title : str, optional
        The ``T`` line (default: the scene's View3D title, or none).
    control : dict, optional
        Control values to write (:data:`CONTROL_DEFAULTS` names), over the scene's.
    emissivity : float or sequence of float, default 0.9
        Emissivities of a scene without View3D data (one, or one per polygon).
    split : bool, default False
        View3D takes triangles and convex quadrilaterals only. False refuses a polygon
        that is neither (naming it); True writes it as convex pieces combined into the
        first (``cmb``), which View3D, and ``area_form_factors(..., combine=True)``,
        report as the one surface (the file then has more surfaces than the scene).

    Raises
    ------
    ValueError
        A polygon View3D cannot take (without ``split``), obstructions before other
        surfaces, or a split polygon that is a base of subsurfaces.

    Examples
    --------
    >>> import tempfile, pathlib, exactff as ef
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "box.vs3"
    >>> box = ef.scenes.subdivided_box(1)
    >>> write_vs3(box, p)
    >>> all((a == b).all() for a, b in zip(read_vs3(p).polygons, box.polygons))
    True
    """
    scene = as_scene(scene)
    v3 = scene.metadata.get("view3d")
    n = len(scene)
    # one record per polygon: kind, emissivity, name, and the polygons (first of their
    # surface) it is a subsurface of and combined with
    if v3 is not None:
        by_number = {s["number"]: s for s in v3["surfaces"]}
        first, count = {}, {}
        for i, num in enumerate(v3["polygon_surface"]):
            first.setdefault(num, i)
            count[num] = count.get(num, 0) + 1
        records = []
        for i, num in enumerate(v3["polygon_surface"]):
            s = by_number[num]
            if s["kind"] != "O" and s["number"] in {t["base"] for t in v3["surfaces"]} \
                    and count[num] > 1:
                raise ValueError(f"polygon {i}: surface {num} is a base of subsurfaces and "
                                 f"was split into {count[num]} polygons, which View3D cannot take")
            cmb = first[s["cmb"]] if s["cmb"] else (first[num] if first[num] != i else None)
            if cmb is not None and s["kind"] != "S":
                raise ValueError(f"polygon {i}: surface {num} ({_KINDS[s['kind']]}) was split "
                                 f"into several polygons, which View3D cannot combine")
            records.append({"kind": s["kind"], "emit": s["emit"], "name": s["name"],
                            "base": first.get(s["base"]) if s["base"] else None, "cmb": cmb})
        ctl, given = dict(v3["control"]), list(v3.get("given", []))
        title = v3["title"] if title is None else title
    else:
        emit = np.broadcast_to(np.asarray(emissivity, dtype=float), (n,))
        records = [{"kind": "O" if scene.groups[i] == "obstruction" else "S",
                    "emit": float(emit[i]), "name": scene.names[i], "base": None, "cmb": None}
                   for i in range(n)]
        ctl, given = dict(CONTROL_DEFAULTS), []
    if control:
        for k, v in control.items():
            if k not in CONTROL_DEFAULTS:
                raise ValueError(f"control: unknown View3D control {k!r}; expected one of "
                                 f"{', '.join(CONTROL_DEFAULTS)}")
            ctl[k] = v
            given.append(k)
    kinds = [r["kind"] for r in records]
    if "O" in kinds and any(k != "O" for k in kinds[kinds.index("O"):]):
        raise ValueError("View3D numbers obstructions (O) after every other surface: "
                         "put the scene's obstructions last")
    # polygons View3D cannot take become convex pieces combined into the first
    rows = []                       # (vertices, polygon index, piece number)
    bases = {r["base"] for r in records if r["base"] is not None}
    for i, P in enumerate(scene.polygons):
        if _convex_quad(P, scene.normals[i]):
            rows.append((P, i, 0))
            continue
        label = f"polygon {i}" + (f" ({scene.names[i]})" if scene.names[i] else "")
        if not split:
            raise ValueError(f"{label}: View3D takes triangles and convex quadrilaterals only, "
                             f"this one has {len(P)} vertices"
                             + ("" if len(P) > 4 else " and is not convex")
                             + "; split=True writes it as convex pieces combined into one")
        if records[i]["kind"] != "S" or i in bases:
            raise ValueError(f"{label}: split=True cannot split a mask, null surface, "
                             f"obstruction or base of subsurfaces")
        try:
            cut = _ear_pieces(P, scene.normals[i])
        except ValueError as exc:
            raise ValueError(f"{label}: {exc}") from None
        rows.extend((Q, i, k) for k, Q in enumerate(cut))
    number_of = {}
    for k, (_, i, piece) in enumerate(rows):
        if piece == 0:
            number_of[i] = k + 1
    vid, vlines, slines = {}, [], []
    for k, (P, i, piece) in enumerate(rows):
        r = records[i]
        ids = []
        for v in P:
            key = tuple(float(c) for c in v)
            if key not in vid:
                vid[key] = len(vid) + 1
                vlines.append(f"V {vid[key]} " + " ".join(repr(c) for c in key))
            ids.append(vid[key])
        ids = ids + [0] if len(ids) == 3 else ids
        cmb = r["cmb"] if r["cmb"] is not None else (i if piece else None)
        cmb = number_of[cmb] if cmb is not None else 0
        base = number_of[r["base"]] if r["base"] is not None else 0
        head = f"{r['kind']} {k + 1} " + " ".join(str(v) for v in ids)
        if r["kind"] == "O":
            slines.append(head + (f"  ! {scene.names[i]}" if scene.names[i] else ""))
        else:
            e = 0.9 if r["emit"] is None else r["emit"]
            slines.append(f"{head} {base} {cmb} {e!r} {_name(r['name'], k + 1)}")
    out = []
    if title:
        out.append(f"T {' '.join(str(title).split())}")
    shown = [k for k in CONTROL_DEFAULTS if k in given or k in ("encl", "emit")]
    out.append("C " + " ".join(f"{k}={ctl[k]!r}" if isinstance(ctl[k], float) else f"{k}={ctl[k]}"
                               for k in shown))
    out.append("F 3")
    out.append("!  #  x  y  z")
    out.extend(vlines)
    out.append("!  #  v1 v2 v3 v4 base cmb emit name")
    out.extend(slines)
    out.append("End of data")
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(out) + "\n")


# ---------------------------------------------------------------------------------------
# View3D's output file
# ---------------------------------------------------------------------------------------
def script_f(F, areas, emissivities):
    """Hottel's total exchange factors ("script-F") of gray diffuse surfaces, what
    View3D writes with ``emit=1``: ``A_i SF[i, j]`` is the share of the radiation
    emitted by ``i`` that ``j`` absorbs, after every diffuse reflection.

    With ``rho = 1 - eps``, the irradiation ``H`` from emissive powers ``E`` solves
    ``H = F (E + rho H)``; so ``SF[i, j] = (A_j / A_i) eps_j eps_i G[j, i]`` with
    ``G = (I - F rho)^-1 F``. In an enclosure each row sums to ``eps_i``, and
    ``A_i SF[i, j] = A_j SF[j, i]``; black surfaces (``eps = 1``) give ``F`` itself.

    Parameters
    ----------
    F : array_like of shape (N, N)
        Form factors (``F[i, j]``: from i to j).
    areas, emissivities : array_like of shape (N,)
        Emissivities in ``[0, 1]``.

    Returns
    -------
    ndarray of shape (N, N)

    Examples
    --------
    Two surfaces that see only each other (parallel plates): ``1 / (1/e1 + 1/e2 - 1)``.

    >>> round(float(script_f([[0, 1], [1, 0]], [1, 1], [0.5, 0.8])[0, 1]), 12)
    0.444444444444
    """
    F = np.asarray(F, dtype=float)
    A = np.asarray(areas, dtype=float)
    eps = np.asarray(emissivities, dtype=float)
    n = len(A)
    if F.shape != (n, n) or eps.shape != (n,):
        raise ValueError(f"script_f: F must be (N, N) and areas, emissivities (N,), got "
                         f"{F.shape}, {A.shape}, {eps.shape}")
    if not (np.all(np.isfinite(eps)) and np.all((eps >= 0) & (eps <= 1))):
        raise ValueError("script_f: emissivities must be in [0, 1]")
    if not np.all(A > 0):
        raise ValueError("script_f: areas must be positive")
    G = np.linalg.solve(np.eye(n) - F * (1.0 - eps)[None, :], F)
    return (A[None, :] / A[:, None]) * eps[None, :] * eps[:, None] * G.T


def write_view3d_factors(path, F, scene=None, *, areas=None, emissivities=None,
                         encl=None, emit=None, binary=None, fmt="%.17g",
                         program="exactff", version=None):
    """Write a matrix in View3D's output file layout (View3D's ``SaveVF``), so that what
    reads View3D's output (its ViewHT program, a user's scripts) reads it.

    Text (View3D's ``out=0``): a header line ``program version 0 encl emit N`` padded to
    30 characters; the N areas; N lines of N factors (row i: from surface i); the N
    emissivities, each line's values separated by one blank. Binary (``out=1``): the
    same header in 32 bytes (ending ``\\r\\n``), then float32 areas, rows and
    emissivities.

    Parameters
    ----------
    path : str or os.PathLike
    F : array_like of shape (N, N)
        Form factors: ``area_form_factors(scene, combine=True)`` for a View3D scene.
    scene : Scene, optional
        Gives the areas, emissivities and ``encl``, ``emit`` and ``out`` of a View3D
        scene (its combined surfaces, :func:`exactff.combine.combined_surfaces`), or the
        polygons' areas of another scene.
    areas, emissivities : array_like of shape (N,), optional
        Instead of (or over) the scene's. Emissivities default to 0.999 where unknown
        (View3D's largest).
    encl, emit : bool, optional
        The header's flags (default: the scene's control values, else 0). With ``emit``
        the factors written are :func:`script_f` of ``F``, as View3D writes them; ``F``
        itself stays the geometric form factors.
    binary : bool, optional
        View3D's binary layout (default: the scene's ``out``, else text).
    fmt : str, default "%.17g"
        The text format of every value: full precision, so that reading the file gives
        ``F`` back exactly. ``"view3d"`` writes View3D's own (``%g`` areas, ``%.6f``
        factors, ``%.3f`` emissivities).
    program, version : str
        The header's first two words (default ``exactff`` and its version; ViewHT keeps
        at most 15 and 7 characters).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "two.vf"
    >>> write_view3d_factors(p, [[0, 0.25], [0.5, 0]], areas=[2, 1], emissivities=[0.9, 0.9],
    ...                      fmt="view3d", program="View3D", version="3.3.1")
    >>> print(p.read_text())
    View3D 3.3.1 0 0 0 2          
    2 1
    0.000000 0.250000
    0.500000 0.000000
    0.900 0.900
    <BLANKLINE>
    """
    from ..version import __version__

    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or F.shape[0] != F.shape[1]:
        raise ValueError(f"F must be a square matrix, got shape {F.shape}")
    n = F.shape[0]
    ctl = {}
    if scene is not None:
        scene = as_scene(scene)
        v3 = scene.metadata.get("view3d")
        c = combined_surfaces(scene)
        if len(c) != n:
            raise ValueError(f"F is {n} x {n} but the scene has {len(c)} surfaces as View3D "
                             f"reports them (area_form_factors(scene, combine=True) gives "
                             f"that matrix)")
        areas = c.areas if areas is None else areas
        if emissivities is None and v3 is not None:
            emissivities = c.emissivities
        ctl = v3["control"] if v3 is not None else {}
    if areas is None:
        raise ValueError("areas: give a scene or the areas")
    A = np.asarray(areas, dtype=float)
    top = tol.VIEW3D_EMISSIVITY_RANGE[1]
    eps = np.full(n, top) if emissivities is None else np.asarray(emissivities, dtype=float)
    eps = np.where(np.isnan(eps), top, eps)
    if A.shape != (n,) or eps.shape != (n,):
        raise ValueError(f"areas and emissivities must have {n} values, got {A.shape}, "
                         f"{eps.shape}")
    encl = int(bool(ctl.get("encl", 0) if encl is None else encl))
    emit = int(bool(ctl.get("emit", 0) if emit is None else emit))
    binary = bool(ctl.get("out", 0) if binary is None else binary)
    version = __version__ if version is None else str(version)
    if len(program) > 15 or len(version) > 7 or not program or " " in program + version:
        raise ValueError(f"program {program!r} and version {version!r}: one word each, at "
                         f"most 15 and 7 characters (what View3D's readers keep)")
    M = script_f(F, A, eps) if emit else F
    header = f"{program} {version} {int(binary)} {encl} {emit} {n}"
    if binary:
        if len(header) > 30:
            raise ValueError(f"the header {header!r} does not fit View3D's 30 characters")
        with open(path, "wb") as fh:
            fh.write((header.ljust(30) + "\r\n").encode("ascii"))
            for a in (A, M, eps):
                fh.write(np.asarray(a, dtype="<f4").tobytes())
        return
    if fmt == "view3d":
        f_area, f_ff, f_eps = "%g", "%.6f", "%.3f"
    else:
        f_area = f_ff = f_eps = fmt
    line = lambda values, f: " ".join(f % v for v in values)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(header.ljust(30) + "\n")
        fh.write(line(A, f_area) + "\n")
        for row in M:
            fh.write(line(row, f_ff) + "\n")
        fh.write(line(eps, f_eps) + "\n")


def read_view3d_factors(path):
    """Read a View3D output file (text or binary, as View3D or
    :func:`write_view3d_factors` writes it).

    Returns
    -------
    dict
        ``program``, ``version``, ``format`` (0 text, 1 binary), ``encl``, ``emit``,
        ``F`` (N x N; script-F factors when ``emit`` is 1), ``areas``, ``emissivities``.

    Raises
    ------
    ValueError
        A header that is not View3D's, or too few values; the message names the file.
    """
    path = os.fspath(path)
    with open(path, "rb") as fh:
        data = fh.read()
    head = data[:32].split(b"\n")[0].decode("ascii", "replace").split()
    try:
        program, version, fmt, encl, emit, n = head[:6]
        fmt, encl, emit, n = int(fmt), int(encl), int(emit), int(n)
    except ValueError:
        raise ValueError(f"{path}: line 1: not a View3D header ('program version format "
                         f"encl emit N'): {' '.join(head)!r}") from None
    if fmt == 1:
        values = np.frombuffer(data[32:], dtype="<f4").astype(float)
    else:
        try:
            values = np.array(data.split(b"\n", 1)[1].split(), dtype=float)
        except (ValueError, IndexError):
            raise ValueError(f"{path}: a value after the header is not a number") from None
    need = n * n + 2 * n
    if len(values) < need:
        raise ValueError(f"{path}: {len(values)} values after the header, {need} expected "
                         f"for N = {n} (areas, N x N factors, emissivities)")
    return {"program": program, "version": version, "format": fmt, "encl": encl,
            "emit": emit, "areas": values[:n], "F": values[n:n + n * n].reshape(n, n),
            "emissivities": values[n + n * n:need]}
