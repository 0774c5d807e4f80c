"""Hypothesis strategies for planar polygons, receivers and scenes.

Every strategy builds valid data by construction: star-shaped (hence simple) or convex
polygons from sorted angles, embedded in 3-D with a random rotation, scale and
translation. Requires ``hypothesis``.
"""

import math

import numpy as np
from hypothesis import strategies as st

__all__ = ["unit_vectors", "points", "polygons_2d", "planar_polygons", "convex_polygons",
           "embed"]


def _spherical(z, phi):
    s = math.sqrt(max(0.0, 1.0 - z * z))
    return np.array([s * math.cos(phi), s * math.sin(phi), z])


def unit_vectors():
    """Unit vectors in R^3 (uniform on the sphere: z uniform in [-1, 1], azimuth uniform),
    shrinking towards +z."""
    return st.builds(_spherical, st.floats(-1, 1).map(lambda z: 1 - abs(z) if z >= 0 else z),
                     st.floats(0, 2 * math.pi))


def points(bound=2.0):
    """Points in the cube ``[-bound, bound]^3``."""
    f = st.floats(-bound, bound, allow_nan=False, allow_infinity=False)
    return st.tuples(f, f, f).map(lambda t: np.array(t, dtype=float))


@st.composite
def polygons_2d(draw, min_vertices=3, max_vertices=8, convex=False):
    """Simple polygons in the plane, counter-clockwise, around the origin, radius <= 1.

    Angles come from positive gaps normalised to 2 pi, each kept below 0.9 pi (moved
    towards equal gaps just enough where needed), so the polygon is star-shaped about
    the origin and therefore simple; ``convex=True`` puts the vertices on the unit
    circle.
    """
    k = draw(st.integers(min_vertices, max_vertices))
    gaps = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=k, max_size=k)))
    gaps = gaps / gaps.sum() * 2 * math.pi
    if gaps.max() >= 0.9 * math.pi:
        # every gap must stay below pi (star-shaped): move the gaps towards equal ones
        # just enough, rather than replacing the polygon by a regular one
        target, even = 0.9 * math.pi * (1 - 1e-9), 2 * math.pi / k
        lam = (gaps.max() - target) / (gaps.max() - even)
        gaps = (1 - lam) * gaps + lam * even
    start = draw(st.floats(0, 2 * math.pi))
    ang = start + np.concatenate([[0.0], np.cumsum(gaps[:-1])])
    if convex:
        r = np.ones(k)
    else:
        r = np.array(draw(st.lists(st.floats(0.3, 1.0), min_size=k, max_size=k)))
    return np.column_stack([r * np.cos(ang), r * np.sin(ang)])


def _frame(normal):
    from ..geometry import receiver_frame

    return receiver_frame(normal)


def embed(P2, normal, centre, scale):
    """Place a counter-clockwise 2-D polygon in 3-D with front normal ``normal``."""
    R = _frame(normal)  # rows t1, t2, n: right-handed
    return centre + scale * (P2[:, :1] * R[0] + P2[:, 1:2] * R[1])


@st.composite
def planar_polygons(draw, min_vertices=3, max_vertices=8, convex=False,
                    scale=st.floats(0.2, 2.0), centre=None):
    """Planar simple polygons of shape (K, 3) in general position in 3-D."""
    P2 = draw(polygons_2d(min_vertices, max_vertices, convex))
    n = draw(unit_vectors())
    c = draw(centre if centre is not None else points(2.0))
    return embed(P2, n, c, draw(scale))


def convex_polygons(**kwargs):
    """Convex planar polygons of shape (K, 3) (vertices on a circle)."""
    return planar_polygons(convex=True, **kwargs)
