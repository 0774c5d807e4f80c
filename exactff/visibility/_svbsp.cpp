// The compiled visibility core (issue 28): one row of exact occluded form factors.
//
// A BSP tree of convex fragments (built by exactff.visibility.bsp, convexified by
// exactff.visibility.compiled) gives the fragments front to back from the point p.
// The covered region is a shadow-volume BSP tree (Chin & Feiner 1989): a BSP tree of
// planes through p whose leaves are covered (IN) or free (OUT); its root is the
// horizon plane (below it: covered). Each fragment is filtered down the tree; the
// parts reaching free leaves are visible: they are integrated with the sector form
// (Lambert) and the leaf is replaced by the planes through p and their edges (their
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
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace py = pybind11;

namespace {

using R = long double;

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

struct Vertex {
    V3 w;       // position in the world
    V3 v;       // w - p: its direction from p (not normalised)
    R length;   // |v|
    R err;      // bound on the error of its direction, radians
};
using Piece = std::vector<Vertex>;

struct Plane {  // m . x = 0 through p; positive side first
    V3 m;
    R mnorm;
    R err;      // bound on its tilt, radians
    int pos, neg;
};

struct Constants {
    R eps;      // unit roundoff of R
    R band;     // relative band of "on the plane" (radians)
    R c1;       // rounding constant of a sector sum (as the Python kernel's C1)
    R split;    // rounding of a split vertex, in units of eps
};

struct RowStats {
    int64_t fragments = 0, visible = 0, hidden = 0, splits = 0, subtrees_culled = 0,
            fragments_culled = 0, box_tests = 0, shadow_planes = 0;
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
         int64_t n_sources, double band, double c1, double split)
        : n_sources_(n_sources) {
        copy(vertices, V_);
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
            source_.size() != count_.size())
            throw std::invalid_argument("inconsistent fragment arrays");
        K_.eps = std::numeric_limits<R>::epsilon() / 2;
        K_.band = band;
        K_.c1 = c1;
        K_.split = split;
        build_boxes();
    }

    int64_t nodes() const { return static_cast<int64_t>(front_.size()); }
    int64_t pieces() const { return static_cast<int64_t>(start_.size()); }
    double unit_roundoff() const { return static_cast<double>(K_.eps); }

    py::tuple row(py::array_t<double, py::array::c_style | py::array::forcecast> point,
                  py::array_t<double, py::array::c_style | py::array::forcecast> normal,
                  py::array_t<int8_t, py::array::c_style | py::array::forcecast> node_side,
                  py::array_t<int8_t, py::array::c_style | py::array::forcecast> source_side,
                  bool two_sided, bool cull, int64_t box_budget) const {
        if (point.size() != 3 || normal.size() != 3)
            throw std::invalid_argument("point and normal must have 3 coordinates");
        if (node_side.size() != nodes())
            throw std::invalid_argument("node_side must have one entry per BSP node");
        if (source_side.size() != n_sources_)
            throw std::invalid_argument("source_side must have one entry per polygon");
        py::array_t<double> F(n_sources_), E(n_sources_);
        const double* pp = point.data();
        const double* pn = normal.data();
        const int8_t* ns = node_side.data();
        const int8_t* ss = source_side.data();
        double* pF = F.mutable_data();
        double* pE = E.mutable_data();
        RowStats st;
        {
            py::gil_scoped_release release;
            std::vector<R> f(n_sources_, 0), e(n_sources_, 0);
            run(pp, pn, ns, ss, two_sided, cull, box_budget, f, e, st);
            const R half_ulp = std::numeric_limits<double>::epsilon() / 2;
            for (int64_t i = 0; i < n_sources_; ++i) {
                pF[i] = static_cast<double>(f[i]);
                // the bound, and the rounding of the value to double
                pE[i] = static_cast<double>(e[i] + half_ulp * std::fabs(f[i])) *
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
        return py::make_tuple(F, E, d);
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

    // side of a direction against a plane: +1, -1, or 0 within the band
    static int side(const Plane& P, const Vertex& x, const Constants& K, R* d_out) {
        R d = dot(P.m, x.v);
        *d_out = d;
        R band = (K.band + P.err + x.err) * P.mnorm * x.length;
        if (d > band) return 1;
        if (d < -band) return -1;
        return 0;
    }

    // is the conic hull (from p) of the box's corners wholly in covered leaves?
    bool box_hidden(const std::vector<Plane>& sv, int64_t k, const V3& p,
                    int64_t budget) const {
        Vertex c[8];
        for (int i = 0; i < 8; ++i) {
            V3 v{(i & 1 ? hi_[3 * k] : lo_[3 * k]) - p.x,
                 (i & 2 ? hi_[3 * k + 1] : lo_[3 * k + 1]) - p.y,
                 (i & 4 ? hi_[3 * k + 2] : lo_[3 * k + 2]) - p.z};
            c[i] = {v, v, norm(v), 4 * K_.eps};
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

    // the sector form of one convex piece above the horizon: its value and bound
    void integrate(const Piece& q, const V3& n, R* value, R* bound) const {
        R S = 0, mag = 0, geo = 0;
        const size_t m = q.size();
        for (size_t i = 0; i < m; ++i) {
            const Vertex& a = q[i];
            const Vertex& b = q[(i + 1) % m];
            V3 c = cross(a.v, b.v);
            R cl = norm(c);
            if (cl == 0) continue;
            R gamma = std::atan2(cl, dot(a.v, b.v));
            R t = gamma * dot(n, c) / cl;
            S += t;
            mag += std::fabs(t);
            geo += gamma * std::max(a.err, b.err);
        }
        const R two_pi = 6.283185307179586476925286766559L;
        const R pi = two_pi / 2;
        *value = std::fabs(S) / two_pi;
        *bound = K_.c1 * K_.eps * mag / two_pi + geo / pi;
    }

    void run(const double* pp, const double* pn, const int8_t* node_side,
             const int8_t* source_side, bool two_sided, bool cull, int64_t budget,
             std::vector<R>& F, std::vector<R>& E, RowStats& st) const {
        const V3 p{pp[0], pp[1], pp[2]};
        V3 n{pn[0], pn[1], pn[2]};
        R nl = norm(n);
        n = {n.x / nl, n.y / nl, n.z / nl};
        std::vector<Plane> sv;
        sv.reserve(1024);
        // the root: the horizon, covered below
        sv.push_back({n, 1, 2 * K_.eps, OUT, IN});
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
                    process(list[j], p, n, source_side, two_sided, sv, work, F, E, st);
                continue;
            }
            if (cull && size_[k] >= 4) {
                ++st.box_tests;
                if (box_hidden(sv, k, p, budget)) {
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
    }

    template <class W>
    void process(int64_t f, const V3& p, const V3& n, const int8_t* source_side,
                 bool two_sided, std::vector<Plane>& sv, std::vector<W>& work,
                 std::vector<R>& F, std::vector<R>& E, RowStats& st) const {
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
            q.push_back({w, v, norm(v), 2 * K_.eps});
        }
        work.clear();
        work.push_back({std::move(q), 0, true});
        // the first step enters the root from a virtual link
        bool first = true;
        while (!work.empty()) {
            W w = std::move(work.back());
            work.pop_back();
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
                if (receives) {
                    R val, bnd;
                    integrate(w.q, n, &val, &bnd);
                    F[src] += val;
                    E[src] += bnd;
                }
                insert_shadow(w.q, w.plane, w.positive, sv, st);
                continue;
            }
            const Plane P = sv[node];
            std::vector<int> sg(w.q.size());
            std::vector<R> d(w.q.size());
            bool pos = false, neg = false;
            for (size_t i = 0; i < w.q.size(); ++i) {
                sg[i] = side(P, w.q[i], K_, &d[i]);
                pos |= sg[i] > 0;
                neg |= sg[i] < 0;
            }
            if (!neg) {  // in front (or wholly in the band: either side)
                for (size_t i = 0; i < w.q.size(); ++i)
                    if (sg[i] == 0) on_plane(w.q[i], P);
                work.push_back({std::move(w.q), node, true});
                continue;
            }
            if (!pos) {
                for (size_t i = 0; i < w.q.size(); ++i)
                    if (sg[i] == 0) on_plane(w.q[i], P);
                work.push_back({std::move(w.q), node, false});
                continue;
            }
            ++st.splits;
            Piece a, b;
            const size_t m = w.q.size();
            for (size_t i = 0; i < m; ++i) {
                const size_t j = (i + 1) % m;
                Vertex u = w.q[i];
                if (sg[i] == 0) on_plane(u, P);
                if (sg[i] >= 0) a.push_back(u);
                if (sg[i] <= 0) b.push_back(u);
                if ((sg[i] > 0 && sg[j] < 0) || (sg[i] < 0 && sg[j] > 0)) {
                    const Vertex& x = w.q[i];
                    const Vertex& y = w.q[j];
                    R t = d[i] / (d[i] - d[j]);
                    V3 v{x.v.x + t * (y.v.x - x.v.x), x.v.y + t * (y.v.y - x.v.y),
                         x.v.z + t * (y.v.z - x.v.z)};
                    V3 wv{x.w.x + t * (y.w.x - x.w.x), x.w.y + t * (y.w.y - x.w.y),
                          x.w.z + t * (y.w.z - x.w.z)};
                    R l = norm(v);
                    // the new vertex: within K.split ulps of the edge's length scale,
                    // plus its ends' and the plane's errors carried over
                    R err = P.err + K_.split * K_.eps * (x.length + y.length) / l +
                            std::max(x.err * x.length, y.err * y.length) / l;
                    Vertex c{wv, v, l, err};
                    a.push_back(c);
                    b.push_back(c);
                }
            }
            work.push_back({std::move(b), node, false});
            work.push_back({std::move(a), node, true});
        }
    }

    // a vertex classified as on a plane within the band: its position is kept, which
    // can misplace the boundary by the band (and the plane's own error)
    void on_plane(Vertex& u, const Plane& P) const {
        u.err += K_.band + P.err;
    }

    // replace the free leaf reached by (plane, branch) with the piece's shadow volume
    void insert_shadow(const Piece& q, int plane, bool positive, std::vector<Plane>& sv,
                       RowStats& st) const {
        const size_t m = q.size();
        if (m < 3) return;
        V3 c{0, 0, 0};
        for (const Vertex& u : q) {
            c.x += u.v.x / u.length;
            c.y += u.v.y / u.length;
            c.z += u.v.z / u.length;
        }
        std::vector<Plane> chain;
        for (size_t i = 0; i < m; ++i) {
            const Vertex& a = q[i];
            const Vertex& b = q[(i + 1) % m];
            // the plane through p, a and b: (a - p) x (b - a), with b - a taken from
            // the world positions (accurate for short edges far from p)
            V3 e{b.w.x - a.w.x, b.w.y - a.w.y, b.w.z - a.w.z};
            V3 mm = cross(a.v, e);
            R ml = norm(mm);
            if (!(ml > 0)) continue;  // an edge through p, or a repeated vertex
            R dc = dot(mm, c);
            if (dc < 0) mm = {-mm.x, -mm.y, -mm.z};
            // its tilt: its end points' errors, and the rounding of the cross product
            // of two rounded vectors relative to its length
            R err = std::max(a.err, b.err) + 8 * K_.eps * a.length * norm(e) / ml;
            chain.push_back({mm, ml, err, OUT, OUT});
        }
        if (chain.size() < 3) return;  // a sliver: hides nothing to speak of
        const int base = static_cast<int>(sv.size());
        for (size_t i = 0; i < chain.size(); ++i) {
            chain[i].pos = i + 1 < chain.size() ? base + static_cast<int>(i) + 1 : IN;
            chain[i].neg = OUT;
            sv.push_back(chain[i]);
        }
        (positive ? sv[plane].pos : sv[plane].neg) = base;
        st.shadow_planes += static_cast<int64_t>(chain.size());
    }

    int64_t n_sources_;
    std::vector<double> V_;
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
                      int64_t, double, double, double>())
        .def("row", &Core::row)
        .def_property_readonly("nodes", &Core::nodes)
        .def_property_readonly("pieces", &Core::pieces)
        .def_property_readonly("unit_roundoff", &Core::unit_roundoff);
}
