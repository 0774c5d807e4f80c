"""Area rows of View3D's files turned, scaled and moved off the axes, against the files
as read (issue 49 item 1: every value within its estimate).

Usage: python benchmarks/bench_area_turned.py [--seeds 1 2 3] [--rounds 15]
           [--tolerance 1e-6] [--timeout 120] [--files test4 facet cube gunter1]

Per seed and round, each file is turned by a random rotation (the Q of a QR of a
normal 3 x 3 matrix, det +1), scaled by 1e-3, 1 or 1e3 and not moved, moved up to 100
times the scale, or up to 1e3 (gunter1 at scale 1e-3: up to 1e3 times the scale; 1e3
there, 1e4 times its size, takes minutes a row). Its whole matrix at ``--tolerance``
is compared with the file's as read: a value is beyond where ``|F - G|`` exceeds the two
estimates and what rounding the moved coordinates moves the values, ``32 u R / L`` (R
the largest coordinate, L the scene's size). A matrix that takes over ``--timeout``
seconds is counted apart. Prints each case beyond and the counts; figures in
docs/explanation/area-form-factors.md ("Files turned off the axes").
"""

import argparse
import os
import signal
import time

import numpy as np

import exactff as ef

DATA = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "view3d")


def _timed_out(*_):
    raise TimeoutError


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--tolerance", type=float, default=1e-6)
    ap.add_argument("--timeout", type=int, default=120)
    ap.add_argument("--files", nargs="+", default=["test4", "facet", "cube", "gunter1"])
    args = ap.parse_args()
    signal.signal(signal.SIGALRM, _timed_out)
    read = {}
    counts = dict(within=0, beyond=0, slow=0)
    t0 = time.time()
    for seed in args.seeds:
        rng = np.random.default_rng(seed)
        for k in range(args.rounds):
            for name in args.files:
                if name not in read:
                    scene = ef.read_vs3(os.path.join(DATA, name + ".vs3"))
                    read[name] = (scene, *ef.area_form_factors(
                        scene, tolerance=args.tolerance, error=True))
                scene, F, E = read[name]
                Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
                Q[:, 0] *= np.sign(np.linalg.det(Q))
                scale = [1e-3, 1.0, 1e3][rng.integers(3)]
                kind = rng.integers(3)
                far = scale if name == "gunter1" and scale < 1 else 1.0
                move = [np.zeros(3), scale * rng.uniform(-100, 100, 3),
                        far * rng.uniform(-1e3, 1e3, 3)][kind]
                moved = ef.Scene.from_polygons([scale * (np.asarray(P) @ Q.T) + move
                                                for P in scene.polygons])
                try:
                    signal.alarm(args.timeout)
                    G, EG = ef.area_form_factors(moved, tolerance=args.tolerance, error=True)
                except TimeoutError:
                    counts["slow"] += 1
                    print(f"over {args.timeout} s: {name} seed {seed} round {k} scale {scale}"
                          f" move {np.round(move, 1).tolist()}", flush=True)
                    continue
                finally:
                    signal.alarm(0)
                rounding = 32 * np.finfo(float).eps * np.abs(moved.vertices).max() / np.ptp(
                    moved.vertices, axis=0).max()
                gap = np.abs(F - G) - (E + EG)
                if gap.max() <= rounding:
                    counts["within"] += 1
                    continue
                counts["beyond"] += 1
                i, j = np.unravel_index(np.argmax(gap), gap.shape)
                print(f"beyond: {name} seed {seed} round {k} scale {scale} pair ({i}, {j}): "
                      f"|F - G| {abs(F - G)[i, j]:.3g} against {E[i, j]:.3g} + {EG[i, j]:.3g}"
                      f" ({abs(F - G)[i, j] / (E + EG + rounding)[i, j]:.2f} times)", flush=True)
    print(f"tolerance {args.tolerance:g}, seeds {args.seeds}, {args.rounds} rounds: "
          f"{counts['within']} within, {counts['beyond']} beyond, {counts['slow']} over "
          f"{args.timeout} s ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
