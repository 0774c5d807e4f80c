// The shadow-volume tree's operations: the conservative side of a direction against a
// plane, the tiling of the upper hemisphere, the exact tests of a vertex against a
// plane through the point (cached per row), and the insertion of a visible piece's
// shadow volume at a free leaf.

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "constants.h"
#include "core.h"

namespace exactff {

namespace {

// the pseudo-angle of (x, y) about the origin: in [0, 4), increasing with atan2(y, x)
// taken in [0, 2 pi) (a quarter turn a unit), one division
inline double pseudo_angle(double x, double y) {
    if (y >= 0) return x >= 0 ? y / (x + y) : 1 + (-x) / (y - x);
    return x < 0 ? 2 + (-y) / (-x - y) : 3 + x / (x - y);
}

// Whether the image of piece q (sides e, each plane oriented to hold the direction sum
// c, cl = |c|) is certainly a convex spherical polygon, in O(m): then every vertex lies
// on the inner side of every side's plane (what insert_shadow otherwise tests pair by
// pair). Sufficient, each decided beyond the same error bounds as that test:
// - every side oriented (state 1: c clearly on its inner side);
// - every vertex in the open hemisphere about c: the central projection from the
//   centre onto the plane tangent at c/|c| then maps the image to a planar polygon,
//   the sides' great circles to lines, and keeps every side of every plane;
// - every side runs the same way about c (its plane's normal along a x b, a and b its
//   ends, for every side, or against it for every side), by more than its ends' errors;
// - the turn at every vertex is strictly convex: the vertex after a side lies clearly
//   on its inner side;
// - the sides wind once about c: their angles about c, summed (as pseudo-angles, each
//   in (0, 2) for a side under a half turn), make one turn (4), not two (8 or more).
// In the projection: a polygon going the same way about an inner point, once, whose
// every turn is convex, is convex, and holds that point (docs/explanation/visibility.md).
// False proves nothing (the caller then tests every pair).
template <typename SideT>
bool convex_image(const Piece& q, const std::vector<SideT>& e, const V3& c, R cl, R eps) {
    const size_t m = q.size();
    int sense = 0;
    for (size_t i = 0; i < m; ++i) {
        const SideT& s = e[i];
        if (s.state != 1) return false;
        const Vertex& a = q[i];
        const Vertex& b = q[(i + 1) % m];
        const Vertex& w = q[(i + 2) % m];
        if (!(dot(c, a.v) > (16 * eps + a.err) * cl * a.length)) return false;
        const V3 ab = cross(a.v, b.v);
        const R abl = norm(ab);
        if (!(abl > 4 * (16 * eps + a.err + b.err) * a.length * b.length)) return false;
        const R along = dot(s.mm, ab);
        const int way = along > R(0.5) * s.ml * abl ? 1 : along < -R(0.5) * s.ml * abl ? -1 : 0;
        if (way == 0 || (sense != 0 && way != sense)) return false;
        sense = way;
        if (!(dot(s.mm, w.v) > (16 * eps + s.err + w.err) * s.ml * w.length)) return false;
    }
    // a frame (e1, e2) of the plane normal to c, and the turn the sides make about c
    const double cd[3] = {static_cast<double>(c.x), static_cast<double>(c.y),
                          static_cast<double>(c.z)};
    int k = 0;
    for (int j = 1; j < 3; ++j)
        if (std::fabs(cd[j]) < std::fabs(cd[k])) k = j;
    double ax[3] = {0, 0, 0};
    ax[k] = 1;
    const double e1[3] = {ax[1] * cd[2] - ax[2] * cd[1], ax[2] * cd[0] - ax[0] * cd[2],
                          ax[0] * cd[1] - ax[1] * cd[0]};
    const double e2[3] = {cd[1] * e1[2] - cd[2] * e1[1], cd[2] * e1[0] - cd[0] * e1[2],
                          cd[0] * e1[1] - cd[1] * e1[0]};
    auto angle = [&](const Vertex& u) {
        return pseudo_angle(e1[0] * u.vd[0] + e1[1] * u.vd[1] + e1[2] * u.vd[2],
                            e2[0] * u.vd[0] + e2[1] * u.vd[1] + e2[2] * u.vd[2]);
    };
    // (e1, e2, c) is right-handed: a side along a x b turns positively about c
    double turn = 0;
    const double first = angle(q[0]);
    double prev = first;
    for (size_t i = 1; i <= m; ++i) {
        const double next = i == m ? first : angle(q[i]);
        double d = sense > 0 ? next - prev : prev - next;
        if (d < 0) d += 4;
        turn += d;
        prev = next;
    }
    return turn < 6;
}

}  // namespace

// side of a direction against a plane, conservatively: +1, -1, or 0 where the
// sign is not sure (within the rounding of d and the plane's and vertex's errors)
int Core::side(const Plane& P, const Vertex& x, const Constants& K, R* d_out) {
    R d = dot(P.m, x.v);
    *d_out = d;
    R band = (K.band + P.err + x.err) * P.mnorm * x.length;
    if (d > band) return 1;
    if (d < -band) return -1;
    return 0;
}

// the normals of the planes that cut the upper hemisphere (about pn) into (tiles + 1)^2
// cells, along each axis: cos t u - sin t n and cos t v - sin t n (t evenly spaced in
// angle; u, v, n a frame). The grid is cut where pieces need it (Core::grow_tile)
void Core::tile_normals(const double* pn, int64_t tiles, TileNormals& xs, TileNormals& ys) {
    double n[3] = {pn[0], pn[1], pn[2]};
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& c : n) c /= nl;
    int a = 0;
    for (int i = 1; i < 3; ++i)
        if (std::fabs(n[i]) < std::fabs(n[a])) a = i;
    double e[3] = {0, 0, 0};
    e[a] = 1;
    double u[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2],
                   e[0] * n[1] - e[1] * n[0]};
    const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (double& c : u) c /= ul;
    double v[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2],
                   n[0] * u[1] - n[1] * u[0]};
    const double pi = 3.14159265358979323846;
    auto planes = [&](const double* w, TileNormals& out) {
        out.clear();
        for (int64_t k = 0; k < tiles; ++k) {
            double t = -pi / 2 + pi * static_cast<double>(k + 1) / (tiles + 1);
            out.push_back({std::cos(t) * w[0] - std::sin(t) * n[0],
                           std::cos(t) * w[1] - std::sin(t) * n[1],
                           std::cos(t) * w[2] - std::sin(t) * n[2]});
        }
    };
    planes(u, xs);
    planes(v, ys);
}

