// The BSP tree of a scene in compiled code (the set-up of a large scene).
//
// The same autopartition as exactff.visibility.bsp.build_bsp (the Python build, which
// the Python engine keeps): at each node up to `candidates` planes of the node's
// fragments are scored by 5 splits + |front - back| - 2 coplanar, on a random sample
// of `sample` fragments at a larger node; a node left badly unbalanced by them also
// tries a plane through the median of its fragments' vertex means along their widest
// axis. Sides are taken with the near-coplanar band of exactff.predicates.coplanar_band
// (a vertex within `band_ulps` ulps of the magnitudes in n . x - d lies in the plane),
// and a fragment is split with every crossing interpolated from its edge's front end
// point (exactff.halfspace.split_polygon), so that an edge shared by two fragments
// splits identically. Only the random streams differ from the Python build's: with
// every candidate tried and no sampling the two trees are the same
// (tests/test_bsp_compiled.py).
//
// The build runs without the GIL.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <vector>

#include "bsp_build.h"
#include "constants.h"
#include "expansion.h"
#include "precision.h"
#include "vec.h"

namespace exactff {
namespace {

constexpr double UNIT_ROUNDOFF = std::numeric_limits<double>::epsilon() / 2;
using LD = long double;
// the unit roundoff of long double (that of double where the two are one type)
constexpr LD LD_ROUNDOFF = std::numeric_limits<LD>::epsilon() / 2;

// The crossings' working precision: quadruple (precision.h). Only + - * / are used, no
// libquadmath call.
using Q = Quad;
const LD Q_ROUNDOFF = static_cast<LD>(QUAD_EPS);
inline Q q_fabs(Q x) { return x < 0 ? -x : x; }

constexpr double DBL_EPSILON_ = std::numeric_limits<double>::epsilon();

// a plane N . x = d with N and d exact (expansions of the input's doubles)
struct ExactSplitPlane {
    Exp N[3];
    Exp d;
};

// A splitting plane as the crossings use it: N . (x - a) = d0. For a polygon that is
// planar exactly (every triangle, and most polygons of more vertices the input has on
// axis planes), its own plane: through its input vertex `a` with normal N = (b - a) x
// (c - a) from three of its vertices, in quadruple precision (the differences of doubles
// are exact there, their products too, so each component is rounded once: within
// Q_ROUNDOFF of M, the magnitude of its two products), d0 = 0; its vertices lie on it
// within `dev`, the quadruple rounding of their distances. For one planar only within
// the validation tolerance there is no such plane: its splits cut along its plane
// (n, d) as the scene stores it, exactly (a = 0, N = n, d0 = d, dev = 0), the plane the
// rest of the engine orders it by. An axis plane x_k = c is N = e_k through a point
// with x_k = c, exactly.
struct SplitPlane {
    double a[3] = {0, 0, 0};
    Q N[3] = {0, 0, 0};
    LD M[3] = {0, 0, 0};
    Q d0 = 0;
    LD norm = 0;
    double dev = 0;
    bool own = false;  // through three of the polygon's vertices (exactly planar), not (n, d)
};

// N . (x - a) - d0 for a point x in quadruple precision, and a bound on its error: each
// component of N within Q_ROUNDOFF M_k of the exact normal's, the differences, products
// and sums rounded within 4 roundoffs of their magnitudes
inline Q plane_value(const SplitPlane& P, const Q* x, LD& err) {
    Q s = -P.d0;
    LD mag = 2 * LD(q_fabs(P.d0));
    for (int k = 0; k < 3; ++k) {
        const Q dx = x[k] - Q(P.a[k]);
        s += P.N[k] * dx;
        const LD adx = LD(q_fabs(dx));
        mag += (LD(q_fabs(P.N[k])) * 5 + P.M[k]) * adx;
    }
    err = 2 * Q_ROUNDOFF * mag;
    return s;
}

// splitmix64: a small deterministic stream for the candidate and sample draws
struct Stream {
    uint64_t state;
    explicit Stream(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31);
    }
    size_t below(size_t n) { return static_cast<size_t>(next() % n); }
};

// k distinct positions of 0 .. n-1 (a partial Fisher-Yates shuffle of `scratch`)
void draw_distinct(Stream& rng, size_t n, size_t k, std::vector<size_t>& scratch,
                   std::vector<size_t>& out) {
    scratch.resize(n);
    std::iota(scratch.begin(), scratch.end(), size_t(0));
    out.clear();
    for (size_t i = 0; i < k; ++i) {
        size_t j = i + rng.below(n - i);
        std::swap(scratch[i], scratch[j]);
        out.push_back(scratch[i]);
    }
}

struct Builder {
    const double* src_normals;   // (n, 3)
    const double* src_offsets;   // (n,)
    int64_t n_src;
    size_t candidates, sample, axis_min;
    double axis_imbalance, band_ulps, snap;
    Stream pool_rng, sample_rng;

