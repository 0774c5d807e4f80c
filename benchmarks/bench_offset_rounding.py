"""What the offsets' rounding term of the point kernel's estimate costs
(``kernel.sector._offset_rounding``, ``docs/explanation/robustness.md``).

Usage: python benchmarks/bench_offset_rounding.py [--k 16] [--rows 16] [--repeat 3]

Rows of the closed ``subdivided_box(k)`` (a convex enclosure: the unoccluded kernel
with its ladder, default tolerance 1e-12) and unoccluded rows of the office (no
tolerance, the double sums alone), with the term and, as the baseline measured in the
same run, without it (the kernel's callers patched to leave it out). Prints the best
time a row, the ratio, the largest estimate, the values above 1e-12 of their value in
double (those the ladder sends to long double) and, for the box, the worst
``|row sum - 1|``.
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
import exactff.area.points as points
import exactff.kernel.ladder as ladder
import exactff.kernel.point as point
from exactff.kernel import sector
from exactff.kernel.flat import flat_polygons

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402

WITH = sector.clipped_sector_sums


def without(*args, rounded_offsets=False, **kwargs):
    """The sums as before the term: the offsets taken as exact."""
    return WITH(*args, **kwargs)


def use(fn):
    for module in (point, ladder, points):
        module.clipped_sector_sums = fn


def timed_rows(run, rows, repeat):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = [run(i) for i in rows]
        best = min(best, (time.perf_counter() - t0) / len(rows))
    return best, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--k", type=int, default=16)
    ap.add_argument("--rows", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(machine())
    box = ef.scenes.subdivided_box(args.k)
    office = ef.scenes.office()
    flat = flat_polygons(office)
    exact = ef.Exact()
    cases = [
        (f"subdivided_box({args.k}), {len(box)} quads, Exact() (tolerance 1e-12)", box,
         lambda i: exact.point_form_factors(box, box.centroids[i], box.normals[i], error=True)),
        (f"office, {len(office)} polygons, unoccluded, no tolerance", office,
         lambda i: point.unoccluded_row(flat, office.centroids[i], office.normals[i],
                                        tolerance=None, return_error=True)),
    ]
    print()
    print("| rows of | term | ms a row | with / without | max estimate | values over 1e-12 F, all rows "
          "(double sums) | worst abs(row sum - 1) |")
    print("|---|---|---|---|---|---|---|")
    for name, scene, run in cases:
        rows = np.linspace(0, len(scene) - 1, args.rows).astype(int)
        run(rows[0])                    # the scene's caches, built before any timing
        base = None
        for label, fn in (("without", without), ("with", WITH)):
            use(fn)
            t, out = timed_rows(run, rows, args.repeat)
            E = max(float(e.max()) for _, e in out)
            # a closed enclosure's rows sum to 1; the office's unoccluded rows do not
            sums = (f"{max(abs(float(f.sum()) - 1) for f, _ in out):.1e}" if scene is box
                    else "-")
            over = sum(int(np.sum(e > 1e-12 * f)) for f, e in
                       (point.unoccluded_row(flat_polygons(scene), scene.centroids[i],
                                             scene.normals[i], tolerance=None,
                                             return_error=True) for i in rows))
            base = t if base is None else base
            print(f"| {name} | {label} | {t * 1e3:.2f} | {t / base:.2f} | {E:.1e} | {over} "
                  f"| {sums} |", flush=True)
    use(WITH)


if __name__ == "__main__":
    main()
