"""Record, or compare bit for bit, what the compiled modules return on a fixed set of rows.

Used when the C++ is moved between files or rebuilt with other flags: the values and bounds
of the compiled core (``exactff.visibility._svbsp``), of the area rows' hidden parts
(``exactff.area._hidden``) and of the unoccluded sector sums (``exactff.kernel._sector``)
must not move.

    python tools/core_bits.py save before.npz       # on the old build
    python tools/core_bits.py save after.npz        # on the new build
    python tools/core_bits.py compare before.npz after.npz
    python tools/core_bits.py time 3                 # each group's best of 3 runs

``save`` also prints the wall time of each group (one run; compare runs made under the same
conditions). ``--from DIR`` first (``python tools/core_bits.py --from DIR save ...``)
imports exactff from the checkout DIR (built in place) instead of the installed one, to
record or time another build in the same environment.
"""

import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))


def _record_sector_sums(out):
    """Wrap the kernel's compiled row sums so that every call's outputs are kept."""
    from exactff.kernel import ladder, point

    def wrap(module, name):
        inner = getattr(module, name)

        def recorded(*args):
            result = inner(*args)
            k = sum(1 for key in out if key.startswith(f"sector/{name}/"))
            for i, a in enumerate(result):
                out[f"sector/{name}/{k}/{i}"] = np.array(a)
            return result
        setattr(module, name, recorded)

    wrap(point, "row_sums")
    wrap(ladder, "row_sums_extended")


def compute():
    """The arrays to compare, by name, and the wall time of each group."""
    import exactff as ef
    from common import load_real_file

    out, times = {}, {}
    _record_sector_sums(out)

    def point_rows(tag, scene, rows):
        t0 = time.perf_counter()
        for r in rows:
            F, E = ef.form_factors(scene, scene.centroids[r], scene.normals[r], error=True)
            out[f"{tag}/{r}/F"], out[f"{tag}/{r}/E"] = F, E
        times[tag] = time.perf_counter() - t0

    office = ef.scenes.office(2000)
    point_rows("office2000", office, range(0, len(office), len(office) // 20)[:20])
    cloister = ef.scenes.cloister(5000)
    point_rows("cloister5000", cloister, range(0, len(cloister), len(cloister) // 10)[:10])
    duplex = load_real_file("ifc-Duplex_A.obj", tempfile.mkdtemp(prefix="exactff-bits-"))
    point_rows("duplex", duplex, [1009, 15025, 0, 5000, 20000])

    t0 = time.perf_counter()
    cornell = ef.scenes.cornell_box()
    M = ef.form_factor_matrix(cornell)
    out["cornell/matrix"] = np.asarray(M.todense() if hasattr(M, "todense") else M)
    times["cornell"] = time.perf_counter() - t0

    # the unoccluded rows' compiled sector sums, double and long double tiers, on every
    # pair of 20 rows of the office (exactff/_core/sector_sums.h)
    from exactff import _tolerances as tol
    from exactff.geometry import receiver_frame
    from exactff.kernel import ladder, point
    from exactff.kernel.flat import flat_polygons

    t0 = time.perf_counter()
    flat = flat_polygons(office)
    picked = np.arange(0, len(office), len(office) // 20)[:20]
    P, N = office.centroids[picked], office.normals[picked]
    rows = np.repeat(np.arange(len(picked)), len(office)).astype(np.int64)
    ids = np.tile(np.arange(len(office)), len(picked)).astype(np.int64)
    frames = np.array([receiver_frame(n) for n in N])
    for i, a in enumerate(point.row_sums(flat.V, flat.offsets, ids, rows, P, frames, tol.EPS,
                                         tol.OFFSET_ROUNDING_ULPS, tol.C2 * tol.EPS)):
        out[f"kernel/row_sums/{i}"] = np.array(a)
    ldframes = np.array([receiver_frame(n, dtype=np.longdouble) for n in N])
    for i, a in enumerate(ladder.row_sums_extended(
            flat.V, flat.offsets, ids, rows, P, ldframes, tol.LONGDOUBLE_EPS,
            tol.OFFSET_ROUNDING_ULPS, tol.C2 * tol.LONGDOUBLE_EPS)):
        out[f"kernel/row_sums_extended/{i}"] = np.array(a)
    times["kernel sums"] = time.perf_counter() - t0

    view3d = os.path.join(HERE, "..", "tests", "data", "view3d")
    for name, rows in (("cube.vs3", None), ("gunter1.vs3", [0, 1, 2])):
        scene = ef.load_scene(os.path.join(view3d, name))
        t0 = time.perf_counter()
        F, E = ef.area_form_factors(scene, rows=rows, tolerance=1e-6, error=True)
        out[f"area/{name}/F"] = np.asarray(F.todense() if hasattr(F, "todense") else F)
        out[f"area/{name}/E"] = np.asarray(E.todense() if hasattr(E, "todense") else E)
        times[f"area {name}"] = time.perf_counter() - t0
    return out, times


def same_bits(x, y):
    """Whether two arrays hold the same values bit for bit (long double: its 10 bytes of
    x87 extended precision, not the padding of its 16)."""
    if x.dtype != y.dtype or x.shape != y.shape:
        return False
    if x.dtype == np.longdouble and np.finfo(np.longdouble).nmant == 63:
        size = x.dtype.itemsize
        return np.array_equal(x.reshape(-1).view(np.uint8).reshape(-1, size)[:, :10],
                              y.reshape(-1).view(np.uint8).reshape(-1, size)[:, :10])
    return x.tobytes() == y.tobytes()


def main(argv):
    if len(argv) > 2 and argv[1] == "--from":
        # another checkout's package before the installed (editable) one
        sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
        sys.path.insert(0, os.path.abspath(argv[2]))
        argv = argv[:1] + argv[3:]
    if len(argv) == 3 and argv[1] == "save":
        out, times = compute()
        np.savez(argv[2], **out)
        print(f"{len(out)} arrays saved to {argv[2]}")
        for tag, t in times.items():
            print(f"  {tag:20s} {t:8.2f} s")
        return 0
    if len(argv) == 3 and argv[1] == "time":
        import exactff

        best = {}
        for _ in range(int(argv[2])):
            for tag, t in compute()[1].items():
                best[tag] = min(best.get(tag, t), t)
        print(f"exactff from {os.path.dirname(exactff.__file__)}: best of {argv[2]} runs")
        for tag, t in best.items():
            print(f"  {tag:20s} {t:8.3f} s")
        return 0
    if len(argv) == 4 and argv[1] == "compare":
        a, b = np.load(argv[2]), np.load(argv[3])
        if set(a.files) != set(b.files):
            print("different arrays:", sorted(set(a.files) ^ set(b.files)))
            return 1
        bad = [k for k in a.files if not same_bits(a[k], b[k])]
        print(f"{len(a.files) - len(bad)} of {len(a.files)} arrays equal bit for bit")
        for k in bad:
            print("  differs:", k)
        return 1 if bad else 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
