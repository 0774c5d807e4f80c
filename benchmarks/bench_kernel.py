"""Kernel benchmark: microseconds per polygon, scalar vs vectorised, on random quads.

Usage: python benchmarks/bench_kernel.py [--quads 10000] [--repeat 5]

Prints a table: path, polygons, best time, microseconds per quad, and the ratio
against the scalar path measured in the same run. The vectorised rows run in plain
double precision (``tolerance=None``) except "escalation on" (the default 1e-12); the
scalar paths validate the polygon and escalate as by default.
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

import exactff as ef
from exactff.kernel import eq3_form_factor, sector_form_factor

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import best_of  # noqa: E402


def random_quads(n, seed=0):
    """Planar convex quads of size ~0.2 around random points within 2 of the origin,
    facing random directions (about half face the receiver; some cross its horizon)."""
    rng = np.random.default_rng(seed)
    base = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float) * 0.1
    out = np.empty((n, 4, 3))
    for i in range(n):
        Rm = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        c = rng.uniform(-2, 2, size=3)
        out[i] = c + base @ Rm[:2]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quads", type=int, default=10_000)
    ap.add_argument("--scalar-quads", type=int, default=2_000,  # noqa: E501
                    help="quads timed on the (slow) scalar paths")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    quads = random_quads(args.quads)
    p, n = np.zeros(3), np.array([0.0, 0.0, 1.0])
    t = time.perf_counter()
    scene = ef.Scene.from_polygons(list(quads))
    t_build = time.perf_counter() - t
    ef.point_polygon_form_factors(p, n, scene)  # warm the flat-array cache

    ns = args.scalar_quads
    rows = []
    t_sector = best_of(lambda: [sector_form_factor(p, n, q) for q in quads[:ns]], max(1, args.repeat // 2))
    t_eq3 = best_of(lambda: [eq3_form_factor(p, n, q) for q in quads[:ns]], 1)
    t_vec = best_of(lambda: ef.point_polygon_form_factors(p, n, scene, tolerance=None), args.repeat)
    t_vec2 = best_of(lambda: ef.point_polygon_form_factors(p, n, scene, two_sided=True,
                                                        tolerance=None), args.repeat)
    t_esc = best_of(lambda: ef.point_polygon_form_factors(p, n, scene, two_sided=True), args.repeat)
    F2, err2 = ef.point_polygon_form_factors(p, n, scene, two_sided=True, tolerance=None,
                                             error=True)
    flagged = int(np.sum(err2 > 1e-12 * F2))
    us_sector = t_sector / ns * 1e6
    rows.append(("scalar sector form", ns, t_sector, us_sector))
    rows.append(("scalar Eq. 3", ns, t_eq3, t_eq3 / ns * 1e6))
    rows.append(("vectorised, one-sided", args.quads, t_vec, t_vec / args.quads * 1e6))
    rows.append(("vectorised, two-sided", args.quads, t_vec2, t_vec2 / args.quads * 1e6))
    rows.append(("two-sided, escalation on", args.quads, t_esc, t_esc / args.quads * 1e6))

    F = ef.point_polygon_form_factors(p, n, scene, two_sided=True)
    print(f"machine: {platform.machine()}, {platform.processor() or '?'}, "
          f"python {platform.python_version()}, numpy {np.__version__}")
    print(f"escalation (tolerance 1e-12, two-sided): {flagged} of {np.count_nonzero(F2)} "
          f"values flagged by the double-precision error estimate")
    print(f"scene build (validation) for {args.quads} quads: {t_build:.3f} s "
          f"({t_build / args.quads * 1e6:.1f} us per quad); "
          f"{np.count_nonzero(F)} quads receive (two-sided)")
    print()
    print(f"| {'path':24s} | {'polygons':>8s} | {'time (s)':>9s} | {'us / quad':>9s} | {'speed-up vs scalar':>18s} |")
    print(f"|{'-' * 26}|{'-' * 10}|{'-' * 11}|{'-' * 11}|{'-' * 20}|")
    for name, count, secs, us in rows:
        print(f"| {name:24s} | {count:8d} | {secs:9.4f} | {us:9.3f} | {us_sector / us:18.1f} |")


if __name__ == "__main__":
    main()
