"""View factors for heat-transfer solvers: Elmer's ``ViewFactors.dat`` and OpenFOAM's
``F`` / ``globalFaceFaces`` pair."""

import os

from ..scene import Scene
from .matrices import FULL_PRECISION, check_number_format, matrix_rows

__all__ = ["write_elmer_view_factors", "write_openfoam_view_factors", "patch_ranges"]


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
