"""The closed cube's exact matrix against a bare vectorised kernel over all pairs (issue 52).

Usage: python benchmarks/bench_closed_cube.py [--k 16] [--chunk 8] [--goal 2]

``scenes.subdivided_box(k)`` (6 k^2 quads, closed, convex: nothing hides anything) is
the case where the exact method has nothing to do but integrate: every row takes the
unoccluded path (the sector sums with their bound and escalation where the bound misses
the tolerance, 1e-12). Its time is compared, in the same run, with the least a
vectorised evaluation of the same values costs: Lambert's sum of every edge of every
polygon from every centroid in numpy, ``chunk`` rows at a time, in double, with no
culling, horizon clipping (nothing crosses a centroid's horizon here), error bound or
escalation. The script prints the two times (process time, and wall), their ratios,
the largest difference of the two matrices and of a row sum from 1, and exits with
status 1 if the ratio of process times exceeds ``--goal`` (the machines are shared: wall
time counts the other jobs' share of the cores; both runs are single-threaded).
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
from exactff.methods import Exact

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402


def bare_matrix(scene, chunk):
    """Lambert's form (DESIGN 2.1) over all pairs: F[i, j] = -1/(2 pi) sum over the edges
    (a, b) of polygon j of theta (n_i . a x b) / |a x b|, a and b the edge's ends from
    centroid i, theta the angle between them (0 on the diagonal). Coordinates as separate
    arrays (numpy's cross and einsum over a last axis of 3 are slower)."""
    V, off = scene.vertices, scene.offsets
    nxt = np.arange(len(V)) + 1
    nxt[off[1:] - 1] = off[:-1]
    W = V[nxt]
    P, N = scene.centroids, scene.normals
    F = np.empty((len(scene), len(scene)))
    for r in range(0, len(scene), chunk):
        p, n = P[r:r + chunk], N[r:r + chunk]
        ax, ay, az = (V[None, :, k] - p[:, k, None] for k in range(3))
        bx, by, bz = (W[None, :, k] - p[:, k, None] for k in range(3))
        mx, my, mz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        s = np.sqrt(mx * mx + my * my + mz * mz)
        theta = np.arctan2(s, ax * bx + ay * by + az * bz)
        mn = mx * n[:, 0, None] + my * n[:, 1, None] + mz * n[:, 2, None]
        t = np.divide(theta * mn, s, out=np.zeros_like(s), where=s > 0)
        F[r:r + chunk] = -np.add.reduceat(t, off[:-1], axis=1) / (2 * np.pi)
    # a centroid's own polygon (its whole fan, -1 by this sum) receives nothing
    np.fill_diagonal(F, 0.0)
    return F


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--k", type=int, default=16)
    ap.add_argument("--chunk", type=int, default=8)
    ap.add_argument("--goal", type=float, default=2.0)
    args = ap.parse_args()
    print(machine())
    box = ef.scenes.subdivided_box(args.k)
    ef.form_factors(box, box.centroids[0], box.normals[0])   # the scene's caches
    t, c = time.perf_counter(), time.process_time()
    G = bare_matrix(box, args.chunk)
    t_bare, c_bare = time.perf_counter() - t, time.process_time() - c
    st = {}
    Exact().point_form_factors(box, box.centroids[0], box.normals[0], stats=st)
    t, c = time.perf_counter(), time.process_time()
    F = ef.form_factor_matrix(box)
    t_exact, c_exact = time.perf_counter() - t, time.process_time() - c
    ratio = c_exact / c_bare
    print("| scene | N | exact matrix (s) | bare kernel, all pairs (s) | ratio (process time) | "
          "ratio (wall) | goal | row path | max abs difference | max abs(row sum - 1) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print(f"| subdivided_box({args.k}) | {len(box)} | {c_exact:.2f} ({t_exact:.2f} wall) | "
          f"{c_bare:.2f} ({t_bare:.2f} wall) | {ratio:.2f} | {t_exact / t_bare:.2f} | "
          f"<= {args.goal:g} | {st.get('path')} | {np.abs(F - G).max():.1e} | "
          f"{np.abs(F.sum(axis=1) - 1).max():.1e} |")
    print(f"goal: exact matrix / bare kernel = {ratio:.2f} in process time (goal <= "
          f"{args.goal:g}): {'MISSED' if ratio > args.goal else 'met'}")
    if ratio > args.goal:
        sys.exit(1)


if __name__ == "__main__":
    main()
