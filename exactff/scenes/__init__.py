"""Built-in scenes: the Cornell box (measured data) and procedural test rooms."""

import json
from importlib import resources

import numpy as np

from ..scene import Scene
from .procedural import OFFICE_REFLECTANCE, cloister, office, office_solids, vaulted_hall

__all__ = ["cornell_box", "cornell_box_data", "subdivided_box", "box_polygons",
           "furnished_box", "unit_squares_room", "office", "office_solids",
           "OFFICE_REFLECTANCE", "cloister", "building", "geodesic_sphere",
           "room_with_sphere", "courtyard", "vaulted_hall"]


def cornell_box_data():
    """The Cornell box document (``exactff-scene/1``, millimetres, y up), as a dict.

    Source: "Cornell Box Data", Cornell University Program of Computer Graphics,
    http://www.graphics.cornell.edu/online/box/data.html, with the derived helpers
    described in ``shared/scenes/README.md``.
    """
    text = resources.files(__package__).joinpath("cornell_box.json").read_text("utf-8")
    return json.loads(text)


def cornell_box(*, left_wall="triangles", ceiling="cut", closed=False):
    """The Cornell box as a scene (millimetres, y up; 16 to 22 polygons).

    Parameters
    ----------
    left_wall : {"triangles", "quad"}, default "triangles"
        The official left (red) wall is not planar (one vertex lies 3.2 mm off the
        plane of the other three). ``"triangles"`` splits it along its v0-v2 diagonal
        into two planar triangles with the same boundary; ``"quad"`` keeps the official
        quad and relaxes the planarity check to 2e-3 of the diameter for the whole scene
        (its form factors then belong to the quad's boundary, not to a planar wall).
    ceiling : {"cut", "whole"}, default "cut"
        The light lies in the ceiling plane on top of the ceiling quad. ``"cut"``
        replaces the ceiling with four rectangles tiling the ceiling minus the light;
        ``"whole"`` keeps the official quad (light and ceiling then overlap).
    closed : bool, default False
        The real box is open at z = 0; True adds the wall that closes it, so that every
        row from inside sums to 1.

    Returns
    -------
    Scene
        Names, groups (``room``, ``light``, ``short_block``, ``tall_block``, ``front``)
        and materials from the data.

    Examples
    --------
    >>> len(cornell_box()), len(cornell_box(closed=True))
    (20, 21)
    """
    if left_wall not in ("triangles", "quad"):
        raise ValueError(f"left_wall must be 'triangles' or 'quad', got {left_wall!r}")
    if ceiling not in ("cut", "whole"):
        raise ValueError(f"ceiling must be 'cut' or 'whole', got {ceiling!r}")
    data = cornell_box_data()
    derived = data["derived"]
    polys, names, groups, materials = [], [], [], []

    def add(vertices, name, group, material):
        polys.append(np.array(vertices, dtype=float))
        names.append(name)
        groups.append(group)
        materials.append(material)

    for s in data["surfaces"]:
        if s["name"] == "left_wall" and left_wall == "triangles":
            for k, tri in enumerate(derived["left_wall_triangles"]["polygons"], start=1):
                add(tri, f"left_wall_{k}", s["group"], s["material"])
        elif s["name"] == "ceiling" and ceiling == "cut":
            for k, quad in enumerate(derived["ceiling_around_light"]["polygons"], start=1):
                add(quad, f"ceiling_{k}", s["group"], s["material"])
        else:
            add(s["vertices"], s["name"], s["group"], s["material"])
    if closed:
        for k, quad in enumerate(derived["front_closing_wall"]["polygons"], start=1):
            add(quad, "front_wall" if k == 1 else f"front_wall_{k}", "front", None)
    options = {"planarity_rtol": 2e-3} if left_wall == "quad" else {}
    return Scene.from_polygons(polys, names=names, groups=groups, materials=materials,
                               **options)


