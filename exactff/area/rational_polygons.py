"""Convex polygons in the plane in exact rational arithmetic, for the walls' proof
(:mod:`exactff.area.walls`): points are pairs of Fractions or ints (not floats: convert
them with ``Fraction(x)``, which is exact); turns and cross products are taken from their
numerators and denominators in integers, one Fraction made at the end or none (each
Fraction operation would normalise by a gcd). Polygons are lists of points.
"""

from fractions import Fraction

__all__ = ["cross2", "turn", "ccw", "hull", "split", "crossing", "area2", "has_area",
           "minus_convex"]


def _cross_parts(o, a, b):
    """``(a - o) x (b - o)`` as an integer numerator and a positive denominator."""
    def diff(u, v):   # u - v as (numerator, denominator > 0)
        return (u.numerator * v.denominator - v.numerator * u.denominator,
                u.denominator * v.denominator)
    x1, dx1 = diff(a[0], o[0])
    y1, dy1 = diff(a[1], o[1])
    x2, dx2 = diff(b[0], o[0])
    y2, dy2 = diff(b[1], o[1])
    return x1 * y2 * dx2 * dy1 - y1 * x2 * dx1 * dy2, dx1 * dy1 * dx2 * dy2


def cross2(o, a, b):
    """The cross product ``(a - o) x (b - o)`` of three rational points.

    Parameters
    ----------
    o, a, b : pair of Fraction or int

    Returns
    -------
    Fraction
        Twice the signed area of the triangle o, a, b: positive counter-clockwise.

    Examples
    --------
    >>> cross2((0, 0), (Fraction(1, 3), 0), (0, Fraction(3, 2)))
    Fraction(1, 2)
    """
    num, den = _cross_parts(o, a, b)
    return Fraction(num, den)


def turn(o, a, b):
    """The sign of :func:`cross2` (the same arguments), without making a Fraction: +1
    where o, a, b turn left (counter-clockwise), -1 right, 0 where they are collinear.

    Examples
    --------
    >>> turn((0, 0), (1, 0), (2, Fraction(1, 10**30))), turn((0, 0), (1, 1), (2, 2))
    (1, 0)
    """
    num = _cross_parts(o, a, b)[0]
    return (num > 0) - (num < 0)


