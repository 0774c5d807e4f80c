// The discrete methods' z-buffer (zbuffer.h): the clippers (a bucket to a chart's or a
// face's frustum, or to the horizon), the scan conversions (a face's scanlines, the
// polar plane's rays, the disk's ellipse arcs, directions under a chart), the depth
// buffer's chunked resolution (resolve_depths) and a row's sums. Every floating-point
// expression is the numpy code's, in its order (exactff/methods/_raster.py,
// _sampling.py, exactff/visibility/charts.py, exactff/halfspace.py).

#include "zbuffer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "constants.h"

namespace exactff {
namespace zbuffer {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();

// numpy's einsum("ij,ij->i") over three components: (x0 y0 + x2 y2) + x1 y1
inline double dot3(const double* a, const double* b) {
    return (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1];
}

inline double absdot3(const double* a, const double* b) {
    return (std::fabs(a[0]) * std::fabs(b[0]) + std::fabs(a[2]) * std::fabs(b[2]))
           + std::fabs(a[1]) * std::fabs(b[1]);
}

// one scratch per thread, grown as needed and reset cell by cell after every chunk
// (a row's buffer of 200,000 cells is not allocated and cleared again row by row):
// CellScratch's fields, the nearest depth per cell (INF: no candidate yet), and room
// for the list of the cells the chunk touched
struct Scratch {
    std::vector<CellScratch> cell;
    std::vector<double> t_min;
    std::vector<std::int64_t> touched;
};

Scratch& scratch(std::int64_t n_cells) {
    thread_local Scratch sc;
    if (static_cast<std::int64_t>(sc.cell.size()) < n_cells) {
        sc.cell.resize(static_cast<size_t>(n_cells));
        sc.t_min.resize(static_cast<size_t>(n_cells), INF);
        // (one more: a candidate writes its cell before counting it)
        sc.touched.resize(static_cast<size_t>(n_cells) + 1);
    }
    return sc;
}

// ---- the chart clipper: exactff.visibility.charts.chart_clip (margin 0) and
// exactff.halfspace.clip_halfspace, expression for expression ----

// V @ h with h of the chart's axes (components 0, +-1): exact whatever the order
static inline double hdot(const double* h, const double* x) {
    return (h[0] * x[0] + h[1] * x[1]) + h[2] * x[2];
}

static inline double sum_abs3(double a, double b, double c) {
    return (std::fabs(a) + std::fabs(b)) + std::fabs(c);
}

// clip_halfspace: polygons V (M, K, 3) with counts to h . x > 0; out (M, Kn, 3)
static void clip_halfspace(const std::vector<double>& V, i64 M, i64 K,
                           const std::vector<i64>& counts, const double* h, const double C,
                           std::vector<double>& out, i64& Kn, std::vector<i64>& nc) {
    const double floor_ = std::numeric_limits<double>::min() / EPS;   // NORMAL_FLOOR
    const double hsum = sum_abs3(h[0], h[1], h[2]);
    std::vector<double> tmp(static_cast<size_t>(M * 2 * K * 3));
    std::vector<double> s(static_cast<size_t>(K));
    nc.assign(static_cast<size_t>(M), 0);
    i64 kmax = 0;
    for (i64 m = 0; m < M; ++m) {
        const double* P = V.data() + m * K * 3;
        const i64 n = counts[m];
        for (i64 k = 0; k < K; ++k) s[k] = hdot(h, P + 3 * k);
        double* o = tmp.data() + m * 2 * K * 3;
        i64 w = 0;
        for (i64 k = 0; k < n; ++k) {
            const i64 j = (k + 1) % n;
            const bool in = s[k] > 0, in_n = s[j] > 0;
            if (in) {
                for (int i = 0; i < 3; ++i) o[3 * w + i] = P[3 * k + i];
                ++w;
            }
            if (in == in_n) continue;
            // the crossing from the inside end point: interpolated, or the meet of
            // the edge's plane through the origin with h where it is as good
            const double* A = in ? P + 3 * k : P + 3 * j;
            const double* B = in ? P + 3 * j : P + 3 * k;
            const double sa = in ? s[k] : s[j], sb = in ? s[j] : s[k];
            const double t = sa / (sa - sb);
            double X[3], e[3];
            for (int i = 0; i < 3; ++i) {
                X[i] = A[i] + t * (B[i] - A[i]);
                e[i] = B[i] - A[i];
            }
            const double d = sa - sb;
            const double mm[3] = {A[1] * e[2] - A[2] * e[1], A[2] * e[0] - A[0] * e[2],
                                  A[0] * e[1] - A[1] * e[0]};
            const double la = sum_abs3(A[0], A[1], A[2]), le = sum_abs3(e[0], e[1], e[2]);
            const double meet[3] = {(mm[1] * h[2] - mm[2] * h[1]) / d,
                                    (mm[2] * h[0] - mm[0] * h[2]) / d,
                                    (mm[0] * h[1] - mm[1] * h[0]) / d};
            const double cond = 1.0 + hsum * le / std::fabs(d);
            // (and on the edge's line to rounding: halfspace.clip_halfspace)
            const double r[3] = {meet[0] - A[0], meet[1] - A[1], meet[2] - A[2]};
            const bool use =
                (sum_abs3(meet[0] - X[0], meet[1] - X[1], meet[2] - X[2]) <=
                 C * EPS * (la + le) * cond) &&
                (sum_abs3(r[1] * e[2] - r[2] * e[1], r[2] * e[0] - r[0] * e[2],
                          r[0] * e[1] - r[1] * e[0]) <= C * EPS * (la + le) * le) &&
                (cond * C * EPS < 1.0) &&
                (sum_abs3(mm[0], mm[1], mm[2]) > C * EPS * la * le) &&
                (std::fabs(d) > floor_) && (la * le > floor_);
            for (int i = 0; i < 3; ++i) o[3 * w + i] = use ? meet[i] + 0.0 : X[i];
            ++w;
        }
        nc[m] = w;
        kmax = std::max(kmax, w);
    }
    Kn = std::max<i64>(kmax, 1);
    out.assign(static_cast<size_t>(M * Kn * 3), 0.0);
    for (i64 m = 0; m < M; ++m)
        std::copy(tmp.data() + m * 2 * K * 3, tmp.data() + m * 2 * K * 3 + nc[m] * 3,
                  out.data() + m * Kn * 3);
}

// S polygons Vc (S, Kc, 3) with counts cc clipped plane after plane (planes
// (n_planes, 3)), as chart_clip and FaceClip loop: each time the polygons with
// fewer than 3 vertices left given count 0, and no more planes once none has 3;
// Kc becomes the last clip's width
static void clip_planes(std::vector<double>& Vc, i64 S, i64& Kc, std::vector<i64>& cc,
                        const double* planes, i64 n_planes, double meet_ulps) {
    std::vector<double> next;
    std::vector<i64> ncount;
    for (i64 j = 0; j < n_planes; ++j) {
        bool any = false;
        for (const i64 n : cc) any = any || n >= 3;
        if (!any) break;
        for (i64& n : cc) if (n < 3) n = 0;
        i64 Kn;
        clip_halfspace(Vc, S, Kc, cc, planes + 3 * j, meet_ulps, next, Kn, ncount);
        Vc.swap(next);
        cc.swap(ncount);
        Kc = Kn;
    }
}

// np.spacing(|x|): the gap to the next double (NaN for inf and NaN)
static inline double spacing_abs(double x) {
    x = std::fabs(x);
    if (!std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
    return std::nextafter(x, INF) - x;
}

// charts.merge_close over the values x: near-coincident ones (each within
// CHART_EDGE_ULPS ulps of the previous, sorted) replaced by the first of their run;
// NaN sorts last and compares false, as numpy's unique and diff have it
static void merge_close(std::vector<double>& x, double ulps) {
    std::vector<double> u(x);
    std::sort(u.begin(), u.end(), [](double a, double b) {
        if (std::isnan(a)) return false;
        if (std::isnan(b)) return true;
        return a < b;
    });
    // unique (NaNs collapsed)
    std::vector<double> q;
    for (const double a : u) {
        if (!q.empty() && (q.back() == a || (std::isnan(q.back()) && std::isnan(a)))) continue;
        q.push_back(a);
    }
    std::vector<double> first(q.size());
    for (size_t i = 0; i < q.size(); ++i) {
        const bool new_run = i == 0 || (q[i] - q[i - 1] > ulps * spacing_abs(q[i]));
        first[i] = new_run ? q[i] : first[i - 1];
    }
    for (double& a : x) {
        size_t i;
        if (std::isnan(a)) {
            i = q.size() - 1;
        } else {
            i = std::lower_bound(q.begin(), q.end(), a, [](double p, double v) {
                    return !std::isnan(p) && p < v;
                }) - q.begin();
        }
        a = first[i];
    }
}

// ---- what the scans share ----

// the spans [X_1, X_2), [X_3, X_4), ... (X sorted, at most `slots` of them) as runs
// of centres c (first centre at or above each end), each cell given to emit(col)
template <class Emit>
static void spans(const std::vector<double>& X, size_t slots, const double* c, i64 n,
                  Emit&& emit) {
    const size_t npairs = std::min(X.size() / 2, slots);
    for (size_t k = 0; k < npairs; ++k) {
        const i64 ia = std::lower_bound(c, c + n, X[2 * k]) - c;
        const i64 ib = std::lower_bound(c, c + n, X[2 * k + 1]) - c;
        for (i64 col = ia; col < ib; ++col) emit(col);
    }
}

// numpy's floor modulo of floats (np.remainder; the divisor positive)
static inline double py_mod(double a, double b) {
    double m = std::fmod(a, b);
    if (m != 0.0) {
        if (m < 0.0) m += b;
    } else {
        m = 0.0;
    }
    return m;
}

// a . b added in order, (x0 y0 + x1 y1) + x2 y2 (the disk's numpy expressions)
static inline double dot_seq(const double* a, const double* b) {
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
}

// numpy's maximum and minimum (a NaN propagates), and sign
static inline double np_max(double a, double b) {
    return (std::isnan(a) || std::isnan(b)) ? std::numeric_limits<double>::quiet_NaN()
                                             : std::max(a, b);
}
static inline double np_min(double a, double b) {
    return (std::isnan(a) || std::isnan(b)) ? std::numeric_limits<double>::quiet_NaN()
                                             : std::min(a, b);
}
static inline double np_sign(double x) {
    return x > 0 ? 1.0 : x < 0 ? -1.0 : x == 0 ? 0.0 : std::numeric_limits<double>::quiet_NaN();
}

// ---- the clippers of a bucket ----

// chart_clip (margin 0): the polygons that reach the chart's frustum, those straddling it
// clipped plane by plane, projected into the chart, snapped onto its edges and merged
// along them
static void clip_to_chart(const double* V, i64 M, i64 K, const i64* counts,
                          const double* planes, const double* eu, const double* ev,
                          const double* ew, bool side, double meet_ulps, double edge_ulps,
                          Clipped& out) {
    // which polygons reach the frustum, which lie wholly inside it
    std::vector<i64> reach, straddle;
    std::vector<char> inside_all;
    for (i64 m = 0; m < M; ++m) {
        const double* P = V + m * K * 3;
        const i64 n = counts[m];
        bool outside = false, inside = true;
        for (int j = 0; j < 4; ++j) {
            bool all_out = true;
            for (i64 k = 0; k < n; ++k) {
                const double sv = hdot(planes + 3 * j, P + 3 * k);
                // (a NaN is neither out nor in, as numpy's comparisons have it)
                if (!(sv <= 0)) all_out = false;
                if (!(sv > 0)) inside = false;
            }
            if (all_out) outside = true;
        }
        if (!outside && n >= 3) {
            reach.push_back(m);
            inside_all.push_back(inside ? 1 : 0);
            if (!inside) straddle.push_back(m);
        }
    }
    // the straddling ones clipped plane by plane
    const i64 S = static_cast<i64>(straddle.size());
    std::vector<double> Vc(static_cast<size_t>(S * K * 3));
    std::vector<i64> cc(static_cast<size_t>(S));
    for (i64 i = 0; i < S; ++i) {
        std::copy(V + straddle[i] * K * 3, V + (straddle[i] + 1) * K * 3, Vc.data() + i * K * 3);
        cc[i] = counts[straddle[i]];
    }
    i64 Kc = K;
    clip_planes(Vc, S, Kc, cc, planes, 4, meet_ulps);
    const i64 Kr = std::max(K, Kc);
    // the live ones, padded by their last vertex, projected into the chart
    out.live.clear();
    out.cl.clear();
    out.K = Kr;
    std::vector<double> P3(static_cast<size_t>(Kr * 3));
    i64 si = 0;
    for (size_t r = 0; r < reach.size(); ++r) {
        const i64 m = reach[r];
        const double* src;
        i64 n, Ks;
        if (inside_all[r]) {
            src = V + m * K * 3;
            n = counts[m];
            Ks = K;
        } else {
            src = Vc.data() + si * Kc * 3;
            n = cc[si];
            Ks = Kc;
            ++si;
        }
        if (n < 3) continue;
        if (n > Ks) throw std::logic_error("clipped count exceeds its width");
        for (i64 k = 0; k < Kr; ++k) {
            const i64 kk = k < n ? k : n - 1;
            for (int i = 0; i < 3; ++i) P3[3 * k + i] = src[3 * kk + i];
        }
        out.live.push_back(m);
        out.cl.push_back(n);
        for (i64 k = 0; k < Kr; ++k) {
            const double* x = P3.data() + 3 * k;
            const double w = hdot(ew, x);
            out.UV.push_back(hdot(eu, x) / w);
            out.UV.push_back(hdot(ev, x) / w);
        }
    }
    std::vector<double>& UV = out.UV;
    const double tiny = std::numeric_limits<double>::min();
    // subnormal chart coordinates flushed to zero
    for (double& a : UV)
        if (std::fabs(a) < tiny) a = 0.0;
    // points within CHART_EDGE_ULPS ulps of the chart's edges snapped onto them
    const double near1 = edge_ulps * (std::nextafter(1.0, 2.0) - 1.0);
    for (const double val : {-1.0, 1.0})
        for (double& a : UV)
            if (std::fabs(a - val) <= near1) a = val;
    if (side)
        for (size_t i = 1; i < UV.size(); i += 2)
            if (std::fabs(UV[i]) <= near1) UV[i] = 0.0;
    // and points along an edge within a few ulps of each other merged
    const std::vector<double> e01 = {-1.0, 1.0};
    const std::vector<double> e1 = side ? std::vector<double>{-1.0, 0.0, 1.0} : e01;
    std::vector<size_t> idx;
    std::vector<double> vals;
    for (int k = 0; k < 2; ++k) {
        const std::vector<double>& edge_vals = k == 0 ? e1 : e01;
        for (const double val : edge_vals) {
            idx.clear();
            for (size_t i = 0; i < UV.size() / 2; ++i)
                if (UV[2 * i + (1 - k)] == val) idx.push_back(2 * i + k);
            if (idx.size() <= 1) continue;
            vals.resize(idx.size());
            for (size_t i = 0; i < idx.size(); ++i) vals[i] = UV[idx[i]];
            merge_close(vals, edge_ulps);
            for (size_t i = 0; i < idx.size(); ++i) UV[idx[i]] = vals[i];
        }
    }
}

// FaceClip: the vertices in the face's frame W = R x (each row's products added
// first to second, then the third, as the numpy code writes it); the polygons that
// reach the frustum (no plane with every vertex on or behind it) clipped plane by
// plane (clip_halfspace: the planes' entries 0 and +-1 make h . W exact); the live
// ones padded by their last vertex and projected, u = (scale W_0) / W_2,
// v = (scale W_1) / W_2.
static void clip_to_face(const double* V, i64 M, i64 K, const i64* counts, const double* R,
                         const double* planes, i64 n_planes, double scale, double meet_ulps,
                         Clipped& out) {
    std::vector<double> W(static_cast<size_t>(M * K * 3));
    for (i64 q = 0; q < M * K; ++q) {
        const double* x = V + 3 * q;
        for (int i = 0; i < 3; ++i)
            W[3 * q + i] = (x[0] * R[3 * i] + x[1] * R[3 * i + 1]) + x[2] * R[3 * i + 2];
    }
    std::vector<i64> reach;
    for (i64 m = 0; m < M; ++m) {
        const i64 n = counts[m];
        bool outside = false;
        for (i64 j = 0; j < n_planes && !outside; ++j) {
            bool all_out = true;
            for (i64 k = 0; k < n; ++k)
                if (!(hdot(planes + 3 * j, W.data() + 3 * (m * K + k)) <= 0)) all_out = false;
            outside = all_out;
        }
        if (!outside && n >= 3) reach.push_back(m);
    }
    const i64 S = static_cast<i64>(reach.size());
    std::vector<double> Vc(static_cast<size_t>(S * K * 3));
    std::vector<i64> cc(static_cast<size_t>(S));
    for (i64 i = 0; i < S; ++i) {
        std::copy(W.data() + reach[i] * K * 3, W.data() + (reach[i] + 1) * K * 3,
                  Vc.data() + i * K * 3);
        cc[i] = counts[reach[i]];
    }
    i64 Kc = K;
    clip_planes(Vc, S, Kc, cc, planes, n_planes, meet_ulps);
    out.live.clear();
    out.cl.clear();
    out.UV.clear();
    out.K = Kc;
    for (i64 i = 0; i < S; ++i) {
        const i64 n = cc[i];
        if (n < 3) continue;
        out.live.push_back(reach[i]);
        out.cl.push_back(n);
        for (i64 k = 0; k < Kc; ++k) {
            const double* x = Vc.data() + 3 * (i * Kc + (k < n ? k : n - 1));
            out.UV.push_back((scale * x[0]) / x[2]);
            out.UV.push_back((scale * x[1]) / x[2]);
        }
    }
}

static void clip_horizon(const double* V, i64 M, i64 K, const i64* counts, double meet_ulps,
                         double near_rel, Horizon& h) {
    std::vector<double> Vs(static_cast<size_t>(M * K * 3));
    for (i64 q = 0; q < M * K; ++q) {
        Vs[3 * q] = V[3 * q + 1];
        Vs[3 * q + 1] = V[3 * q];
        Vs[3 * q + 2] = V[3 * q + 2];
    }
    std::vector<i64> cnt(counts, counts + M), nc;
    std::vector<double> out;
    const double ez[3] = {0.0, 0.0, 1.0};
    i64 Kn;
    clip_halfspace(Vs, M, K, cnt, ez, meet_ulps, out, Kn, nc);
    h.K = Kn;
    h.live.clear(); h.near.clear(); h.cc.clear(); h.Vc.clear();
    for (i64 m = 0; m < M; ++m) {
        const i64 n = nc[m];
        if (n < 3) continue;
        const double* P = out.data() + m * Kn * 3;
        // _passes_near_origin: an edge's closest point to the origin within
        // near_rel of its longer end point's distance
        bool near = false;
        for (i64 e = 0; e < n && !near; ++e) {
            const double* a = P + 3 * e;
            const double* b = P + 3 * ((e + 1) % n);
            const double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const double dd = dot_seq(d, d);
            double s = -dot_seq(a, d) / dd;
            s = std::isnan(s) ? 0.0 : std::min(std::max(s, 0.0), 1.0);
            const double q[3] = {a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]};
            const double closest = std::sqrt(dot_seq(q, q));
            const double scale = np_max(std::sqrt(dot_seq(a, a)), std::sqrt(dot_seq(b, b)));
            near = closest <= near_rel * scale;
        }
        h.live.push_back(m);
        h.near.push_back(near ? 1 : 0);
        h.cc.push_back(n);
        for (i64 k = 0; k < Kn; ++k) {
            const double* x = P + 3 * (k < n ? k : n - 1);
            h.Vc.insert(h.Vc.end(), x, x + 3);
        }
    }
}

}  // namespace

// ---- the public clippers and a row's sums ----

void clip_chart(const Bucket& b, const Chart& ch, double meet_ulps, double edge_ulps,
                Clipped& out) {
    clip_to_chart(b.V, b.M, b.K, b.counts, ch.planes, ch.eu, ch.ev, ch.ew, ch.side, meet_ulps,
                  edge_ulps, out);
}

void clip_face(const Bucket& b, const Face& f, double meet_ulps, Clipped& out) {
    clip_to_face(b.V, b.M, b.K, b.counts, f.R, f.planes, f.n_planes, f.scale, meet_ulps, out);
}

i64 row_sums(const i64* best, i64 C, const i64* ids, i64 L, const bool* receives,
             const double* weights, i64 n, double* F) {
    i64 hit = 0;
    std::fill(F, F + n, 0.0);
    // F[j] kept in a register over a run of cells showing j (the same additions in the
    // same order; neighbouring cells mostly show the same polygon)
    i64 cur = -1;
    double acc = 0.0;
    for (i64 c = 0; c < C; ++c) {
        if (best[c] < 0) continue;
        if (best[c] >= L) return -1;
        ++hit;
        const i64 j = ids[best[c]];
        if (!receives[j]) continue;
        if (j != cur) {
            if (cur >= 0) F[cur] = acc;
            cur = j;
            acc = F[j];
        }
        acc += weights[c];
    }
    if (cur >= 0) F[cur] = acc;
    return hit;
}

// ---- a row's live polygons ----

void live_local(const double* V, i64 M, i64 K, const i64* counts, const bool* alive,
                const double* p, const double* R, std::vector<i64>& live,
                std::vector<double>& local) {
    live.clear();
    local.clear();
    std::vector<double> W(static_cast<size_t>(3 * K));
    for (i64 m = 0; m < M; ++m) {
        if (!alive[m]) continue;
        const double* P = V + m * K * 3;
        for (i64 e = 0; e < K; ++e) {
            const double x = P[3 * e] - p[0], y = P[3 * e + 1] - p[1], z = P[3 * e + 2] - p[2];
            for (int k = 0; k < 3; ++k)
                W[3 * e + k] = (x * R[3 * k] + y * R[3 * k + 1]) + z * R[3 * k + 2];
        }
        // the largest z of the polygon's vertices (numpy's max: a NaN propagates)
        double top = -INF;
        for (i64 e = 0; e < counts[m]; ++e) top = np_max(top, W[3 * e + 2]);
        if (!(top > 0)) continue;
        live.push_back(m);
        local.insert(local.end(), W.begin(), W.end());
    }
}

// ---- Monte Carlo's directions and their charts ----

void direction_norms(const double* D, i64 n, double* norms) {
    for (i64 k = 0; k < n; ++k) {
        const double* d = D + 3 * k;
        norms[k] = std::sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]);
    }
}

