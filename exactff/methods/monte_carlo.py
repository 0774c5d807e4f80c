"""Monte Carlo ray casting with cosine-weighted directions."""

import hashlib

import numpy as np

from ._sampling import CellLayout, SampledMethod

__all__ = ["MonteCarlo"]


class MonteCarlo(SampledMethod):
    """Cosine-weighted ray casting: the randomised twin of discrete PPBH.

    Directions: uniform points on the unit disk lifted to the hemisphere
    (``(x, y, sqrt(1 - x^2 - y^2))``), so each ray carries ``1 / samples`` of the form
    factor. The estimate of ``F_j`` is the fraction of rays whose nearest polygon is
    ``j``; its standard error is ``sqrt(F_j (1 - F_j) / samples)``.

    The rays of a row come from a generator seeded with ``seed`` and the point's
    coordinates, so a row is reproducible whatever the order or the executor.

    Parameters
    ----------
    samples : int, default 65,536
        Rays per row.
    seed : int, default 0

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

    def __init__(self, samples=65536, *, seed=0):
        if not (isinstance(samples, (int, np.integer)) and samples > 0):
            raise ValueError(f"samples must be a positive integer, got {samples!r}")
        if not isinstance(seed, (int, np.integer)):
            raise ValueError(f"seed must be an integer, got {seed!r}")
        self.n = int(samples)
        self.seed = int(seed)
        self._layout = None

    @property
    def samples(self):
        return self.n

    def build_layout(self):
        return self._rays(np.random.default_rng(self.seed))

    def _rays(self, rng):
        r = np.sqrt(rng.random(self.n))
        a = 2.0 * np.pi * rng.random(self.n)
        x, y = r * np.cos(a), r * np.sin(a)
        D = np.column_stack([x, y, np.sqrt(np.maximum(1.0 - x * x - y * y, 0.0))])
        D[D[:, 2] == 0, 2] = 1e-300  # a ray exactly on the horizon: keep it above
        return CellLayout(D, np.full(self.n, 1.0 / self.n), 1.0)

    def directions_for(self, point):
        key = np.asarray(point, dtype=float).tobytes() + self.seed.to_bytes(8, "little", signed=True)
        digest = int.from_bytes(hashlib.blake2b(key, digest_size=8).digest(), "little")
        L = self._rays(np.random.default_rng(digest))
        return L.directions, L.weights

    def form_factors_with_error(self, scene, point, normal, *, two_sided=False):
        """Estimates and their standard errors, each of shape ``(len(scene),)``."""
        F = self.point_form_factors(scene, point, normal, two_sided=two_sided)
        return F, np.sqrt(F * (1.0 - F) / self.n)

    def __repr__(self):
        return f"MonteCarlo(samples={self.n}, seed={self.seed})"


