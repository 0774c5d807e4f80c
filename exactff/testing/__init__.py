"""Helpers for test suites: tolerant comparison of form factors.

The hypothesis strategies live in :mod:`exactff.testing.strategies` (which needs
hypothesis installed); exactff itself never imports them.
"""

import numpy as np

__all__ = ["assert_form_factors_close"]


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
        i = np.flatnonzero(bad.ravel())[0]
        raise AssertionError(
            f"{bad.sum()} of {bad.size} form factors differ beyond atol={atol:g}, "
            f"rtol={rtol:g}; first at flat index {i}: actual {actual.ravel()[i]!r}, "
            f"desired {desired.ravel()[i]!r}, error {err.ravel()[i]:.3g}")
