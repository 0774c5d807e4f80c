"""Open scenes: the uncovered part of a row, split at the horizontal plane through the
receiving point into sky (above it) and ground (below it).

Any row that sums to 1 over its whole domain when nothing is missing (a hemisphere row
of :func:`exactff.form_factors`, a spherical row: visible solid angle over 4 pi) has a
closed-form share of that domain above the horizontal plane through the point (the
*sky share*): ``(1 + n . up) / 2`` for the cosine-weighted hemisphere around ``n``,
``1 / 2`` for the sphere. The uncovered sky is that share minus the row's values of the
polygons' parts above the plane; the ground likewise. The parts come from the scene cut
once along the plane (:func:`horizontal_split`, cached per scene and height), its row
computed by any method (:func:`remainder_row` takes the row as a callable), and the
parts' values summed back per polygon.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from . import _tolerances as tol
from .checks import as_normal, as_point
from .errors import NumericalError, SceneError
from .halfspace import split_polygon
from .predicates import gamma
from .prepared import prepared
from .scene import Scene, as_scene, validate_polygon
from .visibility import convex_pieces

__all__ = ["HorizontalSplit", "horizontal_split", "remainder_row", "hemisphere_sky_share",
           "DEFAULT_UP"]

#: The default up direction (+z).
DEFAULT_UP = (0.0, 0.0, 1.0)

_LOCK = threading.Lock()


@dataclass(frozen=True, eq=False)
class HorizontalSplit:
    """A scene cut along a horizontal plane: what :func:`horizontal_split` returns
    (and caches). The plane is ``up . x = offset``.

    Attributes
    ----------
    scene : Scene
        The cut scene: every polygon of the original that lies on one side (or in the
        plane) unchanged, every one that straddles it as its parts on either side
        (convex pieces of a non-convex polygon first); M polygons.
    owner : ndarray of shape (M,)
        The original polygon of each.
    side : ndarray of shape (M,)
        +1 above the plane (no vertex below it), -1 below (no vertex above), 0 in it.
    up : ndarray of shape (3,)
        The unit up direction.
    offset : float
        ``up . x`` on the plane (``float(up . point)``).
    cuts : dict
        For the bound of the split's rounding (per original polygon touched by the
        plane): ``owner`` (P,), ``a`` and ``b`` (P, 3) the farthest pair of its cut
        points, ``length`` (edge length), ``gap`` (``|s_a - s_b|`` of the cut edge's
        heights), ``err`` (their heights' rounding bound, without the point's own),
        ``round`` (the interpolation's rounding), each (C,) per cut point with
        ``point_owner`` (C,); ``dropped`` a list of ``(owner, area, vertices)`` for the
        parts too thin to be polygons (left with the rest of their polygon).
    """

    scene: Scene
    owner: np.ndarray
    side: np.ndarray
    up: np.ndarray
    offset: float
    cuts: dict


def _unit_up(up):
    return as_normal(DEFAULT_UP if up is None else up, "up").reshape(3)


def _heights(V, up, offset):
    """Signed heights ``up . x - offset`` of points and a bound on their rounding."""
    s = V @ up - offset
    e = gamma(4) * (np.abs(V) @ np.abs(up) + abs(offset))
    return s, e


def _split(scene, up, offset):
    """Build the :class:`HorizontalSplit` of ``scene`` at ``up . x = offset``."""
    s_all, e_all = _heights(scene.vertices, up, offset)
    off = scene.offsets
    lo = np.minimum.reduceat(s_all - e_all, off[:-1])
    hi = np.maximum.reduceat(s_all + e_all, off[:-1])
    smin = np.minimum.reduceat(s_all, off[:-1])
    smax = np.maximum.reduceat(s_all, off[:-1])
    touched = (lo <= 0) & (hi >= 0)           # the plane may pass through it
    polys, owner, side = [], [], []
    c_owner, c_len, c_gap, c_err, c_round, pairs, dropped = [], [], [], [], [], {}, []

    def side_of(smn, smx):
        return 0 if (smn == 0 and smx == 0) else (1 if smn >= 0 else -1)

    for j in range(len(scene)):
        P = scene.polygons[j]
        if not touched[j] or (smin[j] == 0 and smax[j] == 0):
            polys.append(P)
            owner.append(j)
            side.append(side_of(smin[j], smax[j]))
            continue
        pieces = convex_pieces(P, scene.normals[j]) if (smin[j] < 0 < smax[j]) else [P]
        cut_pts = []
        for Q in pieces:
            s, e = _heights(Q, up, offset)
            k = len(Q)
            # cut points, each with what bounds its rounding
            for i in range(k):
                a, b = i, (i + 1) % k
                possible = not ((s[a] - e[a] > 0 and s[b] - e[b] > 0) or
                                (s[a] + e[a] < 0 and s[b] + e[b] < 0))
                if not possible:
                    continue
                if s[a] * s[b] < 0:
                    f, g = (a, b) if s[a] > 0 else (b, a)
                    X = Q[f] + (s[f] / (s[f] - s[g])) * (Q[g] - Q[f])
                    near = 0.0
                else:
                    f = a if abs(s[a]) <= abs(s[b]) else b
                    X, near = Q[f], abs(s[f])
                cut_pts.append(X)
                c_owner.append(j)
                c_len.append(float(np.linalg.norm(Q[b] - Q[a])))
                c_gap.append(float(abs(s[a] - s[b])))
                c_err.append(float(e[a] + e[b] + near))
                c_round.append(gamma(4) * float(np.linalg.norm(Q[a]) + np.linalg.norm(Q[b])))
            if s.min() < 0 < s.max():
                parts = split_polygon(Q, np.sign(s), s)
            else:
                parts = (Q, None) if s.min() >= 0 else (None, Q)
            kept = []
            for part, sd in zip(parts, (1, -1)):
                if part is None:
                    continue
                try:
                    kept.append((validate_polygon(part, j), sd))
                except SceneError:
                    # too thin to be a polygon: left with the rest (its value bounded)
                    n = np.cross(part - part[0], np.roll(part, -1, axis=0) - part[0]).sum(axis=0)
                    dropped.append((j, 0.5 * float(np.linalg.norm(n)), np.array(part)))
            if not kept:
                kept = [(Q, 1 if s.max() >= -s.min() else -1)]
            elif len(kept) == 1 and len(parts) == 2 and all(p is not None for p in parts):
                kept = [(Q, kept[0][1])]          # the whole piece, on its larger side
            for part, sd in kept:
                polys.append(part if part is P else validate_polygon(part, j))
                owner.append(j)
                side.append(sd)
        if cut_pts:
            C = np.array(cut_pts)
            D = np.linalg.norm(C[:, None] - C[None], axis=-1)
            u, v = np.unravel_index(int(np.argmax(D)), D.shape)
            pairs[j] = (C[u], C[v])
    split = Scene(tuple(polys), names=[scene.names[o] for o in owner],
                  groups=[scene.groups[o] for o in owner],
                  materials=[scene.materials[o] for o in owner], _validated=True)
    js = sorted(pairs)
    cuts = {"owner": np.array(js, dtype=int),
            "a": np.array([pairs[j][0] for j in js]).reshape(-1, 3),
            "b": np.array([pairs[j][1] for j in js]).reshape(-1, 3),
            "point_owner": np.array(c_owner, dtype=int), "length": np.array(c_len),
            "gap": np.array(c_gap), "err": np.array(c_err), "round": np.array(c_round),
            "dropped": dropped}
    return HorizontalSplit(split, np.array(owner, dtype=int), np.array(side, dtype=np.int8),
                           up, float(offset), cuts)


def horizontal_split(scene: Scene, point, up=None) -> HorizontalSplit:
    """The scene cut along the horizontal plane through ``point``, built once per
    scene and height and cached beside the scene.

    Parameters
    ----------
    scene : Scene
    point : array_like of shape (3,)
    up : array_like of shape (3,), optional
        The up direction (normalised; default +z).

    Returns
    -------
    HorizontalSplit
        The plane is ``up . x = float(up . point)``; rows at the same height (a floor
        grid) share one split, and its BSP tree.

    Notes
    -----
    Polygons the plane may pass through, within the rounding of their vertices'
    heights, are cut (a non-convex one into convex pieces first, with its own
    vertices, :func:`exactff.visibility.convex_pieces`) by
    :func:`exactff.halfspace.split_polygon`: both parts share the same crossing
    points, so together they are the polygon. A polygon lying in the plane is not cut
    and counts on neither side (its value from a point in its plane is 0 for the exact
    method: it is seen edge-on). A part too thin to be a valid polygon stays with the
    rest of its polygon, and its value is in the bound of :func:`remainder_row`.
    The cache keeps the latest used heights of each scene, up to
    ``REMAINDER_SPLIT_POLYGONS`` polygons in all.

    Examples
    --------
    A unit box's four walls straddle the plane at half height; floor and ceiling do
    not:

    >>> import exactff as ef
    >>> sp = horizontal_split(ef.scenes.subdivided_box(1), [0.5, 0.5, 0.5])
    >>> len(sp.scene), sp.side.tolist()
    (10, [-1, 1, 1, -1, 1, -1, 1, -1, 1, -1])
    >>> horizontal_split(ef.scenes.subdivided_box(1), [0.2, 0.7, 0.5]) is not sp
    True
    """
    as_scene(scene)
    up = _unit_up(up)
    p = as_point(point).reshape(3)
    offset = float(p @ up)
    key = (tuple(up.tolist()), offset)
    cache = prepared(scene).get("horizontal_splits", lambda s: OrderedDict())
    with _LOCK:
        hit = cache.get(key)
        if hit is not None:
            cache.move_to_end(key)
            return hit
    built = _split(scene, up, offset)
    with _LOCK:
        cache[key] = built
        while len(cache) > 1 and sum(len(v.scene) for v in cache.values()) > \
                tol.REMAINDER_SPLIT_POLYGONS:
            cache.popitem(last=False)
    return built


def hemisphere_sky_share(normal, up=None):
    """The cosine-weighted share of the hemisphere around ``normal`` that lies above
    the horizontal plane, and a bound on its rounding. The share is
    ``(1 + n . up) / 2``.

    Parameters
    ----------
    normal : array_like of shape (3,)
        Receiver normal (normalised here).
    up : array_like of shape (3,), optional
        Default +z.

    Returns
    -------
    (float, float)
        The share, and a bound on its rounding.

    Notes
    -----
    With ``c = n . up``, the directions ``w`` of the hemisphere ``w . n > 0`` weighted
    by ``(w . n) / pi`` have total 1; those with ``w . up > 0`` weigh ``(1 + c) / 2``:
    the sky view factor of a plane tilted by ``acos(c)`` under an unobstructed sky
    (``tests/test_remainder.py`` checks it against an mpmath quadrature).

    Examples
    --------
    >>> hemisphere_sky_share([0, 0, 1])[0], hemisphere_sky_share([1, 0, 0])[0]
    (1.0, 0.5)
    >>> hemisphere_sky_share([0, 1, 0], up=[0, 1, 0])[0]
    1.0
    """
    n = as_normal(normal).reshape(3)
    u = _unit_up(up)
    c = float(n @ u)
    share = min(1.0, max(0.0, 0.5 + 0.5 * c))
    return share, gamma(16)


def _split_bounds(sp, point, F, E):
    """Per original polygon touched by the plane: a bound on the value of the region
    between the computed cut and the exact plane through ``point`` (what the split's
    rounding moves between sky and ground), capped by the polygon's value and bound."""
    cuts = sp.cuts
    n0 = int(sp.owner.max()) + 1 if len(sp.owner) else 0
    out = np.zeros(n0)
    total = np.bincount(sp.owner, weights=F + E, minlength=n0)
    e_off = gamma(3) * float(np.abs(point) @ np.abs(sp.up))     # the plane's own offset
    if len(cuts["point_owner"]):
        err = cuts["err"] + 2 * e_off
        room = cuts["gap"] - err
        with np.errstate(divide="ignore", invalid="ignore"):
            # heights exact (err 0: an edge in the plane, say): the cut is exact
            t = np.where(err == 0, 0.0, np.where(room > 0, err / room, 1.0))
        delta = np.minimum(t, 1.0) * cuts["length"] + cuts["round"]
        dmax = np.zeros(n0)
        np.maximum.at(dmax, cuts["point_owner"], delta)
        j = cuts["owner"]
        A, AB = cuts["a"], cuts["b"] - cuts["a"]
        L = np.linalg.norm(AB, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(L[:, None] > 0, AB / L[:, None], 0.0)
        w = point - A
        foot = np.einsum("ij,ij->i", w, u)            # p's foot on the cut line, from A
        d_perp = np.linalg.norm(w - foot[:, None] * u, axis=1)
        dd = 2 * dmax[j]                               # the cut points' spread, doubled
        D = d_perp - dd
        l1, l2 = -foot - dd, L - foot + dd
        with np.errstate(divide="ignore", invalid="ignore"):
            # a strip of width 2 dd along the cut, no nearer to p than D from its line:
            # F <= (1/pi) int 2 dd / (D^2 + l^2) dl over the strip's length
            b = np.where(D > 0, 2 * dd * (np.arctan(l2 / D) - np.arctan(l1 / D))
                         / (math.pi * D), np.inf)
        out[j] = np.minimum(b, total[j])
    for j, area, Vd in cuts["dropped"]:
        diam = float(np.linalg.norm(Vd.max(axis=0) - Vd.min(axis=0)))
        reach = float(np.linalg.norm(Vd - point, axis=1).min()) - diam
        b = area / (math.pi * reach ** 2) if reach > 0 else math.inf
        out[j] += min(b, total[j])
    return np.minimum(out, total)


def remainder_row(scene: Scene, point, row, *, sky_share, share_bound=0.0, up=None,
                  error=False, slack=None):
    """A row of values with its uncovered remainder, split into sky and ground, from
    any row computation.

    Parameters
    ----------
    scene : Scene
    point : array_like of shape (3,)
        The receiving point; the horizontal plane through it splits sky from ground.
    row : callable
        ``row(split_scene)`` returns the row of ``point`` on a scene (ndarray of shape
        (M,) for its M polygons), or ``(values, bounds)`` with ``error=True``: one
        receiver, by whatever method (a hemisphere row, a spherical row).
    sky_share : float
        The row's total weight above the plane when nothing is missing (the total over
        the whole domain being 1): ``(1 + n . up) / 2`` for a hemisphere row
        (:func:`hemisphere_sky_share`), ``1 / 2`` for a spherical row.
    share_bound : float, default 0
        A bound on the rounding of ``sky_share``.
    up : array_like of shape (3,), optional
        Default +z.
    error : bool, default False
        ``row`` returns bounds too, and so does this function.
    slack : float, optional
        How far below 0 a remainder may come out before it is an error: set to 0 down
        to ``-slack``, :class:`exactff.NumericalError` beyond. Default: the remainder's
        bound with ``error=True``, else ``REMAINDER_SLACK``; ``math.inf`` for a sampled
        method (its rows are only within sampling of the shares).

    Returns
    -------
    tuple
        ``(F, sky, ground)``; with ``error=True`` ``(F, sky, ground, E, E_sky,
        E_ground)``: ``F`` of shape (N,) the row on the original polygons (the sum of
        each one's parts), ``sky`` and ``ground`` floats, and bounds on each.
        ``F.sum() + sky + ground`` is 1 up to rounding (and to the clamping of a
        remainder below 0).

    Notes
    -----
    ``sky = sky_share - sum(parts above)``, ``ground = (1 - sky_share) - sum(parts
    below)``; a polygon lying in the plane counts on neither side. The remainder is
    what no polygon *receives*: with one-sided polygons, directions that meet a
    polygon's back (which occludes but does not receive) count in it too, as in a row
    from inside a solid (``two_sided=True`` makes backs receive). Bounds: the parts'
    own bounds, the rounding of the sums and of the share, and for each polygon the
    plane cuts, the value of the region between its computed cut and the exact plane
    (:func:`horizontal_split`).

    Examples
    --------
    From the floor's centre of a unit box without its ceiling (polygon 1, the face
    at z = 1), the sky is the ceiling's form factor:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> roofless = ef.Scene.from_polygons([P for i, P in enumerate(box.polygons) if i != 1])
    >>> p, n = [0.5, 0.5, 0.0], [0, 0, 1]
    >>> F, sky, ground = remainder_row(roofless, p, lambda s: ef.form_factors(s, p, n),
    ...                                sky_share=1.0)
    >>> round(sky, 10), round(float(ef.form_factors(box, p, n)[1]), 10), ground
    (0.2394564705, 0.2394564705, 0.0)
    """
    as_scene(scene)
    p = as_point(point).reshape(3)
    sp = horizontal_split(scene, p, up)
    got = row(sp.scene)
    Fs, Es = (np.asarray(got[0], float), np.asarray(got[1], float)) if error else \
        (np.asarray(got, float), np.zeros(len(sp.scene)))
    if Fs.shape != (len(sp.scene),):
        raise ValueError(f"row must return an array of shape ({len(sp.scene)},) for the "
                         f"split scene, got {Fs.shape}")
    n = len(scene)
    F = np.bincount(sp.owner, weights=Fs, minlength=n)
    above = math.fsum(Fs[sp.side > 0])
    below = math.fsum(Fs[sp.side < 0])
    sky = sky_share - above
    ground = (1.0 - sky_share) - below
    if error:
        sliver = float(_split_bounds(sp, p, Fs, Es).sum())
        E = np.bincount(sp.owner, weights=Es, minlength=n) + gamma(2) * np.abs(F)
        rounding = share_bound + gamma(len(Fs) + 2)
        E_sky = math.fsum(Es[sp.side > 0]) + sliver + rounding * (1 + abs(above))
        E_ground = math.fsum(Es[sp.side < 0]) + sliver + rounding * (1 + abs(below))
    out = []
    for name, v, b in (("sky", sky, E_sky if error else None),
                       ("ground", ground, E_ground if error else None)):
        limit = slack if slack is not None else (b if error else tol.REMAINDER_SLACK)
        if not math.isfinite(v):
            raise NumericalError(f"{name} remainder came out {v} at point {p.tolist()}")
        if v < -limit:
            raise NumericalError(
                f"{name} remainder {v:.3g} at point {p.tolist()}: the row's parts on that "
                f"side exceed the closed-form share by more than {limit:.3g}")
        out.append(max(v, 0.0))
    if error:
        return F, out[0], out[1], E, E_sky, E_ground
    return F, out[0], out[1]
