// The adaptive levels of an occluded pair's hidden-part integral (levels.h): the same
// steps, in the same order, as exactff/area/adaptive.py's _adaptive_levels with
// rules.py's rule_pair, hidden.py's hidden_values (its path without lost points) and
// points.py's point_values, the reference (tests/test_area_pair_compiled.py compares
// them). Sums over a triangle's nodes are taken in order (numpy may pair them): the
// values agree to rounding, far within the estimates.

#include "levels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "hidden.h"
#include "sector_sums.h"

namespace exactff {
namespace {

struct Pt3 {
    double x, y, z;
};
Pt3 vsub(const Pt3& a, const Pt3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
// |(b - a) x (c - a)|: twice the triangle's area (rules.py, triangle_areas and the rules'
// Jacobians; geometry.cross's products)
double twice_area(const Pt3& a, const Pt3& b, const Pt3& c) {
    const Pt3 u = vsub(b, a), v = vsub(c, a);
    const double x = u.y * v.z - u.z * v.y, y = u.z * v.x - u.x * v.z, z = u.x * v.y - u.y * v.x;
    return std::sqrt(x * x + y * y + z * z);
}

// the nodes (appended to X) and weights (to W) of a rule on the triangle a, b, c
// (rules.py: triangle_rule, the collapsed rule, X = a + u (b - a) + u v (c - b) with the
// Jacobian u; symmetric_triangle_rule, X = B a + B b + B c)
void rule_nodes(const TriangleRule& r, const Pt3& a, const Pt3& b, const Pt3& c,
                std::vector<double>& X, std::vector<double>& W) {
    if (r.collapsed) {
        const size_t n = r.x.size();
        const double J = twice_area(a, b, c);
        const Pt3 ba = vsub(b, a), cb = vsub(c, b);
        for (size_t i = 0; i < n; ++i) {
            const double u = 0.5 * (r.x[i] + 1.0), wi = 0.5 * r.w[i];
            for (size_t j = 0; j < n; ++j) {
                const double v = 0.5 * (r.x[j] + 1.0), wj = 0.5 * r.w[j];
                const double uv = u * v;
                X.push_back(a.x + u * ba.x + uv * cb.x);
                X.push_back(a.y + u * ba.y + uv * cb.y);
                X.push_back(a.z + u * ba.z + uv * cb.z);
                W.push_back(wi * wj * u * J);
            }
        }
        return;
    }
    const size_t m = r.w.size();
    const double A = 0.5 * twice_area(a, b, c);
    for (size_t k = 0; k < m; ++k) {
        const double* B = &r.x[3 * k];
        X.push_back(B[0] * a.x + B[1] * b.x + B[2] * c.x);
        X.push_back(B[0] * a.y + B[1] * b.y + B[2] * c.y);
        X.push_back(B[0] * a.z + B[1] * b.z + B[2] * c.z);
        W.push_back(r.w[k] * A);
    }
}

size_t rule_size(const TriangleRule& r) {
    return r.collapsed ? r.x.size() * r.x.size() : r.w.size();
}

// hidden.py's hidden_values at the points X (n, 3) of one chunk, where none is lost:
// the hidden parts H and their estimates EH; false where a point is lost or a value
// lies below 0 beyond its estimate (the caller's reference path then takes over)
bool hidden_chunk(const LevelArgs& a, const double* X, const long long* cells, std::int64_t n,
                  double atol, double* H, double* EH, long long& back_faces) {
    // the scene's size here: the box of the blockers, Qc and the points
    double lo[3] = {a.lo[0], a.lo[1], a.lo[2]}, hi[3] = {a.hi[0], a.hi[1], a.hi[2]};
    for (std::int64_t p = 0; p < n; ++p)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], X[3 * p + k]);
            hi[k] = std::max(hi[k], X[3 * p + k]);
        }
    const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    HiddenArgs h = a.hidden;
    h.X = X;
    h.n = n;
    h.back_face = a.back_face_rtol * size;
    h.edge_on = a.edge_on_rtol * size;
    h.precise_atol = a.precise_share * atol;
    h.rings = false;
    h.cells = cells;
    const HiddenResult r = hidden_pieces(h);
    back_faces += r.back_faces;
    const double pi = 3.14159265358979323846;
    const double *q0 = h.q0, *nQ = h.nQ, *RQ = h.RQ;
    for (std::int64_t p = 0; p < n; ++p) {
        // the clipping's rounding through the kernel's bound h / (pi r^3) over the
        // pieces' box, the slivers dropped, and the clipped vertices' rounding (geo)
        const double delta = a.boolean_ulps * a.lines * a.eps * r.reach[p];
        const double d[3] = {X[3 * p] - q0[0], X[3 * p + 1] - q0[1], X[3 * p + 2] - q0[2]};
        const double hh = d[0] * nQ[0] + d[1] * nQ[1] + d[2] * nQ[2];
        const double fx = d[0] * RQ[0] + d[1] * RQ[1] + d[2] * RQ[2];
        const double fy = d[0] * RQ[3] + d[1] * RQ[4] + d[2] * RQ[5];
        const double* box = &r.box[4 * p];
        const double dx = std::max(0.0, std::max(box[0] - fx, fx - box[2]));
        const double dy = std::max(0.0, std::max(box[1] - fy, fy - box[3]));
        const double rr = std::sqrt(hh * hh + dx * dx + dy * dy);
        const double bound = (rr > 0 && hh > 0) ? hh / (pi * (rr * rr * rr)) : 0.0;
        const double geo = r.moved[p] * r.length[p] * bound;
        EH[p] = r.rounding[p] + (delta * r.length[p] + r.dropped[p]) * bound + geo;
        const bool lost = r.lost[p] || ((r.moved[p] > a.image_rtol * std::max(r.reach[p],
                                                                             h.extent)) &&
                                        (r.length[p] == 0 || geo > atol));
        if (lost) return false;
        H[p] = r.hidden[p];
        // errors.nonnegative: below 0 within the estimate is 0, beyond it (or NaN) the
        // reference raises
        if (!(H[p] >= -EH[p])) return false;
        if (H[p] < 0) H[p] = 0.0;
    }
    return true;
}

