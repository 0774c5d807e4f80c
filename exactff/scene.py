"""Planar polygons and scenes: validation, immutable storage, per-polygon planes."""

import numpy as np
import shapely

from . import _tolerances as tol
from .geometry import area_vector, polygon_diameter

__all__ = ["SceneError", "NumericalError", "Scene", "validate_polygon", "validate_polygons", "describe"]


class SceneError(ValueError):
    """A polygon of a scene is ill-formed; the message names the polygon and the reason.

    Attributes
    ----------
    index : int or None
        Index of the offending polygon in input order.
    reason : str
        What is wrong with it.
    """

    def __init__(self, index, reason, name=None):
        self.index = index
        self.reason = reason
        label = f"polygon {index}" if name is None else f"polygon {index} ({name!r})"
        super().__init__(f"{label}: {reason}")


class NumericalError(ArithmeticError):
    """A computed value broke an invariant beyond its rounding-error estimate (a form
    factor below 0), or higher precision did not converge: a bug or an input outside
    what exactff can evaluate, never silently clamped. The message says which."""


def _distinct_consecutive(P):
    """Vertices with consecutive repeats (cyclically) removed."""
    keep = np.any(P != np.roll(P, -1, axis=0), axis=1)
    return P[keep] if keep.any() else P[:1]


def validate_polygon(polygon, index=0, name=None, *, planarity_rtol=tol.PLANARITY_RTOL):
    """Check one polygon and return it as a read-only float array.

    Parameters
    ----------
    polygon : array_like of shape (K, 3)
        Vertices, counter-clockwise seen from the front. Non-convex simple polygons are
        valid.
    index : int
        Index reported in the error.
    name : str, optional
        Name reported in the error.
    planarity_rtol : float, optional
        Allowed distance of a vertex from the Newell plane, relative to the diameter.

    Returns
    -------
    ndarray of shape (K, 3)
        The vertices as given (consecutive repeats kept), float64, read-only.

    Raises
    ------
    SceneError
        Fewer than 3 vertices; NaN or infinite coordinates; fewer than 3 distinct
        consecutive vertices; zero area (collinear); non-planar (best-fit plane) beyond
        ``PLANARITY_RTOL`` of the diameter plus ``PLANARITY_ULPS`` of the coordinates'
        magnitude; self-intersecting.

    Examples
    --------
    >>> validate_polygon([[0, 0, 0], [1, 0, 0], [2, 0, 0]], index=7)
    Traceback (most recent call last):
    ...
    exactff.scene.SceneError: polygon 7: zero area (the vertices are collinear)
    """
    try:
        P = np.array(polygon, dtype=float)
    except (TypeError, ValueError) as exc:
        raise SceneError(index, f"not an array of 3-D vertices ({exc})", name) from None
    if P.ndim != 2 or P.shape[1] != 3:
        raise SceneError(index, f"expected an array of shape (K, 3), got shape {P.shape}", name)
    if P.shape[0] < 3:
        raise SceneError(index, f"fewer than 3 vertices ({P.shape[0]})", name)
    if not np.all(np.isfinite(P)):
        raise SceneError(index, "NaN or infinite coordinates", name)
    D = _distinct_consecutive(P)
    if D.shape[0] < 3:
        raise SceneError(index, f"fewer than 3 distinct consecutive vertices ({D.shape[0]})", name)
    diam = polygon_diameter(D)
    # best-fit plane (SVD): robust for any vertex set, including bow ties of zero area
    c = D.mean(axis=0)
    _, sv, vt = np.linalg.svd(D - c, full_matrices=False)
    if not sv[1] > tol.DEGENERATE_AREA_RTOL * sv[0]:
        raise SceneError(index, "zero area (the vertices are collinear)", name)
    dev = float(np.abs((D - c) @ vt[2]).max())
    allowed = planarity_rtol * diam + tol.PLANARITY_ULPS * tol.EPS * float(np.abs(D).max())
    if dev > allowed:
        raise SceneError(
            index,
            f"not planar: a vertex lies {dev:.3g} from the best-fit plane, more than "
            f"{planarity_rtol:g} of the diameter {diam:.3g}",
            name,
        )
    # simplicity in the coordinate plane most parallel to the polygon (exact coordinates)
    ring = shapely.linearrings(np.delete(D, int(np.argmax(np.abs(vt[2]))), axis=1))
    if not shapely.is_simple(ring):
        raise SceneError(index, "self-intersecting", name)
    area = float(np.linalg.norm(area_vector(D)))
    if not area > tol.DEGENERATE_AREA_RTOL * diam * diam:
        raise SceneError(index, "zero area", name)
    P.setflags(write=False)
    return P


