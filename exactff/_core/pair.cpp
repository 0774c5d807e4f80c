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
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "expansion.h"
#include "pair.h"
#include "pair_vec.h"
#include "vec.h"

namespace exactff {
namespace {

using pair_vec::D3;
using pair_vec::at;
using pair_vec::add;
using pair_vec::scale;

// the sign of det(b - a, c - a), the side of c of the line through a and b: a double
// filter (Shewchuk's bound for orient2d), else exactly (expansion.h)
int orient2(double ax, double ay, double bx, double by, double cx, double cy) {
    const double l = (bx - ax) * (cy - ay), r = (by - ay) * (cx - ax), det = l - r;
    const double bound = 3.3306690738754716e-16 * (std::fabs(l) + std::fabs(r));
    if (det > bound || -det > bound) return det > 0 ? 1 : -1;
    // the two products grown in place into one expansion (exact: the same sign as any
    // other exact evaluation, without copying the expansions' storage)
    Expansion e;
    mul_into(e, diff(bx, ax), diff(cy, ay), 1.0);
    mul_into(e, diff(by, ay), diff(cx, ax), -1.0);
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

// the largest of |a.x|, |a.y|, |a.z|
double max_abs(const D3& a) { return std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}); }

// whether v lies on the line of the edge (e0, e1) to rounding, or the edge is a point
// (u0 = e0 - v, u1 = e1 - v, m = u0 x u1; rel: AREA_EVENT_LINE_ULPS units of rounding):
// m within rel X (|e1 - e0| + min(|u0|, |u1|)), X the three points' largest coordinate
// and each length its largest component (events.py's _on_edge_line, the same roundings)
bool on_edge_line(const D3& v, const D3& e0, const D3& e1, const D3& u0, const D3& u1,
                  const D3& m, double rel) {
    const double X = std::max(std::max(max_abs(v), max_abs(e0)), max_abs(e1));
    return max_abs(m) <=
           rel * X * (max_abs(sub(e1, e0)) + std::min(max_abs(u0), max_abs(u1)));
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
                    // v on the edge's line to rounding (or the edge a point): the plane
                    // is rounding's, no event (events.py's _on_edge_line)
                    if (on_edge_line(v, e0, e1, u0, u1, m, a.line_ulps * a.eps)) continue;
                    // an edge (v, w) of pa in the plane (coplanar with the edge): the
                    // event is the two edges' (their images collinear), its lines of
                    // sight pass through every point of (v, w): its images of the edge
                    // from (v, w) sweep the interval between those from v and from w
                    // (the four segments joining their ends), culled only where all of
                    // that misses the receiver (unbounded, or both of pa's edges at v in
                    // the plane: kept)
                    int n_in = 0;
                    D3 wv = v;
                    for (const std::int64_t w : {a.start[pa] + (i + ka - 1) % ka,
                                                 a.start[pa] + (i + 1) % ka}) {
                        const D3 vw = sub(at(W + 3 * w), v);
                        if (std::fabs(dot(m, vw)) <= a.event_parallel * norm(m) * norm(vw)) {
                            if (++n_in == 1) wv = at(W + 3 * w);
                        }
                    }
                    if (a.shortcuts && pa > 0 && pb > 0 && n_in < 2) {
                        // between two blockers, the lines through v and the points of the
                        // edge meet Q's plane along the edge's central image from v: an
                        // event only where that image meets the receiver (unbounded: kept)
                        const double d0 = dot(u0, nQ), d1 = dot(u1, nQ);
                        const D3 w0 = sub(e0, wv), w1 = sub(e1, wv);
                        const double dw0 = dot(w0, nQ), dw1 = dot(w1, nQ);
                        if (d0 * d1 > 0 && (n_in == 0 || (dw0 * dw1 > 0 && d0 * dw0 > 0))) {
                            const double h = dot(sub(q0, v), nQ);
                            const D3 ia = sub(add(v, scale(h / d0, u0)), q0);
                            const D3 ib = sub(add(v, scale(h / d1, u1)), q0);
                            const double ax = dot(ia, t1), ay = dot(ia, t2);
                            const double bx = dot(ib, t1), by = dot(ib, t2);
                            bool meets = segment_meets(a.Q2, a.n_q2, ax, ay, bx, by);
                            if (!meets && n_in == 1) {
                                const double hw = dot(sub(q0, wv), nQ);
                                const D3 ja = sub(add(wv, scale(hw / dw0, w0)), q0);
                                const D3 jb = sub(add(wv, scale(hw / dw1, w1)), q0);
                                const double cx = dot(ja, t1), cy = dot(ja, t2);
                                const double dx = dot(jb, t1), dy = dot(jb, t2);
                                meets = segment_meets(a.Q2, a.n_q2, cx, cy, dx, dy) ||
                                        segment_meets(a.Q2, a.n_q2, ax, ay, cx, cy) ||
                                        segment_meets(a.Q2, a.n_q2, bx, by, dx, dy);
                            }
                            if (!meets) {
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

// The emitter cut along the event lines (the reference: area/events.py's cut_cells with
// GEOS). Each line is cut to P (convex: the parameters where it is inside every edge's
// half-plane), an end within step of P's boundary moved onto it; the lines and P's edges
// are noded at their crossings (nodes within merge of each other are one), dangles
// (nodes of one edge) removed until none is left, and the faces traced by turning at
// each node to the next edge clockwise; each face of positive area above sliver is
// clipped into triangles by ears (its straight-angle vertices dropped first).
namespace {

struct Pt {
    double x, y;
};

double cross2(const Pt& o, const Pt& a, const Pt& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// the ears of a simple polygon (counter-clockwise): false where no ear is found
bool ear_clip(std::vector<Pt> v, double flat, std::vector<double>& out) {
    // straight angles (collinear vertices) dropped: a triangle of no area is no cell
    for (bool again = true; again && v.size() > 3;) {
        again = false;
        for (size_t i = 0; i < v.size() && v.size() > 3; ++i) {
            const Pt& a = v[(i + v.size() - 1) % v.size()];
            const Pt& b = v[(i + 1) % v.size()];
            if (std::fabs(cross2(a, v[i], b)) <= flat) {
                v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
                again = true;
            }
        }
    }
    while (v.size() > 3) {
        const size_t n = v.size();
        bool found = false;
        for (size_t i = 0; i < n; ++i) {
            const Pt& a = v[(i + n - 1) % n];
            const Pt& b = v[i];
            const Pt& c = v[(i + 1) % n];
            if (cross2(a, b, c) <= flat) continue;          // reflex or flat
            bool empty = true;
            for (size_t j = 0; j < n && empty; ++j) {
                if (j == i || j == (i + 1) % n || j == (i + n - 1) % n) continue;
                const Pt& p = v[j];
                if (cross2(a, b, p) >= 0 && cross2(b, c, p) >= 0 && cross2(c, a, p) >= 0)
                    empty = false;
            }
            if (!empty) continue;
            out.insert(out.end(), {a.x, a.y, b.x, b.y, c.x, c.y});
            v.erase(v.begin() + static_cast<std::ptrdiff_t>(i));
            found = true;
            break;
        }
        if (!found) return false;
    }
    if (v.size() == 3 && cross2(v[0], v[1], v[2]) > 0)
        out.insert(out.end(), {v[0].x, v[0].y, v[1].x, v[1].y, v[2].x, v[2].y});
    return true;
}

// the largest extent of P along either axis
double size_of(const std::vector<Pt>& P) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const Pt& p : P) {
        x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
    return std::max(x1 - x0, y1 - y0);
}

// The lines E[first:] on one line joined into their union. Two lines are on one line
// where both ends of the second lie within merge of the first's line; their union is one
// line where they overlap or their ends lie within merge of each other along it (the
// arrangement nodes such ends as one, and a T-junction within merge as on the line, so
// it cuts P the same either way). Candidates are found by sorting on the direction's
// angle (within 4 merge / size) and the offset from the origin (within 4 merge); each is
// checked by the distances above, so a line not joined is only a copy left in.
void merge_collinear(std::vector<std::array<Pt, 2>>& E, size_t first, double merge,
                     double size) {
    const size_t m = E.size() - first;
    if (m < 2 || !(merge > 0) || !(size > 0)) return;
    struct Key {
        double angle, offset;
        size_t i;
    };
    std::vector<Key> keys;
    keys.reserve(m);
    for (size_t i = first; i < E.size(); ++i) {
        double dx = E[i][1].x - E[i][0].x, dy = E[i][1].y - E[i][0].y;
        const double len = std::sqrt(dx * dx + dy * dy);
        if (!(len > 0)) continue;              // a point: no line (no edge of the graph)
        if (dy < 0 || (dy == 0 && dx < 0)) dx = -dx, dy = -dy;       // angle in [0, pi]
        keys.push_back({std::atan2(dy, dx), (dx * E[i][0].y - dy * E[i][0].x) / len, i});
    }
    if (keys.empty()) {
        E.resize(first);
        return;
    }
    std::sort(keys.begin(), keys.end(),
              [](const Key& a, const Key& b) { return a.angle < b.angle; });
    // the directions unwrapped at their largest gap (directions pi apart are one): those
    // before it turned by pi, their offsets negated with their direction
    size_t cut = 0;
    double widest = keys.front().angle + M_PI - keys.back().angle;
    for (size_t j = 1; j < keys.size(); ++j)
        if (keys[j].angle - keys[j - 1].angle > widest)
            widest = keys[j].angle - keys[j - 1].angle, cut = j;
    for (size_t j = 0; j < cut; ++j) keys[j].angle += M_PI, keys[j].offset = -keys[j].offset;
    std::rotate(keys.begin(), keys.begin() + static_cast<std::ptrdiff_t>(cut), keys.end());
    const double angle_tol = 4.0 * merge / size, offset_tol = 4.0 * merge;
    std::vector<std::array<Pt, 2>> joined;
    for (size_t g0 = 0; g0 < keys.size();) {
        // a run of directions, each within angle_tol of the one before
        size_t g1 = g0 + 1;
        while (g1 < keys.size() && keys[g1].angle - keys[g1 - 1].angle <= angle_tol) ++g1;
        std::sort(keys.begin() + static_cast<std::ptrdiff_t>(g0),
                  keys.begin() + static_cast<std::ptrdiff_t>(g1),
                  [](const Key& a, const Key& b) { return a.offset < b.offset; });
        std::vector<unsigned char> taken(g1 - g0, 0);
        for (size_t s = g0; s < g1; ++s) {
            if (taken[s - g0]) continue;
            taken[s - g0] = 1;
            const Pt a = E[keys[s].i][0], b = E[keys[s].i][1];
            const double rx = b.x - a.x, ry = b.y - a.y, l2 = rx * rx + ry * ry;
            const double len = std::sqrt(l2);
            // the seed's line and the lines on it, as intervals of its parameter
            std::vector<std::pair<double, std::array<Pt, 2>>> on{{0.0, {a, b}}};
            for (size_t o = s + 1; o < g1 && keys[o].offset - keys[s].offset <= offset_tol;
                 ++o) {
                if (taken[o - g0]) continue;
                std::array<Pt, 2> f = E[keys[o].i];
                if (!(std::fabs(cross2(a, b, f[0])) / len <= merge &&
                      std::fabs(cross2(a, b, f[1])) / len <= merge))
                    continue;
                double t0 = ((f[0].x - a.x) * rx + (f[0].y - a.y) * ry) / l2;
                double t1 = ((f[1].x - a.x) * rx + (f[1].y - a.y) * ry) / l2;
                if (t1 < t0) std::swap(t0, t1), std::swap(f[0], f[1]);
                taken[o - g0] = 1;
                on.push_back({t0, f});
            }
            // the union of the intervals, in order along the seed's direction
            for (auto& p : on) {
                const double t1 = ((p.second[1].x - a.x) * rx + (p.second[1].y - a.y) * ry) / l2;
                if (t1 < p.first) std::swap(p.second[0], p.second[1]), p.first = t1;
            }
            std::sort(on.begin(), on.end(),
                      [](const auto& x, const auto& y) { return x.first < y.first; });
            const double gap = merge / len;
            std::array<Pt, 2> cur = on[0].second;
            double hi = ((cur[1].x - a.x) * rx + (cur[1].y - a.y) * ry) / l2;
            for (size_t j = 1; j < on.size(); ++j) {
                const auto& f = on[j].second;
                const double f1 = ((f[1].x - a.x) * rx + (f[1].y - a.y) * ry) / l2;
                if (on[j].first <= hi + gap) {
                    if (f1 > hi) cur[1] = f[1], hi = f1;
                } else {
                    joined.push_back(cur);
                    cur = f, hi = f1;
                }
            }
            joined.push_back(cur);
        }
        g0 = g1;
    }
    E.resize(first);
    E.insert(E.end(), joined.begin(), joined.end());
}

}  // namespace

CellResult cut_cells(const double* P2, std::int64_t k, const double* S, std::int64_t m,
                     double step, double merge, double sliver) {
    CellResult res;
    std::vector<Pt> P(static_cast<size_t>(k));
    for (std::int64_t i = 0; i < k; ++i) P[i] = {P2[2 * i], P2[2 * i + 1]};
    const size_t K = P.size();
    double area = 0;
    for (size_t i = 0; i < K; ++i) area += cross2({0, 0}, P[i], P[(i + 1) % K]);
    area *= 0.5;
    for (size_t i = 0; i < K; ++i)
        if (cross2(P[i], P[(i + 1) % K], P[(i + 2) % K]) < 0 || !(area > 0)) {
            res.ok = false;                 // not convex: GEOS cuts it
            return res;
        }
    // the edges to node: P's, then each line's part inside P
    std::vector<std::array<Pt, 2>> E;
    for (size_t i = 0; i < K; ++i) E.push_back({P[i], P[(i + 1) % K]});
    for (std::int64_t s = 0; s < m; ++s) {
        const Pt a{S[4 * s], S[4 * s + 1]}, b{S[4 * s + 2], S[4 * s + 3]};
        const double dx = b.x - a.x, dy = b.y - a.y;
        // the line a + t (b - a) inside every edge's half-plane: t in [lo, hi] (the
        // whole line's crossings with the boundary in [LO, HI])
        double lo = 0, hi = 1, LO = -INFINITY, HI = INFINITY;
        bool in = true;
        for (size_t i = 0; i < K && in; ++i) {
            const Pt& p = P[i];
            const Pt& q = P[(i + 1) % K];
            const double f = cross2(p, q, a);            // > 0: a inside this edge
            const double g = (q.x - p.x) * dy - (q.y - p.y) * dx;   // its rate along t
            if (g == 0) {
                if (f < 0) in = false;
                continue;
            }
            const double t = -f / g;
            if (g > 0) LO = std::max(LO, t), lo = std::max(lo, t);
            else HI = std::min(HI, t), hi = std::min(hi, t);
        }
        if (!in || !(lo < hi)) continue;
        const double len = std::sqrt(dx * dx + dy * dy);
        if (!(len > 0)) continue;
        // an end within step of the boundary moved onto it
        if ((lo - LO) * len <= step) lo = LO;
        if ((HI - hi) * len <= step) hi = HI;
        E.push_back({Pt{a.x + lo * dx, a.y + lo * dy}, Pt{a.x + hi * dx, a.y + hi * dy}});
    }
    // collinear lines joined: a line within merge of another's (both ends) and
    // overlapping it (or within merge of its end) is one line with it, their union (many
    // events lie on one line: a vertex of each of a row of blockers against one edge; on
    // View3D's gunter2, 14,177 lines in one emitter lay on 1,586, and noding every copy
    // against every other took 8 GB)
    merge_collinear(E, K, merge, size_of(P));
    res.lines = static_cast<long long>(E.size());
    // the nodes: every edge's ends and crossings, within merge of each other one (the
    // first made: the nodes binned on a grid of merge, the 3 x 3 bins around a point
    // searched)
    std::vector<Pt> N;
    std::unordered_map<std::uint64_t, std::vector<size_t>> bins;
    const auto bin = [&](long long ix, long long iy) {
        return (static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ull) ^
               static_cast<std::uint64_t>(iy);
    };
    const double cell = merge > 0 ? merge : 1.0;
    const auto node = [&](const Pt& p) {
        const long long ix = static_cast<long long>(std::floor(p.x / cell));
        const long long iy = static_cast<long long>(std::floor(p.y / cell));
        size_t best = N.size();
        for (long long a = ix - 1; a <= ix + 1; ++a)
            for (long long b = iy - 1; b <= iy + 1; ++b) {
                const auto it = bins.find(bin(a, b));
                if (it == bins.end()) continue;
                for (size_t i : it->second)
                    if (i < best && std::fabs(N[i].x - p.x) <= merge &&
                        std::fabs(N[i].y - p.y) <= merge)
                        best = i;
            }
        if (best < N.size()) return best;
        N.push_back(p);
        bins[bin(ix, iy)].push_back(N.size() - 1);
        return N.size() - 1;
    };
    std::vector<std::vector<std::pair<double, size_t>>> on(E.size());
    for (size_t e = 0; e < E.size(); ++e) {
        on[e].push_back({0.0, node(E[e][0])});
        on[e].push_back({1.0, node(E[e][1])});
    }
    for (size_t e = 0; e < E.size(); ++e)
        for (size_t f = e + 1; f < E.size(); ++f) {
            const Pt &a = E[e][0], &b = E[e][1], &c = E[f][0], &d = E[f][1];
            const double rx = b.x - a.x, ry = b.y - a.y, sx = d.x - c.x, sy = d.y - c.y;
            const double den = rx * sy - ry * sx;
            const double le = std::sqrt(rx * rx + ry * ry), lf = std::sqrt(sx * sx + sy * sy);
            // an end of one on the other (within merge: a T-junction) is a node of both
            for (int w = 0; w < 2; ++w) {
                const Pt& p = E[f][w];
                const double t = ((p.x - a.x) * rx + (p.y - a.y) * ry) / (le * le);
                if (t > 0 && t < 1 && std::fabs(cross2(a, b, p)) / le <= merge)
                    on[e].push_back({t, node(p)});
                const Pt& q = E[e][w];
                const double u = ((q.x - c.x) * sx + (q.y - c.y) * sy) / (lf * lf);
                if (u > 0 && u < 1 && std::fabs(cross2(c, d, q)) / lf <= merge)
                    on[f].push_back({u, node(q)});
            }
            if (!(std::fabs(den) > 1e-12 * le * lf)) continue;      // (nearly) parallel
            const double qx = c.x - a.x, qy = c.y - a.y;
            double t = (qx * sy - qy * sx) / den, u = (qx * ry - qy * rx) / den;
            const double te = merge / le, tf = merge / lf;
            if (t < -te || t > 1 + te || u < -tf || u > 1 + tf) continue;
            t = std::min(1.0, std::max(0.0, t));
            u = std::min(1.0, std::max(0.0, u));
            const size_t id = node({a.x + t * rx, a.y + t * ry});
            on[e].push_back({t, id});
            on[f].push_back({u, id});
        }
    // the graph's edges: consecutive nodes along each edge, each once
    std::vector<std::pair<size_t, size_t>> G;
    for (auto& L : on) {
        std::sort(L.begin(), L.end());
        for (size_t i = 0; i + 1 < L.size(); ++i) {
            size_t u = L[i].second, v = L[i + 1].second;
            if (u == v) continue;
            G.push_back({std::min(u, v), std::max(u, v)});
        }
    }
    std::sort(G.begin(), G.end());
    G.erase(std::unique(G.begin(), G.end()), G.end());
    // dangles removed until none is left
    std::vector<int> degree(N.size(), 0);
    for (const auto& g : G) ++degree[g.first], ++degree[g.second];
    std::vector<unsigned char> live(G.size(), 1);
    for (bool again = true; again;) {
        again = false;
        for (size_t i = 0; i < G.size(); ++i)
            if (live[i] && (degree[G[i].first] == 1 || degree[G[i].second] == 1)) {
                live[i] = 0;
                --degree[G[i].first];
                --degree[G[i].second];
                again = true;
            }
    }
    // the graph connected (else a cell would have a hole: GEOS cuts it)
    std::vector<size_t> root(N.size());
    for (size_t i = 0; i < N.size(); ++i) root[i] = i;
    const auto find = [&](size_t i) {
        while (root[i] != i) i = root[i] = root[root[i]];
        return i;
    };
    for (size_t i = 0; i < G.size(); ++i)
        if (live[i]) root[find(G[i].first)] = find(G[i].second);
    size_t comps = 0;
    for (size_t i = 0; i < N.size(); ++i)
        if (degree[i] > 0 && find(i) == i) ++comps;
    if (comps != 1) {
        res.ok = false;
        return res;
    }
    // half-edges around each node by angle
    std::vector<std::vector<std::pair<double, size_t>>> out(N.size());
    for (size_t i = 0; i < G.size(); ++i) {
        if (!live[i]) continue;
        const size_t u = G[i].first, v = G[i].second;
        out[u].push_back({std::atan2(N[v].y - N[u].y, N[v].x - N[u].x), v});
        out[v].push_back({std::atan2(N[u].y - N[v].y, N[u].x - N[v].x), u});
    }
    for (auto& o : out) std::sort(o.begin(), o.end());
    std::vector<std::vector<unsigned char>> used(N.size());
    for (size_t i = 0; i < N.size(); ++i) used[i].assign(out[i].size(), 0);
    const auto index = [&](size_t u, size_t v) {
        for (size_t j = 0; j < out[u].size(); ++j)
            if (out[u][j].second == v) return j;
        return out[u].size();
    };
    const double flat = 1e-14 * area;
    int outer = 0;
    double outer_area = 0, inner_area = 0;
    for (size_t s = 0; s < N.size(); ++s)
        for (size_t j0 = 0; j0 < out[s].size(); ++j0) {
            if (used[s][j0]) continue;
            // the face to the left of s -> t: at each node, the next edge clockwise
            // from the way back
            std::vector<Pt> face;
            size_t u = s, j = j0;
            bool closed = false;
            for (size_t guard = 0; guard <= 4 * G.size() + 4; ++guard) {
                used[u][j] = 1;
                face.push_back(N[u]);
                const size_t v = out[u][j].second;
                const size_t back = index(v, u);
                const size_t nj = (back + out[v].size() - 1) % out[v].size();
                u = v;
                j = nj;
                if (u == s && j == j0) {
                    closed = true;
                    break;
                }
                if (used[u][j]) break;
            }
            if (!closed) {
                res.ok = false;
                return res;
            }
            double a = 0;
            for (size_t i = 0; i < face.size(); ++i)
                a += cross2({0, 0}, face[i], face[(i + 1) % face.size()]);
            a *= 0.5;
            if (a < -sliver) {                            // the outer face
                ++outer;
                outer_area -= a;
                continue;
            }
            inner_area += a;
            if (!(a > sliver)) continue;                  // a sliver
            res.areas.push_back(a);
            const size_t before = res.triangles.size();
            if (!ear_clip(face, flat, res.triangles)) {
                res.ok = false;
                return res;
            }
            double t = 0;
            for (size_t i = before; i < res.triangles.size(); i += 6)
                t += 0.5 * cross2({res.triangles[i], res.triangles[i + 1]},
                                  {res.triangles[i + 2], res.triangles[i + 3]},
                                  {res.triangles[i + 4], res.triangles[i + 5]});
            if (!(std::fabs(t - a) <= 1e-12 * area)) {      // the ears are not the face
                res.ok = false;
                return res;
            }
        }
    // a planar arrangement: one outer face, P's boundary, and the cells tile P (else
    // edges crossed without a node, as where merged nodes moved an edge across another)
    if (outer != 1 || !(std::fabs(outer_area - area) <= 1e-12 * area) ||
        !(std::fabs(inner_area - area) <= 1e-12 * area))
        res.ok = false;
    return res;
}

}  // namespace exactff
