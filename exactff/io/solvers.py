"""View factors for heat-transfer solvers: Elmer's ``ViewFactors.dat`` and OpenFOAM's
``F`` / ``globalFaceFaces`` pair."""

import os

from ..scene import Scene
from .matrices import FULL_PRECISION, check_number_format, matrix_rows

__all__ = ["write_elmer_view_factors", "write_openfoam_view_factors", "patch_ranges",
           "read_elmer_view_factors", "read_openfoam_view_factors"]


def write_elmer_view_factors(path, F, *, min_factor=0.0, fmt=FULL_PRECISION):
    """Write a form-factor matrix as Elmer's view-factor file: sparse rows, the factors
    above a minimum.

    Parameters
    ----------
    path : str or os.PathLike
        Where ElmerSolver looks for it: ``MESHDIR/ViewFactors.dat`` (the simulation's
        ``View Factors`` keyword renames it; radiation boundary ``k > 1`` reads
        ``ViewFactors.datk``).
    F : array_like or scipy.sparse matrix of shape (N, N)
        ``F[i, j]``: the area form factor from radiation element i to element j
        (:func:`exactff.area_form_factors`), the rows in Elmer's order of the radiation
        boundary elements (the boundary elements with ``Radiation = Diffuse Gray`` of
        this radiation boundary, in the mesh's order).
    min_factor : float, default 0
        Only ``F[i, j] > min_factor`` is written (Elmer's own ViewFactors writes the
        factors above a tenth of its ``Minimum View Factor``, 1e-20 by default). With
        0 every positive factor is written, and the file holds the whole matrix.
    fmt : str, default ``"%.17g"``
        The number format: 17 significant digits read back to the same doubles.

    Notes
    -----
    The layout, as Elmer's ViewFactors program writes it in ASCII and ElmerSolver's
    RadiationFactors reads it (list-directed Fortran I/O; ``fem/src/ViewFactors.F90``
    and ``fem/src/RadiationFactors.F90``,
    https://github.com/ElmerCSC/elmerfem/blob/devel/fem/src/ViewFactors.F90): for
    each element ``i = 1..N`` in order, a line with the number ``n_i`` of its factors,
    then ``n_i`` lines ``i j F_ij`` (numbered from 1). Elmer recomputes the factors when
    the file is missing; with the file in place it reads these.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "ViewFactors.dat"
    >>> write_elmer_view_factors(p, [[0, 0.75, 0.25], [0.5, 0, 0.5], [0, 0, 0]])
    >>> print(p.read_text(), end="")
    2
    1 2 0.75
    1 3 0.25
    2
    2 1 0.5
    2 3 0.5
    0
    """
    check_number_format(fmt)
    out = []
    for i, (cols, vals) in enumerate(matrix_rows(F, min_factor), start=1):
        out.append(f"{len(cols)}\n")
        out.extend(f"{i} {j + 1} {fmt % v}\n" for j, v in zip(cols.tolist(), vals.tolist()))
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("".join(out))


def patch_ranges(patches):
    """The faces of each patch as ``(name, first, end)``, in order, when every patch's
    faces are consecutive (as viewFactorsGen numbers them); else a ValueError naming the
    first face out of place.

    Examples
    --------
    >>> patch_ranges(["floor", "floor", "walls", "walls", "walls"])
    [('floor', 0, 2), ('walls', 2, 5)]
    >>> patch_ranges(["floor", "walls", "floor"])
    Traceback (most recent call last):
    ...
    ValueError: patches[2]: 'floor' again after 'walls': a patch's faces must be consecutive (viewFactorsGen numbers the faces patch by patch)
    """
    out = []
    for i, name in enumerate(patches):
        if not isinstance(name, str) or not name:
            raise ValueError(f"patches[{i}]: expected a patch name, got {name!r}")
        if out and out[-1][0] == name:
            out[-1][2] = i + 1
            continue
        if any(p[0] == name for p in out):
            raise ValueError(f"patches[{i}]: {name!r} again after {out[-1][0]!r}: a patch's "
                             f"faces must be consecutive (viewFactorsGen numbers the faces "
                             f"patch by patch)")
        out.append([name, i, i + 1])
    return [tuple(p) for p in out]


