"""Other tools' matrices audited (issue 54): real tools where they install, and
planted-defect files in the formats of the tools that do not.

Usage: python benchmarks/bench_audit_tools.py [--out DIR] [--tolerance 1e-6]
                                               [--rays 2000000] [--scenes box:2,cornell_box]

Real tools (each skipped, with a line saying so, when it is not installed):
- pyviewfactor (``pip install pyviewfactor``): ``compute_viewfactor_matrix`` with the
  scene as its own obstacle; its matrix is the transpose of exactff's (F(j -> i) at
  [i, j]).
- raystrack (``pip install raystrack``): Monte Carlo on the CPU, ``--rays`` rays, the
  whole matrix; its standard errors are audited too (entries beyond three of them).
OpenFOAM's viewFactorsGen, View3D, EnergyPlus and Elmer are not run (none installs here
in minutes): their formats get the exact matrix with a defect planted, written by
exactff's writers, read back by the readers, audited through ``exactff audit``:
- OpenFOAM ``F`` + ``globalFaceFaces``: +0.00965 on every pair sharing an edge;
- View3D binary: binary visibility (a partly occluded pair wholly visible when more
  than half of it is seen, else hidden);
- EnergyPlus ``ZoneProperty:UserViewFactors:BySurfaceName``: the floor's row
  normalised to 1, the surfaces listed in another order;
- Elmer ``ViewFactors.dat``: the factors below 1e-3 left out (Elmer's minimum).
Everything goes to DIR (default ``audit_tools``): the matrices, each audit's
``audit.json``, ``worst.csv`` and figures. Printed: a table per scene, times in
seconds (the exact values' time once per scene: the audits share them).
"""

import argparse
import contextlib
import os
import time

import numpy as np

import exactff as ef
from exactff.cli import main as cli, open_scene


def run_pyviewfactor(scene):
    import pyviewfactor as pvf

    mesh = scene.to_pyvista()
    t0 = time.perf_counter()
    F = np.asarray(pvf.compute_viewfactor_matrix(mesh, obstacles=[mesh])).T
    return F, None, time.perf_counter() - t0


def run_raystrack(scene, rays):
    from raystrack import (Accuracy, Budget, Channel, Mesh, Query, Sampling, Scene,
                           SolveOptions, Solver)

    # raystrack's sampling density is per unit area: the scene scaled to a unit box
    # (form factors do not change with scale)
    lo, hi = scene.bounds
    scale = float((hi - lo).max())
    meshes = {}
    for i, P in enumerate(scene.polygons):
        fan = np.array([[0, t, t + 1] for t in range(1, len(P) - 1)], np.int32)
        meshes[f"p{i}"] = Mesh(np.asarray((P - lo) / scale, np.float32), fan)
    options = SolveOptions(sampling=Sampling(density=16, rays_per_cell=128, seed=11),
                           accuracy=Accuracy(max_replicates=20, min_replicates=5,
                                             tolerance=1e-4),
                           batch_size=65536)
    n = len(scene)
    F, E = np.zeros((n, n)), np.zeros((n, n))
    t0 = time.perf_counter()
    with Solver(Scene.from_meshes(meshes), device="cpu", bvh="builtin") as solver:
        result = solver.solve(Query.matrix(), options, Budget(rays=rays))
    for i in range(n):
        for j in range(n):
            ch = Channel("surface", f"p{j}", "front")
            F[i, j] = result.value(f"p{i}", ch) or 0.0
            E[i, j] = result.error(f"p{i}", ch) or 0.0
    return F, E, time.perf_counter() - t0


