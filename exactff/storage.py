"""Where a form-factor matrix goes while it is computed: memory, or a file on disk that
an interrupted run resumes from.

Three formats, chosen by the output's suffix (a path without one of these suffixes gets
``.npy``, or ``.npz`` for a sparse matrix, appended, as :func:`numpy.save` does):

``.npy``
    A dense memory map (NumPy's own format): simple, any tool reads it, but it holds
    every coefficient (8 bytes each, zeros too).
``.zarr``
    A chunked, compressed array store (Zarr): blocks of whole rows, written as they
    finish, compressed (zeros and repeated values cost almost nothing), read lazily by
    ``zarr`` and by ``dask.array.from_zarr``. It is the ecosystem's format for arrays
    larger than memory; the optional extra ``exactff[scale]`` brings it.
``.npz``
    A sparse matrix (SciPy's CSR, ``scipy.sparse.save_npz``): only the non-zero values
    and their column indices. While a run is under way its finished blocks are kept as
    separate files in ``STEM.parts/`` (each written whole, then renamed into place);
    the ``.npz`` is assembled when the last block is in.

Beside every output, ``STEM.meta.json`` records what is computed (a hash of the scene and
the rows, the method and its options, ``two_sided``, the shape); a run with another
computation refuses the file instead of mixing results. The dense formats keep a mask of
the finished rows in ``STEM.done.npy`` (replaced atomically after each block; removed
when every row is done).
"""

import json
import logging
import os
import shutil

import numpy as np

__all__ = ["beside_path", "load_matrix", "MatrixOutput", "output_path", "path_stem", "path_suffix",
           "SUFFIXES",
           "ZARR_CHUNK_VALUES"]

SUFFIXES = (".npy", ".zarr", ".npz")
# blocks of a chunked store: about this many coefficients (16 MiB of doubles) per chunk
ZARR_CHUNK_VALUES = 2 ** 21


def path_stem(path):
    for s in SUFFIXES:
        if path.endswith(s):
            return path[: -len(s)]
    return path


def beside_path(out, what, suffix=None):
    """Where a second output goes: ``STEM.WHAT.SUFFIX`` beside ``out`` (the error
    estimates: ``STEM.error.SUFFIX``; the remainder: ``STEM.remainder.npy``).

    >>> beside_path("m.npz", "error"), beside_path("m.zarr", "remainder", ".npy")
    ('m.error.npz', 'm.remainder.npy')
    """
    out = os.fspath(out)
    return path_stem(out) + "." + what + (path_suffix(out) if suffix is None else suffix)


def path_suffix(path, name="out"):
    for s in SUFFIXES:
        if path.endswith(s):
            return s
    raise ValueError(f"{name}: {path!r} has no known suffix: .npy (dense), .zarr (chunked, "
                     f"compressed) or .npz (sparse)")


def output_path(path, sparse=False, name="out"):
    """The file an output ``path`` names: ``path`` itself when it ends in ``.npy``,
    ``.zarr`` or ``.npz``; otherwise ``path`` with ``.npz`` (``sparse``) or ``.npy``
    appended, as :func:`numpy.save` does (``"m"`` -> ``"m.npy"``, ``"m.v2"`` ->
    ``"m.v2.npy"``).

    >>> output_path("m"), output_path("m", sparse=True), output_path("m.zarr")
    ('m.npy', 'm.npz', 'm.zarr')
    """
    try:
        path = os.fspath(path)
    except TypeError:
        raise TypeError(f"{name}: expected a path (str or os.PathLike), got {path!r}") from None
    if not isinstance(path, str):
        raise TypeError(f"{name}: expected a path as str, got {path!r}")
    if any(path.endswith(s) for s in SUFFIXES):
        return path
    return path + (".npz" if sparse else ".npy")


def _save_atomic(path, array):
    """``np.save`` to a temporary file renamed into place: a kill leaves the old file or
    the new one, never half of one."""
    tmp = path + ".tmp.npy"
    np.save(tmp, array)
    os.replace(tmp, path)


