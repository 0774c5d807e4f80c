"""Area-to-area form factors (issue 15): accuracy and time of the unoccluded pair against
a 30-point Gauss rule per edge pair, the time of occluded values at several tolerances,
and a closed cube's full area matrix.

Usage: python benchmarks/bench_area.py [--cube-k 8]

1. Unoccluded pairs (Howell's C-11 parallel opposed squares and C-14 perpendicular
   rectangles sharing an edge, references in 40-digit mpmath): relative error and time
   per pair of ``polygon_form_factor`` and of the contour integral with a 30 x 30
   Gauss-Legendre rule per edge pair (the peer tools' rule; on a shared edge the inner
   rule has 31 nodes, so that no node pair coincides and ``ln 0`` is never taken).
2. Occluded values (issue 15's two references): time, error and estimate of
   ``area_form_factors`` at tolerances 1e-6, 1e-9, 1e-12.
3. A closed cube, ``subdivided_box(k)`` (6 k^2 quads; every pair unoccluded): the full
   area matrix, its time per pair and its worst row-sum error.
4. View3D's example files (``tests/data/view3d``; issue 30), at tolerances 1e-6 and 1e-9:
   surfaces, exactff's process time for the full matrix, View3D's time (constants,
   measured 2026-12-01 on this machine, one run each), their ratio, the largest
   estimate and, for the enclosures, the worst ``|row sum - 1|`` against the largest
   row's sum of estimates; then the cube of ``subdivided_box(k)`` (``--cube-k``)
   against pyviewfactor's unoccluded matrix (``compute_viewfactor_matrix``, SA-30
   kernel, Numba threads, obstruction skipped) when it is importable, process time
   (all threads) and wall time of each; and the closed Cornell box's full matrix at
   1e-6 and 1e-9 (process and wall time, the rows' and reciprocity's invariants).
   ``--skip-slow`` leaves out gunter1 at 1e-9; ``--only-view3d`` runs this part
   alone.
6. ``--goals`` alone (issue 49's speed goals, at tolerance 1e-6): process time of the
   full matrix of gunter1, of the 106-surface box
   (:func:`exactff.scenes.unit_squares_room`: a 3 x 4 x 5 room of unit squares with two
   unit cubes inside) and of gunter2
   (``tests/data/view3d/gunter2.vs3``; ``--gunter2-rows 0,19,...``: only those
   rows, each timed, the matrix's time extrapolated from their mean and said so), against
   View3D 4.0's times of issue 49 (0.009, 0.044 and 0.52 s) with the goals (30x, 20x,
   20x); then gunter1's wall time on 1 and 2 threads (``executor=ThreadPoolExecutor``),
   best of ``--repeat``, against the goal of 1.7x.
7. ``--threads`` alone (issue 49's thread goal, at tolerance 1e-6): gunter1's full matrix
   (and the 106-surface box's with ``--threads-box``) on 1 and 2 threads
   (``executor=ThreadPoolExecutor``) and in 2 processes (``jobs=2``), alternating,
   ``--repeat`` rounds: each run's wall and process time (all threads, and the
   processes'), the best walls' ratio against the goal of 1.7x, and the
   load average before and after (the machine is shared: a process time near its wall
   time on 2 threads means one core was all it got); then one serial run with every
   compiled call of the area code timed (thread time): the share of the matrix's time
   with the GIL released, which bounds what 2 threads can gain (at most
   ``total / max(total / 2, held)``).
8. ``--umbras ROWS`` alone (issue 49, the pairs a wall hides almost wholly): gunter2's
   rows (comma-separated) at tolerance 1e-6 without and with the umbras
   (``exactff.area.umbra``; off: ``AREA_UMBRA_MIN_LINES`` beyond any pair), in one run:
   process time, point values, umbra cells, the row's sum less 1 against its
   estimates, and the largest difference of a value between the two runs against the
   sum of their estimates; ``--umbra-pairs 38:23,38:3`` the same for single pairs;
   ``--umbra-split``: "without" is the umbras of one blocker alone, "with" adds those of
   several blockers (``exactff.area.umbra.hidden_pieces``).
9. ``--points`` alone (issue 49, the adaptive levels' points): test4, facet, gunter1 and
   the 106-surface box at each of ``--tolerances`` (default 1e-6): process time, the
   point values (hidden parts evaluated), and every value against a reference at 1e-11
   (the box 1e-10; ``--ref-cache DIR`` keeps them): the worst ``|F - ref| / E``, the
   values beyond their estimates, the estimates against the tolerance.
10. ``--curved`` alone (issue 49, the curved events' cost): gunter1 and the 106-surface box
   at ``--tolerances`` (default 1e-6), in one run, with the curved events traced by numpy
   (``curved_event_lines(compiled=False)``, the reference), compiled
   (``_core/curved.cpp``), compiled with even steps only (``AREA_CURVED_CHORD_HALVINGS =
   0``: no step halved where its own midpoint lies too far from its chord, the chords
   before that) and not at all (``AREA_CURVED_MAX_TRIPLES = -1``: every pair
   skipped, as before they were traced): process time, points, the curves traced and the
   pairs skipped, and whether the compiled run's values and estimates are the numpy
   run's to the bit.
11. ``--gunter2-full`` alone (issue 49, gunter2 completes, every value within its
   estimate): gunter2's full matrix at tolerance 1e-6 with ``error=True``, on each of
   ``--gunter2-jobs`` (default ``1,2``; 1: row by row, each row's process time printed,
   ``--gunter2-cache FILE.npz`` keeping the rows done so that a stopped run resumes;
   ``jobs=2``: processes, wall time and their CPU time): rows done, time, the slowest
   rows, the smallest value, values below ``-E``, rows above ``1 + sum E``, the worst
   row sum and reciprocity against the estimates; ``--gunter2-first K`` the first K
   rows only (the pairs among them for reciprocity).
12. ``--walls ROWS`` alone (issue 49, the walls between a pair): View3D's examples,
   the 106-surface box and gunter2's rows ROWS at tolerance 1e-6 with the walls' proof
   (``exactff.area.walls``) off and on, alternating, best of ``--repeat``: process time,
   the pairs the walls take, the pairs integrated, and the largest difference of a value
   between the two runs against the sum of their estimates.
5. ``--pair-path`` alone: the occluded pairs' compiled path against the numpy and GEOS
   reference it replaces, in one run at tolerance 1e-6 (test4, facet, gunter1; process
   time): the events compiled (``exactff/_core/pair.cpp``) or by numpy
   (``event_lines(compiled=False)``), the cells compiled or by GEOS
   (``cut_cells(compiled=False)``); then gunter1's wall time on 1 and 2 threads
   (``executor=ThreadPoolExecutor``: the GIL released in the compiled calls) and in 2
   processes (``jobs=2``), best of ``--repeat``.
12. ``--pair-calls DIR`` alone (issue 49, the occluded pairs' cost per point): every
   compiled pair call (``_core/occluded_pair.cpp``) of gunter1's matrix at 1e-6 and 1e-9
   and of the 106-surface box's at 1e-6, recorded once into DIR (kept there, so that
   another build replays the same calls), replayed best of ``--repeat``: calls, points,
   process time, microseconds a point and a digest of the results (status, value,
   estimate, points and counts: equal digests, equal bits); then the serial matrices
   (process time) of gunter1, test4, facet and cube at 1e-6 and 1e-9 and of the box at
   1e-6, their F and E saved to ``DIR/matrices-TAG.npz`` (``--tag``) to compare builds.
13. ``--constant NAME=V1,V2,...`` alone (a tolerance constant's trade of time against
   points and estimates): test4, facet, gunter1 and the 106-surface box
   (``--constant-scenes``) at ``--constant-tolerances`` with the constant at each value,
   alternating in one run, best of ``--repeat``: process time and its ratio to the first
   value's, points, the estimates' sum and largest, and the largest difference of a
   value from the first value's against the two estimates.
"""

