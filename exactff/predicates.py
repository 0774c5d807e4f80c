"""Exact-sign predicates: float evaluation with an error bound, exact rational fallback.

The only place where exactff decides on which side of a plane a point lies.
"""

from fractions import Fraction

import numpy as np

from ._tolerances import EPS

__all__ = ["side_of_plane", "gamma", "tie_priority"]


def gamma(n):
    """Higham's bound ``n u / (1 - n u)`` on the relative error of n roundings."""
    return n * EPS / (1 - n * EPS)


def side_of_plane(points, normal, offset):
    """Exact sign of ``normal @ x - offset`` for each point ``x``.

    The plane is the one the float numbers ``normal`` and ``offset`` describe exactly.
    The value is computed in float with the bound ``gamma(4) (|n| . |x| + |offset|)``;
    only inside that bound is it recomputed with :class:`fractions.Fraction`, which is
    exact for floats.

    Parameters
    ----------
    points : array_like of shape (M, 3)
    normal : array_like of shape (3,)
    offset : float

    Returns
    -------
    ndarray of shape (M,), dtype int8
        +1 in front (the side ``normal`` points to), -1 behind, 0 exactly on the plane.

    Examples
    --------
    >>> side_of_plane([[0.1, 0, 0], [0.3, 0, 0], [0.2, 0, 0]], [1.0, 0, 0], 0.2).tolist()
    [-1, 1, 0]
    >>> side_of_plane([[0.1 + 0.2, 0, 0]], [1.0, 0, 0], 0.3).tolist()  # 0.30000000000000004
    [1]
    """
    X = np.asarray(points, dtype=float).reshape(-1, 3)
    nv = np.asarray(normal, dtype=float)
    v = X @ nv - offset
    bound = gamma(4) * (np.abs(X) @ np.abs(nv) + abs(offset))
    out = np.sign(v).astype(np.int8)
    unsure = np.flatnonzero(np.abs(v) <= bound)
    if len(unsure):
        nf = [Fraction(float(c)) for c in nv]
        of = Fraction(float(offset))
        for i in unsure:
            x = X[i]
            e = (nf[0] * Fraction(float(x[0])) + nf[1] * Fraction(float(x[1]))
                 + nf[2] * Fraction(float(x[2])) - of)
            out[i] = (e > 0) - (e < 0)
    return out


def tie_priority(facing, index=None):
    """Which of several coplanar overlapping polygons is in front: lower is nearer.

    The one rule for depth ties, shared by the visibility engine (the order of a BSP
    node's coplanar fragments) and the discrete methods' z-buffer: a polygon whose front
    faces the point comes before one whose back faces it (the back of a zero-thickness
    wall is inside the wall), and among polygons facing the point the same way the
    first in input order is in front (a light on a ceiling).

    Parameters
    ----------
    facing : array_like of shape (N,), int
        Side of the point for each polygon, in input order: > 0 when its front faces
        the point, < 0 when its back does (0, seen edge-on, sorts with the fronts).
    index : array_like of shape (N,), int, optional
        The polygons' indices in input order (default ``0 .. N-1``), for a subset or
        for fragments that carry their source polygon's index.

    Returns
    -------
    ndarray of shape (N,), int
        A priority per polygon; among tied polygons the lowest is in front.

    Examples
    --------
    >>> tie_priority([1, -1, 1, -1]).tolist()
    [0, 5, 2, 7]
    """
    s = np.asarray(facing).reshape(-1)
    i = np.arange(len(s)) if index is None else np.asarray(index).reshape(-1)
    big = int(i.max(initial=-1)) + 1
    return i + big * (s < 0)
