"""Visibility-engine benchmark: time per row, BSP build, fragments, peak memory.

Usage: python benchmarks/bench_engine.py [--quick] [--rows 40] [--visibility-only]
       python benchmarks/bench_engine.py --integrators [--rows-per-scene 6]

Output-sensitivity (issue 9): for the procedural office and cloister, exact ms per row
against ``Hemicube(resolution=256)`` ms per row on the same rows (the in-run baseline),
what the clipper left out (tile rejections, predicate decisions) and did (overlays), the
row's tracemalloc peak, the estimated time of the full cloister matrix on 1 and 64
cores, and the two integrators (sector form, Eq. 3) on the same rows.

Integrators (issue 51, ``--integrators``): the compiled core with the sector form and with
Eq. 3 (stable form), both at the default tolerance, on the same rows of the office, the
cloister (every group) and the real files beside the clone (``../shared/scenes/real``):
per-row time (best of 3) and its ratio (goal: Eq. 3 at most 1.5x), rows that raised, the
largest gap over the sum of the two bounds, pieces in quadruple precision; then the stiff
catalogue against its 60-digit references (goal: at most 1e-13 relative): the kernel
(``eq3_form_factor`` / ``sector_form_factor`` at tolerance 1e-13) and the compiled core
(each case as a one-polygon scene, shortcuts off, tolerance 1e-13).

Cases: the open and the closed Cornell box (full matrices); closed cubes with k x k quads
per face, N = 1,536 and N = 6,144 (full matrices, convex: the clipper is skipped), also
timed with the shortcuts off on a sample of rows as the in-run baseline; and a furnished
room of about 4,300 polygons and the procedural office of shared/scenes (4,478 quads;
sampled rows, occluded). Memory: the tracemalloc
peak of one row (Python and numpy allocations; GEOS allocations are not counted), and
the process's peak resident set at the end (it includes the 6,144 x 6,144 matrix).
"""

import argparse
import os
import resource
import sys
import time
import tracemalloc

import numpy as np

import exactff as ef
from exactff.methods import Exact
from exactff.visibility import build_bsp

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import best_of, furnished_room, machine, timed  # noqa: E402



def row_peak_memory(scene, method, i):
    """tracemalloc peak (bytes) of one row, after the scene's caches are built."""
    method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
    tracemalloc.start()
    method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def cloister_rows(scene, per_group=2, seed=0):
    """Rows drawn with a fixed seed, ``per_group`` from every group (floors, walls,
    ceilings, piers, arches, the garth) and the sky polygon's."""
    rng = np.random.default_rng(seed)
    groups = np.array(scene.groups)
    rows = []
    for g in sorted(set(scene.groups)):
        members = np.flatnonzero(groups == g)
        rows += rng.choice(members, min(per_group, len(members)), replace=False).tolist()
    return rows


def output_sensitivity(name, scene, rows, eq3_rows):
    """Exact against hemicube-256 on the same rows; returns the table rows."""
    exact, hemi = Exact(), ef.Hemicube(resolution=256)
    exact.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])  # caches
    hemi.point_form_factors(scene, scene.centroids[rows[0]], scene.normals[rows[0]])
    out = []
    for i in rows:
        p, n = scene.centroids[i], scene.normals[i]
        st = {}
        F, te = timed(lambda: exact.point_form_factors(scene, p, n, stats=st))
        _, th = timed(lambda: hemi.point_form_factors(scene, p, n))
        out.append((name, i, scene.groups[i], te, th, te / th, F.sum(), st))
    peak = row_peak_memory(scene, exact, rows[0])
    integ = []
    for i in eq3_rows:
        p, n = scene.centroids[i], scene.normals[i]
        Fs, ts = timed(lambda: exact.point_form_factors(scene, p, n))
        Fe, tq = timed(lambda: Exact(integrator="eq3", tolerance=None).point_form_factors(scene, p, n))
        integ.append((name, i, ts, tq, float(np.abs(Fs - Fe).max())))
    return out, peak, integ


