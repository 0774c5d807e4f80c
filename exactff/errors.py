"""The errors exactff raises: an ill-formed polygon, and a value it cannot deliver."""

__all__ = ["SceneError", "NumericalError"]


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


# shown (and pickled) by their public name, as numpy does for its exceptions
SceneError.__module__ = "exactff"
NumericalError.__module__ = "exactff"
