"""EnergyPlus: building surfaces read from an IDF file, and form factors written as
``ZoneProperty:UserViewFactors:BySurfaceName``."""

import math
import os
import warnings

import numpy as np

from ..checks import finite_float
from ..scene import Scene, build_scene
from .matrices import FULL_PRECISION, as_square_matrix, check_number_format

__all__ = ["read_idf", "write_energyplus_view_factors", "read_energyplus_view_factors",
           "parse_idf", "IDF_SURFACES",
           "IDF_SKIPPED", "ENERGYPLUS_NAME_LENGTH"]

#: The surface objects read, with the positions of their fields: ``(zone, construction,
#: fields before the vertex count up to EnergyPlus 9.5, the same from 9.6 on)`` (9.6
#: added the ``Space Name`` field after ``Zone Name``). Field positions count from 0 at
#: the object's name. Energy+.idd:
#: https://github.com/NREL/EnergyPlus/blob/develop/idd/Energy%2B.idd.in
IDF_SURFACES = {
    "buildingsurface:detailed": (3, 2, 9, 10),
    "wall:detailed": (2, 1, 8, 9),
    "roofceiling:detailed": (2, 1, 8, 9),
    "floor:detailed": (2, 1, 8, 9),
}

#: Geometric objects that are not read (counted in ``skipped_primitives``, with a
#: warning): subsurfaces (windows and doors lie in their base surface, whose polygon
#: then has a hole exactff cannot represent), shading surfaces, the rectangular
#: shorthand surfaces (given by a corner, azimuth, tilt and size) and internal mass
#: (no geometry).
IDF_SKIPPED = (
    "FenestrationSurface:Detailed", "Window", "Door", "GlazedDoor", "Window:Interzone",
    "Door:Interzone", "GlazedDoor:Interzone", "Shading:Site", "Shading:Building",
    "Shading:Site:Detailed", "Shading:Building:Detailed", "Shading:Zone:Detailed",
    "Shading:Overhang", "Shading:Overhang:Projection", "Shading:Fin",
    "Shading:Fin:Projection", "Wall:Exterior", "Wall:Adiabatic", "Wall:Underground",
    "Wall:Interzone", "Roof", "Ceiling:Adiabatic", "Ceiling:Interzone",
    "Floor:GroundContact", "Floor:Adiabatic", "Floor:Interzone", "InternalMass",
)

#: EnergyPlus's longest object name (``MaxNameLength`` in its input processor)
ENERGYPLUS_NAME_LENGTH = 100

_STARTS = ("upperleftcorner", "lowerleftcorner", "upperrightcorner", "lowerrightcorner")
_DIRECTIONS = ("counterclockwise", "clockwise")
_SYSTEMS = ("relative", "world", "absolute")
# objects whose first field is not a name
_UNNAMED = ("version", "globalgeometryrules")


class _Object:
    """One IDF object: its class, its fields (the class not included) and the line of
    each field."""

    __slots__ = ("kind", "fields", "lines", "line")

    def __init__(self, kind, fields, lines, line):
        self.kind, self.fields, self.lines, self.line = kind, fields, lines, line

    def get(self, i, default=""):
        return self.fields[i] if i < len(self.fields) else default

    def where(self, path, i=None):
        line = self.lines[i] if i is not None and i < len(self.lines) else self.line
        named = self.kind.lower() not in _UNNAMED and self.fields and self.fields[0]
        name = f" {self.fields[0]!r}" if named else ""
        return f"{path}:{line}: {self.kind}{name}"


