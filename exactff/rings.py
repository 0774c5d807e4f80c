"""Ragged rings: many polygons (or rings of vertices) stored flat, in the manner of
shapely's ``_ragged_array``.

A set of ``R`` rings is one vertex array and ``offsets`` of shape (R + 1,): ring ``r``
owns vertices ``offsets[r]:offsets[r + 1]``. Rings are stored so by
:func:`concatenated`. From that follow each vertex's ring
(:func:`owners`), its successor in the ring (:func:`successors`), a selection of rings
packed again (:func:`repack`), the padded arrays some kernels prefer
(:func:`padded`, :func:`padded_buckets`) and the polygons and rings of shapely
geometries (:func:`polygon_parts`, :func:`shapely_rings`). Every module reads rings through these.
"""

import numpy as np
import shapely

__all__ = ["concatenated", "owners", "successors", "repack", "padded", "padded_buckets",
           "polygon_parts", "shapely_rings"]


def concatenated(rings):
    """Rings (a sequence of arrays (K_r, 3)) as one vertex array and their offsets
    (int64, shape (R + 1,)).

    Examples
    --------
    >>> V, offsets = concatenated([np.zeros((3, 3)), np.ones((4, 3))])
    >>> V.shape, offsets.tolist()
    ((7, 3), [0, 3, 7])
    """
    return (np.concatenate(rings),
            np.concatenate([[0], np.cumsum([len(r) for r in rings])]).astype(np.int64))


def owners(offsets):
    """Each vertex's ring: shape (offsets[-1],), sorted.

    Examples
    --------
    >>> owners(np.array([0, 3, 7])).tolist()
    [0, 0, 0, 1, 1, 1, 1]
    """
    offsets = np.asarray(offsets)
    return np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))


def successors(offsets):
    """Each vertex's successor in its ring (the last vertex's is the ring's first).

    Examples
    --------
    >>> successors(np.array([0, 3, 7])).tolist()
    [1, 2, 0, 4, 5, 6, 3]
    """
    offsets = np.asarray(offsets)
    nxt = np.arange(offsets[-1]) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    return nxt


def repack(start, count):
    """The rings starting at ``start`` with ``count`` vertices each, packed contiguously.

    Returns
    -------
    (ndarray, ndarray, ndarray, ndarray)
        ``idx`` (the packed vertices' positions in the original array), ``owner``
        (each packed vertex's ring, 0 to len(start) - 1), ``first`` (each ring's first
        packed vertex) and ``nxt`` (successors in the packed array).

    Examples
    --------
    >>> idx, owner, first, nxt = repack(np.array([4, 0]), np.array([3, 3]))
    >>> idx.tolist(), owner.tolist(), first.tolist(), nxt.tolist()
    ([4, 5, 6, 0, 1, 2], [0, 0, 0, 1, 1, 1], [0, 3], [1, 2, 0, 4, 5, 3])
    """
    start = np.asarray(start)
    count = np.asarray(count)
    offsets = np.concatenate([[0], np.cumsum(count)])
    owner = owners(offsets)
    first = offsets[:-1]
    idx = start[owner] + np.arange(len(owner)) - first[owner]
    return idx, owner, first, successors(offsets)


def padded(polygons):
    """Polygons as one padded array, each padded by repeating its last vertex.

    Parameters
    ----------
    polygons : sequence of ndarray of shape (K_i, 3)

    Returns
    -------
    (ndarray of shape (M, max K_i, 3), ndarray of shape (M,))
        The vertices and the counts ``K_i``.

    Examples
    --------
    >>> V, k = padded([np.zeros((3, 3)), np.ones((4, 3))])
    >>> V.shape, k.tolist()
    ((2, 4, 3), [3, 4])
    """
    counts = np.array([len(P) for P in polygons])
    V = np.empty((len(counts), counts.max(), 3))
    for i, P in enumerate(polygons):
        V[i, : len(P)] = P
        V[i, len(P):] = P[-1]
    return V, counts