import argparse
import os
import sys
import time

import mpmath as mp
import numpy as np
from scipy.special import roots_legendre

import exactff as ef

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from scenes_bench import machine  # noqa: E402
from test_area import howell_parallel, howell_perpendicular, parallel_pair, perpendicular_pair  # noqa: E402,E501
from test_area import OCCLUDED_REFERENCES, _square  # noqa: E402
from exactff.scenes import unit_squares_room  # noqa: E402


def gauss_contour(P, Q, n=30):
    """F(P -> Q) by the contour integral with an n x n Gauss-Legendre rule per edge pair."""
    x, w = roots_legendre(n)
    s, w = 0.5 * (x + 1), 0.5 * w
    x2, w2 = roots_legendre(n + 1)
    s2, w2 = 0.5 * (x2 + 1), 0.5 * w2          # inner nodes never meet the outer ones
    A = float(np.linalg.norm(ef.area_vector(P)))
    eP, eQ = np.roll(P, -1, 0) - P, np.roll(Q, -1, 0) - Q
    total = 0.0
    for a, ea in zip(P, eP):
        X = a + s[:, None] * ea
        for b, eb in zip(Q, eQ):
            Y = b + s2[:, None] * eb
            r = np.linalg.norm(X[:, None, :] - Y[None, :, :], axis=2)
            total += (ea @ eb) * (w @ np.log(r) @ w2)
    return total / (2 * np.pi * A)


def gauss_contour_many(P, Qs, n=30, chunk=64):
    """``gauss_contour`` vectorised over receivers Qs (m, K, 3) of one emitter P."""
    x, w = roots_legendre(n)
    s, w = 0.5 * (x + 1), 0.5 * w
    x2, w2 = roots_legendre(n + 1)
    s2, w2 = 0.5 * (x2 + 1), 0.5 * w2
    A = float(np.linalg.norm(ef.area_vector(P)))
    eP = np.roll(P, -1, 0) - P
    X = P[:, None, :] + s[None, :, None] * eP[:, None, :]                  # (KP, n, 3)
    out = []
    for k in range(0, len(Qs), chunk):
        Q = Qs[k:k + chunk]
        eQ = np.roll(Q, -1, 1) - Q
        Y = Q[:, :, None, :] + s2[None, None, :, None] * eQ[:, :, None, :]  # (m, KQ, n+1, 3)
        r = np.linalg.norm(X[None, :, None, :, None, :] - Y[:, None, :, None, :, :], axis=-1)
        inner = np.einsum("a,mpqab,b->mpq", w, np.log(r), w2)
        out.append((np.einsum("pi,mqi->mpq", eP, eQ) * inner).sum(axis=(1, 2)))
    return np.concatenate(out) / (2 * np.pi * A)


def cube_row_against_gauss(k=16, row=0):
    """One row of the closed cube (every receiver not coplanar with the emitter): the
    whole row by exactff (blockers' test, batched far pairs, contour integrals near)
    and by the vectorised 30-point Gauss rule; the row sums (1 exactly) and the time
    per pair of each."""
    from exactff.area import area_row as _area_row

    cube = ef.scenes.subdivided_box(k)
    polys = np.array([np.asarray(p, float) for p in cube.polygons])
    n = ef.area_vector(polys[row])
    others = [j for j in range(len(polys))
              if j != row and abs((polys[j] - polys[row][0]) @ n).max() > 0]
    t0 = time.perf_counter()
    f, e = _area_row(cube, row, 1e-9)
    t1 = time.perf_counter() - t0
    t0 = time.perf_counter()
    g = gauss_contour_many(polys[row], polys[others])
    t2 = time.perf_counter() - t0
    rel = np.abs(g - f[others]) / f[others]
    print(f"| cube k = {k}, row {row}: {len(others)} receivers | row sum - 1: exactff "
          f"{f.sum() - 1:.1e}, Gauss 30 {g.sum() - 1:.1e} | worst relative difference "
          f"{rel.max():.1e} (median {np.median(rel):.1e}) | ms / pair: exactff "
          f"{t1 / len(others) * 1e3:.3f}, Gauss 30 {t2 / len(others) * 1e3:.3f} "
          f"(ratio {t1 / t2:.2f}) |")


