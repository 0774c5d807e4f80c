"""Figures of the error-versus-run-time study (matplotlib, an optional extra:
``pip install exactff[plots]``; importing exactff does not import matplotlib).

Each function takes :func:`exactff.compare`'s records, draws one line per method on log
axes, labels the axes, and returns the Axes.
"""

import numpy as np

__all__ = ["error_vs_samples", "time_vs_samples", "error_vs_time"]


def _axes(ax):
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("exactff.plot needs matplotlib (pip install exactff[plots])") from None
    return plt.figure(figsize=(6.4, 4.4)).add_subplot()


def _by_method(records, sampled=True):
    """Records grouped by method, sorted by samples (``sampled``: those with samples
    only), in the order the methods first appear."""
    groups = {}
    for r in records:
        if sampled and not r.get("samples"):
            continue
        groups.setdefault(r["method"], []).append(r)
    return {m: sorted(rs, key=lambda r: r["samples"]) for m, rs in groups.items()}


def _finish(ax, xlabel, ylabel, title, legend_size=None):
    from matplotlib.ticker import NullFormatter

    ax.set_xscale("log")
    ax.set_yscale("log")
    # decade labels only: the minor ones crowd a short axis
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=legend_size)
    return ax


def _positive(v):
    # log axes: a zero error (a method against itself) is drawn at the axis' floor
    return max(float(v), 1e-18)


def error_vs_samples(records, ax=None):
    """Mean absolute error over all coefficients against the number of samples (the
    paper's Fig. 2), one line per method.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> recs = [{"method": "ppbh", "samples": s, "mean_abs_error": 1 / s,
    ...          "time_per_row": 1e-6 * s} for s in (1000, 4000)]
    >>> len(error_vs_samples(recs).lines)
    1
    """
    ax = _axes(ax)
    for m, rs in _by_method(records).items():
        ax.plot([r["samples"] for r in rs], [_positive(r["mean_abs_error"]) for r in rs],
                marker="o", label=m)
    return _finish(ax, "samples (cells or rays)", "mean absolute error",
                   "error against samples")


def time_vs_samples(records, ax=None):
    """Time per row against the number of samples (the paper's Fig. 3), one line per
    method.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> recs = [{"method": m, "samples": s, "mean_abs_error": 1 / s,
    ...          "time_per_row": 1e-6 * s} for m in ("a", "b") for s in (1000, 4000)]
    >>> len(time_vs_samples(recs).lines)
    2
    """
    ax = _axes(ax)
    for m, rs in _by_method(records).items():
        ax.plot([r["samples"] for r in rs], [r["time_per_row"] for r in rs], marker="o",
                label=m)
    return _finish(ax, "samples (cells or rays)", "time per row (s)",
                   "run time against samples")


def error_vs_time(records, ax=None):
    """Mean absolute error against time per row, one line per method, with the Pareto
    front (for a time budget per row, the least error any method and resolution gives;
    dashed) and the exact method's time per row as a vertical line (from an ``"exact"``
    record, else from the records' ``reference_time_per_row``).

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> recs = [{"method": "ppbh", "samples": s, "mean_abs_error": 1 / s,
    ...          "time_per_row": 1e-6 * s, "reference_time_per_row": 0.1}
    ...         for s in (1000, 4000)]
    >>> ax = error_vs_time(recs)
    >>> len(ax.lines)        # ppbh, the front, the exact method's time
    3
    """
    ax = _axes(ax)
    sampled = _by_method(records)
    for m, rs in sampled.items():
        ax.plot([r["time_per_row"] for r in rs], [_positive(r["mean_abs_error"]) for r in rs],
                marker="o", label=m)
    pts = sorted((r["time_per_row"], r["mean_abs_error"]) for rs in sampled.values() for r in rs)
    if pts:
        front, best = [], np.inf
        for t, e in pts:
            if e < best:
                best = e
                front.append((t, _positive(e)))
        ax.step([t for t, _ in front], [e for _, e in front], where="post", ls="--",
                color="0.4", lw=1, label="Pareto front")
    exact = [r["time_per_row"] for r in records if r["method"] == "exact"]
    if not exact:
        exact = [r["reference_time_per_row"] for r in records
                 if r.get("reference_time_per_row")]
    if exact:
        ax.axvline(exact[0], color="k", lw=1.5, label=f"exact ({exact[0]:.3g} s / row)")
    return _finish(ax, "time per row (s)", "mean absolute error", "error against run time",
                   legend_size="small")
