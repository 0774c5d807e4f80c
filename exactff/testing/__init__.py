"""exactff as the ground truth of other projects' test suites.

- :func:`ground_truth`: exact rows with occlusion and a per-value error estimate;
- assertions with reports that name the polygon (and row) and the amount:
  :func:`assert_form_factors_close`, :func:`assert_rows_sum_to_one`,
  :func:`assert_reciprocity`;
- :mod:`exactff.testing.strategies`: hypothesis strategies for polygons, receivers,
  enclosures and occluded scenes (needs hypothesis; importing exactff never imports it);
- :mod:`exactff.testing.mp_reference`: independent mpmath references.

See ``docs/how-to/test-your-method.md``.
"""

import numpy as np

__all__ = ["assert_form_factors_close", "assert_rows_sum_to_one", "assert_reciprocity",
           "ground_truth"]


def _where(shape, flat_index):
    """'polygon j' or 'row i, polygon j' for a flat index into an array of this shape."""
    if len(shape) <= 1:
        return f"polygon {flat_index}"
    idx = np.unravel_index(flat_index, shape)
    return f"row {', '.join(map(str, idx[:-1]))}, polygon {idx[-1]}"


def assert_form_factors_close(actual, desired, *, rtol=1e-12, atol=1e-13):
    """Assert ``|actual - desired| <= atol + rtol * |desired|`` elementwise.

    Parameters
    ----------
    actual, desired : array_like
        Form factors; ``desired`` is the reference.
    rtol, atol : float
        Relative and absolute tolerances (defaults: the unoccluded accuracy target).

    Examples
    --------
    >>> assert_form_factors_close([0.25], [0.25 + 1e-15])
    """
    actual = np.asarray(actual, dtype=float)
    desired = np.asarray(desired, dtype=float)
    err = np.abs(actual - desired)
    bad = ~(err <= atol + rtol * np.abs(desired))
    if np.any(bad):
        flat_err = np.where(bad, err, -np.inf).ravel()
        i = int(np.flatnonzero(bad.ravel())[0])
        w = int(np.argmax(flat_err))
        shape = np.broadcast_shapes(actual.shape, desired.shape)
        a = np.broadcast_to(actual, shape).ravel()
        d = np.broadcast_to(desired, shape).ravel()
        raise AssertionError(
            f"{bad.sum()} of {bad.size} form factors differ beyond atol={atol:g}, "
            f"rtol={rtol:g}; first at {_where(shape, i)}: actual {a[i]!r}, desired "
            f"{d[i]!r}, error {err.ravel()[i]:.3g}; worst at {_where(shape, w)}: error "
            f"{err.ravel()[w]:.3g}")


def assert_rows_sum_to_one(F, *, atol=1e-11):
    """Assert that every row of ``F`` (shape ``(..., N)``) sums to 1 within ``atol``: the
    enclosure invariant of a closed scene seen from inside.

    Examples
    --------
    >>> assert_rows_sum_to_one([[0.25, 0.75], [0.5, 0.5]])
    >>> assert_rows_sum_to_one([[0.25, 0.70]])
    Traceback (most recent call last):
    ...
    AssertionError: 1 of 1 rows do not sum to 1 within atol=1e-11; worst: row 0 sums to 0.95 (off by 0.05)
    """
    S = np.asarray(F, dtype=float).sum(axis=-1)
    off = np.abs(S - 1.0)
    bad = ~(off <= atol)
    if np.any(bad):
        w = int(np.argmax(np.where(bad, off, -np.inf).ravel()))
        row = ", ".join(map(str, np.unravel_index(w, S.shape))) if S.ndim else "0"
        raise AssertionError(
            f"{bad.sum()} of {bad.size} rows do not sum to 1 within atol={atol:g}; worst: "
            f"row {row} sums to {S.ravel()[w]:.15g} (off by {off.ravel()[w]:.3g})")


def assert_reciprocity(areas, F, *, rtol=1e-9, atol=0.0):
    """Assert ``A_i F_ij = A_j F_ji`` for an area-to-area form-factor matrix ``F``
    (``(N, N)``, ``F[i, j]`` from i to j) and the polygons' ``areas``.

    The point-to-polygon matrices of :func:`exactff.form_factor_matrix` (rows from the
    centroids) do not satisfy it: use it for area-to-area matrices.

    Examples
    --------
    >>> assert_reciprocity([1.0, 2.0], [[0.0, 0.4], [0.2, 0.0]])
    """
    A = np.asarray(areas, dtype=float)
    F = np.asarray(F, dtype=float)
    if F.shape != (len(A), len(A)):
        raise ValueError(f"F must have shape ({len(A)}, {len(A)}), got {F.shape}")
    G = A[:, None] * F
    err = np.abs(G - G.T)
    bad = ~(err <= atol + rtol * np.maximum(np.abs(G), np.abs(G.T)))
    if np.any(bad):
        i, j = np.unravel_index(int(np.argmax(np.where(bad, err, -np.inf))), G.shape)
        raise AssertionError(
            f"{bad.sum() // 2} pairs break reciprocity (rtol={rtol:g}, atol={atol:g}); "
            f"worst: A_{i} F_{i}{j} = {G[i, j]:.15g}, A_{j} F_{j}{i} = {G[j, i]:.15g}")


def ground_truth(scene, points, normals, *, two_sided=False, tolerance=1e-12):
    """Exact form factors with occlusion, and an error estimate per value.

    Parameters
    ----------
    scene : exactff.Scene
    points, normals : array_like of shape (..., 3)
        Receivers (broadcast together); normals need not be unit.
    two_sided : bool, default False
        Let polygons receive on their back side too.
    tolerance : float, default 1e-12
        Relative accuracy requested of every value, however small (visible pieces
        refined from the input and escalated to long double and mpmath, or in the
        compiled core to quadruple precision, where the error bound misses it): unlike
        the default call (:class:`exactff.Exact`), whose bounds are held to
        ``tolerance`` times the larger of the value and ``VALUE_FLOOR`` and which spends
        no quadruple precision below that floor, this asks ``Exact(floor=0)``: a
        sliver of 1.1e-10 seen through a 1e-9 gap gets a bound of 1.2e-26, where the
        default call's is 1.7e-18. What is checked stays the default's
        (:func:`exactff.errors.misses_tolerance`): where a tier cannot make the bound of
        a value below the floor relative, the bound it reaches is returned.

    Returns
    -------
    F : ndarray of shape (..., len(scene))
    error : ndarray of shape (..., len(scene))
        A bound on ``|F - exact|`` for each value: the rounding of its integration plus
        the error of its visible pieces' vertices, as
        ``form_factors(..., error=True)`` (what it rests on:
        ``docs/explanation/robustness.md``).

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> F, E = ground_truth(box, [0.5, 0.5, 0.0], [0, 0, 1])
    >>> round(float(F.sum()), 12), bool(E.max() < 1e-14)
    (1.0, True)
    """
    from ..formfactors import form_factors
    from ..checks import as_receivers
    from ..methods import Exact

    as_receivers(points, normals, ("points", "normals"))   # names the arguments
    return form_factors(scene, points, normals, method=Exact(tolerance=tolerance, floor=0.0),
                        two_sided=two_sided, error=True)
