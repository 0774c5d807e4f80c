"""The errors exactff raises: an ill-formed polygon, and a value it cannot deliver (with
the check every public result passes on its way out)."""

import numpy as np

from . import _tolerances as tol

__all__ = ["SceneError", "NumericalError", "check_finite", "misses_tolerance",
           "tolerance_missed", "nonnegative"]


class SceneError(ValueError):
    """A polygon of a scene is ill-formed; the message names the polygon and the reason.

    Attributes
    ----------
    index : int or None
        Index of the offending polygon in input order.
    reason : str
        What is wrong with it.

    Examples
    --------
    >>> str(SceneError(3, "zero area", name="floor"))
    "polygon 3 ('floor'): zero area"
    """

    def __init__(self, index, reason, name=None):
        self.index = index
        self.reason = reason
        label = f"polygon {index}" if name is None else f"polygon {index} ({name!r})"
        super().__init__(f"{label}: {reason}")



class NumericalError(ArithmeticError):
    """A computed value broke an invariant beyond its rounding-error estimate (a form
    factor below 0), or higher precision did not converge: a bug or an input outside
    what exactff can evaluate, never silently clamped. The message says which."""



def check_finite(F, E=None, what="form factor"):
    """Return ``F`` (and ``E``) when every value is finite and no error estimate is NaN
    (an infinite estimate is honest: "unknown"); else raise :class:`NumericalError`
    naming the first offending entry. The last step of every public result: a NaN or
    an infinity is never returned as a form factor.

    Examples
    --------
    >>> check_finite(np.array([0.25, 0.5]))
    array([0.25, 0.5 ])
    >>> check_finite(np.array([[0.25, np.nan]]))
    Traceback (most recent call last):
    ...
    exactff.NumericalError: form factor [0, 1] is nan (error estimate None): not finite, never returned
    """
    F_ = np.asarray(F, dtype=float)
    E_ = None if E is None else np.asarray(E, dtype=float)
    # at once where all is well (two whole-array tests, no floating-point state to set)
    if np.isfinite(F_).all() and (E_ is None or not np.isnan(E_).any()):
        return F if E is None else (F, E)
    bad = ~np.isfinite(F_)
    if E is not None:
        bad = bad | np.isnan(E_)
    if np.any(bad):
        k = int(np.flatnonzero(bad.ravel())[0])
        idx = list(np.unravel_index(k, bad.shape)) if bad.ndim else []
        where = f" {[int(i) for i in idx]}" if len(idx) > 1 else (f" {int(idx[0])}" if idx else "")
        est = None if E is None else float(np.broadcast_to(E_, bad.shape).ravel()[k])
        raise NumericalError(f"{what}{where} is {float(F_.ravel()[k])!r} (error estimate "
                             f"{est!r}): not finite, never returned")
    return F if E is None else (F, E)


#: The scalar types misses_tolerance tests without numpy.
_SCALARS = (float, np.float64)


def _larger(a, b):
    """The larger of two floats as np.maximum takes it: NaN where either is."""
    return a if a > b or a != a else b


def misses_tolerance(F, E, tolerance, atol=None):
    """Where a value's bound misses the accuracy asked of it.

    A bound ``E`` misses ``tolerance`` where it exceeds
    ``tolerance * max(|F|, VALUE_FLOOR)``, the relative tolerance with an absolute floor
    proportional to it (``VALUE_FLOOR``, a share of the hemisphere: a value near 0
    cannot carry relative digits its neighbours' rounding does not have). With an
    explicit ``atol`` (area form factors, whose ``tolerance`` is absolute) the floor is
    ``atol`` instead: ``E > max(atol, tolerance * |F|)``, ``tolerance`` None meaning no
    relative part. The one acceptance criterion of every path: unoccluded values after
    their last precision tier, the Python engine's refined pieces (either integrator),
    area form factors, and the compiled core's fallback to the Python engine (after its
    quadruple-precision tier, which makes its sliver bounds relative). An infinite
    bound misses; a NaN is refused by :func:`check_finite`.

    Examples
    --------
    >>> misses_tolerance(np.array([0.5, 0.5, 0.0, 0.0]),
    ...                  np.array([1e-13, 1e-11, 5e-15, 2e-14]), 1e-12)
    array([False,  True, False,  True])
    >>> bool(misses_tolerance(1e-3, 2e-9, 1e-9, atol=1e-9))    # max(1e-9, 1e-12)
    True
    """
    if type(F) in _SCALARS and type(E) in _SCALARS:
        # one value (an area pair's): the same test in Python floats, NaN as numpy
        # takes it (np.maximum keeps a NaN, and E > NaN is False)
        # (numpy's bool, as the array path gives: callers negate it with ~)
        F, E = float(F), float(E)
        if atol is None:
            return np.bool_(E > tolerance * _larger(abs(F), tol.VALUE_FLOOR))
        return np.bool_(E > _larger(float(atol), 0.0 if tolerance is None else tolerance * abs(F)))
    F, E = np.asarray(F, dtype=float), np.asarray(E, dtype=float)
    if atol is None:
        return E > tolerance * np.maximum(np.abs(F), tol.VALUE_FLOOR)
    allowed = np.zeros_like(F) if tolerance is None else tolerance * np.abs(F)
    return E > np.maximum(atol, allowed)