def visibility_report(n_office_rows=12):
    office = ef.scenes.office()
    t = time.perf_counter()
    cloister = ef.scenes.cloister()
    t_gen = time.perf_counter() - t
    t = time.perf_counter()
    from exactff.visibility import scene_bsp
    scene_bsp(cloister)
    t_bsp = time.perf_counter() - t
    print(f"cloister: {len(cloister)} polygons, generation {t_gen:.2f} s, BSP {t_bsp:.2f} s")
    o_rows = np.random.default_rng(0).choice(len(office), n_office_rows, replace=False).tolist()
    c_rows = cloister_rows(cloister)
    res_o, peak_o, int_o = output_sensitivity("office", office, o_rows, o_rows[:4])
    res_c, peak_c, int_c = output_sensitivity("cloister", cloister, c_rows, c_rows[:2])
    keys = ["fragments", "culled_below_horizon", "chart_fragments", "tile_rejections",
            "covered_rejections", "bbox_rejections", "disjoint_accepts", "differences",
            "skipped_after_full", "overlay_repairs"]
    print()
    print("| scene | row | group | exact (ms) | hemicube-256 (ms) | ratio | row sum - 1 | "
          + " | ".join(keys) + " |")
    print("|---|---|---|---|---|---|---|" + "---|" * len(keys))
    for name, i, g, te, th, r, s_, st in res_o + res_c:
        print(f"| {name} | {i} | {g} | {1e3 * te:.0f} | {1e3 * th:.0f} | {r:.2f} | {s_ - 1:.1e} | "
              + " | ".join(str(st.get(k, 0)) for k in keys) + " |")
    print()
    print("| scene | rows | median exact (ms) | median hemicube-256 (ms) | median ratio | "
          "max ratio | max exact (s) | row peak memory (MiB) | peak / polygon (bytes) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, res, peak, scene in (("office", res_o, peak_o, office),
                                   ("cloister", res_c, peak_c, cloister)):
        te = np.array([r[3] for r in res])
        th = np.array([r[4] for r in res])
        ratio = np.array([r[5] for r in res])
        print(f"| {name} | {len(res)} | {1e3 * np.median(te):.0f} | {1e3 * np.median(th):.0f} | "
              f"{np.median(ratio):.2f} | {ratio.max():.2f} | {te.max():.2f} | "
              f"{peak / 2**20:.1f} | {peak / len(scene):.0f} |")
    te = np.array([r[3] for r in res_c])
    total = len(cloister) * te.mean()
    print(f"\nfull cloister matrix from the sampled rows' mean ({te.mean():.2f} s/row): "
          f"{total / 3600:.1f} h on 1 core, {total / 64 / 3600:.2f} h on 64 cores")
    print()
    print("| scene | row | sector form (s) | Eq. 3 (s) | Eq. 3 / sector | max abs difference |")
    print("|---|---|---|---|---|---|")
    for name, i, ts, tq, d in int_o + int_c:
        print(f"| {name} | {i} | {ts:.3f} | {tq:.3f} | {tq / ts:.1f} | {d:.1e} |")


#: the real files of bench_real_rows.py that the integrators' table runs
REAL_FILES = ["CornellBox-Sphere.obj", "CornellBox-Water.obj", "quadknot.obj",
              "ADIS16480.STL", "idler_riser.STL", "ifc-SampleHouse4.obj"]


