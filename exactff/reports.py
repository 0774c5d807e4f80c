"""Reports: the error of the discrete methods against the exact method, and run time."""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from . import _tolerances as tol
from .formfactors import fingerprint, form_factor_matrix
from .geometry import polygon_diameter
from .methods import resolve
from .rings import successors
from .scene import Scene
from .visibility import plane_overlaps

__all__ = ["compare", "to_markdown", "describe", "check_matrix", "MatrixReport"]


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


# ---------------------------------------------------------------------------------------
# the invariants of a matrix: check_matrix and its report
# ---------------------------------------------------------------------------------------
#: rows of a dense matrix (or memory map, or chunked store) read at a time
_BLOCK_VALUES = 2 ** 22
#: rows and pairs a report's text names before it says how many more
_NAMED = 10


@dataclass
class MatrixReport:
    """The invariants of a form-factor matrix: what :func:`check_matrix` returns.

    ``str(report)`` is a summary that names the rows and pairs that miss an invariant;
    :meth:`to_dict` gives the same as plain values (JSON).

    Attributes
    ----------
    shape : (int, int)
        The matrix's shape (R, N).
    sparse : bool
    rows : ndarray of shape (R,)
        The scene's polygon of each row (for reciprocity and the unobstructed rows).
    sums : ndarray of shape (R,)
        Row sums, with the remainder (sky and ground) when it was given.
    deficits : ndarray of shape (R,)
        ``1 - sums``.
    judged : str or None
        Why the rows should sum to 1 (``"remainder"``, ``"closed scene"``,
        ``"closed=True"``), or None when they need not (an open scene without its
        remainder): then no row misses.
    row_bounds : ndarray of shape (R,)
        What each row's sum may miss 1 by: the sum of its error estimates (and the
        remainder's) plus rounding, or ``MATRIX_ROW_SUM_ATOL`` without estimates.
    rows_missing : list of int
        Rows (named by their polygon, from ``rows``) that miss 1 beyond their bound, or
        hold a NaN, a value below 0 or above 1 beyond its estimate. Every ``(row,
        column)`` of the report names the row the same way.
    negatives, nans, above_one : int
        How many values are below 0, NaN, above 1 (beyond their estimates, when given).
    min_value, max_value : float
        Over the non-NaN values (0 for a sparse matrix's implicit zeros included).
    reciprocity : float or None
        ``max |A_i F_ij - A_j F_ji|`` (a scene given and the matrix square over it),
        with ``reciprocity_pair`` its ``(i, j)``.
    area : bool
        Whether the matrix is area-to-area (then reciprocity is judged: pairs beyond
        ``A_i E_ij + A_j E_ji`` plus rounding, or ``MATRIX_RECIPROCITY_RTOL`` of the
        larger product without estimates, are in ``pairs_missing``).
    pairs_missing : list of (int, int)
    max_error : float or None
        The largest error estimate, with ``max_error_at`` its ``(row, column)``.
    obstructed_excess : float or None
        ``max (F_ij - U_ij)`` over the unobstructed matrix ``U`` (0 or less when no
        obstructed value exceeds its unobstructed one), with ``excess_at``;
        ``excess_missing`` the ``(row, column)`` beyond the estimates (without them,
        ``MATRIX_ROW_SUM_ATOL``) plus rounding.
    """

    shape: tuple
    sparse: bool
    rows: np.ndarray
    sums: np.ndarray
    deficits: np.ndarray
    judged: str | None
    row_bounds: np.ndarray
    rows_missing: list
    negatives: int
    nans: int
    above_one: int
    min_value: float
    max_value: float
    reciprocity: float | None = None
    reciprocity_pair: tuple | None = None
    area: bool = False
    pairs_missing: list = field(default_factory=list)
    max_error: float | None = None
    max_error_at: tuple | None = None
    obstructed_excess: float | None = None
    excess_at: tuple | None = None
    excess_missing: list = field(default_factory=list)

    @property
    def ok(self):
        """True when no row, pair or value misses an invariant."""
        return not (self.rows_missing or self.pairs_missing or self.excess_missing)

    def to_dict(self):
        """The report as plain values (lists, floats, None), for JSON."""
        out = {}
        for k in self.__dataclass_fields__:
            v = getattr(self, k)
            if isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple):
                v = [int(x) for x in v]
            elif isinstance(v, list):
                v = [[int(x) for x in e] if isinstance(e, tuple) else int(e) for e in v]
            elif isinstance(v, (np.floating, np.integer, np.bool_)):
                v = v.item()
            out[k] = v
        out["ok"] = self.ok
        return out

    def __str__(self):
        R, N = self.shape
        named = lambda xs: ", ".join(map(str, xs[:_NAMED])) + (
            f" and {len(xs) - _NAMED} more" if len(xs) > _NAMED else "")
        lines = [f"matrix           {R} x {N} ({'sparse' if self.sparse else 'dense'})"]
        if R:
            w = int(np.nanargmax(np.abs(self.deficits))) if np.any(np.isfinite(self.deficits)) else 0
            lines.append(f"row sums         min {np.nanmin(self.sums):.15f}  max "
                         f"{np.nanmax(self.sums):.15f}" if np.any(np.isfinite(self.sums))
                         else "row sums         all NaN")
            why = (f"should be 1 ({self.judged})" if self.judged else
                   "need not be 1 (an open scene: give its remainder, or closed=True)")
            lines.append(f"                 largest deficit {self.deficits[w]:.3g} (row "
                         f"{self.rows[w]}); {why}")
        lines.append(f"values           {self.negatives} below 0, {self.nans} NaN, "
                     f"{self.above_one} above 1 (min {self.min_value:.3g}, max "
                     f"{self.max_value:.3g})")
        if self.reciprocity is not None:
            i, j = self.reciprocity_pair
            judged = "" if self.area else "; not judged (point rows; area=True if areas)"
            lines.append(f"reciprocity      max |A_i F_ij - A_j F_ji| = {self.reciprocity:.3g} "
                         f"(pair {i}, {j}){judged}")
        if self.max_error is not None:
            lines.append(f"error estimates  largest {self.max_error:.3g} (row "
                         f"{self.max_error_at[0]}, column {self.max_error_at[1]})")
        if self.obstructed_excess is not None:
            lines.append(f"obstructed       max excess over unobstructed "
                         f"{max(self.obstructed_excess, 0.0):.3g}"
                         + (f" (row {self.excess_at[0]}, column {self.excess_at[1]})"
                            if self.obstructed_excess > 0 else ""))
        if self.ok:
            lines.append("invariants       every row, pair and value within its bound")
        else:
            if self.rows_missing:
                lines.append(f"MISSED           {len(self.rows_missing)} rows: "
                             f"{named(self.rows_missing)}")
            if self.pairs_missing:
                lines.append(f"MISSED           {len(self.pairs_missing)} pairs "
                             f"(reciprocity): {named(self.pairs_missing)}")
            if self.excess_missing:
                lines.append(f"MISSED           {len(self.excess_missing)} values above "
                             f"their unobstructed value: {named(self.excess_missing)}")
        return "\n".join(lines)