def tolerance_missed(where, value, estimate, allowed, why="", hint=""):
    """The :class:`NumericalError` for a value that misses its tolerance (see
    :func:`misses_tolerance`): names ``where`` (``"polygon 3"``, ``"row 0, polygon
    2"``), the value, its bound and what was allowed (a number: a relative tolerance
    with its floor; a string: as given), ``why`` it could not do better, and that
    ``error=True`` returns the value with its bound instead.

    Examples
    --------
    >>> print(tolerance_missed("polygon 3", 0.25, 2e-9, 1e-12))
    polygon 3: the form factor 0.25 misses the tolerance 1e-12 relative (times the larger of |F| and 0.01) (error estimate 2e-09); ask error=True for the value with its estimate
    """
    why = f" {why}" if why else ""
    hint = f"; {hint}" if hint else ""
    if not isinstance(allowed, str):       # a relative tolerance, with its floor
        allowed = f"{allowed:g} relative (times the larger of |F| and {tol.VALUE_FLOOR:g})"
    return NumericalError(f"{where}: the form factor {float(value):.17g} misses the tolerance "
                          f"{allowed} (error estimate {float(estimate):.3g}){why}{hint}; "
                          f"ask error=True for the value with its estimate")


def nonnegative(value, estimate, what="area form factor", unchecked=None, item=None):
    """``value`` (a float or an array) with what rounding left below 0 set to 0, where
    it lies within its own error ``estimate`` (the estimate still covers it:
    ``0 <= exact <= value + estimate <= estimate``); a value below 0 beyond it, or NaN,
    raises :class:`~exactff.NumericalError` instead of being hidden (naming ``what`` and,
    in an array, the entry's index, as ``"{item} {index}: "`` where ``item`` names what
    the entries are, such as ``"polygon"``). ``unchecked`` marks entries known to be unreliable
    (their estimate says so), exempt from the check but still set to 0 below 0. The one
    place a value is clamped to 0: every path's last step (point rows' sector sums, the
    engine's pieces, the area code). Floating arrays keep their precision.

    Examples
    --------
    >>> float(nonnegative(-1e-17, 1e-16))
    0.0
    >>> nonnegative(-1e-15, 1e-16)
    Traceback (most recent call last):
    ...
    exactff.NumericalError: area form factor -1e-15 below 0 beyond its error estimate 1e-16
    >>> nonnegative(np.array([0.5, -2e-9]), np.array([0.0, 1e-12]), "form factor")
    Traceback (most recent call last):
    ...
    exactff.NumericalError: form factor [1] -2e-09 below 0 beyond its error estimate 1e-12
    """
    v, e = np.asarray(value), np.asarray(estimate)
    v, e = (a if a.dtype.kind == "f" else a.astype(float) for a in (v, e))
    bad = ~(v >= -e)
    if unchecked is not None:
        bad &= ~np.asarray(unchecked, dtype=bool)
    if np.any(bad):
        bad = np.broadcast_to(bad, np.broadcast(v, e).shape)
        k = int(np.flatnonzero(bad.ravel())[0])
        vk = float(np.broadcast_to(v, bad.shape).ravel()[k])
        ek = float(np.broadcast_to(e, bad.shape).ravel()[k])
        why = "is NaN" if np.isnan(vk) else (
            "has a NaN error estimate" if np.isnan(ek) else "below 0 beyond its error estimate")
        index = ", ".join(str(int(i)) for i in np.unravel_index(k, bad.shape))
        where = "" if not bad.ndim else f" [{index}]" if item is None else ""
        named = f"{item} {index}: " if item is not None and bad.ndim else ""
        raise NumericalError(f"{named}{what}{where} {vk!r} {why} {ek!r}")
    out = np.maximum(v, 0.0)
    return float(out) if out.ndim == 0 else out


# shown (and pickled) by their public name, as numpy does for its exceptions
SceneError.__module__ = "exactff"
NumericalError.__module__ = "exactff"
