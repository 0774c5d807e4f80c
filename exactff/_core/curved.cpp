// The curved visibility events of an occluded pair (pair.h, curved_event_lines), compiled:
// the same steps, in the same order, as exactff/area/curved.py's curved_event_lines, which
// stays the reference (tests/test_area_pair_compiled.py compares the chords of every
// occluded pair of gunter1 and the 106-surface box). For three mutually skew edges, two
// of different blockers (a0 + v da, b0 + v db) and one of the receiver's part
// (y = q0 + s dq), the line through y meeting both blocker edges has the direction
// d = ((a0 - y) x da) x ((b0 - y) x db) (the two planes through y and each edge meet in
// it) and meets the emitter's plane n . x = dP at x(s) = y + ((dP - n . y) / (n . d)) d:
// a conic, traced in s and cut into chords.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "pair.h"
#include "pair_vec.h"
#include "vec.h"

namespace exactff {
namespace {

using pair_vec::D3;
using pair_vec::add;
using pair_vec::scale;
using pair_vec::at;
// the reference's a . b (numpy's einsum over the last axis of 3: its two lanes' sums, the
// first and third products, then the second), so that its decisions (an interval of s
// empty or not, a point on which side) are taken on the same doubles
double inner(const D3& a, const D3& b) { return (a.x * b.x + a.z * b.z) + a.y * b.y; }

// whether the lines p0 + u dp and r0 + v dr are skew: |(r0 - p0) . (dp x dr)| more than
// near |dp x dr| (parallel lines: never), as curved.py's _skew
bool skew(const D3& p0, const D3& dp, const D3& r0, const D3& dr, double near) {
    const D3 n = cross(dp, dr);
    return std::fabs(inner(sub(r0, p0), n)) > near * std::sqrt(inner(n, n));
}

// geometry.unit_normal: the area vector over its length
D3 unit_normal(const double* P, std::int64_t k) {
    const D3 A = fan_area_vector<double>(k, [&](std::int64_t i) { return at(P + 3 * i); });
    const double L = norm(A);
    return {A.x / L, A.y / L, A.z / L};
}

// one blocker edge: its start, direction and end
struct Edge {
    D3 e0, de, e1;
};

// the line through y meeting the edges a and b: where it meets P's plane (x) and whether
// it meets both edges between x and y (curved.py's _transversal)
struct Transversal {
    D3 x;
    bool ok;
};

Transversal transversal(const D3& y, const Edge& a, const Edge& b, const D3& nP, double dP) {
    const D3 d = cross(cross(sub(a.e0, y), a.de), cross(sub(b.e0, y), b.de));
    const double t = (dP - inner(y, nP)) / inner(d, nP);
    Transversal r{add(y, scale(t, d)), std::isfinite(t)};
    for (const Edge* e : {&a, &b}) {
        // the points of closest approach of y + u d and e0 + v de (they meet)
        const D3 w = sub(y, e->e0);
        const double A = inner(d, d), B = inner(d, e->de), C = inner(e->de, e->de);
        const double Dd = inner(d, w), E = inner(e->de, w);
        const double den = A * C - B * B;
        const double u = (B * E - C * Dd) / den, v = (A * E - B * Dd) / den;
        r.ok = r.ok && v >= 0 && v <= 1 && u / t > 0 && u / t < 1;
    }
    return r;
}

// one triple: the receiver's edge (q0, dq) and two blocker edges (indices)
struct Triple {
    D3 q0, dq;
    std::int64_t a, b;
};

// a piece of a curve where it is an event: its triple, its ends in s, whether each end is
// lengthened, and (before the disk's bisection) the midpoint of its interval
struct Piece {
    std::int64_t k;
    double lo, hi, mid;
    bool ext_lo, ext_hi;
};

// ||x(s) - c||^2 (NaN where x is at infinity: curved.py's far_at)
double far_at(const Triple& T, const Edge& a, const Edge& b, double s, const D3& nP, double dP,
              const D3& c) {
    const D3 y = add(T.q0, scale(s, T.dq));
    const D3 d = cross(cross(sub(a.e0, y), a.de), cross(sub(b.e0, y), b.de));
    const D3 x = sub(add(y, scale((dP - inner(y, nP)) / inner(d, nP), d)), c);
    return inner(x, x);
}

// the s where the curve may start or stop being an event (curved.py's breaks), clipped to
// [0, 1] (NaN: 0, infinities: the nearer end)
void breaks(const Triple& T, const Edge& A, const Edge& B, const D3& nP, double dP,
            std::vector<double>& out) {
    const D3 Q0 = T.q0, DQ = T.dq;
    const auto through = [&](const D3& p, const D3& l0, const D3& dl) {
        const D3 n = cross(sub(p, l0), dl);
        out.push_back(-inner(sub(Q0, l0), n) / inner(DQ, n));
    };
    for (int o = 0; o < 2; ++o) {
        const Edge& L = o ? B : A;
        const Edge& M = o ? A : B;
        through(L.e0, M.e0, M.de);
        through(add(L.e0, L.de), M.e0, M.de);
        through(add(L.e0, scale((dP - inner(L.e0, nP)) / inner(L.de, nP), L.de)), M.e0, M.de);
        out.push_back(inner(cross(sub(M.e0, Q0), M.de), L.de) / inner(cross(DQ, M.de), L.de));
        const D3 w = sub(Q0, L.e0);
        const double a_ = inner(DQ, DQ), b_ = inner(DQ, L.de), c_ = inner(L.de, L.de),
                     d_ = inner(DQ, w), e_ = inner(L.de, w);
        out.push_back((b_ * e_ - c_ * d_) / (a_ * c_ - b_ * b_));
    }
    // the line through y parallel to P's plane: d(s) . nP = c0 + c1 s + c2 s^2
    const D3 A0v = cross(sub(A.e0, Q0), A.de), A1v = cross(DQ, A.de);
    const D3 B0v = cross(sub(B.e0, Q0), B.de), B1v = cross(DQ, B.de);
    const double c0 = inner(cross(A0v, B0v), nP);
    const double c1 = -inner(add(cross(A0v, B1v), cross(A1v, B0v)), nP);
    const double c2 = inner(cross(A1v, B1v), nP);
    const double root = std::sqrt(std::max(c1 * c1 - 4 * c2 * c0, 0.0));
    out.push_back((-c1 - root) / (2 * c2));
    out.push_back((-c1 + root) / (2 * c2));
    out.push_back(-c0 / c1);
    for (double& s : out) s = std::isnan(s) ? 0.0 : std::min(std::max(s, 0.0), 1.0);
}

}  // namespace

CurvedResult curved_event_lines(const CurvedArgs& a) {
    CurvedResult res;
    const std::int64_t nb = a.n - 1;  // the blockers: S[1:]
    if (nb < 2) return res;
    const D3 nP = at(a.nP), c = at(a.c);
    const double dP = a.dP, radius = a.radius;
    const double* W = a.W;
    // the blockers' edges, their owners and solids
    std::vector<Edge> E;
    std::vector<std::int64_t> owner, group, off_vertex;
    for (std::int64_t p = 1; p <= nb; ++p) {
        const std::int64_t s0 = a.start[p], k = a.start[p + 1] - s0;
        for (std::int64_t i = 0; i < k; ++i) {
            const D3 e0 = at(W + 3 * (s0 + i)), e1 = at(W + 3 * (s0 + (i + 1) % k));
            E.push_back({e0, sub(e1, e0), e1});
            owner.push_back(p - 1);
            group.push_back(a.solid ? a.solid[p] : -1);
            off_vertex.push_back(s0 + (i + 2) % k);  // a vertex of the face off the edge
        }
    }
    const std::int64_t ne = static_cast<std::int64_t>(E.size());
    // the size of the blockers' and Qc's box
    double size = 0;
    for (int ax = 0; ax < 3; ++ax) {
        double lo = E[0].e0[ax], hi = lo;
        for (const Edge& e : E) lo = std::min(lo, e.e0[ax]), hi = std::max(hi, e.e0[ax]);
        for (std::int64_t q = 0; q < a.n_q; ++q)
            lo = std::min(lo, a.Qc[3 * q + ax]), hi = std::max(hi, a.Qc[3 * q + ax]);
        size = std::max(size, hi - lo);
    }
    const double near = a.hull_rtol * size;
    // an edge two faces share (a box's) once: each edge's copy id (its ends from the least,
    // the same doubles), the number of copies and the off-edge vertex of the first two
    std::vector<std::int64_t> cid(ne);
    std::vector<std::int64_t> count, firsts, seconds;
    {
        std::map<std::array<double, 6>, std::int64_t> ids;
        for (std::int64_t i = 0; i < ne; ++i) {
            const D3& d = E[i].de;
            const double lead = d.x != 0 ? d.x : d.y != 0 ? d.y : d.z;
            const D3& p = lead < 0 ? E[i].e1 : E[i].e0;
            const D3& q = lead < 0 ? E[i].e0 : E[i].e1;
            const std::array<double, 6> key{p.x, p.y, p.z, q.x, q.y, q.z};
            auto it = ids.find(key);
            if (it == ids.end()) {
                it = ids.emplace(key, static_cast<std::int64_t>(count.size())).first;
                count.push_back(0);
                firsts.push_back(i);
                seconds.push_back(i);
            }
            cid[i] = it->second;
            if (++count[it->second] == 2) seconds[it->second] = i;
        }
    }
    // the pairs of edges of different polygons (not of one solid), their lines skew and not
    // parallel, each pair of copies once, in order
    std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
    {
        std::map<std::pair<std::int64_t, std::int64_t>, bool> seen;
        for (std::int64_t i = 0; i < ne; ++i) {
            for (std::int64_t j = i + 1; j < ne; ++j) {
                if (owner[i] == owner[j] || (group[i] >= 0 && group[i] == group[j])) continue;
                const Edge &A = E[i], &B = E[j];
                // lines that meet or are coplanar trace straight lines (vertex-edge events)
                if (!skew(A.e0, A.de, B.e0, B.de, near)) continue;
                if (!(norm(cross(A.de, B.de)) > a.event_parallel * norm(A.de) * norm(B.de)))
                    continue;
                const std::int64_t lo = std::min(cid[i], cid[j]), hi = std::max(cid[i], cid[j]);
                if (!seen.emplace(std::make_pair(lo, hi), true).second || lo == hi) continue;
                pairs.emplace_back(i, j);
            }
        }
    }
    // per edge of Qc, the blocker edges that may meet a line from P to it: not wholly behind
    // P's plane (within its disk), nor outside the wedge of the planes through the edge that
    // support the disk's square around P (the lines from P to the edge lie in it)
    const D3 r0 = at(a.frame), r1 = at(a.frame + 3);
    D3 Pr[4];
    const double sg[4][2] = {{1, 1}, {1, -1}, {-1, -1}, {-1, 1}};
    for (int k = 0; k < 4; ++k) {
        const double s0 = radius * sg[k][0], s1 = radius * sg[k][1];
        Pr[k] = add(c, {s0 * r0.x + s1 * r1.x, s0 * r0.y + s1 * r1.y, s0 * r0.z + s1 * r1.z});
    }
    std::vector<unsigned char> behind(ne);
    for (std::int64_t e = 0; e < ne; ++e)
        behind[e] = std::max(inner(E[e].e0, nP), inner(E[e].e1, nP)) <= dP + near;
    std::vector<Triple> triples;
    std::vector<unsigned char> out(ne);
    for (std::int64_t q = 0; q < a.n_q; ++q) {
        const D3 q0 = at(a.Qc + 3 * q), dq = sub(at(a.Qc + 3 * ((q + 1) % a.n_q)), q0);
        for (std::int64_t e = 0; e < ne; ++e) out[e] = behind[e];
        for (int k = 0; k < 4; ++k) {
            D3 N = cross(dq, sub(Pr[k], q0));
            const double m = near * norm(N);
            bool all_le = true, all_ge = true;
            for (int p = 0; p < 4; ++p) {
                const double side = inner(N, Pr[p]) - inner(N, q0);
                all_le = all_le && side <= m;
                all_ge = all_ge && side >= -m;
            }
            if (!(all_le || all_ge)) continue;
            if (all_le) N = neg(N);
            for (std::int64_t e = 0; e < ne; ++e) {
                const double d0 = inner(N, E[e].e0) - inner(N, q0);
                const double d1 = inner(N, E[e].e1) - inner(N, q0);
                if (d0 < -m && d1 < -m) out[e] = 1;
            }
        }
        // a blocker edge whose line meets Qc's edge's (or is parallel to it): no curve
        for (std::int64_t e = 0; e < ne; ++e)
            if (!skew(q0, dq, E[e].e0, E[e].de, near)) out[e] = 1;
        for (const auto& p : pairs)
            if (!out[p.first] && !out[p.second]) triples.push_back({q0, dq, p.first, p.second});
    }
    const std::int64_t nt = static_cast<std::int64_t>(triples.size());
    if (!nt) return res;
    if (nt > a.max_triples) {
        // too many to trace (their chords would swamp the arrangement): the rules meet these
        // kinks uncut, counted
        res.skipped = true;
        return res;
    }
    const double reach2 = (4.0 * radius) * (4.0 * radius);
    const auto curve_at = [&](std::int64_t k, double s) {
        const Triple& T = triples[k];
        return transversal(add(T.q0, scale(s, T.dq)), E[T.a], E[T.b], nP, dP);
    };
    const auto inside = [&](const D3& x) {
        const D3 r = sub(x, c);
        return inner(r, r) <= reach2;
    };
    const auto far = [&](std::int64_t k, double s) {
        const Triple& T = triples[k];
        return far_at(T, E[T.a], E[T.b], s, nP, dP, c);
    };
    const std::int64_t G = a.samples;
    // the triples in batches (as the reference's, whose bisections stop for a whole batch)
    const std::int64_t per = std::max<std::int64_t>(1, a.rows_per_call / (3 * G + 48));
    const std::int64_t n_batch = std::max<std::int64_t>(1, nt / per);
    std::vector<Piece> pieces;
    std::vector<double> s, br;
    std::int64_t k_begin = 0;
    for (std::int64_t bt = 0; bt < n_batch; ++bt) {
        // numpy's array_split: the first nt % n_batch batches one longer
        const std::int64_t len = nt / n_batch + (bt < nt % n_batch ? 1 : 0);
        const std::int64_t k_end = k_begin + len;
        const std::size_t first_piece = pieces.size();
        for (std::int64_t k = k_begin; k < k_end; ++k) {
            // between the breaks (and the steps of the grid) the curve is an event or not
            // throughout, but for the disk
            const Triple& T = triples[k];
            br.clear();
            breaks(T, E[T.a], E[T.b], nP, dP, br);
            s.clear();
            for (std::int64_t g = 0; g <= G; ++g)
                s.push_back(g == G ? 1.0 : static_cast<double>(g) * (1.0 / static_cast<double>(G)));
            s.insert(s.end(), br.begin(), br.end());
            std::sort(s.begin(), s.end());
            const std::size_t ni = s.size() - 1;
            std::vector<unsigned char> ok(ni);
            std::vector<double> mid(ni);
            for (std::size_t j = 0; j < ni; ++j) {
                mid[j] = 0.5 * (s[j] + s[j + 1]);
                const Transversal tr = curve_at(k, mid[j]);
                ok[j] = tr.ok && inside(tr.x) && s[j + 1] > s[j];
            }
            // an end shared with the next event interval is a node of the polyline; any
            // other is lengthened across the line where the curve stops (or leaves the disk)
            for (std::size_t j = 0; j < ni; ++j)
                if (ok[j])
                    pieces.push_back({k, s[j], s[j + 1], mid[j], !(j > 0 && ok[j - 1]),
                                      !(j + 1 < ni && ok[j + 1])});
        }
        // an end outside the disk: the disk's edge by bisection from the midpoint (only x is
        // needed); the bisections stop once every such end of the batch lies beyond twice
        // the radius
        struct End {
            std::size_t piece;
            bool hi;
            double good, bad, far;
        };
        std::vector<End> ends;
        for (int side = 0; side < 2; ++side)
            for (std::size_t p = first_piece; p < pieces.size(); ++p) {
                const Piece& P = pieces[p];
                const double e = side ? P.hi : P.lo;
                if (!(far(P.k, e) <= reach2)) ends.push_back({p, side == 1, P.mid, e, 0.0});
            }
        if (!ends.empty()) {
            for (End& e : ends) e.far = far(pieces[e.piece].k, e.good);
            const double beyond = (2.0 * radius) * (2.0 * radius);
            for (std::int64_t it = 0; it < a.bisections; ++it) {
                bool all_beyond = true;
                for (const End& e : ends) all_beyond = all_beyond && e.far >= beyond;
                if (all_beyond) break;
                for (End& e : ends) {
                    const double half = 0.5 * (e.good + e.bad);
                    const double h_far = far(pieces[e.piece].k, half);
                    if (h_far <= reach2) {
                        e.good = half;
                        e.far = h_far;
                    } else {
                        e.bad = half;
                    }
                }
            }
            for (const End& e : ends) {
                Piece& P = pieces[e.piece];
                (e.hi ? P.hi : P.lo) = e.good;
                (e.hi ? P.ext_hi : P.ext_lo) = false;
            }
        }
        k_begin = k_end;
    }
    if (pieces.empty()) return res;
    // the chords: each piece cut in steps of s so that the midpoint's distance from its
    // chord (which falls as the square of the step) is within the allowed deviation
    const double sq = std::sqrt(a.atol);
    const double dev_allowed = radius * std::min(a.curve_rtol, sq != 0 ? sq : INFINITY);
    const auto frame2 = [&](const D3& x, double& u, double& v) {
        const D3 r = sub(x, c);
        u = r.x * a.frame[0] + r.y * a.frame[1] + r.z * a.frame[2];
        v = r.x * a.frame[3] + r.y * a.frame[4] + r.z * a.frame[5];
    };
    const std::size_t np_ = pieces.size();
    std::vector<std::int64_t> steps(np_), first(np_);
    std::int64_t total = 0;
    for (std::size_t p = 0; p < np_; ++p) {
        const Piece& P = pieces[p];
        double x0, y0, x1, y1, x2, y2;
        frame2(curve_at(P.k, P.lo).x, x0, y0);
        frame2(curve_at(P.k, 0.5 * (P.lo + P.hi)).x, x1, y1);
        frame2(curve_at(P.k, P.hi).x, x2, y2);
        const double cx = x2 - x0, cy = y2 - y0, ox = x1 - x0, oy = y1 - y0;
        const double length = std::hypot(cx, cy);
        double dev = length > 0 ? std::fabs(cx * oy - cy * ox) / length : std::hypot(ox, oy);
        if (std::isnan(dev)) dev = 0.0;
        if (std::isinf(dev)) dev = std::numeric_limits<double>::max();
        const double st = std::ceil(std::sqrt(dev / dev_allowed));
        steps[p] = static_cast<std::int64_t>(std::min(std::max(st, 1.0), 4096.0));
    }
    // then each step whose own midpoint lies farther from its chord than chord_split of the
    // allowed deviation halved, up to chord_halvings times (the piece's midpoint says little
    // where its curvature is uneven); depth first here, level by level in the reference:
    // a step's decision rests on its ends alone, so the points are the same
    const double split_dev = a.chord_split * dev_allowed;
    std::vector<double> sv;            // every piece's points' s, piece by piece
    std::vector<std::int64_t> pv;      // and their pieces
    struct Node {
        double s, u, v;
    };
    const auto node = [&](std::int64_t k, double sj) {
        Node n{sj, 0.0, 0.0};
        frame2(curve_at(k, sj).x, n.u, n.v);
        return n;
    };
    for (std::size_t p = 0; p < np_; ++p) {
        const Piece& P = pieces[p];
        first[p] = static_cast<std::int64_t>(sv.size());
        Node left = node(P.k, P.lo);
        sv.push_back(P.lo);
        pv.push_back(static_cast<std::int64_t>(p));
        for (std::int64_t j = 1; j <= steps[p]; ++j) {
            const double frac = static_cast<double>(j) / static_cast<double>(steps[p]);
            const double sj = j == steps[p] ? P.hi : P.lo + (P.hi - P.lo) * frac;
            const Node right = node(P.k, sj);
            // the step (left, right) and its halves, depth first: the right ends still to
            // reach, each with the depth of the step it ends
            std::vector<std::pair<Node, std::int64_t>> todo{{right, 0}};
            Node at_ = left;
            while (!todo.empty()) {
                const Node r = todo.back().first;
                const std::int64_t depth = todo.back().second;
                bool halve = false;
                Node m{};
                if (depth < a.chord_halvings) {
                    m = node(P.k, 0.5 * (at_.s + r.s));
                    const double cx = r.u - at_.u, cy = r.v - at_.v;
                    const double ox = m.u - at_.u, oy = m.v - at_.v;
                    const double length = std::hypot(cx, cy);
                    double d = length > 0 ? std::fabs(cx * oy - cy * ox) / length
                                          : std::hypot(ox, oy);
                    if (std::isnan(d)) d = 0.0;
                    halve = d > split_dev;
                }
                if (halve) {
                    todo.back().second = depth + 1;     // r, after the left half
                    todo.push_back({m, depth + 1});
                    continue;
                }
                todo.pop_back();
                sv.push_back(r.s);
                pv.push_back(static_cast<std::int64_t>(p));
                at_ = r;
            }
            left = right;
        }
        steps[p] = static_cast<std::int64_t>(sv.size()) - first[p] - 1;
    }
    total = static_cast<std::int64_t>(sv.size());
    // every piece's points, in P's frame (Y) and on Qc's edge (y), and whether each is seen:
    // the line of sight from x to y crosses no blocker (within its rounding) and, for an
    // edge two faces share, the faces' images do not lie either side of the edge's
    std::vector<D3> X(total), Yq(total);
    std::vector<double> Y(2 * total);
    std::vector<std::int64_t> tri(total);
    for (std::int64_t i = 0; i < total; ++i) {
        const Piece& P = pieces[pv[i]];
        const Triple& T = triples[P.k];
        X[i] = curve_at(P.k, sv[i]).x;
        Yq[i] = add(T.q0, scale(sv[i], T.dq));
        frame2(X[i], Y[2 * i], Y[2 * i + 1]);
        tri[i] = P.k;
    }
    std::vector<unsigned char> seen(total, 1);
    // per point, the polygons whose edges its line touches (each copy's: an edge two faces
    // share bounds both), which it meets on those edges (a crossing of their interiors is
    // rounding, as where the line grazes a plane): not tested
    const auto own = [&](std::int64_t i, std::int64_t b) {
        const Triple& T = triples[tri[i]];
        for (const std::int64_t e : {T.a, T.b}) {
            const std::int64_t id = cid[e];
            if (owner[firsts[id]] == b || (count[id] > 1 && owner[seconds[id]] == b))
                return true;
        }
        return false;
    };
    // the blockers' unit normals and their projections on the two axes off the normal's
    // largest component
    for (std::int64_t b = 1; b <= nb; ++b) {
        const std::int64_t s0 = a.start[b], k = a.start[b + 1] - s0;
        const double* A = W + 3 * s0;
        const D3 n = unit_normal(A, k);
        const D3 a0 = at(A);
        int big = 0;
        for (int ax = 1; ax < 3; ++ax)
            if (std::fabs(n[ax]) > std::fabs(n[big])) big = ax;
        const int k0 = big == 0 ? 1 : 0, k1 = big == 2 ? 1 : 2;
        for (std::int64_t i = 0; i < total; ++i) {
            const double hX = inner(sub(X[i], a0), n), hY = inner(sub(Yq[i], a0), n);
            if (!(hX * hY < 0 && std::min(std::fabs(hX), std::fabs(hY)) > near)) continue;
            if (own(i, b - 1)) continue;
            const D3 pt = add(X[i], scale(hX / (hX - hY), sub(Yq[i], X[i])));
            const double u = pt[k0], v = pt[k1];
            // the crossing number of a ray in +u, and the distance to the nearest edge
            int crossings = 0;
            double dist = INFINITY;
            for (std::int64_t e = 0; e < k; ++e) {
                const double ax_ = A[3 * e + k0], ay_ = A[3 * e + k1];
                const std::int64_t f = (e + 1) % k;
                const double bx_ = A[3 * f + k0], by_ = A[3 * f + k1];
                if ((ay_ > v) != (by_ > v) && ax_ + (v - ay_) * (bx_ - ax_) / (by_ - ay_) > u)
                    ++crossings;
                const double ex = bx_ - ax_, ey = by_ - ay_, wx = u - ax_, wy = v - ay_;
                const double t = std::min(
                    std::max((wx * ex + wy * ey) / std::max(ex * ex + ey * ey, 1e-300), 0.0), 1.0);
                const double rx = wx - t * ex, ry = wy - t * ey;
                dist = std::min(dist, std::sqrt(rx * rx + ry * ry));
            }
            if (crossings % 2 == 1 && dist > near) seen[i] = 0;
        }
    }
    for (std::int64_t i = 0; i < total; ++i) {
        const Triple& T = triples[tri[i]];
        for (const std::int64_t e : {T.a, T.b}) {
            // an edge two faces share whose faces' images lie either side of its own
            const std::int64_t id = cid[e];
            if (count[id] != 2) continue;
            const D3 n = cross(E[e].de, sub(X[i], E[e].e0));
            const double sa = inner(sub(at(W + 3 * off_vertex[firsts[id]]), E[e].e0), n);
            const double sb = inner(sub(at(W + 3 * off_vertex[seconds[id]]), E[e].e0), n);
            const double m = near * norm(n) * norm(E[e].de);
            if (std::min(std::fabs(sa), std::fabs(sb)) > m && sa * sb < 0) seen[i] = 0;
        }
    }
    // the chords kept: seen at either end, and one chord either side of those
    std::vector<unsigned char> chord(total > 0 ? total - 1 : 0, 1), seen_c, grow_c;
    for (std::size_t p = 0; p + 1 < np_; ++p) chord[first[p] + steps[p]] = 0;
    seen_c.resize(chord.size());
    for (std::size_t i = 0; i < chord.size(); ++i) seen_c[i] = (seen[i] || seen[i + 1]) && chord[i];
    grow_c = seen_c;
    for (std::size_t i = 0; i < chord.size(); ++i) {
        if (i > 0 && seen_c[i - 1]) grow_c[i] = 1;
        if (i + 1 < chord.size() && seen_c[i + 1]) grow_c[i] = 1;
        grow_c[i] = grow_c[i] && chord[i];
    }
    // an end where the curve stops being an event lengthened across that line (the first
    // ends, then the last: a piece of one step has its first end moved first)
    const double step = a.extend_rtol * radius;
    for (int side = 0; side < 2; ++side)
        for (std::size_t p = 0; p < np_; ++p) {
            if (!(side ? pieces[p].ext_hi : pieces[p].ext_lo)) continue;
            const std::int64_t end = side ? first[p] + steps[p] : first[p];
            const std::int64_t nxt = side ? end - 1 : end + 1;
            const double dx = Y[2 * end] - Y[2 * nxt], dy = Y[2 * end + 1] - Y[2 * nxt + 1];
            const double nrm = std::hypot(dx, dy);
            if (!(nrm > 0)) continue;
            Y[2 * end] += step * dx / nrm;
            Y[2 * end + 1] += step * dy / nrm;
        }
    std::vector<unsigned char> traced(nt, 0);
    for (std::size_t i = 0; i < chord.size(); ++i) {
        if (!grow_c[i]) continue;
        traced[tri[i]] = 1;
        const double* q = &Y[2 * i];
        if (std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]) &&
            std::isfinite(q[3]))
            res.segments.insert(res.segments.end(), q, q + 4);
    }
    for (const unsigned char t : traced) res.events += t;
    return res;
}

}  // namespace exactff
