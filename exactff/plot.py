"""Figures: the error-versus-run-time study and the method's geometry (matplotlib, an
optional extra: ``pip install exactff[plots]``; importing exactff does not import
matplotlib).

The study's functions take :func:`exactff.compare`'s records and draw one line per
method on log axes; the geometry's draw a polygon's projection onto the hemisphere and
its base (:func:`hemisphere_projection`) and a row's visible graph on the unit disk
(:func:`visible_graph`); the audit's (:func:`exactff.audit`) draw another tool's errors
against the pairs' separation, their relative errors, and the scene coloured by each
row's error. Each returns the Axes it drew on.
"""

import numpy as np

__all__ = ["error_vs_samples", "time_vs_samples", "error_vs_time", "hemisphere_projection",
           "visible_graph", "audit_error_vs_distance", "audit_relative_errors",
           "audit_row_errors"]


def _axes(ax, projection=None, figsize=(6.4, 4.4)):
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("exactff.plot needs matplotlib (pip install exactff[plots])") from None
    return plt.figure(figsize=figsize).add_subplot(projection=projection)


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


# ---------------------------------------------------------------------------------------
# the method's geometry: the Nusselt analog and the visible graph
# ---------------------------------------------------------------------------------------
def _arc_points(a, b, n=64):
    """Unit directions along the great-circle arc from ``a`` to ``b`` (n points)."""
    ua, ub = a / np.linalg.norm(a), b / np.linalg.norm(b)
    omega = np.arctan2(np.linalg.norm(np.cross(ua, ub)), ua @ ub)
    s = np.linspace(0.0, 1.0, n)[:, None]
    if omega < 1e-12:
        d = (1 - s) * ua + s * ub
    else:
        d = (np.sin((1 - s) * omega) * ua + np.sin(s * omega) * ub) / np.sin(omega)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _unit_circle(ax, **kw):
    t = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.cos(t), np.sin(t), color="0.3", lw=1, **kw)
    ax.set_aspect("equal")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-1.05, 1.05)


def hemisphere_projection(point, normal, polygon, ax=None, view="base"):
    """The Nusselt analog of one polygon: its projection onto the unit hemisphere over
    ``point`` and then onto the hemisphere's base, whose area over pi is the form factor.

    Coordinates are those of the receiver's local frame (:func:`exactff.receiver_frame`,
    z along the normal); the part of the polygon below the tangent plane is clipped
    away first.

    Parameters
    ----------
    point, normal : array_like of shape (3,)
    polygon : array_like of shape (K, 3)
    ax : matplotlib Axes, optional
        A 2-D Axes for ``view="base"``, a 3-D one for ``view="3d"``; new if None.
    view : {"base", "3d"}, default "base"
        ``"base"``: the image on the base disk, filled, with its edges (the ellipse arcs
        of Eq. 2), its vertices, and the ends of the monotone spans Eq. 3 is integrated
        over (the vertices and the arcs' x-extremes, with a vertical line at each).
        ``"3d"``: the polygon, the rays from the point to its vertices, its image on
        the hemisphere (great-circle arcs) and that image dropped onto the base.

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> sq = [[-.5, -.5, 1], [-.5, .5, 1], [.5, .5, 1], [.5, -.5, 1]]
    >>> ax = hemisphere_projection([0, 0, 0], [0, 0, 1], sq)
    >>> ax.get_title()
    'projection onto the base: F = 0.239456'
    """
    from .kernel import arc_x_extremes, point_polygon_form_factor
    from .kernel.point import local_clipped

    if view not in ("base", "3d"):
        raise ValueError(f"view must be 'base' or '3d', got {view!r}")
    F = point_polygon_form_factor(point, normal, polygon, two_sided=True)
    ring, _ = local_clipped(point, normal, polygon, two_sided=True)
    ring = np.array(ring, dtype=float).reshape(-1, 3)
    arcs = [_arc_points(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]
    image = np.concatenate(arcs) if arcs else np.zeros((0, 3))
    if view == "3d":
        ax = _axes(ax, projection="3d", figsize=(6.4, 5.6))
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi / 2, 10))
        ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v),
                          color="0.8", lw=0.5)
        P = np.vstack([ring, ring[:1]]) if len(ring) else ring
        ax.plot(P[:, 0], P[:, 1], P[:, 2], color="C0", lw=2, label="polygon (clipped)")
        for q in ring:
            d = q / np.linalg.norm(q)
            ax.plot([0, q[0]], [0, q[1]], [0, q[2]], color="0.5", lw=0.6, ls=":")
            ax.plot([d[0], d[0]], [d[1], d[1]], [d[2], 0], color="C2", lw=0.6, ls=":")
        ax.plot(image[:, 0], image[:, 1], image[:, 2], color="C1", lw=2,
                label="image on the hemisphere")
        ax.plot(image[:, 0], image[:, 1], 0 * image[:, 2], color="C2", lw=2,
                label="image on the base")
        ax.scatter([0], [0], [0], color="k", s=12)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_zlabel("z (normal)")
        ax.set_title(f"Nusselt analog: F = {F:.6g}")
        ax.legend(fontsize="small")
        return ax
    ax = _axes(ax, figsize=(5.6, 5.6))
    _unit_circle(ax, label="base of the hemisphere")
    if len(image):
        ax.fill(image[:, 0], image[:, 1], color="C0", alpha=0.25)
        ax.plot(image[:, 0], image[:, 1], color="C0", lw=1.5, label="edges (Eq. 2 arcs)")
        D = ring / np.linalg.norm(ring, axis=1, keepdims=True)
        ax.plot(D[:, 0], D[:, 1], "o", color="C0", ms=4, label="vertices")
        turns = []
        for i in range(len(ring)):
            a, b = ring[i], ring[(i + 1) % len(ring)]
            m = np.cross(a, b)
            if np.linalg.norm(m) == 0 or np.hypot(m[1], m[2]) == 0:
                continue
            w, w_perp, _, _, ts = arc_x_extremes(a, b)
            turns += [np.cos(t) * w + np.sin(t) * w_perp for t in ts]
        if turns:
            T = np.array(turns)
            ax.plot(T[:, 0], T[:, 1], "s", color="C3", ms=6, label="x-extremes")
        for x in np.concatenate([D[:, 0], [t[0] for t in turns]]):
            ax.axvline(x, color="C3", lw=0.5, ls="--", alpha=0.6)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"projection onto the base: F = {F:.6g}")
    ax.legend(fontsize="small", loc="lower left")
    return ax