// block b's middle plane along an axis, its sides the block's halves: a node not yet
// in the tree (Core::place_tile)
Plane Core::tile_plane(const TileBlock& b, bool along_x, const RowStats& st) const {
    const int mid = ((along_x ? b.x0 : b.y0) + (along_x ? b.x1 : b.y1)) / 2;
    const auto& w = st.tiles[b.below][along_x ? 0 : 1][static_cast<size_t>(mid)];
    const V3 mm{w[0], w[1], w[2]};
    TileBlock neg = b, pos = b;
    (along_x ? neg.x1 : neg.y1) = mid;
    (along_x ? pos.x0 : pos.y0) = mid + 1;
    Plane P{mm, norm(mm), 2 * K_.eps, tile_leaf(pos), tile_leaf(neg), -1, 1};
    set_double(P);
    return P;
}

// a tile's plane into the tree, with its exact plane (its double normal): its index
int Core::place_tile(Plane P, std::vector<Plane>& sv, std::vector<ExactPlane>& xp) const {
    P.exact = static_cast<int>(xp.size());
    xp.push_back({1, {P.md[0], P.md[1], P.md[2]}, {0, 0, 0}, P.m, 2 * K_.eps, -1 - P.exact,
                  -1 - P.exact});
    sv.push_back(P);
    return static_cast<int>(sv.size()) - 1;
}

// a block of the tiles' grid cut at once, by middle planes along the axis with more
// planes left, into blocks of fewer than SVBSP_TILES_EAGER planes along each axis: the
// coarse grid every row gets (a balanced tree), finer blocks left to Core::grow_tile
int Core::cut_tiles(int leaf, std::vector<Plane>& sv, std::vector<ExactPlane>& xp,
                    const RowStats& st) const {
    if (leaf > LAZY) return leaf;
    const TileBlock b = tile_block(leaf);
    const bool along_x = b.x1 - b.x0 >= b.y1 - b.y0;
    if ((along_x ? b.x1 - b.x0 : b.y1 - b.y0) < SVBSP_TILES_EAGER) return leaf;
    const int node = place_tile(tile_plane(b, along_x, st), sv, xp);
    const int pos = cut_tiles(sv[static_cast<size_t>(node)].pos, sv, xp, st);
    sv[static_cast<size_t>(node)].pos = pos;
    const int neg = cut_tiles(sv[static_cast<size_t>(node)].neg, sv, xp, st);
    sv[static_cast<size_t>(node)].neg = neg;
    return node;
}

// whether a piece (the work list's current corners) is seen from nearly in its plane:
// the plane through three of its vertices passes within SVBSP_THIN_IMAGE (a sine) of
// the point, relative to its farthest vertex (in double: a choice of how to cut, not a
// decision of what is seen)
bool Core::thin_image(const Filter& work) {
    const size_t m = work.cur.size();
    if (m < 3) return true;
    const auto at = [&](size_t i) -> const double* {
        return work.pool[static_cast<size_t>(work.cur[i].v)].vd;
    };
    const double *a = at(0), *b = at(m / 3), *c = at(2 * m / 3);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double nn[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                          u[0] * v[1] - u[1] * v[0]};
    const double nl = std::sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    double far = 0;
    for (size_t i = 0; i < m; ++i)
        far = std::max(far, work.pool[static_cast<size_t>(work.cur[i].v)].lengthd);
    const double h = std::fabs(nn[0] * a[0] + nn[1] * a[1] + nn[2] * a[2]);
    return !(h > SVBSP_THIN_IMAGE * nl * far);
}

