"""Refinement of visible pieces (issue 18): accuracy on the sliver family, and its cost.

Usage: python benchmarks/bench_refinement.py [--office-rows 8] [--cloister-per-group 1]

1. The sliver family: a unit receiver at distance 2 seen through a gap between two
   occluders at distance 1, gap widths 1e-3 to 1e-12, eight random rigid motions each
   (and the sliver tilted across a chart seam); relative error against the 50-digit
   reference of tests/test_refinement.py, with the refinement (tolerance 1e-12) and
   without it (tolerance None: the clipper's double-precision vertices).
2. Cost per row on the office and on sampled cloister rows: ``Exact()`` (tolerance 1e-12,
   refinement where a value's bound misses it) against ``Exact(tolerance=None)`` (no
   refinement, no escalation), same rows, one run; how many rings went to long double
   and to mpmath; and ``Exact(tolerance=1e-9)``.
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
from exactff.visibility import visible_form_factors

HERE = os.path.dirname(__file__)
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests"))
from bench_engine import cloister_rows  # noqa: E402
from scenes_bench import machine, timed  # noqa: E402
from test_refinement import sliver_reference, sliver_scene  # noqa: E402


def sliver_table(seeds=8):
    print("| gap | tilt | rel. error refined (min .. max) | rel. error unrefined | bound holds |")
    print("|---|---|---|---|---|")
    for tilt in (0.0, 0.8):
        for gap in (1e-3, 1e-6, 1e-9, 1e-12):
            e1, e0, ok = [], [], True
            for s in range(seeds):
                polys, p, n = sliver_scene(gap, s, tilt)
                scene = ef.Scene.from_polygons(polys)
                ref = sliver_reference(polys, p, n)
                F, E = visible_form_factors(scene, p, n, tolerance=1e-12, error=True)
                F0 = visible_form_factors(scene, p, n, tolerance=None)
                e1.append(abs(F[0] - ref) / ref)
                e0.append(abs(F0[0] - ref) / ref)
                ok &= bool(abs(F[0] - ref) <= E[0] + 1.2e-16 * ref)
            print(f"| {gap:.0e} | {tilt} | {min(e1):.1e} .. {max(e1):.1e} | "
                  f"{min(e0):.1e} .. {max(e0):.1e} | {ok} |")



def cost_table(name, scene, rows):
    p0, n0 = scene.centroids[rows[0]], scene.normals[rows[0]]
    visible_form_factors(scene, p0, n0)     # caches (BSP)
    print(f"\n{name}: {len(scene)} polygons, {len(rows)} rows")
    print("| row | unrefined s | refined s | ratio | tol 1e-9 s | ratio | rings ld | rings mp |"
          " max E/F refined |")
    print("|---|---|---|---|---|---|---|---|---|")
    ratios, ratios9 = [], []
    for i in rows:
        p = scene.centroids[i] + 1e-9 * scene.normals[i]
        n = scene.normals[i]
        _, t0 = timed(lambda: visible_form_factors(scene, p, n, tolerance=None))
        st = {}
        (F, E), t1 = timed(lambda: visible_form_factors(scene, p, n, tolerance=1e-12,
                                                        error=True, stats=st))
        _, t9 = timed(lambda: visible_form_factors(scene, p, n, tolerance=1e-9))
        ratios.append(t1 / t0)
        ratios9.append(t9 / t0)
        rel = float(np.max(np.where(F > 0, E / np.where(F > 0, F, 1), 0)))
        print(f"| {i} | {t0:.3f} | {t1:.3f} | {t1 / t0:.2f} | {t9:.3f} | {t9 / t0:.2f} | "
              f"{st['refined_rings']} | {st['refined_rings_mp']} | {rel:.1e} |")
    print(f"median ratio refined / unrefined: {np.median(ratios):.2f} (tolerance 1e-12), "
          f"{np.median(ratios9):.2f} (tolerance 1e-9)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--office-rows", type=int, default=8)
    ap.add_argument("--cloister-per-group", type=int, default=1)
    a = ap.parse_args()
    print(machine())
    sliver_table()
    office = ef.scenes.office()
    rows = np.random.default_rng(0).choice(len(office), a.office_rows, replace=False).tolist()
    cost_table("office", office, rows)
    cloister = ef.scenes.cloister()
    cost_table("cloister", cloister, cloister_rows(cloister, a.cloister_per_group))


if __name__ == "__main__":
    main()
