"""Single-plane methods (Sillion & Puech 1989; Recker, George & Greenberg 1990)."""

import numpy as np

from ._raster import check_backend, compiled_zbuffer, plane_clipper, rasterise_face
from ._sampling import (CellLayout, SampledMethod, ZBufferRow, check_resolution,
                        resolution_from)

__all__ = ["SinglePlane", "parallel_rectangle_form_factor"]


def _corner(x, y):
    """Form factor from the origin (normal z) to the rectangle [0, x] x [0, y] at height 1,
    signed (odd in x and in y): Howell's plane element to a parallel rectangle."""
    ax = np.sqrt(1.0 + x * x)
    ay = np.sqrt(1.0 + y * y)
    return (x / ax * np.arctan(y / ax) + y / ay * np.arctan(x / ay)) / (2.0 * np.pi)


def parallel_rectangle_form_factor(x0, x1, y0, y1):
    """Exact form factor from the origin (normal z) to ``[x0, x1] x [y0, y1]`` at height 1.

    Examples
    --------
    >>> round(float(parallel_rectangle_form_factor(-1, 1, -1, 1)), 10)  # hemicube top face
    0.554126424
    """
    return _corner(x1, y1) - _corner(x0, y1) - _corner(x1, y0) + _corner(x0, y0)


