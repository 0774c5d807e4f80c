"""The compiled visibility core: exact rows whose cost follows what they see.

The BSP tree of :mod:`exactff.visibility.bsp` (its compiled build) orders the fragments
front to back; the compiled core (``exactff/_core/``, C++ through pybind11) keeps the
covered region as a shadow-volume BSP tree (planes through the point, Chin & Feiner
1989), filters each convex fragment down it, integrates the visible pieces with the sector form
(or the paper's Eq. 3 in its stable form), and
skips every BSP subtree whose bounding box is already covered. The row runs without
the GIL. Values whose bound misses the requested tolerance are recomputed by the
Python engine (:func:`exactff.visibility.visible_form_factors`), which refines and
escalates; the row's ``stats`` say when.
"""

import math

import numpy as np
import shapely

from .. import _tolerances as tol
from ..errors import NumericalError, check_finite, misses_tolerance
from ..geometry import cross, hull_blockers
from ..kernel import engine_sides_rows, flat_polygons, unoccluded_row, unoccluded_rows
from ..rings import owners, padded, successors
from ..prepared import prepared
from ._svbsp import Core
from .bsp import build_bsp, node_first_charges, node_sides
from .engine import is_convex_enclosure, visible_form_factors

__all__ = ["compiled_core", "compiled_form_factors", "compiled_form_factor_rows",
           "compiled_solid_angles", "convex_pieces", "convex_rings", "SPHERE_HORIZON"]

#: The plane the compiled core's spherical rows cut the sphere at (through the point,
#: this normal): any does; pieces across it are cut in two.
SPHERE_HORIZON = np.array([0.0, 0.0, 1.0])


def convex_pieces(polygon, normal):
    """A planar polygon as convex pieces with the polygon's own vertices.

    Convex polygons (collinear vertices allowed) are returned whole; others are cut into
    triangles by a constrained Delaunay triangulation of their projection on the
    coordinate plane the normal is most nearly perpendicular to (a ring that touches
    itself, as a BSP split can leave, is repaired first; the points where it touches are
    lifted onto the polygon's plane).

    Parameters
    ----------
    polygon : ndarray of shape (K, 3)
    normal : ndarray of shape (3,)
        Its unit normal (counter-clockwise winding).

    Returns
    -------
    list of ndarray of shape (k, 3)

    Examples
    --------
    >>> L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0.]])
    >>> [len(q) for q in convex_pieces(L, np.array([0, 0, 1.0]))]
    [3, 3, 3, 3]
    >>> len(convex_pieces(L[:4], np.array([0, 0, 1.0])))
    1
    """
    P = np.asarray(polygon, dtype=float)
    if convex_rings(P, np.array([0, len(P)]), np.asarray(normal, dtype=float)[None])[0]:
        return [P]
    axis = int(np.argmax(np.abs(normal)))
    keep = [a for a in range(3) if a != axis]
    lookup = {tuple(q): P[i] for i, q in enumerate(P[:, keep].tolist())}
    tri = shapely.constrained_delaunay_triangles(shapely.make_valid(shapely.Polygon(P[:, keep])))
    offset = float(normal @ P[0])

    def lifted(q):
        # a vertex of the polygon, or one that repairing a self-touching ring added
        # (where a ring touches itself): on the polygon's plane, from its projection
        if tuple(q) in lookup:
            return lookup[tuple(q)]
        x = np.zeros(3)
        x[keep] = q
        x[axis] = (offset - normal[keep] @ np.asarray(q)) / normal[axis]
        return x

    pieces = []
    for t in shapely.get_parts(tri):
        ring = np.asarray(t.exterior.coords)[:-1]
        Q = np.array([lifted(q) for q in ring.tolist()])
        # the polygon's own winding
        if cross(Q[1] - Q[0], Q[2] - Q[0]) @ normal < 0:
            Q = Q[::-1]
        pieces.append(Q)
    return pieces


def compiled_core(scene):
    """The scene's compiled core: its BSP tree (built in compiled code,
    ``build_bsp(scene, engine="compiled")``; the Python engine has its own,
    :func:`exactff.visibility.scene_bsp`) with every fragment convex, and the subtrees'
    bounding boxes (built once, cached with the scene).

    Returns
    -------
    (BSPTree, Core)
    """
    return prepared(scene).get("compiled_core", _build_core)