def validate_polygons(polygons, names=None, planarity_rtol=tol.PLANARITY_RTOL):
    """Validate many polygons at once (as :func:`validate_polygon`, vectorised).

    Polygons with the same number of vertices are checked together; any polygon that a
    batch check flags, or that has repeated consecutive vertices, goes through
    :func:`validate_polygon`, so errors and their messages are the same. The first
    ill-formed polygon in input order raises.

    Returns
    -------
    tuple of ndarray of shape (K_i, 3)
        Read-only float arrays.
    """
    n = len(polygons)
    names = names if names is not None else (None,) * n
    arrays = [None] * n
    slow = []
    by_k = {}
    for i, p in enumerate(polygons):
        try:
            a = np.array(p, dtype=float)
        except (TypeError, ValueError):
            slow.append(i)
            continue
        if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] < 3:
            slow.append(i)
            continue
        arrays[i] = a
        by_k.setdefault(a.shape[0], []).append(i)
    for k, idx in by_k.items():
        if k > tol.BATCH_VALIDATION_MAX_VERTICES:
            slow.extend(idx)   # long polygons one by one (the batch check is O(k^2))
            continue
        P = np.stack([arrays[i] for i in idx])
        ok = np.all(np.isfinite(P), axis=(1, 2))
        ok &= np.all(np.any(P != np.roll(P, -1, axis=1), axis=2), axis=1)
        Pc = np.where(ok[:, None, None], P, 0.0)
        diff = Pc[:, :, None, :] - Pc[:, None, :, :]
        diam = np.sqrt((diff * diff).sum(-1)).max(axis=(1, 2))
        c = Pc.mean(axis=1, keepdims=True)
        _, sv, vt = np.linalg.svd(Pc - c, full_matrices=False)
        ok &= sv[:, 1] > tol.DEGENERATE_AREA_RTOL * sv[:, 0]
        normal = vt[:, 2]
        dev = np.abs(np.einsum("mkj,mj->mk", Pc - c, normal)).max(axis=1)
        allowed = planarity_rtol * diam + tol.PLANARITY_ULPS * tol.EPS * np.abs(Pc).max(axis=(1, 2))
        ok &= dev <= allowed
        Q = Pc - Pc[:, :1]
        A = 0.5 * np.cross(Q, np.roll(Q, -1, axis=1)).sum(axis=1)
        ok &= np.linalg.norm(A, axis=1) > tol.DEGENERATE_AREA_RTOL * diam * diam
        if k > 3:
            # simplicity in the coordinate plane most parallel to each polygon
            drop = np.argmax(np.abs(normal), axis=1)
            keep_axes = np.array([[1, 2], [0, 2], [0, 1]])[drop]
            flat = np.take_along_axis(Pc, keep_axes[:, None, :].repeat(k, axis=1), axis=2)
            rings = shapely.linearrings(flat.reshape(-1, 2), indices=np.repeat(np.arange(len(idx)), k))
            ok &= shapely.is_simple(rings)
        for j, i in enumerate(idx):
            if not ok[j]:
                slow.append(i)
    for i in sorted(slow):
        arrays[i] = validate_polygon(polygons[i], i, names[i], planarity_rtol=planarity_rtol)
    for a in arrays:
        a.setflags(write=False)
    return tuple(arrays)


def _readonly(a):
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