class SinglePlane(SampledMethod):
    """A single plane above the point: cells on ``z = 1`` over ``[-E, E]^2``.

    Cell layouts (``cells=``):

    * ``"equal_ff"`` (Sillion & Puech, "A general two-pass method integrating specular and
      diffuse reflection", SIGGRAPH 1989, doi:10.1145/74334.74367): an ``r x r`` grid
      whose lines are spaced so that every row and column of cells carries the same
      share of the form factor: ``x_i = s_i / sqrt(1 - s_i^2)`` with ``s_i`` uniform in
      ``[-S, S]``, ``S = E / sqrt(1 + E^2)`` (the inverse of the marginal
      ``int dF dy = dx / (2 (1 + x^2)^(3/2))``). The cells are not all equal (the density
      is not separable; within a factor 20 for ``E = 10``, against 40,000 for uniform
      cells). Each cell's delta FF is its exact form factor (Howell's parallel
      rectangle), so the cells sum exactly to the covered part.
    * ``"uniform"`` (Recker, George & Greenberg, "Acceleration techniques for progressive
      refinement radiosity", I3D 1990, doi:10.1145/91385.91438: the hemicube's top face
      extended to ``[-E, E]^2``): square cells, delta FF at the cell centre,
      ``dA / (pi (x^2 + y^2 + 1)^2)``.
    * ``"uniform_refined"``: the uniform plane with the central ``[-1, 1]^2`` (the
      hemicube's top face) subdivided ``refine x refine`` times finer (the extended
      variant with a finer centre).

    What it misses: every direction outside the plane's extent, a band above the
    horizon of form factor ``1 - covered`` (``missed``; 0.0486 for ``E = 4``), is
    lost; the value is reported by ``SinglePlane(...).layout().missed``.

    Parameters
    ----------
    resolution : int, optional
        Cells per side of the plane.
    samples : int, optional
        About this many cells, if ``resolution`` is not given (default 65,536).
    extent : float, default 4
        Half side ``E`` of the plane at height 1.
    cells : {"equal_ff", "uniform", "uniform_refined"}, default "equal_ff"
    refine : int, default 2
        Subdivision of the centre cells for ``"uniform_refined"``.
    native : bool, default True
        Rasterise on the plane: each polygon clipped to the plane's frustum and
        scan-converted on the plane's grid (two grids for ``"uniform_refined"``)
        (:func:`exactff.methods._raster.rasterise_face`). False: the shared sampling
        core (the test oracle).
    backend : {"compiled", "numpy"}, default "compiled"
        Where the native rasterisation runs: the compiled z-buffer
        (``exactff.methods._zbuffer``, C++ without the GIL) or the vectorised numpy
        code, its test oracle; the two give the same polygon in every cell.

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> F = ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=SinglePlane(resolution=64))
    >>> round(float(F[4:8].sum()), 4)  # 3 % high: large centre cells; exact 0.2395
    0.2471
    >>> round(SinglePlane(resolution=64).layout().missed, 4)  # lost near the horizon
    0.0486
    """

    name = "single_plane"

    def __init__(self, resolution=None, *, samples=None, extent=4.0, cells="equal_ff",
                 refine=2, native=True, backend="compiled"):
        if cells not in ("equal_ff", "uniform", "uniform_refined"):
            raise ValueError(f"cells must be 'equal_ff', 'uniform' or 'uniform_refined', "
                             f"got {cells!r}")
        if not (np.isfinite(extent) and extent > 0):
            raise ValueError(f"extent must be a positive finite number, got {extent!r}")
        self.resolution = resolution_from(resolution, samples, 1.0)
        self.refine = check_resolution(refine, "refine")
        self.extent = float(extent)
        self.cells = cells
        self.native = bool(native)
        self.backend = check_backend(backend)
        self._layout = None

    def _cells(self):
        """Cell centres on the plane z = 1 and their delta form factors, and the grids
        they lie on: a list of ``(x, y, index)`` with ``index`` the cells' positions
        in the layout (one grid; two for ``"uniform_refined"``: the coarse cells
        outside the centre and the fine ones inside)."""
        r, E = self.resolution, self.extent
        if self.cells == "equal_ff":
            S = E / np.sqrt(1.0 + E * E)
            s = np.linspace(-S, S, r + 1)
            g = s / np.sqrt(1.0 - s * s)
            g[0], g[-1] = -E, E
            x0, y0 = (a.ravel() for a in np.meshgrid(g[:-1], g[:-1], indexing="ij"))
            x1, y1 = (a.ravel() for a in np.meshgrid(g[1:], g[1:], indexing="ij"))
            w = parallel_rectangle_form_factor(x0, x1, y0, y1)
            # direction through the cell's centre
            xc, yc = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
            return xc, yc, w, [(xc, yc, np.arange(len(xc)))]
        h = 2.0 * E / r
        c = -E + (np.arange(r) + 0.5) * h
        x, y = (a.ravel() for a in np.meshgrid(c, c, indexing="ij"))
        dA = np.full(len(x), h * h)
        grids = [(x, y, np.arange(len(x)))]
        if self.cells == "uniform_refined":
            # cells wholly inside [-1, 1]^2 (half a cell of slack against rounding)
            centre = (np.abs(x) + 0.5 * h <= 1.0 + 0.25 * h) & (np.abs(y) + 0.5 * h <= 1.0 + 0.25 * h)
            k = self.refine
            sub = (np.arange(k) + 0.5) / k - 0.5
            ox, oy = (a.ravel() for a in np.meshgrid(sub * h, sub * h, indexing="ij"))
            xf = (x[centre][:, None] + ox[None, :]).ravel()
            yf = (y[centre][:, None] + oy[None, :]).ravel()
            n_out = int((~centre).sum())
            outer = np.full(len(x), -1)
            outer[~centre] = np.arange(n_out)
            grids = [(x, y, outer), (xf, yf, n_out + np.arange(len(xf)))]
            x = np.concatenate([x[~centre], xf])
            y = np.concatenate([y[~centre], yf])
            dA = np.concatenate([dA[~centre], np.full(len(xf), (h / k) ** 2)])
        w = dA / (np.pi * (x * x + y * y + 1.0) ** 2)
        return x, y, w, grids

    def build_layout(self):
        E = self.extent
        covered = float(parallel_rectangle_form_factor(-E, E, -E, E))
        x, y, w, _ = self._cells()
        return CellLayout(np.column_stack([x, y, np.ones_like(x)]), w, covered)

    def native_buffer(self, scene, point, normal):
        L = self.layout()
        clip = plane_clipper(self.extent)
        z = ZBufferRow(scene, point, normal)
        best_t = np.full(len(L), np.inf)
        best = np.full(len(L), -1, dtype=np.int64)
        zb = compiled_zbuffer(z, L) if self.backend == "compiled" else None
        # each grid of cell centres (the plane's, or the coarse and the fine ones of
        # the refined variant), scan-converted on its own rows and columns
        for xs, ys, table in self._grids():
            rasterise_face(z, None, xs, ys, table, L.directions, best_t, best, clip=clip,
                           zbuffer=zb)
        return z, best

    def _grids(self):
        """Per grid of :meth:`_cells`: its rows' and columns' centres and the layout's
        cell of each grid cell (-1: none), built once."""
        if getattr(self, "_grid_cache", None) is None:
            grids = []
            for x, y, index in self._cells()[3]:
                xs, ys = np.unique(x), np.unique(y)
                m = np.full(len(xs) * len(ys), -1, dtype=np.int64)
                m[np.searchsorted(xs, x) * len(ys) + np.searchsorted(ys, y)] = index
                grids.append((xs, ys, m.reshape(len(xs), len(ys))))
            self._grid_cache = grids
        return self._grid_cache

    def __repr__(self):
        extra = "" if self.native else ", native=False"
        if self.backend != "compiled":
            extra += f", backend={self.backend!r}"
        return (f"SinglePlane(resolution={self.resolution}, extent={self.extent}, "
                f"cells={self.cells!r}{extra})")
