"""The cubic tetrahedron (Beran-Koehn & Pavicic 1991)."""

import numpy as np

from ._raster import check_backend, compiled_zbuffer, face_clipper, rasterise_face
from ._sampling import CellLayout, SampledMethod, ZBufferRow, resolution_from

__all__ = ["CubicTetrahedron", "cubic_tetrahedron_frame"]


def cubic_tetrahedron_frame():
    """Rows: the cube's axes a1, a2, a3 in the local frame, with (a1 + a2 + a3)/sqrt 3 = z."""
    # a rotation taking (1, 1, 1)/sqrt(3) to z: first axis in the x-z plane
    z = np.ones(3) / np.sqrt(3.0)
    e1 = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
    e2 = np.cross(z, e1)
    Q = np.array([e1, e2, z])  # cube coordinates -> local frame
    return Q.T  # rows: images of the cube axes


class CubicTetrahedron(SampledMethod):
    """The cubic tetrahedron: three faces of a cube whose corner points along the normal.

    Cell layout: in cube coordinates (axes ``a1, a2, a3`` with ``a1 + a2 + a3`` along
    the normal), the tetrahedron bounded by the planes ``x' = 1``, ``y' = 1``, ``z' = 1``
    and the base plane ``x' + y' + z' = 0`` of the hemisphere. Each face, e.g. ``x' = 1``,
    is the right triangle ``v, w <= 1``, ``1 + v + w >= 0`` of its other two coordinates;
    it gets the ``r x r`` grid over ``[-2, 1]^2``, of which the cells whose centre lies
    above the base (``1 + v + w > 0``) are kept. The three triangles cover the
    hemisphere exactly, a third of it each. Delta form factor of a cell on ``x' = 1``
    (Beran-Koehn & Pavicic, "A cubic tetrahedral adaptation of the hemi-cube algorithm",
    Graphics Gems II, 1991):

    ``dF = cos(theta_p) cos(theta_c) dA / (pi r^2) = (1 + v + w) dA / (sqrt(3) pi (1 + v^2 + w^2)^2)``

    with ``cos(theta_p) = (1 + v + w) / (sqrt(3) r)``, ``cos(theta_c) = 1 / r``,
    ``r^2 = 1 + v^2 + w^2`` and ``dA = (3 / resolution)^2`` (derived in
    ``tools/derive_delta_ff.py``).

    What it misses: the cells cut by the base plane are kept or dropped whole (by their
    centre); visibility is sampled at cell centres.

    Parameters
    ----------
    resolution : int, optional
        Cells per face edge; about ``3 r^2 / 2`` cells are kept.
    samples : int, optional
        About this many cells, if ``resolution`` is not given (default 65,536).
    native : bool, default True
        Rasterise on the three faces: each polygon clipped to each face's frustum
        (its triangle above the base) and scan-converted on the face's grid
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
    >>> F = ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1], method=CubicTetrahedron(resolution=16))
    >>> round(float(F[4:8].sum()), 4)  # coarse: 6 % low; exact 0.2395
    0.225
    """

    name = "cubic_tetrahedron"

    def __init__(self, resolution=None, *, samples=None, native=True, backend="compiled"):
        self.resolution = resolution_from(resolution, samples, 1.5)
        self.native = bool(native)
        self.backend = check_backend(backend)
        self._layout = None

    def build_layout(self):
        r = self.resolution
        h = 3.0 / r
        c = -2.0 + (np.arange(r) + 0.5) * h
        v, w = (a.ravel() for a in np.meshgrid(c, c, indexing="ij"))
        keep = 1.0 + v + w > 0
        v, w = v[keep], w[keep]
        wt = (1.0 + v + w) * h * h / (np.sqrt(3.0) * np.pi * (1.0 + v * v + w * w) ** 2)
        A = cubic_tetrahedron_frame()
        one = np.ones_like(v)
        dirs = []
        for cube in (np.column_stack([one, v, w]), np.column_stack([w, one, v]),
                     np.column_stack([v, w, one])):
            dirs.append(cube @ A)
        return CellLayout(np.vstack(dirs), np.tile(wt, 3), 1.0)

    def _faces(self):
        """The grid's centres and, per face, its clipper and the layout's cell of each
        grid cell (-1: below the base), built once."""
        if getattr(self, "_face_cache", None) is None:
            r = self.resolution
            c = -2.0 + (np.arange(r) + 0.5) * (3.0 / r)
            v, w = np.meshgrid(c, c, indexing="ij")
            keep = (1.0 + v + w > 0).ravel()
            n_face = int(keep.sum())
            a1, a2, a3 = cubic_tetrahedron_frame()
            # the faces x' = 1, y' = 1, z' = 1 in the layout's order, each with the
            # plane axes of its grid (v, w); the frustum in the face's frame (u, v, w):
            # u, v <= w and above the base (u + v + w > 0: the normal is
            # (a1 + a2 + a3) / sqrt 3)
            planes = [[-1.0, 0.0, 1.0], [0.0, -1.0, 1.0], [1.0, 1.0, 1.0]]
            faces = []
            for k, (ew, eu, ev) in enumerate(((a1, a2, a3), (a2, a3, a1), (a3, a1, a2))):
                index_of = np.full(r * r, -1, dtype=np.int64)
                index_of[keep] = k * n_face + np.arange(n_face)
                faces.append((face_clipper([eu, ev, ew], planes), index_of.reshape(r, r)))
            self._face_cache = c, faces
        return self._face_cache

    def native_buffer(self, scene, point, normal):
        L = self.layout()
        c, faces = self._faces()
        z = ZBufferRow(scene, point, normal)
        best_t = np.full(len(L), np.inf)
        best = np.full(len(L), -1, dtype=np.int64)
        zb = compiled_zbuffer(z, L) if self.backend == "compiled" else None
        for clip, table in faces:
            rasterise_face(z, None, c, c, table, L.directions, best_t, best, clip=clip,
                           zbuffer=zb)
        return z, best

    def __repr__(self):
        extra = "" if self.native else ", native=False"
        if self.backend != "compiled":
            extra += f", backend={self.backend!r}"
        return f"CubicTetrahedron(resolution={self.resolution}{extra})"
