// The vertex-edge visibility events of an occluded pair (exactff/area/, _event_lines: the
// reference, docs/explanation/area-form-factors.md). For a vertex v of one polygon of the
// pair and an edge (e0, e1) of another, the plane through v and the edge,
// m . (x - v) = 0 with m = (e0 - v) x (e1 - v), meets the emitter's plane n . x = dP in
// a line; the points of that line from which v is seen on the edge are the segment
// between the images of e0 and e1 through v, x_i = v + ((dP - n . v) / (n . (e_i - v)))
// (e_i - v), or the whole chord of the disk where the image passes through infinity
// (n . (e0 - v) and n . (e1 - v) of opposite signs, or either within ray_parallel of 0).
// Each polygon's own plane adds its line (a whole chord). The line's point nearest the
// disk's centre c solves the 3 x 3 system n . x = dP, m . x = m . v, d . x = d . c with
// d = n x m (its direction), by Gaussian elimination with partial pivoting; the chord's
// half length is sqrt(radius^2 - |x0 - c|^2).

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "expansion.h"
#include "pair.h"
#include "vec.h"

namespace exactff {
namespace {

using D3 = Vec3<double>;

D3 at(const double* p) { return {p[0], p[1], p[2]}; }
D3 add(const D3& a, const D3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 scale(double s, const D3& a) { return {s * a.x, s * a.y, s * a.z}; }

// the sign of det(b - a, c - a), the side of c of the line through a and b: a double
// filter (Shewchuk's bound for orient2d), else exactly (expansion.h)
int orient2(double ax, double ay, double bx, double by, double cx, double cy) {
    const double l = (bx - ax) * (cy - ay), r = (by - ay) * (cx - ax), det = l - r;
    const double bound = 3.3306690738754716e-16 * (std::fabs(l) + std::fabs(r));
    if (det > bound || -det > bound) return det > 0 ? 1 : -1;
    const Expansion e = add(mul(diff(bx, ax), diff(cy, ay)), neg(mul(diff(by, ay), diff(cx, ax))));
    return sign(e);
}

// whether p (on the line through a and b) lies in the closed segment (a, b)
bool within(double ax, double ay, double bx, double by, double px, double py) {
    return std::min(ax, bx) <= px && px <= std::max(ax, bx) && std::min(ay, by) <= py &&
           py <= std::max(ay, by);
}

// whether the closed segments (a, b) and (p, q) meet
bool segments_meet(double ax, double ay, double bx, double by, double px, double py, double qx,
                   double qy) {
    const int o1 = orient2(ax, ay, bx, by, px, py), o2 = orient2(ax, ay, bx, by, qx, qy);
    const int o3 = orient2(px, py, qx, qy, ax, ay), o4 = orient2(px, py, qx, qy, bx, by);
    if (o1 * o2 < 0 && o3 * o4 < 0) return true;
    return (o1 == 0 && within(ax, ay, bx, by, px, py)) ||
           (o2 == 0 && within(ax, ay, bx, by, qx, qy)) ||
           (o3 == 0 && within(px, py, qx, qy, ax, ay)) ||
           (o4 == 0 && within(px, py, qx, qy, bx, by));
}

// whether the segment (a, b) meets the polygon Q2 (closed, simple, possibly not convex),
// decided exactly on the doubles (as GEOS's intersects): it crosses or touches an edge,
// or a lies inside (the winding number about a, Sunday's rule)
bool segment_meets(const double* Q2, std::int64_t q, double ax, double ay, double bx,
                   double by) {
    int wn = 0;
    for (std::int64_t i = 0, j = q - 1; i < q; j = i++) {
        const double xi = Q2[2 * i], yi = Q2[2 * i + 1], xj = Q2[2 * j], yj = Q2[2 * j + 1];
        if (segments_meet(ax, ay, bx, by, xj, yj, xi, yi)) return true;
        if (yj <= ay) {
            if (yi > ay && orient2(xj, yj, xi, yi, ax, ay) > 0) ++wn;
        } else if (yi <= ay && orient2(xj, yj, xi, yi, ax, ay) < 0) {
            --wn;
        }
    }
    return wn != 0;
}

// x solving the rows A x = r (3 x 3) by Gaussian elimination with partial pivoting
D3 solve3(std::array<std::array<double, 3>, 3> A, std::array<double, 3> r) {
    for (int k = 0; k < 3; ++k) {
        int p = k;
        for (int i = k + 1; i < 3; ++i)
            if (std::fabs(A[i][k]) > std::fabs(A[p][k])) p = i;
        std::swap(A[k], A[p]);
        std::swap(r[k], r[p]);
        for (int i = k + 1; i < 3; ++i) {
            const double f = A[i][k] / A[k][k];
            for (int j = k; j < 3; ++j) A[i][j] -= f * A[k][j];
            r[i] -= f * r[k];
        }
    }
    double x[3];
    for (int k = 2; k >= 0; --k) {
        double s = r[k];
        for (int j = k + 1; j < 3; ++j) s -= A[k][j] * x[j];
        x[k] = s / A[k][k];
    }
    return {x[0], x[1], x[2]};
}

// an event before it is cut to the disk: its plane's normal m, a point v of the plane,
// and where spanned, the ends of its segment in P's plane
struct Event {
    D3 m, v, s0, s1;
    bool spanned;
};

}  // namespace

EventResult event_lines(const EventArgs& a) {
    EventResult out;
    const std::int64_t n = a.n;
    const D3 nP = at(a.nP), nQ = at(a.nQ), q0 = at(a.q0), c = at(a.c);
    const D3 t1 = at(a.RQ), t2 = at(a.RQ + 3);
    const double* W = a.W;
    std::vector<Event> ev;
    for (std::int64_t pa = 0; pa < n; ++pa) {
        // the polygon's own plane, through its first vertex
        const D3 f = at(W + 3 * a.start[pa]);
        ev.push_back({cross(sub(at(W + 3 * (a.start[pa] + 1)), f),
                            sub(at(W + 3 * (a.start[pa] + 2)), f)),
                      f, {0, 0, 0}, {0, 0, 0}, false});
        for (std::int64_t pb = 0; pb < n; ++pb) {
            if (pb == pa) continue;
            const std::int64_t ka = a.start[pa + 1] - a.start[pa];
            const std::int64_t kb = a.start[pb + 1] - a.start[pb];
            if (a.shortcuts && a.solid && a.solid[pa] >= 0 && a.solid[pa] == a.solid[pb]) {
                // two faces of one convex solid: their images united change only at the
                // faces' planes
                out.solid_events += ka * kb;
                continue;
            }
            for (std::int64_t i = 0; i < ka; ++i) {
                const D3 v = at(W + 3 * (a.start[pa] + i));
                for (std::int64_t e = 0; e < kb; ++e) {
                    const std::int64_t ei = a.start[pb] + e;
                    const std::int64_t en = e + 1 == kb ? a.start[pb] : ei + 1;
                    const D3 e0 = at(W + 3 * ei), e1 = at(W + 3 * en);
                    const D3 u0 = sub(e0, v), u1 = sub(e1, v);
                    const D3 m = cross(u0, u1);
                    if (m.x == 0 && m.y == 0 && m.z == 0) continue;
                    if (a.shortcuts && pa > 0 && pb > 0) {
                        // between two blockers, the lines through v and the points of the
                        // edge meet Q's plane along the edge's central image from v: an
                        // event only where that image meets the receiver (unbounded: kept)
                        const double d0 = dot(u0, nQ), d1 = dot(u1, nQ);
                        if (d0 * d1 > 0) {
                            const double h = dot(sub(q0, v), nQ);
                            const D3 ia = sub(add(v, scale(h / d0, u0)), q0);
                            const D3 ib = sub(add(v, scale(h / d1, u1)), q0);
                            if (!segment_meets(a.Q2, a.n_q2, dot(ia, t1), dot(ia, t2),
                                               dot(ib, t1), dot(ib, t2))) {
                                ++out.culled_events;
                                continue;
                            }
                        }
                    }
                    // the images of e0 and e1 through v on P's plane
                    const double den0 = dot(u0, nP), den1 = dot(u1, nP);
                    const bool ok = std::fabs(den0) >= a.ray_parallel * norm(u0) &&
                                    std::fabs(den1) >= a.ray_parallel * norm(u1) &&
                                    den0 * den1 > 0;
                    Event E{m, v, {0, 0, 0}, {0, 0, 0}, ok};
                    if (ok) {
                        const double h = a.dP - dot(v, nP);
                        E.s0 = add(v, scale(h / den0, u0));
                        E.s1 = add(v, scale(h / den1, u1));
                    }
                    ev.push_back(E);
                }
            }
        }
    }
    const D3 r1 = at(a.frame), r2 = at(a.frame + 3);
    std::vector<std::array<double, 4>> segs;
    segs.reserve(ev.size());
    for (const Event& E : ev) {
        // the normal scaled by its largest component (tiny coordinates would underflow in
        // its norm), one orientation for either side
        const double big = std::max({std::fabs(E.m.x), std::fabs(E.m.y), std::fabs(E.m.z)});
        if (!(big > 0)) continue;
        D3 m{E.m.x / big, E.m.y / big, E.m.z / big};
        const double first = m.x != 0 ? m.x : m.y != 0 ? m.y : m.z;
        if (!(first > 0)) m = neg(m);
        D3 d = cross(nP, m);
        const double dn = norm(d);
        if (!(dn >= a.event_parallel * norm(m))) continue;
        d = {d.x / dn, d.y / dn, d.z / dn};
        const D3 x0 = solve3({{{nP.x, nP.y, nP.z}, {m.x, m.y, m.z}, {d.x, d.y, d.z}}},
                             {a.dP, dot(m, E.v), dot(d, c)});
        const D3 w = sub(x0, c);
        const double h2 = a.radius * a.radius - dot(w, w);
        if (!(h2 > 0)) continue;
        const double half = std::sqrt(h2);
        D3 lo = sub(x0, scale(half, d)), hi = add(x0, scale(half, d));
        if (E.spanned) {
            // the span's ends where they lie on the chord (segments that meet there join
            // exactly), else the chord's ends
            D3 s0 = E.s0, s1 = E.s1;
            double ta = dot(sub(s0, x0), d), tb = dot(sub(s1, x0), d);
            if (tb < ta) {
                std::swap(ta, tb);
                std::swap(s0, s1);
            }
            if (!(ta < half && tb > -half)) continue;
            if (ta > -half) lo = s0;
            if (tb < half) hi = s1;
        }
        const D3 p = sub(lo, c), q = sub(hi, c);
        std::array<double, 4> s{dot(p, r1), dot(p, r2), dot(q, r1), dot(q, r2)};
        if (s[0] > s[2] || (s[0] == s[2] && s[1] > s[3])) s = {s[2], s[3], s[0], s[1]};
        for (double& x : s) x += 0.0;   // -0.0 is 0.0
        segs.push_back(s);
    }
    std::sort(segs.begin(), segs.end());
    segs.erase(std::unique(segs.begin(), segs.end()), segs.end());
    out.segments.reserve(4 * segs.size());
    for (const auto& s : segs) out.segments.insert(out.segments.end(), s.begin(), s.end());
    return out;
}

}  // namespace exactff