void cosine_directions(const double* q1, const double* q2, i64 n, double* D, double* norms) {
    const double two_pi = 2.0 * 3.141592653589793;
    for (i64 k = 0; k < n; ++k) {
        const double r = std::sqrt(q1[k]), a = two_pi * q2[k];
        const double x = r * std::cos(a), y = r * std::sin(a);
        const double zz = (1.0 - x * x) - y * y;
        double z = std::sqrt(zz > 0.0 ? zz : 0.0);
        if (z == 0.0) z = 1e-300;        // a ray exactly on the horizon: kept above it
        const double len = std::sqrt((x * x + y * y) + z * z);
        D[3 * k] = x / len;
        D[3 * k + 1] = y / len;
        D[3 * k + 2] = z / len;
    }
    direction_norms(D, n, norms);
}

void ray_charts(const double* D, i64 n, const i64* axis, const double* sign_w, double margin,
                std::vector<RayChart>& charts, i64* slot) {
    // _chart_of: the top chart where z >= max(|x|, |y|), else the side of the larger
    // horizontal component; u = d_u / w, v = d_v / w with w = +-d_w
    std::vector<std::int8_t> chart(static_cast<size_t>(n));
    std::vector<double> uv(static_cast<size_t>(2 * n));
    i64 count[5] = {0, 0, 0, 0, 0};
    for (i64 k = 0; k < n; ++k) {
        const double* d = D + 3 * k;
        const double ax = std::fabs(d[0]), ay = std::fabs(d[1]), az = d[2];
        int c;
        if (az >= np_max(ax, ay))
            c = 0;
        else if (ax >= ay)
            c = d[0] > 0 ? 1 : 2;
        else
            c = d[1] > 0 ? 3 : 4;
        chart[k] = static_cast<std::int8_t>(c);
        const double w = d[axis[3 * c + 2]] * sign_w[c];
        uv[2 * k] = d[axis[3 * c]] / w;
        uv[2 * k + 1] = d[axis[3 * c + 1]] / w;
        ++count[c];
    }
    // _cell_grid per chart: nb x nb buckets over [-1, 1] x [v_lo, 1]; the charts' buckets
    // numbered one after the other, the directions sorted by them (a stable counting
    // sort: numpy's stable argsort)
    charts.clear();
    i64 first[6] = {0, 0, 0, 0, 0, 0}, offset = 0;
    std::vector<i64> chart_at(5, -1);
    for (int c = 0; c < 5; ++c) {
        first[c + 1] = first[c];
        if (count[c] == 0) continue;
        RayChart rc;
        rc.chart = c;
        rc.offset = offset;
        rc.count = count[c];
        rc.v_lo = c != 0 ? -margin : -1.0 - margin;
        rc.nb = std::max<i64>(1, static_cast<i64>(std::sqrt(static_cast<double>(count[c]) / 16.0)));
        first[c + 1] += rc.nb * rc.nb;
        offset += count[c];
        chart_at[c] = static_cast<i64>(charts.size());
        charts.push_back(std::move(rc));
    }
    std::vector<std::int32_t> bucket(static_cast<size_t>(n));
    std::vector<i64> start(static_cast<size_t>(first[5] + 1), 0);
    for (i64 k = 0; k < n; ++k) {
        const int c = chart[k];
        const RayChart& rc = charts[chart_at[c]];
        const i64 nb = rc.nb;
        const double fnb = static_cast<double>(nb);
        // numpy's astype(int) truncates; then clipped to the grid
        const i64 bx = std::min(std::max<i64>(static_cast<i64>((uv[2 * k] + 1.0) * 0.5 * fnb), 0),
                                nb - 1);
        const i64 by = std::min(std::max<i64>(static_cast<i64>((uv[2 * k + 1] - rc.v_lo) /
                                                               (1.0 - rc.v_lo) * fnb),
                                              0),
                                nb - 1);
        const i64 b = first[c] + bx * nb + by;
        bucket[k] = static_cast<std::int32_t>(b);
        ++start[b + 1];
    }
    for (i64 b = 0; b < first[5]; ++b) start[b + 1] += start[b];
    for (RayChart& rc : charts) {
        const i64 f = first[rc.chart], nbb = rc.nb * rc.nb;
        rc.starts.resize(static_cast<size_t>(nbb + 1));
        for (i64 b = 0; b <= nbb; ++b) rc.starts[b] = start[f + b] - rc.offset;
        rc.cu.resize(static_cast<size_t>(rc.count));
        rc.cv.resize(static_cast<size_t>(rc.count));
    }
    // (the charts' buckets follow each other as their directions do: start is the
    // renumbering)
    for (i64 k = 0; k < n; ++k) {
        const i64 at = start[bucket[k]]++;
        slot[k] = at;
        RayChart& rc = charts[chart_at[chart[k]]];
        rc.cu[at - rc.offset] = uv[2 * k];
        rc.cv[at - rc.offset] = uv[2 * k + 1];
    }
}

