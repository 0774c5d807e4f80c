"""Coplanar overlapping polygons found without the BSP tree: a plane hash.

:func:`exactff.visibility.coplanar_overlaps` reads the pairs off the nodes of the BSP
tree, which costs the whole tree (most of ``exactff info`` on a big file). Here the
polygons are grouped by their plane instead, and only polygons of one group are
compared:

1. normals are turned to one hemisphere (the facing is kept) and grouped by gaps:
   sorted along each coordinate, a new group starts where two consecutive normals
   differ by more than ``PLANE_HASH_NORMAL``, so no two normals closer than that are
   ever separated;
2. within a normal group, offsets along the group's mean normal are grouped the same
   way, with a gap that cannot separate two polygons in the coplanar band of each
   other: the band itself plus the group's spread of normals times the scene's size;
3. within a plane group, pairs whose 2-D bounding boxes meet (one STRtree for all the
   groups, each moved to its own place) are kept when one lies in the coplanar band of
   the other's plane (:func:`exactff.predicates.in_plane_band`: the BSP tree's rule),
   and overlap when they share more than ``OVERLAP_RTOL`` of the smaller one's area in
   the plane (as the tree's nodes are compared).
"""

import numpy as np
import shapely

from .. import _tolerances as tol
from ..predicates import in_plane_band, polygons_apart

__all__ = ["plane_overlaps"]

#: pairs of polygons with at most this many vertices each are first tested for an edge
#: that separates them (cheap, vectorised); longer ones go to the overlay directly
_APART_MAX_VERTICES = 8
#: pairs tested together (bounds the temporaries)
_CHUNK = 65536


def _refine(labels, values, gap):
    """New labels: within each label, sorted by value, a new run where consecutive
    values differ by more than ``gap[label]``."""
    order = np.lexsort((values, labels))
    lab, val = labels[order], values[order]
    new = np.ones(len(order), dtype=bool)
    new[1:] = (lab[1:] != lab[:-1]) | (np.diff(val) > gap[lab[1:]])
    out = np.empty(len(order), dtype=np.int64)
    out[order] = np.cumsum(new) - 1
    return out


def _plane_groups(scene, rtol):
    """A plane group per polygon (polygons that may be coplanar within ``rtol`` of the
    magnitudes share one), and the unit mean normal of each polygon's normal group (in
    the hemisphere the normals were turned to)."""
    N, D = scene.normals, scene.plane_offsets
    n = len(N)
    major = np.argmax(np.abs(N), axis=1)
    turn = np.sign(N[np.arange(n), major])
    Nt = N * turn[:, None]
    labels = np.zeros(n, dtype=np.int64)
    for k in range(3):
        labels = _refine(labels, Nt[:, k], np.full(n, tol.PLANE_HASH_NORMAL))
    m = int(labels.max()) + 1
    mean = np.zeros((m, 3))
    np.add.at(mean, labels, Nt)
    mean /= np.linalg.norm(mean, axis=1)[:, None]
    spread = np.zeros(m)
    np.maximum.at(spread, labels, np.linalg.norm(Nt - mean[labels], axis=1))
    lo, hi = scene.bounds
    size = float(np.linalg.norm(hi - lo))
    magnitude = float(np.abs(scene.vertices).max()) + float(np.abs(D).max())
    # a polygon in the band of another's plane has its centroid within the band of it
    # (the band is at most rtol sqrt(3) times the magnitudes): their offsets along the
    # group's mean normal differ by at most the band plus the spread of the normals
    # times the scene's size; twice that, and the rounding of the centroids and offsets
    # (a few ulps of the magnitudes), so that no such pair is ever put apart
    gap = 2 * (rtol * np.sqrt(3) * magnitude + spread * size) + 8 * tol.EPS * magnitude
    offsets = np.einsum("ij,ij->i", mean[labels], scene.centroids)
    return _refine(labels, offsets, gap), mean[labels]


def _vertex_rows(scene, polys):
    """Indices into ``scene.vertices`` of the vertices of ``polys`` (concatenated), and
    the start of each polygon's run."""
    off = scene.offsets
    counts = off[polys + 1] - off[polys]
    starts = np.concatenate([[0], np.cumsum(counts)])
    rows = np.repeat(off[polys] - starts[:-1], counts) + np.arange(starts[-1])
    return rows, starts


def _vertex_rows_of(starts, ends):
    """Rows ``starts[e]:starts[e + 1]`` for every ``e`` of ``ends``, concatenated."""
    counts = starts[ends + 1] - starts[ends]
    first = np.concatenate([[0], np.cumsum(counts)])
    return np.repeat(starts[ends] - first[:-1], counts) + np.arange(first[-1])


def _in_band_of(scene, a, b, rtol):
    """Whether every vertex of polygon ``b[k]`` lies in the band of ``a[k]``'s plane."""
    rows, starts = _vertex_rows(scene, b)
    owner = np.repeat(np.arange(len(b)), np.diff(starts))
    ok = in_plane_band(scene.vertices[rows], scene.normals[a[owner]],
                       scene.plane_offsets[a[owner]], rtol)
    return np.logical_and.reduceat(ok, starts[:-1]) if len(b) else ok