def visible_graph(scene, point, normal, ax=None, *, two_sided=False, labels=False):
    """The visible graph of one row on the unit disk: every visible piece of every
    polygon (:func:`exactff.visibility.visible_graph`), coloured by its polygon.

    Parameters
    ----------
    scene : Scene
    point, normal : array_like of shape (3,)
    ax : matplotlib Axes, optional
    two_sided : bool, default False
    labels : bool, default False
        Write each polygon's index (or name, where the scene has names) at its largest
        piece.

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import exactff as ef
    >>> ax = visible_graph(ef.scenes.cornell_box(closed=True), [278, 0.5, 279.6], [0, 1, 0])
    >>> len(ax.patches) > 0
    True
    """
    import matplotlib
    import shapely
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    from .visibility import visible_graph as graph

    pieces = graph(scene, point, normal, two_sided=two_sided)
    ax = _axes(ax, figsize=(5.6, 5.6))
    cmap = matplotlib.colormaps["tab20"]
    best = {}
    for i, g in pieces:
        for part in shapely.get_parts(g):
            rings = [np.asarray(part.exterior.coords)] + [np.asarray(r.coords)
                                                         for r in part.interiors]
            verts = np.concatenate(rings)
            codes = np.concatenate([[Path.MOVETO] + [Path.LINETO] * (len(r) - 2)
                                    + [Path.CLOSEPOLY] for r in rings])
            # tab20's strong colours first, then the light ones
            colour = cmap((2 * i) % 20 + (i // 10) % 2)
            ax.add_patch(PathPatch(Path(verts, codes), facecolor=colour,
                                   edgecolor="k", lw=0.3))
            if part.area > best.get(i, (0, None))[0]:
                best[i] = (part.area, part.representative_point())
    if labels:
        names = scene.names
        for i, (_, q) in best.items():
            ax.annotate(names[i] or str(i), (q.x, q.y), fontsize=6,
                        ha="center", va="center")
    _unit_circle(ax)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"visible graph: {len(best)} polygons seen, {len(pieces)} pieces")
    return ax


def _first_configuration(report):
    """Each pair's first configuration (in :data:`exactff.audits.CONFIGURATIONS` order),
    or "other"."""
    from .audits import CONFIGURATIONS

    n = len(report.areas)
    label = np.full((n, n), "other", dtype=object)
    for c in CONFIGURATIONS[::-1]:
        label[report.configurations[c]] = c
    return label


def audit_error_vs_distance(report, ax=None):
    """Each entry's ``|error|`` against its pair's separation (distance between
    centroids over the larger circumradius), coloured by configuration; the exact
    values' bounds in grey.

    Parameters
    ----------
    report : AuditReport
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> rep = ef.audit(box, ef.area_form_factors(box) + 1e-3)
    >>> len(audit_error_vs_distance(rep).collections) > 0
    True
    """
    ax = _axes(ax)
    off = ~np.eye(len(report.areas), dtype=bool)
    err = np.abs(report.error)
    label = _first_configuration(report)
    both = np.concatenate([err[off], report.bound[off]])
    # log axes: zeros (exact entries, zero bounds) drawn a decade below the least value
    floor = _positive(both[both > 0].min() / 10 if (both > 0).any() else 0.0)
    for c in ("edge_sharing", "near", "partly_occluded", "grazing", "other"):
        m = off & (label == c)
        if m.any():
            ax.scatter(report.separation[m], np.maximum(err[m], floor), s=10, label=c)
    ax.scatter(report.separation[off], np.maximum(report.bound[off], floor), s=4,
               c="0.6", marker="_", label="exact bound")
    from matplotlib.ticker import NullFormatter

    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("separation (centroid distance / larger circumradius)")
    ax.set_ylabel("|F_other - F_exact|")
    ax.set_title(f"audit ({report.kind}): error against separation")
    ax.legend(fontsize=7)
    ax.grid(True, which="major", alpha=0.3)
    return ax


def audit_relative_errors(report, ax=None, bins=40):
    """A histogram of ``log10 |relative error|`` over the entries whose exact value
    exceeds its bound (the others have no relative error to speak of).

    Parameters
    ----------
    report : AuditReport
    ax : matplotlib Axes, optional
    bins : int, default 40

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> rep = ef.audit(box, ef.area_form_factors(box) * 1.01)
    >>> len(audit_relative_errors(rep).patches) > 0
    True
    """
    ax = _axes(ax)
    rel = np.abs(report.relative_error)
    m = (report.exact > report.slack) & np.isfinite(rel)
    exact = rel[m] == 0
    values = np.log10(rel[m][~exact]) if (~exact).any() else np.zeros(0)
    # values within a thousandth of a decade (a matrix scaled by a constant): one decade
    # around them, as bins narrower than their rounding cannot be made
    lo, hi = (values.min(), values.max()) if values.size else (0.0, 0.0)
    span = None if hi - lo > 1e-3 else (lo - 0.5, hi + 0.5)
    ax.hist(values, bins=bins, range=span, color="C0")
    ax.set_xlabel("log10 |(F_other - F_exact) / F_exact|")
    ax.set_ylabel("entries")
    ax.set_title(f"audit ({report.kind}): relative errors of {int(m.sum())} entries"
                 + (f" ({int(exact.sum())} exact, not shown)" if exact.any() else ""))
    return ax


def audit_row_errors(report, scene, ax=None):
    """The scene, each polygon coloured by its row's largest ``|error|``.

    Parameters
    ----------
    report : AuditReport
    scene : Scene
        The scene audited.
    ax : matplotlib 3-D Axes, optional

    Returns
    -------
    matplotlib Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> rep = ef.audit(box, ef.area_form_factors(box) + 1e-3)
    >>> len(audit_row_errors(rep, box).collections)
    1
    """
    import matplotlib
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    ax = _axes(ax, projection="3d", figsize=(6.4, 5.6))
    row = np.abs(report.error).max(axis=1)
    top = row.max() if row.max() > 0 else 1.0
    norm = matplotlib.colors.Normalize(0.0, top)
    cmap = matplotlib.colormaps["viridis"]
    coll = Poly3DCollection([np.asarray(p) for p in scene.polygons],
                            facecolors=cmap(norm(row)), edgecolors="k", linewidths=0.3,
                            alpha=0.85)
    ax.add_collection3d(coll)
    lo, hi = scene.bounds
    c, r = (lo + hi) / 2, (hi - lo).max() / 2
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    ax.figure.colorbar(sm, ax=ax, shrink=0.6, label="row's largest |error|")
    ax.set_title(f"audit ({report.kind}): each polygon's row error")
    return ax