    // fragments: vertices concatenated (x, y, z), their starts, their source polygons
    std::vector<double> verts;
    // per vertex, a bound on its distance from the point it stands for (0 for the
    // input's; a crossing's from its rounding, its ends' and its plane's: Builder::crossing)
    std::vector<double> vert_err;
    // per vertex, the point in quadruple precision and a bound on its distance from the
    // point it stands for (the input's exactly, with 0): the crossings of later splits
    // start from these, so that a chain of splits does not compound the rounding to double
    std::vector<Q> verts_q;
    std::vector<double> vert_err_q;
    // per vertex, what the edge from it to the next vertex lies on: an input edge (the
    // input vertex it starts from, >= 0) or a splitting plane (-1 - its index in
    // split_planes): the exact crossings are taken from it, not from the vertices
    std::vector<int64_t> carrier;
    // per vertex, the input vertex it is (-1: a crossing)
    std::vector<int64_t> input_id;
    // every plane a split has cut along (a polygon's, or an axis plane), and its exact
    // form where there is one (a polygon planar only within tolerance has none)
    std::vector<SplitPlane> split_planes;
    std::vector<ExactSplitPlane> split_exact;
    std::vector<int64_t> polygon_split_plane;  // per source polygon, -1 until it splits
    std::vector<std::array<const double*, 3>> triple_;  // per polygon, its plane's points
    const double* input_V;
    const int64_t* input_start;
    std::vector<int64_t> input_owner;  // per input vertex, its polygon
    int64_t exact_crossings = 0;
    int64_t outside_crossings = 0;  // exact crossings beyond their edge (Builder::split)
    // per source polygon, the plane its splits cut along (SplitPlane: through three of
    // its vertices, in quadruple precision)
    std::vector<SplitPlane> planes;
    std::vector<int64_t> frag_start, frag_source;
    // nodes
    std::vector<double> node_n, node_d;
    std::vector<int64_t> front, back;
    std::vector<std::vector<int64_t>> here;
    int64_t splits = 0;

    Builder(const double* V, const int64_t* start, int64_t n, const double* normals,
            const double* offsets, size_t candidates_, size_t sample_, size_t axis_min_,
            double axis_imbalance_, double band_ulps_, double snap_, uint64_t seed)
        : src_normals(normals), src_offsets(offsets), n_src(n), candidates(candidates_),
          sample(sample_), axis_min(axis_min_), axis_imbalance(axis_imbalance_),
          band_ulps(band_ulps_), snap(snap_), pool_rng(seed * 2 + 1), sample_rng(seed * 2 + 2) {
        verts.assign(V, V + 3 * start[n]);
        vert_err.assign(size_t(start[n]), 0.0);
        verts_q.assign(V, V + 3 * start[n]);
        vert_err_q.assign(size_t(start[n]), 0.0);
        carrier.resize(size_t(start[n]));
        std::iota(carrier.begin(), carrier.end(), int64_t(0));
        input_id = carrier;
        input_V = V;
        input_start = start;
        input_owner.resize(size_t(start[n]));
        for (int64_t s = 0; s < n; ++s)
            for (int64_t i = start[s]; i < start[s + 1]; ++i) input_owner[size_t(i)] = s;
        polygon_split_plane.assign(size_t(n), -1);
        planes.resize(size_t(n));
        for (int64_t s = 0; s < n; ++s) {
            planes[size_t(s)] = polygon_plane(V, start[s], start[s + 1], normals + 3 * s,
                                              offsets[s]);
        }
        frag_start.assign(start, start + n + 1);
        frag_source.resize(n);
        std::iota(frag_source.begin(), frag_source.end(), int64_t(0));
    }

    size_t count(int64_t f) const { return size_t(frag_start[f + 1] - frag_start[f]); }
    const double* vertex(int64_t f, size_t i) const { return &verts[3 * (frag_start[f] + i)]; }
    double vertex_error(int64_t f, size_t i) const { return vert_err[frag_start[f] + i]; }
    const Q* vertex_q(int64_t f, size_t i) const { return &verts_q[3 * (frag_start[f] + i)]; }
    double vertex_error_q(int64_t f, size_t i) const { return vert_err_q[frag_start[f] + i]; }

    // the plane input polygon V[i0:i1] (plane n . x = d) splits along (SplitPlane): where
    // it is exactly planar, the plane through its first vertex a, the vertex b farthest
    // from it and the vertex c farthest from the line ab (the best conditioned of such
    // triples for a convex polygon; a triangle's own plane), oriented as n; else (n, d)
    SplitPlane polygon_plane(const double* V, int64_t i0, int64_t i1, const double* n,
                             double d) {
        SplitPlane P;
        const double* a = V + 3 * i0;
        auto diff = [&](const double* x, int k) { return LD(x[k]) - LD(a[k]); };
        int64_t ib = i0 + 1, ic = i0 + 2;
        LD far = -1;
        for (int64_t i = i0 + 1; i < i1; ++i) {
            const double* x = V + 3 * i;
            const LD d2 = diff(x, 0) * diff(x, 0) + diff(x, 1) * diff(x, 1) + diff(x, 2) * diff(x, 2);
            if (d2 > far) { far = d2; ib = i; }
        }
        LD wide = -1;
        const double* b = V + 3 * ib;
        for (int64_t i = i0 + 1; i < i1; ++i) {
            if (i == ib) continue;
            const double* x = V + 3 * i;
            const LD u[3] = {diff(b, 0), diff(b, 1), diff(b, 2)};
            const LD v[3] = {diff(x, 0), diff(x, 1), diff(x, 2)};
            const LD c0 = u[1] * v[2] - u[2] * v[1], c1 = u[2] * v[0] - u[0] * v[2],
                     c2 = u[0] * v[1] - u[1] * v[0];
            const LD w2 = c0 * c0 + c1 * c1 + c2 * c2;
            if (w2 > wide) { wide = w2; ic = i; }
        }
        const double* c = V + 3 * ic;
        triple_.push_back({a, b, c});
        Q u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            P.a[k] = a[k];
            u[k] = Q(b[k]) - Q(a[k]);
            v[k] = Q(c[k]) - Q(a[k]);
        }
        for (int k = 0; k < 3; ++k) {
            const int i = (k + 1) % 3, j = (k + 2) % 3;
            P.N[k] = u[i] * v[j] - u[j] * v[i];
            P.M[k] = LD(q_fabs(u[i] * v[j])) + LD(q_fabs(u[j] * v[i]));
        }
        LD dotn = 0, nn = 0;
        for (int k = 0; k < 3; ++k) {
            dotn += LD(P.N[k]) * n[k];
            nn += LD(P.N[k]) * LD(P.N[k]);
        }
        if (dotn < 0)
            for (int k = 0; k < 3; ++k) P.N[k] = -P.N[k];
        P.norm = std::sqrt(nn);
        // how far its polygon's vertices lie from it (0 up to the rounding for a triangle
        // or an exactly planar polygon)
        LD dev = 0;
        for (int64_t i = i0; i < i1; ++i) {
            Q x[3] = {V[3 * i], V[3 * i + 1], V[3 * i + 2]};
            LD err;
            const Q s = plane_value(P, x, err);
            dev = std::max(dev, LD(q_fabs(s)) + err);
        }
        P.dev = P.norm > 0 ? double(1.01L * dev / P.norm) : HUGE_VAL;
        // exactly planar up to the quadruple rounding (a few 1e-32 of its size), or not
        LD size = 0;
        for (int64_t i = i0; i < i1; ++i)
            for (int k = 0; k < 3; ++k) size = std::max(size, std::fabs(LD(V[3 * i + k])));
        if (P.dev <= 1e4L * Q_ROUNDOFF * size) {
            P.own = true;
            return P;
        }
        SplitPlane G;
        for (int k = 0; k < 3; ++k) G.N[k] = n[k];
        G.d0 = d;
        G.norm = std::sqrt(LD(n[0]) * n[0] + LD(n[1]) * n[1] + LD(n[2]) * n[2]);
        return G;
    }

