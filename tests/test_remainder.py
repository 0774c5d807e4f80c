"""Open scenes: sky and ground (exactff.remainder, form_factors(remainder=True)).

Every expected value is independent of the code under test: Howell's point-to-rectangle
closed forms (tests/common.py), Hottel's 2-D string rule for an infinitely long canyon,
an mpmath quadrature of the hemisphere's share above the horizontal, the mpmath
reference of one polygon, or an invariant (sums to 1, splitting invariance).
"""

import math

import mpmath
import numpy as np
import pytest

import exactff as ef
from exactff.errors import NumericalError
from exactff.remainder import hemisphere_sky_share, horizontal_split, remainder_row
from exactff.testing.mp_reference import boundary_form_factor

from common import parallel_rect_corner, perpendicular_rect


def quad(x0, x1, y0, y1, z0, z1, axis, at):
    """An axis-aligned rectangle in the plane ``axis = at``, CCW order left to the
    caller (flip with [::-1])."""
    if axis == "y":
        return np.array([[x0, at, z0], [x1, at, z0], [x1, at, z1], [x0, at, z1]], float)
    if axis == "x":
        return np.array([[at, y0, z0], [at, y1, z0], [at, y1, z1], [at, y0, z1]], float)
    return np.array([[x0, y0, at], [x1, y0, at], [x1, y1, at], [x0, y1, at]], float)


def facing(P, toward):
    """``P`` wound so that its front faces the point ``toward``."""
    n = np.cross(P[1] - P[0], P[2] - P[0])
    return P if n @ (np.asarray(toward) - P[0]) > 0 else P[::-1].copy()


def canyon(W, H, L, k=1):
    """A street canyon along x: floor |y| <= W/2 (facing up), walls y = +-W/2 of height
    H facing in, length L, each wall cut into k x k quads; open at the top and ends."""
    polys = [quad(-L / 2, L / 2, -W / 2, W / 2, 0, 0, "z", 0.0)]
    xs, zs = np.linspace(-L / 2, L / 2, k + 1), np.linspace(0, H, k + 1)
    for y in (-W / 2, W / 2):
        for a in range(k):
            for b in range(k):
                P = quad(xs[a], xs[a + 1], 0, 0, zs[b], zs[b + 1], "y", y)
                polys.append(facing(P, [0, 0, H / 2]))
    return ef.Scene.from_polygons(polys)


def floor_to_wall(x0, y0, x1, x2, Y, H):
    """Howell: a floor point (x0, y0), normal up, to the wall y = Y, x in [x1, x2],
    0 <= z <= H (two rectangles with an edge on the floor, split at x = x0)."""
    d = abs(Y - y0)
    return sum(perpendicular_rect(b, H, d) for b in (x2 - x0, x0 - x1) if b > 0)


# -- the closed-form share --------------------------------------------------------------

@pytest.mark.parametrize("c", [1.0, 0.8, 0.3, 0.0, -0.45, -1.0])
def test_sky_share_vs_quadrature(c):
    """(1 + n.up)/2 against an mpmath quadrature over the hemisphere: with
    up = c n + s e1, the azimuths with w.up > 0 at polar angle theta are
    cos(phi) > -c cot(theta) / s, of measure 2 acos(.)."""
    s = mpmath.sqrt(1 - mpmath.mpf(c) ** 2)

    def f(t):
        if s == 0:
            inside = 2 * mpmath.pi if c > 0 else 0
        else:
            x = -mpmath.mpf(c) * mpmath.cos(t) / (s * mpmath.sin(t))
            inside = 2 * mpmath.acos(max(-1, min(1, x)))
        return mpmath.cos(t) * mpmath.sin(t) * inside / mpmath.pi

    # the clip's kink: |c| cot(theta) = s
    with mpmath.workdps(30):
        kink = mpmath.atan2(abs(c), s) if s != 0 else mpmath.pi / 4
        ref = mpmath.quad(f, [mpmath.mpf(1e-30), kink, mpmath.pi / 2])
    th = math.acos(c)
    n = np.array([math.sin(th), 0.0, c])
    share, bound = hemisphere_sky_share(n)
    assert abs(share - float(ref)) <= 1e-14 + bound