def parse_idf(path):
    """The objects of an IDF file, in file order.

    IDF syntax (EnergyPlus Input Output Reference, "Input-Output Reference / IDF
    syntax"): an object is its class and its fields separated by commas and ended by a
    semicolon, over any number of lines; ``!`` starts a comment that runs to the end of
    the line; blanks around a field are not part of it.

    Returns
    -------
    list of _Object
        ``kind`` (the class as written), ``fields`` (str, the class not included),
        ``lines`` (the line of each field) and ``line`` (the line of the class).

    Raises
    ------
    ValueError
        An object is not ended by ``;`` before the end of the file (the message names
        the file, the line where it starts and its class).
    """
    objects = []
    fields, lines = [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, start=1):
            text = raw.split("!", 1)[0]
            while text:
                cut = min((k for k in (text.find(","), text.find(";")) if k >= 0), default=-1)
                piece = text if cut < 0 else text[:cut]
                if cut < 0:
                    if piece.strip():
                        if fields and fields[-1] is None:
                            raise ValueError(f"{path}:{lineno}: a field runs over two lines: "
                                             f"{piece.strip()!r}")
                        fields.append(piece.strip())
                        lines.append(lineno)
                        fields.append(None)     # a field still open: ended by , or ;
                        lines.append(lineno)
                    break
                if fields and fields[-1] is None:   # the open field's end
                    fields.pop()
                    lines.pop()
                    if piece.strip():
                        raise ValueError(f"{path}:{lineno}: two values in one field: "
                                         f"{fields[-1]!r} and {piece.strip()!r}")
                else:
                    fields.append(piece.strip())
                    lines.append(lineno)
                if text[cut] == ";":
                    if fields[0]:
                        objects.append(_Object(fields[0], fields[1:], lines[1:], lines[0]))
                    elif len(fields) > 1 or any(fields):
                        raise ValueError(f"{path}:{lines[0]}: an object without a class")
                    fields, lines = [], []
                text = text[cut + 1:]
    if fields and fields[-1] is None:
        fields.pop()
    if fields:
        raise ValueError(f"{path}:{lines[0]}: {fields[0] or 'an object'}: not ended by ';' "
                         f"before the end of the file")
    return objects


def _number(obj, i, path, what, default=None):
    text = obj.get(i)
    if text == "" and default is not None:
        return default
    return finite_float(text, f"{obj.where(path, i)}: {what}")


def _version(objects, path):
    for obj in objects:
        if obj.kind.lower() == "version":
            text = obj.get(0)
            try:
                major, minor = (int(p) for p in (text.split(".") + ["0"])[:2])
            except ValueError:
                raise ValueError(f"{obj.where(path, 0)}: expected a version such as "
                                 f"'9.6' or '23.2', got {text!r}") from None
            return major, minor
    return None


def _rules(objects, path):
    rules = [o for o in objects if o.kind.lower() == "globalgeometryrules"]
    if not rules:
        raise ValueError(f"{path}: no GlobalGeometryRules object: EnergyPlus needs one to "
                         f"know the vertex order and the coordinate system (for example "
                         f"'GlobalGeometryRules, UpperLeftCorner, Counterclockwise, World;')")
    if len(rules) > 1:
        raise ValueError(f"{rules[1].where(path)}: a second GlobalGeometryRules object "
                         f"(line {rules[0].line} has the first)")
    obj = rules[0]
    choices = []
    for i, (what, keys, default) in enumerate((
            ("Starting Vertex Position", _STARTS, None),
            ("Vertex Entry Direction", _DIRECTIONS, None),
            ("Coordinate System", _SYSTEMS, "relative"))):
        value = obj.get(i).lower() or default
        if value not in keys:
            raise ValueError(f"{obj.where(path, i)}: {what}: expected one of "
                             f"{', '.join(keys)} (any case), got {obj.get(i)!r}")
        choices.append(value)
    return choices


def _zones(objects, path):
    zones = {}
    for obj in objects:
        if obj.kind.lower() == "zone":
            name = obj.get(0)
            if not name:
                raise ValueError(f"{obj.where(path)}: a zone needs a name")
            zones[name.lower()] = (
                _number(obj, 1, path, "Direction of Relative North", 0.0),
                np.array([_number(obj, k, path, f"{axis} Origin", 0.0)
                          for k, axis in ((2, "X"), (3, "Y"), (4, "Z"))]))
    return zones


def _relative_to_building(P, north, origin):
    """Zone coordinates to building coordinates, as EnergyPlus's ``GetVertices`` does for
    ``Relative``: a rotation about z by minus the zone's Direction of Relative North
    (degrees), then the zone's origin added. Exactly the input when both are zero."""
    if north != 0.0:
        c, s = math.cos(math.radians(-north)), math.sin(math.radians(-north))
        P = np.column_stack([P[:, 0] * c - P[:, 1] * s, P[:, 0] * s + P[:, 1] * c, P[:, 2]])
    if np.any(origin != 0.0):
        P = P + origin
    return P


