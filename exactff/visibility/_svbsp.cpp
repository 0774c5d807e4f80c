// The compiled visibility core (issue 28): one row of exact occluded form factors.
//
// A BSP tree of convex fragments (built by exactff.visibility.bsp, convexified by
// exactff.visibility.compiled) gives the fragments front to back from the point p.
// The covered region is a shadow-volume BSP tree (Chin & Feiner 1989): a BSP tree of
// planes through p whose leaves are covered (IN) or free (OUT); its root is the
// horizon plane (below it: covered). Each fragment is filtered down the tree; the
// parts reaching free leaves are visible: they are integrated with the sector form
// (Lambert), or with the paper's Eq. 3 in its stable form (a row's choice), and the leaf is replaced by the planes through p and their edges (their
// shadow volume). Splitting convex pieces by planes needs no polygon booleans, and
// the topology follows from one sign per vertex and plane.
//
// Before a BSP subtree is entered, the conic hull of its bounding box's corners is
// filtered down the shadow tree: a subtree whose box is wholly covered is skipped
// without touching its fragments (hierarchical occlusion culling), so that the cost
// of a row follows what it sees.
//
// Arithmetic is in long double (x87 80-bit where the platform has it). Every vertex
// carries a bound on the error of its direction (radians); every plane a bound on its
// tilt. A piece's value is bounded by the rounding of its sector sum plus, for each
// edge, its arc length times the larger of its end points' bounds over pi. The
// wrapper checks those bounds against the tolerance and falls back to the Python
// engine where they miss it.
//
// The row runs without the GIL: rows in threads run in parallel.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <cfloat>
#include <cstdint>
#include <limits>
#include <cstring>
#include <stdexcept>
#include <unordered_map>
#include <vector>
#if defined(__SIZEOF_FLOAT128__) && !defined(__aarch64__)
#include <quadmath.h>
using Quad = __float128;
inline Quad q_atan2(Quad y, Quad x) { return atan2q(y, x); }
inline Quad q_sqrt(Quad x) { return sqrtq(x); }
inline Quad q_sin(Quad x) { return sinq(x); }
inline Quad q_abs(Quad x) { return fabsq(x); }
const Quad QUAD_EPS = static_cast<Quad>(std::ldexp(1.0L, -113));  // unit roundoff
#else
// long double is already quadruple (aarch64) or the platform has no quad type: the
// second tier is long double again
using Quad = long double;
inline Quad q_atan2(Quad y, Quad x) { return std::atan2(y, x); }
inline Quad q_sqrt(Quad x) { return std::sqrt(x); }
inline Quad q_sin(Quad x) { return std::sin(x); }
inline Quad q_abs(Quad x) { return std::fabs(x); }
constexpr Quad QUAD_EPS = LDBL_EPSILON / 2;
#endif

namespace py = pybind11;

void register_bsp_build(py::module_& m);  // _bsp_build.cpp

namespace {

using R = long double;

// the classification's double filter: a distance computed in double from the long
// double vectors rounded to double is within this many double roundoffs (DBL_EPSILON
// / 2 each) of |m| |v| of its long double value (6 needed, 8 kept)
constexpr double FILTER_ROUNDOFFS = 4;  // in units of DBL_EPSILON = 2 roundoffs
// the unattributed charges of a row (uncovered parts of shadows, Core::leave_out) that go
// to every receiving polygon, as a share of the relative tolerance: a hundredth of the
// tolerance at VALUE_FLOOR (exactff._tolerances), so that they never decide whether a
// value meets it; larger ones are charged only to the visible pieces they may overlap
constexpr double LEAK_BUDGET_SHARE = 1e-4;
// roundoffs bounding the error of Eq. 3's midpoint factor v_x u_y + u_x v_y, times
// 2 sin(theta / 2) (exactff._tolerances.EQ3_FACTOR_ULPS)
constexpr int EQ3_FACTOR_ULPS = 64;
constexpr int OUT = -1;  // a free leaf of the shadow tree
constexpr int IN = -2;   // a covered leaf

struct V3 {
    R x, y, z;
};
inline R dot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline R norm(const V3& a) { return std::sqrt(dot(a, a)); }

// ---- exact signs of float input (Shewchuk's expansion arithmetic), for the cases the
// band leaves open: a vertex of the input and a plane through p and two input points
// (or with a normal of the input), whose float sign is not sure. Expansions live on the
// stack (the longest here, a 3 x 3 determinant of differences, has at most 192 terms).
struct Expansion {
    std::array<double, 200> c;
    int n = 0;
};

inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    double bv = x - a;
    y = (a - (x - bv)) + (b - bv);
}

// e + b, nonoverlapping increasing (Shewchuk's grow-expansion, zeros dropped)
inline void grow(Expansion& e, double b) {
    double q = b;
    int k = 0;
    for (int i = 0; i < e.n; ++i) {
        double x, y;
        two_sum(q, e.c[i], x, y);
        if (y != 0) e.c[k++] = y;
        q = x;
    }
    if (q != 0 || k == 0) e.c[k++] = q;
    e.n = k;
    // a nonoverlapping expansion of these determinants holds a few hundred bits: a
    // length near the capacity would mean a defect, never silently overrun
    if (k >= static_cast<int>(e.c.size()) - 1) throw std::overflow_error("expansion too long");
}

inline Expansion add(const Expansion& e, const Expansion& f) {
    Expansion h = e;
    for (int i = 0; i < f.n; ++i) grow(h, f.c[i]);
    return h;
}

inline Expansion scale(const Expansion& e, double b) {
    Expansion h;
    for (int i = 0; i < e.n; ++i) {
        double x = e.c[i] * b;
        double y = std::fma(e.c[i], b, -x);
        grow(h, y);
        grow(h, x);
    }
    return h;
}

inline Expansion mul(const Expansion& e, const Expansion& f) {
    Expansion h;
    for (int i = 0; i < f.n; ++i) h = add(h, scale(e, f.c[i]));
    return h;
}

inline Expansion neg(Expansion e) {
    for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
    return e;
}

inline int sign(const Expansion& e) {
    for (int i = e.n - 1; i >= 0; --i)
        if (e.c[i] != 0) return e.c[i] > 0 ? 1 : -1;
    return 0;
}

inline Expansion diff(double a, double b) {  // a - b exactly
    Expansion e;
    double x, y;
    two_sum(a, -b, x, y);
    if (y != 0) e.c[e.n++] = y;
    e.c[e.n++] = x;
    return e;
}

// h += sign * e * f, in place (every product two-product split, grown into h)
inline void mul_into(Expansion& h, const Expansion& e, const Expansion& f, double sign) {
    for (int j = 0; j < f.n; ++j) {
        const double fj = sign * f.c[j];
        for (int i = 0; i < e.n; ++i) {
            const double x = e.c[i] * fj;
            grow(h, std::fma(e.c[i], fj, -x));
            grow(h, x);
        }
    }
}

// det(a - p, b - a, x - p): the side of x of the plane through p, a, b
Expansion orient_exact(const double* p, const double* a, const double* b, const double* x) {
    Expansion A[3], B[3], C[3];
    for (int i = 0; i < 3; ++i) {
        A[i] = diff(a[i], p[i]);
        B[i] = diff(b[i], a[i]);
        C[i] = diff(x[i], p[i]);
    }
    Expansion m[3];
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        mul_into(m[i], B[j], C[k], 1.0);
        mul_into(m[i], B[k], C[j], -1.0);
    }
    Expansion r;
    for (int i = 0; i < 3; ++i) mul_into(r, A[i], m[i], 1.0);
    return r;
}

// n . (x - p)
Expansion dot_exact(const double* n, const double* p, const double* x) {
    Expansion s;
    for (int i = 0; i < 3; ++i) s = add(s, scale(diff(x[i], p[i]), n[i]));
    return s;
}

// the filter: whether the same determinant in long double is surely not 0 (beyond
// 32 roundoffs of its permanent, which bounds the subtractions' and products' rounding)
// the same determinant in long double, and a bound on its rounding error
void filtered(int kind, const double* p, const double* a, const double* b, const double* x,
              R* value_out, R* error_out);

bool surely_off(int kind, const double* p, const double* a, const double* b,
                const double* x) {
    R value, error;
    filtered(kind, p, a, b, x, &value, &error);
    return std::fabs(value) > error;
}

void filtered(int kind, const double* p, const double* a, const double* b, const double* x,
              R* value_out, R* error_out) {
    const R eps = std::numeric_limits<R>::epsilon();
    R value, permanent;
    if (kind == 0) {
        R A[3], B[3], C[3];
        for (int i = 0; i < 3; ++i) {
            A[i] = static_cast<R>(a[i]) - p[i];
            B[i] = static_cast<R>(b[i]) - a[i];
            C[i] = static_cast<R>(x[i]) - p[i];
        }
        R m[3] = {B[1] * C[2] - B[2] * C[1], B[2] * C[0] - B[0] * C[2],
                  B[0] * C[1] - B[1] * C[0]};
        R M[3] = {std::fabs(B[1] * C[2]) + std::fabs(B[2] * C[1]),
                  std::fabs(B[2] * C[0]) + std::fabs(B[0] * C[2]),
                  std::fabs(B[0] * C[1]) + std::fabs(B[1] * C[0])};
        value = A[0] * m[0] + A[1] * m[1] + A[2] * m[2];
        permanent = std::fabs(A[0]) * M[0] + std::fabs(A[1]) * M[1] + std::fabs(A[2]) * M[2];
    } else {
        value = 0;
        permanent = 0;
        for (int i = 0; i < 3; ++i) {
            R d = static_cast<R>(x[i]) - p[i];
            value += a[i] * d;
            permanent += std::fabs(a[i] * d);
        }
    }
    *value_out = value;
    *error_out = 32 * eps * permanent;
}

// two input points, bit for bit
inline bool same_point(const double* x, const double* y) {
    return std::memcmp(x, y, 3 * sizeof(double)) == 0;
}

// a plane through p as the input defines it: through two input points (kind 0, with
// (a - p) x (b - a) its orientation) or with normal n (kind 1, the horizon)
struct ExactPlane {
    int kind;
    double a[3], b[3];
    V3 m;       // its computed normal, in its own orientation
    R err;      // the bound on that normal's tilt, radians
    // the plane's identity for the row's cache of exact tests: kind 0, the distinct
    // input points a and b are (their ids, see Core::uid_); kind 1, -1 - its index
    int64_t ua = -1, ub = -1;
    // kind 0: the turn the input points' own errors give the plane (Core::input_tilt),
    // held apart from err (the computation's)
    R tilt = 0;
};

struct Vertex {
    V3 w;       // position in the world: input vertices only (a computed vertex's
                // differences come from its anchor or its direction, see between())
    V3 v;       // w - p: its direction from p (not normalised)
    R length;   // |v|
    R err;      // bound on the error of its direction, radians
    int64_t id; // index of an input vertex (its coordinates exact), or -1: computed
    int64_t on_edge, on_plane;  // a computed vertex where input edge on_edge (the
                                // input vertex it starts from) crosses exact plane
                                // on_plane, or -1
    int64_t edge;  // the edge to the next vertex: on input edge id (>= 0: the input
                   // vertex it starts from) or on exact plane -1 - k
    R t = 0;       // with on_edge: its parameter along that input edge
    R err_line = 0;  // with on_edge: bound on its direction's error off that edge's
                     // plane through p (its error along the edge moves no boundary)
    double vd[3] = {0, 0, 0};  // v, length and err rounded to double: the
    double lengthd = 0;        // classification's filter (see Core::process)
    double errd = 0;
    R gerr = 0;  // bound on the angle off the planes of its two edges that the input's
                 // own errors add (a BSP crossing is rounded): the geometry's, not the
                 // computation's, so it moves values (Core::charge_edges), not decisions
};

