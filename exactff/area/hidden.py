"""The hidden part of a receiver at points of the emitter: ``F(x -> Q) - F_occ(x -> Q)``,
the point form factor of what the blockers hide of Q from x, built in Q's plane from the
blockers' projections (compiled, :mod:`exactff.area._hidden`) and integrated by the
sector sums, with its error estimate, the engine where a point's images cannot be
trusted, and the bound ``0 <= hidden <= F(x -> Q)`` where that is cheap enough
(docs/explanation/area-form-factors.md).
"""

from typing import NamedTuple

import numpy as np

from .. import _tolerances as tol
from ..errors import nonnegative
from ..geometry import area_vector, plane_frame, polygon_area, receiver_frame, unit_normal
from ..halfspace import NORMAL_FLOOR, clip_front
from ..methods import Exact
from ..predicates import coplanar_band_sides
from ..rings import padded
from ..scene import build_scene, validate_polygon
from ..visibility import convex_pieces, convex_rings
from ._hidden import hidden_pieces
from ._pair import hidden_setup as _compiled_hidden_setup
from .points import point_values

__all__ = ["HiddenSetup", "hidden_setup", "hidden_values", "hidden_values_by_engine"]


class HiddenSetup(NamedTuple):
    """What :func:`hidden_values` needs of a receiver and its blockers whatever the
    points (:func:`hidden_setup`, once per pair)."""

    #: Qc's unit normal, origin (its first vertex) and frame (rows t1, t2, n).
    nQ: np.ndarray
    q0: np.ndarray
    RQ: np.ndarray
    #: The blockers' parts in front of Qc's plane (those with any).
    Kc: list
    #: The pyramid's base (4 or more corners, 3-D): Qc where it is strictly convex, else
    #: a rectangle around it.
    corners: np.ndarray
    #: Qc's convex parts in its frame, padded (p, k, 2), and their vertex counts; none
    #: where the base is Qc itself.
    parts: np.ndarray
    part_counts: np.ndarray
    #: The blockers' convex pieces, padded (m, k, 3), their vertex counts and unit
    #: normals (outward for members of a convex solid).
    V: np.ndarray
    counts: np.ndarray
    NK: np.ndarray
    #: Each piece's convex solid, labelled 0, 1, ... (-1: none).
    group: np.ndarray
    #: The box of the blockers and Qc.
    lo: np.ndarray
    hi: np.ndarray
    #: Qc's size in its plane (the pieces lie within Qc or its box).
    extent: float
    #: The area of Qc's convex parts left out as slivers of rounding (width within
    #: ``CONVEX_TURN_ULPS`` ulps of their length: their sides' half-planes are
    #: rounding's, and may keep what lies outside them): the caller bounds their hidden
    #: part by their unoccluded one.
    sliver_area: float = 0.0


