"""Hypothesis strategies for planar polygons, receivers and scenes.

Every strategy builds valid data by construction: star-shaped (hence simple) or convex
polygons from sorted angles, embedded in 3-D with a random rotation, scale and
translation. Requires ``hypothesis``.
"""

import math

import numpy as np
from hypothesis import strategies as st

__all__ = ["unit_vectors", "points", "polygons_2d", "planar_polygons", "convex_polygons",
           "embed", "points_above", "scenes", "enclosures", "occluded_scenes", "flush_faces"]


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


def _check_int(name, value, low):
    if not (isinstance(value, (int, np.integer)) and value >= low):
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")


def _magnitude(lo_exp, hi_exp):
    """Positive magnitudes 10**e with the exponent e drawn in [lo_exp, hi_exp]."""
    return st.floats(lo_exp, hi_exp).map(lambda e: float(10.0 ** e))


def points_above(polygon, *, min_exponent=-6, max_exponent=2):
    """Receivers ``(point, normal)`` in front of ``polygon``.

    The point lies over a point of the polygon (or beside it), at a distance ``10**e``
    from its plane with ``e`` drawn in ``[min_exponent, max_exponent]`` (near its plane
    included); the normal is drawn on the sphere, often close to the point's horizon
    through the polygon (grazing) or facing it. Eagerly checks its options.

    Examples
    --------
    >>> import numpy as np
    >>> from hypothesis import given
    >>> sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    >>> @given(points_above(sq))
    ... def check(pn):
    ...     p, n = pn
    ...     assert p[2] > 0 and abs(np.linalg.norm(n) - 1) < 1e-12
    >>> check()
    """
    P = np.asarray(polygon, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 3:
        raise ValueError(f"polygon must have shape (K, 3) with K >= 3, got {P.shape}")
    if not min_exponent <= max_exponent:
        raise ValueError(f"min_exponent must not exceed max_exponent, got {min_exponent!r} "
                         f"> {max_exponent!r}")
    return _points_above(P, min_exponent, max_exponent)


@st.composite
def _points_above(draw, P, min_exponent, max_exponent):
    from ..geometry import polygon_diameter, unit_normal

    nP = unit_normal(P)
    size = polygon_diameter(P)
    # a point of the polygon (a convex combination of its vertices), or beside it
    w = np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=len(P), max_size=len(P))))
    base = (w @ P) / w.sum() if w.sum() > 0 else P.mean(axis=0)
    beside = draw(st.sampled_from([0.0, 0.0, 0.5, 2.0]))
    t1 = P[1] - P[0]
    t1 = t1 / np.linalg.norm(t1)
    height = draw(_magnitude(min_exponent, max_exponent)) * max(size, 1e-300)
    p = base + beside * size * t1 + height * nP
    kind = draw(st.sampled_from(["random", "grazing", "facing"]))
    if kind == "random":
        n = draw(unit_vectors())
    else:
        # towards the polygon (facing) or nearly in the plane through p containing the
        # direction to the polygon (grazing: the polygon on the horizon)
        d = base - p
        d = d / np.linalg.norm(d)
        if kind == "facing":
            n = d
        else:
            side = np.cross(d, t1)
            side = side / np.linalg.norm(side) if np.linalg.norm(side) > 0 else nP
            tilt = draw(st.floats(-1e-3, 1e-3))
            n = side + tilt * d
            n = n / np.linalg.norm(n)
    return p, n


def scenes(*, min_polygons=1, max_polygons=8, max_vertices=6):
    """Scenes of planar polygons in general position (interpenetrating allowed), sizes
    from a drawn exponent; each polygon valid by construction.

    Examples
    --------
    >>> from hypothesis import given
    >>> @given(scenes(max_polygons=3))
    ... def check(scene):
    ...     assert 1 <= len(scene) <= 3
    >>> check()
    """
    _check_int("min_polygons", min_polygons, 1)
    _check_int("max_polygons", max_polygons, min_polygons)
    _check_int("max_vertices", max_vertices, 3)
    return _scenes(min_polygons, max_polygons, max_vertices)


