"""The unoccluded area form factor in closed form (issue 30, item 1) against the tanh-sinh
contour rule it replaced: accuracy against mpmath and speed per pair.

Accuracy: Howell's catalogue (parallel and perpendicular rectangles, with the 10 x 0.01
strips and the 1e-3 / 1e3 rectangles), and random facing pairs (tests/test_closed_form.py's
strategy) against the double contour integral in mpmath (40 digits). Speed: one row of
``scenes.subdivided_box(16)`` (1,536 quads, closed), ``unoccluded_pairs`` over all
receivers against ``_contour_tanh_sinh`` per pair (process time, one run each).

Run: ``python benchmarks/bench_closed_form.py [n_random]`` (default 200).
"""

import cProfile
import os
import pstats
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import exactff as ef                                                  # noqa: E402
from exactff.area.closed_form import ClosedFormCounts, unoccluded_pairs  # noqa: E402
from exactff.area.contour_rule import contour_tanh_sinh               # noqa: E402
from hypothesis import given, settings                                # noqa: E402
from test_area import (howell_parallel, howell_perpendicular,         # noqa: E402
                       parallel_pair, perpendicular_pair)
from test_closed_form import facing_pairs, mp_contour_form_factor     # noqa: E402


def accuracy(n_random):
    howell = ([("parallel %g x %g, %g apart" % c, parallel_pair(*c), howell_parallel(*c))
               for c in [(1, 1, 1), (1, 2, 0.5), (3, 0.2, 1), (0.01, 0.01, 1), (10, 10, 0.1),
                         (100, 1, 1), (2, 7, 3)]]
              + [("perpendicular %g, %g, %g" % c, perpendicular_pair(*c), howell_perpendicular(*c))
                 for c in [(1, 1, 1), (2, 1, 0.5), (0.1, 3, 1)]])
    extreme = [("strips 10 x 0.01, 3 apart", parallel_pair(10, 0.01, 3), howell_parallel(10, 0.01, 3)),
               ("perpendicular 1e-3 / 1e3", perpendicular_pair(1e-3, 1, 1e3),
                howell_perpendicular(1e-3, 1, 1e3))]
    pairs = []

    @settings(max_examples=n_random, database=None)
    @given(facing_pairs())
    def draw(p):
        pairs.append(p)
    draw()
    pairs = pairs[:n_random]
    randoms = [("random", p, mp_contour_form_factor(*p, dps=40)) for p in pairs]
    print(f"{'cases':32s} {'n':>4s} {'old (tanh-sinh)':>16s} {'new (closed)':>13s} {'covered':>8s}")
    for name, cases in [("Howell's catalogue", howell), ("extreme aspect ratios", extreme),
                        ("random facing pairs", randoms)]:
        old = max(abs(contour_tanh_sinh(*p)[0] - r) / r for _, p, r in cases)
        new, covered = 0.0, 0
        for _, p, r in cases:
            f, e = ef.polygon_form_factor(*p, error=True)
            new = max(new, abs(f - r) / r)
            covered += abs(f - r) <= e + 2.0 ** -53 * r
        print(f"{name:32s} {len(cases):4d} {old:16.2e} {new:13.2e} {covered:5d}/{len(cases)}")
    for name, p, r in extreme:
        print(f"  {name}: old {abs(contour_tanh_sinh(*p)[0] - r) / r:.2e}, "
              f"new {abs(ef.polygon_form_factor(*p) - r) / r:.2e}")


def speed(k=16, row=0):
    polys = [np.asarray(p, float) for p in ef.scenes.subdivided_box(k).polygons]
    P, Qs = polys[row], [Q for j, Q in enumerate(polys) if j != row]
    counts = ClosedFormCounts()
    t = time.process_time()
    F, E = unoccluded_pairs(P, Qs, counts=counts)
    t_new = time.process_time() - t
    t = time.process_time()
    G = np.array([contour_tanh_sinh(P, Q)[0] for Q in Qs])
    t_old = time.process_time() - t
    n = len(Qs)
    print(f"\nsubdivided_box({k}), row {row}: {n} receivers, row sum {F.sum():.15f}")
    print(f"  unoccluded_pairs (closed form, batch): {t_new:.3f} s, {1e6 * t_new / n:.1f} us a pair")
    print(f"  contour_tanh_sinh per pair (old):      {t_old:.3f} s, {1e6 * t_old / n:.1f} us a pair")
    print(f"  ratio old / new: {t_old / t_new:.1f}; largest difference {np.abs(F - G).max():.1e}")
    print(f"  counts: {counts}")
    pr = cProfile.Profile()
    pr.enable()
    unoccluded_pairs(P, Qs)
    pr.disable()
    pstats.Stats(pr).sort_stats("tottime").print_stats(8)


if __name__ == "__main__":
    speed()
    accuracy(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