def timed(f, *a, repeat=20):
    t0 = time.perf_counter()
    for _ in range(repeat):
        v = f(*a)
    return v, (time.perf_counter() - t0) / repeat


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cube-k", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=1, help="processes for the cube's matrix")
    ap.add_argument("--only-cube", action="store_true")
    ap.add_argument("--against-pyviewfactor", action="store_true",
                    help="only the cube (--cube-k, --jobs) against pyviewfactor, in one run")
    ap.add_argument("--only-view3d", action="store_true",
                    help="only the View3D examples and the cube against pyviewfactor")
    ap.add_argument("--skip-slow", action="store_true", help="leave out gunter1 at 1e-9")
    ap.add_argument("--pair-path", action="store_true",
                    help="only the occluded pairs' compiled path against its reference")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each --pair-path timing")
    ap.add_argument("--goals", action="store_true", help="only issue 49's speed goals")
    ap.add_argument("--threads", action="store_true", help="only issue 49's thread goal")
    ap.add_argument("--threads-box", action="store_true",
                    help="--threads: the 106-surface box too")
    ap.add_argument("--gunter2-rows", default="",
                    help="--goals: rows of gunter2 timed, comma-separated (none: the whole "
                         "matrix)")
    ap.add_argument("--gunter2-full", action="store_true",
                    help="only gunter2's full matrix at 1e-6: time, values against estimates")
    ap.add_argument("--gunter2-jobs", default="1,2",
                    help="--gunter2-full: the jobs to run, comma-separated (1: row by row)")
    ap.add_argument("--gunter2-cache", default="",
                    help="--gunter2-full: an .npz keeping the rows done on 1 job (resumed)")
    ap.add_argument("--gunter2-first", type=int, default=0,
                    help="--gunter2-full: only the first rows (0: all 398)")
    ap.add_argument("--umbras", default="", help="only gunter2's rows (comma-separated) "
                    "without and with the umbras")
    ap.add_argument("--umbra-pairs", default="", help="with --umbras: pairs i:j timed alone")
    ap.add_argument("--umbra-split", action="store_true", help="with --umbras: without = "
                    "the umbras of one blocker alone, with = those of several too")
    ap.add_argument("--curved", action="store_true",
                    help="only the curved events traced by numpy, compiled and not at all")
    ap.add_argument("--points", action="store_true",
                    help="only the occluded pairs' points and values against tight references")
    ap.add_argument("--ref-cache", default="",
                    help="--points: a directory for the references (computed once)")
    ap.add_argument("--tolerances", default="1e-6",
                    help="--points: the tolerances, comma-separated")
    ap.add_argument("--pair-calls", default="",
                    help="only the occluded pairs' calls recorded into (or read from) this "
                         "directory and replayed, and the serial matrices")
    ap.add_argument("--tag", default="run", help="--pair-calls: the matrices' file's tag")
    ap.add_argument("--walls", default="",
                    help="only the walls between a pair (exactff.area.walls) off and on, in "
                         "one run: View3D's examples, the 106-surface box and these gunter2 "
                         "rows (comma-separated)")
    ap.add_argument("--constant", default="",
                    help="only a tolerance constant at several values, NAME=V1,V2,..., "
                         "alternating in one run on View3D's examples and the 106-surface "
                         "box (the first value the baseline; a constant read only at "
                         "import changes nothing here)")
    ap.add_argument("--constant-tolerances", default="1e-6,1e-9",
                    help="--constant: the tolerances, comma-separated")
    ap.add_argument("--constant-scenes", default="test4,facet,gunter1,box",
                    help="--constant: the scenes, comma-separated")
    args = ap.parse_args()
    print(machine())
    print()
    if args.pair_path:
        return pair_path(args)
    if args.pair_calls:
        return pair_calls(args)
    if args.goals:
        return goals(args)
    if args.threads:
        return threads(args)
    if args.gunter2_full:
        return gunter2_full(args)
    if args.umbras or args.umbra_pairs:
        return umbra_rows(args)
    if args.walls:
        return walls_table(args)
    if args.constant:
        return constant_table(args)
    if args.points:
        return points_table(args)
    if args.curved:
        return curved_table(args)
    if args.only_cube:
        return cube_matrix(args)
    if args.against_pyviewfactor:
        return cube_against_pyviewfactor(args.cube_k, args.jobs)
    if args.only_view3d:
        return view3d_table(args)
    cases = [("C-11 squares 1 apart", parallel_pair(1, 1, 1), howell_parallel(1, 1, 1)),
             ("C-11 10 x 10 at 0.1", parallel_pair(10, 10, 0.1), howell_parallel(10, 10, 0.1)),
             ("C-14 unit, common edge", perpendicular_pair(1, 1, 1), howell_perpendicular(1, 1, 1)),
             ("C-14 0.1 x 1 / 2 x 1", perpendicular_pair(0.1, 1, 2), howell_perpendicular(0.1, 1, 2))]
    print("| pair | exactff rel. error | exactff ms / pair | Gauss 30 rel. error | Gauss 30 ms / pair | time ratio |")
    print("|---|---|---|---|---|---|")
    for name, (P, Q), ref in cases:
        v1, t1 = timed(ef.polygon_form_factor, P, Q)
        v2, t2 = timed(gauss_contour, P, Q)
        print(f"| {name} | {abs(v1 - ref) / ref:.1e} | {t1 * 1e3:.2f} | {abs(v2 - ref) / ref:.1e} "
              f"| {t2 * 1e3:.2f} | {t1 / t2:.2f} |")
    print()
    print("Vectorised over the receivers of one emitter (a row of the closed cube):")
    for row in (0, 40):
        cube_row_against_gauss(16, row)
    print()
    print("| occluded reference | tolerance | value | error | estimate | ms / value |")
    print("|---|---|---|---|---|---|")
    for k, (plate, ref) in enumerate(OCCLUDED_REFERENCES):
        scene = ef.Scene.from_polygons([_square(0, True), _square(2, False), plate])
        for tol in (1e-6, 1e-9, 1e-12):
            t0 = time.perf_counter()
            F, E = ef.area_form_factors(scene, rows=[0], tolerance=tol, error=True)
            dt = time.perf_counter() - t0
            print(f"| {ref} | {tol:g} | {F[0, 1]:.15f} | {abs(F[0, 1] - ref):.1e} "
                  f"| {E[0, 1]:.1e} | {dt * 1e3:.0f} |")
    print()
    cube_matrix(args)
    print()
    view3d_table(args)


DATA = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "view3d")

#: View3D's example files: (file, what, View3D's time in s, exactff's before issue 30 at
#: tolerance 1e-9 in s, an enclosure). The times were measured 2026-12-01 on the
#: project's 2-core machine, one run each (View3D 3.3 on the file; exactff
#: ``area_form_factors(tolerance=1e-9)``; exactff's run of gunter1 then crashed at row
#: 8). gunter1's View3D time is issue 30's table's.
VIEW3D_EXAMPLES = (
    ("cube.vs3", "cube", 0.002, 0.06, True),
    ("ParallelPlanesMasked.vs3", "square obstruction (mask)", 0.003, 0.13, False),
    ("test4.vs3", "Pinney & Bean BRE test 4 (L-room)", 0.004, 5.8, True),
    ("facet.vs3", "facet (box and plate)", 0.004, 11.0, True),
    ("gunter1.vs3", "gunter1 (irregular enclosure)", 0.007, 297.0, True),
)

#: pyviewfactor 1.1's unoccluded matrix of ``subdivided_box(16)`` with 2 threads,
#: measured 2026-12-01 (s), shown where pyviewfactor is not importable.
PYVIEWFACTOR_K16 = "13.7-16.7 s"


def pair_path(args):
    """Part 5: the occluded pairs' compiled path against the numpy reference, and threads."""
    from concurrent.futures import ThreadPoolExecutor

    from exactff.area import adaptive, events

    lines, cells = events.event_lines, events.cut_cells

    def lines_numpy(*a, **k):
        return lines(*a, **k, compiled=False)

    def cells_geos(*a, **k):
        return cells(*a, **k, compiled=False)

    print("| example | events | cells | process s | points | max estimate |")
    print("|---|---|---|---|---|---|")
    out = {}
    for name in ("test4.vs3", "facet.vs3", "gunter1.vs3"):
        scene = ef.read_vs3(os.path.join(DATA, name))
        for how, fl, fc in (("numpy | GEOS", lines_numpy, cells_geos),
                            ("compiled | GEOS", lines, cells_geos),
                            ("compiled | compiled", lines, cells)):
            adaptive.event_lines, adaptive.cut_cells = fl, fc
            best = np.inf
            for _ in range(args.repeat):
                st = {}
                t0 = time.process_time()
                F, E = ef.area_form_factors(scene, tolerance=1e-6, error=True, stats=st)
                best = min(best, time.process_time() - t0)
            out[name, how] = F, E
            print(f"| {name} | {how} | {best:.3f} | {st['point_values']:,} | {E.max():.1e} |",
                  flush=True)
        adaptive.event_lines, adaptive.cut_cells = lines, cells
        # the events the same to the bit; the cells triangulated otherwise (ears against
        # constrained Delaunay): within the estimates
        assert np.array_equal(out[name, "numpy | GEOS"][0], out[name, "compiled | GEOS"][0])
        (F0, E0), (F1, E1) = out[name, "compiled | GEOS"], out[name, "compiled | compiled"]
        assert np.all(np.abs(F0 - F1) <= E0 + E1)
    print()
    print("gunter1 at 1e-6, wall time (best of %d):" % args.repeat)
    print()
    print("| how | wall s | speed-up |")
    print("|---|---|---|")
    scene = ef.read_vs3(os.path.join(DATA, "gunter1.vs3"))
    base = None
    for how in ("1 thread", "2 threads", "2 processes"):
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            if how == "2 processes":
                ef.area_form_factors(scene, tolerance=1e-6, jobs=2)
            else:
                with ThreadPoolExecutor(int(how[0])) as pool:
                    ef.area_form_factors(scene, tolerance=1e-6, executor=pool)
            best = min(best, time.perf_counter() - t0)
        base = base or best
        print(f"| {how} | {best:.3f} | {base / best:.2f} |", flush=True)