    // the exact form of polygon s's split plane (SplitPlane): through three of its
    // input vertices, N = (b - a) x (c - a) and d = N . a; or its stored (n, d)
    ExactSplitPlane exact_polygon_plane(int64_t s, const SplitPlane& P) const {
        ExactSplitPlane X;
        if (!P.own) {
            // (n, d) as stored
            for (int k = 0; k < 3; ++k) X.N[k] = e_of(src_normals[3 * s + k]);
            X.d = e_of(src_offsets[s]);
            return X;
        }
        const double* a = triple_[size_t(s)][0];
        const double* b = triple_[size_t(s)][1];
        const double* c = triple_[size_t(s)][2];
        Exp u[3], v[3];
        for (int k = 0; k < 3; ++k) {
            u[k] = e_sub(e_of(b[k]), e_of(a[k]));
            v[k] = e_sub(e_of(c[k]), e_of(a[k]));
        }
        for (int k = 0; k < 3; ++k) {
            const int i = (k + 1) % 3, j = (k + 2) % 3;
            X.N[k] = e_sub(e_mul(u[i], v[j]), e_mul(u[j], v[i]));
        }
        // oriented as P (which polygon_plane turned to agree with the stored normal):
        // the sign of P's largest component decides
        int big = 0;
        for (int k = 1; k < 3; ++k)
            if (q_fabs(P.N[k]) > q_fabs(P.N[big])) big = k;
        if ((e_value(X.N[big]) > 0) != (P.N[big] > 0))
            for (int k = 0; k < 3; ++k)
                for (double& t : X.N[k]) t = -t;
        Exp d;
        for (int k = 0; k < 3; ++k) d = e_add(d, e_mul(X.N[k], e_of(a[k])));
        e_compress(d);
        X.d = d;
        return X;
    }

    // the index in split_planes of polygon s's plane (registered at its first split)
    int64_t polygon_plane_index(int64_t s) {
        int64_t& k = polygon_split_plane[size_t(s)];
        if (k < 0) {
            k = int64_t(split_planes.size());
            split_planes.push_back(planes[size_t(s)]);
            split_exact.push_back(exact_polygon_plane(s, planes[size_t(s)]));
        }
        return k;
    }

    int64_t axis_plane_index(int axis, double c) {
        split_planes.push_back(axis_plane(axis, c));
        ExactSplitPlane X;
        X.N[axis] = Exp{1.0};
        X.d = e_of(c);
        split_exact.push_back(X);
        return int64_t(split_planes.size()) - 1;
    }

    // N . x - d exactly, for a point x of the input
    static Exp exact_value(const ExactSplitPlane& X, const double* x) {
        Exp s;
        for (int k = 0; k < 3; ++k) s = e_add(s, e_mul(X.N[k], e_of(x[k])));
        s = e_sub(s, X.d);
        return s;
    }