def convex_rings(V, offsets, normals):
    """Which rings are convex (collinear vertices allowed), all at once: the test of
    :func:`convex_pieces` over concatenated rings.

    Parameters
    ----------
    V : ndarray of shape (N, 3)
        The rings' vertices, concatenated.
    offsets : ndarray of shape (M + 1,)
        Ring m is ``V[offsets[m]:offsets[m + 1]]``.
    normals : ndarray of shape (M, 3)
        Each ring's unit normal (counter-clockwise winding).

    Returns
    -------
    ndarray of shape (M,), bool

    Examples
    --------
    >>> L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0.]])
    >>> convex_rings(np.vstack([L, L[:4]]), np.array([0, 6, 10]), np.array([[0, 0, 1.0]] * 2)).tolist()
    [False, True]
    """
    nxt = successors(offsets)
    e = V[nxt] - V
    e_next = e[nxt]
    # each corner's turn about the normal, and its cross product's rounding scale
    turn = np.einsum("ij,ij->i", cross(e, e_next), normals[owners(offsets)])
    scale = np.sqrt(np.einsum("ij,ij->i", e, e) * np.einsum("ij,ij->i", e_next, e_next))
    ok = turn >= -tol.CONVEX_TURN_ULPS * tol.EPS * scale
    return np.logical_and.reduceat(ok, offsets[:-1])