def _foam_file(cls, obj, location, comments, rows):
    from ..version import __version__

    head = (
        "/*--------------------------------*- C++ -*----------------------------------*\\\n"
        f"  Written by exactff {__version__}: exact view factors\n"
        "\\*---------------------------------------------------------------------------*/\n"
        "FoamFile\n{\n"
        "    version     2.0;\n"
        "    format      ascii;\n"
        f"    class       {cls};\n"
        f"    location    \"{location}\";\n"
        f"    object      {obj};\n"
        "}\n"
        "// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //\n\n")
    body = "".join(f"// {c}\n" for c in comments) + f"{len(rows)}\n(\n"
    body += "".join(f"{len(r)}({' '.join(r)})\n" for r in rows)
    return head + body + ")\n\n\n// " + "*" * 73 + " //\n"


def write_openfoam_view_factors(case, F, *, patches=None, region=None, min_factor=0.0,
                                fmt=FULL_PRECISION):
    """Write a form-factor matrix as OpenFOAM's view-factor pair ``constant/F`` and
    ``constant/globalFaceFaces``, the files viewFactorsGen writes and the
    ``viewFactor`` radiation model reads.

    Parameters
    ----------
    case : str or os.PathLike
        The case directory; the files go to ``case/constant/`` (``case/constant/REGION/``
        with ``region``), which is made if needed.
    F : array_like or scipy.sparse matrix of shape (N, N)
        ``F[i, j]``: the area form factor from face i to face j
        (:func:`exactff.area_form_factors`). The faces are viewFactorsGen's coarse
        faces, in its order: the view-factor patches in the boundary's order (in
        OpenFOAM-dev's viewFactorsGen, the patches whose ``qr`` is ``fixedValue``),
        each patch's faces in the order of its agglomeration (``finalAgglom``; one face
        each when nothing is agglomerated).
    patches : sequence of N str, or Scene, optional
        The patch of each face (a Scene gives its ``groups``): checked to be
        consecutive, and written as a comment that says which faces belong to which
        patch.
    region : str, optional
        A mesh region (``chtMultiRegionFoam`` cases).
    min_factor : float, default 0
        Only ``F[i, j] > min_factor`` is written, as viewFactorsGen writes only the
        faces it sees; with 0, every positive factor.
    fmt : str, default ``"%.17g"``
        The number format: 17 significant digits read back to the same doubles.

    Returns
    -------
    tuple of str
        The paths of ``F`` and ``globalFaceFaces``.

    Notes
    -----
    The layout, as viewFactorsGen writes it
    (``applications/utilities/preProcessing/viewFactorsGen/viewFactorsGen.C``,
    https://github.com/OpenFOAM/OpenFOAM-dev/tree/master/applications/utilities/preProcessing/viewFactorsGen):
    both are lists of lists in OpenFOAM's ASCII format under a ``FoamFile`` header,
    ``F`` of class ``scalarListList`` and ``globalFaceFaces`` of class
    ``labelListList``, in ``mesh.facesInstance()`` (``constant``). Row i of
    ``globalFaceFaces`` lists the faces j (numbered from 0) that face i sees, and row i
    of ``F`` their view factors F(i -> j), in the same order. The radiation model also
    reads the agglomeration (``finalAgglom``, from faceAgglomerate) and the parallel
    map (``mapDist``, or ``subMap``, ``constructMap`` and ``constructMapDim`` in older
    versions), which describe the mesh, not the factors: run faceAgglomerate and
    viewFactorsGen once as usual, then replace ``F`` and ``globalFaceFaces`` by these.
    Serial runs only: in a decomposed case each processor holds its own rows and a
    compact numbering that exactff does not write.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> case = pathlib.Path(tempfile.mkdtemp())
    >>> f, g = write_openfoam_view_factors(case, [[0, 1], [1, 0]], patches=["a", "b"])
    >>> print(pathlib.Path(f).read_text().split("* //\\n\\n", 1)[1])
    // patch a: faces 0 to 0
    // patch b: faces 1 to 1
    2
    (
    1(1)
    1(1)
    )
    <BLANKLINE>
    <BLANKLINE>
    // ************************************************************************* //
    <BLANKLINE>
    """
    check_number_format(fmt)
    rows = matrix_rows(F, min_factor)
    comments = []
    if patches is not None:
        if isinstance(patches, Scene):
            patches = patches.groups
        patches = list(patches)
        if len(patches) != len(rows):
            raise ValueError(f"patches: expected one patch name per face ({len(rows)}), "
                             f"got {len(patches)}")
        comments = [f"patch {name}: faces {first} to {end - 1}"
                    for name, first, end in patch_ranges(patches)]
    if region is not None and (not isinstance(region, str) or not region
                               or "/" in region or region != region.strip()):
        raise ValueError(f"region: expected a region name, got {region!r}")
    where = os.path.join(os.fspath(case), "constant", *([region] if region else []))
    os.makedirs(where, exist_ok=True)
    location = "constant" + (f"/{region}" if region else "")
    values = [[fmt % v for v in vals.tolist()] for _, vals in rows]
    faces = [[str(j) for j in cols.tolist()] for cols, _ in rows]
    out = []
    for name, cls, data in (("F", "scalarListList", values),
                            ("globalFaceFaces", "labelListList", faces)):
        target = os.path.join(where, name)
        with open(target, "w", encoding="utf-8") as fh:
            fh.write(_foam_file(cls, name, location, comments, data))
        out.append(target)
    return tuple(out)