    // the crossing of what fragment f's edge lies on (`on`: an input edge, or the split
    // plane -1 - k together with the fragment's own polygon's plane) with split plane
    // `cut`, computed exactly and rounded once to quadruple precision: false where the
    // edge's line has no exact form (a split edge of a polygon planar only within
    // tolerance: it lies on no plane of the polygon's) or the planes meet in no point
    bool exact_crossing(int64_t on, int64_t source, int64_t cut, Q* Xq) {
        if (on >= 0) {
            const ExactSplitPlane& P = split_exact[size_t(cut)];
            // the input edge A -> B: X = (o_A B - o_B A) / (o_A - o_B), o = N . x - d
            const int64_t s = input_owner[size_t(on)];
            const int64_t nb = input_start[s] + (on - input_start[s] + 1) %
                                                    (input_start[s + 1] - input_start[s]);
            const double* A = input_V + 3 * on;
            const double* B = input_V + 3 * nb;
            const Exp oa = exact_value(P, A), ob = exact_value(P, B);
            const Exp den = e_sub(oa, ob);
            const Q D = e_value(den);
            if (D == 0) return false;
            for (int k = 0; k < 3; ++k) {
                const Exp num = e_sub(e_mul(oa, e_of(B[k])), e_mul(ob, e_of(A[k])));
                Xq[k] = e_value(num) / D;
            }
            ++exact_crossings;
            return true;
        }
        // the line where the fragment's own plane meets split plane k, cut by P:
        // X = (d1 (N2 x N3) + d2 (N3 x N1) + d3 (N1 x N2)) / (N1 . (N2 x N3))
        const int64_t k = -1 - on;
        if (!(planes[size_t(source)].own && planes[size_t(source)].norm > 0)) return false;
        const int64_t own = polygon_plane_index(source);
        // (split_exact may have grown: take the references after)
        const ExactSplitPlane* pl[3] = {&split_exact[size_t(own)], &split_exact[size_t(k)],
                                        &split_exact[size_t(cut)]};
        auto crossp = [](const ExactSplitPlane& a, const ExactSplitPlane& b, Exp* c) {
            for (int i = 0; i < 3; ++i) {
                const int j = (i + 1) % 3, l = (i + 2) % 3;
                c[i] = e_sub(e_mul(a.N[j], b.N[l]), e_mul(a.N[l], b.N[j]));
            }
        };
        Exp c23[3], c31[3], c12[3];
        crossp(*pl[1], *pl[2], c23);
        crossp(*pl[2], *pl[0], c31);
        crossp(*pl[0], *pl[1], c12);
        Exp det;
        for (int i = 0; i < 3; ++i) det = e_add(det, e_mul(pl[0]->N[i], c23[i]));
        e_compress(det);
        const Q D = e_value(det);
        if (D == 0) return false;
        for (int i = 0; i < 3; ++i) {
            Exp num = e_add(e_add(e_mul(pl[0]->d, c23[i]), e_mul(pl[1]->d, c31[i])),
                            e_mul(pl[2]->d, c12[i]));
            e_compress(num);
            Xq[i] = e_value(num) / D;
        }
        ++exact_crossings;
        return true;
    }

    // an axis plane x_k = c (exact)
    static SplitPlane axis_plane(int axis, double c) {
        SplitPlane P;
        P.a[axis] = c;
        P.N[axis] = 1;
        P.norm = 1;
        return P;
    }

    // the crossing of the edge from A (front) to B (behind) with the splitting plane P,
    // from the ends' quadruple-precision points (within eA and eB of the points they stand
    // for): X = A + t (B - A), t = s_a / (s_a - s_b), in quadruple precision (Xq, within
    // the returned eq of the crossing of the exact edge with P's plane), then rounded to
    // double (X; the return value bounds |X - X*|). To first order, moving the line by d
    // (at most the larger end error) and the plane by w along its normal (the distances'
    // rounding, and P.dev where the splitter's own vertices stand off its plane) moves the
    // crossing within the plane by at most (|d| + w) / sin(beta), beta the edge's angle
    // with the plane (|d_t| + |d_n + w| cot(beta), by Cauchy-Schwarz); the interpolation
    // adds a few quadruple roundoffs of |A| + |B - A| per coordinate. In quadruple
    // precision the distances of a grazing edge (its ends 1e-13 from a slab's plane) keep
    // 20 digits, where long double kept 5 and the rounding to double of the ends none: a
    // crossing 1e-1 m along the edge from where it stands for becomes one within an ulp.
    static double crossing(const Q* A, const Q* B, const SplitPlane& P, double eA, double eB,
                           double* X, Q* Xq, double* eq) {
        LD wa, wb;
        const Q sa = plane_value(P, A, wa), sb = plane_value(P, B, wb);
        Q t = sa / (sa - sb);
        if (t < 0) t = 0;
        if (t > 1) t = 1;
        LD len = 0, size = 0, off = 0;
        for (int k = 0; k < 3; ++k) {
            const Q e = B[k] - A[k];
            Xq[k] = A[k] + t * e;
            X[k] = double(Xq[k]);
            const LD le = LD(q_fabs(e));
            len += le * le;
            size += LD(q_fabs(A[k])) + le;
            const LD r = LD(Xq[k] - Q(X[k]));
            off += r * r;
        }
        len = std::sqrt(len);
        // 1 / sin(beta) = |N| |B - A| / |s_a - s_b| (with the distances' rounding)
        const LD w = std::max(wa, wb) / P.norm + P.dev;
        const LD gap = LD(q_fabs(sa - sb)) - wa - wb;
        const LD steep = gap > 0 ? P.norm * len / gap : LD(HUGE_VAL);
        // the first order holds while the ends' errors tilt the edge well below its angle
        // with the plane; beyond, no bound
        if (!(std::max(eA, eB) * steep <= 0.1L * len)) {
            *eq = HUGE_VAL;
            return HUGE_VAL;
        }
        const LD e = (std::max(eA, eB) + w) * std::max(LD(1), steep) +
                     8 * std::sqrt(LD(3)) * Q_ROUNDOFF * size;
        *eq = double(1.01L * e);
        return double(1.01L * (e + std::sqrt(off)) + 2 * LD_ROUNDOFF * std::sqrt(off));
    }

    // side of vertex x for the plane n . x = d with the coplanar band, and n . x - d
    int side(const double* x, const double* n, double d, double& s) const {
        s = x[0] * n[0] + x[1] * n[1] + x[2] * n[2] - d;
        double mag = std::fabs(x[0]) * std::fabs(n[0]) + std::fabs(x[1]) * std::fabs(n[1]) +
                     std::fabs(x[2]) * std::fabs(n[2]) + std::fabs(d);
        if (std::fabs(s) <= band_ulps * UNIT_ROUNDOFF * mag) return 0;
        return s > 0 ? 1 : -1;
    }

    // whether every vertex of input polygon a lies within the near-coplanar band of
    // input polygon b's plane (exactff.predicates.coplanar_pairs)
    bool within_band(int64_t a, int64_t b) const {
        double s;
        for (int64_t i = input_start[a]; i < input_start[a + 1]; ++i)
            if (side(input_V + 3 * i, src_normals + 3 * b, src_offsets[b], s) != 0) return false;
        return true;
    }