// points.py's point_values to the receiver Qc alone: U and its estimate at each point
// (the points in one call of the sector sums, all in the one frame)
void unoccluded_chunk(const LevelArgs& a, const double* X, std::int64_t n, double* U,
                      double* EU) {
    const double pi = 3.14159265358979323846;
    const std::int64_t off[2] = {0, a.n_q};
    std::vector<std::int64_t> ids(n, 0), rows(n);
    std::vector<double> S(n), M(n), E(n);
    std::unique_ptr<bool[]> up(new bool[n]);
    for (std::int64_t p = 0; p < n; ++p) rows[p] = p;
    kernel::row_sums<double>(a.Qc, off, ids.data(), rows.data(), n, X, a.frame, a.eps,
                             a.offset_ulps, a.c2 * a.eps, S.data(), M.data(), E.data(),
                             up.get(), 0);
    for (std::int64_t p = 0; p < n; ++p) {
        U[p] = std::abs(S[p]) / (2.0 * pi);
        EU[p] = (a.c1 * a.eps * M[p] + E[p]) / (2.0 * pi);
    }
}

}  // namespace

namespace {

// the triangles evaluated and not yet accepted (adaptive.py's pool), per triangle
struct Pool {
    std::vector<double> T, hi, lo, diff, rnd, hiU, loU, rndU, area;
    std::vector<long long> depth, rung;
    std::vector<unsigned char> corner;
    size_t size() const { return diff.size(); }
};

// rules.py's budget_refined: the pool's triangles to refine (out), largest difference
// first, until what is left fits the budget (in the pool's order); false, with nothing
// chosen, where a difference is not finite (the reference raises there: a NaN would
// leave the ordering below no strict weak order, undefined behaviour for the sort)
bool budget_refined(const Pool& p, double before, double atol, double total_area,
                    long long max_depth, std::vector<size_t>& out) {
    out.clear();
    for (size_t k = 0; k < p.size(); ++k)
        if (!std::isfinite(p.diff[k])) return false;
    const double target = 0.5 * atol;
    double stuck = 0.0, room = 0.0, all = 0.0;
    std::vector<size_t> mine;
    for (size_t k = 0; k < p.size(); ++k) {
        if (p.rung[k] == 0 || p.depth[k] < max_depth) mine.push_back(k);
        else stuck += p.diff[k];
    }
    if (mine.empty()) return true;
    for (size_t k : mine) room += p.area[k];
    for (size_t k : mine) all += p.diff[k];
    const double budget = std::max(target - before - stuck, target * room / total_area);
    std::vector<size_t> order = mine;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t x, size_t y) { return -p.diff[x] < -p.diff[y]; });
    double taken = 0.0;
    for (size_t k : order) {
        if (!(all - taken > budget)) break;
        out.push_back(k);
        taken += p.diff[k];
    }
    std::sort(out.begin(), out.end());
    return true;
}