// ---- the row's z-buffer: the entry points ----

void ZBuffer::face(const double* UV, i64 M, i64 K, const i64* cl, const i64* src,
                   const Grid& g, Buffer buf, Chunks ch) {
    scan(UV, M, K, cl, src, nullptr, g.u, g.nu, g.v, g.nv, g.table, buf.t, buf.best, ch.pair,
         ch.depth);
}

void ZBuffer::chart_face(const Bucket& b, const Chart& cf, const Grid& g, Buffer buf,
                         Chunks ch) {
    Clipped c;
    clip_chart(b, cf, row_.clip_meet_ulps, row_.chart_edge_ulps, c);
    scan(c.UV.data(), static_cast<i64>(c.live.size()), c.K, c.cl.data(), b.g_ids,
         c.live.data(), g.u, g.nu, g.v, g.nv, g.table, buf.t, buf.best, ch.pair, ch.depth);
}

void ZBuffer::candidates(const i64* cell, const i64* src, i64 n, Buffer buf,
                         i64 depth_chunk) {
    use_scratch();
    for (i64 k = 0; k < n; ++k) add(cell[k], src[k], buf.t, buf.best, depth_chunk);
    flush(buf.t, buf.best);
}

void ZBuffer::clipped_face(const Bucket& b, const Face& f, const Grid& g, Buffer buf,
                           Chunks ch) {
    Clipped c;
    clip_face(b, f, row_.clip_meet_ulps, c);
    scan(c.UV.data(), static_cast<i64>(c.live.size()), c.K, c.cl.data(), b.g_ids,
         c.live.data(), g.u, g.nu, g.v, g.nv, g.table, buf.t, buf.best, ch.pair, ch.depth);
}

