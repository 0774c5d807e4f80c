"""Discrete PPBH: a square grid over the base of the hemisphere (Rosell & Vivo 2000)."""

import numpy as np

from ._sampling import CellLayout, SampledMethod, resolution_from

__all__ = ["DiscretePPBH"]


class DiscretePPBH(SampledMethod):
    """Discrete PPBH: equal delta form factors on a square grid over the unit disk.

    Cell layout: an ``r x r`` grid of square cells over ``[-1, 1]^2`` on the base of
    the hemisphere; the cells whose centre lies inside the unit disk are kept. By
    Nusselt's analog every cell of the base carries the same delta form factor, so each
    kept cell gets ``1 / (number of kept cells)``: the sum over the hemisphere is exactly
    1. A cell's direction is its centre lifted onto the hemisphere,
    ``(x, y, sqrt(1 - x^2 - y^2))``.

    What it misses: the rim is staircased (cells whose centre is inside count whole), and
    visibility is sampled at cell centres.

    Parameters
    ----------
    resolution : int, optional
        Cells per side of the grid (``r``); about ``pi r^2 / 4`` cells are kept.
    samples : int, optional
        About this many cells, if ``resolution`` is not given (default 65,536).

    Examples
    --------
    From the centre of the floor of a closed unit box, the ceiling's exact value is
    0.2394564705 (4 quads, Howell's parallel-corner formula):

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> F = ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=DiscretePPBH(resolution=64))
    >>> round(float(F[4:8].sum()), 4)  # coarse: 1.2 % low; exact 0.2395
    0.2367
    """

    name = "ppbh"

    def __init__(self, resolution=None, *, samples=None):
        self.resolution = resolution_from(resolution, samples, np.pi / 4)
        self._layout = None

    def build_layout(self):
        r = self.resolution
        c = -1.0 + (np.arange(r) + 0.5) * (2.0 / r)
        x, y = np.meshgrid(c, c, indexing="ij")
        x, y = x.ravel(), y.ravel()
        keep = x * x + y * y < 1.0
        x, y = x[keep], y[keep]
        D = np.column_stack([x, y, np.sqrt(1.0 - x * x - y * y)])
        return CellLayout(D, np.full(len(x), 1.0 / len(x)), 1.0)

    def __repr__(self):
        return f"DiscretePPBH(resolution={self.resolution})"
