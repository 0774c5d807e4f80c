"""Form-factor matrices on their way to other tools' files: the checks every writer
shares, and the number format that keeps every digit."""

import numpy as np

__all__ = ["FULL_PRECISION", "as_square_matrix", "check_number_format", "matrix_rows"]

#: ``printf`` format of the writers: 17 significant digits, enough for every double to
#: read back to the same double (IEEE 754: 17 decimal digits round-trip binary64)
FULL_PRECISION = "%.17g"


def check_number_format(fmt, name="fmt"):
    """``fmt`` if it formats a float as one number (``"%.17g"``, ``"%.6e"``), else a
    ValueError naming the argument.

    Examples
    --------
    >>> check_number_format("%.6f") % 0.25
    '0.250000'
    >>> check_number_format("%d %d")
    Traceback (most recent call last):
    ...
    ValueError: fmt: expected a printf format for one float, such as '%.17g', got '%d %d'
    """
    try:
        text = fmt % 0.5
        float(text)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a printf format for one float, such as "
                         f"'%.17g', got {fmt!r}") from None
    return fmt


def as_square_matrix(F, n=None, name="F"):
    """A form-factor matrix as a dense float array of shape (N, N), checked.

    Parameters
    ----------
    F : array_like or scipy.sparse matrix of shape (N, N)
        ``F[i, j]`` is the form factor from surface i to surface j
        (``docs/explanation/conventions.md``).
    n : int, optional
        The N the caller expects (the number of names or polygons).
    name : str
        The argument's name, for the errors.

    Returns
    -------
    ndarray of shape (N, N)

    Raises
    ------
    ValueError
        ``F`` is not square, not of size ``n``, or holds NaN or infinite values; the
        message names the argument and, for a bad value, its first row and column.

    Examples
    --------
    >>> as_square_matrix([[0, 1], [1, 0]]).tolist()
    [[0.0, 1.0], [1.0, 0.0]]
    >>> as_square_matrix([[0, 1], [1, float("nan")]])
    Traceback (most recent call last):
    ...
    ValueError: F: NaN or infinite value at row 1, column 1
    """
    if hasattr(F, "toarray"):
        F = F.toarray()
    try:
        A = np.array(F, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: not a matrix of numbers ({exc})") from None
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name}: expected a square matrix of shape (N, N), got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise ValueError(f"{name}: expected shape ({n}, {n}) (one row and column per "
                         f"surface), got {A.shape}")
    bad = np.argwhere(~np.isfinite(A))
    if len(bad):
        raise ValueError(f"{name}: NaN or infinite value at row {bad[0][0]}, column {bad[0][1]}")
    return A


def matrix_rows(F, min_factor=0.0, n=None, name="F"):
    """The entries of each row above ``min_factor``: what a sparse view-factor file
    keeps.

    Parameters
    ----------
    F : array_like or scipy.sparse matrix of shape (N, N)
    min_factor : float, default 0
        Entries ``F[i, j] > min_factor`` are kept (with 0, every positive form factor;
        exact zeros and negative values are left out).
    n : int, optional
    name : str

    Returns
    -------
    list of (ndarray of int, ndarray of float)
        For each row i, the columns j kept, increasing, and their ``F[i, j]``.

    Examples
    --------
    >>> [(c.tolist(), v.tolist()) for c, v in matrix_rows([[0, 0.5], [1e-9, 0.25]], 1e-6)]
    [([1], [0.5]), ([1], [0.25])]
    """
    if not (isinstance(min_factor, (int, float, np.floating, np.integer))
            and np.isfinite(min_factor) and min_factor >= 0):
        raise ValueError(f"min_factor: expected a finite number >= 0, got {min_factor!r}")
    A = as_square_matrix(F, n=n, name=name)
    out = []
    for row in A:
        cols = np.flatnonzero(row > min_factor)
        out.append((cols, row[cols]))
    return out
