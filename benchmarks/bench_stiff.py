"""Escalation benchmark: how often double precision is not enough, and what it costs.

Usage: python benchmarks/bench_stiff.py [--rows 40]

1. An ordinary room: the unoccluded rows of the furnished room (4,320 polygons) from
   sampled centroids, and the exact matrix of the closed cube k = 16 (convex path):
   fraction of polygon values escalated at the default tolerance (1e-12) and the time
   against plain double precision (tolerance=None), measured in the same run.
2. The stiff catalogue: per case, escalated or not, time with and without escalation,
   worst relative error against the 60-digit references with and without escalation.
"""

import argparse
import os
import sys

import mpmath as mp
import numpy as np

import exactff as ef
from exactff.catalog import stiff_cases
from exactff.kernel import flat_polygons, unoccluded_row

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import best_of, furnished_room  # noqa: E402

TOL = 1e-12


def paired(f0, f1, k=7):
    """Best times of f0 and f1, measured alternately (the machine is shared and noisy)."""
    t0 = t1 = np.inf
    f0()
    f1()
    for _ in range(k):
        t0 = min(t0, best_of(f0, 1))
        t1 = min(t1, best_of(f1, 1))
    return t0, t1


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=40)
    args = ap.parse_args()

    print("| scene | rows | polygon values | escalated | fraction | time double (s) | "
          "time with escalation (s) | overhead |")
    print("|---|---|---|---|---|---|---|---|")
    for label, gap in (("furnished room, unoccluded rows", 0.0),
                       ("same, shelves 1e-9 off the wall", 1e-9)):
        room = furnished_room(shelf_gap=gap)
        flat = flat_polygons(room)
        ids = np.random.default_rng(3).choice(len(room), args.rows, replace=False)
        esc = vals = 0
        for i in ids:
            F, err = unoccluded_row(flat, room.centroids[i], room.normals[i],
                                    return_error=True)
            live = F > 0
            vals += int(live.sum())
            esc += int((err[live] > TOL * F[live]).sum())
        t0, t1 = paired(
            lambda: [unoccluded_row(flat, room.centroids[i], room.normals[i]) for i in ids],
            lambda: [unoccluded_row(flat, room.centroids[i], room.normals[i], tolerance=TOL)
                     for i in ids])
        print(f"| {label} | {len(ids)} | {vals} | {esc} | {esc / vals:.2e} | {t0:.3f} | "
              f"{t1:.3f} | {t1 / t0 - 1:+.1%} |")
    cube = ef.scenes.subdivided_box(16)
    ef.form_factor_matrix(cube, rows=[0])
    t0, t1 = paired(lambda: ef.form_factor_matrix(cube, method=ef.Exact(tolerance=None)),
                    lambda: ef.form_factor_matrix(cube, method=ef.Exact()), 3)
    flatc = flat_polygons(cube)
    esc = vals = 0
    for i in range(len(cube)):
        F, err = unoccluded_row(flatc, cube.centroids[i], cube.normals[i], return_error=True)
        live = F > 0
        vals += int(live.sum())
        esc += int((err[live] > TOL * F[live]).sum())
    print(f"| closed cube k=16, exact matrix | {len(cube)} | {vals} | {esc} | "
          f"{esc / vals:.2e} | {t0:.3f} | {t1:.3f} | {t1 / t0 - 1:+.1%} |")

    print()
    print("| case | escalated | rel. error, double | rel. error, escalated | "
          "time double (ms) | time escalated (ms) |")
    print("|---|---|---|---|---|---|")
    worst_d = worst_e = 0.0
    n_esc = 0
    tot_d = tot_e = 0.0
    cases = stiff_cases()
    for c in cases:
        args_ = (c.point, c.normal, c.polygon)
        kw = {"two_sided": c.two_sided}
        Fd, est = ef.point_polygon_form_factor(*args_, tolerance=None, error=True, **kw)
        td = best_of(lambda: ef.point_polygon_form_factor(*args_, tolerance=None, **kw))
        te = best_of(lambda: ef.point_polygon_form_factor(*args_, **kw))
        Fe = ef.point_polygon_form_factor(*args_, **kw)
        ref = mp.mpf(c.reference)
        rd = float(abs(mp.mpf(Fd) - ref) / ref)
        re = float(abs(mp.mpf(Fe) - ref) / ref)
        escalated = est > TOL * Fd
        n_esc += escalated
        worst_d, worst_e = max(worst_d, rd), max(worst_e, re)
        tot_d += td
        tot_e += te
        print(f"| {c.name} | {'yes' if escalated else 'no'} | {rd:.1e} | {re:.1e} | "
              f"{td * 1e3:.2f} | {te * 1e3:.2f} |")
    print(f"\ncatalogue: {len(cases)} cases, {n_esc} escalated; worst relative error "
          f"{worst_d:.1e} in double, {worst_e:.1e} with escalation; total time "
          f"{tot_d * 1e3:.1f} ms double, {tot_e * 1e3:.1f} ms with escalation")


if __name__ == "__main__":
    main()