def read_idf(path, *, facing="inside", **options):
    """Read the building surfaces of an EnergyPlus input file into a Scene.

    Every ``BuildingSurface:Detailed`` (and ``Wall:Detailed``, ``RoofCeiling:Detailed``,
    ``Floor:Detailed``) becomes one polygon, in file order, with its name
    (``scene.names``), its zone (``scene.groups``) and its construction
    (``scene.materials``).

    Parameters
    ----------
    path : str or os.PathLike
    facing : {"inside", "outside"}, default "inside"
        Which side of each surface is its front (the side that receives). EnergyPlus
        lists a surface's vertices counter-clockwise seen from *outside* (the outward
        normal; with ``GlobalGeometryRules`` ``Clockwise``, clockwise from outside).
        exactff's front is the side the vertices run counter-clockwise from (the
        right-hand normal; ``docs/explanation/conventions.md``). ``"inside"`` reverses
        the order (first vertex kept) so that every surface receives from its zone, as
        interior view factors and :func:`write_energyplus_view_factors` need;
        ``"outside"`` keeps EnergyPlus's front (for exterior exchange, between
        buildings).
    **options
        Passed to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
        ``planarity_rtol``).

    Returns
    -------
    Scene
        ``scene.skipped_primitives`` counts the geometric objects not read
        (:data:`IDF_SKIPPED`: windows, doors, shading, rectangular shorthand surfaces).

    Raises
    ------
    ValueError
        The file is malformed, has no (or two) ``GlobalGeometryRules``, a surface's
        zone is not defined while coordinates are relative, a coordinate is not a
        number, or the vertex count does not match the coordinates; the message names
        the file, the line and the object.
    SceneError
        A surface's polygon is ill-formed (the message names its line and name).

    Notes
    -----
    ``GlobalGeometryRules``: the *Vertex Entry Direction* is honoured (``Clockwise``
    vertices are reversed to EnergyPlus's counter-clockwise first). The *Starting
    Vertex Position* (which corner comes first) changes no polygon: the file's first
    vertex stays first. *Coordinate System* ``World`` (or ``Absolute``): the vertices
    are read as they are. ``Relative``: they are relative to their zone, as EnergyPlus
    places them: rotated about z by minus the zone's *Direction of Relative North* and
    moved by the zone's origin (``Zone`` object; exact when both are zero); the
    building's *North Axis* is not applied (it turns the whole building about z, which
    changes no form factor), so the scene is in building coordinates. The
    daylighting and rectangular-surface coordinate systems concern objects this
    reader does not read. The field layout follows the file's ``Version``: from 9.6
    on, surfaces carry a ``Space Name`` after ``Zone Name``; without a ``Version``
    object the layout is the one that leaves whole x, y, z triples.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "floor.idf"
    >>> _ = p.write_text('''Version, 9.4;
    ... GlobalGeometryRules, UpperLeftCorner, Counterclockwise, World;
    ... BuildingSurface:Detailed, Floor, Floor, Slab, Room, Ground, , NoSun, NoWind, , 4,
    ...   4, 4, 0,   4, 0, 0,   0, 0, 0,   0, 4, 0;   ! counter-clockwise from below
    ... ''')
    >>> scene = read_idf(p)
    >>> scene.names, scene.groups, scene.normals[0].tolist()
    (('Floor',), ('Room',), [0.0, 0.0, 1.0])
    """
    if facing not in ("inside", "outside"):
        raise ValueError(f"facing must be 'inside' or 'outside', got {facing!r}")
    path = os.fspath(path)
    objects = parse_idf(path)
    version = _version(objects, path)
    _, direction, system = _rules(objects, path)
    zones = _zones(objects, path) if system == "relative" else {}
    reverse = (direction == "clockwise") != (facing == "inside")
    skipped_kinds = {k.lower(): k for k in IDF_SKIPPED}
    faces, names, groups, materials, sources, skipped = [], [], [], [], [], {}
    for obj in objects:
        kind = obj.kind.lower()
        if kind in skipped_kinds:
            label = skipped_kinds[kind]
            skipped[label] = skipped.get(label, 0) + 1
            continue
        if kind not in IDF_SURFACES:
            continue
        zone_at, construction_at, old, new = IDF_SURFACES[kind]
        n_fields = len(obj.fields)
        if version is not None:
            header = new if version >= (9, 6) else old
        else:
            header = new if (n_fields - new - 1) % 3 == 0 else old
        count_at = header
        coords = obj.fields[count_at + 1:]
        if n_fields <= count_at or len(coords) % 3 or len(coords) < 9:
            layout = f"EnergyPlus {version[0]}.{version[1]}" if version else "this layout"
            raise ValueError(f"{obj.where(path)}: expected {count_at} fields, the vertex "
                             f"count, then x, y, z for each of at least 3 vertices "
                             f"({layout}), got {n_fields} fields")
        k = len(coords) // 3
        count = obj.get(count_at).lower()
        if count not in ("", "autocalculate"):
            stated = _number(obj, count_at, path, "Number of Vertices")
            if stated != k:
                raise ValueError(f"{obj.where(path, count_at)}: Number of Vertices is "
                                 f"{obj.get(count_at)} but {k} vertices follow")
        P = np.array([_number(obj, count_at + 1 + 3 * v + a, path,
                              f"vertex {v + 1} {'xyz'[a]}-coordinate")
                      for v in range(k) for a in range(3)]).reshape(k, 3)
        zone = obj.get(zone_at)
        if not zone:
            raise ValueError(f"{obj.where(path, zone_at)}: no zone name")
        if system == "relative":
            if zone.lower() not in zones:
                raise ValueError(f"{obj.where(path, zone_at)}: zone {zone!r} is not "
                                 f"defined by a Zone object, and the coordinates are "
                                 f"relative to its origin (GlobalGeometryRules: Relative)")
            P = _relative_to_building(P, *zones[zone.lower()])
        if reverse:
            P = np.roll(P[::-1], 1, axis=0)
        faces.append(P)
        names.append(obj.get(0) or None)
        groups.append(zone)
        materials.append(obj.get(construction_at) or None)
        sources.append(f"{path}:{obj.line}: {obj.kind}")
    if skipped:
        listed = ", ".join(f"{c} {k}" for k, c in skipped.items())
        warnings.warn(f"{path}: not read (exactff reads BuildingSurface:Detailed, "
                      f"Wall:Detailed, RoofCeiling:Detailed, Floor:Detailed): {listed}",
                      UserWarning, stacklevel=2)
    if not faces:
        raise ValueError(f"{path}: no building surfaces (BuildingSurface:Detailed, "
                         f"Wall:Detailed, RoofCeiling:Detailed or Floor:Detailed)")
    return build_scene(faces, names=names, groups=groups, materials=materials,
                       sources=sources, skipped=tuple(skipped.items()), **options)