def _read_meta(path):
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def _sparse_row(values):
    """A dense row's non-zero column indices and values (exact zeros left out)."""
    nz = np.flatnonzero(values)
    return nz.astype(np.int64), np.asarray(values, dtype=float)[nz]


def _csr(n_rows, n_cols, rows):
    """A CSR array from ``{position: (indices, values)}`` (every position present)."""
    import scipy.sparse as sp

    counts = np.array([len(rows[k][0]) for k in range(n_rows)], dtype=np.int64)
    indptr = np.concatenate([[0], np.cumsum(counts)])
    if n_rows:
        indices = np.concatenate([rows[k][0] for k in range(n_rows)])
        data = np.concatenate([rows[k][1] for k in range(n_rows)])
    else:
        indices, data = np.zeros(0, np.int64), np.zeros(0)
    return sp.csr_array((data, indices, indptr), shape=(n_rows, n_cols))


class MatrixOutput:
    """The matrix being computed: ``done`` (a mask over its rows), ``write(pos, rows)``
    for finished rows, and ``result()`` once every row is in.

    Parameters
    ----------
    shape : (int, int)
    sparse : bool
        Keep only non-zero values (the result is a ``scipy.sparse.csr_array``).
    out : str or None
        A file to stream to and resume from (suffix ``.npy``, ``.zarr`` or ``.npz``).
    meta : dict
        What is computed; compared with the file's record on resume.
    block : int
        Rows per block (a chunked store's chunks are aligned to blocks).
    """

    def __init__(self, shape, sparse=False, out=None, meta=None, block=16):
        self.shape = tuple(int(s) for s in shape)
        self.sparse = bool(sparse)
        self.out = None if out is None else os.fspath(out)
        self.block = int(block)
        self.kind = "memory" if self.out is None else path_suffix(self.out)
        if self.kind == ".npz" and not self.sparse:
            raise ValueError(f"out: {self.out!r} is a sparse format (.npz): pass sparse=True, "
                             f"or write a dense .npy or a chunked .zarr")
        if self.kind in (".npy", ".zarr") and self.sparse:
            raise ValueError(f"out: sparse=True writes a .npz file, got {self.out!r}")
        self.rows = {}                       # sparse rows in memory: position -> (idx, val)
        self.M = None
        if self.out is None:
            if not self.sparse:
                self.M = np.empty(self.shape)
            self.done = np.zeros(self.shape[0], bool)
            return
        stem = path_stem(self.out)
        self.meta_path, self.done_path = stem + ".meta.json", stem + ".done.npy"
        self.parts = stem + ".parts"
        self.meta = dict(meta or {}, shape=list(self.shape), format=self.kind)
        if self.kind == ".zarr":
            self.meta["block"] = self.block
        if os.path.exists(self.out) or os.path.exists(self.parts):
            if _read_meta(self.meta_path) != self.meta:
                raise ValueError(
                    f"out: {self.out!r} was not written by this computation (scene, rows, "
                    f"method, options or format differ, or "
                    f"{os.path.basename(self.meta_path)!r} is missing); remove it or choose "
                    f"another path")
            self._reopen()
        else:
            other = _read_meta(self.meta_path) or {}
            twin = stem + str(other.get("format", ""))
            if other.get("format") not in (None, self.kind) and os.path.exists(twin):
                raise ValueError(
                    f"out: {self.out!r} would share {os.path.basename(self.meta_path)!r} "
                    f"(its record of what was computed) with {twin!r}, an output of the "
                    f"same name in another format; choose another name")
            self._create()

    # -- creating and reopening files --------------------------------------------------
    def _create(self):
        with open(self.meta_path, "w", encoding="utf-8") as fh:
            json.dump(self.meta, fh)
        self.done = np.zeros(self.shape[0], bool)
        if self.kind == ".npy":
            self.M = np.lib.format.open_memmap(self.out, mode="w+", dtype=float,
                                               shape=self.shape)
        elif self.kind == ".zarr":
            zarr = _zarr()
            self.M = zarr.open_array(store=self.out, mode="w", shape=self.shape,
                                     chunks=(self.block, self.shape[1]), dtype="f8",
                                     fill_value=0.0)
        else:
            os.makedirs(self.parts, exist_ok=True)
        if self.kind != ".npz":
            _save_atomic(self.done_path, self.done)

    def _reopen(self):
        if self.kind == ".npz":
            if os.path.exists(self.out) and not os.path.exists(self.parts):
                with np.load(self.out) as z:
                    self._check_shape(tuple(z["shape"]) if "shape" in z else None)
                self.done = np.ones(self.shape[0], bool)
                return
            self.done = np.zeros(self.shape[0], bool)
            for name in os.listdir(self.parts):
                if name.endswith(".npz") and not name.endswith(".tmp.npz"):
                    with np.load(os.path.join(self.parts, name)) as z:
                        self.done[z["pos"]] = True
            return
        finished = not os.path.exists(self.done_path)
        self.done = np.ones(self.shape[0], bool) if finished else np.load(self.done_path)
        if self.kind == ".npy":
            self.M = np.lib.format.open_memmap(self.out, mode="r+")
        else:
            self.M = _zarr().open_array(store=self.out, mode="r+")
        self._check_shape(tuple(self.M.shape))

    def _check_shape(self, shape):
        """A file whose record matches but whose array does not (written over by another
        writer, its record left behind) is not taken for this computation's."""
        if shape != self.shape:
            raise ValueError(f"out: {self.out!r} holds an array of shape {shape}, not the "
                             f"{self.shape} its record says (written over since); remove it "
                             f"or choose another path")

    # -- rows --------------------------------------------------------------------------
    def write(self, pos, values):
        """Store finished rows: ``values[k]`` is the row at position ``pos[k]``."""
        pos = np.asarray(pos, dtype=int)
        if self.sparse:
            rows = [_sparse_row(v) for v in values]
            if self.out is None:
                self.rows.update(zip(pos.tolist(), rows))
            else:
                self._write_part(pos, rows)
        elif self.kind == ".zarr" and len(pos) and pos[-1] - pos[0] + 1 == len(pos):
            # one contiguous run of rows (a whole chunk when the block is complete)
            self.M[int(pos[0]):int(pos[-1]) + 1] = np.asarray(values, dtype=float)
        else:
            for k, v in zip(pos, values):
                self.M[k] = v
        self.done[pos] = True
        if self.out is not None and self.kind != ".npz":
            if self.kind == ".npy":
                self.M.flush()
            _save_atomic(self.done_path, self.done)

    def _write_part(self, pos, rows):
        counts = np.array([len(r[0]) for r in rows], dtype=np.int64)
        name = os.path.join(self.parts, f"rows_{int(pos[0]):012d}")
        np.savez(name + ".tmp.npz", pos=pos, counts=counts,
                 indices=np.concatenate([r[0] for r in rows]) if rows else np.zeros(0, int),
                 data=np.concatenate([r[1] for r in rows]) if rows else np.zeros(0))
        os.replace(name + ".tmp.npz", name + ".npz")

    def result(self):
        """The finished matrix: an ndarray (a memory map for ``.npy``), a ``zarr`` array
        for ``.zarr``, a ``scipy.sparse.csr_array`` when sparse."""
        if not self.done.all():
            raise RuntimeError(f"{int((~self.done).sum())} rows are not computed")
        if self.out is not None and self.kind != ".npz" and os.path.exists(self.done_path):
            os.remove(self.done_path)
        if not self.sparse:
            return self.M
        if self.out is None:
            return _csr(self.shape[0], self.shape[1], self.rows)
        if not os.path.exists(self.parts):       # finished by an earlier run
            return load_matrix(self.out)
        rows = {}
        for name in sorted(os.listdir(self.parts)):
            if name.endswith(".npz") and not name.endswith(".tmp.npz"):
                with np.load(os.path.join(self.parts, name)) as z:
                    # each array read once (an NpzFile reads it again on every access)
                    pos, counts, idx, val = z["pos"], z["counts"], z["indices"], z["data"]
                ends = np.cumsum(counts)
                for p, a, b in zip(pos, ends - counts, ends):
                    rows[int(p)] = (idx[a:b], val[a:b])
        M = _csr(self.shape[0], self.shape[1], rows)
        import scipy.sparse as sp

        tmp = self.out + ".tmp.npz"
        sp.save_npz(tmp, M, compressed=True)
        os.replace(tmp, self.out)
        shutil.rmtree(self.parts)
        return M