class Scene:
    """An immutable list of planar polygons with their planes.

    Build one with :meth:`Scene.from_polygons`, :func:`exactff.load_scene` or a
    function of :mod:`exactff.scenes`.

    Attributes
    ----------
    polygons : tuple of ndarray of shape (K_i, 3)
        Read-only vertex arrays in input order.
    normals : ndarray of shape (N, 3)
        Unit front normals (right-hand rule, Newell).
    areas : ndarray of shape (N,)
    centroids : ndarray of shape (N, 3)
        Area centroids (the receiving points of ``form_factor_matrix``).
    offsets : ndarray of shape (N + 1,)
        Polygon ``i`` owns rows ``offsets[i]:offsets[i + 1]`` of ``vertices``.
    vertices : ndarray of shape (V, 3)
        All vertices, concatenated.
    names, groups, materials : tuple of str or None

    Notes
    -----
    Conventions: see ``docs/explanation/conventions.md``. A polygon's vertices run
    counter-clockwise seen from its front.
    """

    __slots__ = ("polygons", "normals", "areas", "centroids", "offsets", "vertices",
                 "names", "groups", "materials", "_cache")

    def __init__(self, polygons, names=None, groups=None, materials=None,
                 planarity_rtol=tol.PLANARITY_RTOL):
        n = len(polygons)
        labels = {}
        for key, val in (("names", names), ("groups", groups), ("materials", materials)):
            labels[key] = tuple(val) if val is not None else (None,) * n
            if len(labels[key]) != n:
                raise ValueError(f"{key} must have one entry per polygon ({n}), "
                                 f"got {len(labels[key])}")
        if n == 0:
            raise ValueError("polygons: a scene needs at least one polygon")
        names = labels["names"]
        P = validate_polygons(polygons, names, planarity_rtol)
        counts = np.array([len(p) for p in P])
        offsets = np.concatenate([[0], np.cumsum(counts)])
        V = np.concatenate(P, axis=0)
        # Newell area vectors relative to each polygon's first vertex
        first = np.repeat(V[offsets[:-1]], counts, axis=0)
        Q = V - first
        nxt = np.arange(len(V)) + 1
        nxt[offsets[1:] - 1] = offsets[:-1]
        cross = np.cross(Q, Q[nxt])
        A = 0.5 * np.add.reduceat(cross, offsets[:-1], axis=0)
        areas = np.linalg.norm(A, axis=1)
        normals = A / areas[:, None]
        # area centroids: fan triangles (0, i, i+1), weights along the normal
        w = np.einsum("ij,ij->i", cross, np.repeat(normals, counts, axis=0))
        cen = np.add.reduceat((Q + Q[nxt]) / 3.0 * w[:, None], offsets[:-1], axis=0)
        centroids = V[offsets[:-1]] + cen / np.add.reduceat(w, offsets[:-1])[:, None]
        set_ = object.__setattr__
        set_(self, "polygons", P)
        set_(self, "normals", _readonly(normals))
        set_(self, "areas", _readonly(areas))
        set_(self, "centroids", _readonly(centroids))
        set_(self, "offsets", _readonly(offsets))
        set_(self, "vertices", _readonly(V))
        set_(self, "names", names)
        set_(self, "groups", labels["groups"])
        set_(self, "materials", labels["materials"])
        set_(self, "_cache", {})

    def __setattr__(self, key, value):
        raise AttributeError("Scene is immutable")

    def __reduce__(self):
        # rebuild from validated arrays without validating again (for process pools)
        state = {k: getattr(self, k) for k in self.__slots__ if k != "_cache"}
        return (_restore_scene, (state,))

    @classmethod
    def from_polygons(cls, polygons, *, names=None, groups=None, materials=None,
                      planarity_rtol=tol.PLANARITY_RTOL):
        """Validate polygons and build a scene.

        Parameters
        ----------
        polygons : sequence of array_like of shape (K_i, 3)
            Planar simple polygons, counter-clockwise seen from the front.
        names, groups, materials : sequence of str, optional
            One per polygon.
        planarity_rtol : float, optional
            Allowed distance of a vertex from its polygon's Newell plane, relative to
            the polygon's diameter (default ``exactff._tolerances.PLANARITY_RTOL``).

        Raises
        ------
        SceneError
            A polygon is ill-formed; the message names its index and the reason.

        Examples
        --------
        >>> s = Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]])
        >>> len(s), float(s.areas[0])
        (1, 1.0)
        """
        return cls(list(polygons), names=names, groups=groups, materials=materials,
                   planarity_rtol=planarity_rtol)

    def __len__(self):
        return len(self.polygons)

    def __repr__(self):
        return f"<Scene: {len(self)} polygons, {len(self.vertices)} vertices>"

    @classmethod
    def from_pyvista(cls, mesh, **options):
        """A scene from a pyvista ``PolyData`` (or anything with ``points`` and a flat
        ``faces`` array ``[k, i_1, ..., i_k, k, ...]``): every face one polygon, in
        order. pyvista itself is not needed here.

        Parameters
        ----------
        mesh : pyvista.PolyData
        **options
            Passed to :func:`exactff.io.build_scene` (``nonplanar``, ``planarity_rtol``).

        Examples
        --------
        >>> from types import SimpleNamespace
        >>> quad = SimpleNamespace(points=[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        ...                        faces=[4, 0, 1, 2, 3])
        >>> len(Scene.from_pyvista(quad))
        1
        """
        from .io import build_scene

        points = np.asarray(mesh.points, dtype=float)
        flat = np.asarray(mesh.faces, dtype=int).ravel()
        faces, i = [], 0
        while i < len(flat):
            k = int(flat[i])
            if k < 1 or i + 1 + k > len(flat):
                raise ValueError(f"mesh.faces: bad face size {k} at position {i}")
            faces.append(points[flat[i + 1:i + 1 + k]])
            i += 1 + k
        if not faces:
            raise ValueError("mesh: no faces")
        return build_scene(faces, sources=[f"mesh face {j}" for j in range(len(faces))],
                           **options)

    def to_pyvista(self):
        """The scene as a pyvista ``PolyData`` (one face per polygon, in order), so that
        a row or a matrix can be painted on it (``mesh.cell_data["F"] = row``). Needs
        pyvista (``pip install pyvista``)."""
        try:
            import pyvista
        except ImportError:
            raise ImportError("Scene.to_pyvista needs pyvista (pip install pyvista)") from None
        counts = np.diff(self.offsets)
        faces = np.insert(np.arange(len(self.vertices)), self.offsets[:-1], counts)
        return pyvista.PolyData(np.array(self.vertices), faces)

    @property
    def bounds(self):
        """``(min_xyz, max_xyz)`` of all vertices."""
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    @property
    def plane_offsets(self):
        """``normals[i] @ centroids[i]``: the plane of polygon i is ``n @ x = d``."""
        return np.einsum("ij,ij->i", self.normals, self.centroids)