def pair_calls(args):
    """Part 12: the occluded pairs' compiled calls recorded, replayed and timed, and the
    serial matrices."""
    import hashlib
    import pickle

    from exactff.area import compiled_pair

    os.makedirs(args.pair_calls, exist_ok=True)
    scenes = {"gunter1": lambda: ef.read_vs3(os.path.join(DATA, "gunter1.vs3")),
              "106-surface box": unit_squares_room}
    print("The occluded pairs' calls replayed (process time, best of %d):" % args.repeat)
    print()
    print("| scene | tolerance | calls | points | s | us a point | digest |")
    print("|---|---|---|---|---|---|---|")
    call = compiled_pair._compiled_occluded_pair
    for name, tolerance in (("gunter1", 1e-6), ("gunter1", 1e-9), ("106-surface box", 1e-6)):
        path = os.path.join(args.pair_calls, f"{name.split('-')[0]}-{tolerance:g}.pickle")
        if not os.path.exists(path):
            calls = []

            def record(*a):
                calls.append(tuple(x.copy() if isinstance(x, np.ndarray) else x
                                   for x in a[:-1]))
                return call(*a)

            compiled_pair._compiled_occluded_pair = record
            try:
                ef.area_form_factors(scenes[name](), tolerance=tolerance, error=True)
            finally:
                compiled_pair._compiled_occluded_pair = call
            with open(path, "wb") as f:
                pickle.dump(calls, f)
        with open(path, "rb") as f:
            calls = pickle.load(f)
        constants = compiled_pair.pair_constants()
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.process_time()
            out = [call(*c, constants) for c in calls]
            best = min(best, time.process_time() - t0)
        points = sum(o[3] for o in out)
        digest = hashlib.md5(np.array([o[:9] for o in out], dtype=float).tobytes()).hexdigest()
        print(f"| {name} | {tolerance:g} | {len(calls)} | {points:,} | {best:.3f} "
              f"| {1e6 * best / points:.3f} | {digest[:12]} |", flush=True)
    print()
    print("Serial matrices (process time, one run):")
    print()
    print("| scene | tolerance | s |")
    print("|---|---|---|")
    saved = {}
    for name in ("gunter1", "test4", "facet", "cube", "106-surface box"):
        for tolerance in (1e-6,) if name == "106-surface box" else (1e-6, 1e-9):
            scene = (unit_squares_room() if name == "106-surface box"
                     else ef.read_vs3(os.path.join(DATA, name + ".vs3")))
            t0 = time.process_time()
            F, E = ef.area_form_factors(scene, tolerance=tolerance, error=True)
            print(f"| {name} | {tolerance:g} | {time.process_time() - t0:.3f} |", flush=True)
            key = f"{name.split('-')[0]}_{tolerance:g}"
            saved[key + "_F"], saved[key + "_E"] = F, E
    np.savez(os.path.join(args.pair_calls, f"matrices-{args.tag}.npz"), **saved)


def umbra_rows(args):
    """gunter2's rows and pairs at tolerance 1e-6 without and with the umbras."""
    from exactff import _tolerances as tolerances
    from exactff.area import AreaStats, area_row
    from exactff.area import adaptive
    scene = ef.read_vs3(os.path.join(DATA, "gunter2.vs3"))
    on = tolerances.AREA_UMBRA_MIN_LINES

    split = tolerances.AREA_UMBRA_SPLIT_DEPTH

    def run(i, umbra):
        # --umbra-split: without = the umbras of one blocker alone (no pieces)
        tolerances.AREA_UMBRA_MIN_LINES = on if umbra or args.umbra_split else 2 ** 62
        tolerances.AREA_UMBRA_SPLIT_DEPTH = split if umbra or not args.umbra_split else -1
        st = AreaStats()
        t0 = time.process_time()
        f, e = area_row(scene, i, 1e-6, stats=st)
        return f, e, time.process_time() - t0, st

    if args.umbras:
        print("| gunter2 row | s without | s with | ratio | points without | points with "
              "| umbra cells / pieces | sum - 1 (est.) with | largest difference / estimates |")
        print("|---|---|---|---|---|---|---|---|---|")
        for i in (int(r) for r in args.umbras.split(",")):
            f0, e0, t0, s0 = run(i, False)
            f1, e1, t1, s1 = run(i, True)
            worst = float(np.max(np.abs(f1 - f0) / np.maximum(e0 + e1, 1e-300)))
            print(f"| {i} | {t0:.2f} | {t1:.2f} | {t0 / t1:.2f}x | {s0.point_values:,} "
                  f"| {s1.point_values:,} | {s1.umbra_cells} / {s1.umbra_pieces} "
                  f"| {f1.sum() - 1:.1e} "
                  f"({e1.sum():.1e}) | {worst:.2f} |")
    if args.umbra_pairs:
        # a pair alone: its row's blockers and unoccluded value, captured from the row
        captured = {}
        pairs = [tuple(int(x) for x in p.split(":")) for p in args.umbra_pairs.split(",")]
        original = adaptive.occluded_pair
        import exactff.area.row as row_module

        def capture(S, Pc, Qc, *a, **k):
            captured[S[0].tobytes()] = (S, Pc, Qc, a, k)
            return 0.0, 0.0, 0
        row_module.occluded_pair = capture
        try:
            for i in sorted({i for i, _ in pairs}):
                area_row(scene, i, 1e-6)
        finally:
            row_module.occluded_pair = original
        print("| gunter2 pair | s without | s with | points without | points with "
              "| umbra cells / pieces | value with (est.) | difference / estimates |")
        print("|---|---|---|---|---|---|---|---|")
        for i, j in pairs:
            S, Pc, Qc, a, k = captured[np.asarray(scene.polygons[j], float).tobytes()]
            out = []
            for umbra in (False, True):
                tolerances.AREA_UMBRA_MIN_LINES = on if umbra or args.umbra_split else 2 ** 62
                tolerances.AREA_UMBRA_SPLIT_DEPTH = (split if umbra or not args.umbra_split
                                                     else -1)
                st = AreaStats()
                t0 = time.process_time()
                v, e, pts = original(S, Pc, Qc, *a[:5], st, *a[6:], **k)
                out.append((v, e, pts, time.process_time() - t0,
                            f"{st.umbra_cells} / {st.umbra_pieces}"))
            (v0, e0, p0, t0, _), (v1, e1, p1, t1, u1) = out
            print(f"| ({i}, {j}) | {t0:.2f} | {t1:.2f} | {p0:,} | {p1:,} | {u1} "
                  f"| {v1:.3e} ({e1:.1e}) | {abs(v1 - v0) / (e0 + e1):.2f} |")
    tolerances.AREA_UMBRA_MIN_LINES = on
    tolerances.AREA_UMBRA_SPLIT_DEPTH = split