def _dense(M, a, b):
    import scipy.sparse as sp

    return M[a:b].toarray() if sp.issparse(M) else np.asarray(M[a:b], dtype=float)


def _is_closed(scene):
    """Closed as ``exactff info`` says it: the vector area ``|sum A n|`` within
    ``CLOSED_RESIDUAL`` of the total area (T-junctions allowed: a block standing on a
    floor leaves edges unpaired in a closed room)."""
    vector_area = (scene.normals * scene.areas[:, None]).sum(axis=0)
    return np.linalg.norm(vector_area) / scene.areas.sum() <= tol.CLOSED_RESIDUAL


def _unobstructed_rows(scene, rows):
    from .kernel import point_polygon_form_factors

    return np.array([point_polygon_form_factors(scene.centroids[i], scene.normals[i], scene)
                     for i in rows])


def check_matrix(F, scene: Scene | None = None, E=None, *, remainder=None,
                 remainder_error=None, rows=None, closed: bool | None = None,
                 area: bool = False, unobstructed=None) -> MatrixReport:
    """Check a form-factor matrix's invariants: row sums, reciprocity, signs, bounds.

    Works on any matrix, however computed (a user's hemicube matrix, View3D's), dense
    (ndarray, memory map, zarr array: read in blocks) or ``scipy.sparse``.

    Parameters
    ----------
    F : array_like or scipy.sparse matrix of shape (R, N)
        ``F[i, j]`` = F(row i -> polygon j).
    scene : Scene, optional
        The scene (N polygons): its areas for reciprocity, whether it is closed.
    E : array_like or scipy.sparse matrix of shape (R, N), optional
        Error estimates of ``F`` (``|F - exact| <= E``): rows and pairs are then judged
        against them, and the largest is reported.
    remainder : array_like of shape (R, 2) or (R,), optional
        Each row's uncovered remainder (sky and ground, from
        :func:`exactff.form_factors` or :func:`exactff.form_factor_matrix` with
        ``remainder=True``): the rows then sum to 1 with it, in any scene.
    remainder_error : array_like of the same shape, optional
        Bounds on the remainder.
    rows : sequence of int, optional
        The scene's polygon of each row (default ``0 .. R-1``).
    closed : bool, optional
        Whether the rows should sum to 1 without a remainder. Default: when a scene is
        given, whether it is closed as ``exactff info`` says (no vector area; an open
        tube has none either: say ``closed=False``); without one, not judged.
    area : bool, default False
        ``F`` is an area-to-area matrix (:func:`exactff.area_form_factors`, View3D, a
        radiosity code's): reciprocity ``A_i F_ij = A_j F_ji`` is then judged. Point
        rows from centroids (:func:`exactff.form_factor_matrix`) are not reciprocal:
        their defect is reported, not judged.
    unobstructed : array_like, scipy.sparse matrix or "points", optional
        The same matrix without occlusion, or ``"points"`` to compute it here
        (unoccluded point rows from the rows' centroids, cheap): the largest excess of
        ``F`` over it is reported, and values beyond it (with ``E`` and rounding) miss.

    Returns
    -------
    MatrixReport

    Raises
    ------
    ValueError
        A shape that does not match (the message names the argument).

    Notes
    -----
    Bounds: a row's sum ``1 +- (sum_j E_ij + remainder_error + rounding)``, the
    rounding being ``MATRIX_ROUNDING_ULPS`` units of roundoff per value summed; without
    ``E`` the row-sum target ``MATRIX_ROW_SUM_ATOL``. A pair: ``|A_i F_ij - A_j F_ji|
    <= A_i E_ij + A_j E_ji`` plus rounding; without ``E``, ``MATRIX_RECIPROCITY_RTOL`` of
    the larger product. A value: ``-E <= F <= 1 + E``, NaN never.

    Examples
    --------
    A coarse hemicube's rows miss 1 in a closed box; the exact rows do not:

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(2)
    >>> report = check_matrix(ef.form_factor_matrix(box, method="hemicube", resolution=8), box)
    >>> report.ok, len(report.rows_missing), report.judged
    (False, 24, 'closed scene')
    >>> check_matrix(ef.form_factor_matrix(box), box).ok
    True
    >>> print(check_matrix([[0.5, 0.6], [0.2, 0.8]], closed=True))  # doctest: +NORMALIZE_WHITESPACE
    matrix           2 x 2 (dense)
    row sums         min 1.000000000000000  max 1.100000000000000
                     largest deficit -0.1 (row 0); should be 1 (closed=True)
    values           0 below 0, 0 NaN, 0 above 1 (min 0.2, max 0.8)
    MISSED           1 rows: 0
    """
    import scipy.sparse as sp

    sparse = sp.issparse(F)
    if not sparse and not hasattr(F, "shape"):
        F = np.asarray(F, dtype=float)
    if len(F.shape) != 2:
        raise ValueError(f"F must be a matrix (R, N), got shape {F.shape}")
    R, N = (int(s) for s in F.shape)
    if scene is not None and N != len(scene):
        raise ValueError(f"F has {N} columns but the scene has {len(scene)} polygons")
    rows = np.arange(R) if rows is None else np.asarray(rows, dtype=int).reshape(-1)
    if rows.shape != (R,):
        raise ValueError(f"rows must have one entry per row of F ({R}), got {rows.shape}")
    if E is not None:
        if not sp.issparse(E) and not hasattr(E, "shape"):
            E = np.asarray(E, dtype=float)
        if tuple(E.shape) != (R, N):
            raise ValueError(f"E must have the shape of F {(R, N)}, got {tuple(E.shape)}")
    extra = np.zeros(R)
    extra_bound = np.zeros(R)
    if remainder is not None:
        rem = np.asarray(remainder, dtype=float)
        if rem.shape not in ((R,), (R, 2)):
            raise ValueError(f"remainder must have shape ({R}, 2) or ({R},), got {rem.shape}")
        extra = rem.reshape(R, -1).sum(axis=1)
        if remainder_error is not None:
            re = np.asarray(remainder_error, dtype=float)
            if re.shape != rem.shape:
                raise ValueError(f"remainder_error must have the shape of remainder "
                                 f"{rem.shape}, got {re.shape}")
            extra_bound = re.reshape(R, -1).sum(axis=1)
    if isinstance(unobstructed, str):
        if unobstructed != "points":
            raise ValueError(f"unobstructed must be a matrix or 'points', got {unobstructed!r}")
        if scene is None:
            raise ValueError("unobstructed='points' needs the scene")
        unobstructed = _unobstructed_rows(scene, rows)
    if unobstructed is not None:
        if not sp.issparse(unobstructed) and not hasattr(unobstructed, "shape"):
            unobstructed = np.asarray(unobstructed, dtype=float)
        if tuple(unobstructed.shape) != (R, N):
            raise ValueError(f"unobstructed must have the shape of F {(R, N)}, got "
                             f"{tuple(unobstructed.shape)}")
    if closed is not None:
        judged = "closed=True" if closed else None
    elif remainder is not None:
        judged = None
    else:
        judged = "closed scene" if scene is not None and _is_closed(scene) else None
    if remainder is not None:
        judged = "remainder"

    # one pass over the rows: sums, values, estimates, the unobstructed excess
    sums = np.zeros(R)
    abs_sums = np.zeros(R)
    e_sums = np.zeros(R)
    bad_rows = set()
    negatives = nans = above = 0
    vmin, vmax = math.inf, -math.inf
    emax, emax_at = -math.inf, None
    excess, excess_at, excess_missing = -math.inf, None, []
    for a, b, Fb in ((a, b, _dense(F, a, b)) for a, b in _row_ranges(R, N)):
        Eb = np.zeros_like(Fb) if E is None else _dense(E, a, b)
        isnan = np.isnan(Fb)
        nans += int(isnan.sum())
        neg = Fb < -Eb
        big = Fb > 1 + Eb
        negatives += int(neg.sum())
        above += int(big.sum())
        for r in np.flatnonzero(isnan.any(axis=1) | neg.any(axis=1) | big.any(axis=1)):
            bad_rows.add(a + int(r))
        if (~isnan).any():
            vmin = min(vmin, float(np.nanmin(Fb)))
            vmax = max(vmax, float(np.nanmax(Fb)))
        sums[a:b] = Fb.sum(axis=1)
        abs_sums[a:b] = np.abs(np.nan_to_num(Fb)).sum(axis=1)
        e_sums[a:b] = Eb.sum(axis=1)
        if E is not None and Eb.size:
            k = int(np.argmax(Eb))
            if Eb.flat[k] > emax:
                emax, emax_at = float(Eb.flat[k]), (a + k // N, k % N)
        if unobstructed is not None and Fb.size:
            Ub = _dense(unobstructed, a, b)
            D = Fb - Ub
            k = int(np.nanargmax(D)) if np.any(np.isfinite(D)) else 0
            if D.flat[k] > excess:
                excess, excess_at = float(D.flat[k]), (a + k // N, k % N)
            room = ((Eb if E is not None else tol.MATRIX_ROW_SUM_ATOL)
                    + tol.MATRIX_ROUNDING_ULPS * tol.EPS * np.abs(Ub))
            for r, c in zip(*np.nonzero(D > room)):
                excess_missing.append((a + int(r), int(c)))
    sums = sums + extra
    deficits = 1.0 - sums
    rounding = tol.MATRIX_ROUNDING_ULPS * tol.EPS * (N + 2) * (abs_sums + np.abs(extra))
    if E is None and remainder_error is None:
        row_bounds = np.full(R, tol.MATRIX_ROW_SUM_ATOL) + rounding
    else:
        row_bounds = e_sums + extra_bound + rounding
    if judged is not None:
        bad_rows.update(int(r) for r in np.flatnonzero(~(np.abs(deficits) <= row_bounds)))
    # rows named by their polygon (``rows``), as everywhere in the report
    label = lambda k: int(rows[k])
    rows_missing = sorted(label(k) for k in bad_rows)
    excess_missing = [(label(k), c) for k, c in excess_missing]
    emax_at = None if emax_at is None else (label(emax_at[0]), emax_at[1])
    excess_at = None if excess_at is None else (label(excess_at[0]), excess_at[1])

    report = MatrixReport(
        shape=(R, N), sparse=sparse, rows=rows, sums=sums, deficits=deficits, judged=judged,
        row_bounds=row_bounds, rows_missing=rows_missing, negatives=negatives, nans=nans,
        above_one=above, min_value=float(vmin) if math.isfinite(vmin) else math.nan,
        max_value=float(vmax) if math.isfinite(vmax) else math.nan,
        max_error=None if E is None else float(max(emax, 0.0)),
        max_error_at=None if E is None else (emax_at or (0, 0)), area=bool(area),
        obstructed_excess=None if unobstructed is None else float(excess),
        excess_at=None if unobstructed is None else (excess_at or (0, 0)),
        excess_missing=excess_missing)
    if scene is not None and R == N and np.array_equal(rows, np.arange(N)):
        _reciprocity(report, F, E, scene.areas, area)
    return report


def _row_ranges(R, N):
    step = max(1, _BLOCK_VALUES // max(N, 1))
    return [(a, min(a + step, R)) for a in range(0, R, step)]


def _reciprocity(report, F, E, A, area):
    """Fill in the reciprocity defect of a square matrix, block against block, and the
    pairs that miss it (judged when ``area``)."""
    N = len(A)
    worst, at, missing = -1.0, (0, 0), []
    for a, b in _row_ranges(N, N):
        G = A[a:b, None] * _dense(F, a, b)                     # A_i F_ij, rows a:b
        cols = _columns(F, a, b)                                # F[:, a:b]
        H = (A[:, None] * cols).T                               # A_j F_ji, as [i - a, j]
        D = np.abs(G - H)
        if E is not None:
            room = A[a:b, None] * _dense(E, a, b) + (A[:, None] * _columns(E, a, b)).T
        else:
            room = tol.MATRIX_RECIPROCITY_RTOL * np.maximum(np.abs(G), np.abs(H))
        room = room + tol.MATRIX_ROUNDING_ULPS * tol.EPS * (np.abs(G) + np.abs(H))
        if D.size and np.any(np.isfinite(D)):
            k = int(np.nanargmax(D))
            if D.flat[k] > worst:
                worst, at = float(D.flat[k]), (a + k // N, k % N)
        if area:
            for r, c in zip(*np.nonzero(~(D <= room))):
                i, j = a + int(r), int(c)
                if i < j or not (a <= j < b):        # each pair once
                    missing.append((min(i, j), max(i, j)))
    report.reciprocity = max(worst, 0.0)
    report.reciprocity_pair = at
    report.pairs_missing = sorted(set(missing))


def _columns(M, a, b):
    """``M[:, a:b]`` as a dense array (read in row blocks for a dense store)."""
    import scipy.sparse as sp

    if sp.issparse(M):
        return sp.csc_array(M)[:, a:b].toarray()
    R, N = M.shape
    return np.concatenate([np.asarray(M[c:d, a:b], dtype=float) for c, d in _row_ranges(R, N)]
                          or [np.zeros((0, b - a))])
