"""Form factors of a scene: rows from points (broadcasting), and the one matrix driver
for point rows and area rows (jobs, executors, streamed and resumable outputs, sparse)."""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import threading
import time

import numpy as np
from numpy.typing import ArrayLike

from . import _tolerances as tol
from .area import AreaStats, area_row
from .errors import check_finite, misses_tolerance, tolerance_missed
from .checks import as_normal, as_receivers, check_tolerance, row_indices
from .methods import FormFactorMethod, resolve
from .remainder import hemisphere_sky_share, remainder_row
from .scene import Scene, as_scene
from .storage import ZARR_CHUNK_VALUES, MatrixOutput, beside_path, output_path

__all__ = ["form_factors", "form_factor_matrix", "area_form_factors", "run_rows",
           "PointRows", "AreaRows", "Progress", "fingerprint", "method_record"]


def form_factors(scene: Scene, point: ArrayLike, normal: ArrayLike, *,
                 method: str | FormFactorMethod = "exact", two_sided: bool = False,
                 error: bool = False, remainder: bool = False, up: ArrayLike | None = None,
                 **options) -> np.ndarray | tuple[np.ndarray, ...]:
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
    remainder : bool, default False
        Also return the uncovered part of each row, split at the horizontal plane
        through the point: ``sky`` (directions above it) and ``ground`` (below), so
        that ``F.sum(-1) + sky + ground`` is 1 in every scene, open or closed. Every
        method and engine: the scene is cut along that plane (once per height, cached),
        the row computed on the cut scene, its parts summed back per polygon; ``sky`` is
        the closed-form share ``(1 + n . up) / 2`` minus the parts above
        (:func:`exactff.remainder.remainder_row`). A polygon lying in that plane counts
        on neither side.
    up : array_like of shape (3,), optional
        The up direction for ``remainder`` (default +z; the built-in office and
        cloister are y-up: ``up=(0, 1, 0)``).
    **options
        Passed to the method's constructor when ``method`` is a name.

    Returns
    -------
    ndarray of shape (..., len(scene)), or a tuple
        ``F[..., j]`` = F(point -> polygon j); ``(F, E)`` with ``error=True``;
        ``(F, sky, ground)`` with ``remainder=True`` (``sky``, ``ground`` of shape
        ``(...)``, floats for one point); ``(F, sky, ground, E, E_sky, E_ground)`` with
        both (values, then their bounds: the parts' bounds, the rounding of the sums
        and of the share, and what the split's rounding may move between sky and
        ground).

    Raises
    ------
    ValueError
        Bad point, normal, or method (the message names the argument).
    NumericalError
        The exact method: a value fell below 0 beyond its bound or came out NaN or
        infinite (never returned); unless ``error=True``, also a value whose bound
        missed the method's tolerance (**relative**, with an absolute floor of
        ``tolerance * 1e-2``: :func:`exactff.errors.misses_tolerance`; the area
        factors' ``tolerance`` is absolute instead, ``docs/explanation/conventions.md``)
        after
        refinement and every precision tier (on
        every path, with either integrator). With ``error=True`` such a value is
        returned with its bound.

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

    Without the ceiling the sky is what the ceiling took; the walls' parts below the
    floor's plane (none) leave no ground:

    >>> open_box = ef.Scene.from_polygons(box.polygons[:4] + box.polygons[8:])
    >>> F, sky, ground = ef.form_factors(open_box, [0.5, 0.5, 0.0], [0, 0, 1], remainder=True)
    >>> round(sky, 10), ground, round(float(F.sum()) + sky + ground, 12)
    (0.2394564705, 0.0, 1.0)
    """
    m = resolve(method, **options)
    if error and m.name != "exact":
        raise ValueError(f"error=True needs method='exact' (an error bound per value); "
                         f"got method={m.name!r}")
    as_scene(scene)
    P, Nn, shape = as_receivers(point, normal)   # the methods normalise the normals
    if up is not None and not remainder:
        raise ValueError("up= is the up direction of remainder=True: give remainder=True "
                         "too, or leave up out")
    if remainder:
        return _with_remainder(scene, P, Nn, shape, m, two_sided, error, up)
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


def _remainder_row(scene, p, n, method, two_sided, error, up):
    """One receiver's row with its sky and ground (:func:`exactff.remainder.remainder_row`
    with the method's row on the split scene)."""
    share, share_bound = hemisphere_sky_share(n, up)
    if error:
        row = lambda s: method.point_form_factors(s, p, n, two_sided=two_sided, error=True)
    else:
        row = lambda s: method.point_form_factors(s, p, n, two_sided=two_sided)
    # a sampled method's row is only within sampling of the shares: clamp, never raise
    slack = None if method.name == "exact" else math.inf
    return remainder_row(scene, p, row, sky_share=share, share_bound=share_bound, up=up,
                         error=error, slack=slack)