def planted(scene, exact, unoccluded, conf, out):
    """The exact matrix with a defect, in another tool's format: (name, path, format)."""
    n = len(scene)
    files = []
    case = os.path.join(out, "openfoam_case")
    ef.write_openfoam_view_factors(case, exact + 0.00965 * conf["edge_sharing"])
    files.append(("OpenFOAM +0.00965 on edge neighbours", case, "openfoam"))
    # one ray per pair: a partly occluded pair wholly seen or wholly hidden
    B = exact.copy()
    occ = conf["partly_occluded"]
    seen = np.divide(exact, unoccluded, out=np.zeros_like(exact), where=unoccluded > 0)
    B[occ] = np.where(seen[occ] > 0.5, unoccluded[occ], 0.0)
    path = os.path.join(out, "binary_visibility.vf")
    ef.write_view3d_factors(path, B, scene, binary=True)
    files.append(("View3D binary, binary visibility", path, "view3d"))
    N = exact.copy()
    k = scene.names.index("floor") if "floor" in scene.names else 0
    N[k] /= N[k].sum()
    order = np.random.default_rng(0).permutation(n)
    path = os.path.join(out, "normalised_row.idf")
    ef.write_energyplus_view_factors(path, N[np.ix_(order, order)],
                                     names=[scene.names[i] or f"S{i}" for i in order],
                                     zone="Room")
    if all(name is not None for name in scene.names):
        files.append((f"EnergyPlus, row {k} normalised", path, "energyplus"))
    path = os.path.join(out, "ViewFactors.dat")
    ef.write_elmer_view_factors(path, exact, min_factor=1e-3)
    files.append(("Elmer, factors below 1e-3 left out", path, "elmer"))
    return files


def summary(rep):
    b = rep.breakdown()
    i, j, other, exact, error = rep.worst(1)[0]
    return (f"max |err| {np.abs(rep.error).max():.2e}  mean |err| "
            f"{np.abs(rep.error).mean():.2e}  beyond {int(rep.outside.sum())}/"
            f"{rep.error.size}  rows off {len(rep.rows_off)}  left-out mass "
            f"{rep.missing_mass.sum():.2e}\n      worst {rep.labels[i]} -> {rep.labels[j]}: "
            f"{other:.6g} vs {exact:.6g}\n      mean error by configuration: "
            + ", ".join(f"{c} {r['mean_error']:+.2e} ({r['outside']}/{r['pairs']})"
                        for c, r in b.items()))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="audit_tools")
    ap.add_argument("--tolerance", type=float, default=1e-6)
    ap.add_argument("--rays", type=int, default=2_000_000)
    ap.add_argument("--scenes", default="box:2,cornell_box")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for spec in a.scenes.split(","):
        scene = open_scene(spec)
        tag = spec.replace(":", "")
        out = os.path.join(a.out, tag)
        os.makedirs(out, exist_ok=True)
        cache = os.path.join(out, "exact_area.npy")
        t0 = time.perf_counter()
        rep = ef.audit(scene, np.zeros((len(scene),) * 2), tolerance=a.tolerance, out=cache)
        t_exact = time.perf_counter() - t0
        exact = rep.exact
        print(f"\n{spec}: {len(scene)} polygons; exact area matrix to {a.tolerance:g}: "
              f"{t_exact:.1f} s (largest bound {rep.bound.max():.1e})")
        rows = []
        for tool, run in (("pyviewfactor", run_pyviewfactor),
                          ("raystrack", lambda s: run_raystrack(s, a.rays))):
            try:
                F, E, t = run(scene)
            except ImportError:
                print(f"  {tool}: not installed, skipped (pip install {tool})")
                continue
            path = os.path.join(out, f"{tool}.npy")
            np.save(path, F)
            rows.append((f"{tool} ({t:.1f} s)", path, "npy"))
            if E is not None:
                r3 = ef.audit(scene, F, tolerance=a.tolerance, other_bound=3 * E, out=cache)
                print(f"  {tool}: {int(r3.outside.sum())} of {F.size} entries beyond 3 of "
                      f"its own standard errors")
        rows += planted(scene, exact, rep.unoccluded, rep.configurations, out)
        for k, (name, path, fmt) in enumerate(rows):
            target = os.path.join(out, f"audit_{k}")
            t0 = time.perf_counter()
            # the command line: audit.json, worst.csv, figures; its report to report.txt
            os.makedirs(target, exist_ok=True)
            with open(os.path.join(target, "report.txt"), "w") as fh, \
                    contextlib.redirect_stdout(fh):
                code = cli(["audit", spec, path, "--format", fmt, "--area", "--tolerance",
                            str(a.tolerance), "--exact", cache, "--out", target,
                            "--no-progress", "--worst", "10"])
            t = time.perf_counter() - t0
            assert code == 0, (name, code)
            r = ef.audit(scene, ef.read_view_factors(path, scene, format=fmt),
                         tolerance=a.tolerance, out=cache)
            print(f"  {name}: exactff audit {t:.2f} s -> {target}\n      {summary(r)}")

if __name__ == "__main__":
    main()
