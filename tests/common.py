"""Scene zoo and closed forms shared by the tests (independent of exactff's kernels)."""

import math
import os

import numpy as np

UP = np.array([0.0, 0.0, 1.0])
ORIGIN = np.zeros(3)


def rect_xy(x0, x1, y0, y1, z, facing_down=True):
    """Axis-aligned rectangle in the plane z, front facing -z (down) or +z."""
    P = np.array([[x0, y0, z], [x0, y1, z], [x1, y1, z], [x1, y0, z]], dtype=float)
    return P if facing_down else P[::-1].copy()


def parallel_rect_corner(a, b, c):
    """Howell's catalogue, plane element to a parallel a x b rectangle at distance c,
    the element's normal through a corner of the rectangle."""
    A, B = a / c, b / c
    return (A / math.sqrt(1 + A * A) * math.atan(B / math.sqrt(1 + A * A))
            + B / math.sqrt(1 + B * B) * math.atan(A / math.sqrt(1 + B * B))) / (2 * math.pi)


def perpendicular_rect(b, h, d):
    """Howell's catalogue, plane element to a rectangle in a perpendicular plane at
    distance d, the element on the line through one edge's end, normal to that plane:
    F = (1 / 2 pi) [atan(1 / Y) - Y / sqrt(X^2 + Y^2) atan(1 / sqrt(X^2 + Y^2))],
    X = h / b, Y = d / b (rectangle b wide, h high, one edge on the element's plane)."""
    X, Y = h / b, d / b
    R = math.sqrt(X * X + Y * Y)
    return (math.atan(1 / Y) - Y / R * math.atan(1 / R)) / (2 * math.pi)


def coaxial_disc(r, h):
    """Plane element to a parallel coaxial disc of radius r at distance h."""
    return r * r / (h * h + r * r)


def coaxial_regular_polygon(n, R, h):
    """Plane element to a coaxial regular n-gon of circumradius R at height h: the
    polar integral of h^2 / (h^2 + rho^2)^2 over 2n right triangles with apothem a,
    F = (n / pi) (a / sqrt(a^2 + h^2)) atan(a tan(pi / n) / sqrt(a^2 + h^2))."""
    a = R * math.cos(math.pi / n)
    s = math.sqrt(a * a + h * h)
    return n / math.pi * a / s * math.atan(a * math.tan(math.pi / n) / s)


def regular_polygon(n, R, z, facing_down=True):
    ang = 2 * math.pi * np.arange(n) / n
    P = np.column_stack([R * np.cos(ang), R * np.sin(ang), np.full(n, float(z))])
    return P[::-1].copy() if facing_down else P


def rotation(axis, angle):
    """Rotation matrix (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def upward_unit_vectors(min_z=0.05):
    """Hypothesis strategy: unit vectors with z > ``min_z`` (z uniform in (min_z, 1],
    azimuth uniform), shrinking towards +z: every example drawn is valid, none is thrown
    away (an early return or ``assume(n[2] > min_z)`` on the whole sphere loses half)."""
    from hypothesis import strategies as st

    def build(z, phi):
        s = math.sqrt(max(0.0, 1.0 - z * z))
        return np.array([s * math.cos(phi), s * math.sin(phi), z])

    return st.builds(build, st.floats(0.0, 1.0 - min_z, exclude_max=True).map(lambda d: 1.0 - d),
                     st.floats(0, 2 * math.pi))


def checkout_env():
    """The environment for a subprocess that must import this checkout's exactff (not
    another one installed in the interpreter) whatever its working directory: the
    checkout's root first on PYTHONPATH."""
    import os

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = os.environ.get("PYTHONPATH")
    return dict(os.environ, PYTHONPATH=root + (os.pathsep + path if path else ""))


def rotations():
    """Hypothesis strategy: rotation matrices (an axis from the sphere and an angle),
    shrinking towards the identity about +z."""
    from hypothesis import strategies as st

    from exactff.testing.strategies import unit_vectors

    return st.builds(rotation, unit_vectors(), st.floats(0, 2 * math.pi))