void ZBuffer::polar(const Bucket& b, const Face& f, const double* radii, i64 nr,
                    const double* cs, const double* sn, i64 S, Buffer buf, Chunks ch) {
    Clipped c;
    clip_face(b, f, row_.clip_meet_ulps, c);
    scan_polar(c, b.g_ids, radii, nr, cs, sn, S, buf.t, buf.best, ch.pair, ch.depth);
}

std::vector<i64> ZBuffer::disk(const Bucket& b, const Grid& g, Buffer buf, Chunks ch,
                               double near_rel, bool after_near) {
    std::vector<i64> near;
    Horizon h;
    clip_horizon(b.V, b.M, b.K, b.counts, row_.clip_meet_ulps, near_rel, h);
    for (size_t k = 0; k < h.live.size(); ++k)
        if (h.near[k]) near.push_back(h.live[k]);
    if (near.empty() || after_near)
        scan_disk(h, b.g_ids, g.u, g.nu, g.v, g.nv, g.table, buf.t, buf.best, ch.pair,
                  ch.depth);
    return near;
}

bool ZBuffer::chart_rays(const Bucket& b, const Chart& cf, const i64* cells, const double* cu,
                         const double* cv, i64 nb, double v_lo, const i64* order,
                         const i64* starts, Buffer buf, i64 pair_chunk, i64 long_polygon) {
    Clipped c;
    clip_chart(b, cf, row_.clip_meet_ulps, row_.chart_edge_ulps, c);
    if (c.live.empty()) return true;
    if (c.K > long_polygon) return false;
    scan_rays(c, b.g_ids, cells, cu, cv, nb, v_lo, order, starts, buf.t, buf.best, pair_chunk);
    return true;
}

// ---- the depth buffer ----

// this thread's scratch for a call (the buffer's cells), the chunk's candidates
void ZBuffer::use_scratch() {
    Scratch& sc = scratch(row_.n_cells);
    sc_ = sc.cell.data();
    t_min_ = sc.t_min.data();
    touched_ = sc.touched.data();
    n_touched_ = 0;
    cand_.clear();
    in_chunk_ = 0;
}

// every vertex of polygon q (scene index) within the near-coplanar band of p's
// plane: |n . x - d| <= BSP_COPLANAR_ULPS u (|n| . |x| + |d|)
bool ZBuffer::within(i64 p, i64 q) const {
    const double* n = row_.N + 3 * p;
    const double d = row_.Dp[p];
    const i64* off = row_.offsets;
    const double* V = row_.V;
    const double w = row_.coplanar_ulps * EPS;
    for (i64 i = off[q]; i < off[q + 1]; ++i) {
        const double* x = V + 3 * i;
        const double mag = absdot3(x, n) + std::fabs(d);
        if (!(std::fabs(dot3(x, n) - d) <= w * mag)) return false;
    }
    return true;
}

// exactff.predicates.coplanar_pairs for live polygons (cached per pair)
bool ZBuffer::coplanar(i64 a, i64 b) {
    const i64 lo = std::min(a, b), hi = std::max(a, b);
    const std::uint64_t key =
        (static_cast<std::uint64_t>(lo) << 32) | static_cast<std::uint64_t>(hi);
    // neighbouring cells mostly ask about the same pair
    if (key == last_key_) return last_value_;
    auto it = cache_.find(key);
    bool r;
    if (it != cache_.end()) {
        r = it->second;
    } else {
        const i64 pa = row_.ids[a], pb = row_.ids[b];
        r = within(pa, pb) || within(pb, pa);
        cache_.emplace(key, r);
    }
    last_key_ = key;
    last_value_ = r;
    return r;
}

// resolve_depths on the buffered candidates
// one candidate (cell, live polygon) of the current chunk: its depth, the cell's
// nearest depth so far; a ray along its polygon's plane hits nothing
inline void ZBuffer::add(i64 cell, i64 s, double* best_t, i64* best, i64 depth_chunk) {
    const double den = dot3(row_.nl + 3 * s, row_.D + 3 * cell);
    const double t = row_.dl[s] / den;
    if (std::isfinite(t)) {
        // (without branches on the depths: they do not predict)
        double& tm = t_min_[cell];
        touched_[n_touched_] = cell;
        n_touched_ += tm == INF;
        tm = t < tm ? t : tm;
        cand_.push_back(Candidate{t, den, static_cast<std::int32_t>(cell),
                                  static_cast<std::int32_t>(s)});
    }
    // the numpy code's chunks count every candidate, hit or not
    if (++in_chunk_ == depth_chunk) flush(best_t, best);
}

