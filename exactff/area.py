"""Area-to-area form factors (the paper's Eq. 1), unoccluded, by the contour integral.

For two planar polygons P and Q, Stokes' theorem turns the double area integral of
Eq. 1 into a double contour integral (Mitalas & Stephenson 1966; Sparrow 1963):

    A_P F(P -> Q) = (1 / 2 pi) sum_i sum_j (e_i . e_j) int_0^1 int_0^1 ln |p_i(s) - q_j(t)| dt ds

over the edges ``p_i(s) = a_i + s e_i`` of P and ``q_j(t) = b_j + t e_j`` of Q, each
counter-clockwise seen from its front. The inner integral is in closed form (``_segment_log_integral``); the outer one is a tanh-sinh
(double-exponential) quadrature, which keeps full accuracy when the integrand has
logarithmic singularities at the ends of an edge (polygons sharing an edge or a
vertex). ``ln r`` is measured against the distance between the centroids (the shift
contributes ``(sum e_i) . (sum e_j) = 0``), which keeps the terms small when the
polygons are far apart.

The contour terms cancel as (distance / size)^2 when the polygons are far apart: beyond
``FAR`` diameters the double integral is taken instead as the area integral over P of
the exact point form factors (smooth there), by a Gauss-Legendre rule on P's triangles.

One-sided, as the point form factors: only the part of Q in front of P's plane and
the part of P in front of Q's plane take part.
"""

import numpy as np
import shapely
from scipy.special import roots_legendre, xlogy

from .geometry import area_vector, polygon_diameter, receiver_frame
from .scene import validate_polygon
from .visibility.clipper import clip_halfspace

__all__ = ["polygon_form_factor"]


def _tanh_sinh(level=6, t_max=3.6):
    """Tanh-sinh nodes on [0, 1] as (distance to the nearer end, which end, weight):
    the distance to the end is computed without cancellation."""
    h = 2.0 ** -level
    t = np.arange(-int(t_max / h), int(t_max / h) + 1) * h
    u = 0.5 * np.pi * np.sinh(np.abs(t))
    e = np.exp(-2.0 * u)
    d = e / (1.0 + e)                       # (1 - |tanh u|) / 2: distance to the end
    w = h * 0.5 * np.pi * np.cosh(t) * 4.0 * e / (1.0 + e) ** 2 / 2.0
    keep = d > 0
    return d[keep], (t >= 0)[keep], w[keep]


_NODES = _tanh_sinh()


def _segment_log_integral(W, E):
    """``int_0^1 ln |W + t E| dt`` for arrays of vectors W (..., 3) and E (..., 3), in
    closed form: with ``a = |E|^2``, ``u = t + (W . E) / a`` and ``k = |W x E| / a``,
    ``ln |W + t E| = (ln a + ln(u^2 + k^2)) / 2`` and
    ``int ln(u^2 + k^2) du = u ln(u^2 + k^2) - 2 u + 2 k atan(u / k)``."""
    a = np.einsum("...i,...i->...", E, E)
    b = np.einsum("...i,...i->...", W, E) / a
    k = np.linalg.norm(np.cross(W, E), axis=-1) / a
    u0, u1 = b, b + 1.0

    def prim(u):
        with np.errstate(divide="ignore", invalid="ignore"):
            at = np.where(k > 0, k * np.arctan2(u, k), 0.0)
        return xlogy(u, u * u + k * k) - 2.0 * u + 2.0 * at

    return 0.5 * np.log(a) + 0.5 * (prim(u1) - prim(u0))


def _clip_front(P, n, c):
    """The part of polygon P with ``n . (x - c) > 0`` (None when nothing is left): the
    engine's half-space clipping, about the point c."""
    V, k = clip_halfspace((P - c)[None], np.array([len(P)]), n)
    return V[0, :k[0]] + c if k[0] >= 3 else None


#: beyond this distance between centroids (in diameters of the larger polygon) the area
#: integral of exact point values replaces the contour integral, whose terms cancel as
#: (distance / size)^2 (measured: 4e-12 relative for squares 100 diameters apart)
FAR = 3.0

_GL = roots_legendre(12)


def _triangles(P, n):
    """Triangles covering a planar polygon (constrained Delaunay in its plane)."""
    R = receiver_frame(n)
    uv = (P - P[0]) @ R[:2].T
    tris = shapely.get_parts(shapely.constrained_delaunay_triangles(shapely.Polygon(uv)))
    out = []
    for t in tris:
        c = np.asarray(t.exterior.coords)[:3]
        out.append(P[0] + c @ R[:2])
    return out


