"""Audits: another tool's form-factor matrix against the exact one, entry by entry, with
the configurations of the pairs where its errors live."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import _tolerances as tol
from .checks import as_point, check_tolerance
from .formfactors import AreaRows, PointRows, run_rows
from .geometry import polygon_diameter
from .io.dataframe import polygon_labels
from .methods import Exact
from .reports import MatrixReport, check_matrix
from .scene import Scene, as_scene

__all__ = ["audit", "AuditReport", "CONFIGURATIONS", "pair_configurations", "KINDS"]

#: What ``kind=`` chooses: area-to-area values (the paper's Eq. 1), or point rows (from
#: the centroids, or from given points).
KINDS = ("area", "point")

#: The configurations of the breakdown (overlapping: a pair is counted in each it is in;
#: ``"other"`` holds the pairs in none of them):
#: ``edge_sharing`` (an edge, or a length of one, in common), ``near`` (centroids less
#: than ``AUDIT_NEAR_SEPARATION`` of the larger circumradius apart), ``partly_occluded``
#: (something hides part of the pair: the exact value below its unoccluded one, and
#: above 0, beyond the bound), ``grazing`` (one polygon reaches the other's plane from
#: its front, within ``AUDIT_GRAZING_RTOL`` of its size).
CONFIGURATIONS = ("edge_sharing", "near", "partly_occluded", "grazing")


@dataclass
class AuditReport:
    """Another tool's matrix against the exact one: what :func:`audit` returns.

    Every array is over the scene's polygons, ``[i, j]`` for the pair i -> j
    (``docs/explanation/conventions.md``).

    Attributes
    ----------
    kind : {"area", "point"}
    tolerance : float
        The tolerance the exact values were computed to (absolute for ``"area"``,
        relative for ``"point"``).
    labels : list
        A label per polygon (its name, or its group and index:
        :func:`exactff.io.dataframe.polygon_labels`).
    names, groups : tuple
        The scene's polygon names and groups.
    areas : ndarray of shape (N,)
    other : ndarray of shape (N, N)
        The matrix audited, dense, an entry the other tool left out as 0.
    present : ndarray of bool, shape (N, N)
        The entries the other tool gave (every entry of a dense matrix; the stored
        ones of a sparse matrix).
    exact, bound : ndarray of shape (N, N)
        The exact values and their bounds (``|exact - true| <= bound``), computed by
        the matrix driver (:func:`exactff.formfactors.run_rows`).
    unoccluded : ndarray of shape (N, N)
        The same pairs without occlusion (closed forms): what tells the occluded pairs.
    separation : ndarray of shape (N, N)
        The distance between the centroids over the larger circumradius about them.
    configurations : dict of str to ndarray of bool, shape (N, N)
        :data:`CONFIGURATIONS`, symmetric, the diagonal left out.
    other_check, exact_check : MatrixReport
        :func:`exactff.check_matrix` of the two matrices (the exact one with its bounds).
    points : ndarray of shape (N, 3) or None
        The receivers of point rows, where given.
    other_bound : ndarray of shape (N, N) or None
        The other matrix's own error bounds, where given.
    """

    kind: str
    tolerance: float
    labels: list
    names: tuple
    groups: tuple
    areas: np.ndarray
    other: np.ndarray
    present: np.ndarray
    exact: np.ndarray
    bound: np.ndarray
    unoccluded: np.ndarray
    separation: np.ndarray
    configurations: dict
    other_check: MatrixReport
    exact_check: MatrixReport
    points: np.ndarray | None = field(default=None, repr=False)
    other_bound: np.ndarray | None = field(default=None, repr=False)

    # -- per entry -----------------------------------------------------------------
    @property
    def error(self):
        """``other - exact``, ndarray of shape (N, N)."""
        return self.other - self.exact

    @property
    def slack(self):
        """What an entry's error may be without saying anything about the other tool:
        the exact value's bound, the other's own bound where it was given
        (``other_bound``), and the rounding of the difference (``MATRIX_ROUNDING_ULPS``
        roundoffs of the larger value)."""
        own = 0.0 if self.other_bound is None else self.other_bound
        return self.bound + own + tol.MATRIX_ROUNDING_ULPS * tol.EPS * np.maximum(
            np.abs(self.other), np.abs(self.exact))

    @property
    def relative_error(self):
        """``(other - exact) / exact``; where the exact value is 0, 0 if the other is too
        and +-inf if not. ndarray of shape (N, N)."""
        err = self.error
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = err / self.exact
        zero = self.exact == 0
        rel[zero] = np.where(err[zero] == 0, 0.0, np.copysign(np.inf, err[zero]))
        return rel

    @property
    def outside(self):
        """The entries whose error exceeds :attr:`slack`: errors of the other tool (the
        exact value's bound cannot explain them). ndarray of bool, shape (N, N)."""
        return np.abs(self.error) > self.slack

    @property
    def missing(self):
        """Entries the other tool left out whose exact value exceeds its bound: ndarray
        of bool, shape (N, N)."""
        return ~self.present & (self.exact > self.slack)

    @property
    def missing_mass(self):
        """Per row, the sum of the exact values of the entries left out: ndarray of shape
        (N,)."""
        return np.where(self.present, 0.0, self.exact).sum(axis=1)

    # -- rows and pairs ----------------------------------------------------------------
    @property
    def row_sums(self):
        """``(other, exact, bound)`` row sums, each of shape (N,): the bound is the sum of
        the row's bounds plus rounding."""
        n = len(self.areas)
        rounding = tol.MATRIX_ROUNDING_ULPS * tol.EPS * (n + 2) * (
            np.abs(self.other).sum(axis=1) + np.abs(self.exact).sum(axis=1))
        return (self.other.sum(axis=1), self.exact.sum(axis=1),
                self.bound.sum(axis=1) + rounding)

    @property
    def rows_off(self):
        """Rows whose sum differs from the exact row's beyond its bound (a defect of
        the row sums the exact matrix does not have), as a list of int."""
        o, e, b = self.row_sums
        return [int(i) for i in np.flatnonzero(np.abs(o - e) > b)]

    def _reciprocity(self, M):
        G = self.areas[:, None] * M
        return G - G.T

    @property
    def reciprocity(self):
        """``(other, exact)`` reciprocity defects ``A_i F_ij - A_j F_ji``, each (N, N)
        and antisymmetric (for point rows the exact one need not be 0)."""
        return self._reciprocity(self.other), self._reciprocity(self.exact)

    @property
    def pairs_off(self):
        """Pairs ``(i, j)``, ``i < j``, whose reciprocity defect differs from the exact
        matrix's beyond ``A_i bound_ij + A_j bound_ji`` (plus rounding): list of tuples."""
        D_o, D_e = self.reciprocity
        A = self.areas[:, None]
        room = A * self.slack + (A * self.slack).T
        i, j = np.nonzero(np.triu(np.abs(D_o - D_e) > room, 1))
        return [(int(a), int(b)) for a, b in zip(i, j)]

    @property
    def clean(self):
        """True when no entry, row or pair differs from the exact matrix beyond its
        bound (the other matrix is exact as far as the bounds can tell)."""
        return not (self.outside.any() or self.rows_off or self.pairs_off)

    # -- the worst entries and the breakdown ---------------------------------------------
    def worst(self, k=10):
        """The ``k`` entries of largest ``|error|``, largest first.

        Returns
        -------
        list of (int, int, float, float, float)
            ``(i, j, other, exact, error)``.
        """
        k = int(k)
        if k < 0:
            raise ValueError(f"k must be a non-negative integer, got {k}")
        err = self.error
        order = np.argsort(-np.abs(err), axis=None, kind="stable")[:k]
        n = err.shape[1]
        return [(int(f // n), int(f % n), float(self.other.flat[f]), float(self.exact.flat[f]),
                 float(err.flat[f])) for f in order]

    def worst_entries(self, k=10):
        """:meth:`worst` with what else is known of each entry: a list of dicts with
        ``i``, ``j``, ``from``, ``to`` (labels), ``from_group``, ``to_group``, ``other``,
        ``exact``, ``bound``, ``error``, ``relative_error``, ``present`` and
        ``configurations`` (the names of those the pair is in)."""
        rel = self.relative_error
        out = []
        for i, j, o, e, err in self.worst(k):
            r = float(rel[i, j])
            out.append({"i": i, "j": j, "from": self.labels[i], "to": self.labels[j],
                        "from_group": self.groups[i], "to_group": self.groups[j],
                        "other": o, "exact": e, "bound": float(self.bound[i, j]),
                        "error": err, "relative_error": r if math.isfinite(r) else str(r),
                        "present": bool(self.present[i, j]),
                        "configurations": [c for c in CONFIGURATIONS
                                           if self.configurations[c][i, j]] or ["other"]})
        return out

    def breakdown(self):
        """The errors by configuration (:data:`CONFIGURATIONS`, then ``"other"``).

        Returns
        -------
        dict of str to dict
            For each: ``pairs`` (entries, the diagonal left out), ``outside`` (of them,
            beyond the bound), ``mean_error`` (signed: a constant added shows here),
            ``mean_abs_error``, ``max_abs_error`` and ``worst`` (its ``(i, j)``),
            ``rms_error``, ``share`` (of the sum of ``|error|`` over every entry).
        """
        err = self.error
        off = ~np.eye(len(err), dtype=bool)
        out_mask = self.outside
        total = float(np.abs(err).sum())
        masks = {c: self.configurations[c] & off for c in CONFIGURATIONS}
        masks["other"] = off & ~np.logical_or.reduce([masks[c] for c in CONFIGURATIONS])
        out = {}
        for c, m in masks.items():
            e = err[m]
            row = {"pairs": int(m.sum()), "outside": int((out_mask & m).sum())}
            if e.size:
                a = np.abs(np.where(m, err, 0.0))
                w = int(np.argmax(a))
                row.update(mean_error=float(e.mean()), mean_abs_error=float(np.abs(e).mean()),
                           max_abs_error=float(a.flat[w]),
                           worst=[w // len(err), w % len(err)],
                           rms_error=float(np.sqrt(np.mean(e * e))),
                           share=float(np.abs(e).sum() / total) if total > 0 else 0.0)
            else:
                row.update(mean_error=0.0, mean_abs_error=0.0, max_abs_error=0.0, worst=None,
                           rms_error=0.0, share=0.0)
            out[c] = row
        return out

    def to_dict(self, worst=20, matrices=False):
        """The report as plain values (JSON): what ``exactff audit`` writes to
        ``audit.json``.

        Parameters
        ----------
        worst : int, default 20
            How many of the worst entries to list.
        matrices : bool, default False
            Also the (N, N) arrays ``other``, ``exact``, ``bound``, ``error`` (lists of
            lists).
        """
        err = self.error
        o, e, b = self.row_sums
        D_o, D_e = self.reciprocity
        rel = self.relative_error
        finite = np.isfinite(rel) & (self.exact > self.slack)
        n = len(self.areas)
        d = {
            "kind": self.kind, "tolerance": self.tolerance, "polygons": n,
            "clean": self.clean,
            "entries": n * n, "entries_present": int(self.present.sum()),
            "entries_outside": int(self.outside.sum()),
            "max_abs_error": float(np.abs(err).max(initial=0.0)),
            "mean_abs_error": float(np.abs(err).mean()) if n else 0.0,
            "rms_error": float(np.sqrt(np.mean(err * err))) if n else 0.0,
            "max_relative_error": float(np.abs(rel[finite]).max(initial=0.0)),
            "max_bound": float(self.bound.max(initial=0.0)),
            "missing": {"entries": int(self.missing.sum()),
                        "exact_mass": float(self.missing_mass.sum()),
                        "largest": [[int(i), int(j), float(self.exact[i, j])] for i, j in
                                    sorted(zip(*np.nonzero(self.missing)),
                                           key=lambda p: -self.exact[p])[:worst]]},
            "rows_off": self.rows_off,
            "pairs_off": [list(p) for p in self.pairs_off],
            "max_reciprocity_defect": {"other": float(np.abs(D_o).max(initial=0.0)),
                                       "exact": float(np.abs(D_e).max(initial=0.0))},
            "worst": self.worst_entries(worst),
            "breakdown": self.breakdown(),
            "rows": {"labels": [str(x) for x in self.labels], "sum_other": o.tolist(),
                     "sum_exact": e.tolist(), "sum_bound": b.tolist(),
                     "max_abs_error": np.abs(err).max(axis=1, initial=0.0).tolist(),
                     "missing_mass": self.missing_mass.tolist()},
            "other_check": _summary(self.other_check),
            "exact_check": _summary(self.exact_check),
        }
        if matrices:
            d.update(other=self.other.tolist(), exact=self.exact.tolist(),
                     bound=self.bound.tolist(), error=err.tolist())
        return d

    def __str__(self):
        err = self.error
        n = len(self.areas)
        what = ("area-to-area" if self.kind == "area" else
                "point rows from " + ("the points given" if self.points is not None
                                      else "the centroids"))
        lines = [f"audit            {n} x {n}, {what}, exact to {self.tolerance:g} "
                 f"(largest bound {self.bound.max(initial=0.0):.3g})",
                 f"entries          {int(self.present.sum())} given, "
                 f"{int(self.outside.sum())} beyond the exact bound; max |error| "
                 f"{np.abs(err).max(initial=0.0):.3g}, mean |error| "
                 f"{np.abs(err).mean():.3g}"]
        if (~self.present).any():
            lines.append(f"left out         {int((~self.present).sum())} entries, "
                         f"{int(self.missing.sum())} of them non-zero: exact mass "
                         f"{self.missing_mass.sum():.3g}")
        o, e, b = self.row_sums
        w = int(np.argmax(np.abs(o - e))) if n else 0
        lines.append(f"row sums         {len(self.rows_off)} rows off the exact sums; "
                     f"largest difference {o[w] - e[w]:+.3g} (row {w}: {self.labels[w]})")
        D_o, D_e = self.reciprocity
        lines.append(f"reciprocity      {len(self.pairs_off)} pairs off the exact matrix's; "
                     f"max |A_i F_ij - A_j F_ji| {np.abs(D_o).max(initial=0.0):.3g} "
                     f"(exact {np.abs(D_e).max(initial=0.0):.3g})")
        lines.append("configuration    pairs  beyond  mean error  max |error|  share")
        for c, r in self.breakdown().items():
            lines.append(f"  {c:<15}{r['pairs']:>6}  {r['outside']:>6}  {r['mean_error']:>+10.3g}"
                         f"  {r['max_abs_error']:>11.3g}  {r['share']:>5.1%}")
        lines.append("worst entries    i -> j: other, exact, error")
        for i, j, ov, ev, er in self.worst(5):
            lines.append(f"  {self.labels[i]} -> {self.labels[j]}: {ov:.6g}, {ev:.6g}, "
                         f"{er:+.3g}")
        lines.append("verdict          " + ("clean: within the exact bounds" if self.clean
                                             else "the other matrix differs from the exact one"))
        return "\n".join(lines)


def _summary(report):
    d = report.to_dict()
    return {k: d[k] for k in ("judged", "rows_missing", "pairs_missing", "negatives",
                              "nans", "above_one", "reciprocity", "ok")}


# ---------------------------------------------------------------------------------------
# the configurations of the pairs
# ---------------------------------------------------------------------------------------
def _edges(scene, i):
    P = scene.polygons[i]
    return P, np.roll(P, -1, axis=0)


def _edge_sharing(scene):
    """Pairs with a length of edge in common: an edge of each collinear with the other's
    (both ends within ``AUDIT_CONTACT_RTOL`` of the pair's size of its line) and their
    overlap longer than that. Symmetric (N, N) bool, the diagonal False."""
    n = len(scene)
    lo = np.array([p.min(axis=0) for p in scene.polygons])
    hi = np.array([p.max(axis=0) for p in scene.polygons])
    size = np.array([polygon_diameter(p) for p in scene.polygons])
    pad = tol.AUDIT_CONTACT_RTOL * np.maximum(size[:, None], size[None, :])
    touch = np.all((lo[:, None] <= hi[None, :] + pad[..., None])
                   & (lo[None, :] <= hi[:, None] + pad[..., None]), axis=-1)
    out = np.zeros((n, n), bool)
    for i, j in zip(*np.nonzero(np.triu(touch, 1))):
        a, b = _edges(scene, i)
        c, d = _edges(scene, j)
        eps = pad[i, j]
        u = b - a
        L = np.linalg.norm(u, axis=1)
        u = u / L[:, None]
        # distances of j's edge ends from i's edge lines, and their parameters on them
        rel_c = c[None, :, :] - a[:, None, :]
        rel_d = d[None, :, :] - a[:, None, :]
        tc = np.einsum("ekx,ex->ek", rel_c, u)
        td = np.einsum("ekx,ex->ek", rel_d, u)
        dc = np.linalg.norm(rel_c - tc[..., None] * u[:, None, :], axis=-1)
        dd = np.linalg.norm(rel_d - td[..., None] * u[:, None, :], axis=-1)
        overlap = (np.minimum(np.maximum(tc, td), L[:, None])
                   - np.maximum(np.minimum(tc, td), 0.0))
        if np.any((dc <= eps) & (dd <= eps) & (overlap > eps)):
            out[i, j] = out[j, i] = True
    return out


def _radii(scene):
    return np.array([np.linalg.norm(p - c, axis=1).max()
                     for p, c in zip(scene.polygons, scene.centroids)])


def _grazing(scene):
    """Pairs where one polygon reaches the other's plane from its front: its lowest
    vertex over that plane below ``AUDIT_GRAZING_RTOL`` of its size, its highest above
    0. Symmetric (N, N) bool, the diagonal False."""
    n = len(scene)
    size = np.array([polygon_diameter(p) for p in scene.polygons])
    V, off = scene.vertices, scene.offsets
    g = np.zeros((n, n), bool)
    step = max(1, 2 ** 22 // max(len(V), 1))          # blocks of rows of about 4M heights
    for a in range(0, n, step):
        b = min(n, a + step)
        # heights of every vertex over the planes of polygons a:b, then [i, j]: the lowest
        # and highest of polygon j's over the plane of polygon i
        h = scene.normals[a:b] @ V.T - scene.plane_offsets[a:b, None]
        low = np.minimum.reduceat(h, off[:-1], axis=1)
        high = np.maximum.reduceat(h, off[:-1], axis=1)
        g[a:b] = (low < tol.AUDIT_GRAZING_RTOL * size[None, :]) & (high > 0)
    g = g | g.T
    np.fill_diagonal(g, False)
    return g


def _unoccluded(scene, kind, points, tolerance):
    """The pairs' values without occlusion, (N, N): closed-form area form factors (each
    within ``tolerance``: no mpmath where the closed form's estimate meets it), or point
    form factors from the rows' receivers (exact to rounding), and their estimates."""
    n = len(scene)
    U, UE = np.zeros((n, n)), np.zeros((n, n))
    if kind == "area":
        from .area.closed_form import unoccluded_pairs

        for i in range(n):
            others = [j for j in range(n) if j != i]
            if others:
                U[i, others], UE[i, others] = unoccluded_pairs(
                    scene.polygons[i], [scene.polygons[j] for j in others], atol=tolerance)
        return U, UE
    from .kernel import point_polygon_form_factors

    P = scene.centroids if points is None else points
    for i in range(n):
        U[i] = point_polygon_form_factors(P[i], scene.normals[i], scene)
    return U, UE


def pair_configurations(scene, exact=None, bound=None, unoccluded=None,
                        unoccluded_bound=None):
    """The configurations of a scene's pairs (:data:`CONFIGURATIONS`), and their
    separation.

    Parameters
    ----------
    scene : Scene
    exact, bound, unoccluded, unoccluded_bound : ndarray of shape (N, N), optional
        The exact values, their bounds, the unoccluded values and their bounds: needed
        for ``partly_occluded`` (all False without them).

    Returns
    -------
    (dict of str to ndarray of bool of shape (N, N), ndarray of shape (N, N))
        The configurations (symmetric, the diagonal False), and each pair's distance
        between centroids over the larger circumradius about them.

    Examples
    --------
    Two faces of a unit box share an edge; opposite faces are apart:

    >>> import exactff as ef
    >>> conf, sep = pair_configurations(ef.scenes.subdivided_box(1))
    >>> bool(conf["edge_sharing"][0, 2]), bool(conf["edge_sharing"][0, 1])
    (True, False)
    >>> round(float(sep[0, 1]), 6)      # 1 / (sqrt(2) / 2)
    1.414214
    """
    scene = as_scene(scene)
    n = len(scene)
    r = _radii(scene)
    C = scene.centroids
    sep = np.linalg.norm(C[:, None, :] - C[None, :, :], axis=-1) / np.maximum(
        r[:, None], r[None, :])
    conf = {"edge_sharing": _edge_sharing(scene)}
    near = sep < tol.AUDIT_NEAR_SEPARATION
    np.fill_diagonal(near, False)
    conf["near"] = near
    occ = np.zeros((n, n), bool)
    if exact is not None and unoccluded is not None:
        slack = (np.zeros((n, n)) if bound is None else bound) + (
            0.0 if unoccluded_bound is None else unoccluded_bound) + (
            tol.MATRIX_ROUNDING_ULPS * tol.EPS * np.abs(unoccluded))
        occ = (unoccluded - exact > slack) & (exact > slack)
        occ = occ | occ.T
        np.fill_diagonal(occ, False)
    conf["partly_occluded"] = occ
    conf["grazing"] = _grazing(scene)
    return conf, sep


# ---------------------------------------------------------------------------------------
# the audit
# ---------------------------------------------------------------------------------------
def _other_matrix(F_other, n):
    """The other matrix as a dense (N, N) array and the mask of the entries given."""
    import scipy.sparse as sp

    if sp.issparse(F_other):
        S = sp.coo_array(F_other)
        if S.shape != (n, n):
            raise ValueError(f"F_other: expected shape ({n}, {n}) (one row and column per "
                             f"polygon of the scene), got {S.shape}")
        S.sum_duplicates()
        present = np.zeros((n, n), bool)
        present[S.row, S.col] = True
        M = np.zeros((n, n))
        M[S.row, S.col] = S.data
    else:
        try:
            M = np.array(F_other, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"F_other: not a matrix of numbers ({exc})") from None
        if M.shape != (n, n):
            raise ValueError(f"F_other: expected shape ({n}, {n}) (one row and column per "
                             f"polygon of the scene), got {M.shape}")
        present = np.ones((n, n), bool)
    bad = np.argwhere(~np.isfinite(M))
    if len(bad):
        raise ValueError(f"F_other: NaN or infinite value at row {bad[0][0]}, column "
                         f"{bad[0][1]}")
    return M, present


def audit(scene: Scene, F_other, *, kind: str = "area", points=None,
          tolerance: float | None = None, other_bound=None, jobs: int | None = None,
          executor=None, out=None, progress: bool = False) -> AuditReport:
    """How wrong is another tool's form-factor matrix? Every entry against the exact
    value, with its bound.

    Parameters
    ----------
    scene : Scene
        The scene the other matrix is for (N polygons, in the matrix's order: the
        readers of :func:`exactff.read_view_factors` map other tools' surfaces onto
        it).
    F_other : array_like or scipy.sparse matrix of shape (N, N)
        ``F_other[i, j]``: the other tool's F(i -> j) (transpose pyviewfactor's). A
        sparse matrix's entries that are not stored are entries the tool left out:
        they count as 0, and their exact mass is reported.
    kind : {"area", "point"}, default "area"
        ``"area"``: area-to-area form factors (:func:`exactff.area_form_factors`), what
        View3D, OpenFOAM, EnergyPlus and Elmer compute. ``"point"``: row i from a point
        of polygon i with its normal (:func:`exactff.form_factor_matrix`), what
        hemicubes and ray casters from a patch centre compute.
    points : array_like of shape (N, 3), optional
        With ``kind="point"``: the receiver of each row (default the centroids).
    tolerance : float, optional
        The exact values' tolerance: absolute for ``"area"`` (default 1e-9, as
        :func:`exactff.area_form_factors`), relative for ``"point"`` (default the exact
        method's). The bounds returned are what the computation reached.
    other_bound : array_like of shape (N, N), optional
        The other matrix's own bound on each entry's error, where it states one (an
        exact code's, a Monte Carlo code's confidence interval): an entry is then an
        error only beyond both bounds.
    jobs, executor, out, progress
        As for :func:`exactff.form_factor_matrix`: rows in worker processes or on an
        executor, the exact matrix streamed to ``out`` (its bounds beside it in
        ``STEM.error.SUFFIX``) and resumed from it, a progress bar.

    Returns
    -------
    AuditReport
        ``rep.exact``, ``rep.bound`` (N, N); ``rep.error`` (``F_other - exact``);
        ``rep.worst(k)``; ``rep.breakdown()``; ``rep.to_dict()``; ``str(rep)``.

    Raises
    ------
    ValueError
        ``F_other`` is not (N, N) or holds NaN or infinite values; a bad ``kind``,
        ``points`` or ``tolerance`` (the message names the argument).

    Notes
    -----
    An entry is an error of the other tool when ``|error| > bound`` (plus the rounding
    of the difference): :attr:`AuditReport.outside`. Row sums and reciprocity are
    compared with the exact matrix's, not with 1 and 0: an open scene's rows need not
    sum to 1, and point rows are not reciprocal. The exact values are dense in memory
    ((N, N) doubles, three of them): meant for scenes of up to a few thousand polygons.
    The how-to: ``docs/how-to/audit.md``.

    Examples
    --------
    A constant added to every pair of a closed box's faces that share an edge (the
    defect of a code that mishandles adjacent surfaces):

    >>> import exactff as ef
    >>> box = ef.scenes.subdivided_box(1)
    >>> F = ef.area_form_factors(box)
    >>> conf, _ = pair_configurations(box)
    >>> rep = audit(box, F + 0.01 * conf["edge_sharing"], kind="area", tolerance=1e-9)
    >>> rep.clean, round(rep.breakdown()["edge_sharing"]["mean_error"], 12)
    (False, 0.01)
    >>> i, j, other, exact, error = rep.worst(1)[0]
    >>> round(exact, 10), round(error, 12)      # adjacent faces of a cube: Howell C-14
    (0.2000437761, 0.01)
    >>> audit(box, F).clean
    True
    """
    scene = as_scene(scene)
    n = len(scene)
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    M, present = _other_matrix(F_other, n)
    check_tolerance(tolerance)
    if other_bound is not None:
        other_bound = np.array(other_bound, dtype=float)
        if other_bound.shape != (n, n) or not np.all(other_bound >= 0):
            raise ValueError(f"other_bound must be an array of shape ({n}, {n}) of bounds "
                             f">= 0, got shape {other_bound.shape}")
    P = None
    if points is not None:
        if kind != "point":
            raise ValueError("points= gives the receivers of point rows: with kind='point'")
        P = as_point(points, "points")
        if P.shape != (n, 3):
            raise ValueError(f"points must have shape ({n}, 3) (one receiver per polygon), "
                             f"got {P.shape}")
    rows = np.arange(n)
    options = dict(jobs=jobs, executor=executor, out=out, progress=progress,
                   desc="audit: exact values")
    if kind == "area":
        tolerance = 1e-9 if tolerance is None else tolerance
        # values whose estimate misses the tolerance come back with it (error=True)
        E_exact = run_rows(scene, rows, AreaRows(tolerance), **options)
    else:
        method = Exact() if tolerance is None else Exact(tolerance=tolerance)
        tolerance = method.tolerance
        E_exact = run_rows(scene, rows, PointRows(method, False, error=True, points=P),
                           **options)
    exact, bound = (np.array(A, dtype=float) for A in E_exact)      # in memory, not the file
    U, UE = _unoccluded(scene, kind, P, tolerance)
    conf, sep = pair_configurations(scene, exact, bound, U, UE)
    area = kind == "area"
    return AuditReport(
        kind=kind, tolerance=float(tolerance), labels=polygon_labels(scene),
        names=scene.names, groups=scene.groups, areas=np.array(scene.areas), other=M,
        present=present, exact=exact, bound=bound, unoccluded=U, separation=sep,
        configurations=conf, other_check=check_matrix(M, scene, area=area),
        exact_check=check_matrix(exact, scene, bound, area=area), points=P,
        other_bound=other_bound)