def integrators_report(rows_per_scene=6, real=None):
    """Eq. 3 against the sector form in the compiled core (issue 51); ``real``: the
    folder of the real files (default: bench_real_rows.py's)."""
    from bench_real_rows import REAL, load, seeded_rows   # noqa: E402

    real = real or REAL
    sector, eq3 = Exact(), Exact(integrator="eq3")
    scenes = [("office", ef.scenes.office(),
               np.random.default_rng(0).choice(4478, rows_per_scene, replace=False).tolist())]
    cloister = ef.scenes.cloister()
    scenes.append(("cloister", cloister, cloister_rows(cloister, per_group=1)))
    for f in REAL_FILES:
        path = os.path.join(real, f)
        if os.path.exists(path):
            scene = load(path)
            scenes.append((f, scene, seeded_rows(scene, rows_per_scene)))
    print("| scene | polygons | rows | sector (ms/row) | Eq. 3 (ms/row) | Eq. 3 / sector | "
          "raised (sector, Eq. 3) | max gap / (sum of bounds) | quad pieces (sector, Eq. 3) |")
    print("|---|---|---|---|---|---|---|---|---|")
    all_s, all_e, rows_seen = [], [], []
    for name, scene, rows in scenes:
        c, n = scene.centroids, scene.normals
        sector.point_form_factors(scene, c[rows[0]], n[rows[0]])          # caches, untimed
        ts, te, raised, worst, quad = [], [], [0, 0], 0.0, [0, 0]
        for i in rows:
            out = []
            for k, method in enumerate((sector, eq3)):
                st = {}
                try:
                    FE = method.point_form_factors(scene, c[i], n[i], error=True, stats=st)
                    method.point_form_factors(scene, c[i], n[i])         # raises if missed
                except ef.NumericalError:
                    raised[k] += 1
                    FE = None
                quad[k] += st.get("quad_pieces", 0)
                out.append(FE)
                t = best_of(lambda: method.point_form_factors(scene, c[i], n[i], error=True))
                (ts if k == 0 else te).append(t)
            if out[0] is not None and out[1] is not None:
                (F, E), (G, H) = out
                with np.errstate(divide="ignore", invalid="ignore"):
                    r = np.where(E + H > 0, np.abs(F - G) / (E + H), np.where(F == G, 0, np.inf))
                worst = max(worst, float(r.max()))
        all_s += ts
        all_e += te
        rows_seen += [(name, i) for i in rows]
        print(f"| {name} | {len(scene):,} | {len(rows)} | {1e3 * np.mean(ts):.1f} | "
              f"{1e3 * np.mean(te):.1f} | {np.sum(te) / np.sum(ts):.2f} | "
              f"{raised[0]}, {raised[1]} | "
              f"{worst:.2f} | {quad[0]}, {quad[1]} |")
    ratio = np.array(all_e) / np.array(all_s)
    k = int(np.argmax(ratio))
    print(f"\nEq. 3 / sector per row over all {len(ratio)} rows: median {np.median(ratio):.2f}, "
          f"max {ratio.max():.2f} ({rows_seen[k][0]} row {rows_seen[k][1]}: "
          f"{1e3 * all_s[k]:.1f} / {1e3 * all_e[k]:.1f} ms), "
          f"total {np.sum(all_e) / np.sum(all_s):.2f}")
    stiff_accuracy()