def test_sky_share_vs_exact_engine():
    """A tilted receiver above a huge floor: the floor's form factor tends to the
    ground share (1 - c)/2; what it misses is within the floor's angular reach
    (at most h / R of the hemisphere's weight)."""
    h, R = 1.0, 1e6
    floor = ef.Scene.from_polygons([quad(-R, R, -R, R, 0, 0, "z", 0.0)])
    for n in ([0.6, 0.0, 0.8], [0.3, -0.5, 0.2], [1, 0, 0], [0.2, 0.1, -1.0]):
        n = np.asarray(n) / np.linalg.norm(n)
        F = ef.form_factors(floor, [0, 0, h], n)
        assert abs(F[0] - (1 - n[2]) / 2) <= 2 * h / R


# -- street canyon ----------------------------------------------------------------------

def hottel_sky(W, H, y0):
    """Hottel's string rule for an infinitely long canyon, the differential strip at
    floor position y0 (normal up) to the opening: (sin t2 - sin t1) / 2, t the angles
    of the opening's edges from the normal in the cross-section."""
    t2 = math.atan2(W / 2 - y0, H)
    t1 = math.atan2(-W / 2 - y0, H)
    return (math.sin(t2) - math.sin(t1)) / 2


@pytest.mark.parametrize("y0", [0.0, 0.3, -0.42])
def test_canyon_sky_vs_howell_and_hottel(y0):
    W, H, L = 1.0, 1.5, 4000.0
    scene = canyon(W, H, L)
    x0 = 1.7
    F, sky, ground = ef.form_factors(scene, [x0, y0, 0.0], [0, 0, 1], remainder=True)
    # the finite canyon: 1 minus the walls (Howell); the floor is in the tangent plane
    walls = sum(floor_to_wall(x0, y0, -L / 2, L / 2, Y, H) for Y in (-W / 2, W / 2))
    assert abs(sky - (1 - walls)) <= 1e-12
    assert ground == 0.0
    # the infinitely long canyon (Hottel): the ends' openings, two W x H rectangles at
    # about L/2, take less than 4 W H / (pi (L/2 - |x0|)^2) more
    ends = 4 * W * H / (math.pi * (L / 2 - abs(x0)) ** 2)
    assert 0 <= sky - hottel_sky(W, H, y0) <= ends
    # the row itself: the two walls (Howell)
    assert abs(F.sum() - walls) <= 1e-12


def test_canyon_wall_point_plane_cuts_the_opposite_wall():
    """A point on a wall at height z0 facing across: the opposite wall and the ends
    straddle the horizontal plane. Sky = 1/2 minus the opposite wall above (Howell,
    parallel rectangles); ground = 1/2 minus the wall below and the floor (Howell,
    perpendicular rectangle)."""
    W, H, L, z0 = 1.0, 2.0, 400.0, 0.7
    for k in (1, 3):                    # whole walls, and walls of 3 x 3 quads
        scene = canyon(W, H, L, k)
        p, n = [0.0, -W / 2, z0], [0, 1, 0]
        F, sky, ground, E, Es, Eg = ef.form_factors(scene, p, n, remainder=True, error=True)
        above = 2 * parallel_rect_corner(L / 2, H - z0, W)
        below = 2 * parallel_rect_corner(L / 2, z0, W)
        floor = 2 * perpendicular_rect(L / 2, W, z0)
        assert abs(sky - (0.5 - above)) <= max(1e-12, Es)
        assert abs(ground - (0.5 - below - floor)) <= max(1e-12, Eg)
        assert Es < 1e-11 and Eg < 1e-11
        # splitting invariance: the parts add back to the unsplit row
        F0, E0 = ef.form_factors(scene, p, n, error=True)
        assert np.all(np.abs(F - F0) <= E + E0 + 1e-16)
        # the row itself: the opposite wall and the floor (Howell)
        assert abs(F.sum() - (above + below + floor)) <= 1e-12


# -- courtyard ----------------------------------------------------------------------------