def box_polygons(lo, hi, k=1, *, facing="in"):
    """The six faces of an axis-aligned box, each split into ``k x k`` quads.

    Parameters
    ----------
    lo, hi : array_like of shape (3,)
        Opposite corners.
    k : int
        Subdivisions per face edge.
    facing : {"in", "out"}
        ``"in"``: fronts face the inside (a room); ``"out"``: a solid obstacle.

    Returns
    -------
    list of ndarray of shape (4, 3)
        ``6 k^2`` quads, face by face (z = lo, z = hi, y = lo, y = hi, x = lo, x = hi).

    Examples
    --------
    >>> len(box_polygons([0, 0, 0], [1, 2, 3], 2, facing="out"))
    24
    """
    k = int(k)
    if k < 1:
        raise ValueError(f"k must be a positive integer, got {k}")
    if facing not in ("in", "out"):
        raise ValueError(f"facing must be 'in' or 'out', got {facing!r}")
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    if lo.shape != (3,) or hi.shape != (3,) or not np.all(hi > lo):
        raise ValueError(f"need lo < hi componentwise, got lo={lo.tolist()}, hi={hi.tolist()}")
    sx, sy, sz = hi - lo
    u = np.linspace(0.0, 1.0, k + 1)
    polys = []
    # each face: origin, two edge vectors whose cross product points outwards;
    # the quads run along e2 then e1, so their right-hand normals point inwards
    faces = [
        ((0, 0, 0), (0, sy, 0), (sx, 0, 0)),      # z = lo
        ((0, 0, sz), (sx, 0, 0), (0, sy, 0)),     # z = hi
        ((0, 0, 0), (sx, 0, 0), (0, 0, sz)),      # y = lo
        ((0, sy, 0), (0, 0, sz), (sx, 0, 0)),     # y = hi
        ((0, 0, 0), (0, 0, sz), (0, sy, 0)),      # x = lo
        ((sx, 0, 0), (0, sy, 0), (0, 0, sz)),     # x = hi
    ]
    for o, e1, e2 in faces:
        o, e1, e2 = (np.array(v, dtype=float) for v in (o, e1, e2))
        o = o + lo
        for i in range(k):
            for j in range(k):
                a0, a1, b0, b1 = u[i], u[i + 1], u[j], u[j + 1]
                q = np.array([o + a0 * e1 + b0 * e2, o + a0 * e1 + b1 * e2,
                              o + a1 * e1 + b1 * e2, o + a1 * e1 + b0 * e2])
                polys.append(q if facing == "in" else q[::-1].copy())
    return polys


def subdivided_box(k, size=(1.0, 1.0, 1.0)):
    """A closed box whose six faces are each split into ``k x k`` quads, facing inwards.

    Parameters
    ----------
    k : int
        Subdivisions per face edge; the scene has ``6 k^2`` polygons.
    size : tuple of 3 float
        Edge lengths along x, y, z; the box spans ``[0, size]``.

    Examples
    --------
    >>> len(subdivided_box(4))
    96
    """
    return Scene.from_polygons(box_polygons((0, 0, 0), size, k))


def furnished_box(k, boxes, size=(1.0, 1.0, 1.0), box_k=1):
    """A closed room (``subdivided_box(k, size)``) with solid box obstacles inside.

    Parameters
    ----------
    k : int
        Subdivisions per room face edge.
    boxes : sequence of (lo, hi)
        Obstacle corners; obstacles may float, touch or interpenetrate.
    box_k : int
        Subdivisions per obstacle face edge.

    Returns
    -------
    Scene
        Room polygons first (group ``"room"``), then each obstacle's (``"box<i>"``).

    Examples
    --------
    >>> len(furnished_box(2, [((0.2, 0.2, 0.0), (0.5, 0.4, 0.3))]))
    30
    """
    polys = box_polygons((0, 0, 0), size, k)
    groups = ["room"] * len(polys)
    for i, (lo, hi) in enumerate(boxes):
        b = box_polygons(lo, hi, box_k, facing="out")
        polys += b
        groups += [f"box{i}"] * len(b)
    return Scene.from_polygons(polys, groups=groups)