// resolve_depths on the chunk's candidates, merged into the buffer
void ZBuffer::flush(double* best_t, i64* best) {
    in_chunk_ = 0;
    const size_t n = cand_.size();
    if (n == 0) return;
    const double* Dn = row_.Dnorm;
    const double* dl = row_.dl;
    const double* band = row_.band;
    const i64* prio = row_.prio;
    CellScratch* sc = sc_;
    const double* tmin = t_min_;
    const Candidate* cd = cand_.data();
    // one of the polygons at the nearest depth (the last, as numpy's assignment),
    // and of the polygons there the one of lowest priority (priorities are
    // distinct per polygon; a polygon is a candidate of a cell once in a chunk)
    for (size_t k = 0; k < n; ++k) {
        if (cd[k].t == tmin[cd[k].cell]) {
            CellScratch& c = sc[cd[k].cell];
            const i64 s = cd[k].s;
            c.near = s;
            if (prio[s] < c.p_min) {
                c.p_min = prio[s];
                c.pick = s;
            }
        }
    }
    // ties: within four times the tie test's band of the nearest depth, and
    // coplanar with the polygon there
    const double slack_ulps = row_.tie_slack_ulps;
    for (size_t k = 0; k < n; ++k) {
        const i64 cell = cd[k].cell, s = cd[k].s;
        const double t_near = tmin[cell];
        if (cd[k].t == t_near) continue;
        const double slack = 4.0 * (band[s] + EPS * (slack_ulps * std::fabs(t_near) * Dn[cell]
                                                     + std::fabs(dl[s])));
        if (std::fabs(t_near - cd[k].t) * std::fabs(cd[k].den) <= slack) {
            CellScratch& c = sc[cell];
            if (coplanar(c.near, s) && prio[s] < c.p_min) {
                c.p_min = prio[s];
                c.pick = s;
            }
        }
    }
    // merge with the cells' best so far: the nearer wins unless the other is
    // coplanar with it and of lower priority
    for (i64 q = 0; q < n_touched_; ++q) {
        const i64 cell = touched_[q];
        CellScratch& c = sc[cell];
        const i64 s = c.pick;
        if (s >= 0) {
            const double t = tmin[cell];
            const i64 old = best[cell];
            const bool has_old = old >= 0;
            const bool new_nearer = t < best_t[cell];
            bool take;
            if (!has_old)
                take = true;
            else if (new_nearer)
                take = prio[s] < prio[old] || !coplanar(old, s);
            else
                take = prio[s] < prio[old] && coplanar(s, old);
            if (t < best_t[cell]) best_t[cell] = t;
            if (take) best[cell] = s;
        }
        c = CellScratch();
        t_min_[cell] = INF;
    }
    cand_.clear();
    n_touched_ = 0;
}

// ---- a face's scan, scanline by scanline ----

namespace {

// one grid row of a face's table: the columns [lo, hi) hold its cells (-1 outside);
// `simple` when the cell there is base + col (one run of the layout's cells), else its
// prefix counts of cells, pre (nv + 1,)
struct GridRow {
    bool seen = false, simple = true;
    i64 lo = 0, hi = 0, base = 0;
    std::vector<std::int32_t> pre;
};

// the row's layout, its cells checked against the buffer's
void analyse_row(const i64* t, i64 nv, i64 n_cells, GridRow& g) {
    g.seen = true;
    i64 lo = nv, hi = 0;
    for (i64 col = 0; col < nv; ++col) {
        if (t[col] >= n_cells) throw std::invalid_argument("table's cells out of range");
        if (t[col] >= 0) {
            lo = std::min(lo, col);
            hi = col + 1;
        }
    }
    if (lo >= hi) {
        g.lo = g.hi = g.base = 0;
        return;
    }
    g.lo = lo;
    g.hi = hi;
    g.base = t[lo] - lo;
    for (i64 col = lo; col < hi && g.simple; ++col) g.simple = t[col] == g.base + col;
    if (!g.simple) {
        g.pre.assign(static_cast<size_t>(nv + 1), 0);
        for (i64 col = 0; col < nv; ++col) g.pre[col + 1] = g.pre[col] + (t[col] >= 0);
    }
}

// increasing centres c (n,) and std::lower_bound / upper_bound over them, started from
// the guess of evenly spaced centres and moved to the exact index (a binary search
// where the guess is far off)
struct Centres {
    const double* c;
    i64 n;
    double c0 = 0.0, inv_h = 0.0;

    Centres(const double* c_, i64 n_) : c(c_), n(n_) {
        if (n > 1 && c[n - 1] > c[0]) {
            c0 = c[0];
            inv_h = static_cast<double>(n - 1) / (c[n - 1] - c[0]);
        }
    }

    i64 guess(double x) const {
        const double g = (x - c0) * inv_h;
        if (!(g > 0)) return 0;                 // (NaN too)
        return g >= static_cast<double>(n) ? n : static_cast<i64>(g);
    }

    // the first index with c[i] >= x
    i64 lower(double x) const {
        i64 i = guess(x);
        for (int step = 0; step < 4; ++step) {
            if (i > 0 && !(c[i - 1] < x)) {
                --i;
            } else if (i < n && c[i] < x) {
                ++i;
            } else {
                return i;
            }
        }
        return std::lower_bound(c, c + n, x) - c;
    }

    // the first index with c[i] > x
    i64 upper(double x) const {
        i64 i = guess(x);
        for (int step = 0; step < 4; ++step) {
            if (i > 0 && x < c[i - 1]) {
                --i;
            } else if (i < n && !(x < c[i])) {
                ++i;
            } else {
                return i;
            }
        }
        return std::upper_bound(c, c + n, x) - c;
    }
};

}  // namespace

// The spans of a scan (a face's, or the disk's) as runs, cut into the numpy code's
// chunks: (polygon, scanline) pairs by `step`, and `dchunk` candidates (cells of the
// table, whatever their depth), where the numpy code resolves its candidates
struct SpanChunks {
    i64 nu, nv;
    const i64* tab;
    i64 n_cells, step, dchunk;
    std::vector<GridRow> rows;
    std::vector<Run> runs;
    std::vector<size_t> ends;          // chunk k: runs[ends[k - 1], ends[k])
    i64 pairs_in_chunk = 0, in_chunk = 0;

    SpanChunks(i64 nu_, i64 nv_, const i64* tab_, i64 n_cells_, i64 step_, i64 depth_chunk)
        : nu(nu_), nv(nv_), tab(tab_), n_cells(n_cells_), step(step_),
          dchunk(depth_chunk > 0 ? depth_chunk : std::numeric_limits<i64>::max()),
          rows(static_cast<size_t>(nu_)) {}

    void end_chunk() {
        if (runs.size() > (ends.empty() ? 0 : ends.back())) ends.push_back(runs.size());
        in_chunk = 0;
    }

    // after each (polygon, scanline) pair
    void end_pair() {
        if (++pairs_in_chunk == step) {
            end_chunk();
            pairs_in_chunk = 0;
        }
    }

    // the cells of columns [a, b) of row r as runs, cut where a chunk is full
    void emit(i64 r, i64 a, i64 b, i64 s) {
        GridRow& g = rows[r];
        if (!g.seen) analyse_row(tab + r * nv, nv, n_cells, g);
        if (g.simple) {
            a = std::max(a, g.lo);
            b = std::min(b, g.hi);
            while (a < b) {
                const i64 take = std::min(b - a, dchunk - in_chunk);
                runs.push_back(Run{static_cast<std::int32_t>(r), static_cast<std::int32_t>(a),
                                   static_cast<std::int32_t>(a + take),
                                   static_cast<std::int32_t>(s)});
                a += take;
                in_chunk += take;
                if (in_chunk == dchunk) end_chunk();
            }
            return;
        }
        const std::int32_t* pre = g.pre.data();
        while (a < b && pre[b] > pre[a]) {
            const i64 n = pre[b] - pre[a], room = dchunk - in_chunk;
            // the chunk full after the room-th cell: the column past it
            const i64 x = n <= room ? b
                                    : std::upper_bound(pre + a, pre + b + 1, pre[a] + room - 1) -
                                          pre;
            runs.push_back(Run{static_cast<std::int32_t>(r), static_cast<std::int32_t>(a),
                               static_cast<std::int32_t>(x), static_cast<std::int32_t>(s)});
            in_chunk += pre[x] - pre[a];
            a = x;
            if (in_chunk == dchunk) end_chunk();
        }
    }

