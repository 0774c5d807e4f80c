"""Planar polygons and scenes: validation, immutable storage, per-polygon planes."""

from __future__ import annotations

import json

import numpy as np
from numpy.typing import ArrayLike
import shapely

from . import _tolerances as tol
from .errors import SceneError
from .geometry import area_vector, polygon_diameter
from .predicates import collinear
from .rings import successors

__all__ = ["Scene", "distinct_consecutive", "validate_polygon", "validate_polygons", "as_scene", "build_scene",
           "split_nonplanar", "NONPLANAR", "DEGENERATE"]


def distinct_consecutive(P):
    """Vertices with exact consecutive repeats removed, cyclically (a closing vertex
    equal to the first included): the ring without its zero-length edges.

    Examples
    --------
    >>> distinct_consecutive(np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0]])).tolist()
    [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    """
    keep = np.any(P != np.roll(P, -1, axis=0), axis=1)
    return P[keep] if keep.any() else P[:1]


def validate_polygon(polygon: ArrayLike, index: int = 0, name: str | None = None, *,
                     planarity_rtol: float = tol.PLANARITY_RTOL) -> np.ndarray:
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
    ndarray of shape (K', 3)
        The vertices, float64, read-only, with exactly repeated consecutive vertices (and
        a closing vertex equal to the first) dropped: the same ring without its
        zero-length edges, so that every kernel sees it alike (a zero-length edge gave
        0/0 in the area form factors' contour integral).

    Raises
    ------
    SceneError
        Fewer than 3 vertices; NaN or infinite coordinates; fewer than 3 distinct
        consecutive vertices; zero area (collinear: exactly, decided first by
        :func:`exactff.predicates.collinear`, or up to rounding); non-planar (best-fit
        plane) beyond ``PLANARITY_RTOL`` of the diameter plus ``PLANARITY_ULPS`` of the
        coordinates' magnitude; self-intersecting.

    Examples
    --------
    >>> validate_polygon([[0, 0, 0], [1, 0, 0], [2, 0, 0]], index=7)
    Traceback (most recent call last):
    ...
    exactff.SceneError: polygon 7: zero area (the vertices are collinear)
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
    D = distinct_consecutive(P)
    if D.shape[0] < 3:
        raise SceneError(index, f"fewer than 3 distinct consecutive vertices ({D.shape[0]})", name)
    if collinear(D):    # exactly, however far from the origin (before the tests in floats)
        raise SceneError(index, "zero area (the vertices are collinear)", name)
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
    D.setflags(write=False)
    return D


def validate_polygons(polygons, names=None,
                      planarity_rtol: float = tol.PLANARITY_RTOL, *,
                      failures: list | None = None) -> tuple[np.ndarray, ...]:
    """Validate many polygons at once (as :func:`validate_polygon`, vectorised).

    Polygons with the same number of vertices are checked together; any polygon that a
    batch check flags, or that has repeated consecutive vertices, goes through
    :func:`validate_polygon`, so errors and their messages are the same (the batch
    check names fewer than 3 distinct consecutive vertices itself, in the same words).
    The first ill-formed polygon in input order raises, unless ``failures`` is given.

    Parameters
    ----------
    polygons : sequence of array_like of shape (K_i, 3)
    names : sequence of str or None, optional
    planarity_rtol : float, optional
    failures : list, optional
        Where to collect the :class:`SceneError` of every ill-formed polygon, in input
        order, instead of raising the first; their entries of the result are None.

    Returns
    -------
    tuple of ndarray of shape (K_i, 3)
        Read-only float arrays, in input order; a polygon with repeated consecutive
        vertices comes back without them (as from :func:`validate_polygon`).

    Examples
    --------
    >>> bad = []
    >>> out = validate_polygons([[[0, 0, 0], [1, 0, 0], [0, 1, 0]],
    ...                          [[0, 0, 0], [1, 0, 0], [2, 0, 0]]], failures=bad)
    >>> out[1] is None, [str(e) for e in bad]
    (True, ['polygon 1: zero area (the vertices are collinear)'])
    """
    n = len(polygons)
    names = names if names is not None else (None,) * n
    arrays = [None] * n
    slow = []
    decided = {}        # polygons the batch check can name the error of
    by_k, seen = {}, {}
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
        # polygons of k vertices in batches of at most BATCH_VALIDATION_PAIRS vertex
        # pairs (the batch check's temporaries are O(k^2) per polygon)
        k = a.shape[0]
        seen[k] = seen.get(k, 0) + 1
        by_k.setdefault((k, seen[k] // max(1, tol.BATCH_VALIDATION_PAIRS // (k * k))),
                        []).append(i)
    for (k, _), idx in by_k.items():
        if k > tol.BATCH_VALIDATION_MAX_VERTICES:
            slow.extend(idx)   # long polygons one by one (the batch check is O(k^2))
            continue
        P = np.stack([arrays[i] for i in idx])
        ok = np.all(np.isfinite(P), axis=(1, 2))
        distinct = np.any(P != np.roll(P, -1, axis=1), axis=2).sum(axis=1)
        for j in np.flatnonzero(ok & (distinct < 3)):     # as validate_polygon says it
            i = idx[j]
            decided[i] = SceneError(i, f"fewer than 3 distinct consecutive vertices "
                                       f"({max(int(distinct[j]), 1)})", names[i])
        ok &= distinct == k
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
            if not ok[j] and i not in decided:
                slow.append(i)
    for i in sorted(slow + list(decided)):
        exc = decided.get(i)
        if exc is None:
            try:
                arrays[i] = validate_polygon(polygons[i], i, names[i],
                                             planarity_rtol=planarity_rtol)
                continue
            except SceneError as e:
                if failures is None:
                    raise
                # kept without its traceback: that would keep this frame, and every
                # batch array in it, alive in a reference cycle until a full collection
                exc = e.with_traceback(None)
        elif failures is None:
            raise exc
        failures.append(exc)
        arrays[i] = None
    for a in arrays:
        if a is not None:
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
        Read-only vertex arrays in input order (one per input polygon, same index),
        each with exactly repeated consecutive vertices, and a closing vertex equal to
        the first, dropped (:func:`validate_polygon`).
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
    split_faces : int
        Faces of the source file that were not planar and were cut into triangles
        (``nonplanar="split"``); 0 otherwise. Kept when the scene is pickled.
    dropped_faces : int
        Degenerate faces of the source file left out (``degenerate="drop"``); 0
        otherwise. Kept when the scene is pickled.
    dropped_reasons : tuple of (str, int)
        How many of them were left out for each reason (``"fewer than 3 vertices"``,
        ``"fewer than 3 distinct vertices"``, ``"zero area"``); empty if none.
    metadata : dict
        What the source file says beyond the polygons (JSON data; a fresh copy at each
        access, so the scene stays immutable): ``metadata["view3d"]`` for a View3D
        file (:func:`exactff.read_vs3`: title, control values, surface kinds,
        subsurfaces and combined surfaces); empty otherwise. Kept when the scene is
        pickled; :meth:`with_metadata` gives a scene with other metadata.
    skipped_primitives : tuple of (str, int)
        Objects of the source file that are not polygons and were not read, counted by
        kind (a Radiance ``sphere``, an EnergyPlus ``FenestrationSurface:Detailed``),
        in the order first met; empty if none. Kept when the scene is pickled.

    Notes
    -----
    Conventions: see ``docs/explanation/conventions.md``. A polygon's vertices run
    counter-clockwise seen from its front.
    """

    __slots__ = ("polygons", "normals", "areas", "centroids", "offsets", "vertices",
                 "names", "groups", "materials", "split_faces", "dropped_faces",
                 "dropped_reasons", "_metadata", "skipped_primitives", "__weakref__")

    def __init__(self, polygons, names=None, groups=None, materials=None,
                 planarity_rtol=tol.PLANARITY_RTOL, split_faces=0, dropped=(), metadata=None,
                 skipped=(),
                 _validated=False):
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
        # build_scene gives the arrays validate_polygons returned
        P = tuple(polygons) if _validated else validate_polygons(polygons, names, planarity_rtol)
        counts = np.array([len(p) for p in P])
        offsets = np.concatenate([[0], np.cumsum(counts)])
        V = np.concatenate(P, axis=0)
        # Newell area vectors relative to each polygon's first vertex
        first = np.repeat(V[offsets[:-1]], counts, axis=0)
        Q = V - first
        nxt = successors(offsets)
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
        set_(self, "split_faces", int(split_faces))
        set_(self, "dropped_reasons", tuple((str(r), int(c)) for r, c in dropped))
        set_(self, "dropped_faces", sum(c for _, c in self.dropped_reasons))
        set_(self, "_metadata", _metadata_text(metadata))
        set_(self, "skipped_primitives", tuple((str(k), int(c)) for k, c in skipped))

    def __setattr__(self, key, value):
        raise AttributeError("Scene is immutable")

    def __reduce__(self):
        # rebuild from validated arrays without validating again (for process pools)
        state = {k: getattr(self, k) for k in self.__slots__ if k != "__weakref__"}
        return (_restore_scene, (state,))

    @classmethod
    def from_polygons(cls, polygons, *, names=None, groups=None, materials=None,
                      planarity_rtol: float = tol.PLANARITY_RTOL) -> "Scene":
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

        Notes
        -----
        Exactly repeated consecutive vertices (and a closing vertex equal to the first)
        are dropped: ``scene.polygons[i]`` is polygon ``i`` without its zero-length
        edges, the ring every kernel integrates.

        Examples
        --------
        >>> s = Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]])
        >>> len(s), float(s.areas[0])
        (1, 1.0)
        >>> len(Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0]]]).polygons[0])
        3
        """
        return cls(list(polygons), names=names, groups=groups, materials=materials,
                   planarity_rtol=planarity_rtol)

    @property
    def metadata(self):
        """What the source file says beyond the polygons (a copy: see the class)."""
        return json.loads(self._metadata) if self._metadata else {}

    def with_metadata(self, metadata) -> "Scene":
        """The same polygons (shared, not validated again) with other ``metadata``.

        Parameters
        ----------
        metadata : dict or None
            JSON data (str keys; lists, numbers, str, bool, None); None for none.

        Examples
        --------
        >>> s = Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])
        >>> t = s.with_metadata({"note": [1, 2]})
        >>> t.metadata, s.metadata, t.polygons[0] is s.polygons[0]
        ({'note': [1, 2]}, {}, True)
        """
        state = {k: getattr(self, k) for k in self.__slots__ if k != "__weakref__"}
        state["_metadata"] = _metadata_text(metadata)
        return _restore_scene(state)

    def subset(self, indices) -> "Scene":
        """The scene of some of these polygons, in the order given (shared, not
        validated again: a scene built with a looser ``planarity_rtol`` stays valid),
        with their names, groups and materials; no metadata.

        Parameters
        ----------
        indices : array_like of int

        Examples
        --------
        >>> s = Scene.from_polygons([[[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        ...                          [[0, 0, 1], [1, 0, 1], [0, 1, 1]]], names=["a", "b"])
        >>> t = s.subset([1])
        >>> len(t), t.names, t.polygons[0] is s.polygons[1]
        (1, ('b',), True)
        """
        ids = [int(i) for i in np.asarray(indices, dtype=np.int64).ravel()]
        return Scene(tuple(self.polygons[i] for i in ids),
                     names=[self.names[i] for i in ids], groups=[self.groups[i] for i in ids],
                     materials=[self.materials[i] for i in ids], _validated=True)

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
            Passed to :func:`build_scene` (``nonplanar``, ``planarity_rtol``).

        Examples
        --------
        >>> from types import SimpleNamespace
        >>> quad = SimpleNamespace(points=[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        ...                        faces=[4, 0, 1, 2, 3])
        >>> len(Scene.from_pyvista(quad))
        1
        """
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


def _metadata_text(metadata):
    """``metadata`` as canonical JSON text (None for none): checked to be JSON data."""
    if metadata is None or metadata == {}:
        return None
    if not isinstance(metadata, dict):
        raise TypeError(f"metadata must be a dict or None, got {type(metadata).__name__}")
    try:
        return json.dumps(metadata, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"metadata must be JSON data: {exc}") from None


def _restore_scene(state):
    scene = object.__new__(Scene)
    for key, value in state.items():
        if isinstance(value, np.ndarray):
            value = _readonly(value)
        object.__setattr__(scene, key, value)
    return scene


def as_scene(scene):
    """``scene`` if it is an :class:`exactff.Scene`, else a TypeError saying what to do.

    Examples
    --------
    >>> as_scene([[0, 0, 0]])
    Traceback (most recent call last):
    ...
    TypeError: scene must be an exactff.Scene (build one with Scene.from_polygons or load_scene), got list
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be an exactff.Scene (build one with "
                        f"Scene.from_polygons or load_scene), got {type(scene).__name__}")
    return scene


# ---------------------------------------------------------------------------------------
# scenes from the faces of a file: non-planar faces split, errors that name the face
# ---------------------------------------------------------------------------------------
#: what to do with a face that is not planar within the tolerance
NONPLANAR = ("error", "split")

def _fan_score(P, apex):
    """Triangles of the fan of polygon P from vertex ``apex``, and how flat it is: the
    least cosine between a triangle's normal and the polygon's mean normal (-inf when a
    triangle is degenerate or turned over)."""
    k = len(P)
    order = [(apex + j) % k for j in range(k)]
    tris = [P[[order[0], order[j], order[j + 1]]] for j in range(1, k - 1)]
    N = np.array([np.cross(t[1] - t[0], t[2] - t[0]) for t in tris])
    L = np.linalg.norm(N, axis=1)
    mean = N.sum(axis=0)
    if np.any(L <= tol.DEGENERATE_AREA_RTOL * np.max(L)) or not np.linalg.norm(mean) > 0:
        return tris, -np.inf
    cos = (N @ mean) / (L * np.linalg.norm(mean))
    return tris, float(cos.min())


def split_nonplanar(polygon):
    """Planar triangles covering a polygon that is not planar: the fan from the vertex
    that gives the flattest pieces (the triangles' normals closest to the polygon's
    mean normal), orientation kept.

    Parameters
    ----------
    polygon : array_like of shape (K, 3)

    Returns
    -------
    list of ndarray of shape (3, 3)

    Examples
    --------
    A quad with one corner lifted splits along the diagonal that leaves the flattest
    halves:

    >>> q = [[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0]]
    >>> [t.tolist() for t in split_nonplanar(q)]
    [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.1]], [[0.0, 0.0, 0.0], [1.0, 1.0, 0.1], [0.0, 1.0, 0.0]]]
    """
    P = np.asarray(polygon, dtype=float)
    best, best_score = None, -np.inf
    for apex in range(len(P)):
        tris, score = _fan_score(P, apex)
        if score > best_score + tol.SPLIT_FLATNESS_TIE:
            best, best_score = tris, score
    if best is None:
        raise ValueError("no fan of the polygon gives valid triangles")
    return best


#: what to do with a degenerate face (fewer than 3 distinct vertices, or zero area: its
#: vertices collinear): raise, naming and counting them, or leave it out
DEGENERATE = ("raise", "drop")

#: the reasons of validate_polygon that make a face degenerate, by their start
_DEGENERATE_REASONS = (("fewer than 3 vertices", "fewer than 3 vertices"),
                       ("fewer than 3 distinct", "fewer than 3 distinct vertices"),
                       ("zero area", "zero area"))
_DROP_HINT = ("to load the file without such faces, leave them out (--drop-degenerate, "
              "or degenerate='drop')")
_SPLIT_HINT = ("to load it anyway, split such faces into planar triangles "
               "(--split-nonplanar, or nonplanar='split') or allow more "
               "(--planarity-rtol, or planarity_rtol=)")
#: how many ill-formed faces an error lists
_LISTED = 5


def _degenerate_kind(reason):
    """The degenerate reason a face's error falls under, or None (not degenerate: NaN or
    infinite coordinates, not planar, self-intersecting, not an array)."""
    for start, kind in _DEGENERATE_REASONS:
        if reason.startswith(start):
            return kind
    return None


def _hint(reason):
    if reason.startswith("not planar"):
        return "; " + _SPLIT_HINT
    if _degenerate_kind(reason):
        return "; " + _DROP_HINT
    return "; fix the face in the file"


def _kind(reason):
    """What an error's summary calls a face with this reason."""
    if _degenerate_kind(reason):
        return "degenerate"
    for start in ("not planar", "self-intersecting", "NaN or infinite coordinates"):
        if reason.startswith(start):
            return start
    return "ill-formed"


def _file_error(errors, names, groups, sources):
    """One SceneError for the ill-formed faces of a file: the face, where it is, its
    reason and how to proceed; for several, how many of each kind and the first few."""
    def describe(exc):
        i = exc.index
        label = (f" ({names[i]!r})" if names[i] else
                 f" (group {groups[i]!r})" if groups[i] else "")
        where = f"{sources[i]}: " if sources[i] else ""
        return f"{where}polygon {i}{label}: {exc.reason}"

    first = errors[0]
    out = SceneError(first.index, first.reason)
    if len(errors) == 1:
        out.args = (describe(first) + _hint(first.reason),)
        return out
    kinds = {}
    for exc in errors:
        kinds[_kind(exc.reason)] = kinds.get(_kind(exc.reason), 0) + 1
    if list(kinds) == ["degenerate"]:
        reasons = {}
        for exc in errors:
            kind = _degenerate_kind(exc.reason)
            reasons[kind] = reasons.get(kind, 0) + 1
        head = (f"{len(errors):,} faces are degenerate ("
                + ", ".join(f"{c:,} {r}" for r, c in reasons.items()) + ")")
    else:
        head = (f"{len(errors):,} faces are ill-formed ("
                + ", ".join(f"{c:,} {k}" for k, c in kinds.items()) + ")")
    hints = ([_DROP_HINT] if "degenerate" in kinds else []) + (
        [_SPLIT_HINT.replace("load it", "load them")] if "not planar" in kinds else []) + (
        ["fix the others in the file"] if set(kinds) - {"degenerate", "not planar"} else [])
    listed = "; ".join(describe(exc) for exc in errors[:_LISTED])
    out.args = (f"{head}; the first {min(len(errors), _LISTED)}: {listed}; "
                + "; ".join(hints),)
    return out


def build_scene(faces, *, names=None, groups=None, materials=None, sources=None,
                nonplanar="error", degenerate="raise", planarity_rtol=tol.PLANARITY_RTOL,
                face_index=None, skipped=()):
    """A scene from faces read from a file, with errors that name the face.

    Every face is validated once, in bulk (:func:`validate_polygons`); only the faces
    that fail are looked at again, to split or drop them as asked.

    Parameters
    ----------
    faces : list of array_like of shape (K_i, 3)
    names, groups, materials : list of str or None, optional
    sources : sequence of str, optional
        Where each face comes from (``"path:line"``), for the error messages (read by
        index, only for the faces an error names).
    nonplanar : {"error", "split"}, default "error"
        ``"split"`` cuts every face that is not planar within ``planarity_rtol`` into
        planar triangles (:func:`split_nonplanar`); the pieces keep the face's name,
        group and material. The scene records how many faces were split
        (``scene.split_faces``, ``describe(scene)["split_faces"]``).
    degenerate : {"raise", "drop"}, default "raise"
        ``"drop"`` leaves out every degenerate face: fewer than 3 vertices, fewer than
        3 distinct (consecutive) vertices, or zero area (the vertices collinear,
        exactly or up to rounding; :func:`validate_polygon`). The polygons that remain
        keep the file's order (polygon ``i`` of the scene is the ``i``-th face that was
        kept), with their names, groups and materials; the scene records how many were
        left out and why (``scene.dropped_faces``, ``scene.dropped_reasons``,
        ``describe(scene)["dropped_faces"]``). Faces with NaN or infinite coordinates,
        non-planar (unless split) or self-intersecting faces are broken input, not
        degenerate: they raise either way.
    planarity_rtol : float
    face_index : list, optional
        Receives, for each polygon of the scene in order, the index of the face it comes
        from (a split face gives several polygons, a dropped face none): what a reader
        needs to carry its own per-face data over to the polygons.
    skipped : sequence of (str, int), optional
        The file's objects that are not polygons and were not read, counted by kind
        (``scene.skipped_primitives``, ``describe(scene)["skipped_primitives"]``).

    Raises
    ------
    SceneError
        Faces are ill-formed: the message gives how many (of each kind), and for the
        first few where they come from, their index, name or group and reason, then how
        to proceed (``--drop-degenerate`` / ``degenerate="drop"`` for degenerate faces).
    ValueError
        ``nonplanar`` or ``degenerate`` is not one of its values, or every face was
        dropped.

    Examples
    --------
    >>> tri, line = [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 0], [1, 0, 0], [2, 0, 0]]
    >>> build_scene([tri, line, line], sources=["a.obj:5", "a.obj:6", "a.obj:7"])
    Traceback (most recent call last):
    ...
    exactff.SceneError: 2 faces are degenerate (2 zero area); the first 2: a.obj:6: polygon 1: zero area (the vertices are collinear); a.obj:7: polygon 2: zero area (the vertices are collinear); to load the file without such faces, leave them out (--drop-degenerate, or degenerate='drop')
    >>> s = build_scene([tri, line, tri], degenerate="drop")
    >>> len(s), s.dropped_faces, s.dropped_reasons
    (2, 1, (('zero area', 1),))
    """
    if nonplanar not in NONPLANAR:
        raise ValueError(f"nonplanar must be one of {NONPLANAR}, got {nonplanar!r}")
    if degenerate not in DEGENERATE:
        raise ValueError(f"degenerate must be one of {DEGENERATE}, got {degenerate!r}")
    n = len(faces)
    names = list(names) if names is not None else [None] * n
    groups = list(groups) if groups is not None else [None] * n
    materials = list(materials) if materials is not None else [None] * n
    sources = sources if sources is not None else [None] * n     # read by index only
    failures = []
    arrays = list(validate_polygons(faces, planarity_rtol=planarity_rtol, failures=failures))
    pieces, dropped, errors = {}, {}, {}
    for exc in failures:
        i, kind = exc.index, _degenerate_kind(exc.reason)
        if kind is not None and degenerate == "drop":
            dropped[kind] = dropped.get(kind, 0) + 1
        elif nonplanar == "split" and exc.reason.startswith("not planar"):
            try:
                pieces[i] = split_nonplanar(distinct_consecutive(np.asarray(faces[i], dtype=float)))
            except ValueError as why:
                errors[i] = SceneError(i, f"{exc.reason}; and it cannot be split into planar "
                                          f"triangles ({why})")
        else:
            errors[i] = exc
    if pieces:      # the triangles of the split faces, validated together
        owner = [i for i, tris in pieces.items() for _ in tris]
        bad = []
        flat = validate_polygons([T for tris in pieces.values() for T in tris],
                                 planarity_rtol=planarity_rtol, failures=bad)
        for exc in bad:
            i = owner[exc.index]
            errors.setdefault(i, SceneError(i, f"not planar; and a triangle of its split is "
                                               f"ill-formed ({exc.reason})"))
        at = 0
        for i, tris in pieces.items():
            pieces[i], at = flat[at:at + len(tris)], at + len(tris)
    if errors:
        raise _file_error([errors[i] for i in sorted(errors)], names, groups, sources)
    if len(pieces) == 0 and len(dropped) == 0:
        kept = (arrays, names, groups, materials)
        if face_index is not None:
            face_index.extend(range(n))
    else:
        kept = ([], [], [], [])
        for i, P in enumerate(arrays):
            for Q in ([P] if P is not None else pieces.get(i, [])):
                for lst, val in zip(kept, (Q, names[i], groups[i], materials[i])):
                    lst.append(val)
                if face_index is not None:
                    face_index.append(i)
    if not kept[0]:
        raise ValueError(f"faces: all {n:,} faces are degenerate and were left out "
                         f"(degenerate='drop'): no polygon remains")
    return Scene(kept[0], names=kept[1], groups=kept[2], materials=kept[3],
                 split_faces=len(pieces), dropped=tuple(dropped.items()), skipped=skipped,
                 _validated=True)
