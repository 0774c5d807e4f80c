"""Reports: the error of the discrete methods against the exact method, and run time."""

from __future__ import annotations

import os
import time

import numpy as np

from . import _tolerances as tol
from .formfactors import fingerprint, form_factor_matrix
from .geometry import polygon_diameter
from .methods import resolve
from .rings import successors
from .scene import Scene
from .visibility import plane_overlaps

__all__ = ["compare", "to_markdown", "describe"]


def _takes_samples(name):
    """Whether the method class of this name has a sample count (``samples=``)."""
    import inspect

    from .methods import METHODS

    return name in METHODS and "samples" in inspect.signature(METHODS[name]).parameters


def _reference_rows(scene, rows, reference, two_sided, progress):
    """The exact rows (and the time per row, None when read back): computed, given, or
    cached in an ``.npz`` file (computed once and written there, read back when the
    scene, the rows and ``two_sided`` match; a mismatch is an error, never a silent
    reuse)."""
    if reference is not None and not isinstance(reference, (str, os.PathLike)):
        return np.asarray(reference, dtype=float), None
    path = None if reference is None else os.fspath(reference)
    key = fingerprint(scene, rows)          # the scene's geometry and the rows
    if path is not None and os.path.exists(path):
        with np.load(path) as z:
            if not np.array_equal(z["rows"], rows):
                raise ValueError(f"reference {path!r} holds other rows: remove it or give "
                                 f"another path")
            if not (str(z["scene"]) == key and bool(z["two_sided"]) == bool(two_sided)):
                raise ValueError(f"reference {path!r} holds rows of another scene or another "
                                 f"two_sided: remove it or give another path")
            return np.array(z["F"]), float(z["time_per_row"])
    t0 = time.perf_counter()
    ref = form_factor_matrix(scene, rows=rows, two_sided=two_sided, progress=progress)
    t_ref = (time.perf_counter() - t0) / max(len(rows), 1)
    if path is not None:
        np.savez(path, F=ref, rows=rows, scene=key, two_sided=bool(two_sided),
                 time_per_row=t_ref)
    return ref, t_ref


def compare(scene: Scene, methods, samples=(4096, 65536), rows=None, *, reference=None,
            two_sided: bool = False, progress: bool = False) -> list[dict]:
    """Error against run time of form-factor methods on a scene.

    Parameters
    ----------
    scene : Scene
    methods : sequence of str or FormFactorMethod
        Method names (a method with a sample count runs at every one of ``samples``;
        one without, such as ``"exact"``, runs once) or configured instances (run once,
        as configured).
    samples : sequence of int, default (4096, 65536)
        Sample counts for the methods given by name (``samples=`` option).
    rows : sequence of int, optional
        The rows (receiving polygons) to compare; default all.
    reference : ndarray of shape (len(rows), len(scene)), or str or os.PathLike, optional
        Reference rows; default: the exact method, computed here. A path caches them:
        computed and written there (``.npz``) the first time, read back when the scene,
        the rows and ``two_sided`` match.
    two_sided : bool, default False
    progress : bool, default False

    Returns
    -------
    list of dict
        One per run: ``method``, ``samples`` (cells or rays actually used; 0 for a
        method without samples), ``rows``, ``mean_abs_error`` (over all coefficients of
        the rows), ``max_abs_error``, ``rms_error``, ``row_sum_error`` (mean absolute
        difference of the row sums), ``time_per_row`` (seconds),
        ``reference_time_per_row`` (None when the reference was given or read back).

    Examples
    --------
    >>> import exactff as ef
    >>> rec = compare(ef.scenes.cornell_box(closed=True), ["hemicube", "exact"], samples=[4096])
    >>> [(r["method"], r["samples"]) for r in rec], rec[0]["max_abs_error"] < 0.05
    ([('hemicube', 4332), ('exact', 0)], True)
    >>> rec[1]["max_abs_error"]      # the exact method against itself
    0.0
    """
    rows = np.arange(len(scene)) if rows is None else np.asarray(rows, dtype=int).reshape(-1)
    samples = list(samples)
    for s in samples:
        if not (isinstance(s, (int, np.integer)) and s > 0):
            raise ValueError(f"samples must be positive integers, got {s!r}")
    runs = []
    for method in methods:
        if isinstance(method, str):
            if _takes_samples(method):
                runs += [(method, resolve(method, samples=int(s))) for s in samples]
            else:
                runs.append((method, resolve(method)))
        else:
            runs.append((getattr(method, "name", type(method).__name__), resolve(method)))
    ref, t_ref = _reference_rows(scene, rows, reference, two_sided, progress)
    if ref.shape != (len(rows), len(scene)):
        raise ValueError(f"reference must have shape {(len(rows), len(scene))}, "
                         f"got {ref.shape}")
    records = []
    for name, m in runs:
        if hasattr(m, "layout"):
            m.layout()  # build the cells before timing
        t0 = time.perf_counter()
        M = form_factor_matrix(scene, rows=rows, method=m, two_sided=two_sided,
                               progress=progress)
        dt = (time.perf_counter() - t0) / max(len(rows), 1)
        err = M - ref
        records.append({
            "method": name,
            "samples": int(getattr(m, "samples", 0)),
            "rows": int(len(rows)),
            "mean_abs_error": float(np.abs(err).mean()),
            "max_abs_error": float(np.abs(err).max()),
            "rms_error": float(np.sqrt((err * err).mean())),
            "row_sum_error": float(np.abs(M.sum(axis=1) - ref.sum(axis=1)).mean()),
            "time_per_row": dt,
            "reference_time_per_row": t_ref,
        })
    return records


