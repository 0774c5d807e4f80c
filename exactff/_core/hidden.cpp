// The hidden region of a receiver Q seen from many points x of an emitter, for the area
// form factors (exactff/area/occluded.py, _hidden_values): each blocker (convex, in front
// of Q's plane) is clipped to the pyramid from x over a convex base in Q's plane,
// projected from x onto that plane, and the images are united as disjoint convex pieces
// (each new image less the pieces already there, by half-plane splits, the largest image
// first, until the pieces cover the base), then cut by the convex parts of Q where the
// base is not Q itself.
//
// Every edge of a piece carries the line it lies on, taken from the 3-D geometry and not
// from its two (rounded) ends: the trace on Q's plane of the plane through x and a
// blocker's edge, or of one of the pyramid's planes. A split is by such a line, so a
// short edge (a clipped corner, two vertices a few units of rounding apart) still cuts
// in its true direction. Only half-plane splits are used: the pieces move continuously
// with the input, the boundary of their union is within the vertices' rounding of the
// exact one, and there is no topology to get wrong. The pieces are returned as rings for
// the sector sums (kernel/sector.py).

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "hidden.h"
#include "predicates.h"
#include "sector.h"
#include "vec.h"

namespace exactff {
namespace {

struct P2 {
    double x, y;
};
// A vector of a trivially copyable T for the vertices rewritten at every point: its
// storage grows and is kept (clear and a copy into it allocate nothing once it is large
// enough), and resize leaves the new elements unset for the caller to write by index.
template <typename T>
class Pod {
    static_assert(std::is_trivially_copyable<T>::value, "Pod holds plain values");
    T* p_ = nullptr;
    size_t n_ = 0, cap_ = 0;