    // every grid cell of the rows scanned its own layout cell, so that a chunk's
    // scanlines can be resolved one by one
    bool distinct() const {
        std::vector<std::pair<i64, i64>> iv;
        bool general = false;
        for (const GridRow& g : rows) {
            if (!g.seen) continue;
            general = general || !g.simple;
            if (g.hi > g.lo) iv.emplace_back(g.base + g.lo, g.base + g.hi);
        }
        if (!general) {
            std::sort(iv.begin(), iv.end());
            for (size_t k = 1; k < iv.size(); ++k)
                if (iv[k].first < iv[k - 1].second) return false;
            return true;
        }
        std::vector<char> mark(static_cast<size_t>(n_cells), 0);
        for (i64 r = 0; r < nu; ++r) {
            if (!rows[r].seen) continue;
            for (i64 col = 0; col < nv; ++col) {
                const i64 cell = tab[r * nv + col];
                if (cell < 0) continue;
                if (mark[cell]) return false;
                mark[cell] = 1;
            }
        }
        return true;
    }
};

// chunk by chunk, scanline by scanline (the runs of a scanline in the chunk's order);
// where grid cells share a layout cell, the runs' cells candidate by candidate into
// the whole buffer (add, flush at the chunks' ends: add's own flush falls on them)
void ZBuffer::resolve_chunks(const SpanChunks& sc, double* bt, i64* bs, i64 depth_chunk) {
    const i64 nu = sc.nu, nv = sc.nv;
    const std::vector<Run>& runs = sc.runs;
    if (runs.empty()) return;
    if (!sc.distinct()) {
        use_scratch();
        size_t q = 0;
        for (const size_t s1 : sc.ends) {
            for (; q < s1; ++q) {
                const i64* trow = sc.tab + runs[q].r * nv;
                for (std::int32_t col = runs[q].a; col < runs[q].b; ++col)
                    if (trow[col] >= 0) add(trow[col], runs[q].s, bt, bs, depth_chunk);
            }
            flush(bt, bs);
        }
        return;
    }
    std::vector<std::int32_t> head(static_cast<size_t>(nu) + 1), fill(static_cast<size_t>(nu)),
        order(runs.size());
    std::vector<RowCell> L(static_cast<size_t>(nv));
    std::vector<RowCandidate> cand;
    std::vector<std::int32_t> touched;
    size_t s0 = 0;
    for (const size_t s1 : sc.ends) {
        std::fill(head.begin(), head.end(), 0);
        for (size_t q = s0; q < s1; ++q) ++head[runs[q].r + 1];
        for (i64 r = 0; r < nu; ++r) head[r + 1] += head[r];
        std::copy(head.begin(), head.end() - 1, fill.begin());
        for (size_t q = s0; q < s1; ++q) order[fill[runs[q].r]++] = static_cast<std::int32_t>(q);
        for (i64 r = 0; r < nu; ++r) {
            if (head[r] < head[r + 1])
                resolve_row(runs.data(), order.data() + head[r], head[r + 1] - head[r],
                            sc.rows[r].simple, sc.rows[r].base, sc.tab + r * nv, L.data(), cand,
                            touched, bt, bs);
        }
        s0 = s1;
    }
}

void ZBuffer::scan(const double* uv, i64 M, i64 K, const i64* c, const i64* src, const i64* pos,
                   const double* u, i64 nu, const double* v, i64 nv, const i64* tab, double* bt,
                   i64* bs, i64 pair_chunk, i64 depth_chunk) {
    if (nu >= (i64(1) << 31) || nv >= (i64(1) << 31))
        throw std::invalid_argument("at most 2**31 - 1 scanlines and centres");
    SpanChunks sc(nu, nv, tab, row_.n_cells, std::max<i64>(1, pair_chunk / std::max<i64>(K, 1)),
                  depth_chunk);
    // per polygon: its edges from their lower end points (a, b), each edge's scanlines
    // (those it straddles: a_y <= y < b_y), and every scanline's crossings
    std::vector<double> X;
    std::vector<std::int32_t> nx;
    const Centres cu(u, nu), cv(v, nv);
    for (i64 m = 0; m < M; ++m) {
        const double* P = uv + m * K * 2;
        const i64 n = c[m];
        const i64 sm = src[pos ? pos[m] : m];
        // the scanlines whose centre lies in [min y, max y] (none if a coordinate
        // is NaN, as numpy's min and searchsorted have it)
        double lo = INF, hi = -INF;
        bool nan = false;
        for (i64 e = 0; e < K; ++e) {
            const double y = P[2 * e];
            if (std::isnan(y)) nan = true;
            lo = std::min(lo, y);
            hi = std::max(hi, y);
        }
        if (nan) continue;
        const i64 j0 = cu.lower(lo), j1 = cu.upper(hi);
        if (j0 >= j1) continue;
        const i64 nr = j1 - j0;
        X.resize(static_cast<size_t>(nr * std::max<i64>(n, 1)));
        nx.assign(static_cast<size_t>(nr), 0);
        for (i64 e = 0; e < n; ++e) {
            const double* a = P + 2 * e;
            const double* b = P + 2 * (e + 1 < n ? e + 1 : 0);
            if (a[0] == b[0]) continue;                 // crosses no scanline
            // from the lower end point, whichever way the edge runs
            if (a[0] > b[0]) std::swap(a, b);
            const i64 r0 = std::max(cu.lower(a[0]), j0), r1 = std::min(cu.lower(b[0]), j1);
            for (i64 r = r0; r < r1; ++r) {
                const double y = u[r];
                const double x = a[1] + (y - a[0]) * (b[1] - a[1]) / (b[0] - a[0]);
                if (!std::isnan(x)) X[(r - j0) * n + nx[r - j0]++] = x;
            }
        }
        for (i64 r = j0; r < j1; ++r) {
            double* x = X.data() + (r - j0) * n;
            const i64 cnt = nx[r - j0];
            if (cnt == 2) {
                if (x[1] < x[0]) std::swap(x[0], x[1]);
            } else {
                std::sort(x, x + cnt);
            }
            const i64 npairs = std::min<i64>(cnt / 2, K / 2);
            for (i64 k = 0; k < npairs; ++k) {
                const i64 ia = cv.lower(x[2 * k]), ib = cv.lower(x[2 * k + 1]);
                if (ia < ib) sc.emit(r, ia, ib, sm);
            }
            sc.end_pair();
        }
    }
    sc.end_chunk();
    resolve_chunks(sc, bt, bs, depth_chunk);
}

// resolve_depths on one scanline's candidates of a chunk, merged into the buffer: the
// rule of flush, cell for cell (the scanline's cells are no other scanline's)
void ZBuffer::resolve_row(const Run* runs, const std::int32_t* idx, i64 n_runs, bool simple,
                          i64 base, const i64* trow, RowCell* L,
                          std::vector<RowCandidate>& cand, std::vector<std::int32_t>& touched,
                          double* best_t, i64* best) {
    const double* D = row_.D;
    const double* nl = row_.nl;
    const double* dl = row_.dl;
    // (room for every cell of the runs, written in place)
    size_t room = 0;
    for (i64 k = 0; k < n_runs; ++k) room += runs[idx[k]].b - runs[idx[k]].a;
    if (cand.size() < room) cand.resize(room);
    if (touched.size() < room + 1) touched.resize(room + 1);
    RowCandidate* cp = cand.data();
    std::int32_t* tp = touched.data();
    size_t nc = 0, nt = 0;
    // the candidates' depths, the nearest per cell
    for (i64 k = 0; k < n_runs; ++k) {
        const Run& q = runs[idx[k]];
        const std::int32_t s = q.s;
        const double* n = nl + 3 * s;
        const double d = dl[s];
        for (std::int32_t col = q.a; col < q.b; ++col) {
            const i64 cell = simple ? base + col : trow[col];
            if (cell < 0) continue;
            const double den = dot3(n, D + 3 * cell);
            const double t = d / den;
            if (!std::isfinite(t)) continue;
            double& tm = L[col].t_min;
            // (the cell listed when first touched, without a branch)
            tp[nt] = col;
            nt += tm == INF;
            tm = t < tm ? t : tm;
            cp[nc++] = RowCandidate{t, den, col, s};
        }
    }
    const double* Dn = row_.Dnorm;
    const double* band = row_.band;
    const i64* prio = row_.prio;
    // one of the polygons at the nearest depth (the last), and of those the one of
    // lowest priority
    for (size_t k = 0; k < nc; ++k) {
        const RowCandidate& q = cp[k];
        RowCell& c = L[q.col];
        if (q.t == c.t_min) {
            c.near = q.s;
            if (prio[q.s] < c.p_min) {
                c.p_min = prio[q.s];
                c.pick = q.s;
            }
        }
    }
    // ties: within four times the tie test's band of the nearest depth, and coplanar
    // with the polygon there
    const double slack_ulps = row_.tie_slack_ulps;
    for (size_t k = 0; k < nc; ++k) {
        const RowCandidate& q = cp[k];
        RowCell& c = L[q.col];
        const double t_near = c.t_min;
        if (q.t == t_near) continue;
        const i64 cell = simple ? base + q.col : trow[q.col];
        const double slack = 4.0 * (band[q.s] + EPS * (slack_ulps * std::fabs(t_near) * Dn[cell]
                                                       + std::fabs(dl[q.s])));
        if (std::fabs(t_near - q.t) * std::fabs(q.den) <= slack) {
            if (coplanar(c.near, q.s) && prio[q.s] < c.p_min) {
                c.p_min = prio[q.s];
                c.pick = q.s;
            }
        }
    }
    // merged with the cells' best so far, as flush merges
    for (size_t k = 0; k < nt; ++k) {
        const std::int32_t col = tp[k];
        RowCell& c = L[col];
        const i64 s = c.pick;
        if (s >= 0) {
            const i64 cell = simple ? base + col : trow[col];
            const double t = c.t_min;
            const i64 old = best[cell];
            bool take;
            if (old < 0)
                take = true;
            else if (t < best_t[cell])
                take = prio[s] < prio[old] || !coplanar(old, s);
            else
                take = prio[s] < prio[old] && coplanar(s, old);
            if (t < best_t[cell]) best_t[cell] = t;
            if (take) best[cell] = s;
        }
        c = RowCell();
    }
}