def to_markdown(records: list[dict]) -> str:
    """A Markdown table of :func:`compare`'s records.

    Examples
    --------
    >>> print(to_markdown([{"method": "ppbh", "samples": 10, "rows": 1,
    ...                     "mean_abs_error": 1e-3, "max_abs_error": 2e-3, "rms_error": 1e-3,
    ...                     "row_sum_error": 0.0, "time_per_row": 0.01,
    ...                     "reference_time_per_row": 0.1}]))
    | method | samples | mean abs error | max abs error | rms error | row-sum error | s / row |
    |---|---|---|---|---|---|---|
    | ppbh | 10 | 1.00e-03 | 2.00e-03 | 1.00e-03 | 0.00e+00 | 0.0100 |
    """
    lines = ["| method | samples | mean abs error | max abs error | rms error | row-sum error "
             "| s / row |", "|---|---|---|---|---|---|---|"]
    for r in records:
        lines.append(f"| {r['method']} | {r['samples']} | {r['mean_abs_error']:.2e} | "
                     f"{r['max_abs_error']:.2e} | {r['rms_error']:.2e} | "
                     f"{r['row_sum_error']:.2e} | {r['time_per_row']:.4f} |")
    return "\n".join(lines)


#: vertex pairs whose distances one block of the vectorised diameters holds
_PAIRS_PER_BLOCK = 2 ** 20


def _distinct_rings(scene):
    """The scene's rings with consecutive repeats removed (as
    :func:`exactff.scene.distinct_consecutive`): vertices and offsets."""
    V, off = scene.vertices, scene.offsets
    keep = np.any(V != V[successors(off)], axis=1)
    counts = np.add.reduceat(keep.astype(np.int64), off[:-1])
    return V[keep], np.concatenate([[0], np.cumsum(counts)])


