"""Real files at scale (issue 29): a procedural ~300k-triangle furnished room as an OBJ,
with the defects real exports have, loaded, summarised and prepared for the engine.

Usage: python benchmarks/bench_real_files.py [--cells 720] [--work DIR] [--skip-bsp]
       [--no-trace]

The room (``furnished_room_obj``): a 45 x 36 x 3 m shell placed far from the origin
(x about 1620, y about -1013, as the issue's conference room), 40 x 40 quads per face
split into triangles, and ``--cells`` desk cells, each a table (5 boxes), a mat on the
table (its bottom exactly on the table top in half the cells, 1e-13 above it in the
others: faces flush to 1e-13), two chairs (6 boxes each), a bottle (a 16-gon cylinder)
and a lamp (a 32-gon cone whose apex is 32 collapsed vertices: a triangle per segment
with two equal vertices, and a top cap of 32 triangles of one point), all triangles.
413 cells add an exactly collinear sliver triangle along the table's edge (the
"self-intersecting" triangles far from the origin). 720 cells: 313,373 triangles, 46,493
(14.8 %) degenerate. The same room without the defective faces is written beside it
(``room_clean.obj``): the file the old code could load, for the before figures.

Each phase runs in its own process (so that ``ru_maxrss`` is that phase's peak), twice:
once timed, once under ``tracemalloc`` (peak of Python allocations, numpy's included):

- ``load``: ``load_scene(room.obj, degenerate="drop")``;
- ``load clean``: ``load_scene(room_clean.obj)``, and with ``nonplanar="split"``
  (issue 4: the ratio split / error is the cost of the option where nothing is split);
- ``info``: ``exactff info room.obj --drop-degenerate`` (load, ``describe``, print);
- ``overlaps (plane hash)``: the coplanar overlaps as ``describe`` now finds them
  (``exactff.visibility.plane_overlaps``), after the load;
- ``BSP set-up``: the engine's BSP tree and padded buckets (``scene_bsp``), after the
  load;
- ``overlaps (BSP)``: the BSP tree and the coplanar overlaps read off it
  (``exactff.visibility.coplanar_overlaps``: what ``describe`` did before), after the
  load: the baseline of the plane hash.

Run against an older checkout (without ``degenerate=``), the phases that need it are
reported as n/a and the clean file stands in.
"""

import argparse
import inspect
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402

#: room placement: far from the origin in x and y (z up, floor at z = 0)
ORIGIN = np.array([1620.33, -1013.51, 0.0])
FLUSH_GAP = 1e-13


class _Mesh:
    """Vertices and triangles, with a defect flag per triangle."""

    def __init__(self):
        self.V, self.T, self.bad, self.groups = [], [], [], []
        self.nv = 0

    def solid(self, V, T, centre, group, defect=None):
        """Add a closed solid: triangles turned to face away from ``centre``."""
        V = np.asarray(V, dtype=float)
        T = np.asarray(T, dtype=int)
        a, b, c = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
        n = np.cross(b - a, c - a)
        flip = np.einsum("ij,ij->i", n, (a + b + c) / 3 - centre) < 0
        T[flip] = T[flip][:, ::-1]
        self.V.append(V)
        self.T.append(T + self.nv)
        self.bad.append(np.zeros(len(T), dtype=bool) if defect is None else defect)
        self.groups.append((group, len(T)))
        self.nv += len(V)

    def box(self, lo, hi, group):
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        corner = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)])
        V = lo + corner * (hi - lo)
        quads = [(0, 2, 6, 4), (1, 3, 7, 5), (0, 1, 5, 4), (2, 3, 7, 6), (0, 1, 3, 2),
                 (4, 5, 7, 6)]
        T = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
        self.solid(V, T, (lo + hi) / 2, group)

    def cylinder(self, centre, r0, r1, z0, z1, n, group):
        """A cylinder (r1 = r0) or a cone (r1 = 0: its apex is n collapsed vertices)."""
        t = 2 * np.pi * np.arange(n) / n
        ring = np.column_stack([np.cos(t), np.sin(t)])
        bottom = np.column_stack([centre[:2] + r0 * ring, np.full(n, z0)])
        top = np.column_stack([centre[:2] + r1 * ring, np.full(n, z1)])
        V = np.concatenate([bottom, top, [[centre[0], centre[1], z0], [centre[0], centre[1], z1]]])
        i, j = np.arange(n), (np.arange(n) + 1) % n
        T = np.concatenate([np.column_stack([i, j, n + j]), np.column_stack([i, n + j, n + i]),
                            np.column_stack([np.full(n, 2 * n), j, i]),
                            np.column_stack([np.full(n, 2 * n + 1), n + i, n + j])])
        defect = np.zeros(len(T), dtype=bool)
        if r1 == 0:
            defect[n:2 * n] = True          # (b_i, apex, apex)
            defect[3 * n:] = True           # (apex, apex, apex)
        mid = np.array([centre[0], centre[1], (z0 + z1) / 2])
        self.solid(V, T, mid, group, defect)

    def sliver(self, p, length, group):
        """An exactly collinear triangle along x (its y and z are equal)."""
        V = p + np.array([[0, 0, 0], [0.37 * length, 0, 0], [length, 0, 0]])
        self.V.append(V)
        self.T.append(np.array([[0, 1, 2]]) + self.nv)
        self.bad.append(np.ones(1, dtype=bool))
        self.groups.append((group, 1))
        self.nv += 3