def hidden_setup(Qc, blockers, solid=None, inner=None, compiled=True):
    """The :class:`HiddenSetup` of a receiver Qc and its blockers (once per pair): Qc's
    frame, the blockers' parts in front of its plane as convex pieces with their unit
    normals and convex solids, the pyramid's base (Qc where it is strictly convex, else
    a rectangle around it, with Qc's convex parts), the box of the blockers and Qc, and
    Qc's size in its plane. None where no blocker is in front.

    ``solid``: the convex solid of each blocker for the pair
    (:func:`~exactff.area.culling.closed_solids`), -1 for none, and ``inner`` a point
    inside its hull (NaN where not every member of the solid is a blocker of the pair: a member culled within rounding of a line of
    sight could not stand in for one skipped): a solid's members get their outward
    normals, and from a point outside the hull those it sees from behind are skipped
    (their images lie in those of the members it sees from the front). A member whose
    plane passes within ``AREA_HULL_RTOL`` of the hull's size of the inner point leaves
    its solid as a whole (which side is out is not certain).

    ``compiled`` (default): built by :mod:`exactff.area._pair` (``_core/hidden_setup.cpp``)
    where Qc is strictly convex and every blocker's part in front is convex (one piece
    each); else, and without ``compiled``, here, the reference it is tested against
    (``tests/test_area_pair_compiled.py``).

    A blocker in Qc's plane (every vertex within the near-coplanar band of it,
    :func:`exactff.predicates.coplanar_band_sides`: coplanar by the conventions' rule)
    hides nothing here, whichever way it faces: an overlap of coplanar faces is the
    tie rule's, which the row applies (:func:`~exactff.area.culling.tie_covers`), as
    the point engine does. Its part "in front" would be its rounding's."""
    nQ0, q00 = plane_frame(Qc)[:2]
    off = np.array([[float(nQ0 @ q00)]])
    flat = [k for k, K in enumerate(blockers)
            if np.all(coplanar_band_sides(np.asarray(K, dtype=float), nQ0[None], off[0])[0] == 0)]
    if flat:
        keep = [k for k in range(len(blockers)) if k not in set(flat)]
        if not keep:
            return None
        blockers = [blockers[k] for k in keep]
        if solid is not None:
            solid = np.asarray(solid)[keep]
        if inner is not None:
            inner = np.asarray(inner)[keep]    # (a point per blocker, as solid)
    if compiled:
        W = np.concatenate([np.asarray(K, dtype=float) for K in blockers])
        start = np.concatenate([[0], np.cumsum([len(K) for K in blockers])])
        with_solids = solid is not None and inner is not None
        r = _compiled_hidden_setup(
            np.asarray(Qc, dtype=float), W, start,
            np.asarray(solid if with_solids else [], dtype=np.int64),
            np.asarray(inner if with_solids else np.zeros((0, 3)), dtype=float).reshape(-1, 3),
            {k: getattr(tol, k) for k in ("EPS", "CONVEX_TURN_ULPS", "CLIP_MEET_ULPS",
                                          "AREA_STRICT_TURN", "AREA_HULL_RTOL")}
            | {"NORMAL_FLOOR": NORMAL_FLOOR})
        if r[0] == 1:
            return None
        if r[0] == 0:
            _, nQ, q0, RQ, V, counts, NK, group, _, lo, hi, extent = r
            return HiddenSetup(nQ, q0, RQ, [V[k, :c] for k, c in enumerate(counts)],
                               np.asarray(Qc, dtype=float), np.zeros((0, 3, 2)),
                               np.zeros(0, dtype=np.int64), V, counts, NK, group, lo, hi,
                               extent)
    nQ, q0, RQ, Q2 = plane_frame(Qc)
    clipped = [clip_front(np.asarray(K), nQ, q0) for K in blockers]
    kept = [k for k, K in enumerate(clipped) if K is not None]
    Kc = [clipped[k] for k in kept]
    if not Kc:
        return None
    # the pyramid's base: Qc itself where it is strictly convex (the images then lie in
    # it), else a rectangle around it (the pieces then cut by Qc's convex parts)
    sliver_area = 0.0
    if _strictly_convex(Q2):
        corners, parts = np.asarray(Qc, dtype=float), np.zeros((0, 3, 2))
        part_counts = np.zeros(0, dtype=np.int64)
    else:
        lo, hi = Q2.min(axis=0), Q2.max(axis=0)
        pad = tol.AREA_HIDDEN_PAD * float((hi - lo).max())
        lo, hi = lo - pad, hi + pad
        corners = q0 + np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]],
                                 [lo[0], hi[1]]]) @ RQ[:2]
        # (a part a clip left within rounding of a segment, as where Q's edge lies in
        # P's plane: its sides' half-planes may keep the whole base, so it is left out
        # and its area counted instead)
        Qparts = []
        for Qp in convex_pieces(np.asarray(Qc, float), nQ):
            F = (Qp - q0) @ RQ.T
            e = np.roll(F, -1, axis=0) - F
            # its signed area in the frame against its longest side's square
            if area_vector(F)[2] > (tol.CONVEX_TURN_ULPS * tol.EPS
                                    * float((e * e).sum(axis=1).max())):
                Qparts.append(F)
            else:
                sliver_area += polygon_area(Qp)
        parts, part_counts = padded(Qparts)
        parts = parts[:, :, :2]
    # the blockers' convex pieces: a convex one (all tested at once) is its own piece,
    # with its own unit normal
    normals = [unit_normal(K) for K in Kc]
    convex = convex_rings(np.concatenate(Kc), np.cumsum([0] + [len(K) for K in Kc]),
                          np.array(normals))
    pieces = [[K] if ok else convex_pieces(K, n) for K, n, ok in zip(Kc, normals, convex)]
    owner = np.repeat(kept, [len(p) for p in pieces])
    NK = np.array([n if ok else unit_normal(Kp)
                   for p, n, ok in zip(pieces, normals, convex) for Kp in p])
    pieces = [Kp for p in pieces for Kp in p]
    V, counts = padded(pieces)
    group = np.full(len(pieces), -1, dtype=np.int64)
    if solid is not None:
        # outward: the inner point behind the plane
        solid, inner = np.asarray(solid), np.asarray(inner, dtype=float)
        # (no inner point: the solid's members are not all blockers)
        group = np.where(np.isnan(inner[owner]).any(axis=1), -1, solid[owner]).astype(np.int64)
        mine = group >= 0
        depth = np.einsum("kx,kx->k", inner[owner[mine]] - V[mine, 0], NK[mine])
        NK[mine] *= np.where(depth > 0, -1.0, 1.0)[:, None]
        size = float(np.ptp(np.vstack(Kc), axis=0).max())
        unsure = np.unique(group[mine][np.abs(depth) <= tol.AREA_HULL_RTOL * size])
        group[np.isin(group, unsure)] = -1
        # labels 0, 1, ... (the compiled call keeps a flag per label at every point)
        live = group >= 0
        group[live] = np.unique(group[live], return_inverse=True)[1]
    allv = np.vstack(Kc + [Qc])
    extent = float(np.ptp(Q2, axis=0).max())          # the pieces lie within Qc (or its box)
    return HiddenSetup(nQ, q0, RQ, Kc, corners, parts, part_counts, V, counts, NK, group,
                       allv.min(axis=0), allv.max(axis=0), extent, sliver_area)