    // the rule of docs/explanation/conventions.md: two polygons are coplanar (a depth
    // tie) when every vertex of one lies within the band of the other's plane
    bool coplanar_pair(int64_t a, int64_t b) const {
        return a == b || within_band(a, b) || within_band(b, a);
    }

    // the exact side of fragment f's vertex i of the plane a node cuts along (`src`'s,
    // or the axis plane x_axis = c): from its quadruple-precision point where that
    // decides, else exactly for an input vertex; a crossing within its own rounding of
    // the plane (a few 1e-33 of its size) lies on it
    int exact_side(int64_t f, size_t i, int64_t src, int axis, double c) {
        const Q* x = vertex_q(f, i);
        const int64_t id = input_id[size_t(frag_start[f]) + i];
        const LD eq = vertex_error_q(f, i);
        if (src < 0) {
            if (id >= 0) {
                const double v = input_V[3 * id + axis];
                return v > c ? 1 : (v < c ? -1 : 0);
            }
            const Q v = x[axis] - Q(c);
            if (LD(q_fabs(v)) <= eq + 2 * Q_ROUNDOFF * (LD(q_fabs(x[axis])) + std::fabs(LD(c))))
                return 0;
            return v > 0 ? 1 : -1;
        }
        const int64_t k = polygon_plane_index(src);
        LD err;
        const Q v = plane_value(split_planes[size_t(k)], x, err);
        const LD bound = err + eq * split_planes[size_t(k)].norm;
        if (LD(q_fabs(v)) > bound) return v > 0 ? 1 : -1;
        if (id < 0) return 0;
        const Exp e = exact_value(split_exact[size_t(k)], input_V + 3 * id);
        return e.empty() ? 0 : (e.back() > 0 ? 1 : -1);
    }

    // the sides of fragment f's vertices for the plane n . x = d a node cuts along
    // (polygon `src`'s, or the axis plane x_axis = d with src = -1), by the rule of
    // docs/explanation/conventions.md: beyond the near-coplanar band, the sign; within
    // it, 0 (in the plane) where the fragment's polygon is coplanar with `src`, else the
    // exact side (a polygon flush with another to 1e-13 but not coplanar with it is
    // ordered by its exact geometry, and split exactly where it crosses the plane)
    int sides(int64_t f, const double* n, double d, int64_t src, int axis, std::vector<int>& sg) {
        const size_t k = count(f);
        sg.resize(k);
        double s;
        bool zero = false;
        for (size_t i = 0; i < k; ++i) {
            sg[i] = side(vertex(f, i), n, d, s);
            zero |= sg[i] == 0;
        }
        if (zero && !(src >= 0 && coplanar_pair(frag_source[f], src))) {
            for (size_t i = 0; i < k; ++i)
                if (sg[i] == 0) sg[i] = exact_side(f, i, src, axis, d);
        }
        int has = 0;
        for (size_t i = 0; i < k; ++i) {
            if (sg[i] > 0) has |= 1;
            else if (sg[i] < 0) has |= 2;
        }
        return has;
    }

    // whether fragment f has vertices in front (bit 1) and behind (bit 2) of a plane
    int classify(int64_t f, const double* n, double d, int64_t src, int axis) {
        return sides(f, n, d, src, axis, scratch_sides);
    }
    std::vector<int> scratch_sides;

    // score 5 splits + |front - back| - 2 coplanar over fragments `frags`; imbalance too
    void score(const std::vector<int64_t>& frags, const double* n, double d, int64_t src,
               int axis, int64_t& sc, int64_t& imbalance) {
        int64_t nsplit = 0, nfront = 0, nback = 0, ncop = 0;
        for (int64_t f : frags) {
            int has = classify(f, n, d, src, axis);
            if (has == 3) ++nsplit;
            else if (has == 1) ++nfront;
            else if (has == 2) ++nback;
            else ++ncop;
        }
        imbalance = std::llabs(nfront - nback);
        sc = 5 * nsplit + imbalance - 2 * ncop;
    }