def _with_remainder(scene, P, Nn, shape, method, two_sided, error, up):
    n = len(scene)
    F = np.empty((len(P), n))
    R = np.empty((len(P), 2))
    E = np.empty_like(F) if error else None
    ER = np.empty_like(R) if error else None
    for i in range(len(P)):
        got = _remainder_row(scene, P[i], Nn[i], method, two_sided, error, up)
        F[i], R[i] = got[0], got[1:3]
        if error:
            E[i], ER[i] = got[3], got[4:6]
    scalar = lambda a: float(a[0]) if shape == () else a.reshape(shape)
    values = (F.reshape(shape + (n,)), scalar(R[:, 0]), scalar(R[:, 1]))
    if not error:
        return values
    return values + (E.reshape(shape + (n,)), scalar(ER[:, 0]), scalar(ER[:, 1]))


class PointRows:
    """A matrix's rows as point samples: row ``i`` from the centroid of polygon ``i``
    (with its normal) by ``method``. What :func:`form_factor_matrix` computes; with
    ``remainder``, each row is the pair ``(values, [sky, ground])`` (``up`` the up
    direction, default +z). With ``error`` (the exact method only), each row is the
    pair ``(values, bounds)``, the bounds going to ``STEM.error.SUFFIX`` beside an
    output (what :func:`exactff.audit` computes). ``points``, an array of shape
    (len(scene), 3), moves row ``i``'s receiver from the centroid to ``points[i]``
    (still with polygon ``i``'s normal); a hash of it is in :meth:`record`.

    Examples
    --------
    >>> import exactff as ef
    >>> from exactff.methods import Exact
    >>> rows = PointRows(Exact(), two_sided=False)
    >>> [float(r.sum()) for r in rows(ef.scenes.subdivided_box(1), [0])]
    [1.0]
    """

    def __init__(self, method, two_sided, remainder=False, up=None, error=False, points=None):
        self.method, self.two_sided = method, bool(two_sided)
        self.remainder = bool(remainder)
        self.error = bool(error)
        if self.remainder and self.error:
            raise ValueError("PointRows: remainder and error are not computed together")
        if self.error and method.name != "exact":
            raise ValueError(f"error=True needs method='exact' (an error bound per value); "
                             f"got method={method.name!r}")
        self.points = None if points is None else np.array(points, dtype=float)
        self.up = None if up is None else tuple(float(v) for v in np.asarray(up).ravel())
        # with the remainder: a second output, (sky, ground) per row, in STEM.remainder.npy;
        # with the error: the bounds, as wide as the scene, in STEM.error.SUFFIX
        self.outputs = 2 if self.remainder or self.error else 1
        self.suffixes = ("remainder",) if self.remainder else ("error",) if self.error else ()
        self.widths = (2,) if self.remainder else (None,) if self.error else ()

    def record(self):
        rec = {"method": method_record(self.method), "two_sided": self.two_sided}
        if self.remainder:
            rec.update(remainder=True, up=repr(self.up))
        if self.error:
            rec.update(error=True)
        if self.points is not None:
            rec.update(points=hashlib.sha256(
                np.ascontiguousarray(self.points).tobytes()).hexdigest())
        return rec

    def __call__(self, scene, rows):
        if self.points is not None and self.points.shape != (len(scene), 3):
            raise ValueError(f"points must have shape ({len(scene)}, 3) (one receiver per "
                             f"polygon), got {self.points.shape}")
        P = scene.centroids if self.points is None else self.points
        if self.error:
            return [self.method.point_form_factors(scene, P[i], scene.normals[i],
                                                   two_sided=self.two_sided, error=True)
                    for i in rows]
        if self.remainder:
            out = []
            for i in rows:
                F, sky, ground = _remainder_row(scene, P[i], scene.normals[i],
                                                self.method, self.two_sided, False, self.up)
                out.append((F, np.array([sky, ground])))
            return out
        rows = list(rows)
        if hasattr(self.method, "point_rows"):
            # the rows together, where the method can share work among them
            return list(self.method.point_rows(scene, P[rows], scene.normals[rows],
                                               two_sided=self.two_sided))
        return [self.method.point_form_factors(scene, P[i], scene.normals[i],
                                               two_sided=self.two_sided) for i in rows]