// a block of the tiles' grid not yet cut (free leaf `leaf`, reached by side `positive`
// of node `plane`) cut by its middle plane along an axis (the one with more planes left
// first) where the piece arriving there (the work list's current corners) lies clearly
// on one side of it: the new node, its two sides the block's halves; -1 where the piece
// lies across both axes' middle planes (its shadow then takes the whole block: its
// free leaves are the block, cut later where smaller pieces need it). A finer plane is
// placed only where a piece lies wholly on one side of it, so it never cuts that piece
// (later pieces in its region are cut by it, as by a grid cut at once): the shadows of
// small pieces grow in small cells, and the pieces of a row that sees a few large
// polygons stay whole. A piece seen from nearly in its own plane (thin_image) is cut as
// the whole grid would cut it
int Core::grow_tile(int leaf, int plane, bool positive, const Filter& work,
                    std::vector<Plane>& sv, std::vector<ExactPlane>& xp, RowStats& st) const {
    const TileBlock b = tile_block(leaf);
    const bool x_first = b.x1 - b.x0 >= b.y1 - b.y0;
    // a thin image (thin_image) asked for only where the piece lies across a plane:
    // -1 not yet, else whether; a thin image's kernel is charged by its perimeter, so it
    // is cut as a grid cut at once cuts it (smaller pieces, smaller charges)
    int thin = -1;
    for (const bool along_x : {x_first, !x_first}) {
        if ((along_x ? b.x0 : b.y0) >= (along_x ? b.x1 : b.y1)) continue;
        const Plane P = tile_plane(b, along_x, st);
        // the piece's side by the double filter the node's classification starts with
        // (Core::process's plane_width at a node of slack 0: keep the two equal), so
        // that a piece clearly on one side goes there whole
        const double width = static_cast<double>(K_.band + P.err);
        int side = 0;
        for (const Corner& c : work.cur) {
            const int s = filtered_side(P, work.pool[static_cast<size_t>(c.v)], width);
            if (s == 0 || s == -side) {
                side = 0;
                break;
            }
            side = s;
        }
        if (side == 0) {
            if (thin < 0) thin = thin_image(work);
            if (!thin) continue;
        }
        const int node = place_tile(P, sv, xp);
        attach(sv, plane, positive, node, static_cast<size_t>(node), st);
        ++st.tiles_cut;
        return node;
    }
    return -1;
}

// whether two exact planes are one by construction: the same kind, through p and the
// same two input points (in either order), or the same normal
bool Core::same_plane(const ExactPlane& P, const ExactPlane& Q) {
    return P.kind == Q.kind &&
           ((same_point(P.a, Q.a) && (Q.kind == 1 || same_point(P.b, Q.b))) ||
            (Q.kind == 0 && same_point(P.a, Q.b) && same_point(P.b, Q.a)));
}

// an exact plane's value at a point of the input
Expansion Core::exact_value(const ExactPlane& X, const double* p, const double* x) {
    return X.kind == 0 ? orient_exact(p, X.a, X.b, x) : dot_exact(X.a, p, x);
}

// whether input point x lies exactly on exact plane Q, decided once a row (the same
// mesh vertex and edge recur in every fragment that shares them)
bool Core::point_on_plane(const ExactPlane& Q, const double* p, const double* x, int64_t ux,
                          RowStats& st) const {
    if (ux == Q.ua || ux == Q.ub) return true;  // a point that defines it (kind 0)
    const int64_t a = std::min(Q.ua, Q.ub), b = std::max(Q.ua, Q.ub);
    const int known = st.on_plane.find(a, b, ux);
    if (known >= 0) return known != 0;
    ++st.exact_tests;
    const bool on = exactly_on_input(Q, p, x);
    st.on_plane.insert(a, b, ux, on);
    return on;
}

// whether a vertex lies exactly on an exact plane: an input vertex, or the crossing
// of an input edge a -> b with an exact plane P, x = a + t (b - a) with
// t = P(a) / (P(a) - P(b)): Q(x) = (Q(a) P(b) - P(a) Q(b)) / (P(b) - P(a)).
// False where it cannot be told (the vertex is then charged its sliver).
bool Core::exactly_on(std::vector<ExactPlane>& xp, int k, const double* p, int64_t f,
                      const Vertex& u, RowStats& st) const {
    ExactPlane& Q = xp[k];
    if (u.id >= 0) return point_on_plane(Q, p, &V_[3 * u.id], uid_[u.id], st);
    if (u.on_edge < 0) return false;
    if (u.on_plane == k) return true;
    // the plane it was cut by, instantiated again (the same input edge's plane from
    // another piece's shadow, or the same normal): on it
    if (same_plane(xp[u.on_plane], Q)) return true;
    const int64_t ia = u.on_edge;
    const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
    const ExactPlane& P = xp[u.on_plane];
    {   // the edge is one that defines Q (a shared edge): its whole line lies on Q
        const double* A = &V_[3 * ia];
        const double* Bv = &V_[3 * ib];
        if (Q.kind == 0 && ((same_point(A, Q.a) && same_point(Bv, Q.b)) ||
                            (same_point(A, Q.b) && same_point(Bv, Q.a))))
            return true;
    }
    // P and Q through p and a common input point v (two silhouette edges that meet
    // at v): two distinct such planes meet in the line through p and v, so the
    // crossing of the edge with P lies on Q exactly where that line meets the
    // edge's line, i.e. where v lies on the plane through p and the edge (one
    // orientation test of degree 3, against Q(a) P(b) - P(a) Q(b) of degree 6).
    // Where P and Q are one plane this says false, which only charges a sliver.
    if (P.kind == 0 && Q.kind == 0) {
        const double* v = nullptr;
        int64_t uv = -1;
        if (P.ua == Q.ua || P.ua == Q.ub) {
            v = P.a;
            uv = P.ua;
        } else if (P.ub == Q.ua || P.ub == Q.ub) {
            v = P.b;
            uv = P.ub;
        }
        if (v != nullptr && !same_point(v, p)) {
            ExactPlane R{0, {}, {}, V3{0, 0, 0}, 0, uid_[ia], uid_[ib]};
            std::memcpy(R.a, &V_[3 * ia], sizeof R.a);
            std::memcpy(R.b, &V_[3 * ib], sizeof R.b);
            return point_on_plane(R, p, v, uv, st);
        }
    }
    // P and Q one plane, given by other points (the bottom edges of walls standing
    // on the receiver's plane, collinear edges of separate polygons): every point
    // of P lies on Q. Told by the points that define one lying on the other
    // (degree 3 each, and the same pair of planes recurs all row long)
    if ((Q.kind == 0 && point_on_plane(P, p, Q.a, Q.ua, st) &&
         point_on_plane(P, p, Q.b, Q.ub, st)) ||
        (P.kind == 0 && point_on_plane(Q, p, P.a, P.ua, st) &&
         point_on_plane(Q, p, P.b, P.ub, st))) {
        return true;
    }
    // the same crossing against the same plane recurs in every fragment that shares the
    // edge (a mesh's): decided once a row, by the identities of P, Q and the edge (each
    // pair of ids packed into one key where they fit 32 bits, as they do below 2^31
    // input points and exact planes)
    auto pair_key = [](int64_t x, int64_t y, int64_t* key) {
        const int64_t lo = std::min(x, y) + (int64_t{1} << 31), hi = std::max(x, y) + (int64_t{1} << 31);
        if (lo < 0 || hi >= (int64_t{1} << 32)) return false;
        *key = static_cast<int64_t>((static_cast<uint64_t>(lo) << 32) | static_cast<uint64_t>(hi));
        return true;
    };
    int64_t kp, kq, ke;
    const bool keyed = pair_key(P.ua, P.ub, &kp) && pair_key(Q.ua, Q.ub, &kq) &&
                       pair_key(uid_[ia], uid_[ib], &ke);
    if (keyed) {
        const int known = st.on_crossing.find(kp, kq, ke);
        if (known >= 0) return known != 0;
    }
    const bool on = crossing_on(P, Q, p, ia, ib);
    if (keyed) st.on_crossing.insert(kp, kq, ke, on);
    return on;
}