def courtyard(S, H, roof=False):
    """A square courtyard |x|, |y| <= S/2 with walls of height H facing in; with
    ``roof``, a ceiling at H too (a closed room)."""
    c = [0, 0, H / 2]
    polys = [quad(-S / 2, S / 2, -S / 2, S / 2, 0, 0, "z", 0.0)]
    for at in (-S / 2, S / 2):
        polys.append(facing(quad(-S / 2, S / 2, 0, 0, 0, H, "y", at), c))
        polys.append(facing(quad(0, 0, -S / 2, S / 2, 0, H, "x", at), c))
    if roof:
        polys.append(facing(quad(-S / 2, S / 2, -S / 2, S / 2, 0, 0, "z", H), c))
    return ef.Scene.from_polygons(polys)


def test_courtyard_floor_grid_vs_howell():
    S, H = 2.0, 1.3
    scene = courtyard(S, H)
    xy = np.array([[x, y] for x in (-0.7, 0.0, 0.45) for y in (-0.2, 0.6)])
    P = np.column_stack([xy, np.zeros(len(xy))])
    F, sky, ground = ef.form_factors(scene, P, [0, 0, 1], remainder=True)
    assert sky.shape == ground.shape == (len(P),) and F.shape == (len(P), len(scene))
    for (x0, y0), s, g in zip(xy, sky, ground):
        walls = (floor_to_wall(x0, y0, -S / 2, S / 2, -S / 2, H)
                 + floor_to_wall(x0, y0, -S / 2, S / 2, S / 2, H)
                 + floor_to_wall(y0, x0, -S / 2, S / 2, -S / 2, H)
                 + floor_to_wall(y0, x0, -S / 2, S / 2, S / 2, H))
        assert abs(s - (1 - walls)) <= 1e-12
        assert g == 0.0
    # the grid's rows share one split (one height)
    assert horizontal_split(scene, P[0]) is horizontal_split(scene, P[-1])


def test_builtin_courtyard_vs_howell():
    """ef.scenes.courtyard: from a floor point, 1 minus its four walls (Howell)."""
    W, D, H = 20.0, 14.0, (9.0, 6.0, 9.0, 3.0)
    scene = ef.scenes.courtyard(W, D, H, k=3)
    for x0, y0 in ((10.0, 7.0), (3.0, 11.5), (17.2, 1.1)):
        _, sky, ground = ef.form_factors(scene, [x0, y0, 0.0], [0, 0, 1], remainder=True)
        walls = (floor_to_wall(x0, y0, 0, W, 0.0, H[0]) + floor_to_wall(y0, x0, 0, D, W, H[1])
                 + floor_to_wall(x0, y0, 0, W, D, H[2]) + floor_to_wall(y0, x0, 0, D, 0.0, H[3]))
        assert abs(sky - (1 - walls)) <= 1e-12 and ground == 0.0


def test_closed_room_has_no_sky_or_ground():
    """Closed scenes: sky = ground = 0 within their bounds, from receivers at many
    heights and tilts (the office is y-up)."""
    room = courtyard(2.0, 1.3, roof=True)
    rng = np.random.default_rng(3)
    P = np.column_stack([rng.uniform(-0.9, 0.9, (6, 2)), rng.uniform(0.05, 1.25, 6)])
    N = rng.normal(size=(6, 3))
    F, sky, ground, E, Es, Eg = ef.form_factors(room, P, N, remainder=True, error=True)
    # the bounds themselves small: an uncapped bound would hold any sky
    assert np.all(sky <= Es) and np.all(ground <= Eg)
    assert np.all(Es < 1e-11) and np.all(Eg < 1e-11)
    office = ef.scenes.office(300)
    for i in (0, 50, 120, 200, 260):
        _, s, g, _, es, eg = ef.form_factors(office, office.centroids[i], office.normals[i],
                                             remainder=True, error=True, up=(0, 1, 0))
        assert s <= es and g <= eg and es < 1e-10 and eg < 1e-10


