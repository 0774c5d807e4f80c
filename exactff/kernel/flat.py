"""A scene's polygons as flat (ragged) arrays, the view the vectorised kernels read."""

import numpy as np

from ..prepared import prepared
from ..rings import successors

__all__ = ["FlatPolygons", "flat_polygons"]


class FlatPolygons:
    """Flat (ragged) polygon arrays of a scene, shared by the vectorised kernels."""

    __slots__ = ("V", "nxt", "owner", "normals", "centroids", "counts", "offsets", "vmax",
                 "first", "E", "normals_t", "centroids_t")

    def __init__(self, scene):
        self.V = scene.vertices
        self.offsets = scene.offsets
        self.counts = np.diff(scene.offsets)
        self.owner = np.repeat(np.arange(len(scene)), self.counts)
        self.nxt = successors(scene.offsets)
        self.normals = scene.normals
        self.centroids = scene.centroids
        # largest coordinate magnitude of each polygon: the scale of its rounding
        self.vmax = np.maximum.reduceat(np.abs(self.V).max(axis=1), scene.offsets[:-1])
        # offset form: each polygon's first vertex, and every vertex relative to it
        self.first = self.V[scene.offsets[:-1]]
        self.E = self.V - self.first[self.owner]
        # the normals and centroids by coordinate, each row contiguous: every row's
        # distances to the planes (exactff.predicates.plane_distances) in whole-array steps
        self.normals_t = np.ascontiguousarray(self.normals.T)
        self.centroids_t = np.ascontiguousarray(self.centroids.T)


def flat_polygons(scene):
    """The :class:`FlatPolygons` of ``scene``, built once (:mod:`exactff.prepared`).

    Examples
    --------
    >>> import exactff as ef
    >>> f = flat_polygons(ef.scenes.subdivided_box(1))
    >>> f.counts.tolist(), f.nxt[:4].tolist()
    ([4, 4, 4, 4, 4, 4], [1, 2, 3, 0])
    """
    return prepared(scene).get("flat", FlatPolygons)
