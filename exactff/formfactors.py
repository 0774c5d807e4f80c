"""Form factors of a scene: rows from points (broadcasting) and whole matrices."""

import hashlib
import json
import os
import sys
import time

import numpy as np

from .integrate import as_receivers, as_scene
from .methods import resolve

__all__ = ["form_factors", "form_factor_matrix"]


def form_factors(scene, point, normal, *, method="exact", two_sided=False, error=False,
                 **options):
    """Form factors from points to every polygon of a scene, with occlusion.

    Parameters
    ----------
    scene : Scene
    point : array_like of shape (..., 3)
        Receiving points.
    normal : array_like of shape (..., 3)
        Receiver normals, broadcast against ``point``; normalised if not unit.
    method : str or FormFactorMethod, default "exact"
        ``"exact"`` (continuous PPBH with exact occlusion) or a configured instance.
    two_sided : bool, default False
        Let polygons receive on their back side too. Every polygon occludes
        whichever way it faces.
    error : bool, default False
        Also return ``E``, a bound on ``|F - exact|`` per value (the exact method only):
        the rounding of each value's integration plus the error of its visible pieces'
        vertices (refined from the input where the tolerance asks for it). It rests on
        the clipper's topology being right; what it covers is in
        ``docs/explanation/robustness.md``.
    **options
        Passed to the method's constructor when ``method`` is a name.

    Returns
    -------
    ndarray of shape (..., len(scene)), or a pair of them with ``error=True``
        ``F[..., j]`` = F(point -> polygon j).

    Raises
    ------
    ValueError
        Bad point, normal, or method (the message names the argument).

    Notes
    -----
    Conventions: ``docs/explanation/conventions.md``. A polygon receives only when its
    front faces the point (unless ``two_sided``); the part below the point's tangent
    plane is clipped away.

    Examples
    --------
    From the centre of the floor of a closed unit box, the ceiling (4 quads) takes
    4 F(corner of a 0.5 x 0.5 rectangle at height 1) = 0.2394564705:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> F = ef.form_factors(box, [0.5, 0.5, 0.0], [0, 0, 1])
    >>> round(float(F[4:8].sum()), 10), round(float(F.sum()), 12)
    (0.2394564705, 1.0)
    """
    m = resolve(method, **options)
    if error and m.name != "exact":
        raise ValueError(f"error=True needs method='exact' (an error bound per value); "
                         f"got method={m.name!r}")
    as_scene(scene)
    P, Nn, shape = as_receivers(point, normal)   # the methods normalise the normals
    out = np.empty((len(P), len(scene)))
    if error:
        err = np.empty_like(out)
        for i in range(len(P)):
            out[i], err[i] = m.point_form_factors(scene, P[i], Nn[i], two_sided=two_sided,
                                                  error=True)
        return out.reshape(shape + (len(scene),)), err.reshape(shape + (len(scene),))
    for i in range(len(P)):
        out[i] = m.point_form_factors(scene, P[i], Nn[i], two_sided=two_sided)
    return out.reshape(shape + (len(scene),))


def _row_indices(rows):
    """``rows`` as an integer array; floats, booleans and other non-integers raise."""
    r = np.asarray(rows).reshape(-1)
    if r.size and not (np.issubdtype(r.dtype, np.integer) and r.dtype != bool):
        raise ValueError(f"rows must be polygon indices (integers), got {rows!r}")
    return r.astype(int)


def _rows(scene, method, rows, two_sided):
    """Rows of the matrix from the centroids of the given polygons (a worker's task)."""
    return [method.point_form_factors(scene, scene.centroids[i], scene.normals[i],
                                      two_sided=two_sided) for i in rows]


