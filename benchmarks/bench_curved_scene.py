"""Curved objects in a room (issue 52): the exact row against Hemicube(256)'s, one run.

Usage: python benchmarks/bench_curved_scene.py [--rows 6] [--sides 1024]

The scene of issue 52's table: a closed unit room of 16 x 16 quads a face with a solid
geodesic sphere of 5,120 triangles in its middle (``exactff.scenes.room_with_sphere(4,
16)``) and a closed cylinder of ``--sides`` side quads and two caps (1,026 polygons by
default: each cap one ``--sides``-gon) standing on the floor beside it. Rows: the
centroids and normals of ``--rows`` seeded polygons (``numpy.random.default_rng(0)``),
the exact row (``Exact()``, its default tolerance) and the hemicube rows (its compiled
z-buffer and its numpy rasteriser) alternating row by row, process time. The script
prints each row's times and ratios, the medians, and the goal (median exact row <= 3
compiled hemicube-256 rows), and exits with status 1 where it is missed.
"""

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from scenes_bench import machine  # noqa: E402

import exactff as ef  # noqa: E402

GOAL = 3.0


def cylinder(centre, radius, z0, z1, sides):
    """A closed cylinder, its faces' fronts outward: ``sides`` quads and two caps."""
    t = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)], axis=1)
    nxt = np.roll(ring, -1, axis=0)
    quads = [np.array([[a[0], a[1], z0], [b[0], b[1], z0], [b[0], b[1], z1], [a[0], a[1], z1]])
             for a, b in zip(ring, nxt)]
    top = np.column_stack([ring, np.full(sides, z1)])
    bottom = np.column_stack([ring, np.full(sides, z0)])[::-1]
    return quads + [top, bottom]


def curved_scene(sides=1024):
    """The room with the sphere and the cylinder (6,656 + sides + 2 polygons)."""
    room = ef.scenes.room_with_sphere(4, 16)
    can = cylinder((0.15, 0.82), 0.1, 0.0, 0.6, sides)
    return ef.Scene.from_polygons(list(room.polygons) + can)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=6)
    ap.add_argument("--sides", type=int, default=1024)
    args = ap.parse_args()
    print(machine())
    scene = curved_scene(args.sides)
    rows = np.random.default_rng(0).choice(len(scene), args.rows, replace=False)
    c, n = scene.centroids, scene.normals
    exact = ef.Exact()
    hemicube = ef.methods.Hemicube(resolution=256)
    hemicube_numpy = ef.methods.Hemicube(resolution=256, backend="numpy")
    for method in (exact, hemicube, hemicube_numpy):      # the set-ups, untimed
        method.point_form_factors(scene, c[rows[0]], n[rows[0]])
    print(f"scene: {len(scene):,} polygons; rows {args.rows}, seed 0")
    print("| row | exact ms | hemicube-256 ms | numpy hemicube ms | exact / hemicube | [numpy] | row sum |")
    print("|---|---|---|---|---|---|---|")
    ratios, numpy_ratios = [], []
    for r in rows:
        times = []
        for method in (exact, hemicube, hemicube_numpy):
            t0 = time.process_time()
            F = method.point_form_factors(scene, c[r], n[r])
            times.append(time.process_time() - t0)
            if method is exact:
                total = float(F.sum())
        ratios.append(times[0] / times[1])
        numpy_ratios.append(times[0] / times[2])
        print(f"| {r} | {1e3 * times[0]:.1f} | {1e3 * times[1]:.1f} | {1e3 * times[2]:.1f} | "
              f"{ratios[-1]:.2f} | [{numpy_ratios[-1]:.2f}] | {total:.12f} |")
    median = float(np.median(ratios))
    print(f"median exact / hemicube-256: {median:.2f} [numpy {np.median(numpy_ratios):.2f}]")
    met = median <= GOAL
    print(f"goal: median exact row <= {GOAL:g} compiled hemicube-256 rows: {'met' if met else 'MISSED'}")
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