inline void set_double(Vertex& u) {
    u.vd[0] = static_cast<double>(u.v.x);
    u.vd[1] = static_cast<double>(u.v.y);
    u.vd[2] = static_cast<double>(u.v.z);
    u.lengthd = static_cast<double>(u.length);
    u.errd = static_cast<double>(u.err);
}
using Piece = std::vector<Vertex>;

struct Plane {  // m . x = 0 through p; positive side first
    V3 m;
    R mnorm;
    R err;      // bound on its tilt, radians
    int pos, neg;
    int exact;  // the exact plane it is (ExactPlane index)
    int orient; // +1 or -1: m's orientation against the exact plane's
    R slack = 0;  // the widest sliver decided against it so far: the covered region
                  // next to it is uncertain by that much for every later piece
    double md[3] = {0, 0, 0};  // m and mnorm rounded to double, for the filter
    double mnormd = 0;
};

inline void set_double(Plane& P) {
    P.md[0] = static_cast<double>(P.m.x);
    P.md[1] = static_cast<double>(P.m.y);
    P.md[2] = static_cast<double>(P.m.z);
    P.mnormd = static_cast<double>(P.mnorm);
}

struct Constants {
    R eps;      // unit roundoff of R
    R band;     // relative band of "on the plane" (radians)
    R c1;       // rounding constants of a sector sum (the Python kernel's C1, C2)
    R c2;
    R split;    // rounding of a split vertex, in units of eps
};

struct EdgeKey {
    R c[6];
    bool operator==(const EdgeKey& o) const {
        for (int i = 0; i < 6; ++i)
            if (c[i] != o.c[i]) return false;
        return true;
    }
};
struct EdgeKeyHash {
    size_t operator()(const EdgeKey& k) const {
        size_t h = 1469598103934665603ull;
        for (int i = 0; i < 6; ++i) {
            double d = static_cast<double>(k.c[i]);
            uint64_t bits;
            std::memcpy(&bits, &d, sizeof bits);
            h = (h ^ bits) * 1099511628211ull;
        }
        return h;
    }
};
struct EdgeCharge {
    int64_t src;
    R charge;
    int count;
    bool refined;  // its ends' directions from Core::refine (quadruple precision)
    R geo = 0;     // the part the input's own errors make (Vertex::gerr), held apart
};

// the row's cache of exact tests of an input point against an exact plane, by ids:
// open addressing (linear probing, power-of-two capacity, at most half full), one probe
// run and no allocation per test in the usual case
class PointCache {
  public:
    // -1: not decided yet; else whether the point is on the plane
    int find(int64_t a, int64_t b, int64_t x) const {
        if (keys_.empty()) return -1;
        for (size_t i = slot(a, b, x);; i = (i + 1) & (keys_.size() - 1)) {
            const Key& k = keys_[i];
            if (k.x == EMPTY) return -1;
            if (k.a == a && k.b == b && k.x == x) return k.on;
        }
    }
    size_t bytes() const { return keys_.capacity() * sizeof(Key); }
    void insert(int64_t a, int64_t b, int64_t x, bool on) {
        if (2 * (used_ + 1) > keys_.size()) grow();
        size_t i = slot(a, b, x);
        while (keys_[i].x != EMPTY) i = (i + 1) & (keys_.size() - 1);
        keys_[i] = {a, b, x, on ? 1 : 0};
        ++used_;
    }

  private:
    static constexpr int64_t EMPTY = INT64_MIN;
    struct Key {
        int64_t a, b, x;
        int on;
    };
    size_t slot(int64_t a, int64_t b, int64_t x) const {
        uint64_t h = static_cast<uint64_t>(a) * 0x9E3779B97F4A7C15ull;
        h ^= static_cast<uint64_t>(b) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
        h ^= static_cast<uint64_t>(x) * 0xC2B2AE3D27D4EB4Full;
        h ^= h >> 29;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 32;
        return static_cast<size_t>(h) & (keys_.size() - 1);
    }
    void grow() {
        std::vector<Key> old = std::move(keys_);
        keys_.assign(old.empty() ? 1 << 12 : 2 * old.size(), Key{0, 0, EMPTY, 0});
        used_ = 0;
        for (const Key& k : old)
            if (k.x != EMPTY) insert(k.a, k.b, k.x, k.on != 0);
    }
    std::vector<Key> keys_;
    size_t used_ = 0;
};

// a part of the hemisphere a shadow leaves uncovered: within `radius` of direction c,
// worth at most `charge` of any piece behind it
struct Leak {
    V3 c;
    R radius, charge;
};

struct RowStats {
    // exact tests of input points against planes through p already decided this row
    // (the same mesh vertex and edge recur in every fragment that shares them)
    PointCache on_plane;
    // the vertex-error charges of visible pieces' edges with a computed end, by edge:
    // an edge two visible pieces of one polygon share cancels (the two pieces' sums
    // carry it with opposite signs); the rest is charged at the end of the row
    std::unordered_map<EdgeKey, EdgeCharge, EdgeKeyHash> edges;
    // what the shadows leave uncovered (Core::leave_out) and their omitted sides may
    // hide, charged to every receiving polygon
    R unattributed = 0;
    // shadows left out: < 3 vertices, a side the piece straddles, a kernel worth more
    // than the piece, < 3 sides
    int64_t slivers[4] = {0, 0, 0, 0};
    int64_t kernels = 0;        // non-convex images whose kernel is their shadow
    int64_t omitted_sides = 0;  // shadows with a short side left out
    // uncovered parts worth more than the row's budget for unattributed charges
    // (Core::leave_out), and that budget
    std::vector<Leak> leaks;
    R leak_budget = 0;
    R rtol = 0;          // pieces whose bound exceeds this times their value are
                         // integrated again in quadruple precision (0: never)
    const double* normal = nullptr;  // the receiver normal as given
    // integrate with Eq. 3's stable form instead of the sector form, in the frame
    // (e1, e2, n) (Core::integrate)
    bool eq3 = false;
    V3 e1{0, 0, 0}, e2{0, 0, 0};
    int64_t quad_pieces = 0;
    int64_t fragments = 0, visible = 0, hidden = 0, splits = 0, subtrees_culled = 0,
            fragments_culled = 0, box_tests = 0, shadow_planes = 0,
            node_visits = 0,   // shadow-tree nodes a piece was classified at
            near_tests = 0,    // vertices within the band of such a plane
            exact_tests = 0;   // exact tests of an input point decided (not cached)
    int64_t held = 0, held_peak = 0;  // vertices in the filter's work list, now and at most
    int64_t working_bytes = 0;  // the row's own containers at their largest (Core::run)
    // per polygon, the charges of its visible pieces' edges that the input's own errors
    // make (BSP crossings, Vertex::gerr): reported apart from the computation's bound
    std::vector<R> crossing;
};

class Core {
  public:
    Core(py::array_t<double, py::array::c_style | py::array::forcecast> vertices,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> start,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> count,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> source,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> front,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> back,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> here_start,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> here_front,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> here_behind,
         int64_t n_sources, double band, double c1, double c2, double split,
         py::array_t<double, py::array::c_style | py::array::forcecast> vertex_errors)
        : n_sources_(n_sources) {
        copy(vertices, V_);
        copy(vertex_errors, VE_);
        copy(start, start_);
        copy(count, count_);
        copy(source, source_);
        copy(front, front_);
        copy(back, back_);
        copy(here_start, here_start_);
        copy(here_front, here_front_);
        copy(here_behind, here_behind_);
        const int64_t M = static_cast<int64_t>(front_.size());
        if (static_cast<int64_t>(back_.size()) != M ||
            static_cast<int64_t>(here_start_.size()) != M + 1)
            throw std::invalid_argument("inconsistent BSP arrays");
        if (V_.size() % 3 != 0 || start_.size() != count_.size() ||
            source_.size() != count_.size() || VE_.size() != V_.size() / 3)
            throw std::invalid_argument("inconsistent fragment arrays");
        K_.eps = std::numeric_limits<R>::epsilon() / 2;
        K_.band = band;
        K_.c1 = c1;
        K_.c2 = c2;
        K_.split = split;
        build_boxes();
        // one id per distinct input point, bit for bit (a mesh vertex recurs in every
        // polygon and fragment that has it): the row's exact tests are cached by ids
        const int64_t nv = static_cast<int64_t>(V_.size() / 3);
        std::vector<int64_t> order(nv);
        for (int64_t i = 0; i < nv; ++i) order[i] = i;
        auto bits = [&](int64_t i, int k) {
            uint64_t b;
            std::memcpy(&b, &V_[3 * i + k], sizeof b);
            return b;
        };
        std::sort(order.begin(), order.end(), [&](int64_t i, int64_t j) {
            for (int k = 0; k < 3; ++k)
                if (bits(i, k) != bits(j, k)) return bits(i, k) < bits(j, k);
            return false;
        });
        uid_.assign(nv, 0);
        int64_t next = -1;
        for (int64_t r = 0; r < nv; ++r) {
            const int64_t i = order[r];
            if (r == 0 || std::memcmp(&V_[3 * i], &V_[3 * order[r - 1]], 3 * sizeof(double)) != 0)
                ++next;
            uid_[i] = next;
        }
    }

    int64_t nodes() const { return static_cast<int64_t>(front_.size()); }
    int64_t pieces() const { return static_cast<int64_t>(start_.size()); }
    double unit_roundoff() const { return static_cast<double>(K_.eps); }

