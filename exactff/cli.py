"""The ``exactff`` command line: scene information and form-factor jobs."""

import argparse
import sys

import numpy as np

__all__ = ["main", "PROCEDURAL", "build_parser", "open_scene", "parse_rows", "read_points",
           "cmd_info", "cmd_ff",
           "cmd_matrix", "cmd_compare", "cmd_audit", "BUILTIN", "DENSE_OUTPUT_BYTES"]

BUILTIN = {
    "cornell_box": lambda: _scenes().cornell_box(),
    "cornell_box_closed": lambda: _scenes().cornell_box(closed=True),
    "office": lambda: _scenes().office(),
    "cloister": lambda: _scenes().cloister(),
    "courtyard": lambda: _scenes().courtyard(),
}


# built-in scenes with a size: NAME:COUNT (building:NXxNY); the form, the counts' names
# and the builder
PROCEDURAL = {
    "box": ("box:K", ["K"], lambda k: _scenes().subdivided_box(k)),
    "office": ("office:N", ["N"], lambda n: _scenes().office(n)),
    "cloister": ("cloister:N", ["N"], lambda n: _scenes().cloister(n)),
    "building": ("building:NX or building:NXxNY", ["NX", "NY"],
                 lambda nx, ny=1: _scenes().building(nx, ny)),
}


def _scenes():
    from . import scenes

    return scenes


def open_scene(spec, *, split_nonplanar=False, planarity_rtol=None, drop_degenerate=False):
    """A scene from a file path or a built-in name (``cornell_box``, ``cornell_box_closed``,
    ``office``, ``office:N`` for about N quads, ``cloister``, ``cloister:N``, ``courtyard`` (open, z up), ``box:K`` for a closed unit box with K x K
    quads per face, ``building:NXxNY`` for rooms with zero-thickness walls).
    ``drop_degenerate`` leaves a file's degenerate faces out (``degenerate="drop"``)."""
    from .io import load_scene

    options = {"nonplanar": "split" if split_nonplanar else "error",
               "degenerate": "drop" if drop_degenerate else "raise"}
    if planarity_rtol is not None:
        if not (np.isfinite(planarity_rtol) and planarity_rtol > 0):
            raise ValueError(f"--planarity-rtol: expected a positive number, got {planarity_rtol}")
        options["planarity_rtol"] = planarity_rtol
    if spec in BUILTIN:
        return BUILTIN[spec]()
    kind, _, size = spec.partition(":")
    if kind in PROCEDURAL:
        form, names, build = PROCEDURAL[kind]
        texts = size.split("x") if kind == "building" else [size]
        if not 1 <= len(texts) <= len(names):
            raise ValueError(f"scene {spec!r}: expected {form}")
        counts = []
        for name, text in zip(names, texts):
            try:
                counts.append(int(text))
            except ValueError:
                raise ValueError(f"scene {spec!r}: expected {form}, with {name} an integer, "
                                 f"got {text!r}") from None
        try:
            return build(*counts)
        except ValueError as exc:
            raise ValueError(f"scene {spec!r} ({form}): {exc}") from None
    try:
        return load_scene(spec, **options)
    except UnicodeDecodeError:
        raise ValueError(f"{spec}: not a text file (UTF-8)") from None
    except ValueError as exc:
        # name the file in every message (a polygon's SceneError names the polygon)
        raise ValueError(str(exc) if str(exc).startswith(spec) else f"{spec}: {exc}") from None


def _open(args):
    return open_scene(args.scene, split_nonplanar=args.split_nonplanar,
                      planarity_rtol=args.planarity_rtol, drop_degenerate=args.drop_degenerate)


def _scene_arguments(p):
    p.add_argument("scene", help="scene file (.obj, .json, .vs3, .stl, .ply, .off, .vtk, ...) "
                                 "or built-in name (cornell_box, cornell_box_closed, "
                                 "office[:N], cloister[:N], courtyard, box:K, "
                                 "building:NXxNY)")
    p.add_argument("--split-nonplanar", action="store_true",
                   help="cut faces that are not planar into planar triangles instead of "
                        "refusing the file")
    p.add_argument("--planarity-rtol", type=float, default=None,
                   help="allowed vertex distance from a face's plane, relative to its "
                        "diameter (default 1e-6)")
    p.add_argument("--drop-degenerate", action="store_true",
                   help="leave out degenerate faces (fewer than 3 distinct vertices, zero "
                        "area) instead of refusing the file; polygons keep the file's "
                        "order without them, and info says how many were left out")


