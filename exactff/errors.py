"""The errors exactff raises: an ill-formed polygon, and a value it cannot deliver (with
the check every public result passes on its way out)."""

import numpy as np

__all__ = ["SceneError", "NumericalError", "check_finite"]


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
    bad = ~np.isfinite(F_)
    if E is not None:
        bad = bad | np.isnan(np.asarray(E, dtype=float))
    if np.any(bad):
        k = int(np.flatnonzero(bad.ravel())[0])
        idx = list(np.unravel_index(k, bad.shape)) if bad.ndim else []
        where = f" {[int(i) for i in idx]}" if len(idx) > 1 else (f" {int(idx[0])}" if idx else "")
        est = None if E is None else float(np.broadcast_to(np.asarray(E, dtype=float),
                                                           bad.shape).ravel()[k])
        raise NumericalError(f"{what}{where} is {float(F_.ravel()[k])!r} (error estimate "
                             f"{est!r}): not finite, never returned")
    return F if E is None else (F, E)


# shown (and pickled) by their public name, as numpy does for its exceptions
SceneError.__module__ = "exactff"
NumericalError.__module__ = "exactff"