def _ragged_ranges(starts, lengths):
    """The concatenation of ``arange(s, s + k)`` for each start s and length k."""
    lengths = np.asarray(lengths, dtype=np.int64)
    total = int(lengths.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    shift = np.repeat(np.asarray(starts, np.int64) - np.cumsum(lengths) + lengths, lengths)
    return shift + np.arange(total, dtype=np.int64)


def _build_core(scene):
    tree = build_bsp(scene, engine="compiled")
    frag_normals = scene.normals[tree.source]
    counts = np.array([len(P) for P in tree.fragments], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    convex = (convex_rings(np.concatenate(tree.fragments), offsets, frag_normals)
              if len(counts) else np.zeros(0, bool))
    pieces, errors, n_pieces = [], [], np.ones(len(counts), dtype=np.int64)
    fragment_errors = (tree.vertex_errors if tree.vertex_errors is not None
                       else [np.zeros(len(P)) for P in tree.fragments])
    for f, P in enumerate(tree.fragments):
        if convex[f]:
            pieces.append(P)
            errors.append(fragment_errors[f])
            continue
        parts = convex_pieces(P, frag_normals[f])
        pieces.extend(parts)
        errors.extend(_piece_vertex_errors(P, fragment_errors[f], parts, frag_normals[f]))
        n_pieces[f] = len(parts)
    first = np.concatenate([[0], np.cumsum(n_pieces)]).astype(np.int64)
    count = np.array([len(q) for q in pieces], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.int64)
    vertices = np.concatenate(pieces) if pieces else np.zeros((0, 3))
    source = np.repeat(tree.source, n_pieces).astype(np.int64)

    def expand(lists):
        # each node's fragments, in order, as the indices of their pieces
        flat = np.fromiter((f for here in lists for f in here), dtype=np.int64)
        return _ragged_ranges(first[flat], n_pieces[flat])

    sizes = [int(n_pieces[here].sum()) if len(here) else 0 for here in tree.node_fragments]
    here_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    core = Core(vertices=vertices, start=start, count=count, source=source,
                front=tree.front.astype(np.int64), back=tree.back.astype(np.int64),
                here_start=here_start, here_front=expand(tree.node_fragments),
                here_behind=expand(tree.node_fragments_behind), n_sources=len(scene),
                band=tol.SVBSP_BAND, c1=tol.C1, c2=tol.C2, split=tol.SVBSP_SPLIT_ULPS,
                vertex_errors=np.concatenate(errors) if errors else np.zeros(0))
    return tree, core


def _shaft(scene, p, j):
    """The polygons that may hide part of polygon ``j`` from ``p``, with ``j``, as sorted
    indices (the scene's order, which the tie rule of coplanar faces follows): those
    reaching into the convex hull of ``p`` and ``j``, the lines of sight from p to j
    (:func:`exactff.geometry.hull_blockers`, keeping every polygon within
    ``SHAFT_MARGIN`` of the scene's size of it). Where p lies within rounding of j's
    plane (p and j span no solid hull), the hull of j and the two points that margin
    off p along j's normal, which holds the same lines of sight; None only where that
    hull is flat too."""
    flat = flat_polygons(scene)
    # the polygons' boxes (once per scene; the scene is not padded as a whole: one long
    # polygon would pad every other to its length)
    lo_k, hi_k = prepared(scene).get("boxes", lambda s: (
        np.minimum.reduceat(flat.V, flat.offsets[:-1]),
        np.maximum.reduceat(flat.V, flat.offsets[:-1])))
    Q = flat.V[flat.offsets[j]:flat.offsets[j + 1]]
    margin = tol.SHAFT_MARGIN * (1.0 + float(flat.vmax.max()))
    # the points the lines of sight start from: p, or p and p +- margin n_j
    starts = p[None]
    lo, hi = np.minimum(p, Q.min(axis=0)) - 2 * margin, np.maximum(p, Q.max(axis=0)) + 2 * margin
    box = np.all((hi_k >= lo) & (lo_k <= hi), axis=1)
    box[j] = False
    cand = np.flatnonzero(box)
    if len(cand) == 0:
        return np.array([j], dtype=np.int64)
    V, _ = padded([flat.V[flat.offsets[k]:flat.offsets[k + 1]] for k in cand.tolist()])
    kept = hull_blockers(V, np.arange(len(cand)), starts, Q, -margin, none_if_flat=True)
    if kept is None:
        starts = p[None] + np.array([[margin], [-margin]]) * flat.normals[j]
        kept = hull_blockers(V, np.arange(len(cand)), starts, Q, -margin, none_if_flat=True)
    return None if kept is None else np.sort(np.append(cand[kept], j).astype(np.int64))


def _sides(flat, p):
    """The side of ``p`` for every polygon as the engines take it, and the band
    (:func:`exactff.predicates.engine_sides`), by the compiled pass that takes a matrix's
    points at once (:func:`exactff.kernel.engine_sides_rows`: the same sides up to an ulp
    of the in-plane test's threshold, where BLAS may sum ``|n| . |p|`` in another order;
    tested against it), so that a row and the same row of a matrix start from one
    pass."""
    side, band = engine_sides_rows(flat, p[None])
    return side[0], band[0]


def _core_row(scene, p, normal, side, *, two_sided, shortcuts, tolerance, integrator, floor):
    """The compiled core's row from ``p`` (``side``: the polygons' exact sides of it):
    values, bounds (the pieces' rounding and geometry, after the quadruple-precision
    tier where ``tolerance`` times the larger of the value and half ``floor`` asks for
    it), the band's slivers with the node-first order's charge (a bound on the
    topology), the BSP crossings' part, and counters."""
    tree, core = compiled_core(scene)
    node_side = node_sides(tree, p, side)
    F, E, band, crossing, counters = core.row(
        point=p, normal=np.asarray(normal, dtype=float), node_side=node_side,
        source_side=side.astype(np.int8), two_sided=bool(two_sided), cull=bool(shortcuts),
        box_budget=tol.SVBSP_BOX_BUDGET, tiles=_shadow_tiles(len(scene)),
        rtol=0.0 if tolerance is None else float(tolerance), floor=float(floor),
        eq3=integrator == "eq3")
    check_finite(F, E)
    check_finite(band)
    check_finite(crossing)
    # what visiting a node's fragments before its near subtree may misplace: with the
    # band's slivers (a bound on the topology, not checked)
    band = band + 4 * node_first_charges(tree, p, node_side, _receives(side, two_sided), side)
    return F, E, band, crossing, counters


def _receives(side, two_sided):
    """Which polygons receive from a point on their sides ``side``: those it is in front
    of, and with ``two_sided`` those it is behind too."""
    return side != 0 if two_sided else side > 0


def _settled(F, E, crossing, tolerance):
    """Whether values ``F`` with bounds ``E`` (the parts no precision narrows left out:
    the band's slivers and the node-first order's) and BSP crossings' parts
    ``crossing`` meet ``tolerance``, the crossings' part the accuracy target of
    occluded values."""
    return ~(misses_tolerance(F, E, tolerance) | (crossing > tol.OCCLUDED_ATOL))


def _settle_in_shafts(scene, p, normal, missed, *, two_sided, shortcuts, tolerance,
                      integrator, floor, stats):
    """The values of polygons ``missed`` from ``p``, each recomputed on its shaft
    (:func:`_shaft`, the polygons that may hide part of it: the same exact value), whose
    BSP splits along other lines than the scene's, and only where its polygons meet:
    first by the compiled core, where the row's shafts hold at most
    ``SHAFT_COMPILED_MAX_POLYGONS`` polygons in all; then those still missing by the
    Python engine, which refines and escalates, where theirs hold at most
    ``COMPILED_FALLBACK_MAX_POLYGONS`` (about one whole Python row of a scene that
    size). Returns ``{j: (F, E, T)}`` for the values settled, by the criterion of the
    whole row (:func:`_settled`): E the checked bound with the crossings' part, T the
    unchecked topology part (the compiled sub-row's band and node-first charge; 0 from
    the Python engine, whose E holds its own). ``stats["shaft_sizes"]`` collects the sizes of the
    shafts tried, ``stats["shaft_compiled"]`` counts the values the compiled core
    settled there."""
    shafts = {j: _shaft(scene, p, j) for j in missed}
    if any(k is None for k in shafts.values()):
        return {}
    settled, sizes = {}, []
    stats.setdefault("shaft_compiled", 0)
    if sum(len(k) for k in shafts.values()) <= tol.SHAFT_COMPILED_MAX_POLYGONS:
        for j, keep in shafts.items():
            sizes.append(len(keep))
            sub = scene.subset(keep)
            at = int(np.searchsorted(keep, j))
            side, _ = _sides(flat_polygons(sub), p)
            G, H, topology, moved, _ = _core_row(
                sub, p, normal, side, two_sided=two_sided, shortcuts=shortcuts,
                tolerance=tolerance, integrator=integrator, floor=floor)
            if _settled(G[at], H[at], moved[at], tolerance):
                settled[j] = float(G[at]), float(H[at] + moved[at]), float(topology[at])
                stats["shaft_compiled"] += 1
    rest = {j: keep for j, keep in shafts.items() if j not in settled}
    if sum(len(k) for k in rest.values()) > tol.COMPILED_FALLBACK_MAX_POLYGONS:
        rest = {}
    for j, keep in rest.items():
        sizes.append(len(keep))
        sub = scene.subset(keep)
        at = int(np.searchsorted(keep, j))
        # (asks the engine for each polygon's parts of its bound: the rounded crossings',
        # and the node-first order's, which no precision narrows: unchecked, as the core's
        # band)
        sub_st = {"polygon_crossing": None, "polygon_misorder": None}
        G, H = visible_form_factors(sub, p, normal, two_sided=two_sided, stats=sub_st,
                                    shortcuts=shortcuts, tolerance=tolerance, error=True,
                                    integrator=integrator)
        moved = 0.0 if sub_st["polygon_crossing"] is None else sub_st["polygon_crossing"][at]
        order = 0.0 if sub_st["polygon_misorder"] is None else sub_st["polygon_misorder"][at]
        if _settled(G[at], H[at] - moved - order, moved, tolerance):
            settled[j] = float(G[at]), float(H[at]), 0.0
    if sizes:
        stats.setdefault("shaft_sizes", []).extend(sizes)
    return settled


def _missed_message(j, F, E, crossing, tolerance, count, python=False, band=None):
    """The error of a row whose value ``j`` (one of ``count``) missed the tolerance
    (``band``: the band's slivers, named where they exceed the value's scale)."""
    j = int(j)
    where = ("after the Python engine's refinement" if python else
             "in the compiled core (nor by the Python engine on the polygons that may hide "
             "part of it, where they are few enough)")
    part = ("" if python or not crossing[j] > tol.OCCLUDED_ATOL else
            f"; {crossing[j]:.3g} of it from the BSP's rounded crossings")
    if band is not None and misses_tolerance(F[j], band[j], 1.0):
        part += f"; the band's slivers {band[j]:.3g}, beyond the value's scale"
    return (f"polygon {j}: the form factor {F[j]!r} misses the tolerance {tolerance:g} "
            f"relative (times the larger of |F| and {tol.VALUE_FLOOR:g}) {where}: "
            f"error bound {E[j]:.3g}{part} ({count} value(s) of the row miss it); ask "
            f"error=True for the row with its bounds, or a larger tolerance")


def _piece_vertex_errors(P, errors, parts, normal):
    """Per vertex of the convex pieces of fragment ``P``, a bound on its distance from the
    exact point it stands for: a vertex of ``P`` keeps its own (``errors``); one that
    repairing a self-touching ring lifted onto the plane gets the fragment's largest
    plus the lifting's rounding (16 ulps of its coordinates, scaled by the slope of the
    plane over the coordinate plane it was lifted from)."""
    own = {}
    for v, e in zip(P.tolist(), np.asarray(errors).tolist()):
        own[tuple(v)] = max(e, own.get(tuple(v), 0.0))   # a ring may repeat a point
    axis = int(np.argmax(np.abs(normal)))
    slope = 1 + np.abs(normal).sum() / abs(normal[axis])
    worst = float(np.max(errors)) if len(errors) else 0.0
    return [np.array([own.get(tuple(v), worst + 16 * tol.EPS * slope * np.abs(v).sum())
                      for v in Q.tolist()]) for Q in parts]


def _shadow_tiles(n):
    """Planes per axis of the grid the compiled core cuts the upper hemisphere into,
    for a scene of ``n`` polygons: about ``SVBSP_POLYGONS_PER_CELL`` polygons per cell,
    within ``SVBSP_TILES`` and ``SVBSP_TILES_MAX`` (each cell's shadows grow on their
    own chain; more cells, shorter chains). The core cuts it at once only into blocks
    of fewer than ``SVBSP_TILES_EAGER`` planes per axis, and a block further where a
    visible piece lies on one side of its middle plane, so that a finer plane never cuts
    the piece it is placed for.

    Examples
    --------
    >>> _shadow_tiles(4424), _shadow_tiles(80461)
    (8, 35)
    """
    cells_per_axis = math.ceil(math.sqrt(n / tol.SVBSP_POLYGONS_PER_CELL))
    return int(min(max(cells_per_axis - 1, tol.SVBSP_TILES), tol.SVBSP_TILES_MAX))


def compiled_form_factors(scene, point, normal, *, two_sided=False, stats=None,
                          shortcuts=True, tolerance=None, error=False, integrator="sector",
                          floor=tol.VALUE_FLOOR):
    """Exact form factors with occlusion from one point to every polygon of a scene, by
    the compiled core.

    The same values as :func:`exactff.visibility.visible_form_factors` (the Python
    engine, which stays as the oracle) within the two bounds. The compiled row's bound
    of each value is the rounding of its pieces' sector sums, the error of their
    vertices' directions times their edges' arc lengths, and the slivers that the
    band's decisions may misplace: a vertex within rounding of a shadow plane whose
    side exact arithmetic cannot settle (a vertex computed from computed ones) is taken
    as on it, and its two edges' arc lengths times the band are added
    (``docs/explanation/visibility.md``). With a ``tolerance``, a piece whose first two
    exceed it times its value is integrated again in quadruple precision, its computed
    vertices recomputed where its edges' planes meet (``stats["quad_pieces"]``): on a
    sliver the long double cuts leave an absolute bound of about 1e-18, which this makes
    relative. The tier is decided per polygon: it is spent only where the polygon's
    bound exceeds the tolerance times the larger of its value and half ``floor``. By
    default ``floor`` is ``VALUE_FLOOR``, the floor of the contract below: a value
    under it keeps the long double bound where that meets the contract (about 1e-18 on
    the IFC files' grazing values, within the 1e-14 allowed at the default tolerance);
    ``floor=0`` makes every bound relative (:func:`exactff.testing.ground_truth`).
    Where a value's bound still misses the tolerance by the criterion of every path
    (:func:`exactff.errors.misses_tolerance`: ``tolerance`` times the larger of the
    value and ``VALUE_FLOOR``), or its BSP crossings' part exceeds the accuracy
    target of occluded values, those values (and only those) are taken from the Python
    engine, which refines and escalates, on scenes of at most
    ``COMPILED_FALLBACK_MAX_POLYGONS`` polygons (``stats["path"]`` then says
    ``"compiled, python for some polygons"``, ``stats["compiled_missed"]`` and
    ``stats["python_polygons"]`` count them); a value that still misses raises
    :class:`exactff.NumericalError` naming its polygon, unless ``error=True``, which
    returns it with its bound. On a larger scene such a value raises at once (or is
    returned with its bound): the Python engine's row would cost 5 to 20 times the
    compiled one's, and more on a scene that size. The band's slivers
    (``stats["max_band_bound"]``) are a
    bound on the topology: they are in the returned bound but not checked against the
    tolerance, as the Python engine's topology has the same decisions and its bound
    leaves them out. No precision tier narrows them (they come from the decisions, not
    from the arithmetic), so checking them would only send to the Python engine values
    that its own check accepts. Only where they exceed the value's own scale,
    ``max(|F|, VALUE_FLOOR)``, a bound that says nothing of it (a scene with subnormal
    coordinates), is the value taken as missed, as above.

    Parameters
    ----------
    scene : Scene
    point, normal : ndarray of shape (3,)
        The receiving point and its unit normal.
    two_sided : bool, default False
        Let polygons receive on their back side too; every polygon occludes whichever
        way it faces.
    stats : dict, optional
        Filled with what the row did: ``path``, ``fragments`` (filtered down the
        shadow tree), ``visible_pieces``, ``hidden_pieces``, ``splits``,
        ``subtrees_culled`` and ``fragments_culled`` (skipped by their bounding box),
        ``box_tests``, ``shadow_planes``, ``node_visits`` (shadow-tree nodes a piece
        was classified at), ``near_tests`` (vertices within a plane's rounding band),
        ``exact_tests`` (exact tests of an input point decided, not found in the row's
        cache), ``quad_pieces`` (integrated again in
        quadruple precision), ``shadows_left_out`` (visible slivers, whose shadows are
        left out), ``kernel_shadows`` (pieces whose image is not convex to a roundoff:
        their kernel is their shadow), ``omitted_sides`` (shadows without a side too
        short to orient), ``unattributed_bound`` (what those shadows leave uncovered or
        cover beyond their pieces, charged to every value) and ``leaks`` (uncovered
        parts too large for that, charged only to the visible pieces whose cones meet
        theirs), ``collapsed`` (shadow-tree nodes merged into a covered leaf, their
        two sides covered) and ``covered`` (every direction the row sees covered: the
        walk stopped), ``tiles_cut`` (the tiles' planes placed where a visible piece
        lay on one side of a block's middle plane, beyond the coarse grid every row
        starts from), ``repeated_sides`` (shadows' sides left out because the same
        plane, through the same two input points, is already on the path to their
        leaf: the edges adjacent polygons share; 0 without the shortcuts),
        ``fragments_covered`` and ``subtrees_covered`` (fragments and
        subtrees skipped because their directions lie in cells of the cube map about the
        point proven covered), ``cover_proofs``, ``cover_cells`` and ``cover_visits``
        (the proofs tried, the cells proven, the shadow-tree visits they took),
        ``fragments_behind`` (fragments skipped because every vertex lies clearly
        behind the point's tangent plane, 0 without the shortcuts or with the sphere),
        ``working_bytes`` (the row's own containers at their largest: its
        shadow tree, exact planes, work list, edge charges and cache, beyond the
        n-long results), ``max_error_estimate``, ``max_band_bound`` and
        ``max_crossing_bound`` (the part of the bounds the BSP's rounded crossings make,
        added like the band's and checked only against the accuracy target of occluded
        values, 1e-11); where values missed the tolerance, ``compiled_missed`` and,
        after the Python engine, ``python_polygons``.
    shortcuts : bool, default True
        False disables the convex-scene path and the culling of subtrees (results do
        not depend on it).
    tolerance : float or None
        Relative accuracy requested of every value; None: no check, no fallback. The
        parts of the bound no precision tier narrows are checked apart: the band's
        slivers only against the value's own scale, the BSP crossings' rounding against
        the accuracy target of occluded values (``OCCLUDED_ATOL``, 1e-11, absolute); a
        value whose bound misses the tolerance by those parts alone is returned with that
        bound, unchecked.
    error : bool, default False
        Also return each value's bound.
    integrator : {"sector", "eq3"}, default "sector"
        How the core integrates visible pieces, in both of its precisions: the sector
        form, or the paper's Eq. 3 (corrected, monotone spans) in its stable form
        (:func:`exactff.kernel.eq3_ring_sums`); the pieces, the vertices' and edges'
        charges and the quadruple-precision tier are the same. The paths that leave
        the core (the convex-scene shortcut, the fallback) use the same integrator.
    floor : float, default VALUE_FLOOR
        The value below which the quadruple-precision tier holds a polygon's bound to
        half the tolerance times ``floor`` instead of the tolerance times its value,
        between 0 (every bound relative, as far as that tier reaches) and
        ``VALUE_FLOOR``. The check stays :func:`exactff.errors.misses_tolerance`'s,
        whatever the floor.

    Returns
    -------
    ndarray of shape (len(scene),), or a pair of them with ``error=True``

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.cornell_box(closed=True)
    >>> F = compiled_form_factors(box, [278, 0.5, 279.6], [0, 1, 0], tolerance=1e-12)
    >>> bool(abs(F.sum() - 1) < 1e-12)
    True
    """
    st = stats if stats is not None else {}
    p = np.asarray(point, dtype=float)
    flat = flat_polygons(scene)
    side, band = _sides(flat, p)
    if shortcuts and is_convex_enclosure(scene) and np.all(side >= 0):
        if integrator == "eq3":
            # no occlusion, Eq. 3: the Python engine's convex-scene path, which
            # integrates whole polygons with it and escalates
            return visible_form_factors(scene, p, normal, two_sided=two_sided, stats=st,
                                        shortcuts=shortcuts, tolerance=tolerance,
                                        error=error, integrator=integrator)
        # no occlusion: the unoccluded kernel (compiled sector sums) with its ladder,
        # straight from here, as the Python engine's convex-scene path has it
        st["path"] = "unoccluded"
        return unoccluded_row(flat, p, normal, two_sided=two_sided, tolerance=tolerance,
                              sides=(side, band), return_error=error, strict=not error)
    F, E, band, crossing, counters = _core_row(
        scene, p, normal, side, two_sided=two_sided, shortcuts=shortcuts,
        tolerance=tolerance, integrator=integrator, floor=floor)
    st["max_crossing_bound"] = float(crossing.max(initial=0.0))
    path = "compiled"
    if tolerance is not None:
        # the rounding and geometry of the pieces, after the core's second tier (above),
        # by the Python engine's own criterion; the band's slivers (below) no engine
        # here narrows; nor the BSP crossings' rounding (`crossing`: the Python engine's
        # crossings are rounded too, and it holds its own charge for them to the same
        # target), which is held to the accuracy target of occluded values
        # (and a value whose band's slivers exceed its own scale, max(|F|, VALUE_FLOOR):
        # that bound of the topology says nothing of the value, whose decisions are then
        # not the Python engine's; a scene with subnormal coordinates, rotated by an angle
        # of 2e-313, left a closed room's row summing to 0.607 with slivers of 1e307,
        # where the Python engine's sums to 1; on the real files' rows that ratio is at
        # most 6e-11)
        # (none of the three can hold where the row's largest bound of each is within
        # its test's least allowance: the tolerance times VALUE_FLOOR, OCCLUDED_ATOL,
        # VALUE_FLOOR; the usual row, tested in three maxima)
        missed = np.zeros(0, dtype=np.intp)
        if (float(E.max(initial=0.0)) > float(tolerance) * tol.VALUE_FLOOR
                or st["max_crossing_bound"] > tol.OCCLUDED_ATOL
                or float(band.max(initial=0.0)) > tol.VALUE_FLOOR):
            missed = np.flatnonzero(misses_tolerance(F, E, tolerance) |
                                    (crossing > tol.OCCLUDED_ATOL) |
                                    misses_tolerance(F, band, 1.0))
        if len(missed):
            st.update(counters)
            st["compiled_missed"] = int(len(missed))
            if len(scene) > tol.COMPILED_FALLBACK_MAX_POLYGONS:
                # the Python engine, polygon by polygon, on the polygons that may hide
                # part of it (its shaft): the values it settles replace the core's
                settled = _settle_in_shafts(scene, p, normal, missed.tolist(),
                                            two_sided=two_sided, shortcuts=shortcuts,
                                            tolerance=tolerance, integrator=integrator,
                                            floor=floor, stats=st)
                F, E, band, crossing = F.copy(), E.copy(), band.copy(), crossing.copy()
                for j, (value, bound, topology) in settled.items():
                    # its bound is the shaft's row's whole bound (its own band and
                    # crossings included)
                    F[j], E[j], band[j], crossing[j] = value, bound, topology, 0.0
                st["shaft_polygons"] = len(settled)
                st["max_crossing_bound"] = float(crossing.max(initial=0.0))
                missed = np.setdiff1d(missed, list(settled))
                if len(settled):
                    path = "compiled, shaft for some polygons"
                if len(missed) and not error:
                    raise NumericalError(_missed_message(missed[0], F, E, crossing, tolerance,
                                                         len(missed), band=band))
            else:
                # the Python engine (it refines and escalates) for these values only
                G, H = visible_form_factors(scene, p, normal, two_sided=two_sided, stats={},
                                            shortcuts=shortcuts, tolerance=tolerance,
                                            error=True, integrator=integrator)
                F, E, band = F.copy(), E.copy(), band.copy()
                F[missed], E[missed] = G[missed], H[missed]
                band[missed] = 0.0      # (the Python engine's own slivers are in H)
                st["python_polygons"] = int(len(missed))
                st["path"] = "compiled, python for some polygons"
                # the compiled tree's measure of the crossings' rounding added too (the
                # Python engine charges its own tree's: the same geometry split by another
                # tree; both kept, the larger sum still a bound)
                E = _capped_by_unoccluded(scene, p, normal, F, E + band + crossing, two_sided)
                st["max_error_estimate"] = float(E.max(initial=0.0))
                still = missed[misses_tolerance(F[missed], H[missed], tolerance)]
                if len(still) and not error:
                    raise NumericalError(_missed_message(still[0], F, H, crossing, tolerance,
                                                         len(still), python=True))
                return (F, E) if error else F
    st.update(counters)
    st["path"] = path
    E = _capped_by_unoccluded(scene, p, normal, F, E + band + crossing, two_sided)
    st["max_error_estimate"] = float(E.max(initial=0.0))
    st["max_band_bound"] = float(band.max(initial=0.0))
    return (F, E) if error else F


def _capped_by_unoccluded(scene, p, normal, F, E, two_sided):
    """The bounds ``E`` of a row's values ``F``, each at most what the value could be
    off by at all: the exact value lies between 0 and the polygon's unoccluded value U
    (nothing it does not see can add to it), so ``|F - exact| <= max(F, U + e_U - F)``
    with e_U U's own estimate. Taken only where a bound exceeds both its value and
    ``BOUND_CAP_FROM``: the band's slivers of a vertex whose direction is computed from
    nearly parallel planes can reach 1e7 on a value of 3e-6 (SampleHouse4), a bound that
    says nothing."""
    if not E.max(initial=0.0) > tol.BOUND_CAP_FROM:
        return E
    big = np.flatnonzero((E > F) & (E > tol.BOUND_CAP_FROM))
    if len(big) == 0:
        return E
    sub = flat_polygons(scene.subset(big))
    side, band = _sides(sub, p)
    U, eU = unoccluded_rows(sub, p[None], np.asarray(normal, dtype=float)[None], side[None],
                            band[None], two_sided=two_sided, tolerance=tol.DEFAULT_RTOL,
                            strict=False)
    E = E.copy()
    E[big] = np.minimum(E[big], np.maximum(F[big], U[0] + eU[0] - F[big]) * (1 + 4 * tol.EPS))
    return E


def compiled_solid_angles(scene, point, *, two_sided=True, stats=None, shortcuts=True):
    """Visible solid angles with occlusion from one point to every polygon of a scene,
    over the whole sphere, by the compiled core, and their error bounds.

    One row of the core in its sphere mode: the shadow tree's root (the plane through
    the point normal to :data:`SPHERE_HORIZON`) leaves both of its sides free, each cut
    into cells as a plane row's upper hemisphere is, so that one front-to-back walk of
    the BSP tree covers every direction; each visible piece is measured by its solid
    angle (Van Oosterom and Strackee's fan, as :func:`exactff.kernel.solid_angle_sums`)
    instead of its cosine-weighted one. Subtrees behind the horizon are not culled (the
    sphere has no behind); covered ones are. The Python engine's two hemispheres
    (:func:`exactff.visibility.visible_solid_angles`) are its oracle.

    Parameters
    ----------
    scene : Scene
    point : ndarray of shape (3,)
    two_sided : bool, default True
        Both faces of a polygon receive (every polygon occludes either way).
    stats : dict, optional
        Filled with the core's counters (as :func:`compiled_form_factors`), ``path``
        (``"compiled sphere"``) and ``max_error_estimate``.
    shortcuts : bool, default True
        False disables the culling of covered subtrees (results do not depend on it).

    Returns
    -------
    (ndarray of shape (len(scene),), ndarray of shape (len(scene),))
        Solid angles in steradians (their sum at most 4 pi) and bounds on their errors:
        the fans' rounding, the vertices' directions' errors times their edges' arc
        lengths, the band's slivers and the BSP's rounded crossings (as for
        :func:`compiled_form_factors`, whose bounds are areas on the unit sphere too).
        No value is refined: the core has no quadruple-precision solid angle.

    Examples
    --------
    From inside a closed box the whole sphere is seen, a sixth of it through each face
    from the centre:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> W, E = compiled_solid_angles(box, np.array([0.5, 0.5, 0.5]))
    >>> bool(abs(W.sum() - 4 * np.pi) < 1e-13), bool(E.max() < 1e-14)
    (True, True)
    """
    st = stats if stats is not None else {}
    p = np.asarray(point, dtype=float)
    flat = flat_polygons(scene)
    side, _ = _sides(flat, p)
    tree, core = compiled_core(scene)
    node_side = node_sides(tree, p, side)
    F, E, band, crossing, counters = core.row(
        point=p, normal=SPHERE_HORIZON, node_side=node_side, source_side=side.astype(np.int8),
        two_sided=bool(two_sided), cull=bool(shortcuts), box_budget=tol.SVBSP_BOX_BUDGET,
        tiles=_shadow_tiles(len(scene)), rtol=0.0, floor=0.0, eq3=False, sphere=True)
    check_finite(F, E)
    check_finite(band)
    check_finite(crossing)
    band = band + 4 * node_first_charges(tree, p, node_side, _receives(side, two_sided), side)
    # the core's unit is the solid angle over pi (the cosine-weighted rows' unit)
    W = F * math.pi
    # (and the products' rounding)
    E = (E + band + crossing) * (math.pi * (1 + 4 * tol.EPS)) + 2 * tol.EPS * W
    st.update(counters)
    st["path"] = "compiled sphere"
    st["max_error_estimate"] = float(E.max(initial=0.0))
    return W, E


def compiled_form_factor_rows(scene, points, normals, *, two_sided=False, shortcuts=True,
                              tolerance=None, floor=tol.VALUE_FLOOR):
    """Rows of :func:`compiled_form_factors` from many receivers, value for value: the
    rows a convex enclosure leaves unoccluded (with ``shortcuts``, the point in front of
    or in every polygon's plane) computed together, their sector sums in one compiled
    call per tier (:func:`exactff.kernel.point.unoccluded_rows`); the others one by one.

    Parameters
    ----------
    scene : Scene
    points, normals : ndarray of shape (R, 3)
        The receivers (unit normals, or normalised here).
    two_sided, shortcuts, tolerance, floor
        As for :func:`compiled_form_factors`.

    Returns
    -------
    ndarray of shape (R, len(scene))

    Examples
    --------
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(4)
    >>> F = compiled_form_factor_rows(box, box.centroids, box.normals, tolerance=1e-12)
    >>> F.shape, bool(np.abs(F.sum(axis=1) - 1).max() < 1e-13)
    ((96, 96), True)
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    N = np.asarray(normals, dtype=float).reshape(-1, 3)
    out = np.zeros((len(P), len(scene)))
    flat = flat_polygons(scene)
    convex = shortcuts and is_convex_enclosure(scene)
    together = []
    if convex:
        # the sides of every receiver at once (each row's as for its point alone)
        side, band = engine_sides_rows(flat, P)
        together = np.flatnonzero(np.all(side >= 0, axis=1)).tolist()
    if len(together) == len(P):
        return unoccluded_rows(flat, P, N, side, band, two_sided=two_sided,
                               tolerance=tolerance)[0]
    if together:
        out[together] = unoccluded_rows(
            flat, P[together], N[together], side[together], band[together],
            two_sided=two_sided, tolerance=tolerance)[0]
    for r in sorted(set(range(len(P))) - set(together)):
        out[r] = compiled_form_factors(scene, P[r], N[r], two_sided=two_sided,
                                       shortcuts=shortcuts, tolerance=tolerance, floor=floor)
    return out
