"""Spherical rows against plane rows on the office (issue 31): time per row.

Usage: python benchmarks/bench_sphere.py [--points 10] [--n 4428] [--seed 0]

Viewpoints drawn uniformly in the office's free space (outside the furniture's boxes);
each is timed as a spherical row (``sphere_form_factors``, exact: the whole sphere in
one row of the compiled core, or two hemispheres through the Python engine's clipper,
or Monte Carlo over the sphere with 65,536 rays) and as a plane row facing up
(``form_factors``, the compiled core and the Python engine). Caches (BSP tree, flat
arrays) are built before timing. Also printed: the largest deviation of a spherical
row's sum from 1, the largest bound, the largest difference between the two engines'
spherical rows, and the ratio of issue 52 (compiled spherical row over compiled plane
row; goal ``--goal``, 1.5: printed, not enforced).
"""

import argparse
import time

import numpy as np

import exactff as ef


def free_points(scene_solids, k, rng):
    out = []
    while len(out) < k:
        x = rng.uniform([0.2, 0.2, 0.2], [7.8, 2.6, 5.8])
        if not any(np.all((x > lo) & (x < hi)) for lo, hi, _ in scene_solids):
            out.append(x)
    return np.array(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=10)
    ap.add_argument("--n", type=int, default=4428)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--goal", type=float, default=1.5)
    a = ap.parse_args()
    office = ef.scenes.office(a.n)
    P = free_points(ef.scenes.office_solids(), a.points, np.random.default_rng(a.seed))
    up = [0.0, 1.0, 0.0]
    python = ef.Exact(engine="python")
    ef.sphere_form_factors(office, P[0])
    ef.sphere_form_factors(office, P[0], method=python)
    ef.form_factors(office, P[0], up)
    ef.form_factors(office, P[0], up, method=python)

    def per_row(f):
        t0 = time.perf_counter()
        r = f()
        return (time.perf_counter() - t0) / len(P), r

    ts, (S, E) = per_row(lambda: ef.sphere_form_factors(office, P, error=True))
    tsp, (Sp, Ep) = per_row(lambda: ef.sphere_form_factors(office, P, error=True,
                                                           method=python))
    tc, _ = per_row(lambda: ef.form_factors(office, P, up))
    tp, _ = per_row(lambda: ef.form_factors(office, P, up, method=python))
    tm, _ = per_row(lambda: ef.sphere_form_factors(office, P, method="monte_carlo",
                                                   samples=65536))
    print(f"office ({len(office)} polygons), {len(P)} points")
    print(f"sphere_form_factors exact        {ts:.3f} s/row (compiled, whole sphere)")
    print(f"sphere_form_factors exact        {tsp:.3f} s/row (python, two hemispheres)")
    print(f"sphere_form_factors monte_carlo  {tm:.3f} s/row (65,536 rays)")
    print(f"form_factors exact (compiled)    {tc:.3f} s/row")
    print(f"form_factors exact (python)      {tp:.3f} s/row")
    print(f"sphere rows: |sum - 1| <= {np.abs(S.sum(axis=1) - 1).max():.1e}, "
          f"largest bound {E.max():.1e}, largest row bound sum {E.sum(axis=1).max():.1e}")
    print(f"engines: largest |compiled - python| {np.abs(S - Sp).max():.1e}, "
          f"largest python bound {Ep.max():.1e}")
    r = ts / tc
    print(f"goal: sphere row / plane row (compiled) = {r:.2f} (goal <= {a.goal}): "
          f"{'met' if r <= a.goal else 'MISSED'}; python sphere row / compiled one = "
          f"{tsp / ts:.1f}")


if __name__ == "__main__":
    main()