def hidden_values(X, nP, Qc, blockers, st=None, atol=0.0, setup=None, shortcuts=True,
                  weights=None, bound_atol=None):
    """``F(x -> Qc) - F_occ(x -> Qc)`` for each point x of X (normal nP): the point form
    factor of the part of Qc that the blockers hide from x, and its error estimate.

    Built in Qc's plane (compiled, :mod:`exactff.area._hidden`): each blocker, clipped
    to the front of that plane, cut into convex pieces and clipped to the pyramid from x
    over Qc where Qc is strictly convex (else over a rectangle around it), is projected
    from x onto the plane (a projective map: its image stays convex, within the
    pyramid's base); each image (the largest first, until they cover the base) less the
    images before it is added as disjoint convex pieces by half-plane splits alone,
    along the lines the edges lie on (traced from the
    planes through x, not from the rounded vertices), which over a rectangle are then
    cut by Qc's convex parts; the pieces are integrated by the sector sums (Eq. 3's
    kernel) from x. A point on Qc's plane sees nothing of it (0), nor does a blocker
    whose plane passes through x (seen edge-on).

    The estimate adds to the sector sums' rounding the effect of moving the pieces'
    boundaries by the splits' rounding (a few units of the largest coordinate per
    line) and by the clipped vertices' own rounding as the projection magnifies it
    (``moved``; the 3-D work is in doubles, and again in long double at a point where
    that is more than ``AREA_IMAGE_PRECISE_RTOL`` of Qc's size and moves more of the
    value than ``AREA_IMAGE_PRECISE_SHARE`` of ``atol``), through the kernel's
    largest value over the region's bounding box, ``h / (pi r^3)``. Where a point's
    images do not stay finite, or that rounding can move them by more than
    ``AREA_IMAGE_RTOL`` of Qc's size (a crossing or a blocker's vertex at the point, to
    rounding) and more of the value than ``atol`` (the absolute error allowed per point:
    the caller's share of its own ``atol``), the engine computes that point's value
    (:func:`hidden_values_by_engine`), counted in ``st.engine_fallbacks`` (and the
    points in ``st.engine_fallback_points``; ``st``: an
    :class:`~exactff.area.row.AreaStats`, optional). With ``shortcuts``, ``weights``
    (each point's weight in the caller's rules, per unit area of the emitter) and
    ``bound_atol`` (a list of one number: what the caller's pair has left of its
    absolute tolerance for this), such points whose bound ``0 <= hidden <= F(x -> Qc)``
    costs the weighted sum at most that take it instead (``U / 2`` within ``U / 2`` and
    U's own estimate; the cost is taken off ``bound_atol[0]``; counted in
    ``st.bounded_points``): thin cells along a blocker that touches the emitter hold
    such points by the hundred, at a thousandth of the engine's cost each.
    ``setup``: :func:`hidden_setup` of Qc and the blockers, where the caller has it.

    Returns
    -------
    (ndarray of shape (len(X),), ndarray of shape (len(X),))

    Examples
    --------
    A plate halfway between the centre of the floor and a ceiling square twice its size
    hides all of the ceiling from there (its shadow is the whole square), and a quarter
    of the way across, less:

    >>> from exactff.area.points import point_values
    >>> sq = lambda z: np.array([[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]], float)
    >>> Q, plate = sq(2)[::-1], 0.5 * sq(2) + [0.25, 0.25, 0]
    >>> X, nP = np.array([[0.5, 0.5, 0], [0.25, 0.5, 0]]), np.array([0, 0, 1.0])
    >>> H, EH = hidden_values(X, nP, Q, [plate])
    >>> U, EU = (v[0] for v in point_values(X, nP, [Q]))
    >>> bool(abs(H[0] - U[0]) <= EH[0] + EU[0]), bool(0 < H[1] < U[1])
    (True, True)
    """
    nX = len(X)
    zero = np.zeros(nX)
    setup = hidden_setup(Qc, blockers) if setup is None else setup
    if setup is None:
        return zero, zero
    if nX > tol.AREA_POINTS_PER_CALL:
        # in chunks: a point's pieces hold tens of vertices, and the sector sums'
        # temporaries a few dozen bytes each of them
        parts_ = [hidden_values(X[k:k + tol.AREA_POINTS_PER_CALL], nP, Qc, blockers, st,
                                atol, setup, shortcuts, None if weights is None else
                                weights[k:k + tol.AREA_POINTS_PER_CALL], bound_atol)
                  for k in range(0, nX, tol.AREA_POINTS_PER_CALL)]
        return np.concatenate([h for h, _ in parts_]), np.concatenate([e for _, e in parts_])
    nQ, q0, RQ, Kc, corners, parts, part_counts, V, counts, NK, group, lo, hi, extent, _ = setup
    # the scene's size here: the box of the blockers, Qc and the points
    size = float((np.maximum(hi, X.max(axis=0)) - np.minimum(lo, X.min(axis=0))).max())
    # the pieces, and their point form factors by the sector sums (Eq. 3's kernel) with
    # their own rounding (C1, C2 calibrated for the unit roundoff 2**-53), compiled
    (_, _, _, lost, reach, length, box, moved, dropped, H, rnd, back) = hidden_pieces(
        X, corners, q0, nQ, RQ[:2], V, counts, NK, group, tol.AREA_BACK_FACE_RTOL * size,
        tol.AREA_EDGE_ON_RTOL * size,
        tol.AREA_IMAGE_ULPS, tol.AREA_SLIVER_ULPS, tol.AREA_MAX_PIECES,
        tol.AREA_IMAGE_PRECISE_RTOL, extent, parts, part_counts, receiver_frame(nP),
        tol.C1, tol.C2, tol.EPS, False, precise_atol=tol.AREA_IMAGE_PRECISE_SHARE * atol)
    if st is not None and back:
        st.back_faces += int(back)
    # the clipping's rounding: each piece's boundary within delta of the exact one (a
    # few units of the largest coordinate for each clipping line a vertex may descend
    # from), through the kernel's bound h / (pi r^3) over the region's bounding box (r >=
    # the box's distance from x; the box holds the slivers dropped too, so this holds
    # for points that kept no piece at all)
    lines = int(counts.sum()) + len(corners) + int(part_counts.sum()) + 1
    delta = tol.AREA_BOOLEAN_ULPS * lines * tol.EPS * reach
    h = (X - q0) @ nQ
    foot = (X - q0) @ RQ[:2].T
    dx = np.maximum(0.0, np.maximum(box[:, 0] - foot[:, 0], foot[:, 0] - box[:, 2]))
    dy = np.maximum(0.0, np.maximum(box[:, 1] - foot[:, 1], foot[:, 1] - box[:, 3]))
    r = np.sqrt(h ** 2 + dx * dx + dy * dy)
    bound = np.divide(h, np.pi * r ** 3, out=np.zeros_like(r), where=(r > 0) & (h > 0))
    geo = moved * length * bound
    # and the slivers dropped (thinner than rounding), at the kernel's bound
    EH = rnd + (delta * length + dropped) * bound + geo
    # an image the vertices' rounding can move by more than AREA_IMAGE_RTOL of Qc's size
    # (a crossing near x, magnified by the projection), unless what that moves of the
    # value is within the caller's atol, is not to be trusted: that point goes to the
    # engine, as one through infinity
    lost |= ((moved > tol.AREA_IMAGE_RTOL * np.maximum(reach, extent))
             & ((length == 0) | (geo > atol)))
    if lost.any() and shortcuts and weights is not None and bound_atol is not None:
        # the hidden part lies between 0 and the unoccluded value: where the weights
        # make that cheap enough, it is the value
        U, EU = (v[0] for v in point_values(X[lost], nP, [Qc]))
        cost = float((weights[lost] * (0.5 * U + EU)).sum())
        if cost <= bound_atol[0]:
            bound_atol[0] -= cost
            H[lost], EH[lost] = 0.5 * U, 0.5 * U + EU
            if st is not None:
                st.bounded_points += int(lost.sum())
            lost[:] = False
    if lost.any():
        # an image through infinity or not to be trusted: the engine
        if st is not None:
            st.engine_fallbacks += 1
            st.engine_fallback_points += int(lost.sum())
        H[lost], EH[lost] = hidden_values_by_engine(X[lost], nP, Qc, Kc)
    return nonnegative(H, EH, "hidden part"), EH


