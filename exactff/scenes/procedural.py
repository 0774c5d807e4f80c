"""Procedural scenes of shared/scenes/README.md: the office and the cloister.

Faces are axis-aligned rectangles. Where a face rests on or against another (same plane,
opposite facing, one inside the other), the smaller is omitted and becomes a hole of the
larger, whose grid then includes the hole's edges and drops the cells inside it: no
element is hidden or overlapped, and the surfaces stay closed. Each face is meshed into
``ceil(Lu / h) x ceil(Lv / h)`` quads (plus the lines of its holes and regions); the
global ``h`` is bisected until the number of quads is within 1 % of the target.
"""

import math

import numpy as np

from ..scene import Scene

__all__ = ["office", "office_solids", "OFFICE_REFLECTANCE", "cloister", "ROOM_GROUPS", "vaulted_hall"]

#: reflectances of the office's groups: walls, floor and ceiling from the spec; the
#: others are not specified there and are chosen here
OFFICE_REFLECTANCE = {"wall": 0.8, "floor": 0.3, "ceiling": 0.85, "door": 0.4,
                      "window": 0.1, "light": 0.8, "desk": 0.5, "partition": 0.6,
                      "shelf": 0.5}


class _Face:
    """An axis-aligned rectangle: plane ``x[axis] = c``, facing ``sign`` along the axis,
    spanning ``lo..hi`` in the other two axes (in cyclic order axis+1, axis+2)."""

    def __init__(self, axis, c, sign, lo, hi, group):
        self.axis, self.c, self.sign = axis, float(c), sign
        self.lo = np.array(lo, dtype=float)
        self.hi = np.array(hi, dtype=float)
        self.group = group
        self.holes = []
        self.regions = []  # (lo, hi, group)

    def contains(self, other):
        return bool(np.all(self.lo <= other.lo) and np.all(other.hi <= self.hi))

    def overlaps(self, other):
        return bool(np.all(np.maximum(self.lo, other.lo) < np.minimum(self.hi, other.hi)))


def _uv_axes(axis):
    return (axis + 1) % 3, (axis + 2) % 3


def _box(lo, hi, group, facing="out"):
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    faces = []
    for axis in range(3):
        u, v = _uv_axes(axis)
        for c, outward in ((lo[axis], -1), (hi[axis], +1)):
            sign = outward if facing == "out" else -outward
            faces.append(_Face(axis, c, sign, (lo[u], lo[v]), (hi[u], hi[v]), group))
    return faces


def _resolve_contacts(faces):
    """Omit faces lying against larger opposite-facing faces; make them holes there."""
    keep = [True] * len(faces)
    by_plane = {}
    for i, f in enumerate(faces):
        by_plane.setdefault((f.axis, f.c), []).append(i)
    for idx in by_plane.values():
        for a in idx:
            for b in idx:
                fa, fb = faces[a], faces[b]
                if a >= b or fa.sign == fb.sign or not fa.overlaps(fb):
                    continue
                if fb.contains(fa):
                    small, big, s = fa, fb, a
                elif fa.contains(fb):
                    small, big, s = fb, fa, b
                else:
                    raise ValueError("partial contact between faces of groups "
                                     f"{fa.group!r} and {fb.group!r}")
                keep[s] = False
                big.holes.append((small.lo, small.hi))
    return [f for f, k in zip(faces, keep) if k]


def _lines(lo, hi, h, extra):
    """Grid lines of one side: ceil(L / h) equal cells, plus the forced lines (hole and
    region edges); a regular line closer than a quarter cell to a forced one is dropped,
    so that no sliver cells appear."""
    n = max(1, math.ceil((hi - lo) / h - 1e-9))
    regular = np.linspace(lo, hi, n + 1)
    forced = np.array(sorted({x for x in extra if lo < x < hi}))
    if len(forced):
        gap = 0.25 * (hi - lo) / n
        near = np.abs(regular[1:-1, None] - forced[None, :]).min(axis=1) < gap
        regular = np.concatenate([regular[:1], regular[1:-1][~near], regular[-1:]])
    return np.array(sorted(set(regular.tolist()) | set(forced.tolist())))