  public:
    Pod() = default;
    Pod(const Pod& o) { *this = o; }
    Pod(Pod&& o) noexcept : p_(o.p_), n_(o.n_), cap_(o.cap_) {
        o.p_ = nullptr;
        o.n_ = o.cap_ = 0;
    }
    Pod& operator=(const Pod& o) {
        if (this != &o) {
            resize(o.n_);
            if (o.n_) std::memcpy(p_, o.p_, o.n_ * sizeof(T));
        }
        return *this;
    }
    Pod& operator=(Pod&& o) noexcept {
        swap(o);
        return *this;
    }
    ~Pod() { std::free(p_); }
    void swap(Pod& o) noexcept {
        std::swap(p_, o.p_);
        std::swap(n_, o.n_);
        std::swap(cap_, o.cap_);
    }
    size_t size() const { return n_; }
    size_t capacity() const { return cap_; }
    bool empty() const { return n_ == 0; }
    void clear() { n_ = 0; }
    void reserve(size_t c) {
        if (c <= cap_) return;
        c = std::max(c, std::max<size_t>(8, 2 * cap_));
        T* q = static_cast<T*>(std::malloc(c * sizeof(T)));
        if (!q) throw std::bad_alloc();
        if (n_) std::memcpy(q, p_, n_ * sizeof(T));
        std::free(p_);
        p_ = q;
        cap_ = c;
    }
    void resize(size_t n) {
        reserve(n);
        n_ = n;
    }
    void push_back(const T& x) {
        if (n_ == cap_) reserve(n_ + 1);
        p_[n_++] = x;
    }
    T& operator[](size_t i) { return p_[i]; }
    const T& operator[](size_t i) const { return p_[i]; }
    T& back() { return p_[n_ - 1]; }
    T* begin() { return p_; }
    T* end() { return p_ + n_; }
    const T* begin() const { return p_; }
    const T* end() const { return p_ + n_; }
};
// 3-D work in R (Vec3<R>, vec.h): double first, long double (on x86 64 bits of mantissa)
// for a point where what the vertices' rounding can move is too much (a crossing near x of
// an edge whose ends are far from it loses the ends' size in absolute terms, and the
// projection magnifies that near x)
// a line of Q's plane, a u + b v + c = 0, the side a u + b v + c >= 0 inside
struct Line {
    double a, b, c;
    double at(const P2& p) const { return a * p.x + b * p.y + c; }
};
// a convex polygon, counter-clockwise, and the line of each edge (v[i], v[i + 1])
struct Piece {
    Pod<P2> v;
    Pod<Line> l;
    void clear() {
        v.clear();
        l.clear();
    }
    size_t size() const { return v.size(); }
};
// a polygon in 3-D (offsets from x), the plane through x of each edge (inside >= 0), a
// bound on each vertex's rounding and each vertex's distance from x
template <typename R>
struct Poly3 {
    Pod<Vec3<R>> v;
    Pod<Vec3<R>> m;
    Pod<R> e, len;
    void clear() {
        v.clear();
        m.clear();
        e.clear();
        len.clear();
    }
    void swap(Poly3& o) noexcept {
        v.swap(o.v);
        m.swap(o.m);
        e.swap(o.e);
        len.swap(o.len);
    }
};

template <typename C>
double twice_area(const C& p) {
    double s = 0.0;
    for (size_t i = 0, n = p.size(); i < n; ++i) {
        const P2& a = p[i];
        const P2& b = p[i + 1 == n ? 0 : i + 1];
        s += (a.x - p[0].x) * (b.y - p[0].y) - (a.y - p[0].y) * (b.x - p[0].x);
    }
    return s;
}

// The part of V where dot(m, v) >= 0 (Sutherland-Hodgman; the crossing computed from the
// inside end, as exactff.halfspace.clip_halfspace); the cut edge lies on m. A crossing's
// rounding: its ends' larger one plus ulps units of the larger end's length.
template <typename R>
void clip3(const Poly3<R>& V, const Vec3<R>& m, const R* side, R ulps, Poly3<R>& out) {
    // written by index into room for 2 n vertices (each edge gives at most its start
    // and a crossing); side: dot(m, v) of each vertex v, taken once by the caller
    const size_t n = V.v.size();
    out.v.resize(2 * n);
    out.m.resize(2 * n);
    out.e.resize(2 * n);
    out.len.resize(2 * n);
    size_t o = 0;
    for (size_t i = 0; i < n; ++i) {
        const size_t j = i + 1 == n ? 0 : i + 1;
        const Vec3<R>& a = V.v[i];
        const Vec3<R>& b = V.v[j];
        const R sa = side[i], sb = side[j];
        if (sa >= 0) {
            out.v[o] = a;
            out.m[o] = V.m[i];
            out.e[o] = V.e[i];
            out.len[o] = V.len[i];
            ++o;
        }
        if ((sa >= 0) != (sb >= 0)) {
            const Vec3<R>& p = sa >= 0 ? a : b;
            const Vec3<R>& q = sa >= 0 ? b : a;
            const R sp = sa >= 0 ? sa : sb, sq = sa >= 0 ? sb : sa;
            const R t = sp / (sp - sq);
            const Vec3<R> c{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.z + t * (q.z - p.z)};
            out.v[o] = c;
            // leaving: the edge from the crossing runs along m; entering: along V's edge
            out.m[o] = sa >= 0 ? m : V.m[i];
            // (the larger end's length: sqrt of the larger squared length, as sqrt is
            // monotone and correctly rounded)
            out.e[o] = std::max(V.e[i], V.e[j]) + ulps * std::max(V.len[i], V.len[j]);
            out.len[o] = std::sqrt(dot(c, c));
            ++o;
        }
    }
    out.v.resize(o);
    out.m.resize(o);
    out.e.resize(o);
    out.len.resize(o);
}

// Split F by the line L: its part on the inside (L >= 0) and on the outside (L < 0, the
// cut edge on the reversed line), the crossings shared by both halves (written by index
// into room for 2 n vertices each, each vertex's side taken once).
void split(const Piece& F, const Line& L, Piece& in, Piece& out) {
    const Line rev{-L.a, -L.b, -L.c};
    const size_t n = F.size();
    in.v.resize(2 * n);
    in.l.resize(2 * n);
    out.v.resize(2 * n);
    out.l.resize(2 * n);
    size_t ni = 0, no = 0;
    double sq = n ? L.at(F.v[0]) : 0.0;
    const double s0 = sq;
    for (size_t i = 0; i < n; ++i) {
        const size_t j = i + 1 == n ? 0 : i + 1;
        const P2& p = F.v[i];
        const P2& q = F.v[j];
        const double sp = sq;
        sq = j ? L.at(q) : s0;
        const bool pin = sp >= 0, qin = sq >= 0;
        if (pin) {
            in.v[ni] = p;
            in.l[ni++] = F.l[i];
        } else {
            out.v[no] = p;
            out.l[no++] = F.l[i];
        }
        if (pin != qin) {
            // from the end inside, so that the same edge gives the same point
            const P2& u = pin ? p : q;
            const P2& w = pin ? q : p;
            const double su = pin ? sp : sq, sw = pin ? sq : sp;
            const double t = su / (su - sw);
            const P2 c{u.x + t * (w.x - u.x), u.y + t * (w.y - u.y)};
            in.v[ni] = c;
            in.l[ni++] = pin ? L : F.l[i];
            out.v[no] = c;
            out.l[no++] = pin ? F.l[i] : rev;
        }
    }
    in.v.resize(ni);
    in.l.resize(ni);
    out.v.resize(no);
    out.l.resize(no);
}

struct Box {
    double x0, y0, x1, y1;
};
Box box_of(const Piece& p) {
    Box b{p.v[0].x, p.v[0].y, p.v[0].x, p.v[0].y};
    for (const P2& v : p.v) {
        b.x0 = std::min(b.x0, v.x);
        b.y0 = std::min(b.y0, v.y);
        b.x1 = std::max(b.x1, v.x);
        b.y1 = std::max(b.y1, v.y);
    }
    return b;
}
inline bool boxes_apart(const Box& a, const Box& b) {
    return a.x1 <= b.x0 || b.x1 <= a.x0 || a.y1 <= b.y0 || b.y1 <= a.y0;
}

// True where the line of an edge of A has all of B's vertices on or outside it: the two
// convex pieces share no interior.
bool separated_by(const Piece& A, const Piece& B) {
    for (const Line& L : A.l) {
        bool all_out = true;
        for (const P2& v : B.v)
            if (L.at(v) > 0) {
                all_out = false;
                break;
            }
        if (all_out) return true;
    }
    return false;
}

// Pieces thinner than rounding are dropped, their area counted (in the estimate): the
// splits along nearly coincident lines (a back face's image against the front faces'
// that share its outline) would otherwise leave slivers that every later image splits
// again, without end. Pieces keep the winding of their image, which may be either way.
struct Slivers {
    double min_area = 0.0;   // twice the area below which a piece is a sliver
    double dropped = 0.0;    // the slivers' area, for the estimate
    Box box{INFINITY, INFINITY, -INFINITY, -INFINITY};
    bool keep(const Piece& p) { return p.size() >= 3 && keep(p, std::fabs(twice_area(p.v))); }
    // ... given a, the piece's twice_area's magnitude
    bool keep(const Piece& p, double a) {
        if (p.size() < 3) return false;
        if (a > min_area) return true;
        if (a > 0) {
            dropped += 0.5 * a;
            const Box b = box_of(p);
            box = {std::min(box.x0, b.x0), std::min(box.y0, b.y0), std::max(box.x1, b.x1),
                   std::max(box.y1, b.y1)};
        }
        return false;
    }
};

// Pieces whose storage is kept from point to point (a point's pieces are a few dozen
// short vectors: taken from here and given back, not allocated and freed each time).
// fresh: an empty piece, with storage where one is spare; recycle: v's pieces given
// back, v left empty.
Piece fresh(std::vector<Piece>& spare) {
    if (spare.empty()) return Piece();
    Piece p = std::move(spare.back());
    spare.pop_back();
    p.clear();
    return p;
}
void recycle(std::vector<Piece>& v, std::vector<Piece>& spare) {
    for (Piece& p : v)
        if (p.v.capacity()) spare.push_back(std::move(p));
    v.clear();
}

// F less the convex E: F's parts outside each of E's lines in turn (rest, in, outside:
// scratch pieces; F is used up, its storage swapped with rest's).
void difference(Piece& F, const Piece& E, std::vector<Piece>& out, Piece& rest,
                Piece& in, Piece& outside, Slivers& slivers, std::vector<Piece>& spare) {
    rest.v.swap(F.v);
    rest.l.swap(F.l);
    for (size_t i = 0, n = E.size(); i < n && rest.size() >= 3; ++i) {
        split(rest, E.l[i], in, outside);
        if (slivers.keep(outside)) {
            out.push_back(std::move(outside));
            outside = fresh(spare);
        }
        rest.v.swap(in.v);
        rest.l.swap(in.l);
    }
}

// F cut by the convex C: its part inside every line of C.
bool intersect(const Piece& F, const Piece& C, Piece& out, Piece& in, Piece& outside,
               Slivers& slivers) {
    out = F;
    for (const Line& L : C.l) {
        split(out, L, in, outside);
        out.v.swap(in.v);
        out.l.swap(in.l);
        if (out.size() < 3) return false;
    }
    return slivers.keep(out);
}

// The inputs of one call, in doubles.
struct Inputs {
    std::vector<Vec3<double>> base;              // the pyramid's base
    Vec3<double> base_centroid;
    std::vector<std::vector<Vec3<double>>> K;    // the blockers
    std::vector<std::vector<Vec3<double>>> KE;   // their edges' vectors, K[k + 1] - K[k]
    std::vector<Vec3<double>> KN;                // their unit normals (outward for a solid's)
    std::vector<long long> group;              // each one's convex solid, -1: none
    long long groups = 0;                      // 1 + the largest solid's label
    double back_face = 0.0;                    // a distance beyond which p is off a plane
    std::vector<P2> base2;                     // the base in Q's plane frame
    Box base_box{0, 0, 0, 0};
    double base_area2 = 0.0;                   // twice its area
    std::vector<Piece> Qparts;                 // Q's convex parts (none over Q itself)
    std::vector<Box> Qbox;
    Vec3<double> origin, nq, ax, ay;
    double edge_on, vertex_ulps, sliver_ulps;
    size_t max_pieces;
};

// What one point's hidden region is: its pieces, and what the estimate needs.
struct Region {
    std::vector<Piece> pieces;
    Slivers slivers;
    double reach = 0.0, moved = 0.0;
    long long back_faces = 0;                  // a solid's members skipped, seen from behind
    bool ok = true;                            // false: an image not finite, too many pieces
};

// Scratch space reused from point to point.
template <typename R>
struct Work {
    std::vector<Vec3<R>> M;
    std::vector<unsigned char> off_hull;       // per solid: p is outside its hull
    Poly3<R> W, T;
    Pod<R> side;
    Piece img, in, outside, cut, rest;
    std::vector<Piece> incoming, next, images, spare;
    std::vector<std::pair<double, size_t>> order;
    std::vector<double> area2;                 // each image's twice area, its magnitude
    std::vector<size_t> image_blocker;         // each image's blocker
    size_t last_cover = 0;                     // the blocker tried first at the next point
};

// The side of the input point x of the plane through p and the input points a, b:
// orient(p, a, b, x) = det(a - p, b - a, x - p) = (a - p) . n, n = (b - a) x (x - a), an
// affine function of p. Over the box lo <= p <= hi: 0 where it is 0 for every p there
// (a, b, x on a line along an axis, x an end of the edge, or the four in one plane of
// the axes), +1 or -1 where its least or largest value over the box's corners is beyond
// the rounding of n and of the sum (32 units of roundoff of sum(|n_i| permanents) max
// |a - p|, a loose bound of some 4), else 2 (not settled).
int box_side(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& x,
             const double* lo, const double* hi) {
    const bool sx = a.x == b.x && x.x == a.x, sy = a.y == b.y && x.y == a.y,
               sz = a.z == b.z && x.z == a.z;
    if ((sx && sy) || (sy && sz) || (sz && sx) || (x.x == a.x && x.y == a.y && x.z == a.z) ||
        (x.x == b.x && x.y == b.y && x.z == b.z) || (sx && lo[0] == a.x && hi[0] == a.x) ||
        (sy && lo[1] == a.y && hi[1] == a.y) || (sz && lo[2] == a.z && hi[2] == a.z))
        return 0;
    const double e[3] = {b.x - a.x, b.y - a.y, b.z - a.z}, d[3] = {x.x - a.x, x.y - a.y, x.z - a.z};
    const double A[3] = {a.x, a.y, a.z};
    double fmin = 0.0, fmax = 0.0, perm = 0.0, far = 0.0;
    for (int i = 0; i < 3; ++i) {
        const int j = i == 2 ? 0 : i + 1, k = j == 2 ? 0 : j + 1;
        const double n = e[j] * d[k] - e[k] * d[j];
        perm += std::fabs(e[j] * d[k]) + std::fabs(e[k] * d[j]);
        const double t0 = n * (A[i] - lo[i]), t1 = n * (A[i] - hi[i]);
        fmin += std::min(t0, t1);
        fmax += std::max(t0, t1);
        far = std::max(far, std::max(std::fabs(A[i] - lo[i]), std::fabs(A[i] - hi[i])));
    }
    const double bound = 32 * DBL_EPSILON * perm * far;
    if (fmin > bound) return 1;
    if (fmax < -bound) return -1;
    return 2;
}

// The same side at one point p, exactly where box_side does not settle it (predicates.h:
// a long double filter, then expansions).
int point_side(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& x,
               const Vec3<double>& p) {
    const double P[3] = {p.x, p.y, p.z};
    const int s = box_side(a, b, x, P, P);
    if (s != 2) return s;
    const double A[3] = {a.x, a.y, a.z}, B[3] = {b.x, b.y, b.z}, X[3] = {x.x, x.y, x.z};
    exactff::R value, error;
    filtered(0, P, A, B, X, &value, &error);
    if (std::fabs(value) > error) return value > 0 ? 1 : -1;
    return sign(orient_exact(P, A, B, X));
}

// A blocker whose part in the pyramid lies in the cone from p over another blocker, the
// hint, hides nothing more than the hint: its image is in the hint's (both cones and the
// pyramid have their apex at p). The hint is the first blocker projected at p, where it
// is strictly convex seen from p (every other vertex strictly inside each of its edge
// planes: the cone is the planes' intersection, sigma each plane's inner side); a
// blocker is inside it where each of its vertices is inside (or on) each of the hint's
// planes that cuts the pyramid (a corner of the base strictly outside it; a plane that
// does not holds the whole pyramid). Each test is the exact side of an input point of a
// plane through p and two input points (box_side, point_side): the decision is exact,
// the same whichever way it is taken. It is taken once for the points of a cell (their
// box: an affine function's sign at its corners holds inside), and point by point where
// the cell's box does not settle it.
struct Hints {
    const Inputs* in = nullptr;
    // the cell: its box, the hint it was settled for, whether the hint is strictly
    // convex over it, each plane's side and whether it may cut the pyramid there, and
    // per blocker whether it is inside (1), outside (2), not settled (0) or not yet
    // looked at (-1)
    double lo[3], hi[3];
    size_t cell_hint = SIZE_MAX;
    bool cell_sure = false;
    std::vector<signed char> cell_sigma, cell_in;
    std::vector<unsigned char> cell_cut;
    // the point: p, its hint, and the hint's sides and cuts there (point_done)
    Vec3<double> p;
    size_t hint = SIZE_MAX;
    bool have = false, point_done = false;
    std::vector<signed char> sigma;
    std::vector<unsigned char> cut;

