"""Native z-buffers of the discrete methods against the shared sampling core (issue 17).

Usage: python benchmarks/bench_native.py [--office-rows 3] [--cloister-rows 2]
                                         [--samples 4096,16384,65536,262144,1048576]

Time per row of every discrete method at equal sample counts, with its own
rasterisation (``native=True``, the default) and with the shared core
(``native=False``, the test oracle), on the same rows in one run: the office (all
methods) and sampled cloister rows (the hemicube and discrete PPBH, the paper's Fig. 3).
Monte Carlo stays a ray caster (the shared core is its algorithm). The last columns
compare discrete PPBH with the hemicube, and with the polar plane, at equal samples.
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef

sys.path.insert(0, os.path.dirname(__file__))
from bench_engine import cloister_rows  # noqa: E402
from scenes_bench import machine  # noqa: E402

METHODS = {
    "hemicube": lambda s, native: ef.Hemicube(samples=s, native=native),
    "ppbh": lambda s, native: ef.DiscretePPBH(samples=s, native=native),
    "cubic_tetrahedron": lambda s, native: ef.CubicTetrahedron(samples=s, native=native),
    "single_plane": lambda s, native: ef.SinglePlane(samples=s, native=native),
    "polar_plane": lambda s, native: ef.PolarPlane(samples=s, native=native),
}


def row_time(method, scene, rows):
    i0 = rows[0]
    method.point_form_factors(scene, scene.centroids[i0], scene.normals[i0])   # caches
    ts = []
    for i in rows:
        t = time.perf_counter()
        method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
        ts.append(time.perf_counter() - t)
    return float(np.mean(ts))


def table(name, scene, rows, methods, samples):
    print(f"\n{name}: {len(scene)} polygons, rows {rows}")
    print("| samples | method | cells | native ms | shared core ms | native / shared |")
    print("|---|---|---|---|---|---|")
    native = {}
    for s in samples:
        for m in methods:
            mn, ms = METHODS[m](s, True), METHODS[m](s, False)
            tn, ts = row_time(mn, scene, rows), row_time(ms, scene, rows)
            native[(m, s)] = tn
            print(f"| {s} | {m} | {len(mn.layout())} | {1e3 * tn:.1f} | {1e3 * ts:.1f} | "
                  f"{tn / ts:.2f} |")
    print("\n| samples | ppbh / hemicube (native) |" +
          (" ppbh / polar plane (native) |" if "polar_plane" in methods else ""))
    print("|---|---|" + ("---|" if "polar_plane" in methods else ""))
    for s in samples:
        line = f"| {s} | {native[('ppbh', s)] / native[('hemicube', s)]:.2f} |"
        if "polar_plane" in methods:
            line += f" {native[('ppbh', s)] / native[('polar_plane', s)]:.2f} |"
        print(line)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--office-rows", type=int, default=3)
    ap.add_argument("--cloister-rows", type=int, default=2)
    ap.add_argument("--samples", default="4096,16384,65536,262144,1048576")
    a = ap.parse_args()
    samples = [int(x) for x in a.samples.split(",")]
    print(machine())
    office = ef.scenes.office()
    rows = np.random.default_rng(0).choice(len(office), a.office_rows, replace=False).tolist()
    table("office", office, rows, list(METHODS), samples)
    cloister = ef.scenes.cloister()
    rows = cloister_rows(cloister, 1)[:a.cloister_rows]
    table("cloister", cloister, rows, ["hemicube", "ppbh"], samples)


if __name__ == "__main__":
    main()