// whether the crossing of input edge ia -> ib with exact plane P lies on exact plane Q:
// the sign of Q(a) P(b) - P(a) Q(b), filtered in long double, else exact
bool Core::crossing_on(const ExactPlane& P, const ExactPlane& Q, const double* p, int64_t ia,
                       int64_t ib) const {
    {   // the filter: Q(a) P(b) - P(a) Q(b) in long double, with its error bound
        R qa, eqa, qb, eqb, pa, epa, pb, epb;
        filtered(Q.kind, p, Q.a, Q.b, &V_[3 * ia], &qa, &eqa);
        filtered(Q.kind, p, Q.a, Q.b, &V_[3 * ib], &qb, &eqb);
        filtered(P.kind, p, P.a, P.b, &V_[3 * ia], &pa, &epa);
        filtered(P.kind, p, P.a, P.b, &V_[3 * ib], &pb, &epb);
        const R c = qa * pb - pa * qb;
        const R err = (std::fabs(qa) + eqa) * epb + eqa * std::fabs(pb) +
                      (std::fabs(pa) + epa) * eqb + epa * std::fabs(qb) +
                      4 * std::numeric_limits<R>::epsilon() *
                          (std::fabs(qa * pb) + std::fabs(pa * qb));
        if (std::fabs(c) > err) return false;
    }
    Expansion Pa = exact_value(P, p, &V_[3 * ia]), Pb = exact_value(P, p, &V_[3 * ib]);
    Expansion Qa = exact_value(Q, p, &V_[3 * ia]), Qb = exact_value(Q, p, &V_[3 * ib]);
    Expansion r;
    mul_into(r, Qa, Pb, 1.0);
    mul_into(r, Pa, Qb, -1.0);
    return sign(r) == 0;
}

// an input point against an exact plane
bool Core::exactly_on_input(const ExactPlane& Q, const double* p, const double* x) const {
    // one of the two points that define the plane (a shared edge's end): on it
    if (Q.kind == 0 && ((x[0] == Q.a[0] && x[1] == Q.a[1] && x[2] == Q.a[2]) ||
                        (x[0] == Q.b[0] && x[1] == Q.b[1] && x[2] == Q.b[2])))
        return true;
    if (surely_off(Q.kind, p, Q.a, Q.b, x)) return false;
    return sign(exact_value(Q, p, x)) == 0;
}

// replace the free leaf reached by (plane, branch) with the piece's shadow volume
// the plane through p and input points a, b: (a - p) x (b - a), from the doubles'
// error-free differences and products (two-sum, two-product), so that its direction
// is good to a few long double roundoffs even for an edge seen nearly end-on
V3 Core::input_plane(const double* p, const double* a, const double* b) {
    double Ah[3], Al[3], Eh[3], El[3];
    for (int i = 0; i < 3; ++i) {
        two_sum(a[i], -p[i], Ah[i], Al[i]);
        two_sum(b[i], -a[i], Eh[i], El[i]);
    }
    auto term = [&](int i, int j) {  // A_i E_j - A_j E_i
        const double p1 = Ah[i] * Eh[j], p2 = Ah[j] * Eh[i];
        const double e1 = std::fma(Ah[i], Eh[j], -p1), e2 = std::fma(Ah[j], Eh[i], -p2);
        return (static_cast<R>(p1) - p2) + (static_cast<R>(e1) - e2) +
               (static_cast<R>(Ah[i]) * El[j] + static_cast<R>(Al[i]) * Eh[j]) -
               (static_cast<R>(Ah[j]) * El[i] + static_cast<R>(Al[j]) * Eh[i]);
    };
    return {term(1, 2), term(2, 0), term(0, 1)};
}

