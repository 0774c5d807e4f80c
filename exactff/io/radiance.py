"""Radiance scene descriptions (``.rad``): the polygons, with their names and
modifiers."""

import os
import re
import warnings

from ..checks import finite_float
from ..scene import build_scene

__all__ = ["read_rad", "RADIANCE_SURFACES"]

#: Radiance's surface primitives (Radiance reference manual, "Surfaces"). Only
#: ``polygon`` is read; the others are curved or refer to other files, and are counted
#: in ``skipped_primitives`` with a warning. Every other primitive type (materials,
#: patterns, textures, mixtures, ``alias``) describes no geometry and is passed over.
RADIANCE_SURFACES = ("source", "sphere", "bubble", "polygon", "cone", "cup", "cylinder",
                     "tube", "ring", "instance", "mesh")

_WORD = re.compile(r'"[^"]*"|\S+')


def _words(path):
    """``(word, line)`` for every word of the file; a ``#`` word where a primitive may
    start comments out the rest of its line (handled by the reader)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for lineno, raw in enumerate(fh, start=1):
            for m in _WORD.finditer(raw):
                yield m.group(0), lineno


def read_rad(path, **options):
    """Read the polygons of a Radiance scene description into a Scene.

    A Radiance primitive is ``modifier type identifier`` followed by three argument
    lists, each its count and then its values: strings, integers, reals (an ``alias``
    has one word instead, the primitive it copies; Radiance
    reference manual, "Scene Description";
    https://radsite.lbl.gov/radiance/refer/ray.html). A polygon has no string or integer
    argument and ``3 k`` reals, the ``k`` vertices, counter-clockwise seen from its
    front (Radiance's surface normal follows the right-hand rule, as exactff's: no
    vertex is reordered). Every ``polygon`` becomes one polygon of the scene, in file order, with
    its identifier (``scene.names``) and its modifier (``scene.materials``).

    Parameters
    ----------
    path : str or os.PathLike
    **options
        Passed to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
        ``planarity_rtol``).

    Returns
    -------
    Scene
        ``scene.skipped_primitives`` (and ``describe(scene)["skipped_primitives"]``)
        counts the other surface primitives (:data:`RADIANCE_SURFACES`), which are not
        read: ``{"sphere": 1, "ring": 2}``. Each file that has some warns once.

    Raises
    ------
    ValueError
        A primitive is malformed (a count that is not a whole number, too few
        arguments, a real that is not a finite number, a polygon with string or integer
        arguments or a number of reals that is not ``3 k``, ``k >= 3``), or the file
        has an inline command (``!genbox ...``): exactff runs no commands; expand
        them first (``xform scene.rad > expanded.rad``). The message names the file,
        the line and the primitive.
    SceneError
        A polygon is ill-formed (the message names its line and identifier).

    Examples
    --------
    >>> import tempfile, pathlib, warnings
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "room.rad"
    >>> _ = p.write_text('''# a floor and a lamp
    ... void plastic white 0 0 5 .8 .8 .8 0 0
    ... white polygon floor
    ... 0
    ... 0
    ... 12  0 0 0   1 0 0   1 1 0   0 1 0
    ... white sphere lamp 0 0 4 0.5 0.5 0.8 0.1
    ... ''')
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     scene = read_rad(p)
    >>> scene.names, scene.materials, scene.skipped_primitives
    (('floor',), ('white',), (('sphere', 1),))
    """
    path = os.fspath(path)
    words = _words(path)
    faces, names, materials, sources, skipped = [], [], [], [], {}
    comment_line = None
    for word, lineno in words:
        if word.startswith("#") or lineno == comment_line:
            comment_line = lineno
            continue
        if word.startswith("!"):
            raise ValueError(f"{path}:{lineno}: inline command {word!r}: exactff runs no "
                             f"commands; expand them first (xform {os.path.basename(path)} "
                             f"> expanded.rad) and read the result")
        head = [(word, lineno)]
        for w in words:
            head.append(w)
            if len(head) == 3:
                break
        if len(head) < 3:
            raise ValueError(f"{path}:{lineno}: a primitive needs a modifier, a type and an "
                             f"identifier, got {' '.join(w for w, _ in head)!r}")
        (modifier, _), (kind, _), (name, _) = head
        what = f"{path}:{lineno}: {kind} {name!r}"
        if kind == "alias":    # "modifier alias identifier original": no argument lists
            if next(words, None) is None:
                raise ValueError(f"{what}: the file ends before the primitive it aliases")
            continue
        args = []
        for part in ("string", "integer", "real"):
            count_word = next(words, None)
            if count_word is None:
                raise ValueError(f"{what}: the file ends before its {part} arguments")
            try:
                count = int(count_word[0])
            except ValueError:
                count = -1
            if count < 0:
                raise ValueError(f"{path}:{count_word[1]}: {kind} {name!r}: expected the "
                                 f"number of {part} arguments, got {count_word[0]!r}")
            values = []
            for _ in range(count):
                w = next(words, None)
                if w is None:
                    raise ValueError(f"{what}: the file ends inside its {count} {part} "
                                     f"arguments (read {len(values)})")
                values.append(w)
            args.append(values)
        if kind in RADIANCE_SURFACES and kind != "polygon":
            skipped[kind] = skipped.get(kind, 0) + 1
        if kind != "polygon":
            continue
        strings, integers, reals = args
        if strings or integers:
            raise ValueError(f"{what}: a polygon has no string or integer arguments, got "
                             f"{len(strings)} and {len(integers)}")
        if len(reals) % 3 or len(reals) < 9:
            raise ValueError(f"{what}: a polygon needs 3 reals (x y z) for each of at least "
                             f"3 vertices, got {len(reals)}")
        xyz = [finite_float(w, f"{path}:{line}: {kind} {name!r}: a coordinate")
               for w, line in reals]
        faces.append([xyz[i:i + 3] for i in range(0, len(xyz), 3)])
        names.append(name)
        materials.append(modifier)
        sources.append(f"{path}:{lineno}: polygon")
    if skipped:
        listed = ", ".join(f"{c} {k}" for k, c in skipped.items())
        warnings.warn(f"{path}: surfaces that are not polygons were not read: {listed}",
                      UserWarning, stacklevel=2)
    if not faces:
        raise ValueError(f"{path}: no polygons")
    return build_scene(faces, names=names, materials=materials, sources=sources,
                       skipped=tuple(skipped.items()), **options)
