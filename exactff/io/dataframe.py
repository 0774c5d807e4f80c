"""Form-factor matrices as labelled pandas tables."""

import numpy as np

from ..scene import as_scene

__all__ = ["to_dataframe", "polygon_labels"]


def polygon_labels(scene):
    """A label for every polygon: its name where it is unique, else ``"NAME/i"`` or
    ``"GROUP/i"`` (its name or group and its index), else ``"i"``; the plain indices
    ``0..N-1`` (ints) when the scene has neither names nor groups.

    Examples
    --------
    >>> from exactff import Scene
    >>> tri = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    >>> s = Scene.from_polygons([tri] * 4, names=["floor", "wall", "wall", None],
    ...                         groups=[None, None, None, "lamp"])
    >>> polygon_labels(s)
    ['floor', 'wall/1', 'wall/2', 'lamp/3']
    >>> polygon_labels(Scene.from_polygons([tri] * 2))
    [0, 1]
    """
    scene = as_scene(scene)
    names, groups = scene.names, scene.groups
    if all(n is None for n in names) and all(g is None for g in groups):
        return list(range(len(scene)))
    counts = {}
    for n in names:
        counts[n] = counts.get(n, 0) + 1
    out = []
    for i, (n, g) in enumerate(zip(names, groups)):
        if n is not None and counts[n] == 1:
            out.append(n)
        elif n is not None or g is not None:
            out.append(f"{n if n is not None else g}/{i}")
        else:
            out.append(str(i))
    return out


def to_dataframe(F, scene=None, *, rows=None):
    """A form-factor matrix as a pandas DataFrame, its rows and columns labelled by
    polygon.

    Parameters
    ----------
    F : array_like or scipy.sparse matrix of shape (R, N)
        ``F[r, j]``: the form factor from polygon ``rows[r]`` to polygon j (a matrix of
        :func:`exactff.form_factor_matrix` or :func:`exactff.area_form_factors`). A
        sparse matrix gives a DataFrame of sparse columns.
    scene : Scene, optional
        Where the labels come from (:func:`polygon_labels`: the names, or group/index);
        without it the labels are the indices.
    rows : sequence of int, optional
        The polygons of F's rows (as given to ``area_form_factors(scene, rows=...)``);
        all N, in order, by default.

    Returns
    -------
    pandas.DataFrame of shape (R, N)
        ``df.loc[a, b]`` is F(a -> b); the index is named ``"from"``, the columns
        ``"to"``. Needs pandas (``pip install "exactff[formats]"``).

    Raises
    ------
    ValueError
        F is not 2-D, has a number of columns other than the scene's polygons, or a
        number of rows other than ``rows`` (or N); ``rows`` holds an index out of range.

    Examples
    --------
    >>> import exactff as ef
    >>> s = ef.Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
    ...                             [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]],
    ...                            names=["floor", "ceiling"])
    >>> df = ef.to_dataframe(ef.area_form_factors(s), s)
    >>> round(float(df.loc["floor", "ceiling"]), 9)   # Howell C-11: unit squares 1 apart
    0.199824896
    """
    try:
        import pandas as pd
    except ImportError:
        raise ImportError('to_dataframe needs pandas (pip install "exactff[formats]")') from None
    sparse = hasattr(F, "tocsr")
    A = F.tocsr() if sparse else np.asarray(F, dtype=float)
    if A.ndim != 2:
        raise ValueError(f"F: expected a matrix of shape (R, N), got shape {A.shape}")
    n = A.shape[1]
    if scene is not None:
        scene = as_scene(scene)
        if n != len(scene):
            raise ValueError(f"F: {n} columns, but the scene has {len(scene)} polygons")
        labels = polygon_labels(scene)
    else:
        labels = list(range(n))
    if rows is None:
        if A.shape[0] != n:
            raise ValueError(f"F: {A.shape[0]} rows and {n} columns; give rows= (the "
                             f"polygons of the rows) for a matrix of some rows")
        rows = range(n)
    rows = [int(r) for r in rows]
    if len(rows) != A.shape[0]:
        raise ValueError(f"rows: {len(rows)} indices for the {A.shape[0]} rows of F")
    for r in rows:
        if not 0 <= r < n:
            raise ValueError(f"rows: index {r} out of range (0..{n - 1})")
    index = pd.Index([labels[r] for r in rows], name="from")
    columns = pd.Index(labels, name="to")
    if sparse:
        return pd.DataFrame.sparse.from_spmatrix(A, index=index, columns=columns)
    return pd.DataFrame(A, index=index, columns=columns)
