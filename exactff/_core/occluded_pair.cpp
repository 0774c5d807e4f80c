// One occluded pair in one call (occluded_pair.h): adaptive.py's _hidden_integral step
// by step, each step's reference named where it is taken.

#include "occluded_pair.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "frame.h"
#include "hidden_setup.h"
#include "numpy_ops.h"
#include "pair.h"
#include "vec.h"

namespace exactff {

namespace {

using numpy_ops::blas_dot2;
using numpy_ops::blas_dot3;
using numpy_ops::pairwise_sum;
using numpy_ops::sum3;

// geometry.py's area_vector of a polygon (k, 3) (vec.h's fan_area_vector)
void area_vector(const double* P, std::int64_t k, double* A) {
    const Vec3<double> s = fan_area_vector<double>(k, [&](std::int64_t i) {
        return Vec3<double>{P[3 * i], P[3 * i + 1], P[3 * i + 2]};
    });
    A[0] = s.x;
    A[1] = s.y;
    A[2] = s.z;
}

// np.linalg.norm of a 3-vector (sqrt of its BLAS dot with itself)
double norm3(const double* a, bool fused) { return std::sqrt(blas_dot3(a, a, fused)); }

// rules.py's triangle_areas of T (t, 3, 3)
std::vector<double> triangle_areas(const std::vector<double>& T) {
    const size_t t = T.size() / 9;
    std::vector<double> out(t);
    for (size_t k = 0; k < t; ++k) {
        const double* v = &T[9 * k];
        const double a0 = v[3] - v[0], a1 = v[4] - v[1], a2 = v[5] - v[2];
        const double b0 = v[6] - v[0], b1 = v[7] - v[1], b2 = v[8] - v[2];
        const double c0 = a1 * b2 - a2 * b1, c1 = a2 * b0 - a0 * b2, c2 = a0 * b1 - a1 * b0;
        out[k] = 0.5 * std::sqrt(sum3(c0 * c0, c1 * c1, c2 * c2));
    }
    return out;
}

double sum(const std::vector<double>& v) {
    return pairwise_sum(v.data(), static_cast<std::ptrdiff_t>(v.size()));
}

// (X - o) @ R[:2].T for X (k, 3): the points in a frame's first two axes about o
std::vector<double> in_frame(const double* X, std::int64_t k, const double* o,
                             const double* R, bool fused) {
    std::vector<double> out(2 * k);
    for (std::int64_t i = 0; i < k; ++i) {
        const double d[3] = {X[3 * i] - o[0], X[3 * i + 1] - o[1], X[3 * i + 2] - o[2]};
        out[2 * i] = blas_dot3(d, R, fused);
        out[2 * i + 1] = blas_dot3(d, R + 3, fused);
    }
    return out;
}

// whether the segment (a, b) meets the closed polygon P2 (k, 2): an end inside or on
// it, or a crossing or touching of an edge (distinct_lines' count, not a decision of
// the value)
bool segment_meets_polygon(const double* a, const double* b, const std::vector<double>& P2) {
    const size_t k = P2.size() / 2;
    const auto orient = [](const double* p, const double* q, const double* r) {
        const double v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        return (v > 0) - (v < 0);
    };
    const auto on = [](const double* p, const double* q, const double* r) {
        // r on the segment (p, q), given the three collinear
        return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) &&
               std::min(p[1], q[1]) <= r[1] && r[1] <= std::max(p[1], q[1]);
    };
    for (size_t i = 0; i < k; ++i) {
        const double *p = &P2[2 * i], *q = &P2[2 * ((i + 1) % k)];
        const int o1 = orient(a, b, p), o2 = orient(a, b, q), o3 = orient(p, q, a),
                  o4 = orient(p, q, b);
        if (o1 != o2 && o3 != o4) return true;
        if ((o1 == 0 && on(a, b, p)) || (o2 == 0 && on(a, b, q)) || (o3 == 0 && on(p, q, a)) ||
            (o4 == 0 && on(p, q, b)))
            return true;
    }
    // no edge met: inside if the end a is (winding by crossings)
    bool in = false;
    for (size_t i = 0, j = k - 1; i < k; j = i++) {
        const double *p = &P2[2 * i], *q = &P2[2 * j];
        if ((p[1] > a[1]) != (q[1] > a[1]) &&
            a[0] < (q[0] - p[0]) * (a[1] - p[1]) / (q[1] - p[1]) + p[0])
            in = !in;
    }
    return in;
}

// events.py's distinct_lines(lines, size, P2)
long long distinct_lines(const std::vector<double>& S, double size, const std::vector<double>& P2,
                         double key) {
    const double pi = 3.141592653589793;
    std::set<std::pair<double, double>> keys;
    for (size_t s = 0; s < S.size() / 4; ++s) {
        const double* a = &S[4 * s];
        const double* b = a + 2;
        if (!segment_meets_polygon(a, b, P2)) continue;
        const double dx = b[0] - a[0], dy = b[1] - a[1];
        if (!(std::hypot(dx, dy) > 0)) continue;
        double angle = std::fmod(std::atan2(dy, dx), pi);
        if (angle != 0 && angle < 0) angle += pi;
        const double offset = a[0] * std::sin(angle) - a[1] * std::cos(angle);
        keys.emplace(std::nearbyint(angle / key), std::nearbyint(offset / (key * size)));
    }
    return static_cast<long long>(keys.size());
}

// predicates.py's coplanar_band_sides(K, nQ[None], [d]) all 0: every vertex of K within
// the near-coplanar band of the plane nQ . x = d (its sides rounded as a matrix product,
// not as numpy's gemv: a vertex within an ulp of the band's edge may be taken otherwise
// than by the reference, numpy_ops.h)
bool in_plane(const double* K, std::int64_t k, const double* nQ, double d, double ulps,
              double eps, bool fused) {
    double big[3] = {0, 0, 0};
    for (std::int64_t i = 0; i < k; ++i)
        for (int j = 0; j < 3; ++j) big[j] = std::max(big[j], std::fabs(K[3 * i + j]));
    const double aN[3] = {std::fabs(nQ[0]), std::fabs(nQ[1]), std::fabs(nQ[2])};
    const double widest = ulps * eps * (blas_dot3(big, aN, fused) + std::fabs(d));
    for (std::int64_t i = 0; i < k; ++i) {
        const double* v = K + 3 * i;
        const double s = blas_dot3(v, nQ, fused) - d;
        if (s == 0) continue;
        if (!(std::fabs(s) <= widest)) return false;
        const double mag = sum3(std::fabs(v[0]) * aN[0], std::fabs(v[1]) * aN[1],
                                std::fabs(v[2]) * aN[2]) +
                           std::fabs(d);
        if (!(std::fabs(s) <= ulps * eps * mag)) return false;
    }
    return true;
}

// points.py's unevaluated: the triangles of T (t, 3, 3) of least bound times area and their
// corner flags dropped (ties in their order; never the last in that order), while half
// their running sum, per unit area of P, stays within allowed, where they are at least
// the share least of the triangles; returns their area and that sum, and adds the
// triangles dropped to count
std::pair<double, double> drop_unevaluated(std::vector<double>& T,
                                           std::vector<unsigned char>& corner,
                                           const std::vector<double>& bound, double area_P,
                                           double allowed, double least, long long& count) {
    const std::vector<double> area = triangle_areas(T);
    const size_t t = area.size();
    std::vector<double> weight(t);
    for (size_t i = 0; i < t; ++i) weight[i] = bound[i] * area[i];
    std::vector<size_t> order(t);
    for (size_t i = 0; i < t; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t i, size_t j) { return weight[i] < weight[j]; });
    double running = 0.0, running_area = 0.0, skipped = 0.0, skipped_area = 0.0;
    size_t k = 0;
    for (; k + 1 < t; ++k) {
        running += weight[order[k]];
        running_area += area[order[k]];
        if (!(0.5 * running / area_P <= allowed)) break;
        skipped = running;
        skipped_area = running_area;
    }
    if (static_cast<double>(k) < least * static_cast<double>(t)) return {0.0, 0.0};
    std::vector<unsigned char> drop(t, 0);
    for (size_t i = 0; i < k; ++i) drop[order[i]] = 1;
    size_t kept = 0;
    for (size_t i = 0; i < t; ++i) {
        if (drop[i]) continue;
        for (int j = 0; j < 9; ++j) T[9 * kept + j] = T[9 * i + j];
        corner[kept++] = corner[i];
    }
    count += static_cast<long long>(t - kept);
    T.resize(9 * kept);
    corner.resize(kept);
    return {skipped_area, skipped};
}

