// A row's blockers (row_culling.h): the shaft's tests in the order and arithmetic of
// exactff/area/culling.py's shaft, then the hull test of its hull_blockers with the
// hull's faces found directly: every plane through three of the pair's vertices that
// has them all on one side.

#include "row_culling.h"

#include <algorithm>
#include <cmath>

#include "vec.h"

namespace exactff {
namespace area {

namespace {

using V = Vec3<double>;

inline V load(const double* p) { return {p[0], p[1], p[2]}; }

// a side plane of the shaft in the plane of two axes: through the edge of one box
// extreme in direction sa along ax and the other's extreme in sb along bx
struct SidePlane {
    int ax, bx;
    double n0, n1, off;
    bool active;
};

// the 12 side planes of pair a's boxes (culling._SHAFT_EDGES, in its order)
void side_planes(const double* box, SidePlane* out) {
    const double* loP = box;
    const double* hiP = box + 3;
    const double* loQ = box + 6;
    const double* hiQ = box + 9;
    const int axes[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    int c = 0;
    for (const auto& xy : axes)
        for (double sa : {1.0, -1.0})
            for (double sb : {1.0, -1.0}) {
                const int ax = xy[0], bx = xy[1];
                const double eP0 = sa > 0 ? hiP[ax] : loP[ax], eP1 = sb > 0 ? hiP[bx] : loP[bx];
                const double eQ0 = sa > 0 ? hiQ[ax] : loQ[ax], eQ1 = sb > 0 ? hiQ[bx] : loQ[bx];
                const bool p0 = sa * eP0 > sa * eQ0, p1 = sb * eP1 > sb * eQ1;
                const bool q0 = sa * eQ0 > sa * eP0, q1 = sb * eQ1 > sb * eP1;
                bool active = (p0 && q1) || (q0 && p1);
                // the outward normal (sa |d_b|, sb |d_a|), scaled by its largest
                // component before it is normalised (no underflow of its squares)
                double n0 = sa * std::fabs(eQ1 - eP1), n1 = sb * std::fabs(eQ0 - eP0);
                const double big = std::max(std::fabs(n0), std::fabs(n1));
                active = active && big > 0;
                n0 = big > 0 ? n0 / big : 0.0;
                n1 = big > 0 ? n1 / big : 0.0;
                const double size = std::sqrt(n0 * n0 + n1 * n1);
                n0 = size > 0 ? n0 / size : 0.0;
                n1 = size > 0 ? n1 / size : 0.0;
                out[c++] = {ax, bx, n0, n1, n0 * eP0 + n1 * eP1, active};
            }
}

// a face of a pair's hull: outward unit normal n through the point o
struct Face {
    V n, o;
};

// what is known of the hull of a pair's points
enum class Hull { faces, flat, unknown };

// the faces of the convex hull of the points X: planes through three of them with every
// point on or behind them, to tol of their rounding (a thin triangle, whose plane is
// not known to near / 10, is skipped: a face left out only keeps more blockers). flat:
// a plane tried has all the points on it, to its tol (a hull thinner than its rounding:
// none, as qhull raises "initial simplex is flat"; no blockers); unknown: no plane tried
// (every candidate kept).
Hull hull_faces(const std::vector<V>& X, double near, double eps, std::vector<Face>& faces) {
    faces.clear();
    const std::size_t n = X.size();
    double extent = 0;
    for (const V& x : X) extent = std::max(extent, norm(sub(x, X[0])));
    bool flat = false, tried = false;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            for (std::size_t k = j + 1; k < n; ++k) {
                // the triangle's normal from the vertex opposite its longest side, where
                // its angle is largest
                const double lij = norm(sub(X[j], X[i])), ljk = norm(sub(X[k], X[j])),
                             lki = norm(sub(X[i], X[k]));
                const std::size_t o = ljk >= lij && ljk >= lki ? i : lki >= lij ? j : k;
                const std::size_t u = o == i ? j : o == j ? k : i;
                const std::size_t w = o == i ? k : o == j ? i : j;
                const V a = sub(X[u], X[o]), b = sub(X[w], X[o]);
                V c = cross(a, b);
                const double lc = norm(c), la = norm(a), lb = norm(b);
                if (!(lc > 0)) continue;
                // the plane's rounding: of the differences and of the normal's direction
                // (1 / sin of the triangle's angle at X[o])
                const double tol = 64.0 * eps * extent * (la * lb / lc);
                if (!(tol <= 0.1 * near)) continue;
                tried = true;
                c = {c.x / lc, c.y / lc, c.z / lc};
                double smax = -INFINITY, smin = INFINITY;
                for (const V& x : X) {
                    const double s = dot(c, sub(x, X[o]));
                    smax = std::max(smax, s);
                    smin = std::min(smin, s);
                }
                const bool below = smax <= tol, above = smin >= -tol;
                if (below && above) flat = true;
                if (below && !above) faces.push_back({c, X[o]});
                if (above && !below) faces.push_back({neg(c), X[o]});
            }
    if (!tried) return Hull::unknown;
    if (flat) return Hull::flat;
    return faces.empty() ? Hull::unknown : Hull::faces;
}

}  // namespace

RowBlockers row_blockers(const RowCullingArgs& a) {
    RowBlockers out;
    out.start.push_back(0);
    out.boxed.assign(a.m, 0);
    out.left.assign(a.m, 0);
    const V nP = load(a.nP), p0 = load(a.p0);
    const std::int64_t K = a.kmax;
    // every polygon's distance from P's plane, once for the row
    std::vector<double> aboveP(a.n);
    for (std::int64_t k = 0; k < a.n; ++k) {
        double mx = -INFINITY;
        for (std::int64_t v = 0; v < K; ++v)
            mx = std::max(mx, dot(sub(load(a.V + 3 * (k * K + v)), p0), nP));
        aboveP[k] = mx;
    }
    std::vector<std::int64_t> cand;
    std::vector<V> X;
    std::vector<Face> faces;
    SidePlane planes[12];
    for (std::int64_t p = 0; p < a.m; ++p) {
        const double* box = a.boxes + 12 * p;
        double lo[3], hi[3];
        for (int x = 0; x < 3; ++x) {
            lo[x] = std::min(box[x], box[6 + x]);
            hi[x] = std::max(box[3 + x], box[9 + x]);
        }
        const std::int64_t j = a.J[p];
        const V q0 = load(a.V + 3 * (j * K));
        const V nQ = load(a.N + 3 * j);
        side_planes(box, planes);
        cand.clear();
        for (std::int64_t k = 0; k < a.n; ++k) {
            if (k == a.i || k == j) continue;
            // reaching into the open interior of the pair's box
            bool in = true;
            for (int x = 0; x < 3; ++x)
                in = in && a.hi[3 * k + x] > lo[x] && a.lo[3 * k + x] < hi[x];
            if (!in) continue;
            ++out.boxed[p];
            // on or behind P's plane, or the receiver's
            if (!(aboveP[k] > 0.5 * a.near)) continue;
            double mq = -INFINITY;
            for (std::int64_t v = 0; v < K; ++v)
                mq = std::max(mq, dot(sub(load(a.V + 3 * (k * K + v)), q0), nQ));
            if (!(mq > 0.5 * a.near)) continue;
            // on or outside a side plane
            bool drop = false;
            for (const SidePlane& s : planes) {
                if (!s.active) continue;
                double mn = INFINITY;
                for (std::int64_t v = 0; v < K; ++v) {
                    const double* w = a.V + 3 * (k * K + v);
                    mn = std::min(mn, w[s.ax] * s.n0 + w[s.bx] * s.n1);
                }
                if (mn - s.off >= -0.5 * a.near) {
                    drop = true;
                    break;
                }
            }
            if (!drop) cand.push_back(k);
        }
        out.left[p] = std::int64_t(cand.size());
        // the hull test: a candidate on or outside one face of the pair's hull (to near)
        // hides nothing of positive measure; a flat pair (no hull) none
        if (!cand.empty()) {
            X.clear();
            for (std::int64_t v = a.po[p]; v < a.po[p + 1]; ++v) X.push_back(load(a.VP + 3 * v));
            for (std::int64_t v = a.qo[p]; v < a.qo[p + 1]; ++v) X.push_back(load(a.VQ + 3 * v));
            const Hull hull = std::int64_t(X.size()) > a.hull_points
                                  ? Hull::unknown
                                  : hull_faces(X, a.near, a.eps, faces);
            if (hull == Hull::unknown) {
                out.blockers.insert(out.blockers.end(), cand.begin(), cand.end());
            } else if (hull == Hull::faces) {
                for (std::int64_t k : cand) {
                    bool outside = false;
                    for (const Face& f : faces) {
                        bool all = true;
                        for (std::int64_t v = 0; v < K && all; ++v)
                            all = dot(f.n, sub(load(a.V + 3 * (k * K + v)), f.o)) >= -a.near;
                        if (all) {
                            outside = true;
                            break;
                        }
                    }
                    if (!outside) out.blockers.push_back(k);
                }
            }
        }
        out.start.push_back(std::int64_t(out.blockers.size()));
    }
    return out;
}

}  // namespace area
}  // namespace exactff