def _check_name(value, what):
    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{what}: expected a non-empty name, got {value!r}")
    bad = [c for c in ",;!\n\r" if c in value]
    if bad or value != value.strip():
        raise ValueError(f"{what}: {value!r} cannot be an EnergyPlus name (no ',', ';', "
                         f"'!', line breaks, or blanks at either end)")
    if len(value) > ENERGYPLUS_NAME_LENGTH:
        raise ValueError(f"{what}: {value!r} is longer than EnergyPlus's "
                         f"{ENERGYPLUS_NAME_LENGTH} characters")
    return value


def write_energyplus_view_factors(path, F, *, names, zone, fmt=FULL_PRECISION,
                                  append=False):
    """Write a form-factor matrix as an EnergyPlus
    ``ZoneProperty:UserViewFactors:BySurfaceName`` object.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (an IDF fragment to include, or the model itself with
        ``append=True``).
    F : array_like or scipy.sparse matrix of shape (N, N)
        ``F[i, j]``: the area form factor from surface i to surface j
        (:func:`exactff.area_form_factors`), each row a surface of the zone.
    names : sequence of N str, or Scene
        The EnergyPlus surface names, in the order of F's rows (a Scene gives its
        ``names``: those :func:`read_idf` read). Unique, ignoring case, as EnergyPlus
        compares them.
    zone : str
        The zone (or ZoneList) the view factors belong to.
    fmt : str, default ``"%.17g"``
        The number format: 17 significant digits read back to the same doubles.
    append : bool, default False
        Add the object to the end of an existing file instead of replacing it.

    Notes
    -----
    The layout (Energy+.idd, https://github.com/NREL/EnergyPlus/blob/develop/idd/Energy%2B.idd.in;
    Input Output Reference, "ZoneProperty:UserViewFactors:BySurfaceName"): the zone
    name, then one ``From Surface, To Surface, View Factor`` triple per pair, every
    pair of the N surfaces (zeros too), in row order; the view factor is F(From -> To).
    EnergyPlus's zone enclosure holds every heat-transfer surface and subsurface of
    the zone: the list must name them all. EnergyPlus checks the factors' closure and
    reciprocity and corrects factors that miss them; an exact matrix of a closed zone
    passes as it is. A window given as its own polygon lying on its wall (the tie rule
    of :func:`exactff.area_form_factors`, the window first) leaves the wall's row per
    unit of its whole area, summing to its uncovered share; EnergyPlus takes the wall's
    net area (without its subsurfaces): divide that row by its uncovered share first.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "vf.idf"
    >>> write_energyplus_view_factors(p, [[0, 1], [1, 0]], names=["A", "B"], zone="Room")
    >>> print(p.read_text().split("\\n", 1)[1], end="")
    ZoneProperty:UserViewFactors:BySurfaceName,
        Room,                    !- Zone Name
        A, A, 0,                 !- From Surface, To Surface, View Factor
        A, B, 1,
        B, A, 1,
        B, B, 0;
    """
    if isinstance(names, Scene):
        names = names.names
    names = list(names)
    for i, name in enumerate(names):
        _check_name(name, f"names[{i}]")
    seen = {}
    for i, name in enumerate(names):
        if name.lower() in seen:
            raise ValueError(f"names[{i}]: {name!r} repeats names[{seen[name.lower()]}] "
                             f"(EnergyPlus names ignore case)")
        seen[name.lower()] = i
    _check_name(zone, "zone")
    check_number_format(fmt)
    A = as_square_matrix(F, n=len(names))
    from ..version import __version__

    out = [f"! exactff {__version__}: view factors F(From Surface -> To Surface), "
           f"written with {fmt}\n",
           "ZoneProperty:UserViewFactors:BySurfaceName,\n",
           f"    {zone + ',':<24} !- Zone Name\n"]
    n = len(names)
    for i in range(n):
        for j in range(n):
            end = ";" if i == n - 1 and j == n - 1 else ","
            line = f"    {names[i]}, {names[j]}, {fmt % A[i, j]}{end}"
            if i == 0 and j == 0:
                line = f"{line:<28} !- From Surface, To Surface, View Factor"
            out.append(line + "\n")
    with open(path, "a" if append else "w", encoding="utf-8") as fh:
        if append:
            fh.write("\n")
        fh.write("".join(out))


