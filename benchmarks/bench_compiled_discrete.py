"""The compiled z-buffer of the discrete methods against the numpy one (issue 55).

Usage: python benchmarks/bench_compiled_discrete.py [--rows 8] [--resolution 256]

On the office (``ef.scenes.office()``, 4,424 polygons), the same rows: the hemicube's
row time with the numpy rasteriser (``backend="numpy"``, the oracle) and with the
compiled z-buffer (the default), wall and CPU time (the machine is shared: CPU time
is the steadier figure), their ratio, whether every cell shows the same polygon, the
time of clipping the polygons to the five faces (``chart_clip`` in numpy, and the
compiled clipper, bit for bit the same), where the compiled row's time goes, and the
exact method's row time with the exact / hemicube ratio before (numpy) and after
(compiled). Then every discrete method at 65,536 samples (the study's middle column),
numpy against compiled, with whether the rows are equal to the last bit. One run;
medians over the rows.
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=8)
    ap.add_argument("--resolution", type=int, default=256)
    args = ap.parse_args()
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
    other_methods(scene, rows)


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
    """Row CPU time of every discrete method at ``samples``, numpy and compiled."""
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


if __name__ == "__main__":
    main()
