"""Real scene files, row by row (issue 48): every default row delivers, right and
bounded, at hemicube speed.

Usage: python benchmarks/bench_real_rows.py [FILE ...] [--rows 8] [--engines]
       [--extra FILE:ROW ...] [--uniform K] [--against ROOT [--calls 5] [--rounds 2]]

Files: by default the real files beside the clone (``../shared/scenes/real``: the three
IFC building models and the others), each loaded with ``degenerate="drop"`` (and
``nonplanar="split"`` for ``quadknot.obj``). Rows: the centroids and normals of
``--rows`` polygons of at least median area
(``numpy.random.default_rng(0).choice(..., rows, replace=False)``), plus the rows
``--extra`` names (``FILE:ROW``, 0-based polygon indices of the loaded file). Per file,
in one run:

- ``rows``, ``raised``: rows tried, rows whose default call
  (``Exact().point_form_factors(scene, c, n)``) raised ``NumericalError``;
- ``python rows``: rows that left the compiled core for the Python engine
  (``stats["path"]``);
- ``misses``: values whose whole compiled bound (``error=True``: rounding, vertices,
  band and BSP crossings) exceeds ``1e-12 * max(|F|, VALUE_FLOOR)``, over the values
  with ``F > 0`` or a bound ``> 0``, and the share of them that meets it;
- ``worst bound``: the largest bound over ``max(|F|, VALUE_FLOOR)``;
- ``exact / hemicube``: the median and largest ratio of a row's time to
  ``Hemicube(256)``'s on the same row (its compiled z-buffer, the default; and, in
  brackets, the median against its numpy rasteriser, the old baseline), and the
  slowest exact row; ``< 50 seen``: the largest ratio over the rows that see fewer than
  50 polygons (``F > 0``);
- ``KiB / piece``: the row's own working memory (``stats["working_bytes"]``: its shadow
  tree, work list, edge charges and caches) per visible piece, the largest over the
  rows whose working memory passed its initial reserves (1.2 MiB);
- with ``--engines``: the Python engine at ``tolerance=None`` on the same rows, and the
  worst gap ``|Fc - Fp| / (Ec + Ep)`` (values where the two bounds do not cover the gap
  are counted: the rational reference, ``tests/exact_visibility.py``, decides those in
  the tests).

``--uniform K`` instead draws ``K`` rows per file uniformly over all its polygons
(``default_rng(1)``, or ``--seed``; small polygons included, whose centroids lie close
to many split lines) and prints, per file: the rows whose default call raised, split
by cause (the BSP's rounded crossings, or the bound of the pieces), the rows with values
settled on their shafts (``stats["shaft_polygons"]``), the largest crossings' part of a
bound, and the median and slowest row; ``--bounds`` adds, from each row again with
``error=True`` (untimed), the values, those whose whole bound exceeds 1e-12 relative,
and the worst bound over max(|F|, floor).

``--against ROOT`` instead times the same seeded rows before and after a change: this
checkout (its package, with its compiled extensions built in place) and the one at
``ROOT``, each in its own process, row by row, which of the two goes first alternating;
per row and side the least of ``--calls`` default calls (``Exact()``) and of as many
``Hemicube(256)`` calls, over ``--rounds`` rounds. Per row: polygons seen (F > 0),
quadruple-precision pieces (``stats["quad_pieces"]``), the exact times, their ratio,
the hemicube's (the least of both sides) and the exact rows in hemicube rows; the
largest ``|F_new - F_base| / (E_new + E_base)`` (``error=True``, untimed; 0: the same
values). Per file: the medians, the largest ratio over rows that see fewer than 50
polygons, and each side's bounds over 1e-12 relative to max(|F|, floor) and the worst.
``--cpu`` times both methods in the calling thread's CPU time (``time.thread_time``: both
compute in it) instead of wall time, steadier where other jobs load the machine; in the
default mode too, where ``--calls K`` keeps per row the least of K calls of each method
(the exact row's first being the default call whose raising is counted; the numpy
rasteriser's is timed once).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402

import exactff as ef  # noqa: E402
from exactff import _tolerances as tol  # noqa: E402
from exactff.errors import NumericalError  # noqa: E402

REAL = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes", "real")
DEFAULT_FILES = ["ifc-Duplex_A.obj", "ifc-tested_sample_project.obj", "ifc-SampleHouse4.obj",
                 "CornellBox-Water.obj", "CornellBox-Sphere.obj", "ADIS16480.STL",
                 "idler_riser.STL", "quadknot.obj"]
#: rows facing flush pairs, named in ../shared/scenes/real/README.md
README_ROWS = {"ifc-Duplex_A.obj": [15025, 1009], "ifc-tested_sample_project.obj": [47609, 43212],
               "ifc-SampleHouse4.obj": [21905]}


def load(path):
    """A real file as a new user loads it."""
    options = {"degenerate": "drop"}
    if os.path.basename(path) == "quadknot.obj":
        options["nonplanar"] = "split"
    return ef.load_scene(path, **options)


def seeded_rows(scene, k):
    """``k`` polygons of at least median area, as the issue and the README draw them."""
    big = np.flatnonzero(scene.areas >= np.median(scene.areas))
    return [int(i) for i in np.random.default_rng(0).choice(big, min(k, len(big)), replace=False)]


def measure(path, rows, engines, calls=1, clock=time.perf_counter):
    scene = load(path)
    exact = ef.Exact()
    hemicube = ef.methods.Hemicube(resolution=256)
    hemicube_numpy = ef.methods.Hemicube(resolution=256, backend="numpy")
    c, n = scene.centroids, scene.normals
    exact.point_form_factors(scene, c[rows[0]], n[rows[0]])       # the set-up, untimed
    hemicube.point_form_factors(scene, c[rows[0]], n[rows[0]])
    hemicube_numpy.point_form_factors(scene, c[rows[0]], n[rows[0]])
    out = {"rows": len(rows), "raised": 0, "python": 0, "values": 0, "misses": 0,
           "worst": 0.0, "ratios": [], "slowest": 0.0, "gap": 0.0, "beyond": 0, "notes": [],
           "few": 0.0, "kib": 0.0, "numpy_ratios": []}
    def least(method, k):
        # the least of k calls' times (``clock``)
        best = np.inf
        for _ in range(k):
            t = clock()
            method.point_form_factors(scene, c[r], n[r])
            best = min(best, clock() - t)
        return best

    for r in rows:
        st = {}
        t = clock()
        try:
            exact.point_form_factors(scene, c[r], n[r], stats=st)
            raised = False
        except NumericalError as e:
            out["raised"] += 1
            out["notes"].append(f"row {r} raised: {str(e)[:120]}")
            raised = True
        t_exact = clock() - t
        if not raised and calls > 1:          # the default call first, then the others
            t_exact = min(t_exact, least(exact, calls - 1))
        t_hc = least(hemicube, calls)
        out["ratios"].append(t_exact / t_hc)
        out["numpy_ratios"].append(t_exact / least(hemicube_numpy, 1))
        out["slowest"] = max(out["slowest"], t_exact)
        if str(st.get("path", "")).endswith("python"):
            out["python"] += 1
        F, E = exact.point_form_factors(scene, c[r], n[r], error=True)
        if (F > 0).sum() < 50:
            out["few"] = max(out["few"], t_exact / t_hc)
        if st.get("working_bytes", 0) > 1.25 * 2**20 and st.get("visible_pieces"):
            out["kib"] = max(out["kib"], st["working_bytes"] / st["visible_pieces"] / 1024)
        live = (F > 0) | (E > 0)
        scale = np.maximum(np.abs(F), tol.VALUE_FLOOR)
        out["values"] += int(live.sum())
        out["misses"] += int((E > tol.DEFAULT_RTOL * scale).sum())
        out["worst"] = max(out["worst"], float((E / scale).max(initial=0.0)))
        if engines:
            Fc, Ec = ef.Exact(tolerance=None).point_form_factors(scene, c[r], n[r], error=True)
            Fp, Ep = ef.Exact(tolerance=None, engine="python").point_form_factors(
                scene, c[r], n[r], error=True)
            gap = np.abs(Fc - Fp)
            cover = Ec + Ep
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(gap > 0, gap / cover, 0.0)
            beyond = np.flatnonzero(gap > cover)
            out["beyond"] += len(beyond)
            out["gap"] = max(out["gap"], float(ratio.max(initial=0.0)))
            for j in beyond[:3]:
                out["notes"].append(f"row {r}, polygon {j}: Fc {Fc[j]:.6g} Fp {Fp[j]:.6g} "
                                    f"gap {gap[j]:.2g} > Ec + Ep {cover[j]:.2g}")
    return len(scene), out


def uniform(path, k, seed=1, bounds=False):
    """``k`` uniformly drawn default rows of one file (``default_rng(seed)``): raised (by
    cause), settled on shafts, the largest crossings' part, the times; with ``bounds``,
    also the rows' whole bounds (``error=True``): the values, those over 1e-12 relative
    and the worst bound over max(|F|, floor)."""
    scene = load(path)
    rows = np.random.default_rng(seed).choice(len(scene), min(k, len(scene)), replace=False)
    exact = ef.Exact()
    c, n = scene.centroids, scene.normals
    # the set-up, untimed (error=True: the row is drawn again below, where it may raise)
    exact.point_form_factors(scene, c[rows[0]], n[rows[0]], error=True)
    out = {"crossing": 0, "bound": 0, "shaft": 0, "worst": 0.0, "times": [], "notes": [],
           "values": 0, "misses": 0, "worst_bound": 0.0}
    for r in rows.tolist():
        st = {}
        t = time.perf_counter()
        try:
            exact.point_form_factors(scene, c[r], n[r], stats=st)
        except NumericalError as e:
            out["crossing" if "rounded crossings" in str(e) else "bound"] += 1
            out["notes"].append(f"row {r} raised: {str(e)[:150]}")
        out["times"].append(time.perf_counter() - t)
        out["shaft"] += bool(st.get("shaft_polygons"))
        out["worst"] = max(out["worst"], st.get("max_crossing_bound", 0.0))
        if bounds:
            # the whole bounds (the band's slivers and the crossings' part included),
            # untimed: as the seeded rows' table counts them
            F, E = exact.point_form_factors(scene, c[r], n[r], error=True)
            live = (F > 0) | (E > 0)
            scale = np.maximum(np.abs(F), tol.VALUE_FLOOR)
            out["values"] += int(live.sum())
            out["misses"] += int((E > tol.DEFAULT_RTOL * scale).sum())
            out["worst_bound"] = max(out["worst_bound"], float((E / scale).max(initial=0.0)))
    return len(scene), len(rows), out


def main_uniform(files, k, seed=1, bounds=False):
    print(f"exactff {ef.__version__}; {k} rows per file drawn uniformly (default_rng({seed}))")
    extra = (" values | bounds over 1e-12 (share met) | worst bound / max(F, floor) |"
             if bounds else "")
    print("| file | polygons | rows | raised: crossings | raised: bound | rows with values settled on "
          "shafts | largest crossings' part | median row (s) | slowest row (s) |" + extra)
    print("|---" * (12 if bounds else 9) + "|")
    notes = []
    for path in files:
        size, rows, o = uniform(path, k, seed, bounds)
        more = ""
        if bounds:
            met = 100 * (1 - o["misses"] / max(o["values"], 1))
            more = (f" {o['values']:,} | {o['misses']} ({met:.4f}%) | "
                    f"{o['worst_bound']:.2g} |")
        print(f"| {os.path.basename(path)} | {size:,} | {rows} | {o['crossing']} | "
              f"{o['bound']} | {o['shaft']} | {o['worst']:.3g} | "
              f"{np.median(o['times']):.3f} | {max(o['times']):.2f} |" + more, flush=True)
        notes += [f"{os.path.basename(path)}: {t}" for t in o["notes"]]
    for t in notes:
        print("-", t)


def serve(clock=time.perf_counter):
    """One side of ``--against``: reads ``[path, row, calls, out]`` lines on stdin and
    answers each with a JSON line (the least exact and hemicube times, polygons seen,
    quadruple pieces), the row's F and E (``error=True``) saved to ``out``."""
    scenes = {}
    exact = ef.Exact()
    hemicube = ef.methods.Hemicube(resolution=256)
    for line in sys.stdin:
        path, r, calls, out = json.loads(line)
        first = path not in scenes
        scene = scenes[path] = scenes[path] if not first else load(path)
        c, n = scene.centroids[r], scene.normals[r]
        if first:     # the set-up, untimed
            exact.point_form_factors(scene, c, n)
            hemicube.point_form_factors(scene, c, n)
        t_exact, t_hc, st = [], [], {}
        for _ in range(calls):
            st = {}
            t = clock()
            exact.point_form_factors(scene, c, n, stats=st)
            t_exact.append(clock() - t)
            t = clock()
            hemicube.point_form_factors(scene, c, n)
            t_hc.append(clock() - t)
        F, E = exact.point_form_factors(scene, c, n, error=True)
        np.save(out, np.stack([F, E]))
        print(json.dumps({"exact": min(t_exact), "hc": min(t_hc), "seen": int((F > 0).sum()),
                          "quad": st.get("quad_pieces", 0)}), flush=True)