def read_energyplus_view_factors(path, *, zone=None):
    """Read a ``ZoneProperty:UserViewFactors:BySurfaceName`` object (as EnergyPlus reads
    it and :func:`write_energyplus_view_factors` writes it).

    Parameters
    ----------
    path : str or os.PathLike
        An IDF file (a whole model, or a fragment) holding the object.
    zone : str, optional
        The zone whose object to read (any case); needed when the file holds several.

    Returns
    -------
    (list of str, scipy.sparse.csr_array of shape (N, N))
        The surface names in the order they first appear (From Surface, then To
        Surface), and ``F[i, j]`` = F(names[i] -> names[j]) for the pairs listed (the
        others left out).

    Raises
    ------
    ValueError
        No such object (or several without ``zone``), a triple cut short, a view factor
        that is not a number, a pair listed twice (the message names the file and
        line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "vf.idf"
    >>> write_energyplus_view_factors(p, [[0, 1], [1, 0]], names=["A", "B"], zone="Room")
    >>> names, F = read_energyplus_view_factors(p)
    >>> names, F.toarray().tolist()
    (['A', 'B'], [[0.0, 1.0], [1.0, 0.0]])
    """
    import scipy.sparse as sp

    path = os.fspath(path)
    found = [o for o in parse_idf(path)
             if o.kind.lower() == "zoneproperty:userviewfactors:bysurfacename"]
    if zone is not None:
        found = [o for o in found if o.get(0).lower() == str(zone).lower()]
    if not found:
        raise ValueError(f"{path}: no ZoneProperty:UserViewFactors:BySurfaceName object"
                         + (f" for zone {zone!r}" if zone is not None else ""))
    if len(found) > 1:
        zones = ", ".join(repr(o.get(0)) for o in found)
        raise ValueError(f"{path}: {len(found)} ZoneProperty:UserViewFactors:BySurfaceName "
                         f"objects (zones {zones}): say which with zone=")
    obj = found[0]
    fields = obj.fields[1:]
    if len(fields) % 3:
        raise ValueError(f"{obj.where(path)}: {len(fields)} fields after the zone name, not "
                         f"From Surface, To Surface, View Factor triples")
    index, names, entries = {}, [], {}
    for t in range(0, len(fields), 3):
        ends = []
        for name in fields[t:t + 2]:
            if not name:
                raise ValueError(f"{obj.where(path, t + 1)}: an empty surface name")
            key = name.lower()
            if key not in index:
                index[key] = len(names)
                names.append(name)
            ends.append(index[key])
        value = _number(obj, t + 3, path, "View Factor")
        pair = tuple(ends)
        if pair in entries:
            raise ValueError(f"{obj.where(path, t + 3)}: the pair {fields[t]!r} -> "
                             f"{fields[t + 1]!r} again")
        entries[pair] = value
    n = len(names)
    rows = np.array([p[0] for p in entries], dtype=np.int64)
    cols = np.array([p[1] for p in entries], dtype=np.int64)
    return names, sp.csr_array((np.array(list(entries.values()), dtype=float),
                                (rows, cols)), shape=(n, n))