def _mesh(face, h):
    """Quads of one face (vertices, counter-clockwise seen from the front) and groups."""
    u_ax, v_ax = _uv_axes(face.axis)
    extra_u = [r[0][0] for r in face.holes + face.regions] + \
        [r[1][0] for r in face.holes + face.regions]
    extra_v = [r[0][1] for r in face.holes + face.regions] + \
        [r[1][1] for r in face.holes + face.regions]
    us = _lines(face.lo[0], face.hi[0], h, extra_u)
    vs = _lines(face.lo[1], face.hi[1], h, extra_v)
    quads, groups = [], []
    for i in range(len(us) - 1):
        for j in range(len(vs) - 1):
            cu, cv = 0.5 * (us[i] + us[i + 1]), 0.5 * (vs[j] + vs[j + 1])
            if any(lo[0] < cu < hi[0] and lo[1] < cv < hi[1] for lo, hi in face.holes):
                continue
            group = face.group
            for lo, hi, g in face.regions:
                if lo[0] < cu < hi[0] and lo[1] < cv < hi[1]:
                    group = g
            corners = [(us[i], vs[j]), (us[i + 1], vs[j]), (us[i + 1], vs[j + 1]),
                       (us[i], vs[j + 1])]
            if face.sign < 0:
                corners = corners[::-1]
            q = np.empty((4, 3))
            q[:, face.axis] = face.c
            q[:, u_ax] = [c[0] for c in corners]
            q[:, v_ax] = [c[1] for c in corners]
            quads.append(q)
            groups.append(group)
    return quads, groups


def _count(face, h):
    u_ax, v_ax = _uv_axes(face.axis)
    rs = face.holes + [(lo, hi) for lo, hi, _ in face.regions]
    us = _lines(face.lo[0], face.hi[0], h, [r[0][0] for r in rs] + [r[1][0] for r in rs])
    vs = _lines(face.lo[1], face.hi[1], h, [r[0][1] for r in rs] + [r[1][1] for r in rs])
    cu = 0.5 * (us[1:] + us[:-1])
    cv = 0.5 * (vs[1:] + vs[:-1])
    inside = np.zeros((len(cu), len(cv)), dtype=bool)
    for lo, hi in face.holes:
        inside |= ((cu > lo[0]) & (cu < hi[0]))[:, None] & ((cv > lo[1]) & (cv < hi[1]))[None, :]
    return int(inside.size - inside.sum())


def _fit_element_size(count, target):
    """The global element size ``h`` whose element count ``count(h)`` is closest to the
    target: bisection, then (the count being a staircase in h) a scan around the best."""
    lo_h, hi_h = 1e-3, 10.0
    best = None
    for _ in range(60):
        h = math.sqrt(lo_h * hi_h)
        n = count(h)
        if best is None or abs(n - target) < abs(best[1] - target):
            best = (h, n)
        if abs(n - target) <= 0.01 * target:
            return h
        lo_h, hi_h = (h, hi_h) if n > target else (lo_h, h)
    for h in np.geomspace(best[0] / 1.15, best[0] * 1.15, 120):
        n = count(h)
        if abs(n - target) < abs(best[1] - target):
            best = (h, n)
        if abs(n - target) <= 0.01 * target:
            break
    return best[0]


def _mesh_to_target(faces, target, extra=None):
    """Mesh axis-aligned faces with the element size that best meets the target
    (``extra``: the count of all elements, when more than these faces are meshed)."""
    h = _fit_element_size(extra or (lambda h: sum(_count(f, h) for f in faces)), target)
    quads, groups = [], []
    for f in faces:
        q, g = _mesh(f, h)
        quads += q
        groups += g
    return quads, groups, h


def office_solids():
    """The office's furniture as ``(lo, hi, group)`` boxes (x, y, z; y up)."""
    solids = []
    for z0 in (1.0, 4.0):
        for x0 in (1.0, 3.2, 5.4):
            x1, z1 = x0 + 1.6, z0 + 0.8
            solids.append(((x0, 0.0, z0), (x0 + 0.03, 0.72, z1), "desk"))
            solids.append(((x1 - 0.03, 0.0, z0), (x1, 0.72, z1), "desk"))
            solids.append(((x0, 0.72, z0), (x1, 0.75, z1), "desk"))
    for x0 in (1.0, 3.1, 5.2):
        solids.append(((x0, 0.0, 2.975), (x0 + 1.8, 1.5, 3.025), "partition"))
    for x0 in (0.5, 5.0):
        x1 = x0 + 2.0
        solids.append(((x0, 0.0, 5.6), (x0 + 0.02, 2.0, 6.0), "shelf"))
        solids.append(((x1 - 0.02, 0.0, 5.6), (x1, 2.0, 6.0), "shelf"))
        for y0 in (0.0, 0.4, 0.8, 1.2, 1.6, 1.98):
            solids.append(((x0 + 0.02, y0, 5.6), (x1 - 0.02, y0 + 0.02, 6.0), "shelf"))
    return solids