@st.composite
def _scenes(draw, min_polygons, max_polygons, max_vertices):
    from ..scene import Scene

    scale = draw(_magnitude(-3, 3))
    k = draw(st.integers(min_polygons, max_polygons))
    polys = [draw(planar_polygons(max_vertices=max_vertices,
                                  scale=st.floats(0.2, 2.0).map(lambda s: s * scale),
                                  centre=points(2.0).map(lambda c: c * scale)))
             for _ in range(k)]
    return Scene.from_polygons(polys)


def enclosures(*, max_boxes=3, max_k=3):
    """``(scene, point, normal)``: a closed box room (``k x k`` quads per face, size from
    a drawn exponent, anywhere) with up to ``max_boxes`` solid box obstacles (floating,
    touching the floor or the walls, or interpenetrating each other), and a receiver
    inside the room and outside every obstacle, so that its row sums to 1.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import exactff as ef
    >>> @settings(max_examples=3, deadline=None)
    ... @given(enclosures(max_boxes=1))
    ... def check(case):
    ...     scene, p, n = case
    ...     assert abs(ef.form_factors(scene, p, n).sum() - 1) < 1e-11
    >>> check()
    """
    _check_int("max_boxes", max_boxes, 0)
    _check_int("max_k", max_k, 1)
    return _enclosures(max_boxes, max_k)


@st.composite
def _enclosures(draw, max_boxes, max_k):
    from ..scene import Scene
    from ..scenes import box_polygons

    L = draw(_magnitude(-2, 3))
    origin = np.array(draw(points(10.0))) * L
    k = draw(st.integers(1, max_k))
    polys = box_polygons(origin, origin + L, k)
    groups = ["room"] * len(polys)
    unit = st.floats(0.15, 0.95)
    for b in range(draw(st.integers(0, max_boxes))):
        lo = np.array([draw(unit) for _ in range(3)])
        hi = np.minimum(lo + np.array([draw(st.floats(0.05, 0.5)) for _ in range(3)]), 1.0)
        if draw(st.booleans()):
            lo[2] = 0.0          # standing on the floor (touching it)
        if np.any(hi - lo < 0.02):
            continue
        box = box_polygons(origin + lo * L, origin + hi * L, 1, facing="out")
        polys += box
        groups += [f"box{b}"] * len(box)
    # the receiver: in the corner region [0.02, 0.12]^3 of the room, which no obstacle
    # reaches (their x and y start at 0.15 of the room)
    p = origin + np.array([draw(st.floats(0.02, 0.12)) for _ in range(3)]) * L
    return Scene.from_polygons(polys, groups=groups), p, draw(unit_vectors())


def occluded_scenes(*, max_extra=3):
    """``(scene, point, normal)`` where a polygon really hides part of another from the
    point: a far polygon and a nearer one both crossing the line from the point along a
    direction within 60 degrees of the normal, plus up to ``max_extra`` other polygons,
    the whole moved by a random rigid motion and scaled by a drawn exponent.

    Polygon 0 is the far one, polygon 1 the occluder: ``F[0]`` is smaller than the
    unoccluded value.

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import exactff as ef
    >>> @settings(max_examples=3, deadline=None)
    ... @given(occluded_scenes())
    ... def check(case):
    ...     scene, p, n = case
    ...     F = ef.form_factors(scene, p, n)
    ...     U = ef.point_polygon_form_factors(p, n, scene)
    ...     assert F[0] < U[0]
    >>> check()
    """
    _check_int("max_extra", max_extra, 0)
    return _occluded_scenes(max_extra)


@st.composite
def _occluded_scenes(draw, max_extra):
    from ..geometry import receiver_frame
    from ..scene import Scene

    h_near = draw(st.floats(0.3, 1.0))
    h_far = h_near * draw(st.floats(1.3, 4.0))
    # both polygons contain the axis point (0, 0, h) and face the origin (down)
    near = embed(draw(polygons_2d(convex=True)), np.array([0.0, 0.0, -1.0]),
                 np.array([0.0, 0.0, h_near]), h_near * draw(st.floats(0.1, 0.8)))
    far = embed(draw(polygons_2d(convex=True)), np.array([0.0, 0.0, -1.0]),
                np.array([0.0, 0.0, h_far]), h_far * draw(st.floats(0.3, 1.5)))
    polys = [far, near]
    for _ in range(draw(st.integers(0, max_extra))):
        polys.append(draw(planar_polygons(centre=points(2.0).map(lambda c: c + [0, 0, 2.5]))))
    # the receiver normal within 60 degrees of the axis; then a rigid motion and a scale
    n_local = draw(unit_vectors().filter(lambda v: v[2] > 0.5))
    R = receiver_frame(draw(unit_vectors()))
    scale = draw(_magnitude(-2, 2))
    shift = np.array(draw(points(10.0))) * scale
    moved = [scale * (P @ R) + shift for P in polys]
    return Scene.from_polygons(moved), shift.copy(), n_local @ R


