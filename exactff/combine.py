"""Surfaces made of several polygons, as View3D reports them: combined surfaces (the
``cmb`` column), subsurfaces (``base``), masks (``M``), null surfaces (``N``) and
obstructions (``O``) of a scene read by :func:`exactff.read_vs3`.

View3D computes the factors of every polygon as given and then adjusts them by view
factor algebra (NISTIR 6925; the View3D 3.3 manual, "Surface Types" and "Surface
Combination"). The result it prints, and what :func:`combined_surfaces` describes:

- a **combined** surface (``cmb = c``) is merged into surface ``c``: areas added, rows
  area-weighted, columns added;
- a **subsurface** (``base = b``, facing as ``b``, within it) radiates on its own, and
  ``b`` keeps only its part outside its subsurfaces (a window in a wall);
- a **null** surface (``N``, facing against its base, within it) takes its part away
  from its base: that part neither emits nor receives, and is no output surface;
- a **mask** (``M``, facing against its base, within it) hides its part of the base: the
  base keeps its whole area, sees the mask with ``F = A_M / A_b`` and the rest through
  its unmasked part; the mask sees only its base (``F = 1``), and nothing else sees it;
- an **obstruction** (``O``) only blocks: no row, no column.

Here the algebra is replaced by geometry, which needs no cancellation and no rule for
coplanar overlaps: a polygon with subsurfaces, masks or null surfaces on it is cut into
convex pieces covering its part outside them (:func:`region_pieces`), masks and null
surfaces stay as opaque polygons over the rest, and the area matrix of those polygons
(:func:`exactff.area_form_factors` with ``combine=True``) is reduced to the surfaces by
area weighting (:meth:`CombinedSurfaces.reduce`). A scene without View3D data is one
surface per polygon (the reduction is the identity).
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry.polygon import orient

from . import _tolerances as tol
from .scene import Scene, build_scene

__all__ = ["CombinedSurfaces", "combined_surfaces", "region_pieces"]

def _frame(P, normal):
    e1 = P[1] - P[0]
    e1 = e1 / np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    return P[0], e1, e2 / np.linalg.norm(e2)


def region_pieces(P, normal, holes):
    """Convex pieces covering the part of planar polygon ``P`` outside ``holes``
    (polygons in its plane, within it), in ``P``'s plane and facing as ``P``.

    The region is cut along a line through every vertex, parallel to ``P``'s second
    axis (its first edge's normal in the plane): between two such lines each part of it
    is a trapezoid or a triangle. A wall with a window in it gives four rectangles.

    Parameters
    ----------
    P : ndarray of shape (K, 3)
    normal : ndarray of shape (3,)
        ``P``'s unit normal.
    holes : list of ndarray of shape (K_i, 3)

    Returns
    -------
    list of ndarray of shape (k, 3)

    Raises
    ------
    ValueError
        The booleans failed (GEOS), with its message.

    Examples
    --------
    >>> wall = np.array([[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3.]])
    >>> window = np.array([[1, 0, 1], [2, 0, 1], [2, 0, 2], [1, 0, 2.]])
    >>> pieces = region_pieces(wall, np.array([0, -1, 0.]), [window])
    >>> len(pieces), sum(float(np.ptp(q[:, 0]) * np.ptp(q[:, 2])) for q in pieces)
    (4, 11.0)
    """
    P = np.asarray(P, dtype=float)
    o, e1, e2 = _frame(P, np.asarray(normal, dtype=float))
    to2 = lambda X: np.c_[(X - o) @ e1, (X - o) @ e2]
    try:
        base = shapely.Polygon(to2(P))
        cut = shapely.union_all([shapely.Polygon(to2(np.asarray(H, dtype=float)))
                                 for H in holes])
        region = shapely.make_valid(base).difference(cut)
        if region.is_empty:
            return []
        xy = shapely.get_coordinates(shapely.boundary(region))
        size = float(np.ptp(to2(P), axis=0).max())
        xs = np.sort(xy[:, 0])
        cuts = [xs[0]]
        for x in xs[1:]:
            if x - cuts[-1] > tol.VIEW3D_REGION_RTOL * size:
                cuts.append(x)
        cuts[-1] = max(cuts[-1], xs[-1])
        lo, hi = float(xy[:, 1].min()) - size, float(xy[:, 1].max()) + size
        out = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            part = region.intersection(shapely.box(a, lo, b, hi))
            for g in shapely.get_parts(part):
                if g.geom_type != "Polygon" or g.area <= tol.VIEW3D_REGION_RTOL * base.area:
                    continue
                g = orient(g.simplify(0), 1.0)
                ring = np.asarray(g.exterior.coords)[:-1]
                out.append(o + ring[:, :1] * e1 + ring[:, 1:2] * e2)
    except shapely.errors.GEOSException as exc:
        raise ValueError(f"cutting a polygon around its subsurfaces failed (GEOS: {exc})"
                         ) from None
    return out


class CombinedSurfaces:
    """The surfaces of a scene as View3D reports them, and the polygons whose area
    matrix gives theirs (:func:`combined_surfaces`).

    Attributes
    ----------
    names : tuple of str or None
        One per output surface, in View3D's order (its surface numbers, without the
        combined and null surfaces and the obstructions).
    numbers : tuple of int
        View3D's number of each output surface (1-based; ``i + 1`` without View3D data).
    areas : ndarray of shape (N,)
        Their areas: a combined surface's sum, a base's less its subsurfaces and null
        surfaces (not its masks, as View3D keeps it).
    emissivities : ndarray of shape (N,)
        The emissivity of each (a combined surface's is its own, the first's); NaN
        without View3D data.
    members : tuple of tuple of int
        The polygons of the scene that make each output surface (its own, and those
        combined into it).
    scene : Scene
        The polygons computed: the scene's, with every polygon that has subsurfaces,
        masks or null surfaces replaced by convex pieces around them (the scene itself
        when none has).
    owner : ndarray of shape (len(scene),)
        The output surface of each of those polygons, -1 for none (obstructions, masks
        and null surfaces: they only block).
    masks : tuple of (int, int, float)
        ``(mask, base, area)`` for each mask: output indices and the mask's area.
    """

    def __init__(self, names, numbers, areas, emissivities, members, scene, owner, masks):
        self.names, self.numbers, self.members = tuple(names), tuple(numbers), tuple(members)
        self.areas = np.asarray(areas, dtype=float)
        self.emissivities = np.asarray(emissivities, dtype=float)
        self.scene, self.owner, self.masks = scene, np.asarray(owner, dtype=np.int64), tuple(masks)

    def __len__(self):
        return len(self.names)

    def __repr__(self):
        return f"<CombinedSurfaces: {len(self)} surfaces from {len(self.scene)} polygons>"

    def rows_needed(self, rows):
        """The polygons of :attr:`scene` whose area rows make output rows ``rows``."""
        return np.flatnonzero(np.isin(self.owner, np.asarray(rows)))

    def reduce(self, rows, raw_rows, F, E=None):
        """Output rows ``rows`` from the area rows ``F`` (and estimates ``E``) of
        :attr:`scene`'s polygons ``raw_rows`` (:meth:`rows_needed`).

        ``A_I F[I, J] = sum over the polygons a of I and b of J of A_a F[a, b]``, with
        the masks' own entries (``A_M`` between a mask and its base) added; the
        estimates add the same way (all weights are positive).

        Returns
        -------
        ndarray of shape (len(rows), len(self)), or a pair with ``E``
        """
        import scipy.sparse as sp

        rows, raw_rows = np.asarray(rows, dtype=np.int64), np.asarray(raw_rows, dtype=np.int64)
        n = len(self)
        mine = np.flatnonzero(self.owner >= 0)
        # columns: the sum over each surface's polygons; rows: the area-weighted sum
        cols = sp.csr_matrix((np.ones(len(mine)), (mine, self.owner[mine])),
                             shape=(len(self.scene), n))
        pos = np.full(n, -1)
        pos[rows] = np.arange(len(rows))
        target = pos[self.owner[raw_rows]] if len(raw_rows) else np.zeros(0, dtype=np.int64)
        keep = np.flatnonzero(target >= 0)
        W = sp.csr_matrix((self.scene.areas[raw_rows[keep]], (target[keep], keep)),
                          shape=(len(rows), len(raw_rows)))
        out = []
        for M in (F, E):
            if M is None:
                continue
            AF = np.asarray(W @ (cols.T @ np.asarray(M, dtype=float).T).T)
            if M is F:
                for mask, base, area in self.masks:
                    if pos[mask] >= 0:
                        AF[pos[mask], base] += area
                    if pos[base] >= 0:
                        AF[pos[base], mask] += area
            out.append(AF / self.areas[rows][:, None])
        return out[0] if E is None else (out[0], out[1])


def _surfaces_of(scene):
    """The View3D surface table and each polygon's surface number, or one surface per
    polygon for a scene without View3D data."""
    v3 = scene.metadata.get("view3d")
    if v3 is None:
        return ([{"number": i + 1, "kind": "S", "base": 0, "cmb": 0, "emit": None,
                  "name": scene.names[i]} for i in range(len(scene))],
                list(range(1, len(scene) + 1)))
    return v3["surfaces"], v3["polygon_surface"]


def combined_surfaces(scene: Scene) -> CombinedSurfaces:
    """The surfaces of ``scene`` as View3D reports them (see the module): their names,
    areas and emissivities, and the polygons whose area matrix gives theirs.

    Raises
    ------
    ValueError
        A subsurface, mask or null surface is not in its base's plane, does not face as
        it must (a subsurface as its base, a mask or null surface against it), or is
        not within it; a mask or null surface is itself a base; the message names the
        surfaces by their View3D numbers and names.

    Examples
    --------
    >>> import exactff as ef
    >>> c = combined_surfaces(ef.scenes.subdivided_box(1))
    >>> len(c), c.scene is not None, c.numbers[:3]
    (6, True, (1, 2, 3))
    """
    surfaces, polygon_surface = _surfaces_of(scene)
    by_number = {s["number"]: s for s in surfaces}
    label = lambda s: f"surface {s['number']}" + (f" ({s['name']})" if s.get("name") else "")
    outputs = [s for s in surfaces if s["kind"] in "SM" and not s["cmb"]]
    index = {s["number"]: k for k, s in enumerate(outputs)}
    for s in surfaces:
        if s["kind"] in "SM" and s["cmb"]:
            index[s["number"]] = index[s["cmb"]]
    polys = {}
    for p, num in enumerate(polygon_surface):
        polys.setdefault(num, []).append(p)
    children = {}
    for s in surfaces:
        if s["base"]:
            children.setdefault(s["base"], []).append(s["number"])
            b = by_number[s["base"]]
            if s["kind"] in "MN" and s["number"] in children:
                raise ValueError(f"{label(s)}: a mask or null surface cannot be a base")
            _check_on_base(scene, s, b, polys, label)
    pieces, owner, members = [], [], [[] for _ in outputs]
    replaced = False
    for p, num in enumerate(polygon_surface):
        s = by_number[num]
        out = index[num] if s["kind"] == "S" else -1
        if s["kind"] in "SM":
            members[index[num]].append(p)
        holes = [scene.polygons[q] for c in children.get(num, []) for q in polys.get(c, [])]
        if not holes:
            pieces.append(scene.polygons[p])
            owner.append(out)
            continue
        replaced = True
        try:
            cut = region_pieces(scene.polygons[p], scene.normals[p], holes)
        except ValueError as exc:
            raise ValueError(f"{label(s)}: {exc}") from None
        pieces.extend(cut)
        owner.extend([out] * len(cut))
    if replaced:
        kept = []
        comp = build_scene(pieces, degenerate="drop", face_index=kept)
        owner = np.asarray(owner)[kept]
    else:
        comp, owner = scene, np.asarray(owner)
    owner = np.asarray(owner, dtype=np.int64)
    areas = np.bincount(owner[owner >= 0], comp.areas[owner >= 0], minlength=len(outputs))
    masks = []
    for s in surfaces:
        if s["kind"] == "M":
            a = float(sum(scene.areas[q] for q in polys.get(s["number"], [])))
            masks.append((index[s["number"]], index[s["base"]], a))
            areas[index[s["number"]]] += a
            areas[index[s["base"]]] += a
    emit = [np.nan if s.get("emit") is None else s["emit"] for s in outputs]
    return CombinedSurfaces([s.get("name") for s in outputs], [s["number"] for s in outputs],
                            areas, emit, members, comp, owner, masks)


def _check_on_base(scene, s, b, polys, label):
    """View3D's tests of a subsurface, mask or null surface ``s`` on its base ``b``: in
    its plane, facing as it must, within it."""
    if b["kind"] in "MN":
        raise ValueError(f"{label(s)}: its base {label(b)} is a mask or null surface")
    mine, theirs = polys.get(s["number"], []), polys.get(b["number"], [])
    if not mine or not theirs:
        return
    n_b, d_b = scene.normals[theirs[0]], scene.plane_offsets[theirs[0]]
    for q in mine:
        P = scene.polygons[q]
        rc = float(np.linalg.norm(P - P.mean(axis=0), axis=1).max())
        if np.abs(P @ n_b - d_b).max() > tol.VIEW3D_IN_PLANE_RTOL * rc:
            raise ValueError(f"{label(s)} is not in the plane of its base {label(b)}")
        cos = float(scene.normals[q] @ n_b)
        if s["kind"] == "S" and cos < tol.VIEW3D_FACING_COS:
            raise ValueError(f"{label(s)} should face the same way as its base {label(b)}")
        if s["kind"] in "MN" and cos > -tol.VIEW3D_FACING_COS:
            raise ValueError(f"{label(s)}: a mask or null surface should face against its "
                             f"base {label(b)}")
    o, e1, e2 = _frame(scene.polygons[theirs[0]], n_b)
    to2 = lambda X: np.c_[(X - o) @ e1, (X - o) @ e2]
    try:
        base = shapely.union_all([shapely.Polygon(to2(scene.polygons[q])) for q in theirs])
        sub = shapely.union_all([shapely.Polygon(to2(scene.polygons[q])) for q in mine])
        outside = sub.difference(base).area
    except shapely.errors.GEOSException as exc:
        raise ValueError(f"{label(s)}: testing it against its base failed (GEOS: {exc})"
                         ) from None
    if outside > tol.VIEW3D_WITHIN_RTOL * sub.area:
        raise ValueError(f"{label(s)} is not within its base {label(b)} "
                         f"({outside / sub.area:.3g} of its area is outside)")