def _planarity_deviations(scene):
    """Per polygon: the largest distance of a vertex from the plane through the vertex
    mean with the Newell normal, over the polygon's diameter (consecutive repeats
    removed), by vertex count."""
    V, off = _distinct_rings(scene)
    counts = np.diff(off)
    devs = np.zeros(len(counts))
    for k in np.unique(counts):
        idx = np.flatnonzero(counts == k)
        P = V[off[idx][:, None] + np.arange(k)]                    # (m, k, 3)
        Q = P - P[:, :1]
        N = 0.5 * np.cross(Q, np.roll(Q, -1, axis=1)).sum(axis=1)
        N /= np.linalg.norm(N, axis=1)[:, None]
        dev = np.abs(np.einsum("mkj,mj->mk", P - P.mean(axis=1, keepdims=True), N)).max(axis=1)
        if k <= tol.BATCH_VALIDATION_MAX_VERTICES:
            step = max(1, _PAIRS_PER_BLOCK // (k * k))       # bounds the temporaries
            diam = np.concatenate([
                np.sqrt(((B[:, :, None, :] - B[:, None, :, :]) ** 2).sum(axis=-1)).max(axis=(1, 2))
                for B in (P[a:a + step] for a in range(0, len(P), step))])
        else:
            diam = np.array([polygon_diameter(R) for R in P])
        devs[idx] = dev / diam
    return devs


def _unpaired_edges(scene):
    """Directed edges (consecutive repeats removed) whose reverse is not an edge as
    many times: their number."""
    V, off = _distinct_rings(scene)
    E = np.hstack([V, V[successors(off)]]) + 0.0     # -0.0 and 0.0 are one coordinate
    rows = lambda A: np.ascontiguousarray(A).view(np.dtype((np.void, A.dtype.itemsize * 6)))
    keys, count = np.unique(rows(E).ravel(), return_counts=True)
    flipped = rows(np.ascontiguousarray(keys.view(np.float64).reshape(-1, 6)[:, [3, 4, 5, 0, 1, 2]])).ravel()
    at = np.minimum(np.searchsorted(keys, flipped), len(keys) - 1)
    reverse = np.where(keys[at] == flipped, count[at], 0)
    return int(count[reverse != count].sum())


def describe(scene: Scene) -> dict:
    """Summary of a scene: size, area, bounds, planarity and closure.

    Returns
    -------
    dict
        ``polygons``, ``vertices``, ``total_area``, ``bounds_min``, ``bounds_max``,
        ``max_planarity_deviation`` (largest vertex distance from its Newell plane over
        the polygon's diameter), ``closure_residual`` (``|sum A_i n_i| / sum A_i``,
        0 for a closed surface), ``unpaired_edges`` (directed edges whose reverse is
        not an edge of another polygon; 0 for a watertight mesh without T-junctions),
        ``back_to_back_pairs`` (coplanar overlapping pairs facing opposite ways: the two
        faces of a zero-thickness wall, legitimate) and ``same_facing_overlaps``
        (coplanar overlapping pairs facing the same way: usually a modelling mistake),
        both as lists of ``[i, j]`` (the pairs of
        :func:`exactff.visibility.coplanar_overlaps`, found without the BSP tree:
        :func:`exactff.visibility.plane_overlaps`), ``near_coplanar_overlaps``
        (overlapping pairs that are coplanar within ``NEAR_COPLANAR_RTOL`` of the
        magnitudes but not within the BSP tree's band: faces flush to 1e-13, which the
        exact method orders by their geometry and the discrete methods may call a
        tie; ``docs/explanation/conventions.md``), ``split_faces`` (faces of
        the file that were not planar and were cut into triangles when it was read
        with ``nonplanar="split"``; 0 otherwise), ``dropped_faces`` (degenerate faces
        of the file left out when it was read with ``degenerate="drop"``; 0 otherwise),
        ``dropped_reasons`` (how many for each reason, a dict) and
        ``skipped_primitives`` (the file's objects that are not polygons and were not
        read, counted by kind, a dict: ``{"sphere": 1}`` for a Radiance scene with one
        sphere; empty otherwise).

    Examples
    --------
    >>> from exactff.scenes import subdivided_box
    >>> d = describe(subdivided_box(2))
    >>> d["polygons"], d["unpaired_edges"], d["closure_residual"] < 1e-15
    (24, 0, True)
    >>> d["back_to_back_pairs"], d["same_facing_overlaps"], d["dropped_faces"]
    ([], [], 0)
    """
    back_to_back, same_facing, near = plane_overlaps(scene, near_rtol=tol.NEAR_COPLANAR_RTOL)
    devs = _planarity_deviations(scene)
    unpaired = _unpaired_edges(scene)
    vector_area = (scene.normals * scene.areas[:, None]).sum(axis=0)
    lo, hi = scene.bounds
    return {
        "polygons": len(scene),
        "vertices": int(len(scene.vertices)),
        "total_area": float(scene.areas.sum()),
        "bounds_min": lo.tolist(),
        "bounds_max": hi.tolist(),
        "max_planarity_deviation": float(devs.max()),
        "closure_residual": float(np.linalg.norm(vector_area) / scene.areas.sum()),
        "unpaired_edges": int(unpaired),
        "back_to_back_pairs": back_to_back.tolist(),
        "same_facing_overlaps": same_facing.tolist(),
        "near_coplanar_overlaps": near.tolist(),
        "split_faces": scene.split_faces,
        "dropped_faces": scene.dropped_faces,
        "dropped_reasons": dict(scene.dropped_reasons),
        "skipped_primitives": dict(scene.skipped_primitives),
    }