def _restore_scene(state):
    scene = object.__new__(Scene)
    for key, value in state.items():
        if isinstance(value, np.ndarray):
            value = _readonly(value)
        object.__setattr__(scene, key, value)
    object.__setattr__(scene, "_cache", {})
    return scene


def describe(scene):
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
        both as lists of ``[i, j]`` (see
        :func:`exactff.visibility.coplanar_overlaps`), and ``split_faces`` (faces of
        the file that were not planar and were cut into triangles when it was read
        with ``nonplanar="split"``; 0 otherwise).

    Examples
    --------
    >>> from exactff.scenes import subdivided_box
    >>> d = describe(subdivided_box(2))
    >>> d["polygons"], d["unpaired_edges"], d["closure_residual"] < 1e-15
    (24, 0, True)
    >>> d["back_to_back_pairs"], d["same_facing_overlaps"]
    ([], [])
    """
    from .visibility import coplanar_overlaps

    back_to_back, same_facing = coplanar_overlaps(scene)
    devs = []
    edges = {}
    for P in scene.polygons:
        D = _distinct_consecutive(P)
        diam = polygon_diameter(D)
        N = area_vector(D)
        N /= np.linalg.norm(N)
        devs.append(float(np.abs((D - D.mean(axis=0)) @ N).max()) / diam)
        for a, b in zip(map(tuple, D), map(tuple, np.roll(D, -1, axis=0))):
            edges[(a, b)] = edges.get((a, b), 0) + 1
    unpaired = sum(c for (a, b), c in edges.items() if edges.get((b, a), 0) != c)
    vector_area = (scene.normals * scene.areas[:, None]).sum(axis=0)
    lo, hi = scene.bounds
    return {
        "polygons": len(scene),
        "vertices": int(len(scene.vertices)),
        "total_area": float(scene.areas.sum()),
        "bounds_min": lo.tolist(),
        "bounds_max": hi.tolist(),
        "max_planarity_deviation": max(devs),
        "closure_residual": float(np.linalg.norm(vector_area) / scene.areas.sum()),
        "unpaired_edges": int(unpaired),
        "back_to_back_pairs": back_to_back.tolist(),
        "same_facing_overlaps": same_facing.tolist(),
        "split_faces": int(scene._cache.get("split_faces", 0)),
    }
