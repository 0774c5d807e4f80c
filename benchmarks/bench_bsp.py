"""BSP set-up: build time, depth, fragments and splits against the number of polygons.

Usage: python benchmarks/bench_bsp.py [--max-level 6]

Geodesic spheres of 1,280 to 81,920 triangles in a closed unit room of 16 x 16 quads per
face (``exactff.scenes.room_with_sphere``), the procedural office and the cloister. For
the spheres also the tree from the polygons' own planes only (the axis-plane candidates
off: the chain a convex tessellation makes), and a hemicube-256 row of the same scene as
the in-run yardstick (issue 20: set-up within the time of 10 such rows).
"""

import argparse
import os
import sys
import time

import numpy as np

import exactff as ef
from exactff import _tolerances as tol
from exactff.visibility import build_bsp


sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine, timed  # noqa: E402



def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-level", type=int, default=6)
    ap.add_argument("--chain-max-level", type=int, default=4)
    args = ap.parse_args()
    print(machine())
    print("| scene | polygons | candidates | build (s) | depth | fragments | splits | "
          "hemicube-256 row (s) | build / row |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = [(f"room + sphere of {20 * 4**lv} triangles", lambda lv=lv: ef.scenes.room_with_sphere(lv))
             for lv in range(3, args.max_level + 1)]
    cases += [("office", ef.scenes.office), ("cloister", ef.scenes.cloister)]
    default = tol.BSP_AXIS_CANDIDATE_MIN
    for name, make in cases:
        scene = make()
        hemi = ef.Hemicube(resolution=256)
        _, t_row = timed(lambda: hemi.point_form_factors(scene, scene.centroids[0], scene.normals[0]))
        modes = [("planes + axis", default)]
        if name.startswith("room") and len(scene) <= 1536 + 20 * 4**args.chain_max_level:
            modes.append(("own planes only", 10**9))
        for label, thr in modes:
            tol.BSP_AXIS_CANDIDATE_MIN = thr
            tree, t_build = timed(lambda: build_bsp(scene))
            tol.BSP_AXIS_CANDIDATE_MIN = default
            print(f"| {name} | {len(scene)} | {label} | {t_build:.2f} | {tree.depth()} | "
                  f"{len(tree.fragments)} | {tree.splits} | {t_row:.3f} | {t_build / t_row:.1f} |",
                  flush=True)


if __name__ == "__main__":
    main()