def test_tilted_receiver_vs_mpmath():
    """A receiver tilted above one square floor (nothing above it): sky is the whole
    closed-form share, ground the share minus the floor's mpmath value."""
    floor = quad(-3, 4, -2, 5, 0, 0, "z", 0.0)
    scene = ef.Scene.from_polygons([floor])
    p = np.array([0.3, 0.2, 0.9])
    for n in ([0.5, 0.2, 0.8], [1.0, 0.0, 0.0], [0.3, 0.4, -0.6]):
        n = np.asarray(n) / np.linalg.norm(n)
        _, sky, ground = ef.form_factors(scene, p, n, remainder=True)
        # mpmath quadrature of the image's boundary (exactff.testing; not the kernel)
        ref = float(boundary_form_factor(p, n, floor, dps=40))
        c = n[2]
        assert abs(sky - (1 + c) / 2) <= 1e-15
        assert abs(ground - ((1 - c) / 2 - ref)) <= 1e-13


# -- the split -----------------------------------------------------------------------------

def test_splitting_invariance_point_row_with_cuts():
    """Rows at heights where the plane cuts polygons (non-convex ones too): the parts'
    sums equal the unsplit row within their bounds, for both engines."""
    L_shape = np.array([[0, 0, 0], [2, 0, 0], [2, 0, 1], [1, 0, 1], [1, 0, 2], [0, 0, 2]],
                       float) + [0, 2, 0]                    # an L in the plane y = 2
    U = np.array([[0, 0, 0], [3, 0, 0], [3, 0, 2], [2, 0, 2], [2, 0, 1], [1, 0, 1], [1, 0, 2],
                  [0, 0, 2]], float) + [-1, -1.5, 0]          # a U in the plane y = -1.5
    box = ef.scenes.subdivided_box(2)
    polys = [facing(L_shape, [0.5, 0, 1]), facing(U, [0.5, 0, 1])]
    polys += [np.asarray(P) * [4, 6, 3] + [-1.5, -2.5, -0.5] for P in box.polygons]
    scene = ef.Scene.from_polygons(polys)
    for p, n in (([0.5, 0.3, 1.5], [0.2, 0.3, 0.9]), ([0.4, 0.1, 0.5], [0.1, -1, 0.2]),
                 ([0.5, 0.0, 1.0], [0.0, 0.3, -1.0])):
        sp = horizontal_split(scene, p)
        assert len(sp.scene) > len(scene)         # the plane cut something
        for engine in ("compiled", "python"):
            m = ef.Exact(engine=engine)
            F, sky, ground, E, Es, Eg = ef.form_factors(scene, p, n, remainder=True,
                                                        error=True, method=m)
            F0, E0 = ef.form_factors(scene, p, n, error=True, method=m)
            assert np.all(np.abs(F - F0) <= E + E0 + 1e-16)
            assert sky <= Es and ground <= Eg         # closed
            # the box encloses the point: its row alone sums to 1
            assert abs(F.sum() - 1) <= 1e-13


def test_polygon_in_the_plane_counts_on_neither_side():
    """A horizontal shelf at the receiver's height, seen edge-on: value 0, no side."""
    W, H, L = 1.0, 2.0, 50.0
    base = canyon(W, H, L)
    shelf = quad(-1, 1, 0.1, 0.4, 0, 0, "z", 0.7)
    scene = ef.Scene.from_polygons(list(base.polygons) + [shelf])
    p, n = [0.0, -W / 2, 0.7], [0, 1, 0]
    sp = horizontal_split(scene, p)
    assert sp.side[sp.owner == len(scene) - 1].tolist() == [0]
    F, sky, ground = ef.form_factors(scene, p, n, remainder=True)
    F0, sky0, ground0 = ef.form_factors(base, p, n, remainder=True)
    assert F[-1] == 0.0
    assert abs(sky - sky0) <= 1e-15 and abs(ground - ground0) <= 1e-15


