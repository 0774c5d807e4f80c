"""Exact rows on a large scene (issue 28): the compiled core's set-up and rows on the
procedural furnished room of ``bench_real_files.py`` against ``Hemicube(256)``, one run.

Usage: python benchmarks/bench_large_rows.py [--scene room|hall|cad] [--cells 720]
       [--rows 6] [--work DIR]

The room (``bench_real_files.furnished_room_obj``, without its defective faces: 266,880
triangles for 720 cells) is loaded once. Then, in this process (time.process_time, the
machine is noisy: compare the ratios):

- set-up: the compiled engine's (``compiled_core``: its BSP tree built in compiled code,
  the fragments made convex, the core), also in units of the median hemicube row, and
  for comparison the Python engine's BSP tree (``scene_bsp``, which compiled rows do not
  use);
- ``--rows`` seeded rows (``np.random.default_rng(0)``) and the floor row nearest the
  first desk cell: ms per row of ``Hemicube(resolution=256)`` and of the
  compiled core alone (``Exact(tolerance=None)``), their ratio, and how many polygons
  each row sees (nonzero exact values) and the core's counters (visible pieces,
  fragments culled, and the row's working memory: ``stats["working_bytes"]``, its own
  containers at their largest beyond the n-long results, per visible piece).

``--scene hall``: ``exactff.scenes.vaulted_hall(24, 256, 48)`` instead (curved
architecture: a barrel vault of long thin triangles on round columns, closed);
``--scene cad``: the real CAD part ``shared/scenes/real/ADIS16480.STL`` (7,436
triangles: holes, pockets, long thin triangles). Seeded rows only for both.
"""

import argparse
import os
import sys
import tempfile
import time

import numpy as np

import exactff as ef
from exactff.visibility import compiled_core, scene_bsp
from exactff.visibility.compiled import compiled_form_factors

sys.path.insert(0, os.path.dirname(__file__))
from bench_real_files import furnished_room_obj  # noqa: E402
from scenes_bench import machine  # noqa: E402


def cpu(f):
    t = time.process_time()
    out = f()
    return out, time.process_time() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", choices=("room", "hall", "cad"), default="room")
    ap.add_argument("--cells", type=int, default=720)
    ap.add_argument("--rows", type=int, default=6)
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "exactff_large_rows"))
    a = ap.parse_args()
    print(machine())
    rng = np.random.default_rng(0)
    if a.scene == "room":
        os.makedirs(a.work, exist_ok=True)
        path = os.path.join(a.work, f"room_clean_{a.cells}.obj")
        if not os.path.exists(path):
            furnished_room_obj(os.path.join(a.work, "room_unused.obj"), path, cells=a.cells)
        scene, t_load = cpu(lambda: ef.load_scene(path))
        print(f"\nfurnished room, {a.cells} cells: {len(scene)} polygons, loaded in {t_load:.1f} s")
    elif a.scene == "hall":
        scene, t_load = cpu(lambda: ef.scenes.vaulted_hall(24, 256, 48))
        print(f"\nvaulted hall (24 bays, 256 segments, 48-sided columns): {len(scene)} polygons, "
              f"built in {t_load:.1f} s")
    else:
        path = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes", "real",
                            "ADIS16480.STL")
        scene, t_load = cpu(lambda: ef.load_scene(path))
        print(f"\nCAD part ADIS16480.STL: {len(scene)} polygons, loaded in {t_load:.1f} s")
    _, t_core = cpu(lambda: compiled_core(scene))
    _, t_bsp = cpu(lambda: scene_bsp(scene))
    rows = [int(i) for i in rng.choice(len(scene), size=a.rows, replace=False)]
    under = None
    if a.scene == "room":
        # the floor row nearest the first desk cell
        floor = [i for i, n in enumerate(scene.normals) if n[2] > 0.99 and
                 scene.centroids[i][2] < scene.vertices[:, 2].min() + 1e-6]
        x0 = scene.vertices[:, :2].min(axis=0) + [1.6, 1.4]
        under = min(floor, key=lambda i: np.linalg.norm(scene.centroids[i][:2] - x0))
        rows.append(under)
    hemi = ef.Hemicube(resolution=256)
    core = ef.Exact(tolerance=None)
    print("| row | hemicube-256 ms | core ms | core / hemicube | polygons seen | visible pieces "
          "| fragments culled | working memory (KiB) | bytes / visible piece |")
    print("|---|---|---|---|---|---|---|---|---|")
    t_h_all = []
    ratios = []
    for i in rows:
        p, n = scene.centroids[i], scene.normals[i]
        _, t_h = cpu(lambda: ef.form_factors(scene, p, n, method=hemi))
        st = {}
        F, t_c = cpu(lambda: compiled_form_factors(scene, p, n, tolerance=None, stats=st))
        seen = int(np.count_nonzero(F))
        t_h_all.append(t_h)
        ratios.append(t_c / t_h)
        label = f"{i} (floor)" if i == under else str(i)
        print(f"| {label} | {1e3 * t_h:.0f} | {1e3 * t_c:.0f} | {t_c / t_h:.2f} | {seen} | "
              f"{st.get('visible_pieces', 0)} | {st.get('fragments_culled', 0)} | "
              f"{st.get('working_bytes', 0) / 1024:.0f} | "
              f"{st.get('working_bytes', 0) / max(st.get('visible_pieces', 0), 1):.0f} |",
              flush=True)
    med = float(np.median(t_h_all))
    print(f"\nset-up of the compiled engine (compiled_core, its BSP included): {t_core:.2f} s, "
          f"{t_core / med:.1f} median hemicube rows (the Python engine's BSP: {t_bsp:.2f} s, "
          f"{t_bsp / med:.1f}); median core / hemicube over the rows {np.median(ratios):.2f}")


if __name__ == "__main__":
    main()