def _strictly_convex(Q2):
    """True where the 2-D polygon Q2 (counter-clockwise) turns left at every vertex by
    more than ``AREA_STRICT_TURN`` radians (no three vertices nearly on a line)."""
    e = np.roll(Q2, -1, axis=0) - Q2
    f = np.roll(e, -1, axis=0)
    turn = e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]
    return bool(np.all(turn > tol.AREA_STRICT_TURN * np.linalg.norm(e, axis=1)
                       * np.linalg.norm(f, axis=1)))


def hidden_values_by_engine(X, nP, Qc, blockers):
    """:func:`hidden_values` by the engine instead (exact occluded point values on the
    sub-scene of Qc and the blockers, subtracted from the unoccluded ones): about a
    thousand times slower, used where a point's images cannot be trusted. A blocker's
    part of no area (a clip's sliver of rounding) hides nothing and is left out; Qc is
    always kept (a degenerate Qc raises :class:`~exactff.SceneError`), so column 0 is
    Qc's."""
    validate_polygon(Qc)
    sub = build_scene([Qc] + list(blockers), degenerate="drop")
    exact = Exact()
    FE = [exact.point_form_factors(sub, x, nP, error=True) for x in np.atleast_2d(X)]
    F = np.array([f for f, _ in FE])
    E = np.array([e for _, e in FE])
    U, EU = (v[0] for v in point_values(X, nP, [Qc]))
    est = EU + E[:, 0]
    return nonnegative(U - F[:, 0], est, "hidden part"), est