// points.py's unoccluded_bound(Pc, Qc) and unoccluded_bounds, in points.py's order of
// operations: the bounding boxes' gap's square d2, Q's area and the cosines' spreads
// (each polygon's unit normal against the two polygons' vertices, h the widest spread of
// n . v between them, the products' rounding added)
struct BoundParts {
    double d2, area_Q, spread_p, spread_q;
};

BoundParts bound_parts(const double* Pc, std::int64_t n_p, const double* Qc, std::int64_t n_q,
                       double eps, double spread_ulps, bool fused) {
    BoundParts b;
    double gap[3];
    for (int j = 0; j < 3; ++j) {
        double pmin = Pc[j], pmax = Pc[j], qmin = Qc[j], qmax = Qc[j];
        for (std::int64_t i = 1; i < n_p; ++i) {
            pmin = std::min(pmin, Pc[3 * i + j]);
            pmax = std::max(pmax, Pc[3 * i + j]);
        }
        for (std::int64_t i = 1; i < n_q; ++i) {
            qmin = std::min(qmin, Qc[3 * i + j]);
            qmax = std::max(qmax, Qc[3 * i + j]);
        }
        gap[j] = std::max(0.0, std::max(pmin - qmax, qmin - pmax));
    }
    b.d2 = blas_dot3(gap, gap, fused);
    double AQ[3], AP[3];
    area_vector(Qc, n_q, AQ);
    b.area_Q = norm3(AQ, fused);
    // the vertices' coordinates' size: the largest sum of a vertex's absolute coordinates
    double scale_p = -INFINITY, scale_q = -INFINITY;
    for (std::int64_t i = 0; i < n_p; ++i)
        scale_p = std::max(scale_p, sum3(std::fabs(Pc[3 * i]), std::fabs(Pc[3 * i + 1]),
                                         std::fabs(Pc[3 * i + 2])));
    for (std::int64_t i = 0; i < n_q; ++i)
        scale_q = std::max(scale_q, sum3(std::fabs(Qc[3 * i]), std::fabs(Qc[3 * i + 1]),
                                         std::fabs(Qc[3 * i + 2])));
    const double scale = std::max(scale_p, scale_q);
    area_vector(Pc, n_p, AP);
    // each cosine: |n . (y - x)| / r <= h / d
    const auto spread = [&](const double* A, const double* X, std::int64_t nx, const double* Y,
                            std::int64_t ny) {
        const double norm = norm3(A, fused);
        const double n[3] = {A[0] / norm, A[1] / norm, A[2] / norm};
        const auto extremes = [&](const double* V, std::int64_t k, double& lo, double& hi) {
            lo = INFINITY;
            hi = -INFINITY;
            for (std::int64_t i = 0; i < k; ++i) {
                const double s = (V[3 * i] * n[0] + V[3 * i + 1] * n[1]) + V[3 * i + 2] * n[2];
                lo = std::min(lo, s);
                hi = std::max(hi, s);
            }
        };
        double xlo, xhi, ylo, yhi;
        extremes(X, nx, xlo, xhi);
        extremes(Y, ny, ylo, yhi);
        return std::max(yhi - xlo, xhi - ylo) + spread_ulps * eps * scale;
    };
    b.spread_p = spread(AP, Pc, n_p, Qc, n_q);
    b.spread_q = spread(AQ, Qc, n_q, Pc, n_p);
    return b;
}