class _Progress:
    """A progress bar: tqdm when installed, else a line on stderr at most once a second."""

    def __init__(self, total, enabled, desc):
        self.total, self.done, self.bar = total, 0, None
        self.enabled = enabled
        self.t0 = self.last = time.perf_counter()
        self.desc = desc
        if enabled:
            try:
                from tqdm.auto import tqdm

                self.bar = tqdm(total=total, desc=desc, unit="row")
            except ImportError:
                pass

    def update(self, k):
        self.done += k
        if self.bar is not None:
            self.bar.update(k)
        elif self.enabled:
            now = time.perf_counter()
            if now - self.last >= 1.0 or self.done == self.total:
                self.last = now
                rate = self.done / max(now - self.t0, 1e-9)
                eta = (self.total - self.done) / max(rate, 1e-9)
                print(f"\r{self.desc}: {self.done}/{self.total} rows, {rate:.1f} rows/s, "
                      f"{eta:.0f} s left", end="" if self.done < self.total else "\n",
                      file=sys.stderr, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _fingerprint(scene, rows):
    """A hash of the scene's vertices and polygon sizes and of the rows."""
    h = hashlib.sha256()
    for a in (scene.vertices, scene.offsets, np.asarray(rows)):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()


def method_record(method):
    """A complete, explicit record of a method and its options, for resumable output:
    the class and every public attribute (``repr`` may leave options out).

    Examples
    --------
    >>> from exactff.methods import SinglePlane
    >>> method_record(SinglePlane(16, refine=2))["options"]["refine"]
    '2'
    """
    options = {k: repr(v) for k, v in sorted(vars(method).items()) if not k.startswith("_")}
    return {"class": f"{type(method).__module__}.{type(method).__qualname__}",
            "options": options}


def _read_meta(path):
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def form_factor_matrix(scene, *, method="exact", rows=None, two_sided=False, executor=None,
                       progress=False, out=None, chunk_rows=None, **options):
    """The form-factor matrix of a scene, row ``i`` from the centroid of polygon ``i``.

    As in the paper (and the hemicube), the coefficient ``F[i, j]`` is the form factor
    from the centre of patch ``i`` (its centroid, with its normal) to patch ``j``: a
    point sample of the patch-to-patch form factor, not its area average.

    Parameters
    ----------
    scene : Scene
    method : str or FormFactorMethod, default "exact"
    rows : sequence of int, optional
        Compute only these rows (default: all, in order).
    two_sided : bool, default False
    executor : concurrent.futures.Executor, optional
        Rows are computed in chunks submitted to it (threads or processes; the scene
        and method are pickled for processes).
    progress : bool, default False
        Show a progress bar (tqdm when installed).
    out : str or os.PathLike, optional
        Stream rows to this ``.npy`` file (a memory map). A ``.done.npy`` file beside it
        records the finished rows (removed once every row is done) and a ``.meta.json``
        file what is computed (a hash of the scene and rows, the method, the options).
        Calling again with the same ``out`` and the same computation resumes an
        interrupted run and recomputes nothing that was written; with a different
        computation it raises ``ValueError`` instead of mixing results.
    chunk_rows : int, optional
        Rows per task (default: about 4 tasks per worker, at most 64 rows).
    **options
        Passed to the method's constructor when ``method`` is a name.

    Returns
    -------
    ndarray of shape (len(rows), len(scene))
        A memory map when ``out`` is given.

    Examples
    --------
    >>> import exactff as ef
    >>> M = ef.form_factor_matrix(ef.scenes.subdivided_box(2))
    >>> M.shape, bool(np.allclose(M.sum(axis=1), 1.0, rtol=0, atol=1e-12))
    ((24, 24), True)
    """
    m = resolve(method, **options)
    n = len(as_scene(scene))
    rows = np.arange(n) if rows is None else _row_indices(rows)
    if rows.size and (rows.min() < 0 or rows.max() >= n):
        raise ValueError(f"rows must lie in [0, {n}), got values from {rows.min()} to {rows.max()}")
    shape = (len(rows), n)
    if out is not None:
        out = os.fspath(out)
        stem = out[:-4] if out.endswith(".npy") else out
        done_path, meta_path = stem + ".done.npy", stem + ".meta.json"
        # what the file holds: a resumed run must be the same computation
        meta = {"scene": _fingerprint(scene, rows), "method": method_record(m), "two_sided": two_sided,
                "shape": list(shape)}
        if os.path.exists(out):
            old = _read_meta(meta_path)
            if old != meta:
                raise ValueError(
                    f"out: {out!r} was not written by this computation (scene, rows, method "
                    f"or options differ, or {os.path.basename(meta_path)!r} is missing); "
                    f"remove it or choose another path")
            M = np.lib.format.open_memmap(out, mode="r+")
            done = np.load(done_path) if os.path.exists(done_path) else np.ones(len(rows), bool)
        else:
            M = np.lib.format.open_memmap(out, mode="w+", dtype=float, shape=shape)
            done = np.zeros(len(rows), bool)
            with open(meta_path, "w", encoding="utf-8") as fh:
                json.dump(meta, fh)
        np.save(done_path, done)
    else:
        M = np.empty(shape)
        done = np.zeros(len(rows), bool)
    todo = np.flatnonzero(~done)
    bar = _Progress(len(rows), progress, "form factors")
    bar.update(len(rows) - len(todo))

    def store(pos, values):
        for k, v in zip(pos, values):
            M[k] = v
        done[pos] = True
        if out is not None:
            M.flush()
            np.save(done_path, done)
        bar.update(len(pos))

    try:
        if executor is None:
            step = chunk_rows or 16
            for s in range(0, len(todo), step):
                pos = todo[s:s + step]
                store(pos, _rows(scene, m, rows[pos], two_sided))
        else:
            workers = getattr(executor, "_max_workers", None) or os.cpu_count() or 1
            step = chunk_rows or max(1, min(64, -(-len(todo) // (4 * workers))))
            futures = {}
            for s in range(0, len(todo), step):
                pos = todo[s:s + step]
                futures[executor.submit(_rows, scene, m, rows[pos], two_sided)] = pos
            from concurrent.futures import as_completed

            for fut in as_completed(futures):
                store(futures[fut], fut.result())
    finally:
        bar.close()
    if out is not None and done.all():
        os.remove(done_path)
    return M