def office(n=4428):
    """The procedural office of ``shared/scenes/README.md`` (metres, y up), ~n quads.

    An 8 (x) x 6 (z) x 2.8 (y) m room with a door (0.9 x 2.1, wall x = 0) and a window
    (2.0 x 1.2, wall z = 0) as regions of their walls; one 1.2 x 0.6 luminaire flush in
    the ceiling's centre (group ``"light"``, facing down); 6 desks (1.6 x 0.8 x 0.75: a
    0.03 top slab on two 0.03 side panels, all closed boxes) in two rows of three; 3
    partitions (1.8 x 1.5 x 0.05) between the rows; 2 bookshelves (2.0 wide x 2.0 high x
    0.4 deep) against the wall z = 6: two side panels, top and bottom panels and 4 shelf
    slabs, open at the front, the wall behind them. Faces that rest on or against others
    are omitted and cut out of the supporting face's grid.

    Parameters
    ----------
    n : int, default 4428
        Target number of quads. The room's surfaces and the furniture get their own
        element sizes (with one size the count is a staircase whose steps near 4,428
        are 1 to 2 % wide); the closest achievable count is taken. The holes and
        regions force at least about 400.

    Returns
    -------
    Scene
        Groups (and materials): ``floor``, ``ceiling``, ``wall``, ``door``, ``window``,
        ``light``, ``desk``, ``partition``, ``shelf``; reflectances in
        :data:`OFFICE_REFLECTANCE`. The room is closed: rows from free space sum to 1.

    Examples
    --------
    >>> s = office(1000)
    >>> abs(len(s) - 1000) <= 10, sorted(set(s.groups))[:3]
    (True, ['ceiling', 'desk', 'door'])
    """
    if not (isinstance(n, (int, np.integer)) and n >= 100):
        raise ValueError(f"n must be an integer of at least 100, got {n!r}")
    X, Y, Z = 8.0, 2.8, 6.0
    faces = _box((0, 0, 0), (X, Y, Z), "wall", facing="in")
    for f in faces:
        if f.axis == 1:
            f.group = "floor" if f.c == 0 else "ceiling"
    # door on the wall x = 0 (its (u, v) = (y, z)); window on z = 0 ((u, v) = (x, y))
    wall_x0 = next(f for f in faces if f.axis == 0 and f.c == 0)
    wall_x0.regions.append(((0.0, 0.5), (2.1, 1.4), "door"))
    wall_z0 = next(f for f in faces if f.axis == 2 and f.c == 0)
    wall_z0.regions.append(((3.0, 0.9), (5.0, 2.1), "window"))
    ceiling = next(f for f in faces if f.axis == 1 and f.c == Y)
    # ceiling (u, v) = (z, x): the light at x 3.4..4.6, z 2.7..3.3
    ceiling.regions.append(((2.7, 3.4), (3.3, 4.6), "light"))
    for lo, hi, group in office_solids():
        faces += _box(lo, hi, group)
    faces = _resolve_contacts(faces)
    quads, groups = _mesh_two_sizes(faces, int(n), lambda f: f.group in ROOM_GROUPS)
    return Scene.from_polygons(quads, groups=groups, materials=groups)


#: the office's room surfaces (meshed with one element size; the furniture with another)
ROOM_GROUPS = ("floor", "ceiling", "wall")


def _mesh_two_sizes(faces, target, is_room):
    """Mesh the room's faces with an element size h and the others with h f: a single
    size makes the count a staircase whose steps near 4,428 are 1 to 2 % wide; the
    second size fills the steps in (f within a factor 1.5 of 1, the closest count to
    the target)."""
    room = [f for f in faces if is_room(f)]
    other = [f for f in faces if not is_room(f)]
    count = lambda fs, h: sum(_count(f, h) for f in fs)
    h0 = _fit_element_size(lambda h: count(faces, h), target)
    best = (abs(count(faces, h0) - target), h0, 1.0)
    good = max(1, 0.002 * target)        # close enough: stop searching
    for h in (h0, *np.geomspace(h0 / 1.05, h0 * 1.05, 7)):
        if best[0] <= good:
            break
        n_room = count(room, h)
        for f in np.geomspace(1 / 1.5, 1.5, 41):
            err = abs(n_room + count(other, h * f) - target)
            if err < best[0]:
                best = (err, h, f)
            if best[0] <= good:
                break
    _, h, f = best
    quads, groups = [], []
    for face in faces:
        q, g = _mesh(face, h if is_room(face) else h * f)
        quads += q
        groups += g
    return quads, groups