    void new_cell(const double* l, const double* h) {
        std::copy(l, l + 3, lo);
        std::copy(h, h + 3, hi);
        cell_hint = SIZE_MAX;
    }
    void new_point(const Vec3<double>& x) {
        p = x;
        have = point_done = false;
    }
    // the hint's planes' sides (over the box or at p): false where not strictly convex
    template <typename Side>
    bool sides(size_t b, std::vector<signed char>& sg, Side side) const {
        const std::vector<Vec3<double>>& K = in->K[b];
        const size_t kb = K.size();
        if (kb < 3) return false;
        sg.assign(kb, 0);
        for (size_t k = 0; k < kb; ++k) {
            const size_t k1 = k + 1 == kb ? 0 : k + 1;
            for (size_t j = 0; j < kb; ++j) {
                if (j == k || j == k1) continue;
                const int s = side(K[k], K[k1], K[j]);
                if (!(s == 1 || s == -1) || (sg[k] && s != sg[k])) return false;
                sg[k] = static_cast<signed char>(s);
            }
        }
        return true;
    }
    // the blocker b offered as the hint at p (the first projected there): taken where
    // strictly convex
    void offer(size_t b) {
        if (cell_hint != b) {
            cell_hint = b;
            cell_sure = sides(b, cell_sigma, [&](const Vec3<double>& a, const Vec3<double>& e,
                                                 const Vec3<double>& x) {
                return box_side(a, e, x, lo, hi);
            });
            if (cell_sure) {
                // 0: the plane holds the whole pyramid at every point, 1: a corner of the
                // base is strictly outside it at every point, 2: not settled
                const std::vector<Vec3<double>>& K = in->K[b];
                const size_t kb = K.size();
                cell_cut.assign(kb, 0);
                for (size_t k = 0; k < kb; ++k)
                    for (const Vec3<double>& c : in->base) {
                        const int s = box_side(K[k], K[k + 1 == kb ? 0 : k + 1], c, lo, hi);
                        if (s == -cell_sigma[k]) {
                            cell_cut[k] = 1;
                            break;
                        }
                        if (s == 2) cell_cut[k] = 2;
                    }
            }
            cell_in.assign(in->K.size(), -1);
        }
        if (cell_sure) {
            hint = b;
            have = true;
            return;
        }
        if (sides(b, sigma, [&](const Vec3<double>& a, const Vec3<double>& e,
                                const Vec3<double>& x) { return point_side(a, e, x, p); })) {
            hint = b;
            have = point_done = true;
            set_cuts();
        }
    }
    // the hint's planes that cut the pyramid at p, given sigma; with from_cell, a plane
    // the cell settled (cell_cut 0 or 1: so at every point of it) as the cell has it
    void set_cuts(bool from_cell = false) {
        const std::vector<Vec3<double>>& K = in->K[hint];
        const size_t kb = K.size();
        cut.assign(kb, 0);
        for (size_t k = 0; k < kb; ++k) {
            if (from_cell && cell_cut[k] != 2) {
                cut[k] = cell_cut[k];
                continue;
            }
            for (const Vec3<double>& c : in->base) {
                const int s = point_side(K[k], K[k + 1 == kb ? 0 : k + 1], c, p);
                if (s != 0 && s != sigma[k]) {
                    cut[k] = 1;
                    break;
                }
            }
        }
    }
    // whether the blocker c is inside the hint's cone where that cone meets the pyramid
    bool contains(size_t c) {
        const std::vector<Vec3<double>>& K = in->K[hint];
        const std::vector<Vec3<double>>& C = in->K[c];
        const size_t kb = K.size();
        if (cell_hint == hint && cell_sure) {
            // 1: inside at every point, 2: outside at every point (a vertex strictly
            // outside a plane that cuts the pyramid everywhere), 0: not settled
            if (cell_in[c] < 0) {
                bool yes = true, no = false;
                for (size_t k = 0; k < kb && !no; ++k) {
                    if (!cell_cut[k]) continue;
                    for (const Vec3<double>& x : C) {
                        const int s = box_side(K[k], K[k + 1 == kb ? 0 : k + 1], x, lo, hi);
                        if (s == 0 || s == cell_sigma[k]) continue;
                        yes = false;
                        if (s == -cell_sigma[k] && cell_cut[k] == 1) {
                            no = true;
                            break;
                        }
                    }
                }
                cell_in[c] = yes ? 1 : no ? 2 : 0;
            }
            if (cell_in[c] == 2) return false;
            if (cell_in[c]) return true;
            if (!point_done) {
                sigma = cell_sigma;
                set_cuts(true);
                point_done = true;
            }
        }
        for (size_t k = 0; k < kb; ++k) {
            if (!cut[k]) continue;
            for (const Vec3<double>& x : C) {
                const int s = point_side(K[k], K[k + 1 == kb ? 0 : k + 1], x, p);
                if (s != 0 && s != sigma[k]) return false;
            }
        }
        return true;
    }
};

// Over a base other than Q, the region's pieces cut by Q's convex parts.
template <typename R>
void over_parts(const Inputs& in, Region& out, Work<R>& w) {
    if (in.Qparts.empty()) return;
    recycle(w.next, w.spare);
    for (const Piece& F : out.pieces) {
        const Box bf = box_of(F);
        for (size_t q = 0; q < in.Qparts.size(); ++q)
            if (!boxes_apart(bf, in.Qbox[q]) &&
                intersect(F, in.Qparts[q], w.cut, w.in, w.outside, out.slivers)) {
                w.next.push_back(std::move(w.cut));
                w.cut = fresh(w.spare);
            }
    }
    out.pieces.swap(w.next);
}

// The hidden region of Q from the point p, in precision R.
template <typename R>
void region_at(const Inputs& in, const Vec3<double>& pd, Region& out, Work<R>& w,
               Hints& hints) {
    recycle(out.pieces, w.spare);
    out.slivers = Slivers();
    out.reach = out.moved = 0.0;
    out.back_faces = 0;
    out.ok = true;
    const R vertex_error = R(in.vertex_ulps) * std::numeric_limits<R>::epsilon();
    const Vec3<R> p = to<R>(pd), nq = to<R>(in.nq), ax = to<R>(in.ax), ay = to<R>(in.ay);
    const Vec3<R> foot = sub(p, to<R>(in.origin));
    const R h = dot(foot, nq);
    if (!(h > 0)) return;              // on Q's plane: Q edge-on, nothing hidden
    // the pyramid's inward planes through p: (a - p) x (b - a) for its edge a -> b, the
    // edge's vector from the input's coordinates (exact where a and b are close: a
    // short edge keeps its direction, where (a - p) x (b - p) would lose it), inside
    // towards the base's centroid
    const size_t nc = in.base.size();
    w.M.resize(nc);
    for (size_t a = 0; a < nc; ++a) {
        const Vec3<double>& a0 = in.base[a];
        const Vec3<double>& a1 = in.base[a + 1 == nc ? 0 : a + 1];
        w.M[a] = cross(sub(to<R>(a0), p), to<R>(sub(a1, a0)));
        if (dot(w.M[a], sub(to<R>(in.base_centroid), p)) < 0) w.M[a] = neg(w.M[a]);
    }
    // a convex solid's members seen from behind hide nothing that those seen from the
    // front do not, where p is outside the solid's hull (in front of one member's
    // plane): a line of sight through a member it sees from behind enters the hull
    // first through one it sees from the front (the solid is closed but in the emitter's
    // plane, which p is on, and the receiver's, which p sees it from behind), and the
    // shaft culling keeps every member that meets a line of sight
    w.off_hull.assign(static_cast<size_t>(in.groups), 0);
    for (size_t b = 0; b < in.K.size(); ++b)
        if (in.group[b] >= 0 && dot(sub(in.K[b][0], pd), in.KN[b]) < -in.back_face)
            w.off_hull[static_cast<size_t>(in.group[b])] = 1;
    Poly3<R>& W = w.W;
    size_t images = 0;
    // the blocker whose image covered the base at the point before first (neighbouring
    // points are mostly hidden by the same one: a wall between the emitter and the
    // receiver), then the others in order
    const size_t nk = in.K.size(), first = w.last_cover < nk ? w.last_cover : 0;
    hints.new_point(pd);
    for (size_t t = 0; t < nk; ++t) {
        const size_t b = t == 0 ? first : (t <= first ? t - 1 : t);
        // the offsets, each rounded once (within vertex_error of its length: W.e, with
        // the edges' planes, once the blocker is not culled below)
        const std::vector<Vec3<double>>& Kb = in.K[b];
        const size_t kb = Kb.size();
        W.clear();
        W.v.resize(kb);
        for (size_t k = 0; k < kb; ++k) W.v[k] = sub(to<R>(Kb[k]), p);
        if (std::fabs(dot(W.v[0], to<R>(in.KN[b]))) <= R(in.edge_on)) continue;   // edge-on
        // wholly outside one of the pyramid's planes: clipped away, as clip3 would
        bool outside_pyramid = false;
        for (size_t a = 0; a < nc && !outside_pyramid; ++a) {
            outside_pyramid = true;
            for (const Vec3<R>& v : W.v)
                if (dot(w.M[a], v) >= 0) {
                    outside_pyramid = false;
                    break;
                }
        }
        if (outside_pyramid) continue;
        // seen from behind, off the hull (counted only here, where it would be projected)
        if (in.group[b] >= 0 && w.off_hull[static_cast<size_t>(in.group[b])] &&
            dot(sub(in.K[b][0], pd), in.KN[b]) > in.back_face) {
            ++out.back_faces;
            continue;
        }
        // inside the hint's cone where it meets the pyramid: its image is in the hint's
        if (hints.have && hints.contains(b)) continue;
        // each vertex's rounding, and each edge's plane through p (as the pyramid's, from
        // the edge's own vector), inside towards the blocker's centroid
        W.e.resize(kb);
        W.len.resize(kb);
        W.m.resize(kb);
        Vec3<R> g{0, 0, 0};
        for (size_t k = 0; k < kb; ++k) {
            const Vec3<R>& v = W.v[k];
            W.len[k] = std::sqrt(dot(v, v));
            W.e[k] = vertex_error * W.len[k];
            g = {g.x + v.x, g.y + v.y, g.z + v.z};
        }
        for (size_t k = 0; k < kb; ++k) {
            Vec3<R> e = cross(W.v[k], to<R>(in.KE[b][k]));
            W.m[k] = dot(e, g) < 0 ? neg(e) : e;
        }
        for (size_t a = 0; a < nc && W.v.size() >= 3; ++a) {
            // each vertex's side of the plane; wholly inside it: nothing to cut
            const size_t nw = W.v.size();
            w.side.resize(nw);
            bool inside = true;
            for (size_t k = 0; k < nw; ++k) {
                w.side[k] = dot(w.M[a], W.v[k]);
                inside &= w.side[k] >= 0;
            }
            if (inside) continue;
            clip3(W, w.M[a], w.side.begin(), vertex_error, w.T);
            W.swap(w.T);
        }
        if (W.v.size() < 3) continue;
        // central projection from p onto Q's plane, in the plane's frame; each edge's
        // plane m traced on it: (ax . m) u + (ay . m) v + (q0 - p) . m
        if (!hints.have) hints.offer(b);
        if (w.images.size() <= images) w.images.resize(images + 1);
        if (w.image_blocker.size() < images + 1) w.image_blocker.resize(images + 1);
        w.image_blocker[images] = b;
        Piece& img = w.images[images++];
        if (!img.v.capacity()) img = fresh(w.spare);
        const size_t nw = W.v.size();
        img.v.resize(nw);
        img.l.resize(nw);
        for (size_t k = 0; k < nw; ++k) {
            const Vec3<R>& v = W.v[k];
            const R down = -dot(v, nq);
            const R s = h / down;
            // where the vertex's rounding e takes the image: |s| e (1 + |v| / |v . nQ|),
            // large for a crossing close to p
            out.moved = std::max(out.moved, static_cast<double>(
                std::fabs(s) * W.e[k] * (1 + W.len[k] / std::fabs(down))));
            const Vec3<R> q{v.x * s + foot.x, v.y * s + foot.y, v.z * s + foot.z};
            const P2 u{static_cast<double>(dot(q, ax)), static_cast<double>(dot(q, ay))};
            if (!std::isfinite(u.x) || !std::isfinite(u.y)) {
                out.ok = false;
                return;
            }
            out.reach = std::max({out.reach, std::fabs(u.x), std::fabs(u.y)});
            img.v[k] = u;
            const Vec3<R>& m = W.m[k];
            img.l[k] = {static_cast<double>(dot(ax, m)), static_cast<double>(dot(ay, m)),
                        static_cast<double>(-dot(foot, m))};
        }
        // an image that covers the base alone (its area within the slivers' rounding of
        // the base's) is the region: the other blockers hide nothing more, and what is
        // left of the base uncovered is counted with the slivers (in the estimate)
        const double min_area = in.sliver_ulps * DBL_EPSILON * out.reach * out.reach;
        if (w.area2.size() < images) w.area2.resize(images);
        const double area2 = w.area2[images - 1] = std::fabs(twice_area(img.v));
        const double left2 = in.base_area2 - area2;
        if (in.base_area2 > 0 && img.size() >= 3 && left2 <= 2.0 * min_area) {
            out.slivers.min_area = min_area;
            out.slivers.dropped += 0.5 * std::max(left2, 0.0);
            const Box& bb = in.base_box;
            Box& sb = out.slivers.box;
            sb = {std::min(sb.x0, bb.x0), std::min(sb.y0, bb.y0), std::max(sb.x1, bb.x1),
                  std::max(sb.y1, bb.y1)};
            out.pieces.push_back(std::move(img));
            w.last_cover = b;
            over_parts(in, out, w);
            return;
        }
    }
    // the images united, the largest first (a smaller one inside a piece already there
    // adds nothing at the cost of its splits, where one taken before a larger one would
    // cut the larger into pieces around it), each less every piece already there, as
    // disjoint convex pieces; once the pieces cover the base (their area within the
    // slivers' rounding of it, a piece's each), the rest hides nothing more, and what
    // is left of the base uncovered is counted with the slivers (in the estimate)
    out.slivers.min_area = in.sliver_ulps * DBL_EPSILON * out.reach * out.reach;
    w.order.clear();
    for (size_t k = 0; k < images; ++k)
        if (w.images[k].size() >= 3)
            w.order.push_back({-w.area2[k], k});
    std::sort(w.order.begin(), w.order.end());
    if (!w.order.empty()) w.last_cover = w.image_blocker[w.order[0].second];
    double covered2 = 0.0;
    for (const auto& [neg_area, k] : w.order) {
        Piece& img = w.images[k];
        if (!out.slivers.keep(img, -neg_area)) continue;
        recycle(w.incoming, w.spare);
        w.incoming.push_back(std::move(img));
        const size_t have = out.pieces.size();
        for (size_t e = 0; e < have && !w.incoming.empty(); ++e) {
            const Piece& E = out.pieces[e];
            const Box be = box_of(E);
            recycle(w.next, w.spare);
            for (Piece& F : w.incoming) {
                if (boxes_apart(box_of(F), be) || separated_by(E, F) || separated_by(F, E))
                    w.next.push_back(std::move(F));
                else
                    difference(F, E, w.next, w.rest, w.in, w.outside, out.slivers, w.spare);
            }
            w.incoming.swap(w.next);
        }
        for (Piece& F : w.incoming) {
            covered2 += std::fabs(twice_area(F.v));
            out.pieces.push_back(std::move(F));
        }
        // a point whose pieces grow past max_pieces goes to the engine instead
        if (out.pieces.size() > in.max_pieces) {
            out.ok = false;
            return;
        }
        const double left2 = in.base_area2 - covered2;
        if (in.base_area2 > 0 &&
            left2 <= out.slivers.min_area * static_cast<double>(1 + out.pieces.size())) {
            out.slivers.dropped += 0.5 * std::max(left2, 0.0);
            const Box& b = in.base_box;
            Box& sb = out.slivers.box;
            sb = {std::min(sb.x0, b.x0), std::min(sb.y0, b.y0), std::max(sb.x1, b.x1),
                  std::max(sb.y1, b.y1)};
            break;
        }
    }
    over_parts(in, out, w);
}

// Eq. 3's sector sum of one piece seen from x, with its rounding estimate: the port to
// doubles of exactff.kernel.clipped_sector_sums (offset form, the horizon z = 0 of the
// receiving frame clipped and its arcs added; tests/test_area.py checks the two agree).
// The piece's vertices in Q's plane frame; w = q0 - x; frame the receiving frame (rows);
// ax, ay the plane's axes. Adds |sum| to *value and c1 eps sum|terms| + the terms'
// errors to *rounding (both before the division by 2 pi).
struct SectorWork {
    std::vector<Vec3<double>> E;
    std::vector<double> term;
    std::vector<Vec3<double>> crossing;
    std::vector<size_t> crossing_edge;
    std::vector<unsigned char> crossing_enters;
};

inline Vec3<double> rotate(const double frame[3][3], const Vec3<double>& u) {
    return {frame[0][0] * u.x + frame[0][1] * u.y + frame[0][2] * u.z,
            frame[1][0] * u.x + frame[1][1] * u.y + frame[1][2] * u.z,
            frame[2][0] * u.x + frame[2][1] * u.y + frame[2][2] * u.z};
}

void sector_sum(const Piece& F, const Vec3<double>& w, const double frame[3][3], const Vec3<double>& ax,
                const Vec3<double>& ay, double c1, double c2, double eps, SectorWork& k,
                double* value, double* rounding) {
    const size_t m = F.size();
    const P2& f = F.v[0];
    // the reference vertex relative to x, and the offsets from it, in the receiving frame
    const Vec3<double> A = rotate(frame, {w.x + (f.x * ax.x + f.y * ay.x), w.y + (f.x * ax.y + f.y * ay.y),
                                    w.z + (f.x * ax.z + f.y * ay.z)});
    k.E.resize(m);
    for (size_t i = 0; i < m; ++i) {
        const double du = F.v[i].x - f.x, dv = F.v[i].y - f.y;
        k.E[i] = rotate(frame, {du * ax.x + dv * ay.x, du * ax.y + dv * ay.y, du * ax.z + dv * ay.z});
    }
    k.term.assign(m, 0.0);
    k.crossing.clear();
    k.crossing_edge.clear();
    k.crossing_enters.clear();
    double errs = 0.0;
    for (size_t i = 0; i < m; ++i) {
        Vec3<double> Ea = k.E[i], Eb = k.E[i + 1 == m ? 0 : i + 1];
        const double za = A.z + Ea.z, zb = A.z + Eb.z;
        const bool above_a = za > 0, above_b = zb > 0;
        if (!above_a && !above_b) continue;
        if (above_a != above_b) {
            // the edge's horizon crossing, as an offset (its height exactly 0)
            const double t = za / (za - zb);
            const Vec3<double> X{Ea.x + t * (Eb.x - Ea.x), Ea.y + t * (Eb.y - Ea.y),
                               Ea.z + t * (Eb.z - Ea.z)};
            if (!above_a) Ea = X;
            else Eb = X;
            k.crossing.push_back({A.x + X.x, A.y + X.y, A.z + X.z});
            k.crossing_edge.push_back(i);
            k.crossing_enters.push_back(!above_a);
        }
        // the edge's term and its rounding (sector.h, as clipped_sector_sums)
        const SectorTerm<double> st =
            sector_term(A.x, A.y, A.z, Ea.x, Ea.y, Ea.z, Eb.x, Eb.y, Eb.z, c2 * eps);
        k.term[i] = st.term;
        errs += st.err;
    }
    // the horizon arcs: the signed angle of each crossing from the piece's first one
    if (!k.crossing.empty()) {
        const Vec3<double>& g = k.crossing[0];
        for (size_t j = 0; j < k.crossing.size(); ++j) {
            const Vec3<double>& X = k.crossing[j];
            const double phi = std::atan2(g.x * X.y - g.y * X.x, g.x * X.x + g.y * X.y);
            k.term[k.crossing_edge[j]] += k.crossing_enters[j] ? phi : -phi;
        }
    }
    double S = 0.0, mag = 0.0;
    for (size_t i = 0; i < m; ++i) {
        S += k.term[i];
        mag += std::fabs(k.term[i]);
    }
    *value += std::fabs(S);
    *rounding += sum_rounding(c1 * eps, mag, errs);
}

}  // namespace

HiddenResult hidden_pieces(const HiddenArgs& args) {
    // the arrays as the loops read them (C order)
    const auto x = [&](std::ptrdiff_t i, int k) { return args.X[3 * i + k]; };
    const auto cr = [&](std::ptrdiff_t i, int k) { return args.corners[3 * i + k]; };
    const auto bl = [&](std::ptrdiff_t b, std::ptrdiff_t k, int j) {
        return args.blockers[(b * args.blocker_stride + k) * 3 + j];
    };
    const auto bc = [&](std::ptrdiff_t b) { return args.counts[b]; };
    const auto bn = [&](std::ptrdiff_t b, int j) { return args.normals[3 * b + j]; };
    const auto bg = [&](std::ptrdiff_t b) { return args.groups[b]; };
    const auto pa = [&](std::ptrdiff_t q, std::ptrdiff_t k, int j) {
        return args.parts[(q * args.part_stride + k) * 2 + j];
    };
    const auto pc = [&](std::ptrdiff_t q) { return args.part_counts[q]; };
    double frame[3][3];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) frame[a][b] = args.frame[3 * a + b];
    const double *q0 = args.q0, *nQ = args.nQ, *RQ = args.RQ;
    const double back_face = args.back_face, edge_on = args.edge_on,
                 vertex_ulps = args.vertex_ulps, sliver_ulps = args.sliver_ulps,
                 precise_rtol = args.precise_rtol, precise_atol = args.precise_atol,
                 extent = args.extent, c1 = args.c1,
                 c2 = args.c2, eps = args.eps;
    const long long max_pieces = args.max_pieces;
    const bool rings = args.rings;
    Inputs in;
    in.origin = {q0[0], q0[1], q0[2]};
    in.nq = {nQ[0], nQ[1], nQ[2]};
    in.ax = {RQ[0], RQ[1], RQ[2]};
    in.ay = {RQ[3], RQ[4], RQ[5]};
    in.edge_on = edge_on;
    in.vertex_ulps = vertex_ulps;
    in.sliver_ulps = sliver_ulps;
    in.max_pieces = static_cast<size_t>(max_pieces);
    const std::ptrdiff_t n = args.n, nc = args.n_corners, nb = args.n_blockers,
                         np_ = args.n_parts;
    in.base_centroid = {0.0, 0.0, 0.0};
    for (std::ptrdiff_t a = 0; a < nc; ++a) {
        in.base.push_back({cr(a, 0), cr(a, 1), cr(a, 2)});
        in.base_centroid = {in.base_centroid.x + cr(a, 0) / nc, in.base_centroid.y + cr(a, 1) / nc,
                            in.base_centroid.z + cr(a, 2) / nc};
    }
    // the base in Q's plane frame about q0, and twice its area (the region's pieces cover
    // at most that)
    for (const Vec3<double>& b : in.base) {
        const Vec3<double> f = sub(b, in.origin);
        in.base2.push_back({dot(f, in.ax), dot(f, in.ay)});
    }
    if (nc >= 3) {
        Piece B;
        for (const P2& b : in.base2) B.v.push_back(b);
        in.base_box = box_of(B);
        in.base_area2 = std::fabs(twice_area(in.base2));
    }
    in.K.resize(nb);
    in.KE.resize(nb);
    for (std::ptrdiff_t b = 0; b < nb; ++b) {
        for (std::ptrdiff_t k = 0; k < bc(b); ++k)
            in.K[b].push_back({bl(b, k, 0), bl(b, k, 1), bl(b, k, 2)});
        for (size_t k = 0, m = in.K[b].size(); k < m; ++k)
            in.KE[b].push_back(sub(in.K[b][k + 1 == m ? 0 : k + 1], in.K[b][k]));
        in.KN.push_back({bn(b, 0), bn(b, 1), bn(b, 2)});
        in.group.push_back(bg(b));
        in.groups = std::max(in.groups, bg(b) + 1);
    }
    in.back_face = back_face;
    // Q's convex parts, each edge's line from its two vertices (the input's own edges
    // and the diagonals between its vertices), inside towards the part's centroid
    in.Qparts.resize(np_);
    for (std::ptrdiff_t q = 0; q < np_; ++q) {
        Piece& C = in.Qparts[q];
        P2 g{0.0, 0.0};
        for (std::ptrdiff_t k = 0; k < pc(q); ++k) {
            C.v.push_back({pa(q, k, 0), pa(q, k, 1)});
            g.x += pa(q, k, 0) / static_cast<double>(pc(q));
            g.y += pa(q, k, 1) / static_cast<double>(pc(q));
        }
        for (size_t k = 0, m = C.size(); k < m; ++k) {
            const P2& u = C.v[k];
            const P2& w = C.v[(k + 1) % m];
            Line L{-(w.y - u.y), w.x - u.x, 0.0};
            L.c = -(L.a * u.x + L.b * u.y);
            if (L.at(g) < 0) L = {-L.a, -L.b, -L.c};
            C.l.push_back(L);
        }
        in.Qbox.push_back(box_of(C));
    }

