"""Form-factor methods by name: the registry and ``resolve(method)``."""

from ._base import FormFactorMethod
from .cubic_tetrahedron import CubicTetrahedron
from .exact import Exact
from .hemicube import Hemicube
from .monte_carlo import MonteCarlo
from .polar_plane import PolarPlane
from .ppbh import DiscretePPBH
from .single_plane import SinglePlane

__all__ = ["METHODS", "resolve", "FormFactorMethod", "Exact", "DiscretePPBH", "Hemicube",
           "CubicTetrahedron", "SinglePlane", "PolarPlane", "MonteCarlo"]

#: Method classes by name.
METHODS = {
    "exact": Exact,
    "ppbh": DiscretePPBH,
    "hemicube": Hemicube,
    "cubic_tetrahedron": CubicTetrahedron,
    "single_plane": SinglePlane,
    "polar_plane": PolarPlane,
    "monte_carlo": MonteCarlo,
}


def resolve(method, **options):
    """A configured method from a name or an instance.

    Raises
    ------
    ValueError
        Unknown name; the message lists the valid choices.

    Examples
    --------
    >>> resolve("exact")
    Exact(tolerance=1e-12, shortcuts=True)
    """
    if isinstance(method, FormFactorMethod):
        if options:
            raise ValueError(f"method options {sorted(options)} need a method name, "
                             f"not the configured instance {method!r}")
        return method
    if isinstance(method, str) and method in METHODS:
        try:
            return METHODS[method](**options)
        except TypeError as exc:
            raise ValueError(f"options {sorted(options)} for method {method!r}: {exc}") from None
    raise ValueError(f"method must be one of {sorted(METHODS)} or a FormFactorMethod "
                     f"instance, got {method!r}")