// replace the free leaf reached by (plane, branch) with the piece's shadow volume:
// for each edge, the plane it lies on (its input edge's plane through p, or the
// plane it was cut along), oriented to hold the piece
// (false: the shadow is left out)
bool Core::insert_shadow(const Piece& q, int64_t f, const double* pp, int plane,
                         bool positive, std::vector<Plane>& sv, std::vector<ExactPlane>& xp,
                         RowStats& st, PieceWorth& worth, const V3& n) const {
    // the piece's value and bound, where a shadow left out charges them
    auto piece_bound = [&]() { return piece_worth(q, f, n, st, worth); };
    constexpr R PI = 3.14159265358979323846264338327950288L;
    const size_t m = q.size();
    const V3 c = direction_sum(q);
    const R cl = norm(c);
    // per edge: its plane through p, oriented towards the piece (0: through p, not
    // a side; 2: the piece straddles it, no orientation), and how far beyond it the
    // piece's farthest vertex lies (radians)
    struct Side {
        V3 mm;
        R ml, err, beyond;
        int exact, orient;
        int state;  // 0 none (through p), 1 oriented, 2 straddled
        bool on_cut, omit;
    };
    // (the scratch is kept per thread: no allocation per piece)
    // (each side's every field is set below before it is read: no fill)
    thread_local std::vector<Side> e;
    e.resize(m);
    // the vertices' double directions and lengths, contiguous (the filter below reads
    // them m times each)
    thread_local std::vector<double> X, Y, Z, L;
    X.resize(m);
    Y.resize(m);
    Z.resize(m);
    L.resize(m);
    for (size_t k = 0; k < m; ++k) {
        X[k] = q[k].vd[0];
        Y[k] = q[k].vd[1];
        Z[k] = q[k].vd[2];
        L[k] = q[k].lengthd;
    }
    if (m < 3) {
        leave_out(q, piece_bound(), 0, st);
        return false;
    }
    for (size_t i = 0; i < m; ++i) {
        const Vertex& a = q[i];
        Side& s = e[i];
        if (a.edge >= 0) {
            const int64_t ia = a.edge;
            const int64_t ib = ia + 1 == start_[f] + count_[f] ? start_[f] : ia + 1;
            s.mm = input_plane(pp, &V_[3 * ia], &V_[3 * ib]);
            // its rounding; the input points' own errors (BSP crossings) apart
            const R tilt = input_tilt(ia, ib, pp);
            s.err = 8 * K_.eps;
            s.exact = static_cast<int>(xp.size());
            xp.push_back({0, {V_[3 * ia], V_[3 * ia + 1], V_[3 * ia + 2]},
                          {V_[3 * ib], V_[3 * ib + 1], V_[3 * ib + 2]}, s.mm, s.err,
                          uid_[ia], uid_[ib], tilt});
        } else {
            s.exact = static_cast<int>(-1 - a.edge);
            s.mm = xp[s.exact].m;
            s.err = xp[s.exact].err;
        }
        s.on_cut = a.edge < 0;
        s.omit = false;
        s.beyond = 0;
        s.orient = 1;
        s.ml = norm(s.mm);
        if (!(s.ml > 0)) {  // an input edge through p (seen end-on exactly)
            s.state = 0;
            continue;
        }
        const R dc = dot(s.mm, c);
        // the piece must lie clearly on one side
        if (!(std::fabs(dc) > (16 * K_.eps + s.err) * s.ml * cl)) {
            s.state = 2;
            continue;
        }
        s.state = 1;
        if (dc < 0) {
            s.mm = {-s.mm.x, -s.mm.y, -s.mm.z};
            s.orient = -1;
        }
    }
    // and every vertex on each oriented side, up to the plane's and its own errors: how
    // far beyond it the farthest lies (a vertex clearly inside by the classification's
    // double filter, Core::process, needs no long double test). A piece of m vertices
    // costs m^2 of these tests; a long piece whose image is certainly convex
    // (convex_image, O(m)) has every vertex inside every side and needs none. (A side
    // along a cut, whose `beyond` nothing reads, is not tested.)
    const bool convex = m > LONG_SHADOW_EDGES && convex_image(q, e, c, cl, K_.eps);
    for (size_t i = 0; !convex && i < m; ++i) {
        Side& s = e[i];
        if (s.state != 1 || s.on_cut) continue;
        const double md[3] = {static_cast<double>(s.mm.x), static_cast<double>(s.mm.y),
                              static_cast<double>(s.mm.z)};
        const double mld = static_cast<double>(s.ml);
        const double inside = SVBSP_FILTER_ROUNDOFFS * DBL_EPSILON * mld * (1 + 8 * DBL_EPSILON);
        const size_t next = (i + 1) % m;
        for (size_t k = 0; k < m; ++k) {
            if (k == i || k == next) continue;
            if (md[0] * X[k] + md[1] * Y[k] + md[2] * Z[k] > inside * L[k]) continue;
            const Vertex& u = q[k];
            const R tol = 16 * K_.eps + s.err + u.err;
            const R dk = dot(s.mm, u.v);
            if (dk < -tol * s.ml * u.length)
                s.beyond = std::max(s.beyond, -dk / (s.ml * u.length) + tol);
        }
    }
    // The shadow is the intersection of the sides' half-spaces. Where the image is
    // convex, that is the image. Where it is not (a polygon planar only within the
    // validation tolerance seen from nearly in its plane; an input edge shorter than
    // its vertices' roundings, whose direction they decide), it is the image's
    // kernel, less than the image: the part left out lies in the piece on the wrong
    // side of a plane, within `beyond` of it and across the piece's extent (at most
    // half its perimeter), so its projected area is at most beyond * perimeter / 2
    // / pi (projected area <= area on the sphere); a later piece behind it may show
    // through by that much. A short side whose two neighbours turn by less than
    // about 154 degrees together is left out instead where that costs less: the
    // shadow then holds the
    // triangle the two neighbours' planes close beyond it, of apex height at most
    // l tan(theta / 2) / 2 over its arc l (theta the angle of their normals), so
    // area l^2 tan(theta / 2) / 4, which may hide that much of a later piece
    // (the arcs only where a side is straddled or has a vertex beyond it: a convex
    // image, nearly every piece, needs none)
    bool concave = false;
    for (const Side& s : e) concave |= !s.on_cut && (s.state == 2 || s.beyond > 0);
    R perimeter = 0;
    thread_local std::vector<R> arcs;
    arcs.assign(concave ? m : 0, 0);
    for (size_t k = 0; concave && k < m; ++k) {
        arcs[k] = arc(q[k], q[(k + 1) % m]) + q[k].err + q[(k + 1) % m].err;
        perimeter += arcs[k];
    }
    R kernel_charge = 0, omit_charge = 0;
    for (size_t i = 0; i < m; ++i) {
        Side& s = e[i];
        if (s.on_cut || !(s.state == 2 || s.beyond > 0)) continue;
        const Side& prev = e[(i + m - 1) % m];
        const Side& next = e[(i + 1) % m];
        R omit = INFINITY;
        if (prev.state == 1 && next.state == 1 && !prev.omit && !next.omit) {
            const R cosine = dot(prev.mm, next.mm) / (prev.ml * next.ml);
            if (cosine > -0.9L) {   // theta below about 154 degrees: a bounded triangle
                const R theta = std::acos(std::min(cosine, R(1))) +
                                16 * K_.eps + prev.err + next.err;
                omit = arcs[i] * arcs[i] * std::tan(theta / 2) / 4 / PI * (1 + 1e-6L);
            }
        }
        const R keep = s.state == 2 ? INFINITY : s.beyond * perimeter / 2 / PI;
        if (omit <= keep) {
            s.omit = true;
            omit_charge += omit;
        } else {
            kernel_charge += keep;
        }
    }
    size_t sides = 0;  // the piece's edges that bound its shadow, cut ones included
    thread_local std::vector<Plane> chain;
    thread_local std::vector<size_t> chain_edge;  // the piece's edge each plane of the chain is
    chain.clear();
    chain_edge.clear();
    bool straddled = false;
    for (size_t i = 0; i < m; ++i) {
        const Side& s = e[i];
        if (s.state == 0 || s.omit) continue;
        if (s.state == 2) straddled = true;
        ++sides;
        // an edge along a plane the piece was cut by: that plane is on the path to
        // the leaf, whose whole cell already lies on the piece's side of it, so the
        // shadow needs no plane there
        if (!s.on_cut && s.state == 1) {
            chain.push_back({s.mm, s.ml, s.err, OUT, OUT, s.exact, s.orient});
            set_double(chain.back());
            chain_edge.push_back(i);
        }
    }
    // a sliver (a side it straddles, fewer than three sides) or a kernel that leaves
    // out more than the piece is worth: no shadow at all
    if (straddled || sides < 3 ||
        (kernel_charge + omit_charge > 0 && kernel_charge + omit_charge > piece_bound())) {
        leave_out(q, piece_bound(), straddled ? 1 : (sides < 3 ? 3 : 2), st);
        return false;
    }
    leave_out(q, kernel_charge, -1, st);
    // what the omitted sides' triangles may hide is not attributed to a piece
    st.unattributed += omit_charge;
    st.omitted_sides += omit_charge > 0;
    st.kernels += kernel_charge > 0;
    if (st.cull) drop_repeated_sides(plane, positive, sv, xp, chain, chain_edge, st);
    // the shadow's free leaves: the leaf it replaces (a block of tiles not yet cut stays
    // one, Core::grow_tile); a long shadow's (a tree of chords: a free leaf per edge of
    // its rim) are plain free leaves, since a copy of the block in each would have the
    // grid cut again in each (3,541 tile planes for a 1,500-gon disc)
    const int leaf = positive ? sv[plane].pos : sv[plane].neg;
    const size_t first = sv.size();
    if (chain.empty()) {  // the piece fills its leaf's cell: the cell is covered
        attach(sv, plane, positive, IN, first, st);
        return true;
    }
    // a long piece whose image is convex (no side left out, no kernel): a tree of chords
    if (chain.size() > LONG_SHADOW_EDGES && kernel_charge == 0 && omit_charge == 0) {
        const int root = long_shadow(q, pp, chain, chain_edge, sv, xp, st);
        attach(sv, plane, positive, root, first, st);
        return true;
    }
    const int base = static_cast<int>(sv.size());
    for (size_t i = 0; i < chain.size(); ++i) {
        chain[i].pos = i + 1 < chain.size() ? base + static_cast<int>(i) + 1 : IN;
        chain[i].neg = leaf;
        sv.push_back(chain[i]);
    }
    attach(sv, plane, positive, base, first, st);
    st.shadow_planes += static_cast<int64_t>(chain.size());
    return true;
}