// points.py's _cosine: a cosine's bound at the distance d
double cosine_bound(double spread, double d, double cos_slack) {
    return std::min(1.0, spread / d + cos_slack);
}

// points.py's unoccluded_bound(Pc, Qc): 1, and A_Q c_P c_Q / (pi d^2)
double unoccluded_bound(const BoundParts& b, double cos_slack) {
    if (!(b.d2 > 0)) return 1.0;
    const double d = std::sqrt(b.d2);
    const double c_p = cosine_bound(b.spread_p, d, cos_slack);
    const double c_q = cosine_bound(b.spread_q, d, cos_slack);
    return std::min(1.0, b.area_Q * c_p * c_q / (3.141592653589793 * b.d2));
}

// points.py's unoccluded_bounds: the bound of each triangle of T (t, 3, 3), its box's
// gap to Qc's box for d, at most Pc's bound whole
std::vector<double> unoccluded_bounds(const std::vector<double>& T, const double* Qc,
                                      std::int64_t n_q, const BoundParts& b, double whole,
                                      double cos_slack) {
    double qmin[3], qmax[3];
    for (int j = 0; j < 3; ++j) {
        qmin[j] = qmax[j] = Qc[j];
        for (std::int64_t i = 1; i < n_q; ++i) {
            qmin[j] = std::min(qmin[j], Qc[3 * i + j]);
            qmax[j] = std::max(qmax[j], Qc[3 * i + j]);
        }
    }
    const size_t t = T.size() / 9;
    std::vector<double> out(t, whole);
    for (size_t k = 0; k < t; ++k) {
        const double* V = T.data() + 9 * k;
        double g[3];
        for (int j = 0; j < 3; ++j) {
            const double lo = std::min(std::min(V[j], V[3 + j]), V[6 + j]);
            const double hi = std::max(std::max(V[j], V[3 + j]), V[6 + j]);
            g[j] = std::max(0.0, std::max(lo - qmax[j], qmin[j] - hi));
        }
        const double d2 = (g[0] * g[0] + g[1] * g[1]) + g[2] * g[2];
        if (!(d2 > 0)) continue;
        const double d = std::sqrt(d2);
        out[k] = std::min(whole, b.area_Q * cosine_bound(b.spread_p, d, cos_slack) *
                                     cosine_bound(b.spread_q, d, cos_slack) /
                                     (3.141592653589793 * d2));
    }
    return out;
}

}  // namespace

