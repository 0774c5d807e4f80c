"""Form-factor methods by name: the registry and ``resolve(method)``."""

from ._base import FormFactorMethod
from .exact import Exact

__all__ = ["METHODS", "resolve", "FormFactorMethod", "Exact"]

#: Method classes by name.
METHODS = {"exact": Exact}


def resolve(method, **options):
    """A configured method from a name or an instance.

    Raises
    ------
    ValueError
        Unknown name; the message lists the valid choices.

    Examples
    --------
    >>> resolve("exact")
    Exact(shortcuts=True)
    """
    if isinstance(method, FormFactorMethod):
        if options:
            raise ValueError(f"method options {sorted(options)} need a method name, "
                             f"not the configured instance {method!r}")
        return method
    if isinstance(method, str) and method in METHODS:
        return METHODS[method](**options)
    raise ValueError(f"method must be one of {sorted(METHODS)} or a FormFactorMethod "
                     f"instance, got {method!r}")
