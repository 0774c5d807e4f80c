"""Discrete PPBH: a square grid over the base of the hemisphere (Rosell & Vivo 2000)."""

import numpy as np

from ._raster import check_backend, compiled_zbuffer, rasterise_disk
from ._sampling import CellLayout, SampledMethod, ZBufferRow, resolution_from

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
    native : bool, default True
        Rasterise as the paper does: each polygon projected once onto the base of the
        hemisphere (horizon-clipped; its edges are the ellipse arcs of Eq. 2) and
        scan-converted on the disk's grid, one depth buffer
        (:func:`exactff.methods._raster.rasterise_disk`). False: the shared sampling
        core (the test oracle).
    backend : {"compiled", "numpy"}, default "compiled"
        Where the native rasterisation runs: the compiled z-buffer
        (``exactff.methods._zbuffer``, C++ without the GIL) or the vectorised numpy
        code, its test oracle; the two give the same polygon in every cell.

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

    def __init__(self, resolution=None, *, samples=None, native=True, backend="compiled"):
        self.resolution = resolution_from(resolution, samples, np.pi / 4)
        self.native = bool(native)
        self.backend = check_backend(backend)
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

    def _grid(self):
        """The grid's centres and the layout's cell of each grid cell (-1: outside the
        disk), built once."""
        if getattr(self, "_grid_cache", None) is None:
            r = self.resolution
            c = -1.0 + (np.arange(r) + 0.5) * (2.0 / r)
            x, y = np.meshgrid(c, c, indexing="ij")
            index_of = np.full(r * r, -1, dtype=np.int64)
            inside = (x * x + y * y < 1.0).ravel()
            index_of[inside] = np.arange(int(inside.sum()))
            self._grid_cache = c, index_of.reshape(r, r)
        return self._grid_cache

    def native_buffer(self, scene, point, normal):
        L = self.layout()
        c, table = self._grid()
        z = ZBufferRow(scene, point, normal)
        best_t = np.full(len(L), np.inf)
        best = np.full(len(L), -1, dtype=np.int64)
        zb = compiled_zbuffer(z, L) if self.backend == "compiled" else None
        rasterise_disk(z, c, c, table, L.directions, best_t, best, zbuffer=zb)
        return z, best

    def __repr__(self):
        extra = "" if self.native else ", native=False"
        if self.backend != "compiled":
            extra += f", backend={self.backend!r}"
        return f"DiscretePPBH(resolution={self.resolution}{extra})"