    HiddenResult res;
    std::vector<double>& xy = res.xy;
    std::vector<long long>& ring_start = res.ring_start;
    std::vector<long long>& ring_point = res.ring_point;
    ring_start.push_back(0);
    std::vector<unsigned char>& lost = res.lost;
    lost.assign(n, 0);
    long long& back_faces = res.back_faces;
    std::vector<double>&reach = res.reach, &length = res.length, &bounds = res.box,
                       &moved = res.moved, &dropped = res.dropped, &hidden = res.hidden,
                       &rounding = res.rounding;
    for (std::vector<double>* v : {&reach, &length, &moved, &dropped, &hidden, &rounding})
        v->assign(n, 0.0);
    bounds.assign(4 * n, 0.0);
    {
        Region region;
        Work<double> fast;
        Work<long double> precise;
        SectorWork sectors;
        Hints hints;
        hints.in = &in;
        const double two_pi = 6.283185307179586;
        for (std::ptrdiff_t i = 0, cell_end = 0; i < n; ++i) {
            const Vec3<double> p{x(i, 0), x(i, 1), x(i, 2)};
            // a new cell: the box of its points (each point its own without cells)
            if (i == cell_end) {
                cell_end = i + 1;
                if (args.cells)
                    while (cell_end < n && args.cells[cell_end] == args.cells[i]) ++cell_end;
                double lo[3] = {p.x, p.y, p.z}, hi[3] = {p.x, p.y, p.z};
                for (std::ptrdiff_t j = i + 1; j < cell_end; ++j)
                    for (int k = 0; k < 3; ++k) {
                        lo[k] = std::min(lo[k], x(j, k));
                        hi[k] = std::max(hi[k], x(j, k));
                    }
                hints.new_cell(lo, hi);
            }
            // in doubles first; in long double where an image is not finite or the
            // vertices' rounding can move it by more than precise_rtol of its extent
            region_at(in, p, region, fast, hints);
            bool again = !region.ok || region.moved > precise_rtol * std::max(region.reach, extent);
            // the pieces' perimeter where taken here, for the doubles' pieces kept
            double perimeter = 0.0;
            bool have_perimeter = false;
            if (again && region.ok && precise_atol >= 0 && !region.pieces.empty()) {
                // what the doubles' rounding moves of the value, the estimate's term
                // moved * length * h / (pi r^3) (r: the distance from p to the region's
                // box): within precise_atol, the doubles' pieces stand
                double len = 0.0;
                Box bb = region.slivers.box;
                for (const Piece& F : region.pieces)
                    for (size_t k = 0, m = F.size(); k < m; ++k) {
                        const P2& u = F.v[k];
                        const P2& v = F.v[k + 1 == m ? 0 : k + 1];
                        len += std::hypot(v.x - u.x, v.y - u.y);
                        bb.x0 = std::min(bb.x0, u.x);
                        bb.y0 = std::min(bb.y0, u.y);
                        bb.x1 = std::max(bb.x1, u.x);
                        bb.y1 = std::max(bb.y1, u.y);
                    }
                const Vec3<double> f = sub(p, in.origin);
                const double h = dot(f, in.nq), fx = dot(f, in.ax), fy = dot(f, in.ay);
                const double dx = std::max(0.0, std::max(bb.x0 - fx, fx - bb.x1));
                const double dy = std::max(0.0, std::max(bb.y0 - fy, fy - bb.y1));
                const double r = std::sqrt(h * h + dx * dx + dy * dy);
                const double bound = r > 0 && h > 0 ? h / (3.141592653589793 * r * r * r) : 0.0;
                again = !(region.moved * len * bound <= precise_atol);
                perimeter = len;
                have_perimeter = true;
            }
            if (again) {
                region_at(in, p, region, precise, hints);
                have_perimeter = false;
            }
            reach[i] = region.reach;
            moved[i] = region.moved;
            back_faces += region.back_faces;
            if (!region.ok) {
                lost[i] = 1;
                continue;
            }
            double len = 0.0, value = 0.0, rnd = 0.0;
            const Vec3<double> w{in.origin.x - p.x, in.origin.y - p.y, in.origin.z - p.z};
            Box bb = region.slivers.box;     // the slivers dropped lie in the region's box
            dropped[i] = region.slivers.dropped;
            for (const Piece& F : region.pieces) {
                for (size_t k = 0, m = F.size(); k < m; ++k) {
                    const P2& u = F.v[k];
                    const P2& v = F.v[k + 1 == m ? 0 : k + 1];
                    if (rings) {
                        xy.push_back(u.x);
                        xy.push_back(u.y);
                    }
                    if (!have_perimeter) len += std::hypot(v.x - u.x, v.y - u.y);
                    bb.x0 = std::min(bb.x0, u.x);
                    bb.y0 = std::min(bb.y0, u.y);
                    bb.x1 = std::max(bb.x1, u.x);
                    bb.y1 = std::max(bb.y1, u.y);
                }
                sector_sum(F, w, frame, in.ax, in.ay, c1, c2, eps, sectors, &value, &rnd);
                if (rings) {
                    ring_start.push_back(static_cast<long long>(xy.size() / 2));
                    ring_point.push_back(i);
                }
            }
            length[i] = have_perimeter ? perimeter : len;
            hidden[i] = value / two_pi;
            rounding[i] = rnd / two_pi;
            if (bb.x0 <= bb.x1) {
                bounds[4 * i] = bb.x0;
                bounds[4 * i + 1] = bb.y0;
                bounds[4 * i + 2] = bb.x1;
                bounds[4 * i + 3] = bb.y1;
            }
        }
    }
    return res;
}

}  // namespace exactff