@pytest.mark.parametrize("method", sorted(set(ef.METHODS) - {"exact"}))
def test_every_discrete_method_through_the_same_path(method):
    """Discrete methods: sky within sampling of the exact sky, the row within sampling
    of 1 with sky and ground, and their parts adding back to their unsplit row."""
    S, H = 2.0, 1.3
    scene = courtyard(S, H)
    p, n = [0.3, -0.2, 0.5], [0.3, 0.1, 0.9]          # the plane cuts the walls
    F, sky, ground = ef.form_factors(scene, p, n, remainder=True, method=method)
    _, sky_x, ground_x = ef.form_factors(scene, p, n, remainder=True)
    F0 = ef.form_factors(scene, p, n, method=method)
    # sampling at the default resolutions: measured 3e-4 and below, 5e-3 for the polar
    # plane; the single plane loses the energy outside its plane, which then counts as
    # sky or ground (3e-2 here)
    tol = 0.05 if method == "single_plane" else 0.01
    assert abs(sky - sky_x) <= tol and abs(ground - ground_x) <= tol
    assert abs(F.sum() - ef.form_factors(scene, p, n).sum()) <= tol
    # the parts take the same cells (or rays) as the whole: equal up to summation
    assert np.abs(F - F0).max() <= 1e-12
    assert sky >= 0 and ground >= 0


# -- the reusable function and bad input ----------------------------------------------------

def solid_angle(P, c):
    """Van Oosterom & Strackee's solid angle of a convex polygon (a fan of triangles)
    seen from c, unoccluded."""
    R = np.asarray(P, float) - c
    total = 0.0
    for i in range(1, len(R) - 1):
        a, b, d = R[0], R[i], R[i + 1]
        la, lb, ld = (np.linalg.norm(v) for v in (a, b, d))
        num = abs(a @ np.cross(b, d))
        den = la * lb * ld + (a @ b) * ld + (a @ d) * lb + (b @ d) * la
        total += 2 * math.atan2(num, den)
    return total


def test_remainder_row_with_a_spherical_row():
    """A spherical row (solid angle / 4 pi, sky share 1/2) through the same function:
    from the centre of a unit cube without its ceiling the missing face is 1/6 of the
    sphere (symmetry), all of it sky; nothing is missing below."""
    box = ef.scenes.subdivided_box(1)
    roofless = ef.Scene.from_polygons([P for i, P in enumerate(box.polygons) if i != 1])
    c = np.array([0.5, 0.5, 0.5])
    # nothing hides anything from inside a convex box: the row is unoccluded
    sphere_row = lambda s: np.array([solid_angle(P, c) for P in s.polygons]) / (4 * math.pi)
    F, sky, ground = remainder_row(roofless, c, sphere_row, sky_share=0.5)
    assert abs(sky - 1 / 6) <= 1e-15 and ground <= 1e-15
    assert abs(F.sum() - 5 / 6) <= 1e-15


def test_bad_input():
    box = ef.scenes.subdivided_box(1)
    with pytest.raises(ValueError, match="up"):
        ef.form_factors(box, [0.5, 0.5, 0.5], [0, 0, 1], remainder=True, up=[0, 0, 0])
    with pytest.raises(ValueError, match="remainder=True"):
        ef.form_factors(box, [0.5, 0.5, 0.5], [0, 0, 1], up=[0, 0, 1])
    with pytest.raises(ValueError, match="row must return"):
        remainder_row(box, [0.5, 0.5, 0.5], lambda s: np.zeros(3), sky_share=0.5)
    with pytest.raises(NumericalError, match="sky"):
        remainder_row(box, [0.5, 0.5, 0.5], lambda s: np.ones(len(s)), sky_share=0.5)


def test_matrix_remainder_written_beside(tmp_path):
    S, H = 2.0, 1.3
    scene = courtyard(S, H)
    M, R = ef.form_factor_matrix(scene, remainder=True, out=tmp_path / "m")
    assert (tmp_path / "m.remainder.npy").exists()
    assert np.array_equal(np.load(tmp_path / "m.remainder.npy"), R)
    # the open part is the roof (above every row's point): sky is each row's value of
    # the roof in the roofed courtyard, and nothing is open below
    roofed = courtyard(S, H, roof=True)
    roof = ef.form_factors(roofed, scene.centroids, scene.normals)[:, -1]
    assert np.abs(R[:, 0] - roof).max() <= 1e-12 and np.all(R[:, 1] == 0)
    # the floor's centre row: 1 minus the walls (Howell)
    F, sky, ground = ef.form_factors(scene, scene.centroids[0], scene.normals[0],
                                     remainder=True)
    assert R[0].tolist() == [sky, ground]
    assert abs(R[0, 0] - (1 - 8 * perpendicular_rect(S / 2, H, S / 2))) <= 1e-12