def _shell(mesh, size, k):
    """The room's six faces, k x k quads each split in two, facing in."""
    u = np.linspace(0, 1, k + 1)
    for axis in range(3):
        for side in (0, 1):
            a, b = [d for d in range(3) if d != axis]
            g = np.zeros(((k + 1) ** 2, 3))
            A, B = np.meshgrid(u, u, indexing="ij")
            g[:, a], g[:, b] = A.ravel() * size[a], B.ravel() * size[b]
            g[:, axis] = side * size[axis]
            idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
            q = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4)
            T = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
            inside = np.array(size, dtype=float) / 2
            inside[axis] = side * size[axis] + (side - 0.5) * 2e6   # outside: faces turn in
            mesh.solid(ORIGIN + g, T, ORIGIN + inside, f"shell{axis}{side}")


def furnished_room_obj(path, clean_path=None, cells=720, shell_k=40, slivers=413):
    """Write the furnished room (module docstring) to ``path`` and, without its
    defective faces, to ``clean_path``; returns (triangles, defective)."""
    mesh = _Mesh()
    nx = int(np.ceil(np.sqrt(cells * 1.25)))
    ny = int(np.ceil(cells / nx))
    size = (1.5 * nx + 1.5, 2.0 * ny + 1.5, 3.0)
    _shell(mesh, size, shell_k)
    for c in range(cells):
        x0 = ORIGIN + np.array([1.0 + 1.5 * (c % nx), 1.0 + 2.0 * (c // nx), 0.0])
        for dx, dy in ((0, 0), (1.1, 0), (0, 0.7), (1.1, 0.7)):
            mesh.box(x0 + [dx, dy, 0], x0 + [dx + 0.1, dy + 0.1, 0.72], f"table{c}")
        mesh.box(x0 + [0, 0, 0.72], x0 + [1.2, 0.8, 0.75], f"table{c}")
        gap = FLUSH_GAP if c % 2 else 0.0
        mesh.box(x0 + [0.1, 0.1, 0.75 + gap], x0 + [0.7, 0.5, 0.755], f"mat{c}")
        for cy in (-0.45, 0.85):
            s = x0 + [0.4, cy, 0]
            for dx, dy in ((0, 0), (0.36, 0), (0, 0.36), (0.36, 0.36)):
                mesh.box(s + [dx, dy, 0], s + [dx + 0.04, dy + 0.04, 0.43], f"chair{c}")
            mesh.box(s + [0, 0, 0.43], s + [0.4, 0.4, 0.46], f"chair{c}")
            back = 0.0 if cy < 0 else 0.37
            mesh.box(s + [0, back, 0.46], s + [0.4, back + 0.03, 0.9], f"chair{c}")
        mesh.cylinder(x0 + [0.3, 0.3, 0], 0.04, 0.04, 0.755, 0.98, 16, f"bottle{c}")
        mesh.cylinder(x0 + [0.9, 0.6, 0], 0.12, 0.0, 0.75, 1.1, 32, f"lamp{c}")
        if c < slivers:
            mesh.sliver(x0 + [0.0, 0.0, 0.75], 1.2, f"table{c}")
    V = np.concatenate(mesh.V)
    T = np.concatenate(mesh.T)
    bad = np.concatenate(mesh.bad)
    groups = np.repeat([g for g, _ in mesh.groups], [m for _, m in mesh.groups])
    for out, keep in ((path, np.ones(len(T), dtype=bool)), (clean_path, ~bad)):
        if out is None:
            continue
        with open(out, "w", encoding="utf-8") as fh:
            fh.write(f"# furnished room, {int(keep.sum())} triangles (benchmarks/bench_real_files.py)\n")
            np.savetxt(fh, V, fmt="v %.17g %.17g %.17g")
            last = None
            for g, (a, b, c) in zip(groups[keep], T[keep] + 1):
                if g != last:
                    fh.write(f"g {g}\n")
                    last = g
                fh.write(f"f {a} {b} {c}\n")
    return len(T), int(bad.sum())


# ---------------------------------------------------------------------------------------
# phases, each run in its own process
# ---------------------------------------------------------------------------------------
def _has_degenerate():
    import exactff as ef

    return "degenerate" in inspect.signature(ef.load_scene).parameters


def _load(path, **options):
    import exactff as ef

    return ef.load_scene(path, **options)


def phase(name, work):
    """Run one phase; returns its wall time (s)."""
    import exactff as ef

    room, clean = os.path.join(work, "room.obj"), os.path.join(work, "room_clean.obj")
    drop = _has_degenerate()
    t0 = time.perf_counter()
    if name == "load":
        if not drop:
            return None
        _load(room, degenerate="drop")
    elif name == "load clean":
        _load(clean)
    elif name == "load clean, split":
        _load(clean, nonplanar="split")
    elif name == "info":
        from exactff.cli import main

        argv = ["info", room, "--drop-degenerate"] if drop else ["info", clean]
        with open(os.devnull, "w") as devnull:
            stdout, sys.stdout = sys.stdout, devnull
            try:
                main(argv)
            finally:
                sys.stdout = stdout
    elif name == "overlaps (plane hash)":
        from exactff import visibility

        if not hasattr(visibility, "plane_overlaps"):
            return None
        scene = _load(room, degenerate="drop")
        t0 = time.perf_counter()
        visibility.plane_overlaps(scene)
    elif name in ("overlaps (BSP)", "BSP set-up"):
        from exactff.visibility import coplanar_overlaps, scene_bsp

        scene = _load(room, degenerate="drop") if drop else _load(clean)
        t0 = time.perf_counter()
        if name == "overlaps (BSP)":
            coplanar_overlaps(scene, scene_bsp(scene)[0])
        else:
            scene_bsp(scene)
    else:
        raise ValueError(f"unknown phase {name!r}")
    return time.perf_counter() - t0


PHASES = ["load clean", "load clean, split", "load", "info", "overlaps (plane hash)",
          "BSP set-up", "overlaps (BSP)"]


def _child(name, work, traced):
    if traced:
        tracemalloc.start()
    t = phase(name, work)
    peak = tracemalloc.get_traced_memory()[1] if traced else None
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    print(json.dumps({"time": t, "peak": peak, "rss": rss}))


def run_child(name, work, traced):
    out = subprocess.run([sys.executable, __file__, "--child", name, "--work", work]
                         + (["--traced"] if traced else []),
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, default=720)
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "exactff_real_files"),
                    help="where the OBJ files are written (kept: a rerun reuses them)")
    ap.add_argument("--skip-bsp", action="store_true", help="leave out the BSP phases")
    ap.add_argument("--no-trace", action="store_true", help="leave out the tracemalloc runs")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--traced", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return _child(args.child, args.work, args.traced)
    os.makedirs(args.work, exist_ok=True)
    room = os.path.join(args.work, "room.obj")
    stamp = os.path.join(args.work, "cells.txt")
    if not (os.path.exists(stamp) and open(stamp).read() == str(args.cells)):
        t = time.perf_counter()
        n, bad = furnished_room_obj(room, os.path.join(args.work, "room_clean.obj"), args.cells)
        with open(stamp, "w") as fh:
            fh.write(str(args.cells))
        print(f"wrote {room}: {n:,} triangles, {bad:,} defective ({bad / n:.1%}) "
              f"in {time.perf_counter() - t:.1f} s")
    import exactff as ef

    print(machine())
    print(f"exactff {ef.__version__} from {os.path.dirname(ef.__file__)}")
    print("| phase | time (s) | / load clean | tracemalloc peak (MiB) | ru_maxrss (MiB) |")
    print("|---|---|---|---|---|")
    base = None
    for name in PHASES:
        if args.skip_bsp and name in ("BSP set-up", "overlaps (BSP)"):
            continue
        timed = run_child(name, args.work, False)
        if timed["time"] is None:
            print(f"| {name} | n/a | | | |", flush=True)
            continue
        traced = None if args.no_trace else run_child(name, args.work, True)
        if name == "load clean":
            base = timed["time"]
        ratio = f"{timed['time'] / base:.2f}" if base else ""
        peak = f"{traced['peak'] / 2**20:.0f}" if traced else ""
        print(f"| {name} | {timed['time']:.2f} | {ratio} | {peak} | "
              f"{timed['rss'] / 2**20:.0f} |", flush=True)


if __name__ == "__main__":
    main()
