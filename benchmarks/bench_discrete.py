"""Discrete methods: time per row and error against the exact method, by sample count.

Usage: python benchmarks/bench_discrete.py [--rows 8] [--samples 4096 16384 65536 262144 1048576]

On the furnished room of about 4,300 polygons (benchmarks/scenes_bench.py), for each
method and sample count: the median time per row over the sampled rows (the layout is
built before timing), and the mean / max absolute error over all coefficients of those
rows against the exact method. The exact rows' own time is the first line.
"""

import argparse
import os
import platform
import sys
import time

import numpy as np

import exactff as ef

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import furnished_room  # noqa: E402

METHODS = ["ppbh", "hemicube", "cubic_tetrahedron", "single_plane", "polar_plane",
           "monte_carlo"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=8)
    ap.add_argument("--samples", type=int, nargs="+",
                    default=[4096, 16384, 65536, 262144, 1048576])
    args = ap.parse_args()
    scene = furnished_room()
    rows = np.random.default_rng(2).choice(len(scene), args.rows, replace=False)
    P, N = scene.centroids[rows], scene.normals[rows]
    exact = ef.Exact()
    exact.point_form_factors(scene, P[0], N[0])  # build the caches
    times = []
    ref = []
    for p, n in zip(P, N):
        t = time.perf_counter()
        ref.append(exact.point_form_factors(scene, p, n))
        times.append(time.perf_counter() - t)
    ref = np.array(ref)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}, numpy {np.__version__}; scene: {len(scene)} "
          f"polygons, {args.rows} rows")
    print()
    print("| method | samples (asked) | cells | median s/row | mean abs error | max abs error | "
          "mean row-sum error |")
    print("|---|---|---|---|---|---|---|")
    print(f"| exact | - | - | {np.median(times):.4f} | 0 | 0 | - |")
    table = {}
    for name in METHODS:
        for s in args.samples:
            m = ef.methods.resolve(name, samples=s)
            m.layout()
            t_rows, F = [], []
            for p, n in zip(P, N):
                t = time.perf_counter()
                F.append(m.point_form_factors(scene, p, n))
                t_rows.append(time.perf_counter() - t)
            F = np.array(F)
            err = np.abs(F - ref)
            med = float(np.median(t_rows))
            table[name, s] = med
            print(f"| {name} | {s} | {m.samples} | {med:.4f} | {err.mean():.2e} | "
                  f"{err.max():.2e} | {np.abs(F.sum(1) - ref.sum(1)).mean():.2e} |",
                  flush=True)
    print()
    print("discrete PPBH / hemicube time per row at equal samples: " + ", ".join(
        f"{s}: {table['ppbh', s] / table['hemicube', s]:.2f}" for s in args.samples))


if __name__ == "__main__":
    main()
