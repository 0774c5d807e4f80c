"""BSP set-up for tessellated curved objects: array-based node work, shallow trees from
axis planes where the facets' own planes would make a chain, and the same exact rows."""

import numpy as np
import pytest

import exactff as ef
from exactff import _tolerances as tol
from exactff.testing import assert_form_factors_close
from exactff.visibility import build_bsp


def test_convex_tessellation_gives_a_shallow_tree():
    scene = ef.scenes.room_with_sphere(3, 4)     # 1,280 triangles, 96 quads
    tree = build_bsp(scene)
    # the facets' own planes alone make a chain about as deep as the sphere has facets;
    # nodes of up to BSP_AXIS_CANDIDATE_MIN fragments may still chain
    assert tree.depth() < tol.BSP_AXIS_CANDIDATE_MIN + 100 < 1280
    assert sorted(set(tree.source.tolist())) == list(range(len(scene)))


def test_rows_do_not_depend_on_the_tree(monkeypatch):
    scene = ef.scenes.room_with_sphere(2, 3)     # 320 triangles
    rows = [0, 7, 20, 33, 50]
    monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 32)
    shallow = ef.form_factor_matrix(scene, rows=rows)
    d_shallow = build_bsp(scene).depth()
    monkeypatch.setattr(tol, "BSP_AXIS_CANDIDATE_MIN", 10**9)
    chain_scene = ef.Scene.from_polygons(scene.polygons)
    chain = ef.form_factor_matrix(chain_scene, rows=rows)
    assert build_bsp(chain_scene).depth() > 300 > 100 > d_shallow
    assert_form_factors_close(shallow, chain, rtol=0, atol=1e-13)


@pytest.mark.parametrize("level", [1, 3])
def test_room_with_sphere_rows_sum_to_one(level):
    scene = ef.scenes.room_with_sphere(level, 4)
    groups = np.array(scene.groups)
    rows = np.flatnonzero(groups == "room")[::7].tolist() + np.flatnonzero(groups == "sphere")[::37].tolist()
    M = ef.form_factor_matrix(scene, rows=rows)
    assert_form_factors_close(M.sum(axis=1), np.ones(len(rows)), rtol=0, atol=1e-11)
    # the sphere hides part of the room from the room's points
    i = rows[0]
    U = ef.point_polygon_form_factors(scene.centroids[i], scene.normals[i], scene)
    assert np.any(M[0] < U - 1e-4)


def test_split_fragments_keep_their_area():
    scene = ef.scenes.room_with_sphere(3, 2)
    tree = build_bsp(scene)
    assert tree.splits > 0
    area = np.zeros(len(scene))
    np.add.at(area, tree.source, [np.linalg.norm(ef.geometry.area_vector(P)) for P in tree.fragments])
    assert_form_factors_close(area, scene.areas, rtol=1e-12, atol=0)


def brute_force_nearest(P, p, D):
    """Nearest convex polygon along each direction (rows of D) from p, by testing every
    polygon (independent of the engine): plane hit, then inside all edges."""
    V = np.array([np.pad(Q, ((0, 4 - len(Q)), (0, 0)), mode="edge") for Q in P])  # (N, 4, 3)
    from exactff import _tolerances as tol

    n = np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    num = np.einsum("ij,ij->i", n, V[:, 0] - p)
    # decided explicitly, not by the sign of a rounded dot product: p in a polygon's
    # plane to rounding (its own, a coplanar neighbour's) sees it edge-on, and a ray
    # parallel to a plane to rounding misses it, in any CPU's rounding
    ulps = tol.PLANE_SIDE_ULPS * tol.EPS
    edge_on = np.abs(num) <= ulps * (np.abs(p).max() + np.abs(V).max(axis=(1, 2)))
    out = np.full(len(D), -1)
    for s in range(0, len(D), 500):
        d = D[s:s + 500]
        den = d @ n.T                                     # (k, N)
        ok = (np.abs(den) > ulps) & ~edge_on[None, :]
        t = np.divide(num[None, :], den, out=np.full(den.shape, np.inf), where=ok)
        X = p + np.where(ok, t, 0.0)[:, :, None] * d[:, None, :]   # (k, N, 3)
        inside = ok & (t > 1e-12)
        for e in range(4):
            a, b = V[:, e], V[:, (e + 1) % 4]
            c = np.cross(b - a, X - a)
            inside &= (np.einsum("knj,nj->kn", c, n) >= -1e-15) | np.all(a == b, axis=1)
        t = np.where(inside, t, np.inf)
        hit = np.argmin(t, axis=1)
        out[s:s + 500] = np.where(np.isfinite(t[np.arange(len(d)), hit]), hit, -1)
    return out