// the boxes of the receiver's part and of the blockers' pieces, (lo, hi) in turn
std::vector<double> piece_boxes(const LevelArgs& a) {
    std::vector<double> boxes;
    const auto add = [&boxes](const double* v, std::int64_t m) {
        double lo[3] = {v[0], v[1], v[2]}, hi[3] = {v[0], v[1], v[2]};
        for (std::int64_t j = 1; j < m; ++j)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], v[3 * j + k]);
                hi[k] = std::max(hi[k], v[3 * j + k]);
            }
        boxes.insert(boxes.end(), lo, lo + 3);
        boxes.insert(boxes.end(), hi, hi + 3);
    };
    add(a.Qc, a.n_q);
    const HiddenArgs& h = a.hidden;
    for (std::int64_t b = 0; b < h.n_blockers; ++b)
        add(h.blockers + 3 * h.blocker_stride * b, h.counts[b]);
    return boxes;
}

// rules.py's far_triangles: whether the triangle v's box's diagonal is at most small_reach
// times the distance from its box to the nearest of the boxes (the same sums in the
// same order)
bool far_from(const double* v, const std::vector<double>& boxes, double reach) {
    double lo[3], hi[3], h2[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = std::min({v[k], v[3 + k], v[6 + k]});
        hi[k] = std::max({v[k], v[3 + k], v[6 + k]});
        h2[k] = (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    double d2 = std::numeric_limits<double>::infinity();
    for (size_t b = 0; b < boxes.size(); b += 6) {
        double g[3];
        for (int k = 0; k < 3; ++k) {
            const double gap =
                std::max(std::max(boxes[b + k] - hi[k], lo[k] - boxes[b + 3 + k]), 0.0);
            g[k] = gap * gap;
        }
        d2 = std::min(d2, (g[0] + g[1]) + g[2]);
    }
    return (h2[0] + h2[1]) + h2[2] <= (reach * reach) * d2;
}

}  // namespace

LevelResult adaptive_levels(const LevelArgs& a) {
    LevelResult out;
    // the pieces' boxes where the small triangles' rules may be taken (rules.py's
    // rule_pair: at the symmetric pairs' tolerances only)
    const std::vector<double> boxes = a.symmetric ? piece_boxes(a) : std::vector<double>();
    std::vector<unsigned char> small;   // per triangle, for the rules below
    std::vector<double> T = a.T;
    std::vector<long long> depth = a.depth, rung = a.rung;
    std::vector<unsigned char> corner = a.corner;
    const double point_atol = a.budget_share * a.atol;
    Pool pool;
    std::vector<double> X, W, H, EH, U, EU, area_t;
    std::vector<long long> cell;   // each node's triangle (hidden.h's cells)
    std::vector<size_t> first, nl, nh, nm;
    std::vector<unsigned char> null;   // per triangle: the symmetric pair of degrees 4 and 8
    while (true) {
        // a sliver (between nearly coincident events) is not evaluated: half its area,
        // within as much
        size_t t = T.size() / 9, kept = 0;
        area_t.clear();
        for (size_t k = 0; k < t; ++k) {
            const double* v = &T[9 * k];
            const double at = 0.5 * twice_area({v[0], v[1], v[2]}, {v[3], v[4], v[5]},
                                               {v[6], v[7], v[8]});
            if (at / a.area_P <= a.sliver_share * a.atol) {
                out.slivers += at;
                continue;
            }
            std::copy(v, v + 9, &T[9 * kept]);
            depth[kept] = depth[k];
            rung[kept] = rung[k];
            corner[kept] = corner[k];
            area_t.push_back(at);
            ++kept;
        }
        t = kept;
        T.resize(9 * t);
        depth.resize(t);
        rung.resize(t);
        corner.resize(t);
        if (t) {
            // the rules of every triangle, grouped as the reference groups them (rung,
            // then corner, then small), their nodes in one list
            X.clear();
            W.clear();
            cell.clear();
            first.assign(t, 0);
            nl.assign(t, 0);
            nh.assign(t, 0);
            nm.assign(t, 0);
            null.assign(t, 0);
            // a small triangle off a corner: the symmetric pair of degrees 2 and 4 on
            // rung 0, of 4 and 8 on rung 1
            small.assign(t, 0);
            for (size_t k = 0; k < t; ++k)
                small[k] = !corner[k] && a.symmetric &&
                           area_t[k] / a.area_P <= a.small_share &&
                           far_from(&T[9 * k], boxes, a.small_reach);
            for (long long r : {0LL, 1LL})
                for (unsigned char at_corner : {0, 1})
                    for (bool in_small : {false, true})
                        for (size_t k = 0; k < t; ++k) {
                            if (rung[k] != r || (corner[k] != 0) != (at_corner != 0) ||
                                (small[k] != 0) != in_small)
                                continue;
                            const TriangleRule *lo, *hi, *mid = nullptr;
                            if (small[k]) {
                                lo = a.rules[r == 0 ? 7 : 0];
                                hi = a.rules[r == 0 ? 8 : 1];
                                null[k] = r != 0;
                            } else if (r == 0 && !at_corner && a.symmetric) {
                                lo = a.rules[0];
                                hi = a.rules[1];
                                null[k] = 1;
                            } else if (r == 0) {
                                lo = a.rules[2];
                                hi = a.rules[3];
                                if (at_corner) mid = a.rules[6];
                            } else {
                                lo = a.rules[4];
                                hi = a.rules[5];
                            }
                            const double* v = &T[9 * k];
                            const Pt3 p0{v[0], v[1], v[2]}, p1{v[3], v[4], v[5]},
                                p2{v[6], v[7], v[8]};
                            first[k] = W.size();
                            rule_nodes(*lo, p0, p1, p2, X, W);
                            rule_nodes(*hi, p0, p1, p2, X, W);
                            if (mid) rule_nodes(*mid, p0, p1, p2, X, W);
                            cell.resize(W.size(), static_cast<long long>(k));
                            nl[k] = rule_size(*lo);
                            nh[k] = rule_size(*hi);
                            nm[k] = mid ? rule_size(*mid) : 0;
                        }
            const std::int64_t np = static_cast<std::int64_t>(W.size());
            H.resize(np);
            EH.resize(np);
            U.resize(np);
            EU.resize(np);
            for (std::int64_t s = 0; s < np; s += a.points_per_call) {
                const std::int64_t m = std::min<std::int64_t>(a.points_per_call, np - s);
                if (!hidden_chunk(a, &X[3 * s], &cell[s], m, point_atol, &H[s], &EH[s],
                                  out.back_faces)) {
                    out.ok = false;
                    return out;
                }
            }
            unoccluded_chunk(a, X.data(), np, U.data(), EU.data());
            out.points += np;
            // per triangle: the rules' integrals of H and U, the nodes' estimates, per
            // unit area of P, into the pool
            for (size_t k = 0; k < t; ++k) {
                const size_t f = first[k], l = nl[k], hgh = nh[k], md = nm[k];
                double hi = 0, lo = 0, mid = 0, rnd_h = 0, rnd_l = 0, rnd_m = 0, hiU = 0,
                       loU = 0, rU_h = 0, rU_l = 0;
                for (size_t q = f; q < f + l; ++q) {
                    lo += W[q] * H[q];
                    rnd_l += W[q] * EH[q];
                    loU += W[q] * U[q];
                    rU_l += W[q] * EU[q];
                }
                for (size_t q = f + l; q < f + l + hgh; ++q) {
                    hi += W[q] * H[q];
                    rnd_h += W[q] * EH[q];
                    hiU += W[q] * U[q];
                    rU_h += W[q] * EU[q];
                }
                for (size_t q = f + l + hgh; q < f + l + hgh + md; ++q) {
                    mid += W[q] * H[q];
                    rnd_m += W[q] * EH[q];
                }
                if (!md) mid = lo;
                // the symmetric pair's null rules of degree 5 on its 22 nodes (rules.py's
                // symmetric_null_spread)
                double spread = 0;
                if (null[k]) {
                    double n1 = 0, n2 = 0;
                    for (size_t q = f; q < f + l + hgh; ++q) {
                        n1 += H[q] * a.rules[9]->w[q - f];
                        n2 += H[q] * a.rules[10]->w[q - f];
                    }
                    spread = std::sqrt(n1 * n1 + n2 * n2) * area_t[k];
                }
                const double P = a.area_P;
                hi /= P;
                lo /= P;
                mid /= P;
                spread /= P;
                // the high rule's error estimated by the low rule's difference, at a
                // corner on the lower pair also by the third rule's, and on the symmetric
                // pair of degrees 4 and 8 also by its null rules' spread
                pool.T.insert(pool.T.end(), &T[9 * k], &T[9 * k] + 9);
                pool.depth.push_back(depth[k]);
                pool.rung.push_back(rung[k]);
                pool.corner.push_back(corner[k]);
                pool.area.push_back(area_t[k]);
                pool.hi.push_back(hi);
                pool.lo.push_back(lo);
                pool.diff.push_back(std::max(std::max(std::abs(hi - lo), std::abs(hi - mid)),
                                             a.null_factor * spread));
                pool.rnd.push_back((rnd_h + rnd_l + rnd_m) / P);
                pool.hiU.push_back(hiU / P);
                pool.loU.push_back(loU / P);
                pool.rndU.push_back((rU_h + rU_l) / P);
            }
        }
        if (!pool.size()) break;
        // half of atol for the rules' differences, with those accepted before this
        // call: the largest refined while what is left exceeds it
        std::vector<size_t> sel;
        if (!budget_refined(pool, a.rules_err, a.atol, a.total_area, a.max_depth, sel)) {
            out.ok = false;   // a difference not finite: the reference raises
            return out;
        }
        if (sel.empty()) break;
        // the refined: a triangle the low pair missed takes the high pair (rung 1), one
        // the high pair missed is cut in four at its edges' midpoints, one level down, on
        // rung start (rules.py, quarter: (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc,
        // ca), the first keeping the corner); in the reference's order (_refined), the
        // re-ruled ones first
        std::vector<double> T2;
        std::vector<long long> d2, r2;
        std::vector<unsigned char> c2;
        for (size_t k : sel) {
            if (pool.rung[k] != 0) continue;
            T2.insert(T2.end(), &pool.T[9 * k], &pool.T[9 * k] + 9);
            d2.push_back(pool.depth[k]);
            r2.push_back(1);
            c2.push_back(pool.corner[k]);
        }
        for (size_t k : sel) {
            if (pool.rung[k] == 0) continue;
            const double* v = &pool.T[9 * k];
            double m[3][3];   // ab, bc, ca
            for (int x = 0; x < 3; ++x) {
                m[0][x] = (v[x] + v[3 + x]) / 2;
                m[1][x] = (v[3 + x] + v[6 + x]) / 2;
                m[2][x] = (v[6 + x] + v[x]) / 2;
            }
            const double* quads[4][3] = {{v, m[0], m[2]},
                                         {m[0], v + 3, m[1]},
                                         {m[2], m[1], v + 6},
                                         {m[0], m[1], m[2]}};
            for (int q = 0; q < 4; ++q) {
                for (int c = 0; c < 3; ++c) T2.insert(T2.end(), quads[q][c], quads[q][c] + 3);
                d2.push_back(pool.depth[k] + 1);
                r2.push_back(a.start);
                c2.push_back(q == 0 ? pool.corner[k] : 0);
            }
        }
        // the pool less the refined, in order
        Pool rest;
        size_t s = 0;
        for (size_t k = 0; k < pool.size(); ++k) {
            if (s < sel.size() && sel[s] == k) {
                ++s;
                continue;
            }
            rest.T.insert(rest.T.end(), &pool.T[9 * k], &pool.T[9 * k] + 9);
            rest.depth.push_back(pool.depth[k]);
            rest.rung.push_back(pool.rung[k]);
            rest.corner.push_back(pool.corner[k]);
            rest.area.push_back(pool.area[k]);
            rest.hi.push_back(pool.hi[k]);
            rest.lo.push_back(pool.lo[k]);
            rest.diff.push_back(pool.diff[k]);
            rest.rnd.push_back(pool.rnd[k]);
            rest.hiU.push_back(pool.hiU[k]);
            rest.loU.push_back(pool.loU[k]);
            rest.rndU.push_back(pool.rndU[k]);
        }
        pool = std::move(rest);
        T.swap(T2);
        depth.swap(d2);
        rung.swap(r2);
        corner.swap(c2);
    }
    // the pool accepted, in order
    out.T = pool.T;
    out.depth = pool.depth;
    out.rung = pool.rung;
    out.corner = pool.corner;
    out.hi = pool.hi;
    out.lo = pool.lo;
    out.diff = pool.diff;
    out.rnd = pool.rnd;
    out.hiU = pool.hiU;
    out.loU = pool.loU;
    out.rndU = pool.rndU;
    return out;
}

namespace {

// a triangle's size: the largest of its coordinates' ranges
double tri_size(const double* v) {
    double s = 0;
    for (int x = 0; x < 3; ++x)
        s = std::max(s, std::max({v[x], v[3 + x], v[6 + x]}) - std::min({v[x], v[3 + x], v[6 + x]}));
    return s;
}

// per vertex of the triangle v: the first of Vb's vertices (kept ones, in order) that
// touches it, or -1
void touching(const double* v, const std::vector<const double*>& Vb,
              const std::vector<double>& off, double reach, double hull_rtol, long long* first) {
    const double near = hull_rtol * tri_size(v);
    const double within = std::max(near, reach);
    for (int k = 0; k < 3; ++k) {
        first[k] = -1;
        for (size_t b = 0; b < Vb.size(); ++b) {
            if (!(off[b] <= near)) continue;
            const double dx = v[3 * k] - Vb[b][0], dy = v[3 * k + 1] - Vb[b][1],
                         dz = v[3 * k + 2] - Vb[b][2];
            if (std::sqrt(dx * dx + dy * dy + dz * dz) <= within) {
                first[k] = static_cast<long long>(b);
                break;
            }
        }
    }
}

}  // namespace

void corner_first(std::vector<double>& T, const double* Vb, std::int64_t m, const double* n,
                  double dP, double reach, double hull_rtol, std::vector<unsigned char>& corner) {
    const size_t t = T.size() / 9;
    corner.assign(t, 0);
    if (!t || !m) return;
    // only the blocker vertices that may be on the plane for some triangle, in order
    double size = 0;
    for (size_t k = 0; k < t; ++k) size = std::max(size, tri_size(&T[9 * k]));
    std::vector<const double*> keep;
    std::vector<double> off;
    for (std::int64_t b = 0; b < m; ++b) {
        const double* p = Vb + 3 * b;
        const double o = std::abs(p[0] * n[0] + p[1] * n[1] + p[2] * n[2] - dP);
        if (o <= hull_rtol * size) {
            keep.push_back(p);
            off.push_back(o);
        }
    }
    if (keep.empty()) return;
    // a triangle with several such vertices cut in four (rules.py, quarter), after the rest
    std::vector<double> T2, cut;
    long long first[3];
    for (size_t k = 0; k < t; ++k) {
        const double* v = &T[9 * k];
        touching(v, keep, off, reach, hull_rtol, first);
        const int hits = (first[0] >= 0) + (first[1] >= 0) + (first[2] >= 0);
        (hits > 1 ? cut : T2).insert((hits > 1 ? cut : T2).end(), v, v + 9);
    }
    for (size_t k = 0; k < cut.size() / 9; ++k) {
        const double* v = &cut[9 * k];
        double mid[3][3];   // ab, bc, ca
        for (int x = 0; x < 3; ++x) {
            mid[0][x] = (v[x] + v[3 + x]) / 2;
            mid[1][x] = (v[3 + x] + v[6 + x]) / 2;
            mid[2][x] = (v[6 + x] + v[x]) / 2;
        }
        const double* quads[4][3] = {{v, mid[0], mid[2]}, {mid[0], v + 3, mid[1]},
                                     {mid[2], mid[1], v + 6}, {mid[0], mid[1], mid[2]}};
        for (int q = 0; q < 4; ++q)
            for (int c = 0; c < 3; ++c) T2.insert(T2.end(), quads[q][c], quads[q][c] + 3);
    }
    // the vertex touched by the earliest blocker vertex first
    const size_t t2 = T2.size() / 9;
    corner.assign(t2, 0);
    for (size_t k = 0; k < t2; ++k) {
        double* v = &T2[9 * k];
        touching(v, keep, off, reach, hull_rtol, first);
        int shift = -1;
        for (int j = 0; j < 3; ++j)
            if (first[j] >= 0 && (shift < 0 || first[j] < first[shift])) shift = j;
        if (shift < 0) continue;
        corner[k] = 1;
        double w[9];
        for (int j = 0; j < 3; ++j) std::copy(v + 3 * ((j + shift) % 3), v + 3 * ((j + shift) % 3) + 3, w + 3 * j);
        std::copy(w, w + 9, v);
    }
    T.swap(T2);
}

}  // namespace exactff