    // the split of fragment f (exactff.halfspace.split_polygon) by the plane n . x = d
    // (its sides, with the band) along split plane `cut` (its crossings): new fragments,
    // -1 for none. Each crossing is computed in quadruple precision from its edge's ends
    // (Builder::crossing); where that is not within BSP_QUAD_TRUST of an ulp (a chain of
    // grazing splits, or one steeper than 1e12), exactly from what the edge lies on
    // (Builder::exact_crossing). Every vertex records what its outgoing edge lies on.
    void split(int64_t f, const double* n, double d, int64_t src, int axis, int64_t cut,
               int64_t& f_front, int64_t& f_back) {
        // a copy: exact_crossing may register the fragment's own plane (split_planes grows)
        const SplitPlane plane = split_planes[size_t(cut)];
        size_t k = count(f);
        std::vector<int> sg;
        std::vector<double> fv, bv, fe, be, fqe, bqe;
        std::vector<Q> fq, bq;
        std::vector<int64_t> fc, bc;
        const int64_t source = frag_source[f];
        const int64_t along = -1 - cut;
        sides(f, n, d, src, axis, sg);
        std::vector<int64_t> fid, bid;
        auto keep = [&](std::vector<double>& pv, std::vector<double>& pe, std::vector<Q>& pq,
                        std::vector<double>& pqe, std::vector<int64_t>& pc, const double* X,
                        double e, const Q* Xq, double eq, int64_t on) {
            (&pv == &fv ? fid : bid).push_back(-1);
            pv.insert(pv.end(), X, X + 3);
            pe.push_back(e);
            pq.insert(pq.end(), Xq, Xq + 3);
            pqe.push_back(eq);
            pc.push_back(on);
        };
        for (size_t i = 0; i < k; ++i) {
            size_t j = (i + 1) % k;
            const int64_t on = carrier[size_t(frag_start[f]) + i];
            // the outgoing edge of vertex i in the front piece: its own edge where that
            // edge stays in front (or reaches a crossing from in front), else the cut
            const int64_t id = input_id[size_t(frag_start[f]) + i];
            if (sg[i] >= 0) {
                keep(fv, fe, fq, fqe, fc, vertex(f, i), vertex_error(f, i), vertex_q(f, i),
                     vertex_error_q(f, i), (sg[j] >= 0 || sg[i] > 0) ? on : along);
                fid.back() = id;
            }
            if (sg[i] <= 0) {
                keep(bv, be, bq, bqe, bc, vertex(f, i), vertex_error(f, i), vertex_q(f, i),
                     vertex_error_q(f, i), (sg[j] <= 0 || sg[i] < 0) ? on : along);
                bid.back() = id;
            }
            if (sg[i] * sg[j] < 0) {
                // from the front end point, so that a shared edge splits identically
                size_t a = sg[i] > 0 ? i : j, b = sg[i] > 0 ? j : i;
                double X[3], eq;
                Q Xq[3];
                double e = crossing(vertex_q(f, a), vertex_q(f, b), plane, vertex_error_q(f, a),
                                    vertex_error_q(f, b), X, Xq, &eq);
                LD size = 0;
                // the quadruple point rounds to the double the exact one does only where
                // its bound does not straddle a rounding boundary
                bool ambiguous = false;
                for (int c = 0; c < 3; ++c) {
                    size = std::max(size, LD(q_fabs(Xq[c])));
                    ambiguous |= double(Xq[c] - Q(eq)) != double(Xq[c] + Q(eq));
                }
                if ((ambiguous || !(eq <= BSP_QUAD_TRUST * UNIT_ROUNDOFF * double(size))) &&
                    exact_crossing(on, source, cut, Xq)) {
                    // exact, rounded to quadruple precision (three roundoffs of the
                    // quotient and the terms' sum), then to double
                    LD off = 0;
                    for (int c = 0; c < 3; ++c) {
                        X[c] = double(Xq[c]);
                        const LD r = LD(Xq[c] - Q(X[c]));
                        off += r * r;
                    }
                    eq = double(8 * std::sqrt(LD(3)) * Q_ROUNDOFF * size);
                    e = double(1.01L * (LD(eq) + std::sqrt(off)));
                }
                // a crossing within `snap` roundoffs of an end point is that end point
                // (as exactff.halfspace.split_polygon): no edge an ulp long, which the
                // core could not orient; the end point's copy stands for the crossing,
                // within their distance and the crossing's bound
                int near = -1;
                // the crossing must lie on the edge: one beyond its ends (by more than
                // their errors) is the crossing of the carrier line, nearly parallel to
                // the plane, that the rounded ends straddle while the true ones do not
                // (both within their roundings of the plane). The edge then does not
                // cross: it touches the plane at the end nearer to it, which stands for
                // the crossing within its own error and its distance from the plane
                bool outside = false;
                double slack = 0;
                {
                    const double* A = vertex(f, a);
                    const double* B = vertex(f, b);
                    // their errors, the crossing's own and a few roundoffs of their
                    // magnitudes (a subnormal coordinate keeps fewer digits)
                    double amax = 0;
                    for (int c = 0; c < 3; ++c)
                        amax = std::max({amax, std::fabs(A[c]), std::fabs(B[c])});
                    slack = vertex_error(f, a) + vertex_error(f, b) + e + 4 * DBL_EPSILON_ * amax;
                    for (int c = 0; c < 3; ++c)
                        outside |= !(X[c] >= std::min(A[c], B[c]) - slack &&
                                     X[c] <= std::max(A[c], B[c]) + slack);
                }
                LD off_plane = 0, off_plane_q = 0;
                if (outside) {
                    LD ea, eb;
                    const LD va = LD(q_fabs(plane_value(plane, vertex_q(f, i), ea)));
                    const LD vb = LD(q_fabs(plane_value(plane, vertex_q(f, j), eb)));
                    const LD norm = LD(plane.norm);
                    const int nearer = va <= vb ? 0 : 1;
                    off_plane = ((nearer == 0 ? va + ea : vb + eb) / norm) * (1 + 1e-15L);
                    off_plane_q = off_plane;
                    // only where that end lies within its roundings of the plane; else
                    // the crossing is off the edge's box by its own rounding only
                    if (off_plane <= 16 * LD(slack)) {
                        near = nearer;
                        ++outside_crossings;
                    } else {
                        outside = false;
                    }
                }
                for (int w = 0; w < 2 && near < 0; ++w) {
                    const double* E = vertex(f, w == 0 ? i : j);
                    const double amax =
                        std::max({std::fabs(E[0]), std::fabs(E[1]), std::fabs(E[2])});
                    bool close = true;
                    for (int c = 0; c < 3; ++c)
                        close &= std::fabs(X[c] - E[c]) <= snap * DBL_EPSILON_ * amax;
                    if (close) near = w;
                }
                if (near < 0) {
                    // the crossing leaves the front piece along the cut, and the back
                    // piece along its own edge; or the other way round
                    keep(fv, fe, fq, fqe, fc, X, e, Xq, eq, sg[i] > 0 ? along : on);
                    keep(bv, be, bq, bqe, bc, X, e, Xq, eq, sg[i] < 0 ? along : on);
                    continue;
                }
                const size_t w = near == 0 ? i : j;
                const double* E = vertex(f, w);
                const Q* Eq = vertex_q(f, w);
                LD d2 = 0, dq2 = 0;
                for (int c = 0; c < 3; ++c) {
                    const LD r = LD(X[c]) - LD(E[c]);
                    d2 += r * r;
                    const LD rq = LD(Xq[c] - Eq[c]);
                    dq2 += rq * rq;
                }
                const double ec = outside ? double(1.01L * (off_plane + LD(vertex_error(f, w))))
                                          : double(1.01L * (std::sqrt(d2) + LD(e)));
                const double eqc =
                    outside ? double(1.01L * (off_plane_q + LD(vertex_error_q(f, w))))
                            : double(1.01L * (std::sqrt(dq2) + LD(eq)));
                const bool front_side = near == 0 ? sg[i] < 0 : sg[i] > 0;
                // the crossing at i itself: in i's own piece the edge from i now runs
                // along the cut (it went to the crossing along the edge)
                if (near == 0) (sg[i] > 0 ? fc : bc).back() = along;
                if (front_side) {
                    keep(fv, fe, fq, fqe, fc, E, ec, Eq, eqc, near == 0 ? on : along);
                    fid.back() = input_id[size_t(frag_start[f]) + w];
                } else {
                    keep(bv, be, bq, bqe, bc, E, ec, Eq, eqc, near == 0 ? on : along);
                    bid.back() = input_id[size_t(frag_start[f]) + w];
                }
            }
        }
        ++splits;
        auto add = [&](std::vector<double>& pv, std::vector<double>& pe, std::vector<Q>& pq,
                       std::vector<double>& pqe, std::vector<int64_t>& pc,
                       std::vector<int64_t>& pid) -> int64_t {
            // a vertex equal to the one before it (two crossings snapped to one end
            // point) is dropped: the edge from the one before takes its carrier
            for (size_t r = pe.size(); r-- > 1 && pe.size() > 1;) {
                const size_t a = r, b = (r + 1) % pe.size();
                (void)b;
                if (pv[3 * a] == pv[3 * (a - 1)] && pv[3 * a + 1] == pv[3 * (a - 1) + 1] &&
                    pv[3 * a + 2] == pv[3 * (a - 1) + 2]) {
                    pe[a - 1] = std::max(pe[a - 1], pe[a]);
                    pqe[a - 1] = std::max(pqe[a - 1], pqe[a]);
                    pc[a - 1] = pc[a];
                    pv.erase(pv.begin() + 3 * a, pv.begin() + 3 * a + 3);
                    pq.erase(pq.begin() + 3 * a, pq.begin() + 3 * a + 3);
                    pe.erase(pe.begin() + a);
                    pqe.erase(pqe.begin() + a);
                    pc.erase(pc.begin() + a);
                    pid.erase(pid.begin() + a);
                }
            }
            if (pe.size() > 1 && pv[0] == pv[3 * (pe.size() - 1)] &&
                pv[1] == pv[3 * (pe.size() - 1) + 1] && pv[2] == pv[3 * (pe.size() - 1) + 2]) {
                const size_t a = pe.size() - 1;   // the last equals the first: drop the first
                pe[a] = std::max(pe[a], pe[0]);
                pqe[a] = std::max(pqe[a], pqe[0]);
                pc[a] = pc[0];
                pv.erase(pv.begin(), pv.begin() + 3);
                pq.erase(pq.begin(), pq.begin() + 3);
                pe.erase(pe.begin());
                pqe.erase(pqe.begin());
                pc.erase(pc.begin());
                pid.erase(pid.begin());
            }
            if (pv.size() < 9) return -1;
            input_id.insert(input_id.end(), pid.begin(), pid.end());
            verts.insert(verts.end(), pv.begin(), pv.end());
            vert_err.insert(vert_err.end(), pe.begin(), pe.end());
            verts_q.insert(verts_q.end(), pq.begin(), pq.end());
            vert_err_q.insert(vert_err_q.end(), pqe.begin(), pqe.end());
            carrier.insert(carrier.end(), pc.begin(), pc.end());
            frag_start.push_back(int64_t(verts.size() / 3));
            frag_source.push_back(source);
            return int64_t(frag_source.size()) - 1;
        };
        f_front = add(fv, fe, fq, fqe, fc, fid);
        f_back = add(bv, be, bq, bqe, bc, bid);
    }