def read_elmer_view_factors(path):
    """Read Elmer's view-factor file (as :func:`write_elmer_view_factors` and Elmer's
    ViewFactors program write it).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    scipy.sparse.csr_array of shape (N, N)
        ``F[i, j]`` for the entries the file lists (the others left out); N is the
        number of rows (radiation elements) in the file.

    Raises
    ------
    ValueError
        A line that is not a count or ``i j F_ij``, a row out of order, a column out of
        range, or a file that ends inside a row (the message names the file and line).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "ViewFactors.dat"
    >>> write_elmer_view_factors(p, [[0, 0.75, 0.25], [0.5, 0, 0.5], [0, 0, 0]])
    >>> read_elmer_view_factors(p).toarray().tolist()
    [[0.0, 0.75, 0.25], [0.5, 0.0, 0.5], [0.0, 0.0, 0.0]]
    """
    import numpy as np
    import scipy.sparse as sp

    path = os.fspath(path)
    with open(path, encoding="utf-8") as fh:
        lines = [(k, line.split()) for k, line in enumerate(fh, start=1) if line.strip()]
    rows, cols, vals = [], [], []
    n = 0
    pos = 0
    while pos < len(lines):
        k, words = lines[pos]
        if len(words) != 1:
            raise ValueError(f"{path}:{k}: expected the number of factors of row {n + 1}, "
                             f"got {' '.join(words)!r}")
        try:
            count = int(words[0])
        except ValueError:
            raise ValueError(f"{path}:{k}: expected the number of factors of row {n + 1}, "
                             f"got {words[0]!r}") from None
        n += 1
        if count < 0 or pos + 1 + count > len(lines):
            raise ValueError(f"{path}: ends inside row {n} ({count} factors announced at "
                             f"line {k})")
        for k2, w in lines[pos + 1:pos + 1 + count]:
            try:
                if len(w) != 3:
                    raise ValueError(w)
                i, j, f = int(w[0]), int(w[1]), float(w[2])
            except ValueError:
                raise ValueError(f"{path}:{k2}: expected 'i j F_ij', got "
                                 f"{' '.join(w)!r}") from None
            if i != n:
                raise ValueError(f"{path}:{k2}: row {i} where row {n} was expected")
            rows.append(i - 1)
            cols.append(j - 1)
            vals.append(f)
        pos += 1 + count
    if any(j < 0 or j >= n for j in cols):
        bad = next(j for j in cols if j < 0 or j >= n)
        raise ValueError(f"{path}: column {bad + 1} outside 1..{n} (the file has {n} rows)")
    if not np.all(np.isfinite(vals)):
        raise ValueError(f"{path}: a view factor is NaN or infinite")
    return sp.csr_array((np.array(vals, dtype=float), (np.array(rows, dtype=np.int64),
                                                       np.array(cols, dtype=np.int64))),
                        shape=(n, n))


def _foam_tokens(text, path):
    """The tokens of an OpenFOAM ASCII file after its ``FoamFile`` header: numbers and
    parentheses, comments removed."""
    import re

    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    if re.search(r"format\s+binary", text):
        raise ValueError(f"{path}: a binary OpenFOAM file (format binary): run "
                         f"'foamFormatConvert' to write it in ascii first")
    text = re.sub(r"//[^\n]*", " ", text)
    head = re.search(r"FoamFile\s*\{[^}]*\}", text)
    if head:
        text = text[head.end():]
    return re.findall(r"[()]|[^\s()]+", text)