PairResult occluded_pair(const PairArgs& a) {
    const PairConstants& k = *a.k;
    PairResult out;
    const std::int64_t n_p = a.n_p, n_q = a.n_q;
    // the emitter's frame, centre, plane and disk
    double R[9];
    receiver_frame(a.nP, R);
    double c[3];
    for (int j = 0; j < 3; ++j) {
        double s = a.Pc[j];
        for (std::int64_t i = 1; i < n_p; ++i) s += a.Pc[3 * i + j];
        c[j] = s / static_cast<double>(n_p);
    }
    const double dP = blas_dot3(a.nP, a.Pc, k.fused_dot);
    double far = 0;
    for (std::int64_t i = 0; i < n_p; ++i) {
        const double* p = a.Pc + 3 * i;
        const double d0 = p[0] - c[0], d1 = p[1] - c[1], d2 = p[2] - c[2];
        far = std::max(far, std::sqrt(sum3(d0 * d0, d1 * d1, d2 * d2)));
    }
    const double radius = (1.0 + k.hidden_pad) * far;
    // the receiver's part's frame (geometry.py's plane_frame)
    double AQ[3], nQ[3], RQ[9];
    area_vector(a.Qc, n_q, AQ);
    const double lenQ = norm3(AQ, k.fused_dot);
    for (int j = 0; j < 3; ++j) nQ[j] = AQ[j] / lenQ;
    receiver_frame(nQ, RQ);
    const std::vector<double> Q2 = in_frame(a.Qc, n_q, a.Qc, RQ, k.fused_matmul);
    // the vertex-edge events and the curved ones
    EventArgs e;
    e.W = a.W;
    e.start = a.start;
    e.n = a.n;
    e.solid = a.shortcuts ? a.solid : nullptr;
    e.nP = a.nP;
    e.frame = R;
    e.c = c;
    e.dP = dP;
    e.radius = radius;
    e.nQ = nQ;
    e.q0 = a.Qc;
    e.RQ = RQ;
    e.Q2 = Q2.data();
    e.n_q2 = n_q;
    e.shortcuts = a.shortcuts;
    e.ray_parallel = k.ray_parallel;
    e.event_parallel = k.event_parallel;
    e.line_ulps = k.event_line_ulps;
    e.eps = k.eps;
    EventResult events = event_lines(e);
    CurvedArgs cv;
    cv.W = a.W;
    cv.start = a.start;
    cv.n = a.n;
    cv.solid = a.shortcuts ? a.solid : nullptr;
    cv.Qc = a.Qc;
    cv.n_q = n_q;
    cv.nP = a.nP;
    cv.frame = R;
    cv.c = c;
    cv.dP = dP;
    cv.radius = radius;
    cv.atol = a.atol;
    cv.hull_rtol = k.hull_rtol;
    cv.event_parallel = k.event_parallel;
    cv.extend_rtol = k.extend_rtol;
    cv.curve_rtol = k.curve_rtol;
    cv.samples = k.samples;
    cv.bisections = k.bisections;
    cv.max_triples = k.max_triples;
    cv.chord_split = k.chord_split;
    cv.chord_halvings = k.chord_halvings;
    cv.rows_per_call = k.rows_per_call;
    CurvedResult curved = curved_event_lines(cv);
    std::vector<double>& lines = events.segments;
    lines.insert(lines.end(), curved.segments.begin(), curved.segments.end());
    const std::int64_t n_lines = static_cast<std::int64_t>(lines.size() / 4);
    // umbras: the reference's
    if (a.shortcuts && n_lines > k.umbra_min_lines) {
        out.status = 1;
        return out;
    }
    // the arrangement's distinct lines: too many, the reference raises
    const std::vector<double> P2 = in_frame(a.Pc, n_p, c, R, k.fused_matmul);
    if (distinct_lines(lines, 2.0 * radius, P2, k.event_line_key) > k.max_event_lines) {
        out.status = 2;
        return out;
    }
    // the emitter cut along the events (events.py's cut_cells, compiled), covering P
    double AP[3];
    area_vector(a.Pc, n_p, AP);
    double area_Pc = norm3(AP, k.fused_dot);
    std::vector<double> terms(n_p);
    for (std::int64_t i = 0; i < n_p; ++i) {
        const std::int64_t j = (i + 1) % n_p;
        terms[i] = P2[2 * i] * P2[2 * j + 1] - P2[2 * j] * P2[2 * i + 1];
    }
    const double A2 = 0.5 * sum(terms);
    std::vector<double> ring(P2);
    if (!(A2 > 0))
        for (std::int64_t i = 0; i < n_p; ++i) {
            ring[2 * i] = P2[2 * (n_p - 1 - i)];
            ring[2 * i + 1] = P2[2 * (n_p - 1 - i) + 1];
        }
    double size = 0;
    for (int j = 0; j < 2; ++j) {
        double lo = P2[j], hi = P2[j];
        for (std::int64_t i = 1; i < n_p; ++i) {
            lo = std::min(lo, P2[2 * i + j]);
            hi = std::max(hi, P2[2 * i + j]);
        }
        size = std::max(size, hi - lo);
    }
    const CellResult cells = cut_cells(ring.data(), n_p, lines.data(), n_lines,
                                       k.extend_rtol * std::sqrt(std::fabs(A2)),
                                       k.hull_rtol * size, k.sliver_cell * std::fabs(A2));
    if (!cells.ok) {
        out.status = 3;
        return out;
    }
    const size_t t = cells.triangles.size() / 6;
    std::vector<double> T(9 * t);
    for (size_t i = 0; i < 3 * t; ++i)
        for (int j = 0; j < 3; ++j)
            T[3 * i + j] = c[j] + blas_dot2(&cells.triangles[2 * i], R + j, k.fused_stacked, 3);
    // (covering P to cell_cover_rtol of its area, or missing no more than the estimate's
    // charge for it keeps within cell_cover_atol_share of atol: adaptive.py's rule)
    const double cover_slack =
        std::max(k.cell_cover_rtol * area_Pc, k.cell_cover_atol_share * a.atol * a.area_P);
    if (!(sum(triangle_areas(T)) >= area_Pc - cover_slack)) {
        out.status = 3;
        return out;
    }
    // a blocker's vertex on the emitter first in its cells (levels.h's corner_first)
    const std::int64_t b0 = a.start[1];
    const double* Vb = a.W + 3 * b0;
    std::vector<unsigned char> corner;
    corner_first(T, Vb, a.start[a.n] - b0, a.nP, dP, 2.0 * k.extend_rtol * std::sqrt(area_Pc),
                 k.hull_rtol, corner);
    const long long start = T.size() / 9 <= static_cast<size_t>(k.many_cells) &&
                            a.atol < k.low_rules_tolerance;
    // the triangles of least bound times area left unevaluated within a share of atol,
    // each at half its bound on the unoccluded point values times its area (points.py's
    // unoccluded_bounds and unevaluated)
    const BoundParts parts =
        bound_parts(a.Pc, n_p, a.Qc, n_q, k.eps, k.bound_spread_ulps, k.fused_dot);
    const double bound = unoccluded_bound(parts, k.bound_cos_slack);
    double skipped = 0.0, weight = 0.0;
    if (a.shortcuts && !T.empty())
        std::tie(skipped, weight) = drop_unevaluated(
            T, corner, unoccluded_bounds(T, a.Qc, n_q, parts, bound, k.bound_cos_slack),
            a.area_P, k.unevaluated_share * a.atol, k.unevaluated_least, out.unevaluated);
    area_Pc -= skipped;
    const size_t tc = T.size() / 9;
    // the hidden set-up (hidden.py's hidden_setup) of the blockers not in Qc's plane
    // (which hide nothing; with solids, the reference's)
    const double off = blas_dot3(nQ, a.Qc, k.fused_dot);
    std::vector<double> Wk;
    std::vector<std::int64_t> bstart{0};
    const bool solids = a.solid && a.inner;
    for (std::int64_t b = 1; b < a.n; ++b) {
        const double* K = a.W + 3 * a.start[b];
        const std::int64_t kb = a.start[b + 1] - a.start[b];
        if (in_plane(K, kb, nQ, off, k.coplanar_ulps, k.eps, k.fused_matmul)) {
            if (a.solid) {
                out.status = 4;
                return out;
            }
            continue;
        }
        Wk.insert(Wk.end(), K, K + 3 * kb);
        bstart.push_back(bstart.back() + kb);
    }
    if (bstart.size() == 1) {
        out.status = 5;
        return out;
    }
    SetupArgs sa;
    sa.Qc = a.Qc;
    sa.n_q = n_q;
    sa.W = Wk.data();
    sa.start = bstart.data();
    sa.n = static_cast<std::int64_t>(bstart.size()) - 1;
    sa.solid = solids ? a.solid + 1 : nullptr;
    sa.inner = solids ? a.inner + 3 : nullptr;
    sa.eps = k.eps;
    sa.convex_ulps = k.convex_ulps;
    sa.meet_ulps = k.meet_ulps;
    sa.normal_floor = k.normal_floor;
    sa.strict_turn = k.strict_turn;
    sa.hull_rtol = k.hull_rtol;
    const SetupResult setup = hidden_setup(sa);
    if (setup.status) {
        out.status = 5;
        return out;
    }
    // the adaptive levels
    const std::vector<double> areas = triangle_areas(T);
    const double total_area = sum(areas);
    LevelArgs la;
    la.T = std::move(T);
    la.depth.assign(tc, 0);
    la.rung.assign(tc, start);
    la.corner = corner;
    la.nP = a.nP;
    la.frame = R;
    la.area_P = a.area_P;
    la.total_area = total_area;
    la.atol = a.atol;
    la.rules_err = 0.0;
    la.start = start;
    for (int r = 0; r < kLevelRules; ++r) la.rules[r] = &k.rules[r];
    la.symmetric = a.atol >= k.low_rules_tolerance;
    la.Qc = a.Qc;
    la.n_q = n_q;
    HiddenArgs& h = la.hidden;
    h.corners = a.Qc;
    h.n_corners = n_q;
    h.q0 = setup.q0;
    h.nQ = setup.nQ;
    h.RQ = setup.RQ;
    h.blockers = setup.V.data();
    h.n_blockers = static_cast<std::int64_t>(setup.counts.size());
    h.blocker_stride = setup.stride;
    h.counts = setup.counts.data();
    h.normals = setup.NK.data();
    h.groups = setup.group.data();
    h.parts = nullptr;
    h.n_parts = 0;
    h.part_stride = 3;
    h.part_counts = nullptr;
    h.frame = R;
    h.extent = setup.extent;
    h.vertex_ulps = k.vertex_ulps;
    h.sliver_ulps = k.sliver_ulps;
    h.max_pieces = k.max_pieces;
    h.precise_rtol = k.precise_rtol;
    h.c1 = k.c1;
    h.c2 = k.c2;
    h.eps = k.eps;
    la.lo = setup.lo;
    la.hi = setup.hi;
    long long count = 1 + n_q;
    for (long long m : setup.counts) count += m;
    la.lines = static_cast<double>(count);
    la.sliver_share = k.sliver_share;
    la.small_share = k.small_share;
    la.small_reach = k.small_reach;
    la.null_factor = k.null_factor;
    la.budget_share = k.budget_share;
    la.back_face_rtol = k.back_face_rtol;
    la.edge_on_rtol = k.edge_on_rtol;
    la.precise_share = k.precise_share;
    la.boolean_ulps = k.boolean_ulps;
    la.image_rtol = k.image_rtol;
    la.eps = k.eps;
    la.c1 = k.c1;
    la.c2 = k.c2;
    la.offset_ulps = k.offset_ulps;
    la.max_depth = k.max_depth;
    la.points_per_call = k.points_per_call;
    const LevelResult r = adaptive_levels(la);
    if (!r.ok) {
        out.status = 6;
        return out;
    }
    // the rules' errors on U against the pair's closed form: where they do not add up,
    // the reference checks the triangles one by one
    const size_t m = r.hi.size();
    std::vector<double> dF(m), both(m);
    for (size_t i = 0; i < m; ++i) {
        dF[i] = std::fabs((r.hiU[i] - r.loU[i]) - (r.hi[i] - r.lo[i]));
        both[i] = r.diff[i] + dF[i];
    }
    const double slivers = 0.0 + r.slivers;
    const double lost = (slivers + std::max(area_Pc - total_area, 0.0)) / a.area_P +
                        weight / a.area_P;
    const double missed_U = std::fabs(sum(r.hiU) - a.whole_value) - sum(both) - sum(r.rndU) -
                            a.whole_err - lost;
    if (!(missed_U <= 0) && m) {
        out.status = 7;
        return out;
    }
    // the value: the unoccluded one less the hidden part, the slivers at half their bound
    const double half = 0.5 * (bound * slivers + weight) / a.area_P;
    std::vector<double> err_terms(m);
    for (size_t i = 0; i < m; ++i) err_terms[i] = r.diff[i] + r.rnd[i];
    const double hidden = half + sum(r.hi);
    double err = half + sum(err_terms);
    out.value = a.whole_value - hidden;
    err += std::max(area_Pc - total_area, 0.0) / a.area_P;
    out.err = err + a.whole_err;
    out.points = r.points;
    out.culled_events = events.culled_events;
    out.solid_events = events.solid_events;
    out.curved_events = curved.events;
    out.curved_skipped = curved.skipped;
    out.back_faces = r.back_faces;
    return out;
}

}  // namespace exactff