def _area_integral(Pc, nP, Qc):
    """``int_P F(x -> Q) dA`` by a collapsed Gauss-Legendre rule (12 x 12) on each
    triangle of P, with the exact point form factors evaluated together in offset form
    (one frame: P's normal)."""
    from .integrate import _clipped_sector_sums

    x, w = _GL
    x, w = 0.5 * (x + 1.0), 0.5 * w
    U, V = np.meshgrid(x, x, indexing="ij")
    WW = np.outer(w, w) * U                  # the collapse's Jacobian u
    pts, wts = [], []
    for a, b, c in _triangles(Pc, nP):
        J = np.linalg.norm(np.cross(b - a, c - a))
        X = a + U[..., None] * (b - a) + (U * V)[..., None] * (c - b)
        pts.append(X.reshape(-1, 3))
        wts.append((WW * J).ravel())
    X, Wt = np.concatenate(pts), np.concatenate(wts)
    R = receiver_frame(nP)
    E = (Qc - Qc[0]) @ R.T                    # offsets, the same for every point
    A0 = (Qc[0] - X) @ R.T                    # each point's reference vertex
    k = len(Qc)
    owner = np.repeat(np.arange(len(X)), k)
    nxt = np.arange(len(owner)) + 1
    nxt[k - 1::k] -= k
    S, _, _ = _clipped_sector_sums(A0, np.tile(E, (len(X), 1)), nxt, owner, len(X))
    return float(np.abs(S) @ Wt) / (2.0 * np.pi)


def polygon_form_factor(P, Q):
    """The area-to-area form factor F(P -> Q), unoccluded, exact to rounding.

    The paper's Eq. 1: ``(1 / A_P) int_P int_Q cos(theta_P) cos(theta_Q) / (pi r^2)
    dA_Q dA_P``, one-sided (only the parts of each polygon in front of the other's
    plane), by the contour integral of Mitalas and Stephenson with the inner integral
    in closed form and a tanh-sinh outer quadrature (see the module's notes).

    Parameters
    ----------
    P, Q : array_like of shape (K, 3)
        Planar polygons, counter-clockwise seen from their fronts.

    Returns
    -------
    float

    Raises
    ------
    SceneError
        A polygon is ill-formed (as for scenes; P is polygon 0, Q polygon 1).

    Examples
    --------
    Two parallel unit squares one apart, facing each other (Howell's catalogue,
    C-11: 0.19982489570):

    >>> P = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    >>> Q = [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]
    >>> round(polygon_form_factor(P, Q), 12)
    0.199824895698
    """
    P = np.array(validate_polygon(P, 0), dtype=float)
    Q = np.array(validate_polygon(Q, 1), dtype=float)
    AP, AQ = area_vector(P), area_vector(Q)
    area_P = float(np.linalg.norm(AP))
    nP, nQ = AP / area_P, AQ / np.linalg.norm(AQ)
    cP, cQ = P.mean(axis=0), Q.mean(axis=0)
    # one-sided: each polygon's part in front of the other's plane
    Pc = _clip_front(P, nQ, Q[0])
    Qc = _clip_front(Q, nP, P[0])
    if Pc is None or Qc is None:
        return 0.0
    r0 = float(np.linalg.norm(cQ - cP)) or 1.0
    if r0 > FAR * max(polygon_diameter(P), polygon_diameter(Q)):
        return max(_area_integral(Pc, nP, Qc) / area_P, 0.0)
    eP = np.roll(Pc, -1, axis=0) - Pc          # (KP, 3)
    eQ = np.roll(Qc, -1, axis=0) - Qc          # (KQ, 3)
    d, upper, w = _NODES
    # outer nodes along every edge of P, from the nearer end (no cancellation there)
    start = np.where(upper[None, :, None], (Pc + eP)[:, None, :], Pc[:, None, :])
    step = np.where(upper[None, :, None], -eP[:, None, :], eP[:, None, :])
    X = start + d[None, :, None] * step                              # (KP, N, 3)
    Wv = Qc[None, None, :, :] - X[:, :, None, :]                     # (KP, N, KQ, 3)
    G = _segment_log_integral(Wv, np.broadcast_to(eQ, Wv.shape)) - np.log(r0)
    inner = np.einsum("n,pnq->pq", w, G)                             # (KP, KQ)
    total = np.einsum("pq,pq->", eP @ eQ.T, inner) / (2.0 * np.pi)
    return max(float(total) / area_P, 0.0)
