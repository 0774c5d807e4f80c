"""Where an area pair's rules are fooled: the triangles whose high rule is off by more
than its rules' difference, and the kinks of the hidden part inside them.

How the box's values beyond their estimates were traced to a curved event and a culled
event (issue 49; docs/benchmarks.md, "The cause, and the fix"):

    python tools/area_kinks.py box 59 20 1e-6        # the 106-surface box of bench_area.py
    python tools/area_kinks.py tests/data/view3d/gunter1.vs3 16 0 1e-9

For the pair (emitter i, receiver j) of row i at the tolerance: every triangle the rules
accepted, its high rule's integral of the hidden part against a 12 x 12 collapsed Gauss
rule on each of its 16 sixteenths (the reference), printed where the error exceeds the
rules' difference (worst first); then, for the worst, the hidden part on a 301 x 301 grid
over the triangle's box and the largest jumps of its third differences along each axis
inside it (relative to their median): a line of them is a kink the cells were not cut
along. Compare its place with ``exactff.area.events.event_lines`` (with and without
shortcuts) and :func:`exactff.area.curved.curved_event_lines`.
"""

import os
import sys

import numpy as np
import shapely

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

import exactff as ef  # noqa: E402
import exactff.area.row as row  # noqa: E402
from exactff.area import adaptive, area_row  # noqa: E402
from exactff.area.hidden import hidden_values  # noqa: E402
from exactff.area.rules import GAUSS_RULE, quarter, triangle_rule  # noqa: E402
from exactff.geometry import area_vector, receiver_frame  # noqa: E402


def accepted_triangles(scene, i, j, tolerance):
    """Row i at the tolerance; for the pair (i, j): the rules' accepted triangles (the
    adaptive levels' record), the hidden parts' set-up, the receiver part and blockers."""
    grab, levels, occluded = {}, adaptive._levels, row.occluded_pair

    def keep(*a):
        grab["acc"], grab["setup"] = a[-1], a[8]
        return levels(*a)

    def pair(S, Pc, Qc, nP, *a, **k):
        if np.allclose(S[0], scene.polygons[j]):
            grab.update(S=S, Qc=Qc, nP=nP, Pc=Pc)
            adaptive._levels = keep
        try:
            return occluded(S, Pc, Qc, nP, *a, **k)
        finally:
            adaptive._levels = levels

    row.occluded_pair = pair
    try:
        f, e = area_row(scene, i, tolerance)
    finally:
        row.occluded_pair = occluded
    if "acc" not in grab:
        raise SystemExit(f"({i}, {j}) is not an occluded pair of row {i}")
    acc = {k: np.concatenate(v) for k, v in grab["acc"].items() if v}
    return f[j], e[j], acc, grab


def main(argv):
    name, i, j, tolerance = argv[0], int(argv[1]), int(argv[2]), float(argv[3])
    if name == "box":
        scene = ef.scenes.unit_squares_room()
    else:
        scene = ef.read_vs3(name)
    value, err, acc, g = accepted_triangles(scene, i, j, tolerance)
    area_P = float(np.linalg.norm(area_vector(scene.polygons[i])))
    T = acc["T"]
    sub = quarter(quarter(T).reshape(-1, 3, 3)).reshape(-1, 3, 3)
    X, W = triangle_rule(sub, GAUSS_RULE)
    H, _ = hidden_values(X.reshape(-1, 3), g["nP"], g["Qc"], g["S"][1:], setup=g["setup"])
    ref = (W.reshape(-1) * H).reshape(len(T), -1).sum(axis=1) / area_P
    off = np.abs(acc["hi"] - ref)
    ratio = off / np.maximum(acc["diff"] + acc["rnd"], 1e-300)
    print(f"({i}, {j}) at {tolerance:g}: {value!r} +- {err:.3g}; {len(T)} triangles")
    worst = np.argsort(ratio)[::-1]
    for t in worst[:8]:
        if ratio[t] <= 1:
            break
        print(f"  triangle {t}: off {off[t]:.3g}, rules' difference {acc['diff'][t]:.3g} "
              f"({ratio[t]:.1f} times), rung {int(acc['rung'][t])}, level "
              f"{int(acc['depth'][t])}: {np.round(T[t], 6).tolist()}")
    if ratio[worst[0]] <= 1:
        print("  every triangle within its rules' difference")
        return
    # the hidden part on a grid over the worst triangle, in the emitter's frame
    t = worst[0]
    R, c = receiver_frame(g["nP"]), g["Pc"].mean(axis=0)
    T2 = (T[t] - c) @ R[:2].T
    inner = shapely.Polygon(T2).buffer(-0.002 * float(np.ptp(T2, axis=0).max()))
    n = 301
    u = np.linspace(T2[:, 0].min(), T2[:, 0].max(), n)
    v = np.linspace(T2[:, 1].min(), T2[:, 1].max(), n)
    U, V = np.meshgrid(u, v, indexing="ij")
    Xg = c + np.stack([U.ravel(), V.ravel()], axis=1) @ R[:2]
    Hg, _ = hidden_values(Xg, g["nP"], g["Qc"], g["S"][1:], setup=g["setup"])
    Hg = Hg.reshape(n, n)
    inside = shapely.contains_xy(inner, U, V)
    for ax in (0, 1):
        d = np.abs(np.diff(Hg, 3, axis=ax))
        ok = (inside[:-3] & inside[3:]) if ax == 0 else (inside[:, :-3] & inside[:, 3:])
        if not ok.any():
            continue
        med = float(np.median(d[ok])) or 1e-300
        d = np.where(ok, d, 0.0)
        print(f"  third differences along axis {ax} of the frame, largest / median:")
        for k in np.argsort(d.ravel())[::-1][:8]:
            a, b = np.unravel_index(k, d.shape)
            uu, vv = ((u[a] + u[a + 3]) / 2, v[b]) if ax == 0 else (u[a], (v[b] + v[b + 3]) / 2)
            x = c + np.array([uu, vv]) @ R[:2]
            print(f"    {d[a, b] / med:10.3g} at {np.round(x, 6).tolist()}")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        raise SystemExit(__doc__)
    main(sys.argv[1:])