def ccw(poly):
    """A convex polygon counter-clockwise, its repeated and collinear vertices dropped.

    Parameters
    ----------
    poly : list of pairs of Fraction or int

    Returns
    -------
    list of pairs, or None
        None where the polygon is not convex (turns both ways) or has no area.

    Examples
    --------
    >>> ccw([(0, 0), (0, 1), (1, 1), (1, 0), (1, 0)])
    [(1, 0), (1, 1), (0, 1), (0, 0)]
    >>> ccw([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2)]) is None      # not convex
    True
    """
    pts = []
    for v in poly:
        if not pts or v != pts[-1]:
            pts.append(v)
    while len(pts) > 1 and pts[0] == pts[-1]:
        pts.pop()
    turns = [turn(pts[i - 1], pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    if any(t > 0 for t in turns) and any(t < 0 for t in turns):
        return None
    pts = [v for v, t in zip(pts, turns) if t != 0]
    if len(pts) < 3:
        return None
    return pts if any(t > 0 for t in turns) else pts[::-1]


def hull(pts):
    """The convex hull of rational points (Andrew's monotone chain), exact.

    Parameters
    ----------
    pts : iterable of pairs of Fraction or int

    Returns
    -------
    list of pairs
        The hull's vertices counter-clockwise, from the least point (lexicographic),
        collinear points dropped: fewer than three points come back sorted, each once,
        and collinear ones as the two ends of their segment.

    Examples
    --------
    >>> hull([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2), (1, 0)])
    [(0, 0), (2, 0), (2, 2), (0, 2)]
    """
    # sorted by (x, y) with the doubles' order first (rounding to double keeps order, so
    # that only ties among the doubles are compared in rationals), each point once
    ordered = sorted(pts, key=lambda p: (float(p[0]), p[0], float(p[1]), p[1]))
    pts = [p for i, p in enumerate(ordered) if i == 0 or p != ordered[i - 1]]
    if len(pts) < 3:
        return pts
    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and turn(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and turn(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def split(poly, a, b):
    """A convex polygon split by the line a -> b, each vertex's side computed once.

    Parameters
    ----------
    poly : list of pairs of Fraction or int
        Convex, in either orientation (the parts keep it).
    a, b : pair of Fraction or int
        Two distinct points of the line.

    Returns
    -------
    (list, list)
        The parts on the closed left and on the closed right: the polygon's vertices on
        that side (those on the line in both) and the edges' crossings with the line. A
        part may be empty, or of fewer than three points or no area (the polygon touches
        the line); the caller tests it (:func:`has_area`).

    Examples
    --------
    >>> left, right = split([(0, 0), (2, 0), (2, 2), (0, 2)], (1, 0), (1, 1))
    >>> [tuple(map(float, v)) for v in left]
    [(0.0, 0.0), (1.0, 0.0), (1.0, 2.0), (0.0, 2.0)]
    >>> area2(right)
    Fraction(4, 1)
    """
    # each vertex's cross product as an integer numerator and a positive denominator:
    # its side is the numerator's sign; a Fraction is made only for the crossings
    s = [_cross_parts(a, b, p) for p in poly]
    left, right = [], []
    for i, p in enumerate(poly):
        j = (i + 1) % len(poly)
        (np_, dp), (nq, dq) = s[i], s[j]
        if np_ >= 0:
            left.append(p)
        if np_ <= 0:
            right.append(p)
        if (np_ > 0 > nq) or (np_ < 0 < nq):
            x = crossing(p, poly[j], s[i], s[j])
            left.append(x)
            right.append(x)
    return left, right


def crossing(p, q, sp, sq):
    """Where the segment p -> q meets the zero of an affine function that is sp at p and
    sq at q (of opposite signs), exactly: ``p + sp / (sp - sq) (q - p)``.

    Parameters
    ----------
    p, q : tuple of Fraction or int
        Points of any dimension.
    sp, sq : pair of int
        The function's values as (numerator, positive denominator).

    Returns
    -------
    tuple of Fraction
        One Fraction made a coordinate: ``(sp q - sq p) / (sp - sq)`` from the integers.

    Examples
    --------
    >>> crossing((0, Fraction(1, 3)), (1, 1), (1, 4), (-3, 4))
    (Fraction(1, 4), Fraction(1, 2))
    """
    (n1, d1), (n2, d2) = sp, sq
    w1, w2 = n1 * d2, n2 * d1             # sp and sq times d1 d2
    den = w1 - w2
    return tuple(Fraction(v.numerator * u.denominator * w1 - u.numerator * v.denominator * w2,
                          u.denominator * v.denominator * den) for u, v in zip(p, q))


def area2(poly):
    """Twice the signed area of a polygon (the shoelace sum), exact.

    Parameters
    ----------
    poly : list of pairs of Fraction or int

    Returns
    -------
    Fraction or int
        Positive for a counter-clockwise polygon, 0 for one of no area.

    Examples
    --------
    >>> area2([(0, 0), (2, 0), (2, 2), (0, 2)])
    8
    """
    return sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(poly, poly[1:] + poly[:1]))


def minus_convex(piece, K):
    """A convex polygon less another, as convex pieces.

    Parameters
    ----------
    piece, K : list of pairs of Fraction or int
        Convex, counter-clockwise.

    Returns
    -------
    list of lists of pairs
        The pieces of positive area of ``piece`` outside K: for each edge of K in turn,
        the part beyond it and within the edges before it (empty where K covers
        ``piece`` but for a set of no area).

    Examples
    --------
    >>> pieces = minus_convex([(0, 0), (4, 0), (4, 4), (0, 4)], [(1, 1), (3, 1), (3, 3), (1, 3)])
    >>> len(pieces), sum(area2(p) for p in pieces) == 2 * (16 - 4)
    (4, True)
    """
    out = []
    rest = piece
    for i, a in enumerate(K):
        rest, beyond = split(rest, a, K[(i + 1) % len(K)])
        if has_area(beyond):
            out.append(beyond)
        if not has_area(rest):
            break
    return out


def has_area(poly):
    """Whether a convex polygon (either orientation, collinear or repeated vertices
    allowed: the parts :func:`split` makes) has positive area, exactly: the triangles
    of its fan from the first vertex all turn one way or not at all, so its area is 0
    only where every one of them is flat (integer turns, no Fraction made).

    Examples
    --------
    >>> has_area([(0, 0), (1, 0), (1, 1)]), has_area([(0, 0), (1, 1), (2, 2), (3, 3)])
    (True, False)
    """
    return any(turn(poly[0], poly[i], poly[i + 1]) for i in range(1, len(poly) - 1))