def _remainder_arguments(p, what):
    p.add_argument("--remainder", action="store_true", help=what)
    p.add_argument("--up", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"),
                   help="up direction for --remainder (default 0 0 1; the built-in office "
                        "and cloister are y-up: 0 1 0)")


def cmd_info(args):
    from .reports import describe

    scene = _open(args)
    d = describe(scene)
    lo, hi = d["bounds_min"], d["bounds_max"]
    print(f"scene            {args.scene}")
    print(f"polygons         {d['polygons']}")
    print(f"vertices         {d['vertices']}")
    print(f"total area       {d['total_area']:.6g}")
    print(f"bounding box     [{lo[0]:.6g}, {lo[1]:.6g}, {lo[2]:.6g}] .. "
          f"[{hi[0]:.6g}, {hi[1]:.6g}, {hi[2]:.6g}]")
    print(f"planarity        max vertex deviation {d['max_planarity_deviation']:.3g} "
          f"of the polygon's diameter"
          + (f"; {d['split_faces']} non-planar faces split into triangles"
             if d["split_faces"] else ""))
    if d["dropped_faces"] or args.drop_degenerate:
        why = ", ".join(f"{c:,} {r}" for r, c in d["dropped_reasons"].items())
        print(f"dropped faces    {d['dropped_faces']:,} degenerate faces left out"
              + (f" ({why})" if why else ""))
    if d["skipped_primitives"]:
        kinds = ", ".join(f"{c:,} {k}" for k, c in d["skipped_primitives"].items())
        print(f"not read         {kinds} (not polygons)")
    closed = d["closure_residual"] <= 1e-12
    print(f"closure          |sum A n| / sum A = {d['closure_residual']:.3g} "
          f"({'closed' if closed else 'open: rows need not sum to 1'}); "
          f"unpaired directed edges {d['unpaired_edges']} (T-junctions count too)")
    b2b, same = d["back_to_back_pairs"], d["same_facing_overlaps"]
    print(f"coplanar overlaps {len(b2b)} back-to-back pairs (zero-thickness walls: each "
          f"side is seen from its own side)")
    name = lambda i: scene.names[i] or (f"polygon {i} ({scene.groups[i]})" if scene.groups[i]
                                        else f"polygon {i}")
    print(f"                 {len(same)} same-facing pairs"
          + (" (usually a modelling mistake; the first in input order is in front)"
             if same else ""))
    for i, j in same[:5]:
        print(f"                   {name(i)} and {name(j)}")
    if len(same) > 5:
        print(f"                   ... and {len(same) - 5} more")
    from ._tolerances import NEAR_COPLANAR_RTOL

    near = d["near_coplanar_overlaps"]
    print(f"near-coplanar    {len(near)} overlapping pairs flush to within "
          f"{NEAR_COPLANAR_RTOL:g} of the magnitudes but not coplanar"
          + (" (the exact method orders them by their geometry, the discrete methods "
             "may call them ties: docs/explanation/conventions.md)" if near else ""))
    for i, j in near[:5]:
        print(f"                   {name(i)} and {name(j)}")
    if len(near) > 5:
        print(f"                   ... and {len(near) - 5} more")
    v3 = scene.metadata.get("view3d")
    if v3 is not None:
        from .combine import combined_surfaces

        kinds = [s["kind"] for s in v3["surfaces"]]
        subs = sum(1 for s in v3["surfaces"] if s["kind"] == "S" and s["base"])
        cmb = sum(1 for s in v3["surfaces"] if s["cmb"])
        print(f"View3D           format F {v3['format']}; {len(kinds)} surfaces "
              f"({kinds.count('S')} S of which {subs} subsurfaces, {kinds.count('M')} masks, "
              f"{kinds.count('N')} null, {kinds.count('O')} obstructions; {cmb} combined): "
              f"{len(combined_surfaces(scene))} rows with --area --combine")
        for note in v3["notes"]:
            print(f"                 {note}")
    return 0