def register_profiles():
    """The hypothesis profiles: dev (30 examples), ci (60), thorough (1000). Registered
    here, not only in conftest, so that benchmarks importing the tests' helpers see them."""
    from hypothesis import HealthCheck, settings

    settings.register_profile("dev", max_examples=30, deadline=None)
    settings.register_profile("ci", max_examples=60, deadline=None,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("thorough", max_examples=1000, deadline=None,
                              suppress_health_check=[HealthCheck.too_slow])


def examples(n):
    """``max_examples`` for a property test that is slower (``n`` below 30) or cheaper
    (above) than most: ``n`` in the dev profile (30 examples a test), scaled by the
    loaded profile's count over the dev profile's, so every profile runs it in the same
    proportion: twice ``n`` in ci (60), 1000 / 30 times ``n`` in thorough
    (``HYPOTHESIS_PROFILE=thorough``). At least 1."""
    from hypothesis import settings

    register_profiles()
    loaded = settings().max_examples
    dev = settings.get_profile("dev").max_examples
    return max(1, round(n * loaded / dev))


def random_rotation(rng):
    """A uniformly random rotation matrix (from a normalised Gaussian quaternion)."""
    q = rng.normal(size=4)
    a, b, c, d = q / np.linalg.norm(q)
    return np.array([[a*a + b*b - c*c - d*d, 2*(b*c - a*d), 2*(b*d + a*c)],
                     [2*(b*c + a*d), a*a - b*b + c*c - d*d, 2*(c*d - a*b)],
                     [2*(b*d - a*c), 2*(c*d + a*b), a*a - b*b - c*c + d*d]])


#: real files vendored for the tests (sources and licences: tests/data/README.md)
REAL_DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "real")


def real_file_path(name, tmp_dir):
    """The path of the vendored real file ``name`` (tests/data/real), as its reader sees
    it: a gzip-compressed one (``name.gz``) is written out under ``tmp_dir`` first, so
    that ``load_scene`` chooses the reader by the file's own extension."""
    import gzip
    import shutil

    path = os.path.join(REAL_DATA, name)
    if os.path.exists(path):
        return path
    out = os.path.join(tmp_dir, name)
    with gzip.open(path + ".gz", "rb") as src, open(out, "wb") as dst:
        shutil.copyfileobj(src, dst)
    return out


def load_real_file(name, tmp_dir, **options):
    """The scene of the vendored real file ``name`` (``load_scene`` with ``options``)."""
    import exactff as ef

    return ef.load_scene(real_file_path(name, tmp_dir), **options)


def discrete_methods():
    """The discrete methods that rasterise natively, at the resolutions the native and
    compiled z-buffer tests use (odd, even, coarse and fine), by name: factories that
    take the method's options (``native=``, ``backend=``)."""
    import exactff as ef

    return {
        "hemicube-16": lambda **k: ef.Hemicube(resolution=16, **k),
        "hemicube-64": lambda **k: ef.Hemicube(resolution=64, **k),
        "hemicube-130": lambda **k: ef.Hemicube(resolution=130, **k),
        "ppbh-17": lambda **k: ef.DiscretePPBH(resolution=17, **k),
        "ppbh-64": lambda **k: ef.DiscretePPBH(resolution=64, **k),
        "ppbh-101": lambda **k: ef.DiscretePPBH(resolution=101, **k),
        "tetra-15": lambda **k: ef.CubicTetrahedron(resolution=15, **k),
        "tetra-52": lambda **k: ef.CubicTetrahedron(resolution=52, **k),
        "plane-equal_ff": lambda **k: ef.SinglePlane(resolution=48, **k),
        "plane-uniform": lambda **k: ef.SinglePlane(resolution=41, cells="uniform", **k),
        "plane-refined": lambda **k: ef.SinglePlane(resolution=40, cells="uniform_refined",
                                                    refine=3, **k),
        "polar-20x48": lambda **k: ef.PolarPlane(rings=20, sectors=48, **k),
        "polar-31x7": lambda **k: ef.PolarPlane(rings=31, sectors=7, **k),
    }


def small_discrete_methods():
    """One small configuration of each natively rasterising method (property tests),
    by kind: factories that take the method's options."""
    import exactff as ef

    return {"hemicube": lambda **k: ef.Hemicube(resolution=32, **k),
            "ppbh": lambda **k: ef.DiscretePPBH(resolution=45, **k),
            "tetra": lambda **k: ef.CubicTetrahedron(resolution=30, **k),
            "plane": lambda **k: ef.SinglePlane(resolution=30, cells="uniform_refined", **k),
            "polar": lambda **k: ef.PolarPlane(rings=20, sectors=40, **k)}


def pair_parts(scene, i, j):
    """The area row's own culling for the pair (i, j) of a scene: the emitter i and the
    receiver j, each clipped to the front of the other (Pc, Qc), the indices of the
    polygons that may come between them, and the scene's scale."""
    from exactff.area.culling import front_pairs, padded_polygons, pair_blockers

    polys = [np.asarray(p, float) for p in scene.polygons]
    pad = padded_polygons(polys)
    (_, Pc, Qc), = [p for p in front_pairs(polys, i, scene.normals[i], pad) if p[0] == j]
    scale = float(np.ptp(scene.vertices, axis=0).max())
    return Pc, Qc, pair_blockers(pad, i, j, Pc, Qc, scale), scale
