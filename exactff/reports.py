"""Reports: the error of the discrete methods against the exact method, and run time."""

import time

import numpy as np

from .formfactors import form_factor_matrix
from .methods import resolve

__all__ = ["compare", "to_markdown"]


def compare(scene, methods, samples=(4096, 65536), rows=None, *, reference=None,
            two_sided=False, progress=False):
    """Error against run time of form-factor methods on a scene.

    Parameters
    ----------
    scene : Scene
    methods : sequence of str or FormFactorMethod
        Method names (each is run at every sample count) or configured instances (run
        once, as configured).
    samples : sequence of int, default (4096, 65536)
        Sample counts for the methods given by name (``samples=`` option).
    rows : sequence of int, optional
        The rows (receiving polygons) to compare; default all.
    reference : ndarray of shape (len(rows), len(scene)), optional
        Reference rows; default: the exact method, computed here.
    two_sided : bool, default False
    progress : bool, default False

    Returns
    -------
    list of dict
        One per (method, samples): ``method``, ``samples`` (cells or rays actually
        used), ``rows``, ``mean_abs_error`` (over all coefficients of the rows),
        ``max_abs_error``, ``rms_error``, ``row_sum_error`` (mean absolute difference of
        the row sums), ``time_per_row`` (seconds), ``reference_time_per_row``.

    Examples
    --------
    >>> import exactff as ef
    >>> rec = compare(ef.scenes.cornell_box(closed=True), ["hemicube"], samples=[4096])
    >>> rec[0]["method"], rec[0]["samples"], rec[0]["max_abs_error"] < 0.05
    ('hemicube', 4332, True)
    """
    rows = np.arange(len(scene)) if rows is None else np.asarray(rows, dtype=int).reshape(-1)
    t0 = time.perf_counter()
    ref = (form_factor_matrix(scene, rows=rows, two_sided=two_sided, progress=progress)
           if reference is None else np.asarray(reference, dtype=float))
    t_ref = (time.perf_counter() - t0) / max(len(rows), 1) if reference is None else None
    if ref.shape != (len(rows), len(scene)):
        raise ValueError(f"reference must have shape {(len(rows), len(scene))}, "
                         f"got {ref.shape}")
    runs = []
    for method in methods:
        if isinstance(method, str):
            runs += [(method, resolve(method, samples=int(s))) for s in samples]
        else:
            runs.append((getattr(method, "name", type(method).__name__), resolve(method)))
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


def to_markdown(records):
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