def walls_table(args):
    """The walls between a pair (``exactff.area.walls``) off and on, alternating in one
    run, at tolerance 1e-6: process time (best of ``--repeat``), the pairs the walls take
    and those integrated, and the largest difference of a value between the two runs
    against the sum of their estimates."""
    import exactff.area.row as row_module
    proof = row_module.hidden_by_walls
    cases = [(name, ef.read_vs3(os.path.join(DATA, name)), None)
             for name in ("cube.vs3", "test4.vs3", "facet.vs3", "gunter1.vs3")]
    cases.append(("106-surface box", ef.scenes.unit_squares_room(), None))
    g2 = ef.read_vs3(os.path.join(DATA, "gunter2.vs3"))
    cases += [(f"gunter2 row {r}", g2, [int(r)]) for r in args.walls.split(",") if r != "all"]
    print("| case | s off | s on | off / on | pairs the walls take | pairs integrated off / on "
          "| largest difference / estimates | max E off / on |")
    print("|---|---|---|---|---|---|---|---|")
    for name, scene, rows in cases:
        out = {}
        for _ in range(args.repeat):
            for on in (False, True):
                row_module.hidden_by_walls = proof if on else (lambda *a: False)
                st = {}
                t0 = time.process_time()
                f, e = ef.area_form_factors(scene, rows=rows, tolerance=1e-6, error=True,
                                            stats=st)
                t = time.process_time() - t0
                if on not in out or t < out[on][2]:
                    out[on] = (f, e, t, st)
        row_module.hidden_by_walls = proof
        (f0, e0, t0, s0), (f1, e1, t1, s1) = out[False], out[True]
        worst = float(np.max(np.abs(f1 - f0) / np.maximum(e0 + e1, 1e-300)))
        print(f"| {name} | {t0:.3f} | {t1:.3f} | {t0 / t1:.2f}x | {s1['wall_hidden_pairs']} "
              f"| {s0['occluded_pairs']} / {s1['occluded_pairs']} | {worst:.2f} "
              f"| {e0.max():.1e} / {e1.max():.1e} |")


def constant_table(args):
    """A tolerance constant (``exactff._tolerances``) at several values, alternating in one
    run (``--constant NAME=V1,V2,...``): per scene and tolerance, the full matrix's process
    time (best of ``--repeat``) and its ratio to the first value's, the points, the sum
    and largest of the estimates, and the largest difference of a value from the first
    value's against the sum of the two estimates."""
    from exactff import _tolerances as tol
    name, values = args.constant.split("=")
    kept = getattr(tol, name)
    # (an integer constant, a count, stays an integer: the compiled code reads it so)
    values = [int(v) if isinstance(kept, int) and not isinstance(kept, bool) else float(v)
              for v in values.split(",")]
    files = {"test4": "test4.vs3", "facet": "facet.vs3", "gunter1": "gunter1.vs3"}
    print(f"`{name}` at {', '.join(f'{v:g}' for v in values)} (the first the baseline; "
          f"{kept:g} as shipped), best of {args.repeat}:")
    print()
    print("| scene | tolerance | value | s | / first | points | sum E | max E "
          "| max abs(dF) / (E + E first) |")
    print("|---|---|---|---|---|---|---|---|---|")
    try:
        for scene_name in args.constant_scenes.split(","):
            scene = (ef.scenes.unit_squares_room() if scene_name == "box"
                     else ef.read_vs3(os.path.join(DATA, files[scene_name])))
            for tolerance in (float(t) for t in args.constant_tolerances.split(",")):
                out = {}
                for _ in range(args.repeat):
                    for v in values:
                        setattr(tol, name, v)
                        st = {}
                        start = time.process_time()
                        f, e = ef.area_form_factors(scene, tolerance=tolerance, error=True,
                                                    stats=st)
                        t = time.process_time() - start
                        if v not in out or t < out[v][2]:
                            out[v] = (f, e, t, st["point_values"])
                f0, e0, t0, _ = out[values[0]]
                for v in values:
                    f, e, t, points = out[v]
                    gap = float(np.max(np.abs(f - f0) / np.maximum(e + e0, 1e-300)))
                    print(f"| {scene_name} | {tolerance:g} | {v:g} | {t:.3f} | {t / t0:.3f} "
                          f"| {points:,} | {e.sum():.4e} | {e.max():.2e} | {gap:.2g} |",
                          flush=True)
    finally:
        setattr(tol, name, kept)


def matrix_against_estimates(scene, F, E, rows):
    """The invariants of the area rows ``F`` (of the polygons ``rows``) against their
    estimates ``E``: (the smallest value, values below ``-E``, rows summing above ``1 +
    sum E``, the worst ``|row sum - 1| / sum E`` of the rows, and over the pairs of two
    of the rows the worst reciprocity ``|A_i F_ij - A_j F_ji| / (A_i E_ij + A_j E_ji)``
    and how many pairs exceed 1)."""
    A = scene.areas
    s, se = F.sum(axis=1), E.sum(axis=1)
    AF, AE = (A[rows, None] * F)[:, rows], (A[rows, None] * E)[:, rows]
    gap = np.abs(AF - AF.T)
    recip = np.where(gap > 0, gap / np.maximum(AE + AE.T, 1e-300), 0.0)
    return (float(F.min()), int((F < -E).sum()), int((s > 1 + se).sum()),
            float(np.max(np.abs(s - 1) / np.maximum(se, 1e-300))), float(recip.max()),
            int((recip > 1).sum()))