def cmd_ff(args):
    from .kernel import point_polygon_form_factors

    scene = _open(args)
    p = np.array(args.point, dtype=float)
    n = np.array(args.normal, dtype=float)
    if args.up is not None and not args.remainder:
        raise ValueError("--up is the up direction of --remainder: give --remainder too")
    if args.remainder:
        # the remainder of a row needs occlusion (unoccluded values may overlap)
        from .formfactors import form_factors

        F, sky, ground = form_factors(scene, p, n, remainder=True, up=args.up)
        print(f"form factors with occlusion from {p.tolist()} with normal {n.tolist()}:")
    else:
        F = point_polygon_form_factors(p, n, scene)
        print(f"unoccluded form factors from {p.tolist()} with normal {n.tolist()}:")
    for i in np.flatnonzero(F):
        name = scene.names[i] or f"polygon {i}"
        print(f"  {name:24s} {F[i]:.15f}")
    print(f"  {'sum':24s} {F.sum():.15f}")
    if args.remainder:
        up = [0.0, 0.0, 1.0] if args.up is None else list(args.up)
        print(f"  {'sky':24s} {sky:.15f}   (uncovered, above the horizontal plane; up {up})")
        print(f"  {'ground':24s} {ground:.15f}   (uncovered, below it)")
        print(f"  {'sum with sky and ground':24s} {F.sum() + sky + ground:.15f}")
    return 0


def parse_rows(text, n):
    """Row selection: ``"all"``, ``"A:B"`` (a slice) or ``"i,j,k"``."""
    if text in (None, "all"):
        return np.arange(n)
    try:
        if ":" in text:
            a, b = text.split(":", 1)
            a, b = int(a) if a else 0, int(b) if b else n
            if not 0 <= a < b <= n:
                raise IndexError
            return np.arange(a, b)
        rows = np.array([int(v) for v in text.split(",")])
        if rows.min() < 0 or rows.max() >= n:
            raise IndexError
        return rows
    except ValueError:
        raise ValueError(f"--rows: expected 'all', 'A:B' or 'i,j,...', got {text!r}") from None
    except IndexError:
        raise ValueError(f"--rows {text}: the scene has {n} polygons (rows 0 to {n - 1})") from None


