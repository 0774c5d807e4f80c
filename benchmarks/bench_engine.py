"""Visibility-engine benchmark: time per row, BSP build, fragments, peak memory.

Usage: python benchmarks/bench_engine.py [--quick] [--rows 40]

Cases: the open and the closed Cornell box (full matrices); closed cubes with k x k quads
per face, N = 1,536 and N = 6,144 (full matrices, convex: the clipper is skipped), also
timed with the shortcuts off on a sample of rows as the in-run baseline; and a furnished
room of about 4,300 polygons and the procedural office of shared/scenes (4,478 quads;
sampled rows, occluded). Memory: the tracemalloc
peak of one row (Python and numpy allocations; GEOS allocations are not counted), and
the process's peak resident set at the end (it includes the 6,144 x 6,144 matrix).
"""

import argparse
import os
import platform
import resource
import sys
import time
import tracemalloc

import numpy as np

import exactff as ef
from exactff.methods import Exact
from exactff.visibility import build_bsp

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import furnished_room  # noqa: E402


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def row_peak_memory(scene, method, i):
    """tracemalloc peak (bytes) of one row, after the scene's caches are built."""
    method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
    tracemalloc.start()
    method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the N = 6,144 cube")
    ap.add_argument("--rows", type=int, default=40, help="sampled rows of the furnished room")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, python "
          f"{platform.python_version()}, numpy {np.__version__}")
    rows = []

    def case(name, scene, row_ids=None, method=Exact(), note=""):
        t = time.perf_counter()
        tree = build_bsp(scene)
        t_bsp = time.perf_counter() - t
        M, dt = timed(lambda: ef.form_factor_matrix(scene, rows=row_ids, method=method))
        peak = row_peak_memory(scene, method, 0 if row_ids is None else row_ids[0])
        n_rows = M.shape[0]
        per_row = []
        if row_ids is not None:
            # per-row times for the median
            for i in row_ids[: min(len(row_ids), 40)]:
                t = time.perf_counter()
                method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
                per_row.append(time.perf_counter() - t)
        med = np.median(per_row) if per_row else dt / n_rows
        sums = M.sum(axis=1)
        rows.append((name, len(scene), len(tree.fragments), tree.splits, t_bsp, n_rows, dt,
                     dt / n_rows, med, peak / 2**20, sums.min(), sums.max(), note))
        return dt / n_rows

    case("Cornell box (open)", ef.scenes.cornell_box())
    case("Cornell box (closed)", ef.scenes.cornell_box(closed=True))
    cube16 = ef.scenes.subdivided_box(16)
    per_fast = case("cube k=16 (N=1,536)", cube16)
    sample = np.random.default_rng(0).choice(len(cube16), 24, replace=False)
    per_slow = case("cube k=16, shortcuts off", cube16, sample, Exact(shortcuts=False),
                    "baseline")
    if not args.quick:
        case("cube k=32 (N=6,144)", ef.scenes.subdivided_box(32))
    office = ef.scenes.office()
    case("office (procedural, spec)", office,
         np.random.default_rng(0).choice(len(office), args.rows, replace=False))
    room = furnished_room()
    ids = np.random.default_rng(1).choice(len(room), args.rows, replace=False)
    case("furnished room", room, ids)
    case("furnished room, shortcuts off", room, ids[:10], Exact(shortcuts=False), "baseline")

    print()
    print("| case | polygons | fragments | splits | BSP build (s) | rows | total (s) | "
          "mean s/row | median s/row | row peak memory (MiB) | row sum min | row sum max |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        name, n, nf, sp, tb, nr, tot, mean, med, mem, smin, smax, note = r
        print(f"| {name} | {n} | {nf} | {sp} | {tb:.3f} | {nr} | {tot:.3f} | {mean:.5f} | "
              f"{med:.5f} | {mem:.1f} | {smin:.15f} | {smax:.15f} |")
    print(f"\ncube k=16: the convex-scene shortcut is {per_slow / per_fast:.0f} x faster per "
          f"row than the clipper on the same rows")
    print(f"peak resident set of the process: "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
