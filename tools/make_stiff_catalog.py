"""Build the catalogue of stiff cases and their 60-digit references.

Writes ``exactff/data/stiff_cases.json``: for each named case the float input (point,
normal, polygon vertices, as exact float reprs), ``one_sided``, and the reference form
factor as a 60-digit string. The reference is the mpmath quadrature of the image's
boundary integral (``exactff.testing.mp_reference.boundary_form_factor``, independent of
the library's kernels) at 80 digits, cross-checked against the closed-form sector sum in
mpmath (``exactff.kernel.mp_form_factor``) to 50 digits.

Run: ``python tools/make_stiff_catalog.py`` (about a minute).
"""

import json
import math
import os
import sys

import mpmath as mp
import numpy as np

from exactff.geometry import receiver_frame
from exactff.kernel import point_polygon_form_factor
from exactff.kernel.ladder import mp_sector_value
from exactff.testing.mp_reference import boundary_form_factor

OUT = os.path.join(os.path.dirname(__file__), "..", "exactff", "data", "stiff_cases.json")


def rotation(rng):
    Q, R = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(R))
    return Q if np.linalg.det(Q) > 0 else -Q


def square(s):
    return np.array([[0, 0, 0], [s, 0, 0], [s, s, 0], [0, s, 0]], float)


def place(P_local, point_local, rng, shift=0.0):
    """Move a configuration given in the receiver's frame (normal z) by a random rigid
    motion, so that its float coordinates carry rounding."""
    Rm = rotation(rng)
    t = rng.normal(size=3) * shift
    P = P_local @ Rm.T + t
    p = point_local @ Rm.T + t
    n = np.array([0.0, 0.0, 1.0]) @ Rm.T
    return p, n, P


def facing(P, p):
    """Orient P so that its front faces p."""
    N = np.cross(P[1] - P[0], P[2] - P[0])
    return P if N @ (p - P.mean(axis=0)) > 0 else P[::-1].copy()


def cases():
    rng = np.random.default_rng(20261126)
    out = []
    z = np.zeros(3)
    # tiny polygons at distance 1, tilted
    for s in (1e-3, 1e-5, 1e-7, 1e-9):
        T = receiver_frame(np.array([0.3, -0.5, 0.8]))
        P = (square(s) - s / 2) @ T + [0.2, 0.1, 1.0]
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"tiny_square_{s:.0e}", p, n, P, True))
    # horizon slivers: a 1 x 2 rectangle at height h above the tangent plane
    for h in (1e-4, 1e-6, 1e-8, 1e-10):
        P = np.array([[1, -1, h], [2, -1, h], [2, 1, h], [1, 1, h]], float)
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"horizon_sliver_{h:.0e}", p, n, P, False))
    # points almost on an adjacent wall: floor point at gap g from a wall x = g
    for g in (1e-6, 1e-8, 1e-10, 1e-12):
        P = np.array([[g, -1, 0], [g, 1, 0], [g, 1, 1], [g, -1, 1]], float)
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"adjacent_wall_gap_{g:.0e}", p, n, P, True))
    # edges whose plane passes through (or near) the zenith: in the frame of p, an edge in
    # the plane x = 0, and ones tilted off it by 1e-8 and 1e-14
    for tilt in (0.0, 1e-8, 1e-14):
        P = np.array([[tilt, -0.5, 1.0], [-tilt, 0.5, 1.5], [0.8, 0.3, 1.2]], float)
        P = facing(P, z)
        n = np.array([0.0, 0.0, 1.0])
        out.append((f"edge_through_zenith_{tilt:.0e}", z.copy(), n, P, True))
    # polygons and points far from the origin
    for T in (1e4, 1e5, 1e6, 1e7):
        P = np.array([[-0.5, -0.3, 1], [0.6, -0.4, 1], [0.4, 0.5, 1], [-0.3, 0.4, 1]], float)
        p, n, P = place(facing(P, z), z, rng)
        off = rng.normal(size=3)
        off = T * off / np.linalg.norm(off)
        out.append((f"translated_{T:.0e}", p + off, n, P + off, True))
    # huge polygons close to the point
    P = np.array([[-1e8, -1e8, 1], [1e8, -1e8, 1], [1e8, 1e8, 1], [-1e8, 1e8, 1]], float)
    p, n, P = place(facing(P, z), z, rng)
    out.append(("huge_parallel_1e8", p, n, P, True))
    P = np.array([[1, -1e8, -1e8], [1, 1e8, -1e8], [1, 1e8, 1e8], [1, -1e8, 1e8]], float)
    p, n, P = place(facing(P, z), z, rng)
    out.append(("huge_wall_1e8", p, n, P, True))
    # nearly coplanar receiver and emitter: a plane through a point above p, tilted by
    # alpha from the tangent plane
    for alpha in (1e-6, 1e-10):
        c = math.cos(alpha)
        s_ = math.sin(alpha)
        P = np.array([[-2, -1, 0], [2, -1, 0], [2, 1, 0], [-2, 1, 0]], float)
        P = P @ np.array([[1, 0, 0], [0, c, -s_], [0, s_, c]]).T + [0, 0, 1e-3]
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"nearly_coplanar_{alpha:.0e}", p, n, P, False))
    # very short and very long edges together: a wedge 1 long, 1e-8 wide at its tip
    for w in (1e-8, 1e-12):
        P = np.array([[0.2, 0.1, 1.0], [1.2, 0.1, 1.0], [1.2, 0.1 + w, 1.0]], float)
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"short_and_long_edges_{w:.0e}", p, n, P, True))
    # needle triangles
    for a in (1e-6, 1e-10):
        P = np.array([[-0.5, 0.0, 1.0], [0.5, 0.0, 1.0], [0.0, a, 1.0]], float)
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"needle_triangle_{a:.0e}", p, n, P, True))
    # many-vertex polygons approximating discs
    for k in (360, 2048):
        ang = 2 * np.pi * np.arange(k) / k
        P = np.column_stack([0.7 * np.cos(ang), 0.7 * np.sin(ang), np.full(k, 0.6)])
        p, n, P = place(facing(P, z), z, rng)
        out.append((f"disc_{k}_vertices", p, n, P, True))
    return out


def main():
    data = []
    for name, p, n, P, one_sided in cases():
        with mp.workdps(80):
            ref = boundary_form_factor(p, n, P, two_sided=not one_sided, dps=80)
            check = mp_sector_value(p, n, P, not one_sided, 80)
            if abs(ref - check) > mp.mpf(10) ** -50 * max(abs(ref), mp.mpf(10) ** -300):
                raise SystemExit(f"{name}: quadrature {ref} and closed form {check} disagree")
            ref_s = mp.nstr(ref, 60, min_fixed=1, max_fixed=0)
        dbl = point_polygon_form_factor(p, n, P, two_sided=not one_sided, tolerance=None)
        rel = abs(dbl - float(ref)) / abs(float(ref))
        data.append({
            "name": name,
            "point": [repr(float(c)) for c in p],
            "normal": [repr(float(c)) for c in n],
            "polygon": [[repr(float(c)) for c in v] for v in P],
            "one_sided": one_sided,
            "reference": ref_s,
            "double_rel_error_when_generated": f"{rel:.3e}",
        })
        print(f"{name:32s} F = {ref_s[:22]:22s} double rel error {rel:.1e}", flush=True)
    with open(OUT, "w") as fh:
        json.dump({"schema": "exactff-stiff-cases/1", "digits": 60, "cases": data}, fh,
                  indent=1)
    print(f"{len(data)} cases -> {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
