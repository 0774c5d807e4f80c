"""Ground truth at scale (issue 14): throughput with workers, bytes on disk per format,
and the time of the full cloister matrix.

Usage: python benchmarks/bench_scale.py [--office-rows 240] [--cloister-rows 1000]
           [--throughput-rows 40] [--office-matrix docs/results/office_full/reference.npz]
           [--work DIR]

1. Office rows per second, one run: serially, with 2 worker processes that receive the
   scene once (``jobs=2``, a pool initializer) and, as the baseline, with 2 worker
   processes sent the scene with every block (the previous behaviour: a BSP tree built
   per block).
2. Bytes on disk of the whole office matrix (read from ``--office-matrix``, an exact
   matrix written by ``exactff compare office --rows all``, else computed) and of
   ``--cloister-rows`` cloister rows (seed 0; computed with 2 workers into a resumable
   ``.npz`` under ``--work``, so an interrupted benchmark continues) as dense ``.npy``,
   chunked ``.zarr`` and sparse ``.npz``, each written by exactff's own writer.
3. Cloister rows per second (``--throughput-rows`` rows, serially) and from it the time
   of the full 80,461-row matrix on 1, 64 and 1,024 cores, assuming rows spread evenly
   (rows are independent; the estimate ignores start-up and the scheduler).
"""

import argparse
import os
import shutil
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np

import exactff as ef
from exactff import formfactors
from exactff.storage import MatrixOutput

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402


def du(path):
    """Bytes on disk of a file or a directory tree."""
    if os.path.isdir(path):
        return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(path) for f in fs)
    return os.path.getsize(path)