def padded_buckets(polygons):
    """Polygons as padded arrays, one per bucket of similar vertex counts.

    A single padded array costs every polygon as much as the longest one (a 5,000-gon
    in a scene of quads multiplies the work and memory of every row by thousands);
    buckets of vertex counts up to 4, 8, 16, ... (powers of two) keep the padding
    within a factor 2 of each polygon's own count.

    Parameters
    ----------
    polygons : sequence of ndarray of shape (K_i, 3)

    Returns
    -------
    list of (ndarray of int, ndarray of shape (M_b, K_b, 3), ndarray of shape (M_b,))
        For each bucket: the polygons' indices (increasing), their vertices padded
        as by :func:`padded`, and their counts.

    Examples
    --------
    >>> b = padded_buckets([np.zeros((3, 3)), np.ones((40, 3)), np.ones((4, 3))])
    >>> [(ids.tolist(), V.shape) for ids, V, k in b]
    [([0, 2], (2, 4, 3)), ([1], (1, 40, 3))]
    """
    counts = np.array([len(P) for P in polygons])
    size = np.maximum(4, 2 ** np.ceil(np.log2(np.maximum(counts, 1)))).astype(int)
    out = []
    for s in np.unique(size):
        ids = np.flatnonzero(size == s)
        V, c = padded([polygons[i] for i in ids])
        out.append((ids, V, c))
    return out


def polygon_parts(geoms):
    """The non-empty polygons in shapely geometries, collections flattened to any depth
    (GEOS may return a collection holding a multipolygon), and each one's geometry.

    Parameters
    ----------
    geoms : ndarray of shapely geometries, shape (G,)

    Returns
    -------
    (ndarray of shapely Polygons, shape (P,), ndarray of shape (P,))
        The polygons, and the index in ``geoms`` of each.

    Examples
    --------
    >>> sq, tri = shapely.box(0, 0, 1, 1), shapely.Polygon([(2, 0), (3, 0), (2, 1)])
    >>> nested = shapely.GeometryCollection([shapely.MultiPolygon([sq, tri]),
    ...                                      shapely.LineString([(0, 0), (1, 1)])])
    >>> parts, of = polygon_parts(np.array([nested, sq]))
    >>> shapely.area(parts).tolist(), of.tolist()
    ([1.0, 1.0, 0.5], [1, 0, 0])
    """
    parts, part_of = shapely.get_parts(np.asarray(geoms), return_index=True)
    while True:
        nested = np.isin(shapely.get_type_id(parts), (4, 5, 6, 7))   # multi-*, collection
        if not nested.any():
            break
        sub, k = shapely.get_parts(parts[nested], return_index=True)
        parts = np.concatenate([parts[~nested], sub])
        part_of = np.concatenate([part_of[~nested], part_of[nested][k]])
    keep = (shapely.get_type_id(parts) == 3) & ~shapely.is_empty(parts)
    return parts[keep], part_of[keep]


def shapely_rings(polys):
    """The rings of shapely polygons as flat vertex arrays, for the sector sums.

    Parameters
    ----------
    polys : ndarray of shapely Polygons

    Returns
    -------
    coords : ndarray of shape (V, 2)
        Every ring's vertices, its closing point dropped; rings contiguous, each
        polygon's exterior first, then its holes.
    ring_of : ndarray of shape (V,)
        Each vertex's ring (sorted).
    start, count : ndarray of shape (rings,)
        Each ring's first vertex and number of vertices.
    nxt : ndarray of shape (V,)
        Each vertex's successor in its ring.
    is_hole : ndarray of bool, shape (rings,)
    ring_poly : ndarray of shape (rings,)
        Each ring's polygon.

    Examples
    --------
    >>> sq = shapely.box(0, 0, 1, 1)
    >>> coords, ring_of, start, count, nxt, is_hole, ring_poly = shapely_rings(np.array([sq]))
    >>> count.tolist(), nxt.tolist(), is_hole.tolist()
    ([4], [1, 2, 3, 0], [False])
    """
    rings, ring_poly = shapely.get_rings(polys, return_index=True)
    is_hole = np.ones(len(rings), dtype=bool)
    n_rings = shapely.get_num_interior_rings(polys) + 1
    is_hole[np.concatenate([[0], np.cumsum(n_rings)[:-1]])] = False
    coords, ring_of = shapely.get_coordinates(rings, return_index=True)
    last = np.ones(len(ring_of), dtype=bool)
    last[:-1] = ring_of[1:] != ring_of[:-1]
    coords, ring_of = coords[~last], ring_of[~last]
    start = np.searchsorted(ring_of, np.arange(len(rings)))
    count = np.diff(np.append(start, len(ring_of)))
    nxt = successors(np.append(start, len(ring_of)))
    return coords, ring_of, start, count, nxt, is_hole, ring_poly