// drop from a shadow's chain the sides along a plane already on the path to its leaf
// (reached by side `positive` of node `plane`) with the leaf on the piece's side of it:
// the edge two adjacent polygons of a mesh share, the second's piece filtered into a
// cell the first's shadow bounds there. The side is the same exact plane through p and
// the same two input points, and the cell lies wholly on its piece's side, so the node
// would send every later piece the way its ancestor already did (its sign at each vertex
// is the ancestor's, up to the roundings of the two planes' normals, within the band
// whose slivers the ancestor charges): the cell's shadow is the same without it
void Core::drop_repeated_sides(int plane, bool positive, const std::vector<Plane>& sv,
                               const std::vector<ExactPlane>& xp, std::vector<Plane>& chain,
                               std::vector<size_t>& chain_edge, RowStats& st) {
    if (chain.empty()) return;
    bool branch = positive;
    for (int node = plane, below = -1; node >= 0; below = node, node = sv[node].parent) {
        if (below >= 0) branch = sv[node].pos == below;
        const ExactPlane& Y = xp[static_cast<size_t>(sv[node].exact)];
        if (Y.kind != 0) continue;
        for (size_t i = 0; i < chain.size(); ++i) {
            const ExactPlane& X = xp[static_cast<size_t>(chain[i].exact)];
            if (X.kind != 0) continue;
            const bool same = X.ua == Y.ua && X.ub == Y.ub;
            if (!same && !(X.ua == Y.ub && X.ub == Y.ua)) continue;
            // the leaf's side of the ancestor, and the piece's side, against X's normal
            const int leaf = (branch ? 1 : -1) * sv[node].orient * (same ? 1 : -1);
            if (leaf != chain[i].orient) continue;
            chain.erase(chain.begin() + static_cast<std::ptrdiff_t>(i));
            chain_edge.erase(chain_edge.begin() + static_cast<std::ptrdiff_t>(i));
            ++st.repeated_sides;
            if (chain.empty()) return;
            break;
        }
    }
}