    struct Item {
        std::vector<int64_t> ids;
        int64_t parent;
        int child;
    };

    void build() {
        std::vector<Item> stack;
        {
            Item root{std::vector<int64_t>(size_t(n_src)), -1, 0};
            std::iota(root.ids.begin(), root.ids.end(), int64_t(0));
            if (n_src > 0) stack.push_back(std::move(root));
        }
        std::vector<size_t> scratch, drawn;
        std::vector<int64_t> pool, scored;
        while (!stack.empty()) {
            Item item = std::move(stack.back());
            stack.pop_back();
            const std::vector<int64_t>& ids = item.ids;
            int64_t node = int64_t(node_d.size());
            if (item.parent >= 0) (item.child > 0 ? front : back)[item.parent] = node;
            front.push_back(-1);
            back.push_back(-1);
            size_t m = ids.size();
            if (m == 1) {
                // a leaf: the one fragment's own plane holds it
                int64_t s = frag_source[ids[0]];
                node_n.insert(node_n.end(), src_normals + 3 * s, src_normals + 3 * s + 3);
                node_d.push_back(src_offsets[s]);
                here.push_back({ids[0]});
                continue;
            }
            // candidates: every fragment's plane, or the first and a random draw
            pool.clear();
            if (m <= candidates) {
                pool = ids;
            } else {
                pool.push_back(ids[0]);
                draw_distinct(pool_rng, m, candidates - 1, scratch, drawn);
                for (size_t i : drawn) pool.push_back(ids[i]);
            }
            {
                // keep the first of each (a fragment drawn twice)
                std::vector<int64_t> unique;
                for (int64_t f : pool)
                    if (std::find(unique.begin(), unique.end(), f) == unique.end())
                        unique.push_back(f);
                pool.swap(unique);
            }
            // scored on every fragment, or on a sample at a larger node
            const std::vector<int64_t>* on = &ids;
            if (m > sample) {
                draw_distinct(sample_rng, m, sample, scratch, drawn);
                std::sort(drawn.begin(), drawn.end());
                scored.clear();
                for (size_t i : drawn) scored.push_back(ids[i]);
                on = &scored;
            }
            size_t ms = on->size();
            int64_t best = 0, best_imbalance = 0;
            size_t j = 0;
            for (size_t c = 0; c < pool.size(); ++c) {
                int64_t s = frag_source[pool[c]], sc, imb;
                score(*on, src_normals + 3 * s, src_offsets[s], s, -1, sc, imb);

                if (c == 0 || sc < best) {
                    best = sc;
                    best_imbalance = imb;
                    j = c;
                }
            }
            int64_t splitter = pool[j];
            int64_t src = frag_source[splitter];
            double n[3] = {src_normals[3 * src], src_normals[3 * src + 1],
                           src_normals[3 * src + 2]};
            double d = src_offsets[src];
            bool own_plane = true;
            int axis_chosen = -1;
            if (m > axis_min && double(best_imbalance) > axis_imbalance * double(ms)) {
                // a chain in the making: a plane through the median of the fragments'
                // vertex means along their widest axis
                std::vector<Vec3<double>> cen(m);
                Vec3<double> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
                for (size_t i = 0; i < m; ++i) {
                    size_t k = count(ids[i]);
                    Vec3<double> c{0, 0, 0};
                    for (size_t v = 0; v < k; ++v)
                        for (int a = 0; a < 3; ++a) c[a] += vertex(ids[i], v)[a];
                    for (int a = 0; a < 3; ++a) {
                        c[a] /= double(k);
                        lo[a] = std::min(lo[a], c[a]);
                        hi[a] = std::max(hi[a], c[a]);
                    }
                    cen[i] = c;
                }
                int axis = 0;
                for (int a = 1; a < 3; ++a)
                    if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
                std::vector<double> x(m);
                for (size_t i = 0; i < m; ++i) x[i] = cen[i][axis];
                std::sort(x.begin(), x.end());
                double med = m % 2 ? x[m / 2] : 0.5 * (x[m / 2 - 1] + x[m / 2]);
                double na[3] = {0, 0, 0};
                na[axis] = 1.0;
                int64_t a_score, a_imb;
                score(*on, na, med, -1, axis, a_score, a_imb);
                if (a_score < best) {
                    std::copy(na, na + 3, n);
                    d = med;
                    axis_chosen = axis;   // exact: it stands for itself
                    own_plane = false;
                }
            }
            node_n.insert(node_n.end(), n, n + 3);
            node_d.push_back(d);
            int64_t cut = -1;   // the split plane, registered at the node's first split
            // in the plane (or the splitter's own pieces), wholly in front, behind, split
            std::vector<int64_t> in_plane, to_front, to_back, front_parts, back_parts;
            const int64_t cut_src = axis_chosen >= 0 ? -1 : src;
            for (int64_t f : ids) {
                int has = classify(f, n, d, cut_src, axis_chosen);
                if (has == 0 || (own_plane && frag_source[f] == src)) {
                    in_plane.push_back(f);
                } else if (has == 1) {
                    to_front.push_back(f);
                } else if (has == 2) {
                    to_back.push_back(f);
                } else {
                    int64_t ff, fb;
                    if (cut < 0)
                        cut = axis_chosen >= 0 ? axis_plane_index(axis_chosen, d)
                                               : polygon_plane_index(src);
                    split(f, n, d, cut_src, axis_chosen, cut, ff, fb);
                    if (ff >= 0) front_parts.push_back(ff);
                    if (fb >= 0) back_parts.push_back(fb);
                }
            }
            here.push_back(std::move(in_plane));
            to_front.insert(to_front.end(), front_parts.begin(), front_parts.end());
            to_back.insert(to_back.end(), back_parts.begin(), back_parts.end());
            // the front child is pushed first (the back one is built first), as in Python
            if (!to_front.empty()) stack.push_back(Item{std::move(to_front), node, 1});
            if (!to_back.empty()) stack.push_back(Item{std::move(to_back), node, -1});
        }
    }
};

}  // namespace