    py::tuple row(py::array_t<double, py::array::c_style | py::array::forcecast> point,
                  py::array_t<double, py::array::c_style | py::array::forcecast> normal,
                  py::array_t<int8_t, py::array::c_style | py::array::forcecast> node_side,
                  py::array_t<int8_t, py::array::c_style | py::array::forcecast> source_side,
                  bool two_sided, bool cull, int64_t box_budget, int64_t tiles,
                  double rtol, bool eq3) const {
        if (point.size() != 3 || normal.size() != 3)
            throw std::invalid_argument("point and normal must have 3 coordinates");
        if (node_side.size() != nodes())
            throw std::invalid_argument("node_side must have one entry per BSP node");
        if (source_side.size() != n_sources_)
            throw std::invalid_argument("source_side must have one entry per polygon");
        py::array_t<double> F(n_sources_), E(n_sources_), B(n_sources_), G(n_sources_);
        const double* pp = point.data();
        const double* pn = normal.data();
        const int8_t* ns = node_side.data();
        const int8_t* ss = source_side.data();
        double* pF = F.mutable_data();
        double* pE = E.mutable_data();
        double* pB = B.mutable_data();
        double* pG = G.mutable_data();
        RowStats st;
        st.crossing.assign(static_cast<size_t>(n_sources_), 0);
        st.rtol = rtol;
        st.leak_budget = LEAK_BUDGET_SHARE * (rtol > 0 ? rtol : 1e-12);
        st.normal = pn;
        st.eq3 = eq3;
        if (eq3) {
            // Eq. 3's frame: e1 = n x (the axis n is least along), e2 = n x e1
            const R nl = std::sqrt(static_cast<R>(pn[0]) * pn[0] + static_cast<R>(pn[1]) * pn[1] +
                                   static_cast<R>(pn[2]) * pn[2]);
            const V3 un{pn[0] / nl, pn[1] / nl, pn[2] / nl};
            const int k = std::fabs(pn[0]) <= std::fabs(pn[1])
                              ? (std::fabs(pn[0]) <= std::fabs(pn[2]) ? 0 : 2)
                              : (std::fabs(pn[1]) <= std::fabs(pn[2]) ? 1 : 2);
            const V3 ax{k == 0 ? 1.0L : 0.0L, k == 1 ? 1.0L : 0.0L, k == 2 ? 1.0L : 0.0L};
            const V3 c = cross(un, ax);
            const R cl = norm(c);
            st.e1 = {c.x / cl, c.y / cl, c.z / cl};
            st.e2 = cross(un, st.e1);
        }
        {
            py::gil_scoped_release release;
            std::vector<R> f(n_sources_, 0), e(n_sources_, 0), b(n_sources_, 0);
            run(pp, pn, ns, ss, two_sided, cull, box_budget, tiles, f, e, b, st);
            const R half_ulp = std::numeric_limits<double>::epsilon() / 2;
            for (int64_t i = 0; i < n_sources_; ++i) {
                pF[i] = static_cast<double>(f[i]);
                // the bound, and the rounding of the value to double
                pE[i] = static_cast<double>(e[i] + half_ulp * std::fabs(f[i])) *
                        (1 + 4 * std::numeric_limits<double>::epsilon());
                pB[i] = static_cast<double>(b[i]) * (1 + 4 * std::numeric_limits<double>::epsilon());
                pG[i] = static_cast<double>(st.crossing[static_cast<size_t>(i)]) *
                        (1 + 4 * std::numeric_limits<double>::epsilon());
            }
        }
        py::dict d;
        d["fragments"] = st.fragments;
        d["visible_pieces"] = st.visible;
        d["hidden_pieces"] = st.hidden;
        d["splits"] = st.splits;
        d["subtrees_culled"] = st.subtrees_culled;
        d["fragments_culled"] = st.fragments_culled;
        d["box_tests"] = st.box_tests;
        d["shadow_planes"] = st.shadow_planes;
        d["node_visits"] = st.node_visits;
        d["near_tests"] = st.near_tests;
        d["exact_tests"] = st.exact_tests;
        d["quad_pieces"] = st.quad_pieces;
        d["unattributed_bound"] = static_cast<double>(st.unattributed);
        d["shadows_left_out"] = st.slivers[0] + st.slivers[1] + st.slivers[2] + st.slivers[3];
        d["kernel_shadows"] = st.kernels;
        d["omitted_sides"] = st.omitted_sides;
        d["leaks"] = static_cast<int64_t>(st.leaks.size());
        d["working_bytes"] = st.working_bytes;
        return py::make_tuple(F, E, B, G, d);
    }

  private:
    template <class T, class A>
    static void copy(const A& a, std::vector<T>& out) {
        out.assign(a.data(), a.data() + a.size());
    }

    // bounding boxes of every subtree (post-order) and the number of pieces in it
    void build_boxes() {
        const int64_t M = nodes();
        lo_.assign(3 * M, std::numeric_limits<double>::infinity());
        hi_.assign(3 * M, -std::numeric_limits<double>::infinity());
        size_.assign(M, 0);
        if (M == 0) return;
        std::vector<int64_t> order;
        order.reserve(M);
        std::vector<int64_t> stack{0};
        while (!stack.empty()) {
            int64_t k = stack.back();
            stack.pop_back();
            order.push_back(k);
            if (front_[k] >= 0) stack.push_back(front_[k]);
            if (back_[k] >= 0) stack.push_back(back_[k]);
        }
        for (auto it = order.rbegin(); it != order.rend(); ++it) {
            int64_t k = *it;
            for (int64_t j = here_start_[k]; j < here_start_[k + 1]; ++j) {
                int64_t f = here_front_[j];
                for (int64_t i = start_[f]; i < start_[f] + count_[f]; ++i)
                    for (int a = 0; a < 3; ++a) {
                        lo_[3 * k + a] = std::min(lo_[3 * k + a], V_[3 * i + a]);
                        hi_[3 * k + a] = std::max(hi_[3 * k + a], V_[3 * i + a]);
                    }
                size_[k] += 1;
            }
            for (int64_t c : {front_[k], back_[k]}) {
                if (c < 0) continue;
                for (int a = 0; a < 3; ++a) {
                    lo_[3 * k + a] = std::min(lo_[3 * k + a], lo_[3 * c + a]);
                    hi_[3 * k + a] = std::max(hi_[3 * k + a], hi_[3 * c + a]);
                }
                size_[k] += size_[c];
            }
        }
    }

    // side of a direction against a plane, conservatively: +1, -1, or 0 where the
    // sign is not sure (within the rounding of d and the plane's and vertex's errors)
    static int side(const Plane& P, const Vertex& x, const Constants& K, R* d_out) {
        R d = dot(P.m, x.v);
        *d_out = d;
        R band = (K.band + P.err + x.err) * P.mnorm * x.length;
        if (d > band) return 1;
        if (d < -band) return -1;
        return 0;
    }