def write_formats(M, work, name):
    """Write ``M`` (dense rows) with exactff's writers; bytes on disk per format."""
    out = {}
    n_rows, n = M.shape
    for suffix, sparse in ((".npy", False), (".zarr", False), (".npz", True)):
        # one stem per format: the sidecar files (STEM.meta.json) are per stem
        path = os.path.join(work, f"{name}_{suffix[1:]}{suffix}")
        for p in (path, path[: -len(suffix)] + ".meta.json"):
            if os.path.isdir(p):
                shutil.rmtree(p)
            elif os.path.exists(p):
                os.remove(p)
        block = max(1, min(64, 2 ** 21 // n)) if suffix == ".zarr" else 64
        w = MatrixOutput(M.shape, sparse=sparse, out=path, meta={"bench": name}, block=block)
        for a in range(0, n_rows, block):
            w.write(np.arange(a, min(a + block, n_rows)), M[a:a + block])
        w.result()
        out[suffix] = du(path)
    return out


def old_style(scene, rows, workers):
    """The previous behaviour: the scene pickled into every block, a BSP tree per block."""
    step = max(1, min(64, -(-len(rows) // (4 * workers))))
    m = ef.methods.resolve("exact")
    with ProcessPoolExecutor(workers) as ex:
        futs = [ex.submit(formfactors.PointRows(m, False), scene, rows[a:a + step])
                for a in range(0, len(rows), step)]
        return [f.result() for f in as_completed(futs)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--office-rows", type=int, default=240)
    ap.add_argument("--cloister-rows", type=int, default=1000)
    ap.add_argument("--throughput-rows", type=int, default=40)
    ap.add_argument("--office-matrix", default="docs/results/office_full/reference.npz")
    ap.add_argument("--work", default="bench_scale_work")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    print(machine())
    print()

    # 1. office throughput, one run
    office = ef.scenes.office()
    rows = np.sort(np.random.default_rng(0).choice(len(office), args.office_rows, replace=False))
    t = {}
    t0 = time.perf_counter()
    ef.form_factor_matrix(office, rows=rows)
    t["serial (1 worker)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    old_style(office, rows, 2)
    t["2 workers, scene per block (before)"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ef.form_factor_matrix(office, rows=rows, jobs=2)
    t["2 workers, scene once (jobs=2)"] = time.perf_counter() - t0
    base = t["serial (1 worker)"]
    print(f"office ({len(office)} polygons), {len(rows)} rows (seed 0)")
    print(f"| run | rows / s | time (s) | speed-up over serial |")
    print(f"|---|---|---|---|")
    for k, v in t.items():
        print(f"| {k} | {len(rows) / v:.2f} | {v:.1f} | {base / v:.2f} |")
    print(f"gain of shipping once: {t['2 workers, scene per block (before)'] / t['2 workers, scene once (jobs=2)']:.3f}x")
    print()

    # 2. bytes on disk
    if args.office_matrix and os.path.exists(args.office_matrix):
        with np.load(args.office_matrix) as z:
            M = np.array(z["F"])
    else:
        M = np.asarray(ef.form_factor_matrix(office, jobs=2, progress=True))
    sizes = {"office": (M.shape, np.count_nonzero(M), write_formats(M, args.work, "office"))}
    del M
    cloister = ef.scenes.cloister()
    crow = np.sort(np.random.default_rng(0).choice(len(cloister), args.cloister_rows,
                                                   replace=False))
    t0 = time.perf_counter()
    S = ef.form_factor_matrix(cloister, rows=crow, sparse=True, jobs=2, progress=True,
                              out=os.path.join(args.work, f"cloister_{len(crow)}_rows.npz"))
    compute = time.perf_counter() - t0
    C = S.toarray()
    sizes["cloister"] = (C.shape, int(S.nnz), write_formats(C, args.work, "cloister"))
    del C
    print(f"(cloister rows: {len(crow)} computed or resumed with 2 workers in {compute:.0f} s)")
    print()
    print("| matrix | shape | non-zeros | .npy | .zarr | .npz (sparse) | .npz bytes / non-zero | .zarr / .npy |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (shape, nnz, b) in sizes.items():
        print(f"| {name} | {shape[0]} x {shape[1]} | {nnz:,} ({nnz / (shape[0] * shape[1]):.1%}) "
              f"| {b['.npy'] / 2**20:.1f} MiB | {b['.zarr'] / 2**20:.1f} MiB "
              f"| {b['.npz'] / 2**20:.1f} MiB | {b['.npz'] / max(nnz, 1):.2f} "
              f"| {b['.zarr'] / b['.npy']:.3f} |")
    print()

    # 3. cloister throughput and the full matrix
    trow = crow[: args.throughput_rows]
    ef.form_factors(cloister, cloister.centroids[trow[0]], cloister.normals[trow[0]])  # BSP
    t0 = time.perf_counter()
    ef.form_factor_matrix(cloister, rows=trow)
    per_row = (time.perf_counter() - t0) / len(trow)
    print(f"cloister ({len(cloister)} polygons): {1 / per_row:.3f} rows / s per core "
          f"({per_row:.2f} s per row, {len(trow)} rows, serial)")
    nnz_share = sizes["cloister"][1] / (sizes["cloister"][0][0] * sizes["cloister"][0][1])
    full_npz = sizes["cloister"][2][".npz"] / sizes["cloister"][0][0] * len(cloister)
    full_zarr = sizes["cloister"][2][".zarr"] / sizes["cloister"][0][0] * len(cloister)
    print(f"full cloister matrix: {len(cloister)}^2 = {len(cloister) ** 2:,} values, "
          f"dense {len(cloister) ** 2 * 8 / 1e9:.1f} GB; at the sampled rows' "
          f"{nnz_share:.1%} non-zero: sparse about {full_npz / 1e9:.1f} GB, "
          f"chunked about {full_zarr / 1e9:.1f} GB")
    print("| cores | estimated time |")
    print("|---|---|")
    for cores in (1, 64, 1024):
        s = len(cloister) * per_row / cores
        print(f"| {cores} | {s / 3600:.1f} h ({s / 60:.1f} min) |")


if __name__ == "__main__":
    main()