# ---------------------------------------------------------------------------------------
# the cloister
# ---------------------------------------------------------------------------------------
def _orient(P, normal):
    """P with its right-hand normal turned towards ``normal``."""
    P = np.asarray(P, dtype=float)
    Q = P - P[0]
    A = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    return P if A @ np.asarray(normal, dtype=float) > 0 else P[::-1].copy()


def _mesh_quad(P, h):
    """Bilinear ``nu x nv`` grid of a planar convex quad (sub-quads stay planar, convex)."""
    P = np.asarray(P, dtype=float)
    nu = max(1, math.ceil(max(np.linalg.norm(P[1] - P[0]), np.linalg.norm(P[2] - P[3])) / h - 1e-9))
    nv = max(1, math.ceil(max(np.linalg.norm(P[3] - P[0]), np.linalg.norm(P[2] - P[1])) / h - 1e-9))
    s = np.linspace(0.0, 1.0, nu + 1)
    t = np.linspace(0.0, 1.0, nv + 1)
    G = ((1 - s)[:, None, None] * (1 - t)[None, :, None] * P[0]
         + s[:, None, None] * (1 - t)[None, :, None] * P[1]
         + s[:, None, None] * t[None, :, None] * P[2]
         + (1 - s)[:, None, None] * t[None, :, None] * P[3])
    out = []
    for i in range(nu):
        for j in range(nv):
            out.append(np.array([G[i, j], G[i + 1, j], G[i + 1, j + 1], G[i, j + 1]]))
    return out


def _quad_count(P, h):
    P = np.asarray(P, dtype=float)
    nu = max(1, math.ceil(max(np.linalg.norm(P[1] - P[0]), np.linalg.norm(P[2] - P[3])) / h - 1e-9))
    nv = max(1, math.ceil(max(np.linalg.norm(P[3] - P[0]), np.linalg.norm(P[2] - P[1])) / h - 1e-9))
    return nu * nv


def _ring_pieces(c, y, a, r, up):
    """The square ``[-a, a]^2`` around ``c`` (x, z) at height y minus the inscribed
    octagon of circumradius r (vertices at 22.5 + 45 k degrees), as 8 convex pieces,
    facing up (``up=True``) or down."""
    ang = np.radians(22.5 + 45.0 * np.arange(8))
    cs, sn = np.cos(ang), np.sin(ang)
    V = np.column_stack([c[0] + r * cs, np.full(8, y), c[1] + r * sn])
    # where the rays through the octagon's vertices leave the square
    k = a / np.maximum(np.abs(cs), np.abs(sn))
    S = np.column_stack([c[0] + k * cs, np.full(8, y), c[1] + k * sn])
    pieces = []
    for i in range(8):
        j = (i + 1) % 8
        poly = [V[i], S[i]]
        mid = np.radians(22.5 + 45.0 * i + 22.5)
        if abs(abs(math.cos(mid)) - abs(math.sin(mid))) < 1e-12:
            # the square's corner lies between the two rays
            poly.append([c[0] + a * np.sign(math.cos(mid)), y, c[1] + a * np.sign(math.sin(mid))])
        poly += [S[j], V[j]]
        pieces.append(_orient(poly, (0, 1 if up else -1, 0)))
    return pieces


def _octagon_facets(c, y0, y1, r):
    ang = np.radians(22.5 + 45.0 * np.arange(9))
    facets = []
    for i in range(8):
        a0 = (c[0] + r * math.cos(ang[i]), c[1] + r * math.sin(ang[i]))
        a1 = (c[0] + r * math.cos(ang[i + 1]), c[1] + r * math.sin(ang[i + 1]))
        out = (math.cos(ang[i] + np.radians(22.5)), 0.0, math.sin(ang[i] + np.radians(22.5)))
        P = [(a0[0], y0, a0[1]), (a1[0], y0, a1[1]), (a1[0], y1, a1[1]), (a0[0], y1, a0[1])]
        facets.append(_orient(P, out))
    return facets


