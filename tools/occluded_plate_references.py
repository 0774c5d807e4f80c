"""The occluded references of tests/test_area.py (OCCLUDED_REFERENCES) to 25 digits.

Two unit squares 2 apart ([0, 1]^2 at z = 0 facing up, at z = 2 facing down) with a
0.5 x 0.5 plate at z = 1 between them ([.25, .75]^2 centred, [.6, 1.1] x [.25, .75]
offset). From a point x of the lower square the plate's shadow on the upper one is the
plate scaled by 2 about x: the rectangle [2 a - x, 2 b - x] per axis. The point's
visible part is the upper square minus the shadow's part in it, an axis-aligned
rectangle: by Howell's superposition of corner rectangles (catalogue B-3, element to
a parallel rectangle through a corner, odd in each side), F(x) = F(square) - F(shadow in
the square). The area form factor is the mean of F(x) over the lower square (area 1):
mpmath quadrature over the pieces between the shadow's kinks (where its edges cross
the square's), where F(x) is analytic.

Run: python tools/occluded_plate_references.py (about 1.5 min of one core). Printed
(exactff @ade06d0's tree, 2026-12-05): centred 0.03140269424799635601252592, offset
0.05202766304540471487060044, each differing by 2e-33 between 30 and 40 digits.
"""

import mpmath as mp


def corner(a, b, c):
    """Howell B-3: a plane element to a parallel a x b rectangle at distance c, the
    element's normal through a corner; odd in a and in b."""
    A, B = a / c, b / c
    return (A / mp.sqrt(1 + A * A) * mp.atan(B / mp.sqrt(1 + A * A))
            + B / mp.sqrt(1 + B * B) * mp.atan(A / mp.sqrt(1 + B * B))) / (2 * mp.pi)


def rectangle(x, y, x1, x2, y1, y2, c):
    """The element at (x, y, 0) facing up to the rectangle [x1, x2] x [y1, y2] at z = c."""
    if x1 >= x2 or y1 >= y2:
        return mp.mpf(0)
    return (corner(x2 - x, y2 - y, c) - corner(x1 - x, y2 - y, c)
            - corner(x2 - x, y1 - y, c) + corner(x1 - x, y1 - y, c))


def reference(plate_x, plate_y, dps=30):
    """F(lower square -> upper square) past the plate [plate_x] x [plate_y] at z = 1."""
    with mp.workdps(dps):
        def visible(x, y):
            sx = (max(0, 2 * plate_x[0] - x), min(1, 2 * plate_x[1] - x))
            sy = (max(0, 2 * plate_y[0] - y), min(1, 2 * plate_y[1] - y))
            return rectangle(x, y, 0, 1, 0, 1, 2) - rectangle(x, y, *sx, *sy, 2)

        # the kinks: the shadow's edges 2 a - x cross the square's edges 0 and 1
        def breaks(a, b):
            return sorted({0, 1} | {t for t in (2 * a, 2 * a - 1, 2 * b, 2 * b - 1)
                                    if 0 < t < 1})
        xs = [mp.mpf(t) for t in breaks(*plate_x)]
        ys = [mp.mpf(t) for t in breaks(*plate_y)]
        return mp.quad(visible, xs, ys)


if __name__ == "__main__":
    # the plates' coordinates as the test's doubles (0.6 and 1.1 are not exact), taken
    # exactly
    for name, px, py in (("centred", (mp.mpf(0.25), mp.mpf(0.75)), (mp.mpf(0.25), mp.mpf(0.75))),
                         ("offset", (mp.mpf(0.6), mp.mpf(1.1)), (mp.mpf(0.25), mp.mpf(0.75)))):
        a = reference(px, py, 30)
        b = reference(px, py, 40)
        print(name, mp.nstr(b, 25), "difference at 30/40 digits", mp.nstr(abs(a - b), 3))