def _zarr():
    try:
        import zarr
    except ImportError:
        raise ImportError("a .zarr output needs zarr: pip install 'exactff[scale]'") from None
    return zarr


def _with_suffix(path):
    """``path`` itself where it ends in a known suffix; else the one output named
    ``path`` + suffix that exists (finished, or interrupted: its error says so)."""
    if any(path.endswith(s) for s in SUFFIXES):
        return path
    found = [path + s for s in SUFFIXES
             if os.path.exists(path + s) or
             (s == ".npz" and os.path.exists(path + ".parts"))]
    if not found:
        raise FileNotFoundError(f"path: no matrix at {path!r}, nor at "
                                f"{', '.join(repr(path + s) for s in SUFFIXES)}")
    if len(found) > 1:
        raise ValueError(f"path: {path!r} has no suffix and names {len(found)} outputs "
                         f"({', '.join(map(repr, found))}); give the one to read")
    logging.getLogger("exactff").info("load_matrix: %r has no suffix: reading %r", path,
                                      found[0])
    return found[0]


def load_matrix(path):
    """Read back a matrix written by :func:`exactff.form_factor_matrix` (``out=PATH``).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.npy`` (dense), ``.zarr`` (chunked store) or ``.npz`` (sparse) output. A
        path without one of those suffixes names the output that ``out=PATH`` wrote for
        it, as :func:`numpy.load` users expect: ``PATH.npy``, ``PATH.npz`` or
        ``PATH.zarr``, whichever exists (the one read is logged at INFO level on the
        ``exactff`` logger; two of them raise ``ValueError``).

    Returns
    -------
    numpy.memmap, zarr.Array or scipy.sparse.csr_array of shape (rows, polygons)
        ``.npy``: a read-only memory map; ``.zarr``: the store opened read-only (lazy:
        slice it, or ``dask.array.from_zarr(path)``); ``.npz``: a CSR array.

    Raises
    ------
    ValueError
        The file is not a finished output (a run was interrupted: call
        ``form_factor_matrix`` again with the same arguments to finish it), or a path
        without a suffix matches more than one output.
    FileNotFoundError
        Nothing at ``path`` (nor, without a suffix, at any of its three names).

    Examples
    --------
    >>> import tempfile, os, exactff as ef
    >>> d = tempfile.mkdtemp()
    >>> M = ef.form_factor_matrix(ef.scenes.subdivided_box(1), sparse=True,
    ...                           out=os.path.join(d, "box.npz"))
    >>> S = load_matrix(os.path.join(d, "box.npz"))
    >>> S.shape, S.nnz, bool((S != M).nnz == 0)
    ((6, 6), 30, True)
    >>> load_matrix(os.path.join(d, "box")).nnz      # box.npz, as out="box" wrote it
    30
    """
    path = _with_suffix(os.fspath(path))
    kind = path_suffix(path, "path")
    stem = path_stem(path)
    if not os.path.exists(path):
        if kind == ".npz" and os.path.exists(stem + ".parts"):
            raise ValueError(f"path: {path!r} is not finished (its blocks are in "
                             f"{stem + '.parts'!r}); run form_factor_matrix again with the "
                             f"same arguments to finish it")
        raise FileNotFoundError(f"path: no matrix at {path!r}")
    if kind != ".npz" and os.path.exists(stem + ".done.npy"):
        done = np.load(stem + ".done.npy")
        raise ValueError(f"path: {path!r} is not finished ({int(done.sum())} of {len(done)} "
                         f"rows written); run form_factor_matrix again with the same "
                         f"arguments to finish it")
    if kind == ".npy":
        return np.load(path, mmap_mode="r")
    if kind == ".zarr":
        return _zarr().open_array(store=path, mode="r")
    import scipy.sparse as sp

    return sp.csr_array(sp.load_npz(path))