def unit_squares_room(size=(3, 4, 5), boxes=(((0.5, 0.5, 0.5), (1.5, 1.5, 1.5)),
                                            ((1.4, 2.2, 2.8), (2.4, 3.2, 3.8)))):
    """A closed room of whole-number edge lengths cut into unit squares facing in, with
    solid box obstacles inside (their six faces facing out, one polygon each). The
    defaults are the 106-surface box of the area benchmarks (``benchmarks/bench_area.py``,
    ``tests/test_area_curved.py``): a 3 x 4 x 5 room (94 squares) with two unit cubes
    floating inside, at (0.5, 0.5, 0.5)-(1.5, 1.5, 1.5) and (1.4, 2.2, 2.8)-(2.4, 3.2, 3.8).

    Parameters
    ----------
    size : tuple of 3 int
        The room's edge lengths along x, y, z; it spans ``[0, size]``.
    boxes : sequence of (lo, hi)
        The obstacles' opposite corners, inside the room (``lo < hi`` componentwise);
        else ValueError.

    Returns
    -------
    Scene
        The room's squares face by face (the order of :func:`box_polygons`), each face's
        row by row, then each obstacle's faces; no groups.

    Examples
    --------
    >>> len(unit_squares_room())
    106
    >>> len(unit_squares_room((1, 1, 2), []))
    10
    """
    sizes = np.asarray(size, dtype=float)
    if sizes.shape != (3,) or not np.all(sizes >= 1) or not np.all(sizes == np.round(sizes)):
        raise ValueError(f"size must be three whole numbers >= 1, got {size!r}")
    room = []
    for F in box_polygons((0, 0, 0), sizes, 1, facing="in"):
        u, v = F[1] - F[0], F[3] - F[0]
        nu, nv = int(round(np.linalg.norm(u))), int(round(np.linalg.norm(v)))
        for a in range(nu):
            for b in range(nv):
                room.append(np.array([F[0] + (a + i) / nu * u + (b + j) / nv * v
                                      for i, j in ((0, 0), (1, 0), (1, 1), (0, 1))]))
    for k, (lo, hi) in enumerate(boxes):
        lo_k, hi_k = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        if not (np.all(lo_k >= 0) and np.all(hi_k <= sizes)):
            raise ValueError(f"boxes[{k}] must lie inside the room [0, {size!r}], got "
                             f"lo={lo!r}, hi={hi!r}")
        room += box_polygons(lo, hi, 1, facing="out")
    return Scene.from_polygons(room)


def _axis_rect(axis, c, lo, hi, facing):
    """Rectangle in the plane ``x[axis] = c`` spanning ``lo..hi`` in the other two axes
    (in cyclic order axis+1, axis+2), its front facing ``facing`` (+1 or -1) along axis."""
    u, v = (axis + 1) % 3, (axis + 2) % 3
    P = np.zeros((4, 3))
    P[:, axis] = c
    P[:, u] = [lo[0], hi[0], hi[0], lo[0]]
    P[:, v] = [lo[1], lo[1], hi[1], hi[1]]
    # (e_u x e_v) = e_axis: this order faces +axis
    return P if facing > 0 else P[::-1].copy()


def _wall_with_door(span, height, door):
    """Rectangles (lo, hi) in (along, up) tiling a wall of ``span`` x ``height`` minus a
    centred door of ``door = (width, height)`` standing on the floor."""
    a0, a1 = span
    if door is None:
        return [((a0, 0.0), (a1, height))]
    w, h = door
    m = 0.5 * (a0 + a1)
    d0, d1 = m - 0.5 * w, m + 0.5 * w
    return [((a0, 0.0), (d0, height)), ((d1, 0.0), (a1, height)), ((d0, h), (d1, height))]


