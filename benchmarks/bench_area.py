"""Area-to-area form factors (issue 15): accuracy and time of the unoccluded pair against
a 30-point Gauss rule per edge pair, the time of occluded values at several tolerances,
and a closed cube's full area matrix.

Usage: python benchmarks/bench_area.py [--cube-k 8]

1. Unoccluded pairs (Howell's C-11 parallel opposed squares and C-14 perpendicular
   rectangles sharing an edge, references in 40-digit mpmath): relative error and time
   per pair of ``polygon_form_factor`` and of the contour integral with a 30 x 30
   Gauss-Legendre rule per edge pair (the peer tools' rule; on a shared edge the inner
   rule has 31 nodes, so that no node pair coincides and ``ln 0`` is never taken).
2. Occluded values (issue 15's two references): time, error and estimate of
   ``area_form_factors`` at tolerances 1e-6, 1e-9, 1e-12.
3. A closed cube, ``subdivided_box(k)`` (6 k^2 quads; every pair unoccluded): the full
   area matrix, its time per pair and its worst row-sum error.
"""

import argparse
import os
import sys
import time

import mpmath as mp
import numpy as np
from scipy.special import roots_legendre

import exactff as ef

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from scenes_bench import machine  # noqa: E402
from test_area import howell_parallel, howell_perpendicular, parallel_pair, perpendicular_pair  # noqa: E402,E501
from test_area import OCCLUDED_REFERENCES, _square  # noqa: E402


def gauss_contour(P, Q, n=30):
    """F(P -> Q) by the contour integral with an n x n Gauss-Legendre rule per edge pair."""
    x, w = roots_legendre(n)
    s, w = 0.5 * (x + 1), 0.5 * w
    x2, w2 = roots_legendre(n + 1)
    s2, w2 = 0.5 * (x2 + 1), 0.5 * w2          # inner nodes never meet the outer ones
    A = float(np.linalg.norm(ef.area_vector(P)))
    eP, eQ = np.roll(P, -1, 0) - P, np.roll(Q, -1, 0) - Q
    total = 0.0
    for a, ea in zip(P, eP):
        X = a + s[:, None] * ea
        for b, eb in zip(Q, eQ):
            Y = b + s2[:, None] * eb
            r = np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=2)
            total += (ea @ eb) * (w @ np.log(r) @ w2)
    return total / (2 * np.pi * A)


def timed(f, *a, repeat=20):
    t0 = time.perf_counter()
    for _ in range(repeat):
        v = f(*a)
    return v, (time.perf_counter() - t0) / repeat


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cube-k", type=int, default=8)
    args = ap.parse_args()
    print(machine())
    print()
    cases = [("C-11 squares 1 apart", parallel_pair(1, 1, 1), howell_parallel(1, 1, 1)),
             ("C-11 10 x 10 at 0.1", parallel_pair(10, 10, 0.1), howell_parallel(10, 10, 0.1)),
             ("C-14 unit, common edge", perpendicular_pair(1, 1, 1), howell_perpendicular(1, 1, 1)),
             ("C-14 0.1 x 1 / 2 x 1", perpendicular_pair(0.1, 1, 2), howell_perpendicular(0.1, 1, 2))]
    print("| pair | exactff rel. error | exactff ms / pair | Gauss 30 rel. error | Gauss 30 ms / pair | time ratio |")
    print("|---|---|---|---|---|---|")
    for name, (P, Q), ref in cases:
        v1, t1 = timed(ef.polygon_form_factor, P, Q)
        v2, t2 = timed(gauss_contour, P, Q)
        print(f"| {name} | {abs(v1 - ref) / ref:.1e} | {t1 * 1e3:.2f} | {abs(v2 - ref) / ref:.1e} "
              f"| {t2 * 1e3:.2f} | {t1 / t2:.2f} |")
    print()
    print("| occluded reference | tolerance | value | error | estimate | s / value |")
    print("|---|---|---|---|---|---|")
    for k, (plate, ref) in enumerate(OCCLUDED_REFERENCES):
        scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
        for tol in (1e-6, 1e-9, 1e-12):
            t0 = time.perf_counter()
            F, E = ef.area_form_factors(scene, rows=[0], tolerance=tol, error=True)
            dt = time.perf_counter() - t0
            print(f"| {ref} | {tol:g} | {F[0, 1]:.15f} | {abs(F[0, 1] - ref):.1e} "
                  f"| {E[0, 1]:.1e} | {dt:.1f} |")
    print()
    cube = ef.scenes.subdivided_box(args.cube_k)
    t0 = time.perf_counter()
    F, E = ef.area_form_factors(cube, tolerance=1e-9, error=True)
    dt = time.perf_counter() - t0
    n = len(cube)
    A = cube.areas
    recip = np.abs(A[:, None] * F - (A[:, None] * F).T).max()
    print(f"closed cube, {n} quads: full area matrix in {dt:.1f} s "
          f"({dt / (n * n) * 1e6:.0f} us per pair); worst |row sum - 1| "
          f"{np.abs(F.sum(axis=1) - 1).max():.1e}; worst reciprocity {recip:.1e}; "
          f"largest estimate {E.max():.1e}")
    print(f"estimated for 1,536 quads (k = 16) at the same cost per pair: "
          f"{dt / (n * n) * 1536 ** 2 / 60:.0f} min")


if __name__ == "__main__":
    main()
