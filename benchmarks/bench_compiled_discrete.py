"""The compiled z-buffer of the discrete methods against the numpy one (issue 55).

Usage: python benchmarks/bench_compiled_discrete.py [--rows 8] [--resolution 256]
       python benchmarks/bench_compiled_discrete.py --sweep [--rows 8] [--cloister-rows 3]

On the office (``ef.scenes.office()``, 4,424 polygons), the same rows: the hemicube's
row time with the numpy rasteriser (``backend="numpy"``, the oracle) and with the
compiled z-buffer (the default), wall and CPU time (the machine is shared: CPU time
is the steadier figure), their ratio, whether every cell shows the same polygon, the
time of clipping the polygons to the five faces (``chart_clip`` in numpy, and the
compiled clipper, bit for bit the same), where the compiled row's time goes, and the
exact method's row time with the exact / hemicube ratio before (numpy) and after
(compiled). Then every discrete method at 65,536 samples (the study's middle column),
numpy against compiled, with whether the rows are equal to the last bit; and the
issue's two goals (the office hemicube-256 row, every method's ratio at 65,536 samples)
on one line. One run; medians over the rows.

``--sweep``: the study's time axis in CPU time (``exactff compare`` times wall clock,
which a shared machine inflates unevenly): every discrete method (compiled) at the
study's sample counts on the office and the cloister, the methods interleaved row by
row (so that a change of load falls on all of them), median CPU ms per row; with
PPBH's time over the hemicube's and the polar plane's, and the exact row's time.
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
from exactff import _tolerances as tol
from exactff.methods._sampling import ZBufferRow
from exactff.methods import _zbuffer
from exactff.methods._zbuffer import row_sums
from exactff.visibility.charts import CHARTS, chart_clip, chart_planes

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402


def timed_rows(f, scene, rows):
    """Per row: (wall s, CPU s, result)."""
    out = []
    for i in rows:
        w, c = time.perf_counter(), time.process_time()
        r = f(scene.centroids[i], scene.normals[i])
        out.append((time.perf_counter() - w, time.process_time() - c, r))
    return out


def clip_time(scene, p, n):
    """CPU time of the five faces' frustum clipping of one row: numpy (chart_clip) and
    compiled (the same clips, bit for bit)."""
    z = ZBufferRow(scene, p, n)
    out = []
    for clip in (lambda V, counts, chart: chart_clip(V, counts, chart),
                 lambda V, counts, chart: _zbuffer.chart_clip(
                     V, counts, np.array(chart_planes(chart)), *chart, tol.CLIP_MEET_ULPS,
                     tol.CHART_EDGE_ULPS)):
        c = time.process_time()
        for chart in CHARTS:
            for _, V, counts in z.local:
                clip(V, counts, chart)
        out.append(time.process_time() - c)
    return out


METHODS = ("ppbh", "hemicube", "cubic_tetrahedron", "single_plane", "polar_plane",
           "monte_carlo")
SAMPLES = (1024, 4096, 16384, 65536, 262144, 1048576)


def sweep(name, scene, rows):
    """CPU ms per row of every method and sample count, interleaved row by row."""
    methods = {(m, s): ef.methods.resolve(m, samples=s) for s in SAMPLES for m in METHODS}
    exact = ef.Exact()
    t = {k: [] for k in methods}
    t_exact = []
    for k, m in methods.items():                   # layouts, tables, scene caches
        m.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    exact.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    for i in rows:
        p, n = scene.centroids[i], scene.normals[i]
        for k, m in methods.items():
            c = time.process_time()
            m.point_form_factors(scene, p, n)
            t[k].append(time.process_time() - c)
        c = time.process_time()
        exact.point_form_factors(scene, p, n)
        t_exact.append(time.process_time() - c)
    med = {k: 1e3 * float(np.median(v)) for k, v in t.items()}
    print(f"\n{name}: {len(scene)} polygons, rows {list(map(int, rows))}; exact row "
          f"{1e3 * float(np.median(t_exact)):.1f} ms CPU")
    print("| samples | " + " | ".join(METHODS) + " | ppbh / hemicube | ppbh / polar_plane |")
    print("|---" * (len(METHODS) + 3) + "|")
    for s in SAMPLES:
        print(f"| {s} | " + " | ".join(f"{med[(m, s)]:.1f}" for m in METHODS)
              + f" | {med[('ppbh', s)] / med[('hemicube', s)]:.2f}"
              f" | {med[('ppbh', s)] / med[('polar_plane', s)]:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=8)
    ap.add_argument("--cloister-rows", type=int, default=3)
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("--sweep", action="store_true")
    args = ap.parse_args()
    if args.sweep:
        print(machine())
        for name, scene, k in (("office", ef.scenes.office(), args.rows),
                               ("cloister", ef.scenes.cloister(), args.cloister_rows)):
            sweep(name, scene, np.random.default_rng(5).choice(len(scene), k, replace=False))
        return
    scene = ef.scenes.office()
    rows = np.random.default_rng(5).choice(len(scene), args.rows, replace=False).tolist()
    r = args.resolution
    numpy_h = ef.Hemicube(resolution=r, backend="numpy")
    compiled_h = ef.Hemicube(resolution=r)
    exact = ef.Exact()
    i0 = rows[0]
    for m in (numpy_h, compiled_h, exact):        # layouts and scene caches
        m.point_form_factors(scene, scene.centroids[i0], scene.normals[i0])
    tn = timed_rows(lambda p, n: numpy_h.native_hits(scene, p, n), scene, rows)
    tc = timed_rows(lambda p, n: compiled_h.native_hits(scene, p, n), scene, rows)
    same = all(np.array_equal(a[2], b[2]) for a, b in zip(tn, tc))
    # whole rows through the public interface (what the study times)
    rn = timed_rows(lambda p, n: numpy_h.point_form_factors(scene, p, n), scene, rows)
    rc = timed_rows(lambda p, n: compiled_h.point_form_factors(scene, p, n), scene, rows)
    re = timed_rows(lambda p, n: exact.point_form_factors(scene, p, n), scene, rows)
    clip = [clip_time(scene, scene.centroids[i], scene.normals[i]) for i in rows]
    parts = [row_parts(compiled_h, scene, scene.centroids[i], scene.normals[i]) for i in rows]
    med = lambda t, k: 1e3 * float(np.median([x[k] for x in t]))
    print(machine())
    print(f"office: {len(scene)} polygons, hemicube resolution {r} ({len(compiled_h.layout())} "
          f"cells), rows {rows}")
    print()
    print("| hemicube row | numpy wall ms | compiled wall ms | numpy / compiled | "
          "numpy CPU ms | compiled CPU ms | numpy / compiled (CPU) |")
    print("|---|---|---|---|---|---|---|")
    for name, a, b in (("z-buffer (native_hits)", tn, tc), ("whole row", rn, rc)):
        print(f"| {name} | {med(a, 0):.1f} | {med(b, 0):.1f} | {med(a, 0) / med(b, 0):.1f} | "
              f"{med(a, 1):.1f} | {med(b, 1):.1f} | {med(a, 1) / med(b, 1):.1f} |")
    print()
    print(f"every cell the same polygon (compiled vs numpy, {len(rows)} rows): {same}")
    clip = np.median(clip, axis=0)
    print(f"clipping to the five faces: numpy chart_clip {1e3 * clip[0]:.1f} ms CPU, "
          f"compiled {1e3 * clip[1]:.1f} ms CPU")
    parts = np.median(parts, axis=0)
    print()
    print("| compiled hemicube row, CPU ms | row set-up (ZBufferRow) | compiled clipping "
          "| compiled scan and depth buffer | weights' sum (row_sums) | whole row |")
    print("|---|---|---|---|---|---|")
    print("| median | " + " | ".join(f"{1e3 * x:.1f}" for x in parts) + " |")
    print()
    print("| exact row ms (wall / CPU) | exact / hemicube numpy | exact / hemicube compiled |")
    print("|---|---|---|")
    print(f"| {med(re, 0):.1f} / {med(re, 1):.1f} | {med(re, 0) / med(rn, 0):.2f} "
          f"(CPU {med(re, 1) / med(rn, 1):.2f}) | {med(re, 0) / med(rc, 0):.2f} "
          f"(CPU {med(re, 1) / med(rc, 1):.2f}) |")
    ratios = other_methods(scene, rows)
    worst = min(ratios, key=ratios.get)
    print()
    print(f"issue 55's goals: office hemicube-{r} row (whole row, median CPU) "
          f"{med(rc, 1):.1f} ms (goal <= 10 ms); at 65,536 samples every method "
          f"numpy / compiled >= {ratios[worst]:.1f} ({worst}; goal >= 5)")
    cloister = ef.scenes.cloister()
    exact_over_hemicube(cloister, np.random.default_rng(5).choice(len(cloister),
                                                                  args.cloister_rows,
                                                                  replace=False), r)


def exact_over_hemicube(scene, rows, r):
    """Exact / hemicube-r on ``scene`` in CPU time, the three interleaved row by row:
    the exact row, the hemicube with the numpy rasteriser and with the compiled one."""
    methods = {"exact": ef.Exact(), "numpy": ef.Hemicube(resolution=r, backend="numpy"),
               "compiled": ef.Hemicube(resolution=r)}
    t = {k: [] for k in methods}
    for m in methods.values():
        m.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    for i in rows:
        for k, m in methods.items():
            c = time.process_time()
            m.point_form_factors(scene, scene.centroids[i], scene.normals[i])
            t[k].append(time.process_time() - c)
    med = {k: 1e3 * float(np.median(v)) for k, v in t.items()}
    print(f"\n{len(scene)} polygons, rows {list(map(int, rows))}, CPU ms per row (median):")
    print("| exact | hemicube numpy | hemicube compiled | exact / hemicube numpy "
          "| exact / hemicube compiled |")
    print("|---|---|---|---|---|")
    print(f"| {med['exact']:.1f} | {med['numpy']:.1f} | {med['compiled']:.1f} | "
          f"{med['exact'] / med['numpy']:.2f} | {med['exact'] / med['compiled']:.2f} |")


def row_parts(m, scene, p, n):
    """CPU seconds of a compiled hemicube row's parts: the row's set-up (the live
    polygons in the local frame), the compiled clipping alone, the rest of the compiled
    z-buffer (scan conversion and depth buffer), the weights' sum per polygon (compiled
    too); and the whole row (``point_form_factors``)."""
    from exactff.methods._raster import compiled_zbuffer, rasterise_face

    c = time.process_time()
    z = ZBufferRow(scene, p, n)
    t_row = time.process_time() - c
    t_clip = clip_time(scene, p, n)[1]
    L = m.layout()
    best_t = np.full(len(L), np.inf)
    best = np.full(len(L), -1, dtype=np.int64)
    c = time.process_time()
    zb = compiled_zbuffer(z, L)
    for chart, uc, vc, table in m._faces():
        rasterise_face(z, chart, uc, vc, table, L.directions, best_t, best, zbuffer=zb)
    t_zb = time.process_time() - c
    c = time.process_time()
    row_sums(best, z.ids, z.side > 0, L.weights, len(scene))
    t_sum = time.process_time() - c
    c = time.process_time()
    m.point_form_factors(scene, p, n)
    t_all = time.process_time() - c
    return t_row, t_clip, t_zb - t_clip, t_sum, t_all


def other_methods(scene, rows, samples=65536):
    """Row CPU time of every discrete method at ``samples``, numpy and compiled; returns
    numpy / compiled per method."""
    ratios = {}
    print()
    print(f"| {samples} samples | cells | numpy CPU ms | compiled CPU ms | numpy / compiled | "
          "rows equal |")
    print("|---|---|---|---|---|---|")
    for name in ("hemicube", "cubic_tetrahedron", "single_plane", "polar_plane", "ppbh",
                 "monte_carlo"):
        mn = ef.methods.resolve(name, samples=samples, backend="numpy")
        mc = ef.methods.resolve(name, samples=samples)
        for m in (mn, mc):
            m.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
        tn = timed_rows(lambda p, n: mn.point_form_factors(scene, p, n), scene, rows)
        tc = timed_rows(lambda p, n: mc.point_form_factors(scene, p, n), scene, rows)
        same = all(np.array_equal(a[2], b[2]) for a, b in zip(tn, tc))
        a = 1e3 * float(np.median([x[1] for x in tn]))
        b = 1e3 * float(np.median([x[1] for x in tc]))
        print(f"| {name} | {mc.samples} | {a:.1f} | {b:.1f} | {a / b:.1f} | {same} |")
        ratios[name] = a / b
    return ratios


if __name__ == "__main__":
    main()
