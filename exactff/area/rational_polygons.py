"""Convex polygons in the plane in exact rational arithmetic, for the walls' proof
(:mod:`exactff.area.walls`): points are pairs of Fractions (or ints); turns and cross
products are taken from their numerators and denominators in integers, one Fraction made
at the end or none (each Fraction operation would normalise by a gcd).
"""

from fractions import Fraction

__all__ = ["cross2", "turn", "ccw", "hull", "split", "area2", "minus_convex"]


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
    """The cross product ``(a - o) x (b - o)`` of three rational points, a Fraction
    (twice the signed area of the triangle o, a, b: positive counter-clockwise).

    Examples
    --------
    >>> cross2((0, 0), (Fraction(1, 3), 0), (0, Fraction(3, 2)))
    Fraction(1, 2)
    """
    num, den = _cross_parts(o, a, b)
    return Fraction(num, den)


def turn(o, a, b):
    """The sign of :func:`cross2`: +1 where o, a, b turn left, -1 right, 0 collinear.

    Examples
    --------
    >>> turn((0, 0), (1, 0), (2, Fraction(1, 10**30))), turn((0, 0), (1, 1), (2, 2))
    (1, 0)
    """
    num = _cross_parts(o, a, b)[0]
    return (num > 0) - (num < 0)


def ccw(poly):
    """The polygon counter-clockwise, its repeated and collinear vertices dropped; None
    where it is not convex or of no area.

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
    """The convex hull of rational points (Andrew's monotone chain), counter-clockwise,
    exact; fewer than three points as given (sorted, each once).

    Examples
    --------
    >>> hull([(0, 0), (2, 0), (1, 1), (2, 2), (0, 2), (1, 0)])
    [(0, 0), (2, 0), (2, 2), (0, 2)]
    """
    pts = sorted(set(pts))
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
    """A convex polygon split by the line a -> b: its parts on the closed left and on
    the closed right (each vertex's side computed once, exactly).

    Examples
    --------
    >>> left, right = split([(0, 0), (2, 0), (2, 2), (0, 2)], (1, 0), (1, 1))
    >>> [tuple(map(float, v)) for v in left]
    [(0.0, 0.0), (1.0, 0.0), (1.0, 2.0), (0.0, 2.0)]
    >>> area2(right)
    Fraction(4, 1)
    """
    s = [cross2(a, b, p) for p in poly]
    left, right = [], []
    for i, p in enumerate(poly):
        j = (i + 1) % len(poly)
        sp, sq = s[i], s[j]
        if sp >= 0:
            left.append(p)
        if sp <= 0:
            right.append(p)
        if (sp > 0 > sq) or (sp < 0 < sq):
            q = poly[j]
            t = sp / (sp - sq)
            x = (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))
            left.append(x)
            right.append(x)
    return left, right


def area2(poly):
    """Twice the signed area of a polygon (the shoelace sum), exact.

    Examples
    --------
    >>> area2([(0, 0), (2, 0), (2, 2), (0, 2)])
    8
    """
    return sum(p[0] * q[1] - q[0] * p[1] for p, q in zip(poly, poly[1:] + poly[:1]))


def minus_convex(piece, K):
    """The convex pieces of positive area of ``piece`` less the convex polygon K (both
    counter-clockwise): the parts beyond each edge of K and within the ones before it.

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
        if len(beyond) >= 3 and area2(beyond) != 0:
            out.append(beyond)
        if len(rest) < 3 or area2(rest) == 0:
            break
    return out