// rasterise_polar on the clipped images c (live bucket indices into src)
void ZBuffer::scan_polar(const Clipped& c, const i64* src, const double* radii, i64 nr,
                         const double* cs, const double* sn, i64 S, double* bt, i64* bs,
                         i64 pair_chunk, i64 depth_chunk) {
    const double PI = 3.141592653589793, TWO_PI = 2.0 * PI;
    const double step = TWO_PI / static_cast<double>(S);
    const i64 L = static_cast<i64>(c.live.size()), K = c.K;
    const i64 chunk = std::max<i64>(1, pair_chunk / std::max<i64>(K, 1));
    i64 pairs_in_chunk = 0;
    std::vector<double> A(static_cast<size_t>(2 * K)), B(static_cast<size_t>(2 * K));
    std::vector<double> X;
    X.reserve(static_cast<size_t>(K + 1));
    use_scratch();
    for (i64 m = 0; m < L; ++m) {
        const double* P = c.UV.data() + m * K * 2;
        const i64 n = c.cl[m];
        const i64 sm = src[c.live[m]];
        // every edge from its lower end point (y, then x)
        double lo0 = INF, lo1 = INF, hi0 = -INF, hi1 = -INF;
        bool nan = false;
        for (i64 e = 0; e < K; ++e) {
            const double* a = P + 2 * e;
            const double* b = e < n - 1 ? P + 2 * (e + 1) : P;
            if (e >= n) b = a;
            const bool swap = (b[1] < a[1]) || (b[1] == a[1] && b[0] < a[0]);
            if (swap) std::swap(a, b);
            A[2 * e] = a[0]; A[2 * e + 1] = a[1];
            B[2 * e] = b[0]; B[2 * e + 1] = b[1];
            if (std::isnan(P[2 * e]) || std::isnan(P[2 * e + 1])) nan = true;
            lo0 = std::min(lo0, P[2 * e]); hi0 = std::max(hi0, P[2 * e]);
            lo1 = std::min(lo1, P[2 * e + 1]); hi1 = std::max(hi1, P[2 * e + 1]);
        }
        if (nan) continue;
        // the sectors within the image's angular extent (all when its box holds
        // the centre), one sector of margin on either side
        i64 k0, k1;
        if (lo0 <= 0 && hi0 >= 0 && lo1 <= 0 && hi1 >= 0) {
            k0 = 0;
            k1 = S - 1;
        } else {
            const double mid = std::atan2((lo1 + hi1) / 2, (lo0 + hi0) / 2);
            const double cx[4] = {lo0, lo0, hi0, hi0}, cy[4] = {lo1, hi1, hi1, lo1};
            double omin = INF, omax = -INF;
            for (int q = 0; q < 4; ++q) {
                const double off = py_mod(std::atan2(cy[q], cx[q]) - mid + PI, TWO_PI) - PI;
                omin = std::min(omin, off);
                omax = std::max(omax, off);
            }
            k0 = static_cast<i64>(std::ceil((mid + omin) / step - 0.5)) - 1;
            k1 = static_cast<i64>(std::floor((mid + omax) / step - 0.5)) + 1;
            k1 = std::min(k1, k0 + S - 1);
        }
        for (i64 kk = k0; kk <= k1; ++kk) {
            const i64 k = ((kk % S) + S) % S;
            const double cx = cs[k], sy = sn[k];
            X.clear();
            size_t crossings = 0;
            for (i64 e = 0; e < n; ++e) {
                const double* a = A.data() + 2 * e;
                const double* b = B.data() + 2 * e;
                // the edge's crossing with the ray (cos phi, sin phi) rho, rho > 0
                const double sa = cx * a[1] - sy * a[0];
                const double sb = cx * b[1] - sy * b[0];
                if ((sa > 0) == (sb > 0)) continue;
                const double t = sa / (sa - sb);
                const double xx = a[0] + t * (b[0] - a[0]);
                const double yy = a[1] + t * (b[1] - a[1]);
                const double rho = cx * xx + sy * yy;
                if (!(rho > 0)) continue;
                X.push_back(rho);
                ++crossings;
            }
            // an odd count: the centre is inside, the first span starts at 0
            if (crossings % 2 == 1) X.push_back(-INF);
            std::sort(X.begin(), X.end());
            spans(X, static_cast<size_t>((K + 1) / 2), radii, nr,
                  [&](i64 ring) { add(ring * S + k, sm, bt, bs, depth_chunk); });
            if (++pairs_in_chunk == chunk) {
                flush(bt, bs);
                pairs_in_chunk = 0;
            }
        }
    }
    flush(bt, bs);
}