def cloister(n=80884, n_arc=12):
    """The procedural cloister of ``shared/scenes/README.md`` (metres, y up), ~n elements.

    A 20 x 20 m garth ringed by 0.5 m arcade walls (centre lines at +-10.25) and four
    3.5 m walks under flat ceilings at 4.5 m; outer walls at +-14 (inner faces only).
    Each side has 6 bays: piers at the corners and 5 between, octagonal shafts
    (circumradius 0.25, 2.5 tall) on 0.7 x 0.7 x 0.2 bases under 0.7 x 0.7 x 0.2
    capitals (springing at 2.9); semicircular arches of ``n_arc`` segments (span 2.92),
    each with ``n_arc`` soffit rectangles and ``n_arc`` spandrel trapezoids on both wall
    faces up to 4.5. The garth's opening at 4.5 is ONE emitting polygon (group
    ``"light"``, facing down, not meshed). Garth ground, arcade strips and walk floors are
    separate surfaces; bases are cut out of them.

    Parameters
    ----------
    n : int, default 80884
        Target number of elements (the closest count a single global element size
        gives; the arches, piers and rings force at least about 3,000).
    n_arc : int, default 12

    Returns
    -------
    Scene
        Groups: ``garth``, ``walk_floor``, ``walk_ceiling``, ``outer_wall``, ``arcade``
        (walls, spandrels, soffits), ``pier`` (shafts, bases, capitals), ``light``.

    Examples
    --------
    >>> s = cloister(4000)
    >>> abs(len(s) - 4000) < 400, s.groups.count("light")
    (True, 1)
    """
    if not (isinstance(n, (int, np.integer)) and n >= 1000):
        raise ValueError(f"n must be an integer of at least 1000, got {n!r}")
    if not (isinstance(n_arc, (int, np.integer)) and n_arc >= 2):
        raise ValueError(f"n_arc must be an integer of at least 2, got {n_arc!r}")
    G, T, C, O, H = 10.0, 0.5, 10.25, 14.0, 4.5
    spring, half, r_oct = 2.9, 0.35, 0.25
    step = 2 * C / 6
    rect = []      # axis-aligned faces (contacts resolved, holes, grids)
    general = []   # (polygon, group, mesh?) convex polygons in any plane

    def floor(x0, x1, z0, z1, group, y=0.0, up=True):
        # axis 1: (u, v) = (z, x)
        rect.append(_Face(1, y, 1 if up else -1, (z0, x0), (z1, x1), group))

    floor(-G, G, -G, G, "garth")
    for sgn in (-1, 1):
        floor(-G - T, G + T, min(sgn * G, sgn * (G + T)), max(sgn * G, sgn * (G + T)), "arcade")
        floor(min(sgn * G, sgn * (G + T)), max(sgn * G, sgn * (G + T)), -G, G, "arcade")
        floor(-O, O, min(sgn * (G + T), sgn * O), max(sgn * (G + T), sgn * O), "walk_floor")
        floor(min(sgn * (G + T), sgn * O), max(sgn * (G + T), sgn * O), -G - T, G + T,
              "walk_floor")
        floor(-O, O, min(sgn * (G + T), sgn * O), max(sgn * (G + T), sgn * O),
              "walk_ceiling", y=H, up=False)
        floor(min(sgn * (G + T), sgn * O), max(sgn * (G + T), sgn * O), -G - T, G + T,
              "walk_ceiling", y=H, up=False)
        # outer walls, facing in: axis 0 (u, v) = (y, z); axis 2 (u, v) = (x, y)
        rect.append(_Face(0, sgn * O, -sgn, (0.0, -O), (H, O), "outer_wall"))
        rect.append(_Face(2, sgn * O, -sgn, (-O, 0.0), (O, H), "outer_wall"))
    general.append((_orient([(-G, H, -G), (G, H, -G), (G, H, G), (-G, H, G)], (0, -1, 0)),
                    "light", False))
    # piers: the four corners and five between on each side
    centres = {(sx * C, sz * C) for sx in (-1, 1) for sz in (-1, 1)}
    for k in range(1, 6):
        t = -C + k * step
        centres |= {(t, C), (t, -C), (C, t), (-C, t)}
    for cx, cz in sorted(centres):
        base = [f for f in _box((cx - half, 0.0, cz - half), (cx + half, 0.2, cz + half), "pier")
                if not (f.axis == 1)]
        cap = [f for f in _box((cx - half, 2.7, cz - half), (cx + half, spring, cz + half), "pier")
               if not (f.axis == 1 and f.sign < 0)]
        rect.extend(base + cap)
        general += [(P, "pier", True) for P in _octagon_facets((cx, cz), 0.2, 2.7, r_oct)]
        general += [(P, "pier", False) for P in _ring_pieces((cx, cz), 0.2, half, r_oct, True)]
        general += [(P, "pier", False) for P in _ring_pieces((cx, cz), 2.7, half, r_oct, False)]
        # the base stands on the floors: cut its footprint out of each
        for f in rect:
            if f.axis == 1 and f.c == 0.0 and f.sign > 0:
                lo, hi = (cz - half, cx - half), (cz + half, cx + half)
                if np.all(np.maximum(f.lo, lo) < np.minimum(f.hi, hi)):
                    f.holes.append((np.array(lo), np.array(hi)))
    # arcade walls: north/south run along x (with the corner blocks), east/west along z
    ang = np.pi * np.arange(n_arc + 1) / n_arc
    cos_a, sin_a = np.cos(ang), np.sin(ang)

    def side(along, across, corners):
        # along: 0 (x) or 2 (z); across: +-1, the wall's side; coordinates map (t, y, w)
        # with w = distance of the wall face from the centre (G or G + T)
        def P(t, y, w):
            p = [0.0, y, 0.0]
            p[along] = t
            p[2 - along] = across * w
            return p

        out_dir = [0.0, 0.0, 0.0]
        out_dir[2 - along] = across
        ts = [-C + k * step for k in range(7)]
        blocks = range(7) if corners else range(1, 6)
        for k in blocks:
            lo, hi = [0.0, spring, 0.0], [0.0, H, 0.0]
            lo[along], hi[along] = ts[k] - r_oct, ts[k] + r_oct
            w0, w1 = sorted((across * G, across * (G + T)))
            lo[2 - along], hi[2 - along] = w0, w1
            rect.extend(f for f in _box(lo, hi, "arcade") if not (f.axis == 1 and f.sign > 0))
        for k in range(6):
            t0, t1 = ts[k] + r_oct, ts[k + 1] - r_oct
            m, rad = 0.5 * (t0 + t1), 0.5 * (t1 - t0)
            xs = m - rad * cos_a
            ys = spring + rad * sin_a
            xs[0], xs[-1], ys[0], ys[-1] = t0, t1, spring, spring
            for i in range(n_arc):
                a = (xs[i], ys[i])
                b = (xs[i + 1], ys[i + 1])
                centre = np.array(P(m, spring, G + T / 2))
                sof = [P(a[0], a[1], G), P(b[0], b[1], G), P(b[0], b[1], G + T),
                       P(a[0], a[1], G + T)]
                mid = np.mean(np.array(sof), axis=0)
                general.append((_orient(sof, centre - mid), "arcade", True))
                for w, facing in ((G, -1), (G + T, 1)):
                    nrm = np.array(out_dir) * facing
                    sp = [P(a[0], a[1], w), P(b[0], b[1], w), P(b[0], H, w), P(a[0], H, w)]
                    general.append((_orient(sp, nrm), "arcade", True))
            # the bay's end faces against the pier blocks (removed by contact)
            for tt, sgn in ((t0, -1), (t1, 1)):
                lo = [0.0, spring, 0.0]
                hi = [0.0, H, 0.0]
                w0, w1 = sorted((across * G, across * (G + T)))
                lo[2 - along], hi[2 - along] = w0, w1
                u, v = _uv_axes(along)
                f = _Face(along, tt, sgn, (lo[u], lo[v]), (hi[u], hi[v]), "arcade")
                rect.append(f)

    for across in (-1, 1):
        side(0, across, True)
        side(2, across, False)
    rect = _resolve_contacts(rect)

    def count(h):
        return (sum(_count(f, h) for f in rect)
                + sum(_quad_count(P, h) if m else 1 for P, _, m in general))

    quads, groups, h = _mesh_to_target(rect, n, extra=count)
    for P, g, m in general:
        parts = _mesh_quad(P, h) if m else [P]
        quads += parts
        groups += [g] * len(parts)
    return Scene.from_polygons(quads, groups=groups, materials=groups)


