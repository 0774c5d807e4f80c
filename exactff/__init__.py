"""exactff: exact form factors for scenes of planar polygons (continuous PPBH).

The flat API re-exports each module's ``__all__``; see ``docs/reference``.
"""

from . import catalog, scenes
from .area import *  # noqa: F401,F403
from .formfactors import *  # noqa: F401,F403
from .geometry import *  # noqa: F401,F403
from .integrate import *  # noqa: F401,F403
from .io import *  # noqa: F401,F403
from .reports import *  # noqa: F401,F403
from .methods import (METHODS, CubicTetrahedron, DiscretePPBH, Exact,  # noqa: F401
                      FormFactorMethod, Hemicube, MonteCarlo, PolarPlane, SinglePlane)
from .scene import *  # noqa: F401,F403
from .storage import *  # noqa: F401,F403
from . import (area as _area, formfactors as _formfactors, geometry as _geometry, integrate as _integrate,
               io as _io, reports as _reports, scene as _scene, storage as _storage)

__version__ = "0.1.0"

__all__ = (["catalog", "scenes", "__version__", "METHODS", "FormFactorMethod", "Exact", "DiscretePPBH",
            "Hemicube", "CubicTetrahedron", "SinglePlane", "PolarPlane", "MonteCarlo"]
           + _scene.__all__ + _geometry.__all__ + _integrate.__all__ + _io.__all__
           + _formfactors.__all__ + _storage.__all__ + _reports.__all__ + _area.__all__)
