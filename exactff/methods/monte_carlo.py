"""Monte Carlo ray casting with cosine-weighted directions, and over the whole sphere
(uniform directions) for the spherical factors."""

import hashlib

import numpy as np

from ..checks import as_point
from ..kernel import flat_polygons
from ..predicates import plane_sides
from ..scene import as_scene
from ._sampling import CellLayout, SampledMethod, nearest_polygons
from ._zbuffer import cosine_directions

__all__ = ["MonteCarlo"]


class MonteCarlo(SampledMethod):
    """Cosine-weighted ray casting: the randomised twin of discrete PPBH.

    Directions: uniform points on the unit disk lifted to the hemisphere
    (``(x, y, sqrt(1 - x^2 - y^2))``), so each ray carries ``1 / samples`` of the form
    factor. The estimate of ``F_j`` is the fraction of rays whose nearest polygon is
    ``j``; its standard error is ``sqrt(F_j (1 - F_j) / samples)``.

    The rays of a row come from a generator seeded with ``seed`` and the point's
    coordinates, so a row is reproducible whatever the order or the executor.

    Sphere mode (:meth:`point_sphere_factors`, what
    ``exactff.sphere_form_factors(..., method="monte_carlo")`` calls): ``samples``
    directions uniform over the whole sphere, each carrying ``1 / samples`` of the
    spherical factor, with the same standard error.

    Parameters
    ----------
    samples : int, default 65,536
        Rays per row.
    seed : int, default 0
    backend : {"compiled", "numpy"}, default "compiled"
        Where the rays are cast: the shared core's compiled z-buffer
        (:func:`exactff.methods._sampling.nearest_polygons` with ``backend="compiled"``:
        each chart's clipping, crossing numbers and depth buffer in C++, without the
        GIL) or its numpy code, the oracle. The numpy code widens the charts' frustums
        by ``CHART_MARGIN``, the compiled one clips to the exact frustums: the same
        polygon for every ray but one within rounding of a chart's edge and of a
        polygon's edge there (none in the tests; with margin 0 the numpy code gives
        the compiled hits bit for bit).

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> mc = MonteCarlo(samples=20000, seed=1)
    >>> F, se = mc.form_factors_with_error(box, [0.5, 0.5, 0.0], [0, 0, 1])
    >>> abs(float(F[4:8].sum()) - 0.2394564705) < 4 * 0.0031  # within 4 standard errors
    True
    """

    name = "monte_carlo"

    def __init__(self, samples=65536, *, seed=0, backend="compiled"):
        if not (isinstance(samples, (int, np.integer)) and samples > 0):
            raise ValueError(f"samples must be a positive integer, got {samples!r}")
        if not isinstance(seed, (int, np.integer)):
            raise ValueError(f"seed must be an integer, got {seed!r}")
        if backend not in ("compiled", "numpy"):
            raise ValueError(f"backend must be one of ['compiled', 'numpy'], got {backend!r}")
        self.n = int(samples)
        self.seed = int(seed)
        self.backend = backend
        self._layout = None

    @property
    def samples(self):
        return self.n

    @property
    def rays_backend(self):
        return self.backend

    def build_layout(self):
        return self._rays(np.random.default_rng(self.seed))

    def _rays(self, rng):
        # uniform points (r cos a, r sin a) of the unit disk, r = sqrt(q1), a = 2 pi q2,
        # lifted to the hemisphere and normalised (compiled: _zbuffer.cosine_directions,
        # the numpy expressions in their order; a ray on the horizon kept above it)
        q1 = rng.random(self.n)
        q2 = rng.random(self.n)
        D, norms = cosine_directions(q1, q2)
        return CellLayout(D, np.full(self.n, 1.0 / self.n), 1.0, norms=norms)

    def directions_for(self, point):
        L = self._rays(self._generator(point, b""))
        return L.directions, L.weights

    def _generator(self, point, salt):
        key = (np.asarray(point, dtype=float).tobytes()
               + self.seed.to_bytes(8, "little", signed=True) + salt)
        digest = int.from_bytes(hashlib.blake2b(key, digest_size=8).digest(), "little")
        return np.random.default_rng(digest)

    def sphere_directions(self, point):
        """The row's ``samples`` directions, uniform over the sphere (Archimedes: z
        uniform in [-1, 1], azimuth uniform), seeded by ``seed`` and the point."""
        rng = self._generator(point, b"sphere")
        z = 2.0 * rng.random(self.n) - 1.0
        a = 2.0 * np.pi * rng.random(self.n)
        r = np.sqrt(np.maximum(1.0 - z * z, 0.0))
        return np.column_stack([r * np.cos(a), r * np.sin(a), z])

    def point_sphere_factors(self, scene, point, *, two_sided=True, stats=None,
                             error=False):
        """Spherical factors from one point: the share of uniform directions over the
        sphere whose nearest polygon is ``j`` (receiving on the face it shows, both
        with ``two_sided``); with ``error=True`` also their standard errors
        ``sqrt(S (1 - S) / samples)``.

        Examples
        --------
        >>> import exactff as ef
        >>> S, se = MonteCarlo(20000, seed=3).point_sphere_factors(
        ...     ef.scenes.subdivided_box(1), [0.5, 0.5, 0.5], error=True)
        >>> bool(np.all(np.abs(S - 1 / 6) < 5 * se)), float(S.sum())
        (True, 1.0)
        """
        as_scene(scene)
        p = as_point(point)
        D = self.sphere_directions(p)
        hit = np.full(self.n, -1)
        # two hemispheres, each in its own local frame (z along +z, then -z): a
        # direction's local coordinates are (x, y, |z|) up to a rotation about the
        # axis, which a uniform distribution does not see
        for sign in (1.0, -1.0):
            k = np.flatnonzero(D[:, 2] * sign > 0)
            if len(k):
                L = np.column_stack([D[k, 0], D[k, 1], np.abs(D[k, 2])])
                hit[k] = nearest_polygons(scene, p, np.array([0.0, 0.0, sign]), L,
                                          backend=self.backend)
        side, _ = plane_sides(flat_polygons(scene), p, exact=False)
        receives = (side > 0) | (bool(two_sided) & (side < 0))
        ok = hit >= 0
        ok[ok] = receives[hit[ok]]
        if stats is not None:
            stats["rays"] = self.n
            stats["rays_hit"] = int((hit >= 0).sum())
        S = np.bincount(hit[ok], minlength=len(scene)) / self.n
        return (S, np.sqrt(S * (1.0 - S) / self.n)) if error else S

    def form_factors_with_error(self, scene, point, normal, *, two_sided=False):
        """Estimates and their standard errors, each of shape ``(len(scene),)``."""
        F = self.point_form_factors(scene, point, normal, two_sided=two_sided)
        return F, np.sqrt(F * (1.0 - F) / self.n)

    def __repr__(self):
        extra = "" if self.backend == "compiled" else f", backend={self.backend!r}"
        return f"MonteCarlo(samples={self.n}, seed={self.seed}{extra})"