def _foam_list_list(path, kind):
    """An OpenFOAM ``labelListList`` or ``scalarListList`` (ASCII) as a list of lists."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        tokens = _foam_tokens(fh.read(), path)
    pos = 0

    def take(what):
        nonlocal pos
        if pos >= len(tokens):
            raise ValueError(f"{path}: ends where {what} was expected")
        pos += 1
        return tokens[pos - 1]

    def count(what):
        t = take(what)
        try:
            return int(t)
        except ValueError:
            raise ValueError(f"{path}: expected {what} (an integer), got {t!r}") from None

    n = count("the number of faces")
    if take("'('") != "(":
        raise ValueError(f"{path}: expected '(' after the number of faces")
    out = []
    for i in range(n):
        k = count(f"the length of list {i}")
        if take("'('") != "(":
            raise ValueError(f"{path}: expected '(' after the length of list {i}")
        items = [take(f"item of list {i}") for _ in range(k)]
        if take("')'") != ")":
            raise ValueError(f"{path}: list {i} holds more than its {k} items")
        try:
            out.append([kind(t) for t in items])
        except ValueError:
            raise ValueError(f"{path}: list {i}: not {kind.__name__}s: {items[:4]}") from None
    if take("')'") != ")":
        raise ValueError(f"{path}: more than the {n} lists announced")
    return out


def read_openfoam_view_factors(case, *, region=None):
    """Read OpenFOAM's view-factor pair ``constant/F`` and ``constant/globalFaceFaces``
    (as viewFactorsGen and :func:`write_openfoam_view_factors` write them; ASCII).

    Parameters
    ----------
    case : str or os.PathLike
        The case directory, or the path of its ``F`` file (``globalFaceFaces`` beside
        it).
    region : str, optional
        A mesh region (``constant/REGION/``).

    Returns
    -------
    (scipy.sparse.csr_array of shape (N, N), list of str or None)
        ``F[i, j]`` for the faces j that face i sees (the others left out), and each
        face's patch where the file says it (the comments
        :func:`write_openfoam_view_factors` writes), else None.

    Raises
    ------
    ValueError
        A file missing, binary, or malformed; the two files' lists not of one shape; a
        face index out of range (the message names the file).

    Examples
    --------
    >>> import tempfile
    >>> case = tempfile.mkdtemp()
    >>> _ = write_openfoam_view_factors(case, [[0, 1], [0.5, 0.5]], patches=["a", "b"])
    >>> F, patches = read_openfoam_view_factors(case)
    >>> F.toarray().tolist(), patches
    ([[0.0, 1.0], [0.5, 0.5]], ['a', 'b'])
    """
    import re

    import numpy as np
    import scipy.sparse as sp

    case = os.fspath(case)
    if os.path.isdir(case):
        where = os.path.join(case, "constant", *([region] if region else []))
        f_path = os.path.join(where, "F")
    else:
        f_path = case
        where = os.path.dirname(case)
    g_path = os.path.join(where, "globalFaceFaces")
    for p in (f_path, g_path):
        if not os.path.exists(p):
            raise ValueError(f"{p}: not found (OpenFOAM's view factors are the pair F and "
                             f"globalFaceFaces in constant/)")
    values = _foam_list_list(f_path, float)
    faces = _foam_list_list(g_path, int)
    n = len(values)
    if len(faces) != n or any(len(a) != len(b) for a, b in zip(values, faces)):
        raise ValueError(f"{f_path} and {g_path}: the lists differ in shape (row i of F "
                         f"holds the factors to the faces of row i of globalFaceFaces)")
    rows = np.repeat(np.arange(n), [len(v) for v in values])
    cols = np.array([j for r in faces for j in r], dtype=np.int64)
    data = np.array([v for r in values for v in r], dtype=float)
    if cols.size and (cols.min() < 0 or cols.max() >= n):
        raise ValueError(f"{g_path}: face {int(cols[(cols < 0) | (cols >= n)][0])} outside "
                         f"0..{n - 1} (a decomposed case's compact numbering is not read)")
    if not np.all(np.isfinite(data)):
        raise ValueError(f"{f_path}: a view factor is NaN or infinite")
    with open(f_path, encoding="utf-8", errors="replace") as fh:
        ranges = re.findall(r"//\s*patch\s+(\S+):\s*faces\s+(\d+)\s+to\s+(\d+)", fh.read())
    patches = None
    if ranges:
        patches = [None] * n
        for name, a, b in ranges:
            for k in range(int(a), min(int(b) + 1, n)):
                patches[k] = name
        if any(p is None for p in patches):
            patches = None
    return sp.csr_array((data, (rows, cols)), shape=(n, n)), patches