# ---------------------------------------------------------------------------------------
# the vaulted hall
# ---------------------------------------------------------------------------------------
def vaulted_hall(bays=12, segments=128, column_sides=32, *, span=8.0, bay=4.0, height=5.0):
    """A closed hall under a tessellated barrel vault on two rows of round columns
    (metres, z up): curved architecture as many long thin triangles.

    The hall runs along x over ``bays`` bays of ``bay`` metres, ``span`` wide
    (``abs(y) <= span / 2``), its side walls ``height`` tall under a semicircular barrel vault
    (radius span / 2, axis at z = height) of ``segments`` strips per bay, each strip two
    triangles (``bay`` long, about ``pi span / (2 segments)`` wide). The end walls are one
    polygon each (a rectangle under a half disc: ``segments + 3`` vertices on the vault's
    own). Columns (radius 0.25, 0.6 from the walls, one at each bay line) rise from the
    floor to the springing, each side of ``column_sides`` facets split into two
    triangles and a top cap of ``column_sides`` vertices. The floor and the side walls
    are one quad per bay. Every surface faces into the hall, every column out; the
    columns stand open-ended on the floor, which closes them: a row from any surface
    sums to 1.

    Parameters
    ----------
    bays, segments, column_sides : int
    span, bay, height : float

    Returns
    -------
    Scene
        Groups: ``floor``, ``wall``, ``vault``, ``end_wall``, ``column``.

    Examples
    --------
    >>> s = vaulted_hall(2, 8, 6)
    >>> len(s), s.groups.count("vault")
    (118, 32)
    """
    for name, value, least in (("bays", bays, 1), ("segments", segments, 2),
                               ("column_sides", column_sides, 3)):
        if not (isinstance(value, (int, np.integer)) and value >= least):
            raise ValueError(f"{name} must be an integer of at least {least}, got {value!r}")
    for name, value in (("span", span), ("bay", bay), ("height", height)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    if span < 2.0:
        raise ValueError(f"span must be at least 2 (columns stand 0.6 from the walls), got {span!r}")
    R, L = span / 2, bays * bay
    xs = bay * np.arange(bays + 1)
    theta = np.pi * np.arange(segments + 1) / segments
    arc = np.column_stack([R * np.cos(theta), height + R * np.sin(theta)])   # (y, z)
    polys, groups = [], []

    def add(P, normal, group):
        polys.append(_orient(P, normal))
        groups.append(group)

    for x0, x1 in zip(xs[:-1], xs[1:]):
        add([[x0, -R, 0], [x1, -R, 0], [x1, R, 0], [x0, R, 0]], [0, 0, 1], "floor")
        for s in (-1, 1):
            add([[x0, s * R, 0], [x1, s * R, 0], [x1, s * R, height], [x0, s * R, height]],
                [0, -s, 0], "wall")
        for (y0, z0), (y1, z1) in zip(arc[:-1], arc[1:]):
            inward = [0, -(y0 + y1) / 2, height - (z0 + z1) / 2]
            add([[x0, y0, z0], [x1, y0, z0], [x1, y1, z1]], inward, "vault")
            add([[x0, y0, z0], [x1, y1, z1], [x0, y1, z1]], inward, "vault")
    for x, facing in ((0.0, 1), (L, -1)):
        end = [[x, -R, 0], [x, R, 0]] + [[x, y, z] for y, z in arc]
        add(end, [facing, 0, 0], "end_wall")
    r = 0.25
    phi = 2 * np.pi * np.arange(column_sides + 1) / column_sides
    ring = np.column_stack([r * np.cos(phi), r * np.sin(phi)])
    for x in xs:
        for yc in (-(R - 0.6), R - 0.6):
            # a column at the end walls stands 0.6 inside the hall too
            xc = min(max(x, 0.6), L - 0.6)
            for (a, b), (c, d) in zip(ring[:-1], ring[1:]):
                out = [(a + c) / 2, (b + d) / 2, 0]
                p0, p1 = [xc + a, yc + b], [xc + c, yc + d]
                add([[*p0, 0], [*p1, 0], [*p1, height]], out, "column")
                add([[*p0, 0], [*p1, height], [*p0, height]], out, "column")
            add([[xc + a, yc + b, height] for a, b in ring[:-1]], [0, 0, 1], "column")
    return Scene.from_polygons(polys, groups=groups, materials=groups)