class AreaRows:
    """A matrix's rows as area-to-area form factors with occlusion, each value within
    an absolute ``tolerance`` (or ``max(tolerance, rtol * |F|)`` with ``rtol``;
    :func:`exactff.area.area_row`) and ``shortcuts`` on or off; each row is the pair ``(values, error estimates)``. What
    :func:`area_form_factors` computes. The options travel with it to worker processes
    (it is pickled) and are in :meth:`record` (resumable outputs key on it). ``stats``,
    a dict, receives the sums of the rows' counters as the driver stores them
    (:meth:`collect`, in the calling process), whichever executor computed them.
    ``strict`` (what :func:`area_form_factors` sets unless ``error=True``): a row with a
    value whose estimate misses the tolerance raises :class:`exactff.NumericalError`
    instead of being stored (not part of :meth:`record`: it changes no stored value).

    Examples
    --------
    >>> import exactff as ef
    >>> (f, e, counts), = AreaRows(1e-9)(ef.scenes.subdivided_box(1), [0])
    >>> abs(float(f.sum()) - 1) < 1e-12, counts.enclosure_unoccluded_pairs
    (True, 5)
    """

    outputs = 2
    suffixes = ("error",)
    widths = (None,)

    def __init__(self, tolerance, shortcuts=True, stats=None, rtol=None, strict=False):
        self.tolerance, self.rtol, self.shortcuts = tolerance, rtol, bool(shortcuts)
        self.stats, self.strict = stats, bool(strict)

    def record(self):
        return {"area": True, "tolerance": repr(self.tolerance), "rtol": repr(self.rtol),
                "shortcuts": self.shortcuts}

    def __getstate__(self):
        # the caller's dict stays in the caller's process: workers return their counts
        return dict(vars(self), stats=None)

    def __call__(self, scene, rows):
        out = []
        for i in rows:
            st = AreaStats()
            f, e = area_row(scene, i, self.tolerance, rtol=self.rtol, shortcuts=self.shortcuts,
                            stats=st)
            # every row checked before it is stored: a NaN is never returned, nor (strict)
            # a value whose estimate misses the tolerance
            check_finite(f, e)
            if self.strict:
                bad = np.flatnonzero(misses_tolerance(f, e, self.rtol, atol=self.tolerance))
                if len(bad):
                    j = int(bad[0])
                    allowed = (f"{self.tolerance:g} absolute" if self.rtol is None else
                               f"max({self.tolerance:g}, {self.rtol:g} * F)")
                    raise tolerance_missed(f"row {i}, polygon {j}", f[j], e[j], allowed,
                                           "(area form factor, after adaptive refinement)")
            out.append((f, e, st))
        return out

    def collect(self, values):
        """Add the counters of stored rows (``(values, estimates, AreaStats)``) to
        ``stats``, a dict keyed by :class:`~exactff.area.AreaStats`' attributes."""
        if self.stats is None:
            return
        for *_, st in values:
            for k, v in st.as_dict().items():
                self.stats[k] = self.stats.get(k, 0) + v


class Progress:
    """A progress bar: tqdm when installed, else a line on stderr at most once a second.

    Examples
    --------
    >>> bar = Progress(3, enabled=False, desc="rows")
    >>> bar.update(2); bar.done
    2
    >>> bar.close()
    """

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


def fingerprint(scene, rows):
    """A hash of the scene's vertices and polygon sizes and of the rows.

    Examples
    --------
    >>> import exactff as ef
    >>> s = ef.scenes.subdivided_box(1)
    >>> fingerprint(s, [0]) == fingerprint(s, [0]) != fingerprint(s, [1])
    True
    """
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


# a worker's computations (scene with its prepared BSP tree, the row computation), by key:
# installed once per process (a process pool's initializer), or kept from the first
# task that brought them (any other executor), or resolved from a dask scatter
_WORKER = {}
_WORKER_KEEP = 4
_WORKER_LOCK = threading.Lock()       # threads of one process share _WORKER


def _computation_key(scene, computation):
    h = hashlib.sha256(fingerprint(scene, []).encode())
    h.update(json.dumps(computation.record(), sort_keys=True).encode())
    return h.hexdigest()


def _install(job):
    """Keep ``job = (key, scene, computation)`` in this process (the process pool's
    initializer; also the first task of another executor); returns it."""
    with _WORKER_LOCK:
        while len(_WORKER) >= _WORKER_KEEP:
            _WORKER.pop(next(iter(_WORKER)))
        _WORKER[job[0]] = job[1:]
        return job[1:]


def _task(job, rows):
    """Rows computed in a worker. ``job`` is the key of a computation this process
    holds, or the computation itself (kept for the tasks after it)."""
    if isinstance(job, str):
        with _WORKER_LOCK:
            scene, computation = _WORKER[job]
    else:
        with _WORKER_LOCK:
            held = _WORKER.get(job[0])
        scene, computation = held if held is not None else _install(job)
    return computation(scene, rows)


def _dask_client(executor):
    """The ``dask.distributed`` client behind ``executor`` (a Client or its executor), or
    None."""
    mod = type(executor).__module__ or ""
    if not mod.startswith("distributed"):
        return None
    return executor if hasattr(executor, "scatter") else getattr(executor, "_client", None)


