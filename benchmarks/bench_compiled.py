"""The compiled visibility core against the Python engine and Hemicube(256), one run.

Usage: python benchmarks/bench_compiled.py [--rows 4] [--cloister-rows 3]

For seeded rows of the procedural office (4,424 polygons) and cloister (80,461): ms per
row of ``Hemicube(resolution=256)`` (the in-run baseline: its compiled z-buffer, and
its numpy rasteriser, ``backend="numpy"``, the baseline before issue 55), of the compiled core alone
(``tolerance=None``: no fallback), of ``Exact(engine="compiled")`` at the default
tolerance (falls back to the Python engine where a bound misses it) and of the Python
engine; the set-up (BSP tree, then the core's convex pieces and boxes); and rows per
second with one and two threads (compiled core alone; the row runs without the GIL; best
of three runs each).
"""

import argparse
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import exactff as ef
from exactff.visibility import compiled_core, scene_bsp

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import best_of, machine, timed  # noqa: E402



def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=4)
    ap.add_argument("--cloister-rows", type=int, default=3)
    a = ap.parse_args()
    print(machine())
    methods = {"hemicube-256": ef.Hemicube(resolution=256),
               "hemicube-256 numpy": ef.Hemicube(resolution=256, backend="numpy"),
               "core alone": ef.Exact(engine="compiled", tolerance=None),
               "compiled": ef.Exact(engine="compiled"),
               "python": ef.Exact(engine="python")}
    for name, scene, k in (("office", ef.scenes.office(), a.rows),
                           ("cloister", ef.scenes.cloister(), a.cloister_rows)):
        _, t_core = timed(lambda: compiled_core(scene))
        _, t_bsp = timed(lambda: scene_bsp(scene))
        print(f"\n{name}: {len(scene)} polygons; set-up of the compiled engine (its BSP "
              f"included) {t_core:.2f} s; the Python engine's BSP {t_bsp:.2f} s")
        rows = np.random.default_rng(0).choice(len(scene), k, replace=False)
        print("| row | " + " | ".join(f"{m} ms" for m in methods)
              + " | core / hemicube | compiled / hemicube | compiled / hemicube numpy"
              " | fallback |")
        print("|---" * (len(methods) + 5) + "|")
        for i in rows:
            p, n = scene.centroids[i], scene.normals[i]
            t, st = {}, {}
            for m, meth in methods.items():
                kw = {"stats": st} if m == "compiled" else {}
                _, t[m] = timed(lambda: meth.point_form_factors(scene, p, n, **kw))
            print(f"| {i} | " + " | ".join(f"{1e3 * t[m]:.1f}" for m in methods)
                  + f" | {t['core alone'] / t['hemicube-256']:.2f}"
                  f" | {t['compiled'] / t['hemicube-256']:.2f}"
                  f" | {t['compiled'] / t['hemicube-256 numpy']:.2f}"
                  f" | {'yes' if st['path'] != 'compiled' else 'no'} |")
        core = methods["core alone"]
        work = [int(i) for i in rows] * 2
        run = lambda i: core.point_form_factors(scene, scene.centroids[i], scene.normals[i])
        # best of three each (the machine is shared: a short run is easily disturbed)
        t1 = best_of(lambda: [run(i) for i in work])
        with ThreadPoolExecutor(2) as pool:
            t2 = best_of(lambda: list(pool.map(run, work)))
        print(f"threads (best of 3 runs of {len(work)} rows): 1: {len(work) / t1:.2f} rows/s, "
              f"2: {len(work) / t2:.2f} rows/s, ratio {t1 / t2:.2f}")


if __name__ == "__main__":
    main()