// the parents of the children of nodes `first` on (their links)
void Core::adopt(std::vector<Plane>& sv, size_t first) {
    for (size_t k = first; k < sv.size(); ++k)
        for (int c : {sv[k].pos, sv[k].neg})
            if (c >= 0) sv[static_cast<size_t>(c)].parent = static_cast<int>(k);
}

// hang `child` (a node, IN, OUT or a block of tiles) on the side `positive` of node
// `plane`, where the nodes from `first` on are new (their parents set from their
// links). A node whose two sides are then both covered is covered itself (its region
// is the union of theirs): it becomes a covered leaf of its parent, and so on up, so
// that later pieces behind it are hidden at the first node whose region is wholly
// covered instead of being cut along every shadow inside it. Where the root goes, every
// direction the row sees is covered (RowStats::covered)
void Core::attach(std::vector<Plane>& sv, int plane, bool positive, int child, size_t first,
                  RowStats& st) {
    (positive ? sv[plane].pos : sv[plane].neg) = child;
    adopt(sv, first);
    if (child >= 0) sv[static_cast<size_t>(child)].parent = plane;
    if (child != IN) return;
    for (int node = plane; sv[node].pos == IN && sv[node].neg == IN;) {
        ++st.collapsed;
        const int up = sv[node].parent;
        if (up < 0) {
            st.covered = true;
            return;
        }
        (sv[up].pos == node ? sv[up].pos : sv[up].neg) = IN;
        node = up;
    }
}

// a part of the hemisphere that a piece covers but its shadow does not (all of a
// sliver's, a kernel's remainder), worth at most `charge`: a later visible piece
// that may overlap it may show through by as much, and no more than itself. Small
// charges go to every receiving polygon (up to the row's budget); the others are
// kept with the cone that holds them (Core::leaked)
void Core::leave_out(const Piece& q, R charge, int why, RowStats& st) const {
    if (why >= 0) ++st.slivers[why];
    if (!(charge > 0)) return;
    if (st.unattributed + charge <= st.leak_budget) {
        st.unattributed += charge;
        return;
    }
    st.leaks.push_back(cone(q));
    st.leaks.back().charge = charge;
}

// a cone about the piece's mean direction that holds its image (radians, with its
// vertices' errors and a margin for the arcs' rounding)
// the sum of a piece's unit vertex directions (its mean direction, unnormalised)
V3 Core::direction_sum(const Piece& q) {
    V3 c{0, 0, 0};
    for (const Vertex& u : q) {
        c.x += u.v.x / u.length;
        c.y += u.v.y / u.length;
        c.z += u.v.z / u.length;
    }
    return c;
}

Leak Core::cone(const Piece& q) const {
    const V3 c = direction_sum(q);
    Leak k{c, 0, 0};
    const R cl = norm(c);
    if (!(cl > 1e-6L)) {  // about opposite directions: the whole sphere
        k.radius = 4;
        return k;
    }
    k.c = {c.x / cl, c.y / cl, c.z / cl};
    for (const Vertex& u : q)
        k.radius = std::max(k.radius, std::atan2(norm(cross(k.c, u.v)), dot(k.c, u.v)) + u.err);
    k.radius += 64 * K_.eps;
    return k;
}

// what the row's kept leaks may have shown of visible piece q, worth val + bnd: the
// charges of those whose cones meet its cone, at most the piece itself
R Core::leaked(const Piece& q, R worth, const RowStats& st) const {
    if (st.leaks.empty()) return 0;
    const Leak k = cone(q);
    R sum = 0;
    for (const Leak& l : st.leaks)
        if (k.radius >= 4 || l.radius >= 4 ||
            std::atan2(norm(cross(k.c, l.c)), dot(k.c, l.c)) <= k.radius + l.radius + 64 * K_.eps)
            sum += l.charge;
    return std::min(sum, worth);
}