def stiff_accuracy(tolerance=1e-13):
    """Both integrators on the stiff catalogue against its 60-digit references."""
    import mpmath as mp

    from exactff.catalog import stiff_cases
    from exactff.visibility import compiled_form_factors

    worst = {}
    print()
    print("| case | reference | Eq. 3 kernel (rel) | sector kernel (rel) | "
          "Eq. 3 compiled (rel) | sector compiled (rel) |")
    print("|---|---|---|---|---|---|")
    for c in stiff_cases():
        ref = mp.mpf(c.reference)
        scene = ef.Scene.from_polygons([c.polygon])
        vals = [ef.eq3_form_factor(c.point, c.normal, c.polygon, two_sided=c.two_sided,
                                   tolerance=tolerance),
                ef.sector_form_factor(c.point, c.normal, c.polygon, two_sided=c.two_sided,
                                      tolerance=tolerance)]
        for integ in ("eq3", "sector"):
            try:
                vals.append(float(compiled_form_factors(
                    scene, c.point, c.normal, two_sided=c.two_sided, shortcuts=False,
                    tolerance=tolerance, integrator=integ)[0]))
            except ef.NumericalError:
                vals.append(float("nan"))
        rel = [float(abs(v - ref) / ref) if ref else abs(v) for v in vals]
        for k, r in zip(("eq3 kernel", "sector kernel", "eq3 compiled", "sector compiled"), rel):
            worst[k] = max(worst.get(k, 0.0), r) if r == r else float("nan")
        print(f"| {c.name} | {mp.nstr(ref, 6)} | " + " | ".join(f"{r:.1e}" for r in rel) + " |")
    print("\nlargest relative error on the stiff catalogue (goal <= 1e-13): "
          + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the N = 6,144 cube")
    ap.add_argument("--rows", type=int, default=40, help="sampled rows of the furnished room")
    ap.add_argument("--visibility-only", action="store_true",
                    help="only the office / cloister output-sensitivity tables")
    ap.add_argument("--integrators", action="store_true",
                    help="only Eq. 3 against the sector form in the compiled core (issue 51)")
    ap.add_argument("--rows-per-scene", type=int, default=6,
                    help="rows per scene of the integrators' table")
    ap.add_argument("--real", default=None, help="folder of the real files (integrators)")
    args = ap.parse_args()
    print(machine())
    if args.integrators:
        integrators_report(args.rows_per_scene, args.real)
        return
    visibility_report()
    if args.visibility_only:
        return
    rows = []

    def case(name, scene, row_ids=None, method=Exact(), note=""):
        t = time.perf_counter()
        tree = build_bsp(scene)
        t_bsp = time.perf_counter() - t
        M, dt = timed(lambda: ef.form_factor_matrix(scene, rows=row_ids, method=method))
        peak = row_peak_memory(scene, method, 0 if row_ids is None else row_ids[0])
        n_rows = M.shape[0]
        per_row = []
        if row_ids is not None:
            # per-row times for the median
            for i in row_ids[: min(len(row_ids), 40)]:
                t = time.perf_counter()
                method.point_form_factors(scene, scene.centroids[i], scene.normals[i])
                per_row.append(time.perf_counter() - t)
        med = np.median(per_row) if per_row else dt / n_rows
        sums = M.sum(axis=1)
        rows.append((name, len(scene), len(tree.fragments), tree.splits, t_bsp, n_rows, dt,
                     dt / n_rows, med, peak / 2**20, sums.min(), sums.max(), note))
        return dt / n_rows

    case("Cornell box (open)", ef.scenes.cornell_box())
    case("Cornell box (closed)", ef.scenes.cornell_box(closed=True))
    cube16 = ef.scenes.subdivided_box(16)
    per_fast = case("cube k=16 (N=1,536)", cube16)
    sample = np.random.default_rng(0).choice(len(cube16), 24, replace=False)
    per_slow = case("cube k=16, shortcuts off", cube16, sample, Exact(shortcuts=False),
                    "baseline")
    if not args.quick:
        case("cube k=32 (N=6,144)", ef.scenes.subdivided_box(32))
    office = ef.scenes.office()
    case("office (procedural, spec)", office,
         np.random.default_rng(0).choice(len(office), args.rows, replace=False))
    room = furnished_room()
    ids = np.random.default_rng(1).choice(len(room), args.rows, replace=False)
    case("furnished room", room, ids)
    case("furnished room, shortcuts off", room, ids[:10], Exact(shortcuts=False), "baseline")

    print()
    print("| case | polygons | fragments | splits | BSP build (s) | rows | total (s) | "
          "mean s/row | median s/row | row peak memory (MiB) | row sum min | row sum max |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        name, n, nf, sp, tb, nr, tot, mean, med, mem, smin, smax, note = r
        print(f"| {name} | {n} | {nf} | {sp} | {tb:.3f} | {nr} | {tot:.3f} | {mean:.5f} | "
              f"{med:.5f} | {mem:.1f} | {smin:.15f} | {smax:.15f} |")
    print(f"\ncube k=16: the convex-scene shortcut is {per_slow / per_fast:.0f} x faster per "
          f"row than the clipper on the same rows")
    print(f"peak resident set of the process: "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
