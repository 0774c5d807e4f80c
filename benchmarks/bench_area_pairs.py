"""Area form factors of random occluded pairs against tighter values (issue 49: every
value within its estimate).

Usage: python benchmarks/bench_area_pairs.py [--seed 8] [--pairs 800] [--blockers 0:40]
       [--factors 0,3] [--budget 1200]

gunter2's pairs (``tests/data/view3d/gunter2.vs3``, 398 surfaces) in a random order
(``--seed``), each in a scene of its own: the emitter, the receiver and the polygons that
may come between them (``tests/test_area_view3d.py``'s ``_pair_scene``), those with a
number of blockers in ``--blockers`` (``lo:hi``, more than lo and at most hi) and a value
above 1e-9. Per pair, the value at tolerance 1e-9 (which takes the collapsed rules
alone, not the symmetric ones of coarse tolerances) is the reference, and the value
at 1e-6 is computed once per ``AREA_NULL_RULE_FACTOR`` of ``--factors`` (0: the
symmetric pair's error estimated by its two rules' difference alone), in the same run.
The table: per factor, the point values, the values beyond their estimates
(``|F - R| > E + E_R``), the worst ``|F - R| / (E + E_R)`` and the pairs that reach it.
Stops after ``--pairs`` pairs or ``--budget`` seconds.
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
from exactff import _tolerances as tol

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402
from test_area_view3d import _gunter2, _random_pairs  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=8)
    ap.add_argument("--pairs", type=int, default=800)
    ap.add_argument("--blockers", default="0:40", help="lo:hi, blockers per pair")
    ap.add_argument("--factors", default="0,3", help="AREA_NULL_RULE_FACTOR values")
    ap.add_argument("--budget", type=float, default=1200.0, help="seconds")
    args = ap.parse_args()
    print(machine())
    lo, hi = (int(v) for v in args.blockers.split(":"))
    factors = [float(f) for f in args.factors.split(",")]
    kept, rows = tol.AREA_NULL_RULE_FACTOR, []
    t0 = time.process_time()
    try:
        for i, j, sub, R, ER in _random_pairs(_gunter2(), args.seed, (lo, hi)):
            row = [i, j]
            for factor in factors:
                tol.AREA_NULL_RULE_FACTOR = factor
                st = {}
                G, EG = ef.area_form_factors(sub, rows=[0], tolerance=1e-6, error=True, stats=st)
                row += [abs(G[0, 1] - R) / (EG[0, 1] + ER), st["point_values"]]
            tol.AREA_NULL_RULE_FACTOR = kept     # the next pair's reference
            rows.append(row)
            if len(rows) >= args.pairs or time.process_time() - t0 > args.budget:
                break
    finally:
        tol.AREA_NULL_RULE_FACTOR = kept
    res = np.array(rows, float)
    print(f"\n{len(res)} pairs (seed {args.seed}, blockers in ({lo}, {hi}]), "
          f"{time.process_time() - t0:.0f} s\n")
    print("| AREA_NULL_RULE_FACTOR | point values | ratio | beyond | worst abs(F - R) / (E + E_R) "
          "| worst pairs |")
    print("|---|---|---|---|---|---|")
    base = res[:, 3].sum()
    for k, factor in enumerate(factors):
        q, p = res[:, 2 + 2 * k], res[:, 3 + 2 * k]
        worst = ", ".join(f"({int(r[0])}, {int(r[1])}) {r[2 + 2 * k]:.2f}"
                          for r in res[np.argsort(-q)[:3]])
        print(f"| {factor:g} | {int(p.sum()):,} | {p.sum() / base:.3f} | {int((q > 1).sum())} "
              f"| {q.max():.3f} | {worst} |")


if __name__ == "__main__":
    main()