def building(nx=2, ny=1, *, size=1.0, height=1.0, door=(0.2, 0.7), walls_first="low"):
    """A closed building of ``nx x ny`` square rooms with zero-thickness interior walls.

    Every interior wall is written the way building models write it: two sets of
    coincident rectangles facing opposite ways, one set for each room, around a centred
    door (the rooms connect through the doors). Outer walls, floors and ceilings face the
    inside. Rows from any point inside sum to 1 (each room sees the face of a shared
    wall that faces it; see ``docs/explanation/conventions.md``, coplanar ties).

    Parameters
    ----------
    nx, ny : int
        Rooms along x and y; room (i, j) spans ``[i, i+1] x [j, j+1]`` times ``size``.
    size, height : float
        Room edge and storey height.
    door : (float, float) or None
        Door width and height (centred in every interior wall); None for no doors.
    walls_first : {"low", "high"}
        Of each back-to-back pair, which face comes first in input order: the one facing
        the room with the lower index (``"low"``) or the higher. The results do not
        depend on it.

    Returns
    -------
    Scene
        Groups ``floor``, ``ceiling``, ``outer_wall``, ``inner_wall``; names
        ``"room<i>_<j>_<surface>"`` and, for the faces of interior walls, the room faced.

    Examples
    --------
    >>> b = building(2, 1)
    >>> len(b), b.groups.count("inner_wall")
    (16, 6)
    """
    for name, val in (("nx", nx), ("ny", ny)):
        if not (isinstance(val, (int, np.integer)) and val >= 1):
            raise ValueError(f"{name} must be a positive integer, got {val!r}")
    if not (size > 0 and height > 0):
        raise ValueError(f"size and height must be positive, got {size!r}, {height!r}")
    if door is not None:
        w, h = door
        if not (0 < w < size and 0 < h < height):
            raise ValueError(f"door must fit in a wall (0 < width < size, 0 < height < "
                             f"height), got {door!r}")
    if walls_first not in ("low", "high"):
        raise ValueError(f"walls_first must be 'low' or 'high', got {walls_first!r}")
    polys, names, groups = [], [], []

    def add(P, name, group):
        polys.append(P)
        names.append(name)
        groups.append(group)

    L = size
    for i in range(nx):
        for j in range(ny):
            room = f"room{i}_{j}"
            lo, hi = (i * L, j * L), ((i + 1) * L, (j + 1) * L)
            add(_axis_rect(2, 0.0, lo, hi, +1), f"{room}_floor", "floor")
            add(_axis_rect(2, height, lo, hi, -1), f"{room}_ceiling", "ceiling")
    # walls: planes x = i L (axis 0, spanning (y, z)) and y = j L (axis 1, spanning (z, x))
    for axis, n_planes, n_along in ((0, nx, ny), (1, ny, nx)):
        for k in range(n_planes + 1):
            c = k * L
            for m in range(n_along):
                span = (m * L, (m + 1) * L)
                if axis == 0:
                    rooms = (f"room{k - 1}_{m}", f"room{k}_{m}")
                    to_2d = lambda lo, hi: (lo, hi)                     # (y, z)
                else:
                    rooms = (f"room{m}_{k - 1}", f"room{m}_{k}")
                    to_2d = lambda lo, hi: ((lo[1], lo[0]), (hi[1], hi[0]))  # (z, x)
                if k in (0, n_planes):
                    facing = +1 if k == 0 else -1
                    for (a0, z0), (a1, z1) in _wall_with_door(span, height, None):
                        lo2, hi2 = to_2d((a0, z0), (a1, z1))
                        add(_axis_rect(axis, c, lo2, hi2, facing),
                            f"{rooms[1] if k == 0 else rooms[0]}_outer_wall", "outer_wall")
                    continue
                # the two faces of the interior wall: facing -axis (the low room) and +axis
                sides = [(-1, rooms[0]), (+1, rooms[1])]
                if walls_first == "high":
                    sides.reverse()
                for facing, room in sides:
                    for (a0, z0), (a1, z1) in _wall_with_door(span, height, door):
                        lo2, hi2 = to_2d((a0, z0), (a1, z1))
                        add(_axis_rect(axis, c, lo2, hi2, facing), f"{room}_inner_wall",
                            "inner_wall")
    return Scene.from_polygons(polys, names=names, groups=groups)