// rasterise_disk's scan of the polygons h holds that are not near the point
void ZBuffer::scan_disk(const Horizon& h, const i64* src, const double* xc, i64 nx,
                        const double* yc, i64 ny, const i64* tab, double* bt, i64* bs,
                        i64 pair_chunk, i64 depth_chunk) {
    const i64 K = h.K, K2 = 2 * K;
    if (nx >= (i64(1) << 31) || ny >= (i64(1) << 31))
        throw std::invalid_argument("at most 2**31 - 1 scanlines and centres");
    SpanChunks sc(nx, ny, tab, row_.n_cells, std::max<i64>(1, pair_chunk / std::max<i64>(K2, 1)),
                  depth_chunk);
    // per monotone piece: its parameter interval, its end points' y, and the
    // edge's a, d = b - a, a.a, d.d, a.d
    std::vector<double> S0(K2), S1(K2), Y0(K2), Y1(K2), ax(K2), ay(K2), dx(K2), dy(K2),
        a2(K2), v2(K2), av(K2);
    std::vector<char> ok(K2);
    std::vector<double> ya(K), X;
    X.reserve(static_cast<size_t>(K2));
    for (size_t li = 0; li < h.live.size(); ++li) {
        if (h.near[li]) continue;
        const double* P = h.Vc.data() + li * K * 3;
        const i64 n = h.cc[li];
        const i64 sm = src[h.live[li]];
        // each vertex's y on the disk
        for (i64 e = 0; e < K; ++e) {
            const double* a = P + 3 * e;
            ya[e] = a[1] / std::sqrt(dot_seq(a, a));
        }
        for (i64 e = 0; e < K; ++e) {
            const bool slot = e < n;
            const i64 nxt = (e + 1) % n;
            const double* A = P + 3 * e;
            const double* B = slot ? P + 3 * nxt : A;
            double yv = ya[e], yb = slot ? ya[nxt] : ya[e];
            // every edge from its lower end point (y, then x, then z)
            const bool swap = (yb < yv) ||
                              (yb == yv && (B[0] < A[0] || (B[0] == A[0] && B[2] < A[2])));
            if (swap) {
                std::swap(A, B);
                std::swap(yv, yb);
            }
            const double d[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]};
            const double ad = dot_seq(A, d), aa = dot_seq(A, A), ddd = dot_seq(d, d);
            // the arc's extreme in y: d/ds y(s) = 0 is linear in s
            double s_ext = (A[1] * ad - d[1] * aa) / (d[1] * ad - A[1] * ddd);
            const bool inner = s_ext > 0 && s_ext < 1 && slot;
            double y_ext = yb;
            if (inner) {
                const double q[3] = {A[0] + s_ext * d[0], A[1] + s_ext * d[1],
                                     A[2] + s_ext * d[2]};
                y_ext = q[1] / std::sqrt(dot_seq(q, q));
            } else {
                s_ext = 1.0;
            }
            // monotone pieces: [0, s_ext] from yv to y_ext, [s_ext, 1] from y_ext to yb
            S0[e] = 0.0; S1[e] = s_ext; Y0[e] = yv; Y1[e] = y_ext; ok[e] = slot;
            S0[K + e] = s_ext; S1[K + e] = 1.0; Y0[K + e] = y_ext; Y1[K + e] = yb;
            ok[K + e] = inner;
            for (const i64 j : {e, K + e}) {
                ax[j] = A[0]; ay[j] = A[1]; dx[j] = d[0]; dy[j] = d[1];
                a2[j] = aa; v2[j] = ddd; av[j] = ad;
            }
        }
        double lo = INF, hi = -INF;
        bool lo_nan = false, hi_nan = false;
        for (i64 j = 0; j < K2; ++j) {
            if (!ok[j]) continue;
            const double mn = np_min(Y0[j], Y1[j]), mx = np_max(Y0[j], Y1[j]);
            if (std::isnan(mn)) lo_nan = true; else lo = std::min(lo, mn);
            if (std::isnan(mx)) hi_nan = true; else hi = std::max(hi, mx);
        }
        // the scanlines within [lo, hi] (numpy's searchsorted puts NaN last)
        const i64 j0 = lo_nan ? nx : std::lower_bound(xc, xc + nx, lo) - xc;
        const i64 j1 = hi_nan ? nx : std::upper_bound(xc, xc + nx, hi) - xc;
        for (i64 r = j0; r < j1; ++r) {
            const double y = xc[r];
            X.clear();
            for (i64 j = 0; j < K2; ++j) {
                if (!ok[j] || ((Y0[j] > y) == (Y1[j] > y))) continue;
                // the crossing: (a_y + s d_y)^2 = y^2 |a + s d|^2, a quadratic in s
                const double yy = y * y;
                const double q2 = dy[j] * dy[j] - yy * v2[j];
                const double q1 = 2.0 * (ay[j] * dy[j] - yy * av[j]);
                const double q0 = ay[j] * ay[j] - yy * a2[j];
                const double disc = std::sqrt(np_max(q1 * q1 - 4.0 * q2 * q0, 0.0));
                // the two roots, in the cancellation-free forms; q2 = 0: one root
                const double big = -0.5 * (q1 + std::copysign(disc, q1));
                const double cand[3] = {big / q2, q0 / big, -q0 / q1};
                const double s0 = S0[j], s1 = S1[j];
                // the root on the piece and on the row's side, the nearest the piece
                double best_s = 0.5 * (s0 + s1), best_d = INF;
                for (const double cd : cand) {
                    const bool side = np_sign(ay[j] + cd * dy[j]) == np_sign(y) || y == 0;
                    double dist = np_max(np_max(s0 - cd, cd - s1), 0.0);
                    dist = (std::isfinite(cd) ? dist : INF) + (side ? 0.0 : 1.0);
                    if (dist < best_d) {
                        best_s = cd;
                        best_d = dist;
                    }
                }
                const double s = np_min(np_max(best_s, s0), s1);
                const double x = (ax[j] + s * dx[j]) /
                                 std::sqrt(a2[j] + s * (2.0 * av[j] + s * v2[j]));
                if (!std::isnan(x)) X.push_back(x);
            }
            std::sort(X.begin(), X.end());
            const size_t npairs = std::min(X.size() / 2, static_cast<size_t>(K));
            for (size_t k = 0; k < npairs; ++k) {
                const i64 ia = std::lower_bound(yc, yc + ny, X[2 * k]) - yc;
                const i64 ib = std::lower_bound(yc, yc + ny, X[2 * k + 1]) - yc;
                if (ia < ib) sc.emit(r, ia, ib, sm);
            }
            sc.end_pair();
        }
    }
    sc.end_chunk();
    resolve_chunks(sc, bt, bs, depth_chunk);
}

// _zbuffer_chart on the clipped images c
void ZBuffer::scan_rays(const Clipped& c, const i64* src, const i64* cells, const double* cu,
                        const double* cv, i64 nb, double v_lo, const i64* order, const i64* starts,
                        double* bt, i64* bs, i64 pair_chunk) {
    const i64 L = static_cast<i64>(c.live.size()), K = c.K;
    const double fnb = static_cast<double>(nb);
    // (polygon, bucket) pairs: the buckets under each image's bounding box
    std::vector<double> box(static_cast<size_t>(4 * L));
    std::vector<i64> pb_poly, pb_b, cum;
    auto bucket = [&](double x) {
        // numpy's astype(int) truncates; then clipped to the grid
        const i64 b = static_cast<i64>(x);
        return std::min(std::max<i64>(b, 0), nb - 1);
    };
    i64 total = 0;
    for (i64 m = 0; m < L; ++m) {
        const double* P = c.UV.data() + m * K * 2;
        double lo0 = INF, lo1 = INF, hi0 = -INF, hi1 = -INF;
        for (i64 e = 0; e < K; ++e) {
            lo0 = np_min(lo0, P[2 * e]); hi0 = np_max(hi0, P[2 * e]);
            lo1 = np_min(lo1, P[2 * e + 1]); hi1 = np_max(hi1, P[2 * e + 1]);
        }
        box[4 * m] = lo0; box[4 * m + 1] = lo1; box[4 * m + 2] = hi0; box[4 * m + 3] = hi1;
        const i64 bx0 = bucket((lo0 + 1.0) * 0.5 * fnb), bx1 = bucket((hi0 + 1.0) * 0.5 * fnb);
        const i64 by0 = bucket((lo1 - v_lo) / (1.0 - v_lo) * fnb);
        const i64 by1 = bucket((hi1 - v_lo) / (1.0 - v_lo) * fnb);
        const i64 nby = by1 - by0 + 1, nbk = (bx1 - bx0 + 1) * nby;
        for (i64 k = 0; k < nbk; ++k) {
            const i64 b = (bx0 + k / nby) * nb + by0 + k % nby;
            pb_poly.push_back(m);
            pb_b.push_back(b);
            total += starts[b + 1] - starts[b];
            cum.push_back(total);
        }
    }
    // chunks of about pair_chunk (polygon, direction) pairs, as the numpy code cuts
    // them: bounds = [0] + searchsorted(cum, range(pair_chunk, total, pair_chunk),
    // "right") + [pairs]
    const i64 n_pairs = static_cast<i64>(pb_b.size());
    std::vector<i64> bounds{0};
    for (i64 x = pair_chunk; x < total; x += pair_chunk)
        bounds.push_back(std::upper_bound(cum.begin(), cum.end(), x) - cum.begin());
    bounds.push_back(n_pairs);
    use_scratch();
    const i64 no_chunk = std::numeric_limits<i64>::max();
    for (size_t q = 0; q + 1 < bounds.size(); ++q) {
        for (i64 p = bounds[q]; p < bounds[q + 1]; ++p) {
            const i64 m = pb_poly[p], b = pb_b[p];
            const double* P = c.UV.data() + m * K * 2;
            const double* bx = box.data() + 4 * m;
            const i64 sm = src[c.live[m]];
            const i64 ncl = c.cl[m];
            for (i64 j = starts[b]; j < starts[b + 1]; ++j) {
                const i64 cl = order[j];
                const double uu = cu[cl], vv = cv[cl];
                if (!(uu >= bx[0] && uu <= bx[2] && vv >= bx[1] && vv <= bx[3])) continue;
                // the crossing number over the edges, each from its lower end
                // point (the padding's zero-length edges cross nothing: the
                // polygon's own edges, the last one closing it)
                bool inside = false;
                for (i64 e = 0; e < ncl; ++e) {
                    const double* a = P + 2 * e;
                    const double* d = P + 2 * (e + 1 < ncl ? e + 1 : 0);
                    const bool straddles = (a[1] > vv) != (d[1] > vv);
                    if (!straddles) continue;
                    if (a[1] > d[1]) std::swap(a, d);
                    const double ux = a[0] + (vv - a[1]) * (d[0] - a[0]) / (d[1] - a[1]);
                    if (uu < ux) inside = !inside;
                }
                if (inside) add(cells[cl], sm, bt, bs, no_chunk);
            }
        }
        // resolve_depths once per chunk
        flush(bt, bs);
    }
}

}  // namespace zbuffer
}  // namespace exactff