def flush_faces(*, min_gap_exponent=-16, max_gap_exponent=-9, max_shift_exponent=4):
    """``(scene, point, normal)`` with two faces flush to within rounding: a base
    triangle, and a second triangle overlapping it whose vertices lie ``10**k``
    times the size off the base's plane (``k`` drawn in ``[min_gap_exponent,
    max_gap_exponent]``, each vertex on its own side, so that the face may cross the
    plane at a grazing angle or lie parallel to it), facing either way, with a third
    polygon that may hide part of both (triangles stay exactly planar whatever the
    rotation, as the triangles of an export are); the whole turned by a random rotation and moved
    up to ``10**max_shift_exponent`` sizes from the origin, as building models exported
    from IFC place walls on slabs and rafters under roofs.

    Polygon 0 is the base, polygon 1 the flush face (the rotation's rounding moves each
    vertex by an ulp of the shifted coordinates, which at the far shifts is more than the
    smaller gaps: the faces are then flush, coplanar or crossing as rounding leaves them).

    Examples
    --------
    >>> from hypothesis import given, settings
    >>> import exactff as ef
    >>> @settings(max_examples=3, deadline=None)
    ... @given(flush_faces())
    ... def check(case):
    ...     scene, p, n = case
    ...     F = ef.form_factors(scene, p, n, tolerance=None)
    ...     assert len(scene) == 3 and F.min() >= 0
    >>> check()
    """
    _check_int("max_shift_exponent", max_shift_exponent, 0)
    if not min_gap_exponent <= max_gap_exponent:
        raise ValueError(f"min_gap_exponent must be at most max_gap_exponent, got "
                         f"{min_gap_exponent!r} > {max_gap_exponent!r}")
    return _flush_faces(min_gap_exponent, max_gap_exponent, max_shift_exponent)


@st.composite
def _flush_faces(draw, min_gap, max_gap, max_shift):
    from ..geometry import receiver_frame
    from ..scene import Scene

    h = draw(st.floats(0.5, 2.0))
    down = np.array([0.0, 0.0, -1.0])
    # a triangle, as the exports are: exactly planar after any rotation
    base = embed(draw(polygons_2d(convex=True, max_vertices=3)), down, np.array([0.0, 0.0, h]),
                 h * draw(st.floats(0.5, 1.5)))
    # the flush face: overlapping the base, each vertex its own gap off the base's plane
    centre = np.array([draw(st.floats(-0.3, 0.3)) * h, draw(st.floats(-0.3, 0.3)) * h, h])
    facing = down if draw(st.booleans()) else -down
    flush = embed(draw(polygons_2d(convex=True, max_vertices=3)), facing, centre,
                  h * draw(st.floats(0.3, 1.2)))
    size = float(np.ptp(flush, axis=0).max())
    for v in flush:
        v[2] = h + draw(st.sampled_from([-1.0, 1.0])) * size * 10.0 ** draw(
            st.floats(min_gap, max_gap))
    if np.cross(flush[1] - flush[0], flush[2] - flush[0]) @ facing < 0:
        flush = flush[::-1]
    # an occluder between the point and the pair, or beside it
    occluder = embed(draw(polygons_2d(convex=True)), down,
                     np.array([draw(st.floats(-1, 1)) * h, draw(st.floats(-1, 1)) * h,
                               h * draw(st.floats(0.3, 0.8))]), h * draw(st.floats(0.1, 0.5)))
    n_local = draw(unit_vectors().filter(lambda v: v[2] > 0.5))
    R = receiver_frame(draw(unit_vectors()))
    shift = np.array(draw(points(1.0))) * h * 10.0 ** draw(st.floats(0, max_shift))
    moved = [(P @ R) + shift for P in (base, flush, occluder)]
    return Scene.from_polygons(moved), shift.copy(), n_local @ R