def geodesic_sphere(level, centre=(0.0, 0.0, 0.0), radius=1.0, *, facing="out"):
    """Triangles of a geodesic sphere: the icosahedron with every face split ``level``
    times into four (``20 * 4**level`` triangles), vertices on the sphere.

    Parameters
    ----------
    level : int
        Subdivision level, 0 to 7.
    centre : array_like of shape (3,)
    radius : float
    facing : {"out", "in"}
        Fronts facing away from the centre (a solid ball) or towards it.

    Returns
    -------
    list of ndarray of shape (3, 3)

    Examples
    --------
    >>> len(geodesic_sphere(2))
    320
    """
    if not (isinstance(level, (int, np.integer)) and 0 <= level <= 7):
        raise ValueError(f"level must be an integer from 0 to 7, got {level!r}")
    if facing not in ("out", "in"):
        raise ValueError(f"facing must be 'out' or 'in', got {facing!r}")
    t = (1.0 + 5.0 ** 0.5) / 2.0
    V = np.array([(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
                  (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)],
                 dtype=float)
    F = np.array([(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9),
                  (5, 11, 4), (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2),
                  (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
                  (8, 6, 7), (9, 8, 1)])
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(level):
        # midpoints of the edges, shared between the two faces of each edge
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        edges, inv = np.unique(E, axis=0, return_inverse=True)
        M = V[edges[:, 0]] + V[edges[:, 1]]
        mid = len(V) + inv.reshape(3, -1).T          # (faces, 3): ab, bc, ca
        V = np.concatenate([V, M / np.linalg.norm(M, axis=1, keepdims=True)])
        a, b, c = F.T
        ab, bc, ca = mid.T
        F = np.concatenate([np.column_stack(x) for x in
                            ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
    T = V[F] * float(radius) + np.asarray(centre, dtype=float)
    # orient: the right-hand normal of the face must point away from the centre
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    out = np.einsum("ij,ij->i", n, T.mean(axis=1) - np.asarray(centre, dtype=float)) > 0
    flip = out != (facing == "out")
    T[flip] = T[flip][:, ::-1]
    return list(T)


def room_with_sphere(level=4, k=16):
    """A closed unit room of ``k x k`` quads per face with a solid geodesic sphere of
    ``20 * 4**level`` triangles (radius 0.25) floating in its middle: a tessellated
    curved object, whose facets' own planes make a chain of a BSP tree.

    Examples
    --------
    >>> len(room_with_sphere(2, 2))
    344
    """
    polys = box_polygons((0, 0, 0), (1, 1, 1), k)
    ball = geodesic_sphere(level, (0.5, 0.5, 0.5), 0.25)
    return Scene.from_polygons(polys + ball, groups=["room"] * len(polys) + ["sphere"] * len(ball))


def courtyard(width=20.0, depth=14.0, heights=(9.0, 6.0, 9.0, 3.0), *, k=1):
    """An open courtyard (z up): a floor ``[0, width] x [0, depth]`` facing up and four
    walls facing in, of their own heights, open to the sky above.

    Parameters
    ----------
    width, depth : float
        Along x and y.
    heights : 4 floats
        Heights of the walls y = 0 ("south"), x = width ("east"), y = depth ("north")
        and x = 0 ("west").
    k : int, default 1
        The floor as ``k x k`` quads (a floor plan to paint rows on).

    Returns
    -------
    Scene
        Floor quads first (group ``floor``), then the walls (group ``wall``, names
        ``wall_south`` ... ``wall_west``). Rows from the floor do not sum to 1: the rest
        is sky (``form_factors(..., remainder=True)``).

    Examples
    --------
    >>> import exactff as ef
    >>> c = courtyard(k=2)
    >>> len(c), c.names[-4:]
    (8, ('wall_south', 'wall_east', 'wall_north', 'wall_west'))
    >>> F, sky, ground = ef.form_factors(c, [10, 7, 0], [0, 0, 1], remainder=True)
    >>> round(sky, 6), round(float(F.sum()) + sky, 12), ground
    (0.60904, 1.0, 0.0)
    """
    W, D = float(width), float(depth)
    H = [float(h) for h in heights]
    if not (W > 0 and D > 0 and len(H) == 4 and all(h > 0 for h in H)):
        raise ValueError(f"width, depth and the 4 heights must be positive, got "
                         f"{width!r}, {depth!r}, {heights!r}")
    if not (isinstance(k, (int, np.integer)) and k >= 1):
        raise ValueError(f"k must be a positive integer, got {k!r}")
    xs, ys = np.linspace(0.0, W, k + 1), np.linspace(0.0, D, k + 1)
    polys = [np.array([[xs[i], ys[j], 0], [xs[i + 1], ys[j], 0], [xs[i + 1], ys[j + 1], 0],
                       [xs[i], ys[j + 1], 0]], dtype=float)
             for j in range(k) for i in range(k)]
    names = [None] * len(polys)
    s, e, n, w = H
    walls = {   # counter-clockwise seen from inside
        "wall_south": [[0, 0, 0], [0, 0, s], [W, 0, s], [W, 0, 0]],
        "wall_east": [[W, 0, 0], [W, 0, e], [W, D, e], [W, D, 0]],
        "wall_north": [[W, D, 0], [W, D, n], [0, D, n], [0, D, 0]],
        "wall_west": [[0, D, 0], [0, D, w], [0, 0, w], [0, 0, 0]],
    }
    for name, P in walls.items():
        polys.append(np.array(P, dtype=float))
        names.append(name)
    groups = ["floor"] * (k * k) + ["wall"] * 4
    return Scene.from_polygons(polys, names=names, groups=groups)