def gunter2_full(args):
    """gunter2's full matrix at tolerance 1e-6 with its estimates, on 1 job (row by row,
    each row's process time; ``--gunter2-cache`` keeps the rows done) and on 2 processes
    (``jobs=2``, wall time and the processes' CPU time): whether it completes, the time,
    and every value against its estimate (none below ``-E``, rows within ``1 + sum E``,
    reciprocity within the two estimates; with ``--gunter2-first K``, over the first K
    rows and the pairs among them)."""
    scene = ef.read_vs3(os.path.join(DATA, "gunter2.vs3"))
    n = len(scene) if not args.gunter2_first else args.gunter2_first
    rows = np.arange(n)
    print(f"gunter2 ({len(scene)} polygons), rows 0-{n - 1} at tolerance 1e-6, error=True:")
    print()
    print("| jobs | rows done | process s (all processes) | wall s | slowest rows (s) | points "
          "| min F | F below -E | rows above 1 + sum E | worst abs(sum - 1) / sum E "
          "| worst reciprocity / estimates (pairs beyond) | max E |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    results = {}
    for jobs in (int(j) for j in args.gunter2_jobs.split(",")):
        st = {}
        if jobs == 1:
            F, E = np.zeros((n, len(scene))), np.zeros((n, len(scene)))
            T, W, P = np.full(n, np.nan), np.full(n, np.nan), np.zeros(n, dtype=np.int64)
            cache = args.gunter2_cache
            if cache and os.path.exists(cache):
                with np.load(cache) as z:
                    k = min(len(z["T"]), n)
                    F[:k], E[:k], T[:k], W[:k], P[:k] = (z["F"][:k], z["E"][:k], z["T"][:k],
                                                       z["W"][:k], z["P"][:k])
            for r in rows[np.isnan(T)]:
                st = {}
                t0, w0 = time.process_time(), time.perf_counter()
                f, e = ef.area_form_factors(scene, rows=[r], tolerance=1e-6, error=True,
                                            stats=st)
                T[r], W[r] = time.process_time() - t0, time.perf_counter() - w0
                F[r], E[r], P[r] = f[0], e[0], st["point_values"]
                print(f"  row {r}: {T[r]:.2f} s, {P[r]:,} points, sum - 1 "
                      f"{F[r].sum() - 1:.1e} ({E[r].sum():.1e})", flush=True)
                if cache:
                    np.savez(cache, F=F, E=E, T=T, W=W, P=P)
            cpu, wall, points = float(T.sum()), float(W.sum()), int(P.sum())
            slow = ", ".join(f"{r}: {T[r]:.0f}" for r in np.argsort(-T)[:5])
        else:
            c0, w0 = os.times(), time.perf_counter()
            F, E = ef.area_form_factors(scene, rows=rows, tolerance=1e-6, error=True,
                                        jobs=jobs, stats=st)
            c1 = os.times()
            wall = time.perf_counter() - w0
            cpu = sum(c1[:4]) - sum(c0[:4])
            points, slow = st["point_values"], "-"
        results[jobs] = F, E
        low, below, above, rowsum, recip, beyond = matrix_against_estimates(scene, F, E, rows)
        print(f"| {jobs} | {n} | {cpu:.1f} | {wall:.1f} | {slow} | {points:,} | {low:.1e} "
              f"| {below} | {above} | {rowsum:.2f} | {recip:.2f} ({beyond}) | {E.max():.1e} |",
              flush=True)
    if len(results) > 1:
        (F0, E0), *rest = results.values()
        for F1, E1 in rest:
            print(f"jobs against 1 job: largest difference {np.abs(F1 - F0).max():.1e}, "
                  f"bit for bit {bool(np.array_equal(F0, F1) and np.array_equal(E0, E1))}")


#: View3D 4.0's times of issue 49's table (s, gcc -O2, 2026-12-05) and the goals' ratios.
GOALS = (("gunter1", 0.009, 30), ("106-surface box", 0.044, 20), ("gunter2", 0.52, 20))


#: --points: the scenes and their references' tolerance (much tighter).
POINTS_SCENES = (("test4", 1e-11), ("facet", 1e-11), ("gunter1", 1e-11),
                 ("106-surface box", 1e-10))


def points_table(args):
    """Part 9: the occluded pairs' point values (hidden parts evaluated) and process time
    of each scene's full matrix at each of ``--tolerances``, and every value against a
    reference computed at a much tighter tolerance (the same code, ``POINTS_SCENES``;
    cached in ``--ref-cache`` where given): the worst ``|F - ref| / E`` (E the value's
    estimate), how many values exceed their estimate, and the largest and median ``E /
    tolerance`` of the occluded values."""
    print("Occluded pairs' points, every value against a tighter reference:")
    print()
    print("| scene | tolerance | process s | points | occluded values | worst abs(F - ref) "
          "/ E (pair) | values beyond E | max E / tolerance | median E / tolerance "
          "(occluded) | reference tolerance, its max E |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, ref_tol in POINTS_SCENES:
        scene = (unit_squares_room() if name == "106-surface box"
                 else ef.read_vs3(os.path.join(DATA, name + ".vs3")))
        cache = (os.path.join(args.ref_cache, f"{name.replace(' ', '_')}_{ref_tol:g}.npz")
                 if args.ref_cache else "")
        if cache and os.path.exists(cache):
            with np.load(cache) as z:
                R, RE = z["F"], z["E"]
        else:
            R, RE = ef.area_form_factors(scene, tolerance=ref_tol, error=True)
            if cache:
                np.savez(cache, F=R, E=RE)
        for tolerance in (float(t) for t in args.tolerances.split(",")):
            st = {}
            t0 = time.process_time()
            F, E = ef.area_form_factors(scene, tolerance=tolerance, error=True, stats=st)
            dt = time.process_time() - t0
            ratio = np.abs(F - R) / np.maximum(E, 1e-300)
            w = np.unravel_index(np.argmax(ratio), ratio.shape)
            occ = E > 1e-12             # the unoccluded values' estimates are rounding's
            print(f"| {name} | {tolerance:g} | {dt:.3f} | {st['point_values']:,} "
                  f"| {int(occ.sum())} | {ratio.max():.3f} ({w[0]}, {w[1]}) "
                  f"| {int((ratio > 1).sum())} | {E.max() / tolerance:.3f} "
                  f"| {np.median(E[occ]) / tolerance:.2e} | {ref_tol:g}, {RE.max():.1e} |",
                  flush=True)


def curved_table(args):
    """Part 10: the curved events traced by numpy, compiled, compiled with even steps
    only and not at all, same run."""
    import functools

    from exactff import _tolerances as tol
    from exactff.area import adaptive, curved

    print("Curved events by numpy (the reference), compiled, compiled with even steps "
          "only, and none (process time, one run each):")
    print()
    print("| scene | tolerance | curves | process s | points | curves traced | pairs skipped "
          "| max E | F, E the numpy run's to the bit |")
    print("|---|---|---|---|---|---|---|---|---|")
    scenes = {"gunter1": ef.read_vs3(os.path.join(DATA, "gunter1.vs3")),
              "106-surface box": unit_squares_room()}
    limit, halvings = tol.AREA_CURVED_MAX_TRIPLES, tol.AREA_CURVED_CHORD_HALVINGS
    for name, scene in scenes.items():
        for tolerance in (float(t) for t in args.tolerances.split(",")):
            ref = None
            for how in ("numpy", "compiled", "even steps", "none"):
                adaptive.curved_event_lines = functools.partial(
                    curved.curved_event_lines, compiled=how != "numpy")
                tol.AREA_CURVED_MAX_TRIPLES = -1 if how == "none" else limit
                tol.AREA_CURVED_CHORD_HALVINGS = 0 if how == "even steps" else halvings
                st = {}
                try:
                    t0 = time.process_time()
                    F, E = ef.area_form_factors(scene, tolerance=tolerance, error=True, stats=st)
                    dt = time.process_time() - t0
                finally:
                    adaptive.curved_event_lines = curved.curved_event_lines
                    tol.AREA_CURVED_MAX_TRIPLES = limit
                    tol.AREA_CURVED_CHORD_HALVINGS = halvings
                ref = (F, E) if ref is None else ref
                same = "-" if how != "compiled" else bool(
                    np.array_equal(F, ref[0]) and np.array_equal(E, ref[1]))
                print(f"| {name} | {tolerance:g} | {how} | {dt:.3f} | {st['point_values']:,} "
                      f"| {st['curved_events']:,} | {st['curved_skipped']:,} | {E.max():.1e} "
                      f"| {same} |", flush=True)


def goals(args):
    """Part 6: issue 49's speed goals at 1e-6."""
    from concurrent.futures import ThreadPoolExecutor

    print("Issue 49's goals at tolerance 1e-6 (process time, one run; View3D: issue 49's "
          "figures):")
    print()
    print("| scene | surfaces | rows timed | exactff s (full matrix) | View3D s | ratio | goal "
          "| points | max estimate | worst abs(row sum - 1) within estimates |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    g1 = ef.read_vs3(os.path.join(DATA, "gunter1.vs3"))
    scenes = {"gunter1": g1, "106-surface box": unit_squares_room(),
              "gunter2": ef.read_vs3(os.path.join(DATA, "gunter2.vs3"))}
    for name, v3d, goal in GOALS:
        scene = scenes[name]
        n = len(scene)
        rows = None
        if name == "gunter2" and args.gunter2_rows:
            rows = [int(r) for r in args.gunter2_rows.split(",")]
        st, each = {}, []
        t0 = time.process_time()
        if rows is None:
            F, E = ef.area_form_factors(scene, tolerance=1e-6, error=True, stats=st)
        else:
            FE = []
            for r in rows:
                t1 = time.process_time()
                FE.append(ef.area_form_factors(scene, rows=[r], tolerance=1e-6, error=True,
                                               stats=st))
                each.append(f"{r}: {time.process_time() - t1:.2f} s")
            F, E = np.vstack([f for f, _ in FE]), np.vstack([e for _, e in FE])
        dt = time.process_time() - t0
        full = dt if rows is None else dt * n / len(rows)
        dev = np.abs(F.sum(axis=1) - 1)
        within = bool(np.all(dev <= E.sum(axis=1) + 1e-13))
        timed_rows = "all" if rows is None else f"{len(rows)} (extrapolated)"
        print(f"| {name} | {n} | {timed_rows} | {full:.3f} | {v3d} | {full / v3d:.0f} | {goal} "
              f"| {st['point_values']:,} | {E.max():.1e} | {dev.max():.1e} {within} |",
              flush=True)
        if each:
            print(f"|   ({name}'s rows: {', '.join(each)}) |||||||||| ")
    print()
    print("The pair path's compiled levels and set-up against their numpy reference "
          "(adaptive.COMPILED_LEVELS, hidden_setup(compiled=False)), same run:")
    print()
    print("| scene | numpy levels and set-up s | compiled s | ratio | points (both) | "
          "largest abs difference | within the estimates |")
    print("|---|---|---|---|---|---|---|")
    import functools

    from exactff.area import adaptive, hidden
    for name in ("gunter1", "106-surface box"):
        out = []
        for compiled in (False, True):
            adaptive.COMPILED_LEVELS = compiled
            adaptive.hidden_setup = functools.partial(hidden.hidden_setup, compiled=compiled)
            st = {}
            t0 = time.process_time()
            F, E = ef.area_form_factors(scenes[name], tolerance=1e-6, error=True, stats=st)
            out.append((time.process_time() - t0, F, E, st["point_values"]))
        adaptive.COMPILED_LEVELS, adaptive.hidden_setup = True, hidden.hidden_setup
        (t0_, F0, E0, p0), (t1_, F1, E1, p1) = out
        print(f"| {name} | {t0_:.3f} | {t1_:.3f} | {t0_ / t1_:.2f} | {p0:,} / {p1:,} "
              f"| {np.abs(F0 - F1).max():.1e} | {bool(np.all(np.abs(F0 - F1) <= E0 + E1))} |",
              flush=True)
    print()
    print("gunter1 at 1e-6, wall time (best of %d):" % args.repeat)
    print()
    print("| threads | wall s | speed-up | goal |")
    print("|---|---|---|---|")
    base = None
    for k in (1, 2):
        best = np.inf
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            with ThreadPoolExecutor(k) as pool:
                ef.area_form_factors(g1, tolerance=1e-6, executor=pool)
            best = min(best, time.perf_counter() - t0)
        base = base or best
        print(f"| {k} | {best:.3f} | {base / best:.2f} | {'-' if k == 1 else 1.7} |", flush=True)


def gil_share(scene, tolerance=1e-6):
    """One serial run of ``scene``'s area matrix with every compiled call of the area
    code (the ``_compiled_*`` names its modules import) timed in thread time: (the run's
    thread time, the time in the compiled calls, {call: time})."""
    import functools
    import importlib

    spent = {}

    def timed_call(f, label):
        @functools.wraps(f)
        def g(*a, **k):
            t = time.thread_time()
            try:
                return f(*a, **k)
            finally:
                spent[label] = spent.get(label, 0.0) + time.thread_time() - t
        return g

    patched = []
    for name in ("events", "curved", "hidden", "adaptive", "compiled_pair", "edge_integrals",
                 "culling", "closed_form"):
        mod = importlib.import_module(f"exactff.area.{name}")
        for attr in dir(mod):
            if attr.startswith("_compiled_"):
                patched.append((mod, attr, getattr(mod, attr)))
                setattr(mod, attr, timed_call(getattr(mod, attr), attr[len("_compiled_"):]))
    try:
        t = time.thread_time()
        ef.area_form_factors(scene, tolerance=tolerance)
        total = time.thread_time() - t
    finally:
        for mod, attr, f in patched:
            setattr(mod, attr, f)
    return total, sum(spent.values()), spent


def threads(args):
    """Part 7: gunter1 (and the 106-surface box) on 1 and 2 threads at 1e-6."""
    from concurrent.futures import ThreadPoolExecutor

    scenes = [("gunter1", ef.read_vs3(os.path.join(DATA, "gunter1.vs3")))]
    if args.threads_box:
        scenes.append(("106-surface box", unit_squares_room()))
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    print()
    print("| scene | threads | runs: wall / process s | best wall s | speed-up | goal |")
    print("|---|---|---|---|---|---|")
    for name, scene in scenes:
        ef.area_form_factors(scene, rows=[0], tolerance=1e-6)        # imports, prepared
        runs = {1: [], 2: [], "jobs=2": []}
        for _ in range(args.repeat):
            for k in runs:
                # process time of this process and of its finished children (jobs=2)
                c0, t0 = sum(os.times()[:4]), time.perf_counter()
                if k == "jobs=2":
                    ef.area_form_factors(scene, tolerance=1e-6, jobs=2)
                else:
                    with ThreadPoolExecutor(k) as pool:
                        ef.area_form_factors(scene, tolerance=1e-6, executor=pool)
                runs[k].append((time.perf_counter() - t0, sum(os.times()[:4]) - c0))
        best = {k: min(w for w, _ in runs[k]) for k in runs}
        for k in runs:
            each = ", ".join(f"{w:.3f} / {c:.3f}" for w, c in runs[k])
            what = f"{k} (processes)" if k == "jobs=2" else k
            print(f"| {name} | {what} | {each} | {best[k]:.3f} | {best[1] / best[k]:.2f} "
                  f"| {'-' if k == 1 else 1.7} |", flush=True)
    print()
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print()
    print("The GIL over one serial run (thread time; the compiled calls release it):")
    print()
    print("| scene | total s | compiled s (GIL released) | held s | held share | "
          "2-thread bound | largest compiled calls |")
    print("|---|---|---|---|---|---|---|")
    for name, scene in scenes:
        total, free, spent = gil_share(scene)
        held = total - free
        top = ", ".join(f"{k} {v:.3f}" for k, v in sorted(spent.items(), key=lambda x: -x[1])[:4])
        print(f"| {name} | {total:.3f} | {free:.3f} | {held:.3f} | {held / total:.0%} "
              f"| {total / max(total / 2, held):.2f} | {top} |", flush=True)


def view3d_table(args):
    """Part 4: View3D's examples, then the cube against pyviewfactor."""
    print("View3D examples, full area matrix (exactff: process time, one run; View3D and "
          "'before': measured 2026-12-01, one run each, tolerance 1e-9 for 'before'):")
    print()
    print("| example | surfaces | tolerance | exactff s | before s | View3D s | exactff / View3D "
          "| max estimate | worst abs(row sum - 1) | largest row's sum of estimates | stats |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for tol in (1e-6, 1e-9):
        for name, what, v3d, before, encl in VIEW3D_EXAMPLES:
            if args.skip_slow and name == "gunter1.vs3" and tol == 1e-9:
                print(f"| {what} | 25 | {tol:g} | skipped (--skip-slow) | {before} | - | - | - | - | - | - |")
                continue
            scene = ef.read_vs3(os.path.join(DATA, name))
            st = {}
            t0 = time.process_time()
            F, E = ef.area_form_factors(scene, tolerance=tol, error=True, stats=st)
            dt = time.process_time() - t0
            ratio = f"{dt / v3d:.3g}" if v3d else "-"
            rows = (f"{np.abs(F.sum(axis=1) - 1).max():.1e} | {E.sum(axis=1).max():.1e}"
                    if encl else "- | -")
            brief = ", ".join(f"{k} {v}" for k, v in st.items() if v)
            print(f"| {what} | {len(scene)} | {tol:g} | {dt:.3f} | {before if tol == 1e-9 else '-'} "
                  f"| {v3d if v3d else 'not measured'} | {ratio} | {E.max():.1e} | {rows} | {brief} |",
                  flush=True)
    print()
    cornell_matrix()
    print()
    cube_against_pyviewfactor(args.cube_k, args.jobs)


def cornell_matrix():
    """The closed Cornell box's full area matrix (21 polygons, ten block faces between
    the floor and the light; issue 30's goal: 1e-9 in under a minute): process and wall
    time, points, and the invariants (every row sums to 1 but the floor's, which sums to
    1 less the blocks' footprints, as the blocks are open below; reciprocity), each
    within the estimates."""
    scene = ef.scenes.cornell_box(closed=True)
    A = scene.areas
    want = np.ones(len(scene))
    want[1] = 1.0 - (A[10] + A[15]) / A[1]       # the blocks' tops are their footprints
    print("Closed Cornell box, full area matrix (one process):")
    print()
    print("| tolerance | process s | wall s | points | max estimate | worst abs(row sum - "
          "expected) | largest row's sum of estimates | rows within | reciprocity within | stats |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for tol in (1e-6, 1e-9):
        st = {}
        t0, w0 = time.process_time(), time.perf_counter()
        F, E = ef.area_form_factors(scene, tolerance=tol, error=True, stats=st)
        dt, dw = time.process_time() - t0, time.perf_counter() - w0
        dev = np.abs(F.sum(axis=1) - want)
        AF, AE = A[:, None] * F, A[:, None] * E
        brief = ", ".join(f"{k} {v}" for k, v in st.items() if v and k != "point_values")
        print(f"| {tol:g} | {dt:.1f} | {dw:.1f} | {st['point_values']:,} | {E.max():.1e} "
              f"| {dev.max():.1e} | {E.sum(axis=1).max():.1e} "
              f"| {bool(np.all(dev <= E.sum(axis=1) + 1e-13))} "
              f"| {bool(np.all(np.abs(AF - AF.T) <= AE + AE.T + 1e-12))} | {brief} |", flush=True)


def cube_against_pyviewfactor(k, jobs=1):
    """The closed cube of 6 k^2 quads: exactff's full area matrix (``jobs`` processes)
    and pyviewfactor's unoccluded one on the same quads, side by side (issue 49's goal:
    exactff's wall time at most half pyviewfactor's, both on 2 cores). Process time
    counts this process only: with ``jobs > 1`` compare wall times."""
    cube = ef.scenes.subdivided_box(k)
    n = len(cube)
    t0, w0 = time.process_time(), time.perf_counter()
    F, E = ef.area_form_factors(cube, tolerance=1e-9, error=True, jobs=jobs)
    dt, dw = time.process_time() - t0, time.perf_counter() - w0
    exact_wall = dw
    print(f"| cube subdivided_box({k}), {n} quads | process s | wall s | us of CPU per pair "
          f"| worst abs(row sum - 1) |")
    print("|---|---|---|---|---|")
    print(f"| exactff ({jobs} process{'es' if jobs > 1 else ''}, tolerance 1e-9) | "
          f"{dt:.1f}{' (this process)' if jobs > 1 else ''} | {dw:.1f} "
          f"| {dt / (n * n) * 1e6 if jobs == 1 else float('nan'):.0f} "
          f"| {np.abs(F.sum(axis=1) - 1).max():.1e} |")
    try:
        import pyvista as pv
        import pyviewfactor as pvf
    except ImportError:
        print(f"| pyviewfactor (not importable; its k = 16 time measured 2026-12-01, 2 threads) "
              f"| - | {PYVIEWFACTOR_K16} | - | - |")
        return

    def mesh(scene):
        faces = np.concatenate([[len(P), *range(o, o + len(P))]
                                for P, o in zip(scene.polygons, scene.offsets[:-1])])
        return pv.PolyData(np.asarray(scene.vertices, float), faces)

    pvf.compute_viewfactor_matrix(mesh(ef.scenes.subdivided_box(1)), skip_obstruction=True)  # JIT
    t0, w0 = time.process_time(), time.perf_counter()
    G = pvf.compute_viewfactor_matrix(mesh(cube), skip_obstruction=True).T   # F[i, j] = F(i -> j)
    dt, dw = time.process_time() - t0, time.perf_counter() - w0
    print(f"| pyviewfactor {pvf.__version__} (compute_viewfactor_matrix, obstruction skipped, "
          f"Numba threads) | {dt:.1f} | {dw:.1f} | {dt / (n * n) * 1e6:.0f} "
          f"| {np.abs(G.sum(axis=1) - 1).max():.1e} |")
    print(f"worst abs(exactff - pyviewfactor) {np.abs(F - G).max():.1e}; exactff's wall time "
          f"/ pyviewfactor's {exact_wall / dw:.2f} (goal <= 0.5)")


def cube_matrix(args):
    from concurrent.futures import ProcessPoolExecutor

    cube = ef.scenes.subdivided_box(args.cube_k)
    t0 = time.perf_counter()
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as ex:
            F, E = ef.area_form_factors(cube, tolerance=1e-9, error=True, executor=ex,
                                        progress=True)
    else:
        F, E = ef.area_form_factors(cube, tolerance=1e-9, error=True, progress=True)
    dt = time.perf_counter() - t0
    n = len(cube)
    A = cube.areas
    recip = np.abs(A[:, None] * F - (A[:, None] * F).T).max()
    print(f"closed cube, {n} quads, {args.jobs} process(es): full area matrix in {dt:.1f} s "
          f"({dt * args.jobs / (n * n) * 1e6:.0f} us of one core per pair); worst |row sum - 1| "
          f"{np.abs(F.sum(axis=1) - 1).max():.1e}; worst reciprocity {recip:.1e}; "
          f"largest estimate {E.max():.1e}; largest row's sum of estimates "
          f"{E.sum(axis=1).max():.1e}")


if __name__ == "__main__":
    main()