def form_factor_matrix(scene: Scene, *, method: str | FormFactorMethod = "exact",
                       rows: ArrayLike | None = None, two_sided: bool = False, executor=None,
                       jobs: int | None = None, progress: bool = False,
                       out: str | os.PathLike | None = None, sparse: bool = False,
                       chunk_rows: int | None = None, remainder: bool = False,
                       up: ArrayLike | None = None, **options):
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
    executor : concurrent.futures.Executor or dask.distributed.Client, optional
        Rows are computed in blocks submitted to it. A dask ``Client`` (or its
        ``get_executor()``) receives the scene once per worker (scattered); any other
        executor sends it with every block (a process keeps the scene, and its BSP tree,
        from one block to the next).
    jobs : int, optional
        Run in this many worker processes of a pool that exactff starts and stops; the
        scene reaches each process once (the pool's initializer). Not with ``executor``.
    progress : bool, default False
        Show a progress bar (tqdm when installed): rows per second and time left.
    out : str or os.PathLike, optional
        Stream rows to this file as they finish and resume from it: ``.npy`` (a dense
        memory map), ``.zarr`` (a chunked, compressed store; ``exactff[scale]``) or
        ``.npz`` (sparse, with ``sparse=True``); formats in :mod:`exactff.storage`.
        A path without one of these suffixes gets ``.npy`` appended, or ``.npz`` with
        ``sparse=True``, as :func:`numpy.save` does: ``out="m"`` writes ``m.npy``.
        ``STEM.meta.json`` beside it records what is computed (a hash of the scene and
        rows, the method, the options). Calling again with the same ``out`` and the
        same computation resumes an interrupted (even killed) run and recomputes no
        finished row; a different computation raises ``ValueError`` instead of mixing
        results. :func:`exactff.load_matrix` reads any of them back.
    sparse : bool, default False
        Return a ``scipy.sparse.csr_array`` holding the non-zero values (exactly the
        dense matrix's, bit for bit).
    chunk_rows : int, optional
        Rows per block (default: 16 serially; with workers about four blocks per
        worker, at most 64 rows; a ``.zarr`` store's chunks: about 2**21 values, at most
        64 rows).
    remainder : bool, default False
        Also return each row's uncovered remainder, ``R`` of shape (len(rows), 2): the
        sky (column 0) and the ground (column 1), as :func:`form_factors` with
        ``remainder=True`` (the matrix's values are then the sums of the polygons'
        parts). With ``out``, ``R`` is written beside it to ``STEM.remainder.npy``.
    up : array_like of shape (3,), optional
        The up direction of ``remainder`` (default +z).
    **options
        Passed to the method's constructor when ``method`` is a name.

    Returns
    -------
    ndarray, zarr.Array or scipy.sparse.csr_array of shape (len(rows), len(scene))
        A memory map for ``.npy``, the store for ``.zarr``, CSR when ``sparse``;
        with ``remainder=True`` the pair ``(M, R)``.

    Raises
    ------
    ValueError
        Bad rows, jobs, chunk_rows, an ``out`` of another computation or format.

    Examples
    --------
    >>> import exactff as ef
    >>> M = ef.form_factor_matrix(ef.scenes.subdivided_box(2))
    >>> M.shape, bool(np.allclose(M.sum(axis=1), 1.0, rtol=0, atol=1e-12))
    ((24, 24), True)
    >>> S = ef.form_factor_matrix(ef.scenes.subdivided_box(2), sparse=True)
    >>> bool(np.array_equal(S.toarray(), M)), S.nnz < M.size
    (True, True)
    >>> M, R = ef.form_factor_matrix(ef.scenes.subdivided_box(2), remainder=True)
    >>> R.shape, float(np.abs(R).max())      # a closed box: no sky, no ground
    ((24, 2), 0.0)
    """
    m = resolve(method, **options)
    scene = as_scene(scene)
    rows = row_indices(rows, len(scene))
    if up is not None and not remainder:
        raise ValueError("up= is the up direction of remainder=True: give remainder=True "
                         "too, or leave up out")
    if up is not None:
        as_normal(up, "up")
    got = run_rows(scene, rows, PointRows(m, two_sided, remainder, up), executor=executor,
                   jobs=jobs, progress=progress, out=out, sparse=sparse,
                   chunk_rows=chunk_rows, desc="form factors")
    return (got[0], got[1]) if remainder else got[0]


def run_rows(scene, rows, computation, *, executor=None, jobs=None, progress=False, out=None,
             sparse=False, chunk_rows=None, desc="rows"):
    """The one matrix driver: rows ``rows`` of ``computation`` (:class:`PointRows`,
    :class:`AreaRows`) computed in blocks, serially, in ``jobs`` processes or on an
    executor (a dask client gets the scene once per worker), streamed to ``out`` and
    resumed from it, dense or sparse, with a progress bar.

    Returns a list with one matrix per output of the computation (values, and error
    estimates for :class:`AreaRows`, which go to ``STEM.error.SUFFIX`` beside ``out``;
    sky and ground for :class:`PointRows` with ``remainder``, to
    ``STEM.remainder.npy``).
    The arguments are described in :func:`form_factor_matrix`.

    Examples
    --------
    >>> import exactff as ef
    >>> from exactff.methods import Exact
    >>> s = ef.scenes.subdivided_box(1)
    >>> M, = run_rows(s, np.arange(6), PointRows(Exact(), False))
    >>> M.shape
    (6, 6)
    """
    n = len(scene)
    if jobs is not None:
        if isinstance(jobs, bool) or not isinstance(jobs, (int, np.integer)) or jobs < 1:
            raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
        if executor is not None:
            raise ValueError("give executor or jobs, not both")
    if chunk_rows is not None and (isinstance(chunk_rows, bool) or
                                   not isinstance(chunk_rows, (int, np.integer)) or chunk_rows < 1):
        raise ValueError(f"chunk_rows must be a positive integer, got {chunk_rows!r}")
    client = None if executor is None else _dask_client(executor)
    workers = (jobs if jobs and jobs > 1 else None) or (
        len(client.scheduler_info().get("workers", {})) if client is not None
        else getattr(executor, "_max_workers", None) or (os.cpu_count() if executor else 1)) or 1
    out = None if out is None else output_path(out, sparse)
    zarr_out = out is not None and out.endswith(".zarr")
    if chunk_rows:
        step = int(chunk_rows)
    elif zarr_out:   # fixed by the store (not by the workers): a resumed run has the same
        step = max(1, min(64, ZARR_CHUNK_VALUES // max(n, 1)))
    elif workers > 1:
        step = max(1, min(64, -(-len(rows) // (4 * workers))))
    else:
        step = 16
    meta = dict(computation.record(), scene=fingerprint(scene, rows))
    # second outputs beside the first: as wide as the scene (the error estimates, in the
    # same format) or narrower (the remainder's sky and ground: dense, STEM.WHAT.npy)
    results = [MatrixOutput((len(rows), n), sparse=sparse, out=out, meta=meta, block=step)]
    for what, width in zip(getattr(computation, "suffixes", ()),
                           getattr(computation, "widths", ())):
        narrow = width is not None
        path = None if out is None else beside_path(out, what, ".npy" if narrow else None)
        results.append(MatrixOutput((len(rows), width if narrow else n),
                                    sparse=sparse and not narrow, out=path, meta=meta,
                                    block=step))
    done = np.logical_and.reduce([r.done for r in results])
    # blocks of positions aligned to ``step`` (a chunked store's chunks), unfinished rows only
    blocks = [b[~done[b]] for b in np.array_split(
        np.arange(len(rows)), np.arange(step, len(rows), step))]
    blocks = [b for b in blocks if len(b)]
    bar = Progress(len(rows), progress, desc)
    bar.update(int(done.sum()))

    def store(pos, values):
        if computation.outputs == 1:
            values = [(v,) for v in values]
        for k, result in enumerate(results):
            result.write(pos, [v[k] for v in values])
        collect = getattr(computation, "collect", None)
        if collect is not None:          # what the rows report beyond their outputs
            collect(values)
        bar.update(len(pos))

    pool = None
    try:
        if executor is None and not (jobs and jobs > 1):
            for pos in blocks:
                store(pos, computation(scene, rows[pos]))
        else:
            from concurrent.futures import ProcessPoolExecutor, as_completed

            job = (_computation_key(scene, computation), scene, computation)
            if client is not None:
                # dask: the scene reaches each worker once; tasks refer to it
                ex = client.get_executor(pure=False)
                payload = client.scatter([job], broadcast=True, hash=False)[0]
            elif executor is None:
                pool = ex = ProcessPoolExecutor(jobs, initializer=_install, initargs=(job,))
                payload = job[0]
            else:
                ex, payload = executor, job
            futures = {ex.submit(_task, payload, rows[pos]): pos for pos in blocks}
            for fut in as_completed(futures):
                store(futures[fut], fut.result())
    finally:
        bar.close()
        if pool is not None:
            pool.shutdown(cancel_futures=True)
    return [result.result() for result in results]


def area_form_factors(scene, rows=None, *, tolerance=1e-9, error=False, executor=None,
                      jobs=None, progress=False, out=None, sparse=False, chunk_rows=None,
                      rtol=None, shortcuts=True, stats=None, combine=False):
    """Area-to-area form factors with occlusion (the paper's Eq. 1), each within a
    requested **absolute** tolerance (or, with ``rtol``, a share of the value).

    ``F[i, j] = (1 / A_i) int_{P_i} F_occ(x -> j) dA_x``, with ``F_occ`` the exact
    occluded point form factor from ``x`` (normal of ``P_i``) to polygon ``j`` (as
    :func:`exactff.form_factors`; here built in the receiver's plane from the blockers'
    projections), one-sided. Coplanar overlapping polygons facing the same way follow
    the tie rule (the first in input order is in front, docs/explanation/conventions.md):
    a polygon they cover receives and emits through its uncovered part only, its row
    still divided by its whole area ``A_i`` (reciprocal with ``scene.areas``; the row
    sums to its uncovered share in a closed room, 0 when covered whole). A pair with
    nothing that can come between (no other polygon reaches into the convex hull of the two, each clipped to
    the front of the other) is computed in closed form (the contour integral with
    dilogarithms, :func:`exactff.area.closed_form.unoccluded_pairs`, all of a row's such
    pairs at once), accepted where its rounding estimate is within ``tolerance`` (else
    by the far-field rule or mpmath). Otherwise the emitter is cut along the lines where the integrand may lose
    smoothness (vertex-edge visibility events between the receiver and the polygons
    that may hide it, and their planes), its cells triangulated, and each triangle
    integrated by two collapsed Gauss-Legendre rules (6 and 10 points a side) and cut in
    four while they differ by more than its share of ``tolerance`` (an emitter cut into
    many small triangles tries a lower pair first). Between two faces of one
    closed convex solid (a box) there is no vertex-edge event: their images united are
    the solid's.

    Parameters
    ----------
    scene : Scene
    rows : sequence of int, optional
        Emitters (default: every polygon).
    tolerance : float, default 1e-9
        **Absolute** error allowed per value: the target of the adaptive rules on
        occluded pairs, ``|F[i, j] - exact| <= tolerance`` whatever the value's size
        (unlike the point functions' and :class:`exactff.Exact`'s ``tolerance``, which is
        relative to each value, with a floor of 1e-2 of it:
        ``docs/explanation/conventions.md``). Passed down as ``atol``
        (:func:`exactff.area.area_row`). Unoccluded pairs are exact to rounding
        whatever it is.
    rtol : float, optional
        Also allowed: this share of each value; the bound per value is then
        ``max(tolerance, rtol * |F[i, j]|)`` (say ``tolerance=1e-15, rtol=1e-9`` for a
        relative target). Default: the absolute ``tolerance`` alone.
    error : bool, default False
        Also return the per-value error estimates. For an unoccluded pair the estimate
        bounds the closed form's rounding; for an occluded pair it is an **estimate**,
        not a proven bound: it counts the point values' bounds and any area lost, but
        the adaptive rules' share is the difference of two rules on each triangle,
        which two rules that miss the same feature of the integrand can make too small
        (see Notes). It is checked against what is known exactly (the unoccluded point
        values' integral, in closed form) and has held against independent values on
        every View3D example the tests have (``tests/test_area_view3d.py``). It is an
        estimate above all where the emitter is not cut along a line where the
        integrand kinks, which the rules then meet inside a triangle: the curved events
        of a pair with more than ``AREA_CURVED_MAX_TRIPLES`` triples of skew edges (none
        of its curves traced; ``stats["curved_skipped"]``), the curves where the images
        of three blockers' edges meet at one point (none of them the receiver's), and
        the events of the line where two interpenetrating blockers cross (an edge of
        what they hide that is no polygon's edge). On files turned, scaled and moved
        off the axes, whose faces share edges and planes only to rounding, it has
        held at 1e-6 on 180 random turns of test4, facet, the cube and gunter1, each
        against the file as read (before, a vertex on another polygon's edge line
        drew an event line of rounding's: docs/explanation/area-form-factors.md,
        "Files turned off the axes").
    executor, jobs, progress, out, sparse, chunk_rows
        As for :func:`form_factor_matrix`: rows in parallel, a progress bar, streamed to
        ``out`` and resumed from it (the estimates to ``STEM.error.SUFFIX`` beside it),
        sparse results.
    shortcuts : bool, default True
        False disables every shortcut, for testing that they never change a result
        beyond the estimates: the convex-enclosure test, the walls between a
        pair (``exactff.area.walls``), shaft culling and the hull
        test (every other polygon is then taken as a possible blocker of every pair,
        and the pair goes through the occluded path),
        the far-field rule (mpmath instead where the closed form misses) and the cull
        of blocker-blocker events whose lines of sight miss the receiver or join two
        faces of one convex solid. Much slower.
        Part of what a resumable ``out`` records.
    stats : dict, optional
        Filled with the sums over the rows computed in this call (with any executor) of
        :class:`exactff.area.AreaStats`' counters: ``enclosure_unoccluded_pairs`` (pairs of a
        convex enclosure, where nothing can come between: no shaft or hull test),
        ``hull_unoccluded_pairs`` (pairs taken by the closed form because shaft culling and the hull test left no
        blocker), ``hull_culled_blockers`` (the polygons they left out),
        ``shaft_culled_blockers`` (polygons in a pair's bounding box that the shaft's
        planes rejected, so the hull test never saw them), ``shaft_unoccluded_pairs``
        (pairs whose box held polygons but the shaft none: no hull built),
        ``far_pairs`` (by the far-field rule), ``contour_rule_pairs`` and
        ``escalated_pairs`` (unoccluded values whose closed form missed, taken by the
        tanh-sinh contour rule or with edge pairs in mpmath), ``culled_events``,
        ``solid_events``
        (vertex-edge pairs of two faces of one convex solid, not cut along),
        ``back_faces`` (members of such a solid that a point saw from behind, left out
        of its hidden region; per point),
        ``engine_fallbacks`` and ``engine_fallback_points`` (hidden parts the engine
        computed where GEOS failed or a point's images did not stay finite),
        ``bounded_points`` (such points of little weight given the bound
        ``0 <= hidden <= unoccluded`` instead of the engine's value),
        ``umbra_pairs`` and ``umbra_cells`` (pairs with umbras, regions of the emitter
        from which one blocker hides the whole receiver: their event lines cut away and
        their cells taken by the closed form, ``exactff.area.umbra``; and those cells'
        triangles), ``umbra_pieces`` (squares of emitters from which several blockers
        together hide the whole receiver, ``exactff.area.joint_umbra``),
        ``unevaluated_triangles`` (a pair's cells of least bound times area, left
        unevaluated at half their bounds on the unoccluded point values times their
        areas while they take at most a quarter of the pair's tolerance,
        ``exactff.area.points.unevaluated``),
        ``wall_hidden_pairs`` (pairs that walls between them hide whole, blockers in
        one plane or in a few one behind the other, proven in rationals: exactly 0,
        not integrated; ``exactff.area.walls``),
        ``curved_events`` (curved visibility events cut along: two blockers' edges seen
        crossing on the receiver's edge, ``exactff.area.curved``; not a shortcut) and
        ``curved_skipped`` (pairs with too many triples of edges to trace them, left
        uncut),
        ``cell_fallbacks`` (emitters cut along their visibility events another way,
        where GEOS failed or the cells did not cover the emitter: the lines not
        lengthened across its boundary, or noded on a grid of 1e-12 of its size),
        ``occluded_pairs``, ``point_values``, and the check of the rules'
        differences: ``checked_triangles`` (triangles checked one by one against their
        closed form, where a pair's sum missed) and ``refined_triangles`` (those it sent
        back to be refined). Every shortcut's counter is 0 with ``shortcuts=False``.
    combine : bool, default False
        The matrix View3D prints for a scene read from a ``.vs3`` file
        (:func:`exactff.read_vs3`; :mod:`exactff.combine`): one row and column per
        surface View3D reports (:func:`exactff.combined_surfaces`: combined surfaces
        merged by area weighting, subsurfaces separated from their bases, null
        surfaces taken from their bases, masks seen only by their bases, obstructions
        left out), from the exact factors of the polygons (those with subsurfaces, masks
        or null surfaces on them cut into convex pieces around them). ``rows`` are then
        those surfaces; without ``rows``, the file's ``row`` control value (when set)
        selects that surface's row, as View3D computes only it. With the file's
        ``encl=1`` a row that does not sum to 1 within its estimates warns (the values
        are not normalised: they need not be). The estimates add up the polygons'. A
        scene without View3D data gives the same matrix as ``combine=False``. Not with
        ``out`` or ``sparse``.

    Returns
    -------
    ndarray of shape (len(rows), len(scene)), or a pair of them with ``error=True``
        (CSR arrays with ``sparse=True``, memory maps or stores with ``out``); with
        ``combine``, of shape (len(rows), len(combined_surfaces(scene)))

    Raises
    ------
    NumericalError
        A value came out NaN or infinite, or an estimate NaN (never returned); unless
        ``error=True``, also a value whose estimate exceeds ``tolerance`` (or
        ``max(tolerance, rtol * |F|)``) after the adaptive rules' cutting (the message
        names the row and the polygon). With ``error=True`` such a value is returned
        with its estimate, which says so. Rows read back from a resumed ``out`` were
        checked when they were computed, under that run's ``error``.

    Notes
    -----
    What the estimate rests on: for unoccluded pairs, the rounding of the closed form's
    terms (tested against mpmath, Howell's catalogue, reciprocity and splitting); for
    occluded pairs, that on a triangle between visibility events the integrand is
    smooth, so that the difference between a triangle's two rules (6 and 10 points a
    side, or a lower pair first) estimates the finer rule's error, plus the point
    values' own bounds, the area of any cell the cutting lost (counted at the largest
    value the hidden part can take), and the cells left unevaluated (each at half its
    bound on the unoccluded point values, within as much: a bound, not an estimate).
    The rules' difference is an estimate, not a bound:
    on View3D's gunter2 two collapsed rules on half a floor differed by 7.2e-8 where
    the finer one was 2.1e-7 off (both missed the kernel's peak near a corner), and
    the value came out -2.1e-7 (pinned: ``tests/test_area_view3d.py``, gunter2's floor
    to a strip the wall hides). So it is checked: the rules' errors on the hidden part
    and on the occluded point values add up to their error on the unoccluded point
    values, whose integral is known in closed form, per pair and, where the pair's sum
    misses, per triangle; a triangle whose difference that shows too small is refined
    (``stats``: ``checked_triangles``, ``refined_triangles``). The check can only
    show an estimate too small, never prove one right. Two rules fooled alike are
    guarded by a third rule (at corners, ``AREA_CORNER_MIDDLE_ORDER``) and on the
    symmetric pair of degrees 4 and 8 (tolerances of 1e-7 and coarser) by two null
    rules of degree 5 on the same nodes (``AREA_NULL_RULE_FACTOR``): a needle cell of
    gunter2 had rules agreeing 24 times closer than their error. Curved events (two blockers'
    edges seen crossing on the receiver's edge) are cut along where the three edges
    are mutually skew, traced as chords within ``AREA_CURVED_EVENT_RTOL`` of the
    emitter's size (or ``sqrt(tolerance)`` of it, where less; ``exactff.area.curved``);
    the kinks left uncut (``error`` above names them) are left to the adaptive cutting,
    and a triangle still unresolved after ``MAX_DEPTH`` cuts keeps its (large)
    estimate, so that a value whose estimate exceeds ``tolerance`` says so: it raises,
    or with ``error=True`` comes back with that estimate, but two rules that miss the
    same kink alike can also agree there. Cost grows with the
    events of each occluded pair: meant for scenes of up to a few hundred polygons.

    Examples
    --------
    Unit squares one apart with a 0.5 x 0.5 plate halfway between (the test's
    reference: 0.0314026942480):

    >>> import exactff as ef
    >>> sq = lambda z, up: [[0, 0, z], [1, 0, z], [1, 1, z], [0, 1, z]][::1 if up else -1]
    >>> plate = [[.25, .25, 1], [.75, .25, 1], [.75, .75, 1], [.25, .75, 1]]
    >>> scene = ef.Scene.from_polygons([sq(0, True), sq(2, False), plate])
    >>> F, E = area_form_factors(scene, rows=[0], tolerance=1e-8, error=True)
    >>> round(float(F[0, 1]), 8), bool(E[0, 1] <= 1e-8)
    (0.03140269, True)
    """
    scene = as_scene(scene)
    check_tolerance(tolerance, allow_none=False)
    check_tolerance(rtol, "rtol")
    if stats is not None and not isinstance(stats, dict):
        raise ValueError(f"stats must be a dict or None, got {type(stats).__name__}")
    if combine:
        return _combined_area_form_factors(
            scene, rows, error=error, tolerance=tolerance, executor=executor, jobs=jobs,
            progress=progress, out=out, sparse=sparse, chunk_rows=chunk_rows, rtol=rtol,
            shortcuts=shortcuts, stats=stats)
    rows = row_indices(rows, len(scene))
    F, E = run_rows(scene, rows, AreaRows(tolerance, shortcuts, stats, rtol, strict=not error),
                    executor=executor, jobs=jobs,
                    progress=progress, out=out, sparse=sparse, chunk_rows=chunk_rows,
                    desc="area form factors")
    return (F, E) if error else F


def _combined_area_form_factors(scene, rows, *, error, tolerance, out, sparse, **options):
    """``area_form_factors(..., combine=True)``: the area rows of the polygons of
    :func:`exactff.combined_surfaces`, reduced to the surfaces."""
    import warnings

    from .combine import combined_surfaces

    if out is not None or sparse:
        raise ValueError("combine=True: not with out= or sparse= (the matrix of the "
                         "surfaces is computed in memory)")
    surfaces = combined_surfaces(scene)
    control = scene.metadata.get("view3d", {}).get("control", {})
    if rows is None and control.get("row"):
        numbers = {num: k for k, num in enumerate(surfaces.numbers)}
        v3 = scene.metadata["view3d"]
        s = v3["surfaces"][control["row"] - 1]
        num = s["cmb"] or s["number"]
        if num not in numbers:
            raise ValueError(f"control row={control['row']}: surface {control['row']} is a "
                             f"null surface (no row)")
        rows = [numbers[num]]
    rows = row_indices(rows, len(surfaces))
    raw = surfaces.rows_needed(rows)
    comp = surfaces.scene
    if len(raw):
        F, E = run_rows(comp, raw, AreaRows(tolerance, options.pop("shortcuts"),
                                            options.pop("stats"), options.pop("rtol")),
                        desc="area form factors", **options)
    else:
        F = E = np.zeros((0, len(comp)))
    F, E = surfaces.reduce(rows, raw, F, E)
    if control.get("encl") and len(rows) == len(surfaces):
        sums = F.sum(axis=1)
        slack = E.sum(axis=1) + 64 * tol.EPS * len(surfaces)
        bad = np.flatnonzero(np.abs(sums - 1.0) > slack)
        if len(bad):
            i = int(bad[np.argmax(np.abs(sums[bad] - 1.0))])
            warnings.warn(f"{scene.metadata['view3d'].get('source', 'the scene')}: encl=1 (the "
                          f"surfaces form an enclosure) but {len(bad)} rows do not sum to 1 "
                          f"within their estimates; surface {surfaces.numbers[i]} "
                          f"({surfaces.names[i]}): {sums[i]:.12g}", stacklevel=3)
    return (F, E) if error else F