def test_room_with_sphere_against_a_brute_force_ray_cast():
    # cosine-weighted directions from a floor point: the fraction of rays whose nearest
    # polygon is j estimates F(p -> j) (front faces only); every estimate within 5
    # standard errors of the exact value, and the exact row sums to 1
    scene = ef.scenes.room_with_sphere(2, 4)
    i = 5
    p, n = scene.centroids[i], scene.normals[i]
    F = ef.form_factors(scene, p, n)
    rng = np.random.default_rng(7)
    N = 40000
    r, phi = np.sqrt(rng.uniform(size=N)), rng.uniform(0, 2 * np.pi, N)
    local = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - r * r)])
    R = ef.geometry.receiver_frame(n)
    D = local @ R                                         # to world directions
    hit = brute_force_nearest(scene.polygons, p, D)
    front = np.einsum("ij,ij->i", scene.normals[np.maximum(hit, 0)], D) < 0
    est = np.bincount(hit[(hit >= 0) & front], minlength=len(scene)) / N
    sigma = np.sqrt(np.maximum(F * (1 - F), 1 / N) / N)
    assert np.all(np.abs(est - F) <= 5 * sigma)
    assert abs(F.sum() - 1) <= 1e-11
    assert F[np.array(scene.groups) == "sphere"].sum() > 0.01   # the sphere is seen


def _clip(P, n, d):
    """The part of polygon P with n . x >= d (Sutherland-Hodgman)."""
    out = []
    s = P @ n - d
    for k in range(len(P)):
        a, b, sa, sb = P[k], P[(k + 1) % len(P)], s[k], s[(k + 1) % len(P)]
        if sa >= 0:
            out.append(a)
        if (sa >= 0) != (sb >= 0):
            out.append(a + sa / (sa - sb) * (b - a))
    return np.array(out)


def shadow_reference(scene, p, n):
    """Occluded form factors by shadow polygons, independent of the engine: for each
    polygon j facing p, the part of every other polygon between p and j's plane is
    projected centrally from p onto that plane; j minus the union of these shadows
    (2-D booleans in j's plane) is what p sees of j, integrated with the unoccluded
    kernel (exterior rings minus holes)."""
    import shapely

    from exactff import _tolerances as tol

    F = np.zeros(len(scene))
    for j, Pj in enumerate(scene.polygons):
        nj, dj = scene.normals[j], scene.plane_offsets[j]
        h = dj - nj @ p                    # < 0: p in front of j
        # decided explicitly, not by the sign of a rounded dot product: p behind j, or in
        # its plane to the rounding of the coordinates (seen edge-on, 0; a row from a
        # coplanar neighbour's centroid), where h is 0 or 1e-17 depending on the CPU's
        # rounding and the projection below would divide by a rounded 0
        band = tol.PLANE_SIDE_ULPS * tol.EPS * (np.abs(p).max() + np.abs(Pj).max())
        if h >= -band:
            continue
        e1 = Pj[1] - Pj[0]
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(nj, e1)
        to2d = lambda X: np.column_stack([(X - Pj[0]) @ e1, (X - Pj[0]) @ e2])
        # the pyramid from p over j: planes through p and each edge of j
        cj = Pj.mean(axis=0)
        pyramid = []
        for a, b in zip(Pj, np.roll(Pj, -1, axis=0)):
            m = np.cross(a - p, b - p)
            m = m if m @ (cj - p) > 0 else -m
            pyramid.append((m, m @ p))
        shadows = []
        for i, Pi in enumerate(scene.polygons):
            if i == j:
                continue
            # keep the part of i between p and j's plane (on p's side of it, a little
            # beyond p), inside the pyramid: its central projection lies in j
            Q = _clip(Pi, nj, dj + 1e-12 * abs(h))          # n_j . x >= d_j: p's side
            if len(Q) >= 3:
                # and beyond p towards j, by more than the rounding of the projection's
                # denominator (Q - p) . n_j, so that it is negative in any rounding
                margin = max(1e-9 * abs(h), tol.PLANE_SIDE_ULPS * tol.EPS
                             * (np.abs(p).max() + np.abs(Q).max()))
                Q = _clip(Q, -nj, -(nj @ p) + margin)
            for m, dm in pyramid:
                if len(Q) >= 3:
                    Q = _clip(Q, m, dm)
            if len(Q) < 3:
                continue
            den = (Q - p) @ nj
            assert np.all(den < 0), den     # the clips above guarantee it
            t = h / den
            S = shapely.Polygon(to2d(p + t[:, None] * (Q - p)))
            if S.is_valid and S.area > 0:
                shadows.append(S)
        vis = shapely.Polygon(to2d(Pj))
        if shadows:
            vis = vis.difference(shapely.union_all(shadows))
        for part in shapely.get_parts(vis):
            if part.geom_type != "Polygon" or part.area < 1e-14:
                continue
            rings = [np.asarray(part.exterior.coords)[:-1]] + [np.asarray(r.coords)[:-1]
                                                                for r in part.interiors]
            for r, ring in enumerate(rings):
                X = Pj[0] + ring[:, :1] * e1 + ring[:, 1:] * e2
                val = ef.point_polygon_form_factor(p, n, X, two_sided=True)
                F[j] += val if r == 0 else -val
    return F


def test_small_room_with_sphere_against_shadow_polygons():
    scene = ef.scenes.room_with_sphere(0, 2)     # an icosahedron in a room of 24 quads
    for i in (0, 5, 13, 30):
        p, n = scene.centroids[i], scene.normals[i]
        F = ef.form_factors(scene, p, n)
        assert_form_factors_close(F, shadow_reference(scene, p, n), rtol=0, atol=1e-11)