def plane_overlaps(scene, *, rtol=tol.BSP_COPLANAR_ULPS * tol.EPS, near_rtol=None):
    """Pairs of polygons that lie in one plane and overlap, by facing, without the BSP
    tree (the same pairs as :func:`exactff.visibility.coplanar_overlaps` where the tree
    puts every pair of coplanar polygons in one node; tested on the built-in scenes).

    Parameters
    ----------
    scene : Scene
    rtol : float, optional
        The coplanar band, relative to the magnitudes in ``n . x - d``: every vertex of
        one polygon lies within it of the other's plane (default: the BSP tree's,
        ``BSP_COPLANAR_ULPS`` ulps).
    near_rtol : float, optional
        Also return the overlapping pairs that are coplanar within this wider band but
        not within ``rtol``: near-coplanar faces (a face flush with another to 1e-13),
        which the exact method orders by their geometry and the discrete methods may
        call a tie.

    Returns
    -------
    back_to_back : ndarray of shape (P, 2), int
        Pairs ``i < j`` facing opposite ways (the two faces of a zero-thickness wall).
    same_facing : ndarray of shape (Q, 2), int
        Pairs ``i < j`` facing the same way (usually a modelling mistake).
    near : ndarray of shape (R, 2), int
        Only with ``near_rtol``: the near-coplanar overlapping pairs ``i < j``.

    Examples
    --------
    >>> from exactff.scenes import building
    >>> b2b, same = plane_overlaps(building(2, 1))
    >>> len(b2b), len(same)
    (3, 0)
    """
    wide = rtol if near_rtol is None else max(rtol, near_rtol)
    empty = np.zeros((0, 2), dtype=int)
    labels, normal = _plane_groups(scene, wide)
    counts = np.bincount(labels)
    live = np.flatnonzero(counts[labels] > 1)
    out = [empty, empty] + ([empty] if near_rtol is not None else [])
    if len(live) == 0:
        return tuple(out)
    # 2-D coordinates in each group's plane (the axis of the group's normal dropped)
    rows, starts = _vertex_rows(scene, live)
    counts = np.diff(starts)
    keep = np.array([[1, 2], [0, 2], [0, 1]])[np.argmax(np.abs(normal[live]), axis=1)]
    owner = np.repeat(np.arange(len(live)), counts)
    uv = np.take_along_axis(scene.vertices[rows], keep[owner], axis=1)
    # pairs whose bounding boxes meet: one STRtree, each group moved to its own place
    lo = np.minimum.reduceat(uv, starts[:-1], axis=0)
    hi = np.maximum.reduceat(uv, starts[:-1], axis=0)
    g = labels[live]
    base = np.full((int(labels.max()) + 1, 2), np.inf)
    np.minimum.at(base, g, lo)
    lo, hi = lo - base[g], hi - base[g]
    width = float(hi.max()) + 1.0
    pad = tol.PLANE_HASH_PAD * width
    shift = np.column_stack([g * 4.0 * width, np.zeros(len(g))])
    boxes = shapely.box(*(lo + shift - pad).T, *(hi + shift + pad).T)
    ia, ib = shapely.STRtree(boxes).query(boxes)      # the boxes' envelopes meet
    sel = (ia < ib) & (g[ia] == g[ib])
    ia, ib = ia[sel], ib[sel]
    # polygons that certainly share no area (neighbours in a mesh) need no overlay
    apart = np.zeros(len(ia), dtype=bool)
    small = (counts[ia] <= _APART_MAX_VERTICES) & (counts[ib] <= _APART_MAX_VERTICES)
    kinds = counts[ia] * (_APART_MAX_VERTICES + 1) + counts[ib]
    for kind in np.unique(kinds[small]):
        ka, kb = divmod(int(kind), _APART_MAX_VERTICES + 1)
        todo = np.flatnonzero(small & (kinds == kind))
        for c in range(0, len(todo), _CHUNK):
            k = todo[c:c + _CHUNK]
            apart[k] = polygons_apart(uv[starts[ia[k]][:, None] + np.arange(ka)],
                                      uv[starts[ib[k]][:, None] + np.arange(kb)])
    ia, ib = ia[~apart], ib[~apart]
    # coplanar: one polygon in the band of the other's plane (the BSP tree's rule)
    a, b = live[ia], live[ib]
    near = _in_band_of(scene, a, b, wide) | _in_band_of(scene, b, a, wide)
    ia, ib, a, b = ia[near], ib[near], a[near], b[near]
    if len(a) == 0:
        return tuple(out)
    # overlap in the plane: more than OVERLAP_RTOL of the smaller polygon's area shared
    ends, inv = np.unique(np.concatenate([ia, ib]), return_inverse=True)
    sub = _vertex_rows_of(starts, ends)
    polys = shapely.make_valid(shapely.polygons(shapely.linearrings(
        uv[sub], indices=np.repeat(np.arange(len(ends)), counts[ends]))))
    area = shapely.area(polys)
    ja, jb = inv[:len(ia)], inv[len(ia):]
    shared = shapely.area(shapely.intersection(polys[ja], polys[jb]))
    hit = shared > tol.OVERLAP_RTOL * np.minimum(area[ja], area[jb])
    a, b = a[hit], b[hit]
    facing = np.sign(np.einsum("ij,ij->i", scene.normals[a], scene.normals[b]))
    pairs = np.column_stack([np.minimum(a, b), np.maximum(a, b)])
    exact = np.ones(len(a), dtype=bool)
    if near_rtol is not None and near_rtol > rtol:
        exact = _in_band_of(scene, a, b, rtol) | _in_band_of(scene, b, a, rtol)
    as_sorted = lambda P: P[np.lexsort((P[:, 1], P[:, 0]))] if len(P) else empty
    out[0] = as_sorted(np.unique(pairs[exact & (facing < 0)], axis=0))
    out[1] = as_sorted(np.unique(pairs[exact & (facing > 0)], axis=0))
    if near_rtol is not None:
        out[2] = as_sorted(np.unique(pairs[~exact], axis=0))
    return tuple(out)
