"""Kernel accuracy against mpmath: worst errors of the three kernels on random polygons.

Usage: python benchmarks/accuracy_kernel.py [--polygons 300] [--dps 40]

Random planar polygons (3 to 8 vertices, star-shaped or convex) around a receiver with a
random normal, so that many cross its horizon; the reference is
``exactff.testing.mp_reference.boundary_form_factor`` at ``dps`` digits. Prints the
worst absolute error, the worst error in units of the target ``1e-13 + 1e-12 F``, and
the worst disagreement between Eq. 3 and the sector form.
"""

import argparse
import math

import numpy as np

import exactff as ef
from exactff.kernel import eq3_form_factor, sector_form_factor
from exactff.testing.mp_reference import boundary_form_factor


def random_polygon(rng):
    k = int(rng.integers(3, 9))
    gaps = rng.uniform(0.2, 1.0, k)
    ang = rng.uniform(0, 2 * math.pi) + np.concatenate([[0], np.cumsum(gaps[:-1] / gaps.sum() * 2 * math.pi)])
    r = rng.uniform(0.3, 1.0, k) if rng.random() < 0.5 else np.ones(k)
    P2 = np.column_stack([r * np.cos(ang), r * np.sin(ang)])
    Rm = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    return rng.uniform(-1.5, 1.5, 3) + rng.uniform(0.2, 2.0) * P2 @ Rm[:2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--polygons", type=int, default=300)
    ap.add_argument("--dps", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    worst = {"sector": (0, 0), "eq3": (0, 0), "vectorised": (0, 0)}
    eq3_vs_sector = 0.0
    crossing = received = 0
    for _ in range(args.polygons):
        P = random_polygon(rng)
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        two_sided = bool(rng.random() >= 0.5)
        if abs(ef.unit_normal(P) @ P.mean(axis=0)) < 1e-9:
            continue
        z = P @ n
        crossing += bool(z.min() < 0 < z.max())
        ref = float(boundary_form_factor(np.zeros(3), n, P, two_sided=two_sided, dps=args.dps))
        received += ref > 0
        vals = {
            "sector": sector_form_factor(np.zeros(3), n, P, two_sided=two_sided),
            "eq3": eq3_form_factor(np.zeros(3), n, P, two_sided=two_sided),
            "vectorised": float(ef.point_polygon_form_factors(np.zeros(3), n, [P], two_sided=two_sided)[0]),
        }
        for k, v in vals.items():
            err = abs(v - ref)
            units = err / (1e-13 + 1e-12 * abs(ref))
            worst[k] = (max(worst[k][0], err), max(worst[k][1], units))
        eq3_vs_sector = max(eq3_vs_sector, abs(vals["eq3"] - vals["sector"]))
    print(f"{args.polygons} random polygons ({crossing} crossing the horizon, {received} "
          f"with F > 0), reference mpmath at {args.dps} digits")
    print()
    print("| kernel | worst abs error | worst error / (1e-13 + 1e-12 F) |")
    print("|---|---|---|")
    for k, (e, u) in worst.items():
        print(f"| {k} | {e:.2e} | {u:.3f} |")
    print(f"\nworst |Eq. 3 - sector form| = {eq3_vs_sector:.2e}")


if __name__ == "__main__":
    main()