    // the upper hemisphere cut into (tiles + 1)^2 cells by planes through p with double
    // normals cos t u - sin t n and cos t v - sin t n (t evenly spaced in angle; u, v, n
    // a frame), as balanced trees: each cell's shadows grow on their own, so a piece
    // is filtered down the shadows of its own part of the sky only
    int tile_tree(const double* pn, int64_t tiles, std::vector<Plane>& sv,
                  std::vector<ExactPlane>& xp) const {
        double n[3] = {pn[0], pn[1], pn[2]};
        const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (double& c : n) c /= nl;
        int a = 0;
        for (int i = 1; i < 3; ++i)
            if (std::fabs(n[i]) < std::fabs(n[a])) a = i;
        double e[3] = {0, 0, 0};
        e[a] = 1;
        double u[3] = {e[1] * n[2] - e[2] * n[1], e[2] * n[0] - e[0] * n[2],
                       e[0] * n[1] - e[1] * n[0]};
        const double ul = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (double& c : u) c /= ul;
        double v[3] = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2],
                       n[0] * u[1] - n[1] * u[0]};
        const double pi = 3.14159265358979323846;
        auto planes = [&](const double* w) {
            std::vector<std::array<double, 3>> out;
            for (int64_t k = 0; k < tiles; ++k) {
                double t = -pi / 2 + pi * static_cast<double>(k + 1) / (tiles + 1);
                out.push_back({std::cos(t) * w[0] - std::sin(t) * n[0],
                               std::cos(t) * w[1] - std::sin(t) * n[1],
                               std::cos(t) * w[2] - std::sin(t) * n[2]});
            }
            return out;
        };
        const auto xs = planes(u), ys = planes(v);
        using Normals = std::vector<std::array<double, 3>>;
        std::function<int(const Normals&, int64_t, int64_t, const std::function<int()>&)>
            build = [&](const Normals& ms, int64_t lo, int64_t hi,
                        const std::function<int()>& inner) -> int {
            if (lo >= hi) return inner();
            const int64_t mid = (lo + hi) / 2;
            const auto& m = ms[mid];
            V3 mm{m[0], m[1], m[2]};
            const int node = static_cast<int>(sv.size());
            const int exact = static_cast<int>(xp.size());
            xp.push_back({1, {m[0], m[1], m[2]}, {0, 0, 0}, mm, 2 * K_.eps,
                          -1 - exact, -1 - exact});
            sv.push_back({mm, norm(mm), 2 * K_.eps, OUT, OUT, exact, 1});
            set_double(sv.back());
            const int neg = build(ms, lo, mid, inner);
            const int pos = build(ms, mid + 1, hi, inner);
            sv[node].neg = neg;
            sv[node].pos = pos;
            return node;
        };
        std::function<int()> out_leaf = []() { return OUT; };
        std::function<int()> cells = [&]() { return build(ys, 0, tiles, out_leaf); };
        return build(xs, 0, tiles, cells);
    }

    // an exact plane's value at a point of the input
    static Expansion exact_value(const ExactPlane& X, const double* p, const double* x) {
        return X.kind == 0 ? orient_exact(p, X.a, X.b, x) : dot_exact(X.a, p, x);
    }

    // whether input point x lies exactly on exact plane Q, decided once a row (the same
    // mesh vertex and edge recur in every fragment that shares them)
    bool point_on_plane(const ExactPlane& Q, const double* p, const double* x, int64_t ux,
                        RowStats& st) const {
        const int64_t a = std::min(Q.ua, Q.ub), b = std::max(Q.ua, Q.ub);
        const int known = st.on_plane.find(a, b, ux);
        if (known >= 0) return known != 0;
        ++st.exact_tests;
        const bool on = exactly_on_input(Q, p, x);
        st.on_plane.insert(a, b, ux, on);
        return on;
    }

    // whether a vertex lies exactly on an exact plane: an input vertex, or the crossing
    // of an input edge a -> b with an exact plane P, x = a + t (b - a) with
    // t = P(a) / (P(a) - P(b)): Q(x) = (Q(a) P(b) - P(a) Q(b)) / (P(b) - P(a)).
    // False where it cannot be told (the vertex is then charged its sliver).
    bool exactly_on(std::vector<ExactPlane>& xp, int k, const double* p, int64_t f,
                    const Vertex& u, RowStats& st) const {
        ExactPlane& Q = xp[k];
        if (u.id >= 0) return point_on_plane(Q, p, &V_[3 * u.id], uid_[u.id], st);
        if (u.on_edge < 0) return false;
        if (u.on_plane == k) return true;
        {   // the plane it was cut by, instantiated again (the same input edge's plane
            // from another piece's shadow, or the same normal): on it
            const ExactPlane& P0 = xp[u.on_plane];
            if (P0.kind == Q.kind &&
                ((same_point(P0.a, Q.a) && (Q.kind == 1 || same_point(P0.b, Q.b))) ||
                 (Q.kind == 0 && same_point(P0.a, Q.b) && same_point(P0.b, Q.a))))
                return true;
        }
        const int64_t ia = u.on_edge;
        const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
        const ExactPlane& P = xp[u.on_plane];
        {   // the edge is one that defines Q (a shared edge): its whole line lies on Q
            const double* A = &V_[3 * ia];
            const double* Bv = &V_[3 * ib];
            if (Q.kind == 0 && ((same_point(A, Q.a) && same_point(Bv, Q.b)) ||
                                (same_point(A, Q.b) && same_point(Bv, Q.a))))
                return true;
        }
        // P and Q through p and a common input point v (two silhouette edges that meet
        // at v): two distinct such planes meet in the line through p and v, so the
        // crossing of the edge with P lies on Q exactly where that line meets the
        // edge's line, i.e. where v lies on the plane through p and the edge (one
        // orientation test of degree 3, against Q(a) P(b) - P(a) Q(b) of degree 6).
        // Where P and Q are one plane this says false, which only charges a sliver.
        if (P.kind == 0 && Q.kind == 0) {
            const double* v = nullptr;
            int64_t uv = -1;
            if (P.ua == Q.ua || P.ua == Q.ub) {
                v = P.a;
                uv = P.ua;
            } else if (P.ub == Q.ua || P.ub == Q.ub) {
                v = P.b;
                uv = P.ub;
            }
            if (v != nullptr && !same_point(v, p)) {
                ExactPlane R{0, {}, {}, V3{0, 0, 0}, 0, uid_[ia], uid_[ib]};
                std::memcpy(R.a, &V_[3 * ia], sizeof R.a);
                std::memcpy(R.b, &V_[3 * ib], sizeof R.b);
                return point_on_plane(R, p, v, uv, st);
            }
        }
        // P and Q one plane, given by other points (the bottom edges of walls standing
        // on the receiver's plane, collinear edges of separate polygons): every point
        // of P lies on Q. Told by the points that define one lying on the other
        // (degree 3 each, and the same pair of planes recurs all row long)
        if ((Q.kind == 0 && point_on_plane(P, p, Q.a, Q.ua, st) &&
             point_on_plane(P, p, Q.b, Q.ub, st)) ||
            (P.kind == 0 && point_on_plane(Q, p, P.a, P.ua, st) &&
             point_on_plane(Q, p, P.b, P.ub, st))) {
            return true;
        }
        {   // the filter: Q(a) P(b) - P(a) Q(b) in long double, with its error bound
            R qa, eqa, qb, eqb, pa, epa, pb, epb;
            filtered(Q.kind, p, Q.a, Q.b, &V_[3 * ia], &qa, &eqa);
            filtered(Q.kind, p, Q.a, Q.b, &V_[3 * ib], &qb, &eqb);
            filtered(P.kind, p, P.a, P.b, &V_[3 * ia], &pa, &epa);
            filtered(P.kind, p, P.a, P.b, &V_[3 * ib], &pb, &epb);
            const R c = qa * pb - pa * qb;
            const R err = (std::fabs(qa) + eqa) * epb + eqa * std::fabs(pb) +
                          (std::fabs(pa) + epa) * eqb + epa * std::fabs(qb) +
                          4 * std::numeric_limits<R>::epsilon() *
                              (std::fabs(qa * pb) + std::fabs(pa * qb));
            if (std::fabs(c) > err) return false;
        }
        Expansion Pa = exact_value(P, p, &V_[3 * ia]), Pb = exact_value(P, p, &V_[3 * ib]);
        Expansion Qa = exact_value(Q, p, &V_[3 * ia]), Qb = exact_value(Q, p, &V_[3 * ib]);
        Expansion r;
        mul_into(r, Qa, Pb, 1.0);
        mul_into(r, Pa, Qb, -1.0);
        return sign(r) == 0;
    }

    // an input point against an exact plane
    bool exactly_on_input(const ExactPlane& Q, const double* p, const double* x) const {
        // one of the two points that define the plane (a shared edge's end): on it
        if (Q.kind == 0 && ((x[0] == Q.a[0] && x[1] == Q.a[1] && x[2] == Q.a[2]) ||
                            (x[0] == Q.b[0] && x[1] == Q.b[1] && x[2] == Q.b[2])))
            return true;
        if (surely_off(Q.kind, p, Q.a, Q.b, x)) return false;
        return sign(exact_value(Q, p, x)) == 0;
    }

    // b - a: from the world coordinates where both are input vertices (exact doubles:
    // their difference loses nothing to the distance from p), else from the
    // directions (a computed vertex's world position would be rounded at the scale of
    // its coordinates, far coarser than its direction from p far from the origin; the
    // directions' rounding is in the vertices' own error bounds)
    //
    // A vertex on an input edge is anchored there (its start plus its parameter times
    // the edge), so differences of anchored vertices come from the input's own
    // differences too. ``scale`` receives the magnitude the difference's rounding is
    // relative to.
    V3 between(const Vertex& a, const Vertex& b, int64_t f, R* scale) const {
        if (a.id >= 0 && b.id >= 0) {
            V3 e{b.w.x - a.w.x, b.w.y - a.w.y, b.w.z - a.w.z};
            *scale = norm(e);
            return e;
        }
        const bool anchored_a = a.id >= 0 || a.on_edge >= 0;
        const bool anchored_b = b.id >= 0 || b.on_edge >= 0;
        if (anchored_a && anchored_b) {
            auto anchor = [&](const Vertex& u, V3* base, V3* edge, R* t) {
                const int64_t i0 = u.id >= 0 ? u.id : u.on_edge;
                *base = {V_[3 * i0], V_[3 * i0 + 1], V_[3 * i0 + 2]};
                *edge = {0, 0, 0};
                *t = 0;
                if (u.id < 0) {
                    const int64_t i1 = start_[f] + (i0 - start_[f] + 1) % count_[f];
                    *edge = {V_[3 * i1] - base->x, V_[3 * i1 + 1] - base->y,
                             V_[3 * i1 + 2] - base->z};
                    *t = u.t;
                }
            };
            V3 ba, ea, bb, eb;
            R ta, tb;
            anchor(a, &ba, &ea, &ta);
            anchor(b, &bb, &eb, &tb);
            V3 d0{bb.x - ba.x, bb.y - ba.y, bb.z - ba.z};
            V3 e{d0.x + tb * eb.x - ta * ea.x, d0.y + tb * eb.y - ta * ea.y,
                 d0.z + tb * eb.z - ta * ea.z};
            *scale = norm(d0) + std::fabs(tb) * norm(eb) + std::fabs(ta) * norm(ea);
            return e;
        }
        *scale = a.length + b.length;
        return {b.v.x - a.v.x, b.v.y - a.v.y, b.v.z - a.v.z};
    }

    static bool lex_less(const V3& x, const V3& y) {
        if (x.x != y.x) return x.x < y.x;
        if (x.y != y.y) return x.y < y.y;
        return x.z < y.z;
    }

    // arc length between two directions
    static R arc(const Vertex& a, const Vertex& b) {
        return std::atan2(norm(cross(a.v, b.v)), dot(a.v, b.v));
    }

    // is subtree k's box wholly in the closed half-space behind the point's tangent
    // plane, n . (x - p) <= 0 at every corner (exactly)? Then nothing in it is in front,
    // and it hides nothing in front: a part in the tangent plane has no image of area
    // (the box test below cannot say so for a box that touches the plane, as every
    // subtree under a floor point's own floor does)
    bool box_behind(int64_t k, const double* pp, const double* pn) const {
        for (int i = 0; i < 8; ++i) {
            const double c[3] = {i & 1 ? hi_[3 * k] : lo_[3 * k],
                                 i & 2 ? hi_[3 * k + 1] : lo_[3 * k + 1],
                                 i & 4 ? hi_[3 * k + 2] : lo_[3 * k + 2]};
            R d = 0, mag = 0;
            for (int a = 0; a < 3; ++a) {
                const R t = (static_cast<R>(c[a]) - pp[a]) * pn[a];
                d += t;
                mag += std::fabs(t);
            }
            // the filter (the differences and products within 2 roundoffs each, the
            // sum within 3 of the magnitudes), then the exact sign
            if (d < -8 * K_.eps * mag) continue;
            if (d > 8 * K_.eps * mag) return false;
            if (sign(dot_exact(pn, pp, c)) > 0) return false;
        }
        return true;
    }

    // is the conic hull (from p) of the box's corners wholly in covered leaves?
    bool box_hidden(const std::vector<Plane>& sv, int64_t k, const V3& p,
                    int64_t budget) const {
        Vertex c[8];
        for (int i = 0; i < 8; ++i) {
            V3 v{(i & 1 ? hi_[3 * k] : lo_[3 * k]) - p.x,
                 (i & 2 ? hi_[3 * k + 1] : lo_[3 * k + 1]) - p.y,
                 (i & 4 ? hi_[3 * k + 2] : lo_[3 * k + 2]) - p.z};
            c[i] = {v, v, norm(v), 4 * K_.eps, -1, -1, -1, -1};
        }
        // p must be outside the box (with a margin): the hull is then a pointed cone
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
            R pa = a == 0 ? p.x : (a == 1 ? p.y : p.z);
            R margin = 1e-9L * (std::fabs(lo_[3 * k + a]) + std::fabs(hi_[3 * k + a]) +
                                std::fabs(pa)) + 1e-300L;
            if (pa < lo_[3 * k + a] - margin || pa > hi_[3 * k + a] + margin) inside = false;
        }
        if (inside) return false;
        std::vector<int> stack{0};
        int64_t visits = 0;
        while (!stack.empty()) {
            int node = stack.back();
            stack.pop_back();
            if (node == IN) continue;
            if (node == OUT || ++visits > budget) return false;
            const Plane& P = sv[node];
            bool pos = false, neg = false;
            for (int i = 0; i < 8; ++i) {
                R d;
                int s = side(P, c[i], K_, &d);
                if (s >= 0) pos = true;
                if (s <= 0) neg = true;
            }
            if (pos) stack.push_back(P.pos);
            if (neg) stack.push_back(P.neg);
        }
        return true;
    }

    // the angle a direction turns when its point, at distance r from p, moves by at most
    // `ratio` r: asin(ratio) <= 1.01 ratio for ratio <= 0.1, else any angle (pi)
    static R turn_bound(R ratio) {
        return ratio <= static_cast<R>(0.1) ? static_cast<R>(1.01) * ratio
                                            : static_cast<R>(3.14159265358979323846L);
    }

    // a bound on the angle at p between input point i's direction and that of the exact
    // point it stands for (a BSP split's crossing is rounded: VE_[i] bounds its
    // distance), with `length` its distance from p
    R input_error(int64_t i, R length) const {
        const R e = VE_[static_cast<size_t>(i)];
        return e == 0 ? 0 : turn_bound(e / length);
    }

    // a bound on the angle by which the plane through p and input points a, b turns off
    // the one through the exact points they stand for, over the wedge between them (the
    // part of the plane where it bounds a shadow): a point of the edge moves by at most
    // the larger end error (in the world), and it is at least h = |(a - p) x (b - p)| /
    // |b - a| from p, so its direction turns by at most that over h (0 for input points
    // that are exact; any angle, pi, where the first order does not hold)
    R input_tilt(int64_t ia, int64_t ib, const double* pp) const {
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

    // the sector form of one convex piece above the horizon, in offset form (as
    // exactff.kernel.clipped_sector_sums): each edge's plane as
    // m = a0 x (e_b - e_a) + e_a x e_b with a0 the first vertex's direction and e the
    // world offsets from it, accurate for pieces small next to their distance; each
    // term's rounding bounded by the magnitudes of the products in n . m (C2 ulps per
    // unit of the cross product's condition), the sum's by C1 ulps of its terms
    //
    // With `eq3` (its frame e1, e2 with e1 x e2 = n), each edge is integrated by the
    // paper's Eq. 3 (corrected) over its monotone spans, in its stable form
    // (tools/derive_eq3.py, exactff.kernel.eq3_ring_sums): minus twice int y dx along
    // the arc's image is C theta - sin(theta) (v_x u_y + u_x v_y), the sector term and
    // d(x y)/dt at the arc's midpoint u (v = m x u / |m|) times sin(theta), every term
    // O(theta); the second term's rounding is the plane's (as the first's) and a few
    // roundoffs of the unit midpoint and tangent, times 2 sin(theta / 2)
    void integrate(const Piece& q, int64_t f, const V3& n, R* value, R* bound,
                   const RowStats* eq3 = nullptr) const {
        R S = 0, mag = 0, errs = 0;
        const size_t m = q.size();
        const V3 a0 = q[0].v;
        R unused;
        auto offset = [&](const Vertex& u) { return between(q[0], u, f, &unused); };
        for (size_t i = 0; i < m; ++i) {
            const Vertex& a = q[i];
            const Vertex& b = q[(i + 1) % m];
            const V3 ea = offset(a), eb = offset(b);
            const V3 d{eb.x - ea.x, eb.y - ea.y, eb.z - ea.z};
            const V3 c1 = cross(a0, d), c2 = cross(ea, eb);
            const V3 c{c1.x + c2.x, c1.y + c2.y, c1.z + c2.z};
            // the magnitudes of the products that make up n . m
            const R Z = std::fabs(n.x) * (std::fabs(a0.y * d.z) + std::fabs(a0.z * d.y) +
                                          std::fabs(ea.y * eb.z) + std::fabs(ea.z * eb.y)) +
                        std::fabs(n.y) * (std::fabs(a0.z * d.x) + std::fabs(a0.x * d.z) +
                                          std::fabs(ea.z * eb.x) + std::fabs(ea.x * eb.z)) +
                        std::fabs(n.z) * (std::fabs(a0.x * d.y) + std::fabs(a0.y * d.x) +
                                          std::fabs(ea.x * eb.y) + std::fabs(ea.y * eb.x));
            const R cl = norm(c);
            const R Nm = a.length * b.length;
            const R theta = std::atan2(cl, dot(a.v, b.v));
            if (!(cl > 0)) {
                if (Nm > 0) errs += 2 * K_.eps;  // a degenerate edge: its term unknown
                continue;
            }
            const R t = theta * dot(n, c) / cl;
            S += t;
            mag += std::fabs(t);
            const R rel = K_.c2 * K_.eps * (Z + theta * theta * Nm) / cl;
            errs += theta * std::min(static_cast<R>(2), rel);
            if (eq3) {
                const R sin_t = cl / Nm;
                const V3 um{a.v.x / a.length + b.v.x / b.length, a.v.y / a.length + b.v.y / b.length,
                            a.v.z / a.length + b.v.z / b.length};
                const R lu = norm(um);
                if (lu > 0) {
                    const V3 u{um.x / lu, um.y / lu, um.z / lu};
                    const V3 v = cross(c, u);
                    const R xy = sin_t * (dot(v, eq3->e1) * dot(u, eq3->e2) +
                                          dot(u, eq3->e1) * dot(v, eq3->e2)) / cl;
                    S -= xy;
                    mag += std::fabs(xy);
                } else {
                    errs += sin_t;  // opposite ends: no midpoint, the factor is within 1
                }
                errs += theta * std::min(static_cast<R>(2), rel) +
                        EQ3_FACTOR_ULPS * K_.eps * 2 * std::sin(theta / 2);
            }
        }
        const R two_pi = 6.283185307179586476925286766559L;
        *value = std::fabs(S) / two_pi;
        *bound = (K_.c1 * K_.eps * mag + errs) / two_pi;
    }

    // each edge's share of the error of its ends' directions: its arc length times the
    // larger of their bounds, over pi (the area swept by moving the edge that far); with
    // `refined`, the bounds of the directions Core::refine gave the piece instead
    // (the computation's part: the one returned and added to E; the input's own errors'
    // part, arc length times the larger of the ends' gerr over pi, goes to st.crossing)
    R charge_edges(const Piece& q, int64_t src, std::vector<R>& E, RowStats& st,
                   const std::vector<R>* refined = nullptr, bool record = true) const {
        const R pi = 3.14159265358979323846264338327950288L;
        const size_t m = q.size();
        R total = 0;
        for (size_t i = 0; i < m; ++i) {
            const Vertex& a = q[i];
            const Vertex& b = q[(i + 1) % m];
            // off the plane the edge lies on: for an input edge, its ends' distances
            // from that edge's plane (a crossing slides along it, which moves nothing)
            auto off = [&](const Vertex& u, size_t k) {
                if (refined) return (*refined)[k];
                if (a.edge >= 0 && u.id < 0 && u.on_edge == a.edge) return u.err_line;
                return u.err;
            };
            const R length = arc(a, b);
            const R charge = length * std::max(off(a, i), off(b, (i + 1) % m)) / pi;
            // the input's own errors: the edge's points move by at most the ends' world
            // errors, and lie at least h (p's distance from the edge's line) from p, so
            // their directions turn by at most turn_bound(moved / h)
            R geo = 0;
            if (a.gerr > 0 || b.gerr > 0) {
                const V3 d{b.v.x - a.v.x, b.v.y - a.v.y, b.v.z - a.v.z};
                const R dl = norm(d);
                const R h = dl > 0 ? norm(cross(a.v, b.v)) / dl : std::min(a.length, b.length);
                const R moved = std::max(a.gerr * a.length, b.gerr * b.length);
                geo = h > 0 ? length * turn_bound(moved / h) / pi : length;
            }
            total += charge;
            if (!record) continue;
            if (a.id >= 0 && b.id >= 0 && a.gerr == 0 && b.gerr == 0) {
                // an input edge of the scene's: on its polygon's boundary
                E[src] += charge;
                continue;
            }
            // a cut edge, or one a BSP split made (two fragments of one polygon share
            // it): keyed by its ends, in a fixed order
            const Vertex* lo = &a;
            const Vertex* hi = &b;
            if (lex_less(hi->v, lo->v)) std::swap(lo, hi);
            EdgeKey k{{lo->v.x, lo->v.y, lo->v.z, hi->v.x, hi->v.y, hi->v.z}};
            auto it = st.edges.find(k);
            const bool r = refined != nullptr;
            if (it == st.edges.end()) {
                st.edges.emplace(k, EdgeCharge{src, charge, 1, r, geo});
            } else if (it->second.src == src && it->second.count == 1) {
                // shared by two visible pieces of src: moving it moves area from one to
                // the other, if both place it alike; one refined and one not do not:
                // the coarser placement's charge stays
                it->second.count = 2;
                if (it->second.refined != r) E[src] += std::max(charge, it->second.charge);
            } else {
                E[src] += charge;
                st.crossing[static_cast<size_t>(src)] += geo;
            }
        }
        return total;
    }

    // the normal of the plane through p that a piece's edge lies on (edge code as
    // Vertex::edge: an input edge of fragment f, or exact plane -1 - k) in quadruple
    // precision from the input's doubles, and its condition: |a - p| |b - p| / |m| for a
    // plane through two points (the tilt of m is within a few roundoffs times it), 0
    // for a plane given by its normal (exact)
    void quad_plane(int64_t code, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
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
        const Quad ml = q_sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        const Quad al = q_sqrt(A[0] * A[0] + A[1] * A[1] + A[2] * A[2]);
        const Quad bl = q_sqrt(B[0] * B[0] + B[1] * B[1] + B[2] * B[2]);
        *cond = ml > 0 ? al * bl / ml : static_cast<Quad>(INFINITY);
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
    // to its value. A vertex keeps its long double direction and bound where its two
    // edges are one plane, where the planes are too close to tell, or where the line is
    // farther from the long double direction than that direction's bound (a vertex taken
    // as on a plane within the band, whose sliver the band's bound holds)
    void refine(const Piece& q, int64_t f, const double* pp, const std::vector<ExactPlane>& xp,
                std::vector<std::array<Quad, 3>>& v, std::vector<R>& err) const {
        const size_t m = q.size();
        v.resize(m);
        err.resize(m);
        auto len = [](const Quad* x) { return q_sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]); };
        for (size_t i = 0; i < m; ++i) {
            const Vertex& u = q[i];
            if (u.id >= 0) {
                for (int k = 0; k < 3; ++k) v[i][k] = static_cast<Quad>(V_[3 * u.id + k]) - pp[k];
                err[i] = 4 * static_cast<R>(QUAD_EPS);  // the differences' rounding, if any
                continue;
            }
            v[i] = {static_cast<Quad>(u.v.x), static_cast<Quad>(u.v.y), static_cast<Quad>(u.v.z)};
            err[i] = std::max(u.err, u.err_line);
            const int64_t e1 = q[(i + m - 1) % m].edge, e2 = u.edge;
            if (e1 == e2) continue;
            Quad d[3];
            R e;
            const int64_t cut = -1 - u.on_plane;
            if (u.on_edge >= 0 && u.on_plane >= 0 &&
                ((e1 == u.on_edge && e2 == cut) || (e2 == u.on_edge && e1 == cut))) {
                // the crossing of input edge a -> b with the exact plane
                const int64_t ia = u.on_edge;
                const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
                Quad mp[3], c;
                quad_plane(cut, f, pp, xp, mp, &c);
                Quad A[3], Bm[3];
                for (int k = 0; k < 3; ++k) {
                    A[k] = static_cast<Quad>(V_[3 * ia + k]) - pp[k];
                    Bm[k] = static_cast<Quad>(V_[3 * ib + k]) - V_[3 * ia + k];
                }
                const Quad den = mp[0] * Bm[0] + mp[1] * Bm[1] + mp[2] * Bm[2];
                if (!(den != 0) || !(c < static_cast<Quad>(INFINITY))) continue;
                const Quad sp = -(mp[0] * A[0] + mp[1] * A[1] + mp[2] * A[2]) / den;
                for (int k = 0; k < 3; ++k) d[k] = A[k] + sp * Bm[k];
                const Quad dl = len(d);
                if (!(dl > 0)) continue;
                // off the edge's plane: the sum's rounding; off the exact plane, also
                // s's (its two dot products, each within 4 roundoffs of |m| |x|) and the
                // normal's tilt
                const Quad W = len(A) + q_abs(sp) * len(Bm);
                e = static_cast<R>(QUAD_EPS * (16 * W / dl + 8 * c + 4));
            } else {
                Quad m1[3], m2[3], c1, c2;
                quad_plane(e1, f, pp, xp, m1, &c1);
                quad_plane(e2, f, pp, xp, m2, &c2);
                d[0] = m1[1] * m2[2] - m1[2] * m2[1];
                d[1] = m1[2] * m2[0] - m1[0] * m2[2];
                d[2] = m1[0] * m2[1] - m1[1] * m2[0];
                const Quad dl = len(d), l1 = len(m1), l2 = len(m2);
                if (!(dl > 0) || !(l1 > 0) || !(l2 > 0)) continue;
                e = static_cast<R>(8 * QUAD_EPS * (c1 + c2 + 1) * (l1 * l2 / dl));
            }
            e += 2 * static_cast<R>(QUAD_EPS);  // and the scaling below
            if (!(e < err[i])) continue;
            if (d[0] * v[i][0] + d[1] * v[i][1] + d[2] * v[i][2] < 0)
                for (int k = 0; k < 3; ++k) d[k] = -d[k];
            const Quad s = static_cast<Quad>(u.length) / len(d);
            const V3 dr{static_cast<R>(d[0] * s), static_cast<R>(d[1] * s),
                        static_cast<R>(d[2] * s)};
            // the line must lie within the long double direction's bound of it (with the
            // rounding of this test: the angle, and dr's rounding to long double)
            const R apart = std::atan2(norm(cross(dr, u.v)), dot(dr, u.v));
            if (!(apart <= err[i] + e + 16 * K_.eps)) continue;
            for (int k = 0; k < 3; ++k) v[i][k] = d[k] * s;
            err[i] = e;
        }
    }

    // the same sector form in quadruple precision, from the directions Core::refine gave
    // the piece's vertices (their errors are charged edge by edge, apart), with the
    // normal as given (unnormalised: the value is divided by its length at the end, a
    // relative error); the second tier for pieces whose terms cancel (grazing, far,
    // small, slivers)
    //
    // With `eq3`, Eq. 3's stable form as in Core::integrate, in a frame (e1, e2, n)
    // built here in quadruple precision (the midpoint terms telescope around the ring
    // for any frame: only their rounding depends on it)
    void integrate_quad(const std::vector<std::array<Quad, 3>>& v, const double* pn, R* value,
                        R* bound, bool eq3 = false) const {
        const size_t m = v.size();
        const Quad n[3] = {pn[0], pn[1], pn[2]};
        const Quad nl = q_sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        Quad S = 0, mag = 0, errs = 0;
        Quad e1[3] = {0, 0, 0}, e2[3] = {0, 0, 0};
        if (eq3) {
            // e1: n crossed with the axis n is least along, e2 = n x e1 (n unit here)
            Quad un[3] = {n[0] / nl, n[1] / nl, n[2] / nl};
            int k = 0;
            for (int j = 1; j < 3; ++j)
                if (q_abs(un[j]) < q_abs(un[k])) k = j;
            Quad ax[3] = {0, 0, 0};
            ax[k] = 1;
            e1[0] = un[1] * ax[2] - un[2] * ax[1];
            e1[1] = un[2] * ax[0] - un[0] * ax[2];
            e1[2] = un[0] * ax[1] - un[1] * ax[0];
            const Quad l1 = q_sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
            for (int j = 0; j < 3; ++j) e1[j] /= l1;
            e2[0] = un[1] * e1[2] - un[2] * e1[1];
            e2[1] = un[2] * e1[0] - un[0] * e1[2];
            e2[2] = un[0] * e1[1] - un[1] * e1[0];
        }
        const auto& a0 = v[0];
        for (size_t i = 0; i < m; ++i) {
            const size_t j = (i + 1) % m;
            Quad ea[3], eb[3], d[3], c[3];
            for (int k = 0; k < 3; ++k) {
                ea[k] = v[i][k] - a0[k];
                eb[k] = v[j][k] - a0[k];
                d[k] = eb[k] - ea[k];
            }
            c[0] = (a0[1] * d[2] - a0[2] * d[1]) + (ea[1] * eb[2] - ea[2] * eb[1]);
            c[1] = (a0[2] * d[0] - a0[0] * d[2]) + (ea[2] * eb[0] - ea[0] * eb[2]);
            c[2] = (a0[0] * d[1] - a0[1] * d[0]) + (ea[0] * eb[1] - ea[1] * eb[0]);
            Quad Z = 0;
            {
                const Quad P[3] = {q_abs(a0[1] * d[2]) + q_abs(a0[2] * d[1]) +
                                       q_abs(ea[1] * eb[2]) + q_abs(ea[2] * eb[1]),
                                   q_abs(a0[2] * d[0]) + q_abs(a0[0] * d[2]) +
                                       q_abs(ea[2] * eb[0]) + q_abs(ea[0] * eb[2]),
                                   q_abs(a0[0] * d[1]) + q_abs(a0[1] * d[0]) +
                                       q_abs(ea[0] * eb[1]) + q_abs(ea[1] * eb[0])};
                for (int k = 0; k < 3; ++k) Z += q_abs(n[k]) * P[k];
            }
            const Quad cl = q_sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
            const Quad la = q_sqrt(v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2]);
            const Quad lb = q_sqrt(v[j][0] * v[j][0] + v[j][1] * v[j][1] + v[j][2] * v[j][2]);
            const Quad ab = v[i][0] * v[j][0] + v[i][1] * v[j][1] + v[i][2] * v[j][2];
            const Quad theta = q_atan2(cl, ab);
            if (!(cl > 0)) {
                if (la * lb > 0) errs += 2 * QUAD_EPS;
                continue;
            }
            const Quad t = theta * (n[0] * c[0] + n[1] * c[1] + n[2] * c[2]) / (cl * nl);
            S += t;
            mag += q_abs(t);
            const Quad rel = static_cast<Quad>(K_.c2) * QUAD_EPS *
                             (Z / nl + theta * theta * la * lb) / cl;
            errs += theta * (rel < 2 ? rel : static_cast<Quad>(2));
            if (eq3) {
                const Quad sin_t = cl / (la * lb);
                Quad u[3];
                for (int k = 0; k < 3; ++k) u[k] = v[i][k] / la + v[j][k] / lb;
                const Quad lu = q_sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                if (lu > 0) {
                    for (int k = 0; k < 3; ++k) u[k] /= lu;
                    const Quad w[3] = {c[1] * u[2] - c[2] * u[1], c[2] * u[0] - c[0] * u[2],
                                       c[0] * u[1] - c[1] * u[0]};
                    auto dt = [](const Quad* x, const Quad* y) {
                        return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
                    };
                    const Quad xy = sin_t * (dt(w, e1) * dt(u, e2) + dt(u, e1) * dt(w, e2)) / cl;
                    S -= xy;
                    mag += q_abs(xy);
                } else {
                    errs += sin_t;
                }
                errs += theta * (rel < 2 ? rel : static_cast<Quad>(2)) +
                        EQ3_FACTOR_ULPS * QUAD_EPS * 2 * q_sin(theta / 2);
            }
        }
        const Quad two_pi = static_cast<Quad>(6.283185307179586476925286766559L);
        *value = static_cast<R>(q_abs(S) / two_pi);
        // the quad sums' own rounding, and the value's to long double (the vertices'
        // errors are charged edge by edge, apart)
        *bound = static_cast<R>((static_cast<Quad>(K_.c1) * QUAD_EPS * mag + errs) / two_pi) +
                 K_.eps * *value;
    }

    void run(const double* pp, const double* pn, const int8_t* node_side,
             const int8_t* source_side, bool two_sided, bool cull, int64_t budget,
             int64_t tiles, std::vector<R>& F, std::vector<R>& E, std::vector<R>& B, RowStats& st) const {
        const V3 p{pp[0], pp[1], pp[2]};
        V3 n{pn[0], pn[1], pn[2]};
        R nl = norm(n);
        n = {n.x / nl, n.y / nl, n.z / nl};
        std::vector<Plane> sv;
        sv.reserve(1024);
        std::vector<ExactPlane> xp;
        xp.reserve(1024);
        // the root: the horizon, covered below
        sv.push_back({n, 1, 2 * K_.eps, OUT, IN, 0, 1});
        set_double(sv.back());
        xp.push_back({1, {pn[0], pn[1], pn[2]}, {0, 0, 0}, n, 2 * K_.eps, -1, -1});
        if (tiles > 0) sv[0].pos = tile_tree(pn, tiles, sv, xp);
        if (nodes() == 0) return;
        struct Item {
            int64_t node;
            bool emit;
        };
        std::vector<Item> stack{{0, false}};
        // work list of the filter: a piece and the link (plane, branch) it arrived by
        struct Work {
            Piece q;
            int plane;
            bool positive;
        };
        std::vector<Work> work;
        Piece q0, qp, qn;
        while (!stack.empty()) {
            Item it = stack.back();
            stack.pop_back();
            const int64_t k = it.node;
            const bool near_front = node_side[k] >= 0;
            if (it.emit) {
                const auto& list = near_front ? here_front_ : here_behind_;
                for (int64_t j = here_start_[k]; j < here_start_[k + 1]; ++j)
                    process(list[j], pp, p, n, source_side, two_sided, sv, xp, work, F, E,
                            B, st);
                continue;
            }
            if (cull && size_[k] >= 4) {
                ++st.box_tests;
                if (box_behind(k, pp, pn) || box_hidden(sv, k, p, budget)) {
                    ++st.subtrees_culled;
                    st.fragments_culled += size_[k];
                    continue;
                }
            }
            int64_t nearc = near_front ? front_[k] : back_[k];
            int64_t farc = near_front ? back_[k] : front_[k];
            if (farc >= 0) stack.push_back({farc, false});
            stack.push_back({k, true});
            if (nearc >= 0) stack.push_back({nearc, false});
        }
        for (const auto& [key, e] : st.edges)
            if (e.count == 1) {
                E[e.src] += e.charge;
                st.crossing[static_cast<size_t>(e.src)] += e.geo;
            }
        // what the row held beyond its n-long results: the shadow tree and its exact
        // planes, the traversal's stack, the work list's pieces at their most, the edge
        // charges and the exact tests' cache (containers only grow during a row, so their
        // capacities are their peaks)
        st.working_bytes = static_cast<int64_t>(
            sv.capacity() * sizeof(Plane) + xp.capacity() * sizeof(ExactPlane) +
            stack.capacity() * sizeof(Item) + work.capacity() * sizeof(Work) +
            static_cast<size_t>(st.held_peak) * sizeof(Vertex) +
            st.edges.bucket_count() * sizeof(void*) +
            st.edges.size() * (sizeof(EdgeKey) + sizeof(EdgeCharge) + 2 * sizeof(void*)) +
            st.on_plane.bytes());
        // a visible sliver whose shadow was left out may wrongly show any later piece
        // behind it: its area goes to every receiving polygon's band bound
        if (st.unattributed > 0)
            for (int64_t i = 0; i < n_sources_; ++i)
                if (source_side[i] > 0 || (two_sided && source_side[i] < 0))
                    B[i] += st.unattributed;
    }

    template <class W>
    void process(int64_t f, const double* pp, const V3& p, const V3& n,
                 const int8_t* source_side, bool two_sided, std::vector<Plane>& sv,
                 std::vector<ExactPlane>& xp, std::vector<W>& work, std::vector<R>& F,
                 std::vector<R>& E, std::vector<R>& B, RowStats& st) const {
        const int64_t src = source_[f];
        const int s = source_side[src];
        if (s == 0) return;  // seen edge-on: no image, hides nothing
        ++st.fragments;
        const bool receives = s > 0 || two_sided;
        Piece q;
        q.reserve(count_[f]);
        for (int64_t i = start_[f]; i < start_[f] + count_[f]; ++i) {
            V3 w{V_[3 * i], V_[3 * i + 1], V_[3 * i + 2]};
            V3 v{w.x - p.x, w.y - p.y, w.z - p.z};
            // the difference is exact where it fits long double (the usual case): the
            // direction has no error then, else half an ulp per coordinate
            bool exact = true;
            for (int k = 0; k < 3; ++k) {
                double hi, lo;
                two_sum(V_[3 * i + k], -pp[k], hi, lo);
                const R vk = k == 0 ? v.x : (k == 1 ? v.y : v.z);
                exact = exact && (vk - hi == lo);
            }
            const R length = norm(v);
            q.push_back({w, v, length, exact ? static_cast<R>(0) : 2 * K_.eps, i, -1, -1, i});
            q.back().gerr = input_error(i, length);
            set_double(q.back());
        }
        work.clear();
        work.push_back({std::move(q), 0, true});
        st.held = static_cast<int64_t>(work.back().q.size());
        // the first step enters the root from a virtual link
        bool first = true;
        // each step's signs, distances and crossings (reused: no allocation per step)
        std::vector<int> sg;
        std::vector<R> d;
        std::vector<Vertex> cut;
        std::vector<std::array<Quad, 3>> qdirs;  // Core::refine's, for integrate_quad
        std::vector<R> qerrs;
        while (!work.empty()) {
            W w = std::move(work.back());
            work.pop_back();
            // vertices held by the work list (with this piece): for the row's peak
            st.held_peak = std::max(st.held_peak, st.held);
            st.held -= static_cast<int64_t>(w.q.size());
            int node;
            if (first) {
                node = 0;
                first = false;
            } else {
                node = w.positive ? sv[w.plane].pos : sv[w.plane].neg;
            }
            if (node == IN) {
                ++st.hidden;
                continue;
            }
            if (node == OUT) {
                ++st.visible;
                R val, bnd;
                integrate(w.q, f, n, &val, &bnd, st.eq3 ? &st : nullptr);
                bool refined = false;
                if (receives && st.rtol > 0) {
                    // the second tier where the sums' rounding or the vertices' errors
                    // exceed the tolerance times the value
                    const R charges = charge_edges(w.q, src, E, st, nullptr, false);
                    if (bnd + charges > st.rtol * val) {
                        refine(w.q, f, pp, xp, qdirs, qerrs);
                        R qv, qb;
                        integrate_quad(qdirs, st.normal, &qv, &qb, st.eq3);
                        ++st.quad_pieces;
                        const R qcharges = charge_edges(w.q, src, E, st, &qerrs, false);
                        if (qb + qcharges < bnd + charges) {
                            val = qv;
                            bnd = qb;
                            refined = true;
                        }
                    }
                }
                if (receives) {
                    F[src] += val;
                    E[src] += bnd;
                    charge_edges(w.q, src, E, st, refined ? &qerrs : nullptr);
                }
                if (receives) B[src] += leaked(w.q, val + bnd, st);
                // a piece whose shadow is left out is an image folded or flat along a
                // side (seen from within the band of a plane it is not planar in): its
                // own value is charged it too, as the band's slivers are
                if (!insert_shadow(w.q, f, pp, w.plane, w.positive, sv, xp, st, val + bnd) &&
                    receives)
                    B[src] += val + bnd;
                continue;
            }
            const Plane P = sv[node];
            const size_t m = w.q.size();
            ++st.node_visits;
            sg.resize(m);
            d.resize(m);
            bool pos = false, neg = false;
            const double plane_width = static_cast<double>(K_.band + P.err + P.slack);
            for (size_t i = 0; i < m; ++i) {
                // a vertex within the rounding band of d is taken as on the plane (it
                // goes with the others); one within that band plus the plane's and its
                // own errors may lie on the other side of the true plane by up to them:
                // the sliver along its two edges is charged to the piece
                const Vertex& u = w.q[i];
                // the filter: P.m . u.v in double, off its long double value by at most
                // 6 double roundoffs of |m| |v| (the roundings to double, the products
                // and sums); a vertex clearly beyond the widest band is decided by it
                // (its long double distance is then computed only if the piece is cut)
                {
                    const double dd = P.md[0] * u.vd[0] + P.md[1] * u.vd[1] + P.md[2] * u.vd[2];
                    const double widthd = plane_width + u.errd;
                    if (std::fabs(dd) > (widthd + FILTER_ROUNDOFFS * DBL_EPSILON) *
                                            (P.mnormd * u.lengthd) * (1 + 8 * DBL_EPSILON)) {
                        sg[i] = dd > 0 ? 1 : -1;
                        pos |= dd > 0;
                        neg |= dd < 0;
                        d[i] = NAN;
                        continue;
                    }
                }
                d[i] = dot(P.m, u.v);
                const R scale = P.mnorm * u.length;
                sg[i] = d[i] > K_.band * scale ? 1 : (d[i] < -K_.band * scale ? -1 : 0);
                pos |= sg[i] > 0;
                neg |= sg[i] < 0;
                const R width = K_.band + P.err + P.slack + u.err;
                if (!(std::fabs(d[i]) <= width * scale)) continue;
                ++st.near_tests;
                if (!exactly_on(xp, P.exact, pp, f, u, st)) {
                    R adjacent = arc(w.q[(i + m - 1) % m], u) + arc(u, w.q[(i + 1) % m]);
                    if (receives)
                        B[src] += adjacent * width / 3.14159265358979323846264338327950288L;
                    // the sliver, on whichever side it truly is, also hides or uncovers
                    // what lies behind it near this plane: every later piece classified
                    // or cut here is charged it too (the plane's slack; not fed back into
                    // the slack itself, so that it does not grow hit by hit)
                    sv[node].slack = std::max(sv[node].slack, K_.band + P.err + u.err);
                }
            }
            if (!neg) {  // in front (or in the plane: either side)
                work.push_back({std::move(w.q), node, true});
                st.held += static_cast<int64_t>(work.back().q.size());
                continue;
            }
            if (!pos) {
                work.push_back({std::move(w.q), node, false});
                st.held += static_cast<int64_t>(work.back().q.size());
                continue;
            }
            ++st.splits;
            for (size_t i = 0; i < m; ++i)
                if (std::isnan(d[i])) d[i] = dot(P.m, w.q[i].v);
            cut.resize(m);
            for (size_t i = 0; i < m; ++i) {
                const size_t j = (i + 1) % m;
                if ((sg[i] > 0 && sg[j] < 0) || (sg[i] < 0 && sg[j] > 0)) {
                    // the crossing computed from the edge's ends in a fixed order, so
                    // that the piece across the edge gets the same point bit for bit
                    const bool swap = lex_less(w.q[j].v, w.q[i].v);
                    const Vertex& x = swap ? w.q[j] : w.q[i];
                    const Vertex& y = swap ? w.q[i] : w.q[j];
                    const R dx = swap ? d[j] : d[i], dy = swap ? d[i] : d[j];
                    R t = dx / (dx - dy);
                    V3 v{x.v.x + t * (y.v.x - x.v.x), x.v.y + t * (y.v.y - x.v.y),
                         x.v.z + t * (y.v.z - x.v.z)};
                    R l = norm(v);
                    // the new vertex: within K.split ulps of its ends' interpolated distance
                    // (and its own), plus its ends' and the plane's errors carried over
                    R err = P.err + P.slack +
                            K_.split * K_.eps * ((1 - t) * x.length + t * y.length + l) / l +
                            std::max(x.err * x.length, y.err * y.length) / l;
                    cut[i] = {V3{0, 0, 0}, v, l, err, -1, -1, -1, -1};
                    set_double(cut[i]);
                    // off the true plane by its tilt; off the true edge's by its ends'
                    // world errors over its distance (as the computation's, above)
                    cut[i].gerr = xp[static_cast<size_t>(P.exact)].tilt +
                                  std::max(x.gerr * x.length, y.gerr * y.length) / l;
                    // the parameter along the input edge the piece's edge i -> j lies on
                    const Vertex& xi = w.q[i];
                    const Vertex& yj = w.q[j];
                    const R ti = swap ? 1 - t : t;
                    if (xi.edge >= 0) {  // on an input edge: exactly known
                        const int64_t ia = xi.edge;
                        const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
                        R tx = -1, ty = -1;  // the ends' parameters along it
                        if (xi.id == ia) tx = 0;
                        else if (xi.on_edge == ia) tx = xi.t;
                        if (yj.id == ib) ty = 1;
                        else if (yj.on_edge == ia) ty = yj.t;
                        if (tx >= 0 && ty >= 0) {
                            cut[i].on_edge = ia;
                            cut[i].on_plane = P.exact;
                            cut[i].t = tx + ti * (ty - tx);
                            // off the edge's line: the interpolation's rounding, and its
                            // ends' own distances from it
                            auto off = [&](const Vertex& u) {
                                return u.id >= 0 ? u.err : u.err_line;
                            };
                            cut[i].err_line =
                                4 * K_.eps + std::max(off(xi) * xi.length, off(yj) * yj.length) / l;
                        }
                    }
                }
            }
            // the two parts, each vertex with the edge to its successor: the input edge
            // it was on, or the cut along this plane
            const int64_t cut_edge = -1 - static_cast<int64_t>(P.exact);
            auto part = [&](int sigma) {
                Piece out;
                for (size_t i = 0; i < m; ++i) {
                    const size_t j = (i + 1) % m;
                    const int si = sigma * sg[i], sj = sigma * sg[j];
                    if (si >= 0) {
                        out.push_back(w.q[i]);
                        if (si == 0 && sj < 0) out.back().edge = cut_edge;
                    }
                    if ((si > 0 && sj < 0) || (si < 0 && sj > 0)) {
                        out.push_back(cut[i]);
                        out.back().edge = si > 0 ? cut_edge : w.q[i].edge;
                    }
                }
                return out;
            };
            work.push_back({part(-1), node, false});
            st.held += static_cast<int64_t>(work.back().q.size());
            work.push_back({part(1), node, true});
            st.held += static_cast<int64_t>(work.back().q.size());
        }
    }

    // replace the free leaf reached by (plane, branch) with the piece's shadow volume
    // the plane through p and input points a, b: (a - p) x (b - a), from the doubles'
    // error-free differences and products (two-sum, two-product), so that its direction
    // is good to a few long double roundoffs even for an edge seen nearly end-on
    static V3 input_plane(const double* p, const double* a, const double* b) {
        double Ah[3], Al[3], Eh[3], El[3];
        for (int i = 0; i < 3; ++i) {
            two_sum(a[i], -p[i], Ah[i], Al[i]);
            two_sum(b[i], -a[i], Eh[i], El[i]);
        }
        auto term = [&](int i, int j) {  // A_i E_j - A_j E_i
            const double p1 = Ah[i] * Eh[j], p2 = Ah[j] * Eh[i];
            const double e1 = std::fma(Ah[i], Eh[j], -p1), e2 = std::fma(Ah[j], Eh[i], -p2);
            return (static_cast<R>(p1) - p2) + (static_cast<R>(e1) - e2) +
                   (static_cast<R>(Ah[i]) * El[j] + static_cast<R>(Al[i]) * Eh[j]) -
                   (static_cast<R>(Ah[j]) * El[i] + static_cast<R>(Al[j]) * Eh[i]);
        };
        return {term(1, 2), term(2, 0), term(0, 1)};
    }

    // replace the free leaf reached by (plane, branch) with the piece's shadow volume:
    // for each edge, the plane it lies on (its input edge's plane through p, or the
    // plane it was cut along), oriented to hold the piece
    // (false: the shadow is left out)
    bool insert_shadow(const Piece& q, int64_t f, const double* pp, int plane, bool positive,
                       std::vector<Plane>& sv, std::vector<ExactPlane>& xp, RowStats& st,
                       R piece_bound) const {
        constexpr R PI = 3.14159265358979323846264338327950288L;
        const size_t m = q.size();
        V3 c{0, 0, 0};
        for (const Vertex& u : q) {
            c.x += u.v.x / u.length;
            c.y += u.v.y / u.length;
            c.z += u.v.z / u.length;
        }
        const R cl = norm(c);
        // per edge: its plane through p, oriented towards the piece (0: through p, not
        // a side; 2: the piece straddles it, no orientation), and how far beyond it the
        // piece's farthest vertex lies (radians)
        struct Side {
            V3 mm;
            R ml, err, beyond;
            int exact, orient;
            int state;  // 0 none (through p), 1 oriented, 2 straddled
            bool on_cut, omit;
        };
        std::vector<Side> e(m);
        if (m < 3) {
            leave_out(q, piece_bound, 0, st);
            return false;
        }
        for (size_t i = 0; i < m; ++i) {
            const Vertex& a = q[i];
            Side& s = e[i];
            if (a.edge >= 0) {
                const int64_t ia = a.edge;
                const int64_t ib = start_[f] + (ia - start_[f] + 1) % count_[f];
                s.mm = input_plane(pp, &V_[3 * ia], &V_[3 * ib]);
                // its rounding; the input points' own errors (BSP crossings) apart
                const R tilt = input_tilt(ia, ib, pp);
                s.err = 8 * K_.eps;
                s.exact = static_cast<int>(xp.size());
                xp.push_back({0, {V_[3 * ia], V_[3 * ia + 1], V_[3 * ia + 2]},
                              {V_[3 * ib], V_[3 * ib + 1], V_[3 * ib + 2]}, s.mm, s.err,
                              uid_[ia], uid_[ib], tilt});
            } else {
                s.exact = static_cast<int>(-1 - a.edge);
                s.mm = xp[s.exact].m;
                s.err = xp[s.exact].err;
            }
            s.on_cut = a.edge < 0;
            s.omit = false;
            s.beyond = 0;
            s.orient = 1;
            s.ml = norm(s.mm);
            if (!(s.ml > 0)) {  // an input edge through p (seen end-on exactly)
                s.state = 0;
                continue;
            }
            const R dc = dot(s.mm, c);
            // the piece must lie clearly on one side
            if (!(std::fabs(dc) > (16 * K_.eps + s.err) * s.ml * cl)) {
                s.state = 2;
                continue;
            }
            s.state = 1;
            if (dc < 0) {
                s.mm = {-s.mm.x, -s.mm.y, -s.mm.z};
                s.orient = -1;
            }
            // and every vertex on that side, up to the plane's and its own errors
            for (size_t k = 0; k < m; ++k) {
                if (k == i || k == (i + 1) % m) continue;
                const Vertex& u = q[k];
                const R tol = 16 * K_.eps + s.err + u.err;
                const R dk = dot(s.mm, u.v);
                if (dk < -tol * s.ml * u.length)
                    s.beyond = std::max(s.beyond, -dk / (s.ml * u.length) + tol);
            }
        }
        // The shadow is the intersection of the sides' half-spaces. Where the image is
        // convex, that is the image. Where it is not (a polygon planar only within the
        // validation tolerance seen from nearly in its plane; an input edge shorter than
        // its vertices' roundings, whose direction they decide), it is the image's
        // kernel, less than the image: the part left out lies in the piece on the wrong
        // side of a plane, within `beyond` of it and across the piece's extent (at most
        // half its perimeter), so its projected area is at most beyond * perimeter / 2
        // / pi (projected area <= area on the sphere); a later piece behind it may show
        // through by that much. A short side whose two neighbours turn by less than
        // about 154 degrees together is left out instead where that costs less: the
        // shadow then holds the
        // triangle the two neighbours' planes close beyond it, of apex height at most
        // l tan(theta / 2) / 2 over its arc l (theta the angle of their normals), so
        // area l^2 tan(theta / 2) / 4, which may hide that much of a later piece
        R perimeter = 0;
        std::vector<R> arcs(m);
        for (size_t k = 0; k < m; ++k) {
            arcs[k] = arc(q[k], q[(k + 1) % m]) + q[k].err + q[(k + 1) % m].err;
            perimeter += arcs[k];
        }
        R kernel_charge = 0, omit_charge = 0;
        for (size_t i = 0; i < m; ++i) {
            Side& s = e[i];
            if (s.on_cut || !(s.state == 2 || s.beyond > 0)) continue;
            const Side& prev = e[(i + m - 1) % m];
            const Side& next = e[(i + 1) % m];
            R omit = INFINITY;
            if (prev.state == 1 && next.state == 1 && !prev.omit && !next.omit) {
                const R cosine = dot(prev.mm, next.mm) / (prev.ml * next.ml);
                if (cosine > -0.9L) {   // theta below about 154 degrees: a bounded triangle
                    const R theta = std::acos(std::min(cosine, R(1))) +
                                    16 * K_.eps + prev.err + next.err;
                    omit = arcs[i] * arcs[i] * std::tan(theta / 2) / 4 / PI * (1 + 1e-6L);
                }
            }
            const R keep = s.state == 2 ? INFINITY : s.beyond * perimeter / 2 / PI;
            if (omit <= keep) {
                s.omit = true;
                omit_charge += omit;
            } else {
                kernel_charge += keep;
            }
        }
        size_t sides = 0;  // the piece's edges that bound its shadow, cut ones included
        std::vector<Plane> chain;
        bool straddled = false;
        for (size_t i = 0; i < m; ++i) {
            const Side& s = e[i];
            if (s.state == 0 || s.omit) continue;
            if (s.state == 2) straddled = true;
            ++sides;
            // an edge along a plane the piece was cut by: that plane is on the path to
            // the leaf, whose whole cell already lies on the piece's side of it, so the
            // shadow needs no plane there
            if (!s.on_cut && s.state == 1) {
                chain.push_back({s.mm, s.ml, s.err, OUT, OUT, s.exact, s.orient});
                set_double(chain.back());
            }
        }
        // a sliver (a side it straddles, fewer than three sides) or a kernel that leaves
        // out more than the piece is worth: no shadow at all
        if (straddled || sides < 3 || kernel_charge + omit_charge > piece_bound) {
            leave_out(q, piece_bound, straddled ? 1 : (sides < 3 ? 3 : 2), st);
            return false;
        }
        leave_out(q, kernel_charge, -1, st);
        // what the omitted sides' triangles may hide is not attributed to a piece
        st.unattributed += omit_charge;
        st.omitted_sides += omit_charge > 0;
        st.kernels += kernel_charge > 0;
        if (chain.empty()) {  // the piece fills its leaf's cell: the cell is covered
            (positive ? sv[plane].pos : sv[plane].neg) = IN;
            return true;
        }
        const int base = static_cast<int>(sv.size());
        for (size_t i = 0; i < chain.size(); ++i) {
            chain[i].pos = i + 1 < chain.size() ? base + static_cast<int>(i) + 1 : IN;
            chain[i].neg = OUT;
            sv.push_back(chain[i]);
        }
        (positive ? sv[plane].pos : sv[plane].neg) = base;
        st.shadow_planes += static_cast<int64_t>(chain.size());
        return true;
    }

    // a part of the hemisphere that a piece covers but its shadow does not (all of a
    // sliver's, a kernel's remainder), worth at most `charge`: a later visible piece
    // that may overlap it may show through by as much, and no more than itself. Small
    // charges go to every receiving polygon (up to the row's budget); the others are
    // kept with the cone that holds them (Core::leaked)
    void leave_out(const Piece& q, R charge, int why, RowStats& st) const {
        if (why >= 0) ++st.slivers[why];
        if (!(charge > 0)) return;
        if (st.unattributed + charge <= st.leak_budget) {
            st.unattributed += charge;
            return;
        }
        st.leaks.push_back(cone(q));
        st.leaks.back().charge = charge;
    }

    // a cone about the piece's mean direction that holds its image (radians, with its
    // vertices' errors and a margin for the arcs' rounding)
    Leak cone(const Piece& q) const {
        V3 c{0, 0, 0};
        for (const Vertex& u : q) {
            c.x += u.v.x / u.length;
            c.y += u.v.y / u.length;
            c.z += u.v.z / u.length;
        }
        Leak k{c, 0, 0};
        const R cl = norm(c);
        if (!(cl > 1e-6L)) {  // about opposite directions: the whole sphere
            k.radius = 4;
            return k;
        }
        k.c = {c.x / cl, c.y / cl, c.z / cl};
        for (const Vertex& u : q)
            k.radius = std::max(k.radius, std::atan2(norm(cross(k.c, u.v)), dot(k.c, u.v)) + u.err);
        k.radius += 64 * K_.eps;
        return k;
    }

    // what the row's kept leaks may have shown of visible piece q, worth val + bnd: the
    // charges of those whose cones meet its cone, at most the piece itself
    R leaked(const Piece& q, R worth, const RowStats& st) const {
        if (st.leaks.empty()) return 0;
        const Leak k = cone(q);
        R sum = 0;
        for (const Leak& l : st.leaks)
            if (k.radius >= 4 || l.radius >= 4 ||
                std::atan2(norm(cross(k.c, l.c)), dot(k.c, l.c)) <= k.radius + l.radius + 64 * K_.eps)
                sum += l.charge;
        return std::min(sum, worth);
    }

    int64_t n_sources_;
    std::vector<double> V_;
    std::vector<double> VE_;  // per input point, a bound on its distance from the exact one
    std::vector<int64_t> uid_;  // distinct input point of each vertex
    std::vector<int64_t> start_, count_, source_, front_, back_, here_start_, here_front_,
        here_behind_;
    std::vector<double> lo_, hi_;
    std::vector<int64_t> size_;
    Constants K_;
};

}  // namespace

PYBIND11_MODULE(_svbsp, m) {
    m.doc() = "Compiled visibility core: shadow-volume BSP rows (exactff.visibility.compiled)";
    py::class_<Core>(m, "Core")
        .def(py::init<py::array_t<double, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      py::array_t<int64_t, py::array::c_style | py::array::forcecast>,
                      int64_t, double, double, double, double,
                      py::array_t<double, py::array::c_style | py::array::forcecast>>())
        .def("row", &Core::row, py::arg("point"), py::arg("normal"), py::arg("node_side"),
             py::arg("source_side"), py::arg("two_sided"), py::arg("cull"),
             py::arg("box_budget"), py::arg("tiles"), py::arg("rtol"), py::arg("eq3") = false)
        .def_property_readonly("nodes", &Core::nodes)
        .def_property_readonly("pieces", &Core::pieces)
        .def_property_readonly("unit_roundoff", &Core::unit_roundoff);
    register_bsp_build(m);
}
