"""Argument checks shared by every entry point: each returns the checked value or raises
ValueError naming the argument (in the manner of scikit-image's ``_shared/utils``)."""

import math
import warnings

import numpy as np

__all__ = ["as_point", "as_normal", "as_receiver", "as_receivers", "check_tolerance",
           "row_indices", "check_sides", "finite_float"]


def finite_float(text, where):
    """The finite float a file's field ``text`` holds, or a ValueError that starts with
    ``where`` (the file, the line, the object and the field).

    Examples
    --------
    >>> finite_float("2.5e-1", "a.rad:3: polygon 'p'")
    0.25
    >>> finite_float("nan", "a.rad:3: polygon 'p'")
    Traceback (most recent call last):
    ...
    ValueError: a.rad:3: polygon 'p': expected a finite number, got 'nan'
    """
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not np.isfinite(value):
        raise ValueError(f"{where}: expected a finite number, got {text!r}")
    return value


def as_point(point, name="point"):
    """Return ``point`` as a finite float array of shape (..., 3), or raise ValueError."""
    p = np.asarray(point, dtype=float)
    if p.shape[-1:] != (3,):
        raise ValueError(f"{name} must have shape (..., 3), got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name} must be finite, got {point!r}")
    return p


def as_normal(normal, name="normal"):
    """Return ``normal`` scaled to unit length, shape (..., 3), or raise ValueError.

    Any finite non-zero vector is accepted and normalised.
    """
    n = as_point(normal, name)
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    if np.any(length == 0) or not np.all(np.isfinite(length)):
        raise ValueError(f"{name} must be a non-zero finite vector, got {normal!r}")
    return n / length


def as_receiver(point, normal):
    """One receiver, checked once for every entry point: ``point`` and ``normal`` as float
    arrays of shape (3,), finite, the normal non-zero (returned as given, not scaled:
    the methods normalise it). Raises ValueError naming the argument.

    Examples
    --------
    >>> as_receiver([0, 0, 0], [0, 0, 2])[1].tolist()
    [0.0, 0.0, 2.0]
    >>> as_receiver([0, float("nan"), 0], [0, 0, 1])
    Traceback (most recent call last):
    ...
    ValueError: point must be finite, got [0, nan, 0]
    """
    p = np.asarray(point, dtype=float)
    if p.shape == (3,):
        # one point and one normal, each of shape (3,) (a row's call: the checks of
        # as_receivers on three floats each, in its order, without numpy's whole-array
        # steps)
        x = p.tolist()
        if not (math.isfinite(x[0]) and math.isfinite(x[1]) and math.isfinite(x[2])):
            raise ValueError(f"point must be finite, got {point!r}")
        n = np.asarray(normal, dtype=float)
        if n.shape == (3,):
            m = n.tolist()
            if not (math.isfinite(m[0]) and math.isfinite(m[1]) and math.isfinite(m[2])):
                raise ValueError(f"normal must be finite, got {normal!r}")
            # (the squared length as np.linalg.norm forms it: zero where every square
            # underflows, infinite where one overflows, as as_normal refuses them)
            squared = m[0] * m[0] + m[1] * m[1] + m[2] * m[2]
            if squared == 0 or not math.isfinite(squared):
                raise ValueError(f"normal must be a non-zero finite vector, got {normal!r}")
            return p, n
    P, N, shape = as_receivers(point, normal)
    if shape != ():
        raise ValueError(f"point and normal must have shape (3,), got {np.shape(point)} and "
                         f"{np.shape(normal)}")
    return P[0], N[0]


def as_receivers(point, normal, names=("point", "normal")):
    """Receivers broadcast together: ``(P, N, shape)`` with ``P``, ``N`` of shape (M, 3)
    (normals as given, not scaled) and ``shape`` the broadcast shape without the last
    axis. Raises ValueError naming the argument.

    Examples
    --------
    >>> P, N, shape = as_receivers([[0, 0, 0], [1, 0, 0]], [0, 0, 1])
    >>> P.shape, N.shape, shape
    ((2, 3), (2, 3), (2,))
    """
    p = as_point(point, names[0])
    as_normal(normal, names[1])
    n = np.asarray(normal, dtype=float)
    try:
        p, n = np.broadcast_arrays(p, n)
    except ValueError:
        raise ValueError(f"{names[0]} of shape {p.shape} and {names[1]} of shape {n.shape} "
                         f"do not broadcast") from None
    return p.reshape(-1, 3), n.reshape(-1, 3), p.shape[:-1]


def check_tolerance(tolerance, name="tolerance", allow_none=True):
    """``tolerance`` if it is a positive finite number (or None where allowed), else a
    ValueError naming the argument.

    Examples
    --------
    >>> check_tolerance(1e-9)
    1e-09
    >>> check_tolerance(0)
    Traceback (most recent call last):
    ...
    ValueError: tolerance must be a positive number or None, got 0
    """
    if tolerance is None and allow_none:
        return None
    if (isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating))
            or not (np.isfinite(tolerance) and tolerance > 0)):
        either = " or None" if allow_none else ""
        raise ValueError(f"{name} must be a positive number{either}, got {tolerance!r}")
    return tolerance


def row_indices(rows, n):
    """Rows of an ``n``-polygon scene as an integer array (None: all of them, in order);
    floats, booleans, other non-integers and indices outside ``[0, n)`` raise.

    Examples
    --------
    >>> row_indices([2, 0], 3).tolist(), row_indices(None, 2).tolist()
    ([2, 0], [0, 1])
    >>> row_indices([3], 3)
    Traceback (most recent call last):
    ...
    ValueError: rows must lie in [0, 3), got values from 3 to 3
    """
    if rows is None:
        return np.arange(n)
    r = np.asarray(rows).reshape(-1)
    if r.size and not (np.issubdtype(r.dtype, np.integer) and r.dtype != bool):
        raise ValueError(f"rows must be polygon indices (integers), got {rows!r}")
    r = r.astype(int)
    if r.size and (r.min() < 0 or r.max() >= n):
        raise ValueError(f"rows must lie in [0, {n}), got values from {r.min()} to {r.max()}")
    return r


def check_sides(two_sided, one_sided=None):
    """Whether both sides of a polygon receive, from ``two_sided`` (the option's name
    everywhere) and the deprecated ``one_sided`` (its old name in the point functions,
    ``one_sided = not two_sided``: a DeprecationWarning; ValueError when the two
    disagree). What the public functions pass down as ``two_sided``.

    Examples
    --------
    >>> check_sides(False), check_sides(True)
    (False, True)
    """
    if not isinstance(two_sided, (bool, np.bool_)):
        raise ValueError(f"two_sided must be True or False, got {two_sided!r}")
    if one_sided is None:
        return bool(two_sided)
    warnings.warn("one_sided= is deprecated: use two_sided= (two_sided=not one_sided)",
                  DeprecationWarning, stacklevel=3)
    if two_sided and one_sided:
        raise ValueError("one_sided=True contradicts two_sided=True (one_sided is "
                         "deprecated: give two_sided only)")
    return not one_sided