BspArrays build_bsp(const double* V, const int64_t* start, int64_t n, const double* normals,
                    const double* offsets, size_t candidates, size_t sample, size_t axis_min,
                    double axis_imbalance, double band_ulps, double snap, uint64_t seed) {
    Builder b(V, start, n, normals, offsets, candidates, sample, axis_min, axis_imbalance,
              band_ulps, snap, seed);
    BspArrays out;
    out.here_start.push_back(0);
    out.live_start.push_back(0);
    b.build();
    // keep only the fragments the nodes hold, numbered in node order
    for (const auto& h : b.here) {
        for (int64_t f : h) {
            out.here.push_back(int64_t(out.live_source.size()));
            out.live_source.push_back(b.frag_source[f]);
            out.whole.push_back(f < n);
            out.live_verts.insert(out.live_verts.end(), b.verts.begin() + 3 * b.frag_start[f],
                                  b.verts.begin() + 3 * b.frag_start[f + 1]);
            out.live_err.insert(out.live_err.end(), b.vert_err.begin() + b.frag_start[f],
                                b.vert_err.begin() + b.frag_start[f + 1]);
            out.live_start.push_back(int64_t(out.live_verts.size() / 3));
        }
        out.here_start.push_back(int64_t(out.here.size()));
    }
    out.node_n = std::move(b.node_n);
    out.node_d = std::move(b.node_d);
    out.front = std::move(b.front);
    out.back = std::move(b.back);
    out.splits = b.splits;
    return out;
}

}  // namespace exactff