def main_against(files, rows, root, calls, rounds, cpu=False):
    """``--against``: this checkout ("new") and ``root`` ("base"), row by row (times in
    CPU time with ``cpu``)."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    sides = {}
    for name, tree in (("base", os.path.abspath(root)), ("new", here)):
        env = dict(os.environ, PYTHONPATH=tree)
        sides[name] = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--serve"] +
                                       (["--cpu"] if cpu else []),
                                       stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                       text=True, env=env, cwd=tree)
    print(f"base: {os.path.abspath(root)}; new: {here}; per row the least of {calls} calls "
          f"a round, {rounds} round(s); {'CPU' if cpu else 'wall'} time")
    tmp = tempfile.mkdtemp(prefix="bench_real_rows_")
    k = 0
    for path in files:
        name = os.path.basename(path)
        picked = list(dict.fromkeys(seeded_rows(load(path), rows) + README_ROWS.get(name, [])))
        best = {}
        for _ in range(rounds):
            for r in picked:
                for side in (("base", "new") if k % 2 == 0 else ("new", "base")):
                    out = os.path.join(tmp, f"{side}_{r}.npy")
                    sides[side].stdin.write(json.dumps([path, r, calls, out]) + "\n")
                    sides[side].stdin.flush()
                    o = json.loads(sides[side].stdout.readline())
                    if (side, r) in best:
                        o["exact"] = min(o["exact"], best[side, r]["exact"])
                        o["hc"] = min(o["hc"], best[side, r]["hc"])
                    best[side, r] = o
                k += 1
        print(f"\n{name}\n")
        print("| row | seen | quadruple pieces | exact (ms) | new / base | hemicube (ms) "
              "| hemicube rows | max dF / (E_base + E_new) |")
        print("|---" * 8 + "|")
        ratios = {"base": [], "new": []}
        few = {"base": 0.0, "new": 0.0}
        bounds = {"base": [0, 0.0], "new": [0, 0.0]}
        worst = 0.0
        for r in picked:
            b, a = best["base", r], best["new", r]
            hc = min(b["hc"], a["hc"])
            FE = {side: np.load(os.path.join(tmp, f"{side}_{r}.npy")) for side in sides}
            gap = np.abs(FE["new"][0] - FE["base"][0])
            with np.errstate(divide="ignore", invalid="ignore"):
                w = float(np.where(gap > 0, gap / (FE["new"][1] + FE["base"][1]), 0.0).max())
            worst = max(worst, w)
            for side, o in (("base", b), ("new", a)):
                ratios[side].append(o["exact"] / hc)
                if o["seen"] < 50:
                    few[side] = max(few[side], o["exact"] / hc)
                F, E = FE[side]
                scale = np.maximum(np.abs(F), tol.VALUE_FLOOR)
                bounds[side][0] += int((E > tol.DEFAULT_RTOL * scale).sum())
                bounds[side][1] = max(bounds[side][1], float((E / scale).max(initial=0.0)))
            print(f"| {r} | {a['seen']} | {b['quad']} -> {a['quad']} | {1e3 * b['exact']:.2f} -> "
                  f"{1e3 * a['exact']:.2f} | {a['exact'] / b['exact']:.3f} | {1e3 * hc:.2f} | "
                  f"{ratios['base'][-1]:.2f} -> {ratios['new'][-1]:.2f} | {w:.2g} |")
        total = {side: sum(best[side, r]["exact"] for r in picked) for side in sides}
        print(f"\nmedian hemicube rows {np.median(ratios['base']):.2f} -> "
              f"{np.median(ratios['new']):.2f}; < 50 seen {few['base']:.2f} -> {few['new']:.2f}; "
              f"total exact {1e3 * total['base']:.0f} -> {1e3 * total['new']:.0f} ms; "
              f"bounds over 1e-12 (worst / max(F, floor)) {bounds['base'][0]} "
              f"({bounds['base'][1]:.2g}) -> {bounds['new'][0]} ({bounds['new'][1]:.2g}); "
              f"max dF / (E_base + E_new) {worst:.2g}", flush=True)
    for proc in sides.values():
        proc.stdin.close()
        proc.wait()


def main():
    if sys.argv[1:] == ["--serve"]:
        return serve()
    if sys.argv[1:] == ["--serve", "--cpu"]:
        return serve(time.thread_time)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", help="scene files (default: the real files beside the clone)")
    ap.add_argument("--rows", type=int, default=8, help="seeded rows per file")
    ap.add_argument("--engines", action="store_true",
                    help="also compare with the Python engine (slow)")
    ap.add_argument("--extra", nargs="*", default=[], metavar="FILE:ROW",
                    help="more rows: the file's base name and a 0-based polygon index")
    ap.add_argument("--uniform", type=int, default=0, metavar="K",
                    help="instead, K rows per file drawn uniformly: which raise, and why")
    ap.add_argument("--seed", type=int, default=1,
                    help="with --uniform, the seed of the draw (default 1)")
    ap.add_argument("--bounds", action="store_true",
                    help="with --uniform, also each row's whole bounds (error=True, untimed)")
    ap.add_argument("--against", metavar="ROOT",
                    help="instead, before (the checkout at ROOT) and after (this one), "
                         "alternating row by row")
    ap.add_argument("--calls", type=int, default=None,
                    help="calls a row (the least kept): with --against, a row and side "
                         "per round (default 5); else a row and method (default 1: the "
                         "default call alone)")
    ap.add_argument("--rounds", type=int, default=2, help="with --against, rounds")
    ap.add_argument("--cpu", action="store_true",
                    help="CPU time (the thread's) instead of wall time: steadier on a "
                         "machine other jobs load")
    args = ap.parse_args()
    files = args.files or [os.path.join(REAL, f) for f in DEFAULT_FILES
                           if os.path.exists(os.path.join(REAL, f))]
    if not files:
        sys.exit(f"no scene files given and none found in {REAL}")
    print(machine())
    if args.uniform:
        return main_uniform(files, args.uniform, args.seed, args.bounds)
    if args.against:
        return main_against(files, args.rows, args.against, args.calls or 5, args.rounds,
                            args.cpu)
    print(f"exactff {ef.__version__}; rows per file: {args.rows} seeded + the README's flush rows")
    head = ("| file | polygons | rows | raised | python rows | values | bounds over 1e-12 (share met) "
            "| worst bound / max(F, floor) | exact / hemicube-256, median (max) [numpy] | < 50 seen "
            "| slowest row (s) | KiB / piece |")
    if args.engines:
        head += " engines: worst gap / (Ec + Ep), values beyond |"
    print(head)
    print("|---" * (head.count("|") - 1) + "|")
    extra = {}
    for item in args.extra:
        name, sep, row = item.rpartition(":")
        if not sep or not row.isdigit():
            sys.exit(f"--extra: expected FILE:ROW, got {item!r}")
        extra.setdefault(name, []).append(int(row))
    notes = []
    for path in files:
        name = os.path.basename(path)
        scene_rows = (seeded_rows(load(path), args.rows) + README_ROWS.get(name, []) +
                      extra.get(name, []))
        size, o = measure(path, scene_rows, args.engines, calls=args.calls or 1,
                          clock=time.thread_time if args.cpu else time.perf_counter)
        share = 1 - o["misses"] / max(o["values"], 1)
        line = (f"| {name} | {size:,} | {o['rows']} | {o['raised']} | {o['python']} | "
                f"{o['values']:,} | {o['misses']} ({share:.4%}) | {o['worst']:.2g} | "
                f"{np.median(o['ratios']):.2f} ({max(o['ratios']):.2f}) "
                f"[{np.median(o['numpy_ratios']):.2f}] | {o['few']:.2f} | "
                f"{o['slowest']:.2f} | {o['kib']:.2f} |")
        if args.engines:
            line += f" {o['gap']:.2g}, {o['beyond']} |"
        print(line, flush=True)
        notes += [f"{name}: {t}" for t in o["notes"]]
    for t in notes:
        print("-", t)


if __name__ == "__main__":
    main()
