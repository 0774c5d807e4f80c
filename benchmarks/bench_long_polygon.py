"""One long polygon in a scene: time and memory per row with and without it (issue 21).

Usage: python benchmarks/bench_long_polygon.py [--rows 6] [--max-vertices 50000]

The procedural office (4,478 quads) plus one round table top given as a single polygon
of 500, 5,000 or 50,000 vertices (radius 0.6 m at desk height, facing up). The same
sampled rows are timed for every scene in one run; the ratio is against the office
without the table. Memory: the tracemalloc peak of one row after the scene's caches are
built (numpy and Python allocations; GEOS's own are not traced). Also the hemicube-256
row (the discrete methods' z-buffer), which used to pad every polygon to the longest.
"""

import argparse
import os
import sys
import time
import tracemalloc

import numpy as np

import exactff as ef
from exactff.methods import Exact

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402


def table_top(k, centre=(4.0, 1.1, 3.0), radius=0.6):
    """A regular k-gon in the plane y = centre[1], facing up (+y)."""
    t = 2 * np.pi * np.arange(k) / k
    P = np.column_stack([centre[0] + radius * np.cos(t), np.full(k, centre[1]),
                         centre[2] + radius * np.sin(t)])
    # counter-clockwise seen from +y: (x, z) must turn clockwise in the x-z plane
    return P[::-1].copy()


def row_time_and_peak(scene, method, rows):
    method.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    ts = []
    for i in rows:
        t = time.perf_counter()
        method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
        ts.append(time.perf_counter() - t)
    tracemalloc.start()
    method.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return float(np.median(ts)), peak


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=6)
    ap.add_argument("--max-vertices", type=int, default=50000)
    args = ap.parse_args()
    print(machine())
    office = ef.scenes.office()
    rows = np.random.default_rng(0).choice(len(office), args.rows, replace=False).tolist()
    base = {}
    print("| long polygon (vertices) | method | median s/row | ratio | row peak (MiB) | "
          "extra peak (MiB) | set-up (s) |")
    print("|---|---|---|---|---|---|---|")
    for k in [0, 500, 5000, 50000]:
        if k > args.max_vertices:
            continue
        t = time.perf_counter()
        scene = office if k == 0 else ef.Scene.from_polygons(
            list(office.polygons) + [table_top(k)], groups=list(office.groups) + ["table"])
        setup = time.perf_counter() - t
        for name, method in (("exact", Exact()), ("hemicube-256", ef.Hemicube(resolution=256))):
            t = time.perf_counter()
            method.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
            first = time.perf_counter() - t
            med, peak = row_time_and_peak(scene, method, rows)
            if k == 0:
                base[name] = (med, peak)
            print(f"| {k} | {name} | {med:.3f} | {med / base[name][0]:.2f} | {peak / 2**20:.1f} | "
                  f"{(peak - base[name][1]) / 2**20:.1f} | {setup + first:.2f} |", flush=True)


if __name__ == "__main__":
    main()