def _matrix_summary(M):
    """Row sums and the share of zero entries, block by block (a chunked store or a
    sparse matrix is never made dense)."""
    import scipy.sparse as sp

    if sp.issparse(M):
        return np.asarray(M.sum(axis=1)).ravel(), 1.0 - M.nnz / max(M.shape[0] * M.shape[1], 1)
    sums, zeros, step = [], 0, max(1, 2 ** 22 // max(M.shape[1], 1))
    for a in range(0, M.shape[0], step):
        block = np.asarray(M[a:a + step])
        sums.append(block.sum(axis=1))
        zeros += int(np.count_nonzero(block == 0))
    sums = np.concatenate(sums) if sums else np.zeros(0)
    return sums, zeros / max(M.shape[0] * M.shape[1], 1)


# a dense matrix larger than this goes to a chunked store by default
DENSE_OUTPUT_BYTES = 2 ** 31


def _area_matrix(scene, rows, args, out, executor):
    """``exactff matrix --area``: the area-to-area matrix, each value within
    ``--tolerance``, and its bounds beside it (STEM.error.SUFFIX), by the matrix driver
    of the point rows: ``--jobs`` or ``--scheduler``, ``--sparse``, a ``.zarr`` store,
    and a killed run resumed from ``out``. With ``--combine`` (the surfaces View3D
    reports, computed in memory): a dense ``.npy``."""
    from .formfactors import area_form_factors
    from .storage import beside_path

    if args.two_sided:
        raise ValueError("--area is one-sided (not with --two-sided)")
    if not (args.tolerance > 0):
        raise ValueError(f"--tolerance must be positive, got {args.tolerance}")
    jobs = args.jobs if args.jobs > 1 else None
    error_path = beside_path(out, "error")
    if args.combine:
        if args.sparse or not out.endswith(".npy"):
            raise ValueError("--area --combine writes a dense .npy (not with --sparse, "
                             ".zarr or .npz)")
        F, E = area_form_factors(scene, rows, tolerance=args.tolerance, error=True,
                                 executor=executor, jobs=jobs,
                                 progress=not args.no_progress, combine=True)
        _save_without_records(out, F)
        _save_without_records(error_path, E)
    else:
        F, E = area_form_factors(scene, rows, tolerance=args.tolerance, error=True,
                                 executor=executor, jobs=jobs,
                                 progress=not args.no_progress, out=out, sparse=args.sparse)
    largest = max((float(np.asarray(E[a:a + 1024].max())) for a in range(0, E.shape[0], 1024)),
                  default=0.0)
    print(f"error bounds     max {largest:.3g} (tolerance {args.tolerance:g}) "
          f"-> {error_path}")
    return F, E


def _save_without_records(path, M):
    """``np.save`` a matrix computed in memory, removing what a resumable run to the same
    path left beside it (its record and its rows done), which would otherwise pass the
    file for that run's."""
    import os
    import shutil

    from .storage import path_stem

    stem = path_stem(path)
    for beside in (stem + ".meta.json", stem + ".done.npy", stem + ".parts"):
        if os.path.isdir(beside):
            shutil.rmtree(beside)
        elif os.path.exists(beside):
            os.remove(beside)
    np.save(path, M)


def read_points(path):
    """Viewpoints from a file: ``.npy`` (an array of shape (P, 3)) or text with three
    numbers a line (separated by commas or white space; ``#`` starts a comment)."""
    try:
        if path.endswith(".npy"):
            P = np.load(path)
        else:
            with open(path, encoding="utf-8") as fh:
                text = fh.read().replace(",", " ")
            P = np.loadtxt(text.splitlines(), ndmin=2)
    except OSError as exc:
        raise ValueError(f"--points {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise ValueError(f"--points {path}: not three numbers a line ({exc})") from None
    P = np.asarray(P, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0:
        raise ValueError(f"--points {path}: expected an array of shape (P, 3), got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise ValueError(f"--points {path}: every coordinate must be finite")
    return P


def _sphere_matrix(scene, rows, args, out):
    """``exactff matrix --sphere``: spherical factors (visible solid angle / 4 pi) from
    the points of ``--points`` (or, without it, from the centroids of ``rows``), written
    to a .npy with their bounds beside it (STEM.error.npy)."""
    from .sphere import sphere_form_factors

    if args.sparse or args.scheduler or args.area or args.jobs > 1 or not out.endswith(".npy"):
        raise ValueError("--sphere writes a dense .npy (not with --sparse, --scheduler, "
                         "--area, --jobs or .zarr)")
    points = read_points(args.points) if args.points else scene.centroids[rows]
    S, E = sphere_form_factors(scene, points, two_sided=not args.front_only, error=True)
    _save_without_records(out, S)
    _save_without_records(out[:-4] + ".error.npy", E)
    what = f"{len(points)} points of {args.points}" if args.points else "the centroids"
    print(f"sphere           visible solid angle / 4 pi from {what}"
          + ("" if args.points else " (each polygon edge-on from its own centroid: a "
             "closed room's rows sum to 1/2)"))
    print(f"error bounds     max {E.max(initial=0.0):.3g} -> {out[:-4] + '.error.npy'}")
    return S


def cmd_matrix(args):
    import os
    import shutil
    import time

    from .formfactors import form_factor_matrix
    from .storage import beside_path, output_path, path_stem, path_suffix

    scene = _open(args)
    if args.combine and not args.area:
        raise ValueError("--combine: the surfaces View3D reports, with --area")
    if args.combine:
        from .combine import combined_surfaces

        n_rows = len(combined_surfaces(scene))
        rows = None if args.rows in (None, "all") else parse_rows(args.rows, n_rows)
    else:
        rows = parse_rows(args.rows, len(scene))
    if args.jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {args.jobs}")
    if (args.points or args.front_only) and not args.sphere:
        raise ValueError("--points and --front-only go with --sphere")
    if args.points and args.rows not in (None, "all"):
        raise ValueError("--rows selects centroids: not with --points")
    if args.scheduler and args.jobs > 1:
        raise ValueError("--jobs and --scheduler: give one (the scheduler's workers run the rows)")
    out = args.output
    if out is None:
        stem = args.scene.split(":")[0].rsplit("/", 1)[-1].rsplit(".", 1)[0]
        big = (len(scene) if rows is None else len(rows)) * len(scene) * 8 > DENSE_OUTPUT_BYTES
        out = (f"{stem}_sphere.npy" if args.sphere else
               f"{stem}_ff" + (".npz" if args.sparse else ".zarr" if big else ".npy"))
    out = output_path(out, args.sparse)
    suffix = path_suffix(out, "--output")
    if args.area and args.remainder:
        raise ValueError("--remainder is for point rows (not with --area)")
    if args.up is not None and not args.remainder:
        raise ValueError("--up is the up direction of --remainder: give --remainder too")
    if args.sparse != (suffix == ".npz"):
        raise ValueError(f"--output {out}: " + ("--sparse writes a .npz file" if args.sparse
                                                 else "a .npz output needs --sparse"))
    stem = path_stem(out)
    if args.overwrite:
        beside = [s + e for s in (stem + ".remainder", path_stem(beside_path(out, "error")))
                  for e in (".done.npy", ".meta.json", ".parts")]
        beside += [stem + ".remainder.npy", beside_path(out, "error")]
        for path in (out, stem + ".done.npy", stem + ".meta.json", stem + ".parts", *beside):
            if os.path.isdir(path):
                shutil.rmtree(path)
            elif os.path.exists(path):
                os.remove(path)
    elif (not (args.sphere or args.combine)
          and (os.path.exists(out) or os.path.exists(stem + ".parts"))):
        print(f"resuming {out} (rows already written are kept; --overwrite to start over)")
    executor = client = None
    if args.scheduler:
        try:
            from dask.distributed import Client
        except ImportError:
            raise ValueError("--scheduler needs dask.distributed: pip install 'exactff[scale]'"
                             ) from None
        try:
            client = executor = Client(args.scheduler, timeout=args.scheduler_timeout)
        except (OSError, TimeoutError) as e:
            raise ValueError(f"--scheduler {args.scheduler}: cannot connect ({e})") from None
    t0 = time.perf_counter()
    E = R = None
    try:
        if args.sphere:
            M = _sphere_matrix(scene, rows, args, out)
        elif args.area:
            M, E = _area_matrix(scene, rows, args, out, executor)
        else:
            M = form_factor_matrix(scene, rows=rows, two_sided=args.two_sided,
                                   executor=executor, jobs=args.jobs if args.jobs > 1 else None,
                                   sparse=args.sparse, progress=not args.no_progress, out=out,
                                   remainder=args.remainder, up=args.up)
            if args.remainder:
                M, R = M
    finally:
        if client is not None:
            client.close()
    elapsed = time.perf_counter() - t0
    if args.csv:
        import scipy.sparse as sp

        np.savetxt(args.csv, M.toarray() if sp.issparse(M) else np.asarray(M), delimiter=",",
                   fmt="%.17g")
    _, zero_share = _matrix_summary(M)
    print(f"scene            {args.scene} ({len(scene)} polygons)")
    what = ("area-to-area, the surfaces View3D reports" if args.combine else "area-to-area"
            if args.area else "rows from the "
            + ("points" if args.sphere and args.points else "polygons' centroids"))
    print(f"matrix           {M.shape[0]} x {M.shape[1]} {what} "
          f"-> {out}" + (f" and {args.csv}" if args.csv else ""))
    if R is not None:
        print(f"remainder        sky and ground per row -> {stem}.remainder.npy "
              f"(sky max {R[:, 0].max():.6g}, ground max {R[:, 1].max():.6g})")
    print(f"time             {elapsed:.3f} s ({elapsed / max(M.shape[0], 1) * 1e3:.2f} ms per row)")
    print(f"zero entries     {zero_share:.1%}")
    if not args.sphere:  # spherical rows have no invariant of 1 to report
        # (the surfaces View3D reports are not the scene's polygons: judged alone)
        _write_report(M, None if args.combine else scene, E, R,
                      None if args.combine else rows, args.area, stem + ".report.json")
    return 0


def _write_report(M, scene, E, R, rows, area, path):
    """The invariants' report (:func:`exactff.check_matrix`): its summary printed, the
    whole written to ``path`` (JSON)."""
    import json

    from .reports import check_matrix

    report = check_matrix(M, scene, E, remainder=R, rows=rows, area=area)
    print("-- report (exactff.check_matrix) " + "-" * 40)
    print(str(report))
    doc = report.to_dict()
    per_row = ("rows", "sums", "deficits", "row_bounds")
    # the summary first, the per-row arrays after it
    doc = {**{k: v for k, v in doc.items() if k not in per_row},
           **{k: doc[k] for k in per_row}}
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1, allow_nan=True)
    print(f"report           -> {path}")
    return report


def _rows_for_study(text, seed, n):
    """``--rows``: an integer K (K rows drawn without replacement with ``--seed``), or
    'all', 'A:B', 'i,j,...'."""
    if text not in (None, "all") and text.isdigit():
        k = int(text)
        if not 0 < k <= n:
            raise ValueError(f"--rows {text}: expected 1 to {n} rows (the scene has {n})")
        return np.sort(np.random.default_rng(seed).choice(n, k, replace=False))
    return parse_rows(text, n)


def _int_list(text, name):
    try:
        vals = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(f"{name}: expected comma-separated positive integers, got {text!r}") from None
    if not vals or min(vals) <= 0:
        raise ValueError(f"{name}: expected comma-separated positive integers, got {text!r}")
    return vals


def _save_figures(out, figures):
    """Draw ``figures``, pairs ``(name, draw)`` with ``draw(exactff.plot)`` returning
    the Axes it drew, to ``OUT/NAME.png``; the names written (none, said so, without
    matplotlib)."""
    import os

    try:
        import matplotlib
    except ImportError:
        print("figures: not drawn (pip install exactff[plots] for them)")
        return []
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from . import plot

    written = []
    for name, draw in figures:
        ax = draw(plot)
        ax.figure.tight_layout()
        ax.figure.savefig(os.path.join(out, name + ".png"), dpi=120)
        plt.close(ax.figure)
        written.append(name + ".png")
    return written


def cmd_compare(args):
    import csv
    import json
    import os
    import platform

    from .version import __version__
    from .methods import METHODS
    from .reports import compare, to_markdown

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    bad = [m for m in methods if m not in METHODS]
    if not methods or bad:
        raise ValueError(f"--methods: unknown {bad or methods!r}; choose from "
                         f"{', '.join(sorted(METHODS))}")
    samples = _int_list(args.samples, "--samples")
    scene = _open(args)
    rows = _rows_for_study(args.rows, args.seed, len(scene))
    os.makedirs(args.out, exist_ok=True)
    reference = args.reference or os.path.join(args.out, "reference.npz")
    records = compare(scene, methods, samples=samples, rows=rows, reference=reference,
                      two_sided=args.two_sided, progress=not args.no_progress)
    print(f"scene {args.scene} ({len(scene)} polygons), {len(rows)} rows"
          + (f" (seed {args.seed})" if args.rows not in (None, "all") and args.rows.isdigit()
             else ""))
    print(to_markdown(records))
    doc = {"records": records, "scene": args.scene, "polygons": len(scene),
           "rows": rows.tolist(), "seed": args.seed, "samples": samples, "methods": methods,
           "two_sided": bool(args.two_sided), "reference": reference,
           "exactff": __version__,
           "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
                      f"python {platform.python_version()}, numpy {np.__version__}"}
    with open(os.path.join(args.out, "results.json"), "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1)
    with open(os.path.join(args.out, "results.csv"), "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(records[0]))
        w.writeheader()
        w.writerows(records)
    def titled(draw):
        def drawn(plot):
            ax = draw(plot)(records)
            ax.set_title(f"{ax.get_title()}: {args.scene}, {len(rows)} rows")
            return ax
        return drawn

    written = ["results.csv", "results.json"] + _save_figures(args.out, [
        ("error_vs_samples", titled(lambda plot: plot.error_vs_samples)),
        ("time_vs_samples", titled(lambda plot: plot.time_vs_samples)),
        ("error_vs_time", titled(lambda plot: plot.error_vs_time))])
    print(f"written to {args.out}: {', '.join(written)}")
    return 0


def cmd_audit(args):
    """``exactff audit SCENE MATRIX``: another tool's matrix against the exact one
    (:func:`exactff.audit`), its report printed and written to ``OUT/audit.json``, the
    worst entries to ``OUT/worst.csv``, figures where matplotlib is installed."""
    import csv
    import json
    import os

    from .audits import audit
    from .io import read_view_factors
    from .version import __version__

    scene = _open(args)
    kind = "point" if (args.points or args.centroids) else "area"
    points = read_points(args.points) if args.points else None
    if args.jobs < 1:
        raise ValueError(f"--jobs must be at least 1, got {args.jobs}")
    if args.worst < 0:
        raise ValueError(f"--worst must be at least 0, got {args.worst}")
    if args.tolerance is not None and not (args.tolerance > 0):
        raise ValueError(f"--tolerance must be positive, got {args.tolerance}")
    F = read_view_factors(args.matrix, scene, format=args.format, zone=args.zone,
                          region=args.region)
    os.makedirs(args.out, exist_ok=True)
    # the exact values stream to OUT, or --exact (resumed by a second run of the same
    # audit: of another matrix of the same scene too)
    exact_path = args.exact or os.path.join(args.out, f"exact_{kind}.npy")
    if not exact_path.endswith(".npy"):
        raise ValueError(f"--exact {exact_path}: expected a .npy file")
    if args.overwrite:
        from .storage import beside_path, path_stem

        for path in (exact_path, beside_path(exact_path, "error")):
            for p in (path, path_stem(path) + ".done.npy", path_stem(path) + ".meta.json"):
                if os.path.exists(p):
                    os.remove(p)
    rep = audit(scene, F, kind=kind, points=points, tolerance=args.tolerance,
                jobs=args.jobs if args.jobs > 1 else None, out=exact_path,
                progress=not args.no_progress)
    print(f"scene            {args.scene} ({len(scene)} polygons)")
    print(f"matrix           {args.matrix}")
    print(str(rep))
    doc = dict(rep.to_dict(worst=args.worst), scene=args.scene, matrix=args.matrix,
               exactff=__version__)
    with open(os.path.join(args.out, "audit.json"), "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1, allow_nan=False)
    fields = ["i", "j", "from", "to", "from_group", "to_group", "other", "exact", "bound",
              "error", "relative_error", "present", "configurations"]
    with open(os.path.join(args.out, "worst.csv"), "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        for row in rep.worst_entries(args.worst):
            w.writerow({k: ";".join(v) if isinstance(v, list) else v
                        for k, v in row.items()})
    written = ["audit.json", "worst.csv", exact_path] + _save_figures(args.out, [
        ("error_vs_distance", lambda plot: plot.audit_error_vs_distance(rep)),
        ("relative_errors", lambda plot: plot.audit_relative_errors(rep)),
        ("row_errors", lambda plot: plot.audit_row_errors(rep, scene))])
    print(f"written to {args.out}: {', '.join(written)}")
    return 0


def build_parser():
    parser = argparse.ArgumentParser(
        prog="exactff",
        description="Exact form factors (view factors) for scenes of planar polygons.")
    from .version import __version__

    parser.add_argument("--version", action="version", version=f"exactff {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("info", help="size, area, bounds, planarity and closure of a scene")
    _scene_arguments(p)
    p.set_defaults(func=cmd_info)
    p = sub.add_parser("ff", help="unoccluded form factors from one point to every polygon")
    _scene_arguments(p)
    p.add_argument("--point", nargs=3, type=float, required=True, metavar=("X", "Y", "Z"))
    p.add_argument("--normal", nargs=3, type=float, required=True, metavar=("X", "Y", "Z"))
    _remainder_arguments(p, "with occlusion (the exact method), and the uncovered rest of "
                            "the hemisphere: sky above the horizontal plane, ground below")
    p.set_defaults(func=cmd_ff)
    p = sub.add_parser("matrix", help="exact form-factor matrix (rows from the polygons' "
                                      "centroids), written to .npy, .zarr or .npz, with "
                                      "the report of its invariants (STEM.report.json)")
    _scene_arguments(p)
    p.add_argument("-o", "--output", help="output: .npy (dense), .zarr (chunked, "
                                          "compressed) or .npz (sparse, with --sparse); "
                                          "without one of these suffixes .npy (.npz with "
                                          "--sparse) is appended; default SCENE_ff.npy, "
                                          ".zarr above 2 GiB, .npz with --sparse; an "
                                          "interrupted run resumes from it")
    p.add_argument("--sparse", action="store_true",
                   help="keep the non-zero values only (scipy.sparse CSR in a .npz)")
    p.add_argument("--area", action="store_true",
                   help="area-to-area form factors (the paper's Eq. 1) with occlusion, "
                        "each within --tolerance, instead of rows from the centroids; "
                        "their bounds to STEM.error.SUFFIX beside the output")
    p.add_argument("--combine", action="store_true",
                   help="with --area: one row and column per surface View3D reports (a "
                        ".vs3 file's combined surfaces merged, subsurfaces separated, "
                        "obstructions left out), as View3D prints them")
    p.add_argument("--tolerance", type=float, default=1e-9,
                   help="absolute error allowed per value with --area (default 1e-9)")
    p.add_argument("--sphere", action="store_true",
                   help="spherical factors (visible solid angle / 4 pi, both faces "
                        "receiving) from --points or the centroids, instead of plane "
                        "form factors; writes a dense .npy and STEM.error.npy")
    p.add_argument("--points", metavar="FILE",
                   help="with --sphere: the viewpoints, .npy of shape (P, 3) or text with "
                        "three numbers a line")
    p.add_argument("--front-only", action="store_true",
                   help="with --sphere: only the front of a polygon receives")
    p.add_argument("--csv", help="also write the matrix as CSV")
    p.add_argument("--rows", default="all", help="'all', 'A:B' or 'i,j,...' (the centroids "
                                                 "with --sphere: not with --points)")
    p.add_argument("--two-sided", action="store_true", help="polygons receive on both sides")
    p.add_argument("--jobs", type=int, default=1, help="worker processes on this machine")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="send the rows to a running dask.distributed scheduler "
                        "(tcp://host:8786); needs exactff[scale]")
    p.add_argument("--scheduler-timeout", type=float, default=30.0, metavar="SECONDS",
                   help=argparse.SUPPRESS)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--overwrite", action="store_true",
                   help="start over instead of resuming an existing output file")
    _remainder_arguments(p, "also each row's sky and ground (the uncovered hemisphere above "
                            "and below the horizontal plane), written to "
                            "STEM.remainder.npy (columns sky, ground)")
    p.set_defaults(func=cmd_matrix)
    p = sub.add_parser("compare", help="error against run time of discrete methods "
                                       "(and the exact method) on a scene: tables, CSV, "
                                       "JSON and figures")
    _scene_arguments(p)
    p.add_argument("--methods", required=True,
                   help="comma-separated: exact, ppbh, hemicube, cubic_tetrahedron, "
                        "single_plane, polar_plane, monte_carlo")
    p.add_argument("--samples", default="4096,65536",
                   help="comma-separated sample counts (methods with samples run at each)")
    p.add_argument("--rows", default="all",
                   help="K (K rows drawn with --seed), 'all', 'A:B' or 'i,j,...'")
    p.add_argument("--seed", type=int, default=0, help="seed of the rows drawn (--rows K)")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--reference", help="cache of the exact rows (.npz; default "
                                       "OUT/reference.npz, reused when it matches)")
    p.add_argument("--two-sided", action="store_true", help="polygons receive on both sides")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_compare)
    p = sub.add_parser("audit", help="another tool's form-factor matrix against the exact "
                                     "one: errors per entry, row sums, reciprocity, the "
                                     "worst entries, by configuration; JSON, CSV, figures")
    _scene_arguments(p)
    p.add_argument("matrix", help="the other tool's matrix: View3D output (text or "
                                  "binary), an OpenFOAM case (constant/F and "
                                  "globalFaceFaces), an EnergyPlus IDF "
                                  "(ZoneProperty:UserViewFactors:BySurfaceName), Elmer's "
                                  "ViewFactors.dat, .npy, .npz or .csv")
    from .io.view_factors import VIEW_FACTOR_FORMATS

    p.add_argument("--format", choices=list(VIEW_FACTOR_FORMATS),
                   help="the matrix's format (default: from its name and first bytes)")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--area", action="store_true",
                       help="area-to-area form factors (the default: View3D, OpenFOAM, "
                            "EnergyPlus and Elmer compute these)")
    which.add_argument("--centroids", action="store_true",
                       help="point rows from the polygons' centroids (hemicubes, ray "
                            "casters from patch centres)")
    which.add_argument("--points", metavar="FILE",
                       help="point rows from these receivers, one per polygon (.npy of "
                            "shape (N, 3) or three numbers a line), with the polygons' "
                            "normals")
    p.add_argument("--tolerance", type=float, default=None,
                   help="of the exact values: absolute with --area (default 1e-9), "
                        "relative for point rows (default the exact method's)")
    p.add_argument("--zone", help="EnergyPlus: the zone whose view factors to read")
    p.add_argument("--region", help="OpenFOAM: the mesh region")
    p.add_argument("--worst", type=int, default=20,
                   help="how many of the worst entries to list (default 20)")
    p.add_argument("--out", default="audit", help="output directory (default ./audit)")
    p.add_argument("--exact", metavar="PATH.npy",
                   help="where the exact values go (their bounds beside it, "
                        "PATH.error.npy), resumed from it by the next audit of the same "
                        "scene, kind and tolerance (default OUT/exact_area.npy or "
                        "OUT/exact_point.npy)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes on this machine")
    p.add_argument("--overwrite", action="store_true",
                   help="recompute the exact values instead of resuming them")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_audit)
    return parser


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


def main(argv=None):
    """Entry point of the ``exactff`` command.

    Returns the exit status: 0 on success, 2 for a usage error (bad arguments, a scene
    that cannot be opened or is invalid, an output of another computation; argparse's
    own errors exit with 2 too), 1 when the computation fails (an
    :class:`exactff.NumericalError`: a value that cannot be computed to its tolerance;
    running out of memory). Each error is one line on stderr, without a traceback.
    """
    from .errors import NumericalError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except NumericalError as exc:
        print(f"exactff: numerical error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except MemoryError as exc:
        print(f"exactff: error: out of memory ({_one_line(exc)})", file=sys.stderr)
        return 1
    except (ValueError, OSError) as exc:
        print(f"exactff: error: {_one_line(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