// the shadow of a convex piece with many edges (more than LONG_SHADOW_EDGES in its
// chain): a chain of its edges' planes costs every piece behind it a visit per edge,
// and cuts the pieces around it along the edges' planes, nearly parallel near each
// other (slivers with ill-conditioned crossings). Instead the piece is split by chords,
// planes through p and two of its input vertices, into convex parts of at most
// LONG_SHADOW_LEAF edges, in a balanced tree: the first chord from a vertex to one
// halfway round, each next from the middle of a part's rim to the vertex halfway round
// the piece from it (nearly through the piece's middle, so that it cuts what lies
// around the piece nearly across its edges). A part is the piece's intersection with
// the sides of the chords on its path, a closed convex polygon whose other edges are
// its rim's: its cone is those half-spaces, the chords on the path and the chain of its
// rim's planes (cut edges' planes are on the path already), and the parts cover the
// piece. A chord is kept only where every vertex of the part's rim is clearly on the
// side of its own half (as insert_shadow asks of a chain's planes), else that part gets
// the chain of its rim's planes.
int Core::long_shadow(const Piece& q, const double* pp, const std::vector<Plane>& chain,
                      const std::vector<size_t>& chain_edge, std::vector<Plane>& sv,
                      std::vector<ExactPlane>& xp, RowStats& st) const {
    const size_t m = q.size();
    std::vector<int> plane_of(m, -1);  // the chain's plane of each edge of the piece
    for (size_t k = 0; k < chain.size(); ++k) plane_of[chain_edge[k]] = static_cast<int>(k);
    // the chain of the planes of the piece's edges [a, b) (positions along the rim, mod m)
    auto rim_chain = [&](size_t a, size_t b) {
        int first = IN, prev = -1;
        for (size_t k = a; k < b; ++k) {
            const int e = plane_of[k % m];
            if (e < 0) continue;
            const int node = static_cast<int>(sv.size());
            sv.push_back(chain[static_cast<size_t>(e)]);
            sv.back().pos = IN;
            sv.back().neg = OUT;
            if (prev >= 0) sv[static_cast<size_t>(prev)].pos = node;
            else first = node;
            prev = node;
            ++st.shadow_planes;
        }
        return first;
    };
    // an input vertex of the piece at a position near `want` within (lo, hi), or none
    const size_t none = static_cast<size_t>(-1);
    auto input_near = [&](size_t want, size_t lo, size_t hi) {
        for (size_t d = 0; d <= hi - lo; ++d)
            for (size_t c : {want - d, want + d})
                if (c > lo && c < hi && q[c % m].id >= 0) return c;
        return none;
    };
    // the chord through the input vertices at positions e0 and e1, oriented so that the
    // rim's vertices at [a, mid] lie on its positive side and those at [mid, b] on its
    // negative side (the chord's own ends apart), each clearly (beyond the band that
    // insert_shadow asks of a chain's planes); -1 where they do not
    auto chord = [&](size_t e0, size_t e1, size_t a, size_t mid, size_t b) {
        const int64_t i0 = q[e0 % m].id, i1 = q[e1 % m].id;
        V3 mm = input_plane(pp, &V_[3 * i0], &V_[3 * i1]);
        const R ml = norm(mm);
        const R err = 8 * K_.eps;
        if (!(ml > 0)) return -1;
        int orient = 0;
        for (size_t k = a; k <= b; ++k) {
            if (k % m == e0 % m || k % m == e1 % m) continue;
            const Vertex& u = q[k % m];
            const R dk = dot(mm, u.v);
            const R w = (16 * K_.eps + err + u.err) * ml * u.length;
            const int s = dk > w ? 1 : (dk < -w ? -1 : 0);
            const int want = k < mid ? 1 : -1;
            if (s == 0 || (orient != 0 && s * want != orient)) return -1;
            orient = s * want;
        }
        if (orient == 0) return -1;
        const int exact = static_cast<int>(xp.size());
        xp.push_back({0, {V_[3 * i0], V_[3 * i0 + 1], V_[3 * i0 + 2]},
                      {V_[3 * i1], V_[3 * i1 + 1], V_[3 * i1 + 2]}, mm, err, uid_[i0],
                      uid_[i1], input_tilt(i0, i1, pp)});
        if (orient < 0) mm = {-mm.x, -mm.y, -mm.z};
        const int node = static_cast<int>(sv.size());
        sv.push_back({mm, ml, err, OUT, OUT, exact, orient});
        set_double(sv.back());
        ++st.shadow_planes;
        return node;
    };
    std::function<int(size_t, size_t)> part = [&](size_t a, size_t b) -> int {
        if (b - a <= LONG_SHADOW_LEAF) return rim_chain(a, b);
        const size_t mid = input_near(a + (b - a) / 2, a, b);
        if (mid == none) return rim_chain(a, b);
        // the far end: an input vertex about halfway round from mid, off [a, b]
        size_t opp = none;
        for (size_t d = 0; d < m / 2 && opp == none; ++d)
            for (size_t c : {mid + m / 2 - d, mid + m / 2 + d})
                if (c > b && c < a + m && q[c % m].id >= 0) {
                    opp = c;
                    break;
                }
        const int node = opp != none ? chord(mid, opp, a, mid, b) : -1;
        if (node < 0) return rim_chain(a, b);
        const int pos = part(a, mid);
        sv[static_cast<size_t>(node)].pos = pos;
        const int neg = part(mid, b);
        sv[static_cast<size_t>(node)].neg = neg;
        return node;
    };
    // the first chord: from an input vertex to one about halfway round
    size_t s0 = 0;
    while (s0 < m && q[s0].id < 0) ++s0;
    const size_t half = s0 < m ? input_near(s0 + m / 2, s0, s0 + m) : none;
    const int root = half != none ? chord(s0, half, s0, half, s0 + m) : -1;
    if (root < 0) return rim_chain(0, m);
    const int pos = part(s0, half);
    sv[static_cast<size_t>(root)].pos = pos;
    const int neg = part(half, s0 + m);
    sv[static_cast<size_t>(root)].neg = neg;
    return root;
}

}  // namespace exactff
