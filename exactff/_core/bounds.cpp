// The bounds of a visible piece's value beyond its sector sum's rounding: each edge's
// share of its ends' direction errors (charge_edges), the input points' own errors
// (input_error, input_tilt), and the quadruple-precision refinement of a piece whose
// bound is too large for its value (quad_plane, refine).

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "core.h"

namespace exactff {

// the angle a direction turns when its point, at distance r from p, moves by at most
// `ratio` r: asin(ratio) <= 1.01 ratio for ratio <= 0.1, else any angle (pi)
R Core::turn_bound(R ratio) {
    return ratio <= static_cast<R>(0.1) ? static_cast<R>(1.01) * ratio
                                        : static_cast<R>(3.14159265358979323846L);
}

// a bound on the angle at p between input point i's direction and that of the exact
// point it stands for (a BSP split's crossing is rounded: VE_[i] bounds its
// distance), with `length` its distance from p
R Core::input_error(int64_t i, R length) const {
    const R e = VE_[static_cast<size_t>(i)];
    return e == 0 ? 0 : turn_bound(e / length);
}

// a bound on the angle by which the plane through p and input points a, b turns off
// the one through the exact points they stand for, over the wedge between them (the
// part of the plane where it bounds a shadow): a point of the edge moves by at most
// the larger end error (in the world), and it is at least h = |(a - p) x (b - p)| /
// |b - a| from p, so its direction turns by at most that over h (0 for input points
// that are exact; any angle, pi, where the first order does not hold)
R Core::input_tilt(int64_t ia, int64_t ib, const double* pp) const {
    const size_t a = static_cast<size_t>(ia), b = static_cast<size_t>(ib);
    const R e = std::max(VE_[a], VE_[b]);
    if (e == 0) return 0;
    R A[3], B[3], D[3];
    for (int k = 0; k < 3; ++k) {
        A[k] = static_cast<R>(V_[3 * a + k]) - pp[k];
        B[k] = static_cast<R>(V_[3 * b + k]) - pp[k];
        D[k] = static_cast<R>(V_[3 * b + k]) - V_[3 * a + k];
    }
    const V3 c = cross(V3{A[0], A[1], A[2]}, V3{B[0], B[1], B[2]});
    const R d = std::sqrt(D[0] * D[0] + D[1] * D[1] + D[2] * D[2]);
    const R h = d > 0 ? norm(c) / d : 0;
    return turn_bound(h > 0 ? e / h : static_cast<R>(HUGE_VAL));
}

// each edge's share of the error of its ends' directions: its arc length times the
// larger of their bounds, over pi (the area swept by moving the edge that far); with
// `refined`, the bounds of the directions Core::refine gave the piece instead
// (the computation's part: the one returned and added to E; the input's own errors'
// part, arc length times the larger of the ends' gerr over pi, or times the turn of
// the edge's own plane where that is known (Core::edge_tilt), goes to st.crossing)
R Core::charge_edges(const Piece& q, int64_t src, std::vector<R>& E, RowStats& st,
                     const std::vector<R>* refined, bool record,
                     std::vector<std::pair<EdgeKey, R>>* keyed, std::vector<R>* arcs,
                     int64_t f) const {
    const R pi = 3.14159265358979323846264338327950288L;
    const size_t m = q.size();
    R total = 0;
    for (size_t i = 0; i < m; ++i) {
        const size_t j = i + 1 == m ? 0 : i + 1;
        const Vertex& a = q[i];
        const Vertex& b = q[j];
        // off the plane the edge lies on: for an input edge, its ends' distances
        // from that edge's plane (a crossing slides along it, which moves nothing)
        auto off = [&](const Vertex& u, size_t k) {
            if (refined) return (*refined)[k];
            if (a.edge >= 0 && u.id < 0 && u.on_edge == a.edge) return u.err_line;
            return u.err;
        };
        // (the arcs of a piece charged more than once are computed once: `arcs`)
        if (arcs != nullptr && arcs->size() < m) arcs->push_back(arc_bound(a, b));
        const R length = arcs != nullptr ? (*arcs)[i] : arc_bound(a, b);
        const R charge = length * std::max(off(a, i), off(b, j)) / pi;
        total += charge;
        if (!record && keyed == nullptr) continue;
        if (a.id >= 0 && b.id >= 0 && a.gerr == 0 && b.gerr == 0) {
            // an input edge of the scene's: on its polygon's boundary
            if (record) E[src] += charge;
            continue;
        }
        // the input's own errors: the edge's points move by at most the ends' world
        // errors, and lie at least h (p's distance from the edge's line) from p, so
        // their directions turn by at most turn_bound(moved / h)
        R geo = 0;
        if (record && (a.gerr > 0 || b.gerr > 0)) {
            const V3 d{b.v.x - a.v.x, b.v.y - a.v.y, b.v.z - a.v.z};
            const R dl = norm(d);
            const R h = dl > 0 ? norm(cross(a.v, b.v)) / dl : std::min(a.length, b.length);
            const R moved = std::max(a.gerr * a.length, b.gerr * b.length);
            geo = h > 0 ? length * turn_bound(moved / h) / pi : length;
            // the same sweep with each point's own displacement: the point at t along
            // the edge moves by at most (1 - t) ea + t eb (the ends' world errors), and
            // (1 - t) / |x(t)| = sin(L - th) / (|a| sin L) at angle th from a (L the
            // edge's arc; the sine rule), so the swept area is at most
            // (ea / |a| + eb / |b|) tan(L / 2) = (a.gerr + b.gerr) tan(L / 2); for
            // L <= pi / 2 each point turns by at most a.gerr + b.gerr, within the first
            // order of turn_bound where that is at most 0.1
            const R turn = a.gerr + b.gerr;
            if (length <= pi / 2 && turn <= static_cast<R>(0.1))
                geo = std::min(geo, static_cast<R>(1.01) * turn * std::tan(length / 2) / pi);
            // where the edge's plane through p is one the input's errors turn by a known
            // angle over the edge (Core::edge_tilt), its points move off that plane by at
            // most that: their slides along it (its ends where other edges' planes cross
            // it) sweep nothing of this edge (the next edges' charges hold them)
            const R own = edge_tilt(a.edge, f, st);
            if (own >= 0) geo = std::min(geo, length * own / pi);
        }
        // a cut edge, or one a BSP split made (two fragments of one polygon share
        // it): keyed by its ends, in a fixed order
        const Vertex* lo = &a;
        const Vertex* hi = &b;
        if (lex_less(hi->v, lo->v)) std::swap(lo, hi);
        EdgeKey k{{lo->v.x, lo->v.y, lo->v.z, hi->v.x, hi->v.y, hi->v.z}};
        if (!record) {
            keyed->push_back({k, charge});
            continue;
        }
        EdgeCharge* it = st.edges.find(k);
        const bool r = refined != nullptr;
        if (it == nullptr) {
            st.edges.emplace(k, EdgeCharge{src, charge, 1, r, geo});
        } else if (it->src == src && it->count == 1) {
            // shared by two visible pieces of src: moving it moves area from one to
            // the other, if both place it alike; one refined and one not do not:
            // the coarser placement's charge stays
            it->count = 2;
            if (it->refined != r) E[src] += std::max(charge, it->charge);
        } else {
            E[src] += charge;
            st.crossing[static_cast<size_t>(src)] += geo;
        }
    }
    return total;
}

// a bound on the angle by which the input's own errors turn the plane through p that a
// piece's edge lies on (edge code as Vertex::edge), over that edge, or -1 where none is
// known: 0 for an exact plane given by its normal (the horizon and the tiles: no input
// point makes it); Core::input_tilt for an input edge of fragment f (the piece's edge
// lies on that edge, so within the wedge of its two input points, where input_tilt
// holds); -1 for an exact plane through two input points (a piece may be cut by it
// outside their wedge) or without the fragment
R Core::edge_tilt(int64_t code, int64_t f, const RowStats& st) const {
    if (code >= 0) {
        if (f < 0 || st.point == nullptr) return -1;
        const int64_t ib = start_[f] + (code - start_[f] + 1) % count_[f];
        return input_tilt(code, ib, st.point);
    }
    if (st.xp == nullptr) return -1;
    return (*st.xp)[static_cast<size_t>(-1 - code)].kind == 1 ? 0 : -1;
}

// the normal of the plane through p that a piece's edge lies on (edge code as
// Vertex::edge: an input edge of fragment f, or exact plane -1 - k) in quadruple
// precision from the input's doubles, and its condition: |a - p| |b - p| / |m| for a
// plane through two points (the tilt of m is within a few roundoffs times it), 0
// for a plane given by its normal (exact)
void Core::quad_plane(int64_t code, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
                      Quad m[3], Quad* cond) const {
    const double* a;
    const double* b;
    int kind = 0;
    if (code >= 0) {
        const int64_t ib = start_[f] + (code - start_[f] + 1) % count_[f];
        a = &V_[3 * code];
        b = &V_[3 * ib];
    } else {
        const ExactPlane& X = xp[static_cast<size_t>(-1 - code)];
        kind = X.kind;
        a = X.a;
        b = X.b;
    }
    if (kind == 1) {
        for (int k = 0; k < 3; ++k) m[k] = a[k];
        *cond = 0;
        return;
    }
    Quad A[3], B[3];
    for (int k = 0; k < 3; ++k) {
        A[k] = static_cast<Quad>(a[k]) - pp[k];
        B[k] = static_cast<Quad>(b[k]) - pp[k];
    }
    m[0] = A[1] * B[2] - A[2] * B[1];
    m[1] = A[2] * B[0] - A[0] * B[2];
    m[2] = A[0] * B[1] - A[1] * B[0];
    // (a bound's factor: in long double, raised by its few roundoffs)
    const R ml = rough_length(m), al = rough_length(A), bl = rough_length(B);
    *cond = ml > 0 ? static_cast<Quad>(al * bl / ml * (1 + 16 * K_.eps))
                   : static_cast<Quad>(INFINITY);
}

// the length of a quadruple vector, in long double from its coordinates rounded to long
// double: within a few roundoffs of long double (the same exponent range: a nonzero
// vector's is nonzero); for bounds' factors and scales, not for values
R Core::rough_length(const Quad x[3]) {
    const R a = static_cast<R>(x[0]), b = static_cast<R>(x[1]), c = static_cast<R>(x[2]);
    return std::sqrt(a * a + b * b + c * c);
}

// a piece's vertex directions in quadruple precision, for integrate_quad, each with
// a bound on its angle off the planes through p of its two edges (what moves the
// piece's boundary: Core::charge_edges). An input vertex's from its coordinates. A
// computed one where its edges' planes meet: where they are an input edge and the
// exact plane it crosses, as that crossing (a + s (b - a), s from the plane's
// normal: off either plane by a few roundoffs of |a - p| + s |b - a| over the
// distance, however small the angle between them); else as the line m1 x m2, whose
// rounding (8 QUAD_EPS (c1 + c2 + 1) |m1| |m2| / |m1 x m2|, c the normals'
// conditions) grows as the planes close. Either is scaled to its long double length.
// The line is the true vertex wherever the piece's edges are the true ones (the
// topology's errors are the band's, apart), so its bound no longer carries the long
// double cuts' rounding, which on a sliver is absolute (about 1e-18), not relative
// to its value. A vertex keeps its long double direction where its two edges are one
// plane, where the planes are too close to tell, or where the line is farther from
// the long double direction than that direction's bound (a vertex taken as on a plane
// within the band, whose sliver the band's bound holds; or one where two nearly
// parallel planes meet, whose line the long double cut may place far along them):
// there its bound is what it measures off its two edges' planes in quadruple
// precision (Core::measured_off), where that is smaller than the long double one
void Core::refine(const Piece& q, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
                  std::vector<std::array<Quad, 3>>& v, std::vector<R>& err) const {
    const size_t m = q.size();
    v.resize(m);
    err.resize(m);
    // (lengths for bounds and scales: Core::rough_length)
    auto len = [](const Quad* x) { return static_cast<Quad>(rough_length(x)); };
    // the plane of each of the piece's edges (edge k: from vertex k to k + 1), its
    // condition and its normal's length, each computed once where first asked for
    // (every computed vertex asks for its two edges')
    struct EdgePlane {
        Quad m[3], cond, length;
        bool have = false, have_length = false;
    };
    thread_local std::vector<EdgePlane> planes;
    planes.assign(m, EdgePlane{});
    auto plane_of = [&](size_t k) -> EdgePlane& {
        EdgePlane& P = planes[k];
        if (!P.have) {
            quad_plane(q[k].edge, f, pp, xp, P.m, &P.cond);
            P.have = true;
        }
        return P;
    };
    auto length_of = [&](size_t k) -> Quad {
        EdgePlane& P = plane_of(k);
        if (!P.have_length) {
            P.length = len(P.m);
            P.have_length = true;
        }
        return P.length;
    };
    // the line where vertex i's two edges' planes meet (edges k1 into it, k2 out of it),
    // as its direction and bound, where it is within the long double direction's bound
    // of it: whether it is
    auto line = [&](size_t i, size_t k1, size_t k2) -> bool {
        const Vertex& u = q[i];
        const int64_t e1 = q[k1].edge, e2 = q[k2].edge;
        Quad d[3], dl;
        R e;
        const int64_t cut = -1 - u.on_plane;
        if (u.on_edge >= 0 && u.on_plane >= 0 &&
            ((e1 == u.on_edge && e2 == cut) || (e2 == u.on_edge && e1 == cut))) {
            // the crossing of input edge a -> b with the exact plane
            const int64_t ia = u.on_edge;
            const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
            const EdgePlane& P = plane_of(e2 == cut ? k2 : k1);
            const Quad* mp = P.m;
            const Quad c = P.cond;
            Quad A[3], Bm[3];
            for (int k = 0; k < 3; ++k) {
                A[k] = static_cast<Quad>(V_[3 * ia + k]) - pp[k];
                Bm[k] = static_cast<Quad>(V_[3 * ib + k]) - V_[3 * ia + k];
            }
            const Quad den = mp[0] * Bm[0] + mp[1] * Bm[1] + mp[2] * Bm[2];
            if (!(den != 0) || !(c < static_cast<Quad>(INFINITY))) return false;
            const Quad sp = -(mp[0] * A[0] + mp[1] * A[1] + mp[2] * A[2]) / den;
            for (int k = 0; k < 3; ++k) d[k] = A[k] + sp * Bm[k];
            dl = len(d);
            if (!(dl > 0)) return false;
            // off the edge's plane: the sum's rounding; off the exact plane, also
            // s's (its two dot products, each within 4 roundoffs of |m| |x|) and the
            // normal's tilt
            const Quad W = len(A) + q_abs(sp) * len(Bm);
            e = static_cast<R>(QUAD_EPS * (16 * W / dl + 8 * c + 4)) * (1 + 16 * K_.eps);
        } else {
            const EdgePlane& P1 = plane_of(k1);
            const EdgePlane& P2 = plane_of(k2);
            const Quad* m1 = P1.m;
            const Quad* m2 = P2.m;
            const Quad c1 = P1.cond, c2 = P2.cond;
            d[0] = m1[1] * m2[2] - m1[2] * m2[1];
            d[1] = m1[2] * m2[0] - m1[0] * m2[2];
            d[2] = m1[0] * m2[1] - m1[1] * m2[0];
            dl = len(d);
            const Quad l1 = length_of(k1), l2 = length_of(k2);
            if (!(dl > 0) || !(l1 > 0) || !(l2 > 0)) return false;
            e = static_cast<R>(8 * QUAD_EPS * (c1 + c2 + 1) * (l1 * l2 / dl)) * (1 + 16 * K_.eps);
        }
        e += 2 * static_cast<R>(QUAD_EPS);  // and the scaling below
        if (!(e < err[i])) return false;
        if (d[0] * v[i][0] + d[1] * v[i][1] + d[2] * v[i][2] < 0)
            for (int k = 0; k < 3; ++k) d[k] = -d[k];
        // (|d| as above: a flipped sign leaves its squares as they were)
        const Quad s = static_cast<Quad>(u.length) / dl;
        const V3 dr{static_cast<R>(d[0] * s), static_cast<R>(d[1] * s),
                    static_cast<R>(d[2] * s)};
        // the line must lie within the long double direction's bound of it (with the
        // rounding of this test: the angle, and dr's rounding to long double)
        const R apart = std::atan2(norm(cross(dr, u.v)), dot(dr, u.v));
        if (!(apart <= err[i] + e + 16 * K_.eps)) return false;
        for (int k = 0; k < 3; ++k) v[i][k] = d[k] * s;
        err[i] = e;
        return true;
    };
    for (size_t i = 0; i < m; ++i) {
        const Vertex& u = q[i];
        if (u.id >= 0) {
            for (int k = 0; k < 3; ++k) v[i][k] = static_cast<Quad>(V_[3 * u.id + k]) - pp[k];
            err[i] = 4 * static_cast<R>(QUAD_EPS);  // the differences' rounding, if any
            continue;
        }
        v[i] = {static_cast<Quad>(u.v.x), static_cast<Quad>(u.v.y), static_cast<Quad>(u.v.z)};
        err[i] = std::max(u.err, u.err_line);
        const size_t k1 = (i + m - 1) % m, k2 = i;  // the edges into and out of it
        if (q[k1].edge == u.edge || line(i, k1, k2)) continue;
        // the long double direction kept: its bound measured off the two planes
        const EdgePlane& P1 = plane_of(k1);
        const EdgePlane& P2 = plane_of(k2);
        const R off = std::max(measured_off(P1.m, length_of(k1), P1.cond, v[i]),
                               measured_off(P2.m, length_of(k2), P2.cond, v[i]));
        if (off < err[i]) err[i] = off;
    }
}

// the angle by which direction x (exact in quadruple precision) is off the plane
// through p of normal m (quadruple precision, of length ml and condition cond, as
// Core::quad_plane gives them), bounded from above: |m . x| / (|m| |x|) within a few
// roundoffs (relative, and of |m| |x| for the dot product), plus m's tilt off the
// exact normal (8 cond roundoffs, as Core::refine charges a crossing), as an angle
// (asin(s) <= 1.01 s for s <= 0.1; else any angle, pi)
R Core::measured_off(const Quad m[3], Quad ml, Quad cond, const std::array<Quad, 3>& x) {
    const Quad xl = static_cast<Quad>(rough_length(x.data()));
    if (!(ml > 0) || !(xl > 0) || !(cond < static_cast<Quad>(INFINITY)))
        return static_cast<R>(HUGE_VAL);
    const Quad s = q_abs(m[0] * x[0] + m[1] * x[1] + m[2] * x[2]) / (ml * xl);
    // (the lengths within a few roundoffs of long double: Core::rough_length)
    const Quad sin_off = s * (1 + 16 * static_cast<Quad>(std::numeric_limits<R>::epsilon())) +
                         QUAD_EPS * (8 * cond + 8);
    // (rounded up to long double)
    return turn_bound(static_cast<R>(sin_off) * (1 + 4 * std::numeric_limits<R>::epsilon()));
}

}  // namespace exactff
